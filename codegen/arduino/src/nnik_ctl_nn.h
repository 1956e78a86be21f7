/*
 * nnik_ctl_nn.h - the online-learning integer 4-8-1 network both neural controllers share
 * (nnik_ctl_nn_axes.c, nnik_ctl_nn_vector.c; the Python spec: nnik/implementations/servo/nn/net.py,
 * formats in nn/formats.py).  Included by the one compiled controller only (static functions).
 *
 *   x   inputs int16 Q3.12;  w1, w2  int32 master words (Q3.28), the forward pass uses the top 16 bits
 *   a_j = sat16(sum_i (w1_ji >> 16) x_i >> 12)    |w1 >> 16| <= 16384: the sum cannot wrap
 *   h_j = nnik_tanh(a_j)                          Q15 (generated: nnik_nn_tanh.h)
 *   y   = sum_j (w2_j >> 16) h_j                  |w2 >> 16| <= 8192: cannot wrap; Q8 duty = y >> OUT_SHIFT
 * learning with the previous tick's cache and delta_out d (Q3.12):
 *   g_j = 32767 - (h_j h_j >> 15);  dh_j = (sat16(d (w2_j >> 16) >> 12) g_j) >> 15
 *   w2_j += rnd(rnd(d, ETA & 7) h_j, 8 (ETA >> 3));  w1_ji += rnd(rnd(dh_j, S & 7) x_i, 8 (S >> 3)), S = ETA + 3
 *   (rnd(v, s) = (v + 2^s / 2) >> s): the learning rate's bits on the int16 delta, its whole bytes on
 *   the product (byte moves on the AVR); each master word clamped (+-2^29, +-2^30)
 *   skipped when the previous output sat at +-NNIK_DUTY_MAX and d pushes it further (anti-windup)
 * Every product is int16 x int16 -> int32.  nnik_ctl_sum: the master words' low halves summed mod 2^16
 * (kept up to date by each update's change).
 */
#ifndef NNIK_CTL_NN_H
#define NNIK_CTL_NN_H

#include <stdint.h>

#include "nnik_ctl.h"
#include "nnik_ctl_fix.h"
#include "nnik_flash.h"
#include "nnik_imath.h"
#include "nnik_nn_tanh.h"

/* the small helpers are always inlined: at -Os avr-gcc would call them, and a call costs more than
 * the multiply-accumulate itself */
#if defined(__GNUC__)
#define NNIK_NN_INLINE static inline __attribute__((always_inline))
#else
#define NNIK_NN_INLINE static inline
#endif

#define NNIK_NN_IN 4
#define NNIK_NN_HID 8
#define NNIK_NN_W1_LIM (1L << 30)
#define NNIK_NN_W2_LIM (1L << 29)

/* a raw integer input into Q3.12 by 2^s (s a constant, -12 .. 12), saturated to +-32767 */
#define NNIK_NN_POS(s) ((s) >= 0 ? (s) : 0)
#define NNIK_NN_SCALE(raw, s)                                                                        \
    ((s) >= 0 ? (int16_t)(nnik_ctl_sat((raw), 32767L >> NNIK_NN_POS(s)) * (1L << NNIK_NN_POS(s))) \
              : nnik_ctl_s16((raw) >> NNIK_NN_POS(-(s))))

typedef struct {
    int32_t w1[NNIK_NN_HID][NNIK_NN_IN];
    int32_t w2[NNIK_NN_HID];
    int16_t x[NNIK_NN_IN]; /* the last forward pass' inputs and hidden outputs */
    int16_t h[NNIK_NN_HID];
    int16_t u; /* and its output (duty) */
    uint8_t primed; /* a forward pass is cached */
} nnik_nn_t;

static NNIK_FLASH const int32_t nnik_nn_w1_init[NNIK_NN_NETS * NNIK_NN_HID * NNIK_NN_IN] = NNIK_NN_W1_INIT;
static NNIK_FLASH const int32_t nnik_nn_w2_init[NNIK_NN_NETS * NNIK_NN_HID] = NNIK_NN_W2_INIT;

/* acc + a * b (int16 x int16 -> int32; by range analysis it never wraps).  On the AVR, inline: the
 * four-MUL signed multiply-accumulate of Atmel's AVR201 (mac16x16_32), a third of __mulhisi3's
 * cycles with its call; elsewhere plain C.  The same value everywhere. */
#if defined(__GNUC__) && defined(__AVR__)
NNIK_NN_INLINE int32_t nnik_nn_mac(int32_t acc, int16_t a, int16_t b)
{
    uint8_t z;
    __asm__("clr %[z]\n\t"
            "muls %B[a], %B[b]\n\t"
            "add %C[acc], r0\n\t"
            "adc %D[acc], r1\n\t"
            "mul %A[a], %A[b]\n\t"
            "add %A[acc], r0\n\t"
            "adc %B[acc], r1\n\t"
            "adc %C[acc], %[z]\n\t"
            "adc %D[acc], %[z]\n\t"
            "mulsu %B[a], %A[b]\n\t"
            "sbc %D[acc], %[z]\n\t"
            "add %B[acc], r0\n\t"
            "adc %C[acc], r1\n\t"
            "adc %D[acc], %[z]\n\t"
            "mulsu %B[b], %A[a]\n\t"
            "sbc %D[acc], %[z]\n\t"
            "add %B[acc], r0\n\t"
            "adc %C[acc], r1\n\t"
            "adc %D[acc], %[z]\n\t"
            "clr __zero_reg__"
            : [acc] "+r"(acc), [z] "=&r"(z)
            : [a] "a"(a), [b] "a"(b));
    return acc;
}
#else
NNIK_NN_INLINE int32_t nnik_nn_mac(int32_t acc, int16_t a, int16_t b)
{
    return acc + (int32_t)a * b;
}
#endif

/* p >> s (arithmetic) for a constant s: whole bytes first, held apart (avr-gcc -Os shifts an int32
 * one bit per loop pass, 6 cycles a bit), then the remaining bits */
NNIK_NN_INLINE int32_t nnik_nn_asr(int32_t p, uint8_t s)
{
    if (s >= 16) {
        p >>= 16;
        NNIK_KEEP16(p);
        s -= 16;
    }
    if (s >= 8) {
        p >>= 8;
        NNIK_KEEP16(p);
        s -= 8;
    }
    return p >> s;
}

/* p >> 15 for |p| < 2^30, in 16-bit arithmetic: 2 (p >> 16) + (the low half's top bit) */
NNIK_NN_INLINE int16_t nnik_nn_shr15(int32_t p)
{
    return (int16_t)((int16_t)(p >> 16) * 2 + (int16_t)((uint16_t)p >> 15));
}

/* v / 2^r rounded half up, r a constant 0 .. 7: floor((w + 1) / 2) = (w >> 1) + (w & 1), w = v >> (r - 1) */
NNIK_NN_INLINE int16_t nnik_nn_rnd16(int16_t v, uint8_t r)
{
    if (r == 0)
        return v;
    v = (int16_t)(v >> (r - 1));
    return (int16_t)((v >> 1) + (v & 1));
}

/* the learning rate 2^-s as a bit shift of the int16 delta (s & 7) and a whole-byte rounding shift
 * of the product (s >> 3 bytes) */
#define NNIK_NN_S2 (NNIK_NN_ETA)
#define NNIK_NN_S1 (NNIK_NN_ETA + 3)
#define NNIK_NN_HALF(s) ((s) >= 8 ? (1L << (8 * ((s) >> 3) - 1)) : 0L)

/* w clamped to +-lim (lim = 2^29 or 2^30); the common case, |w| < 2^29, is told by the top byte alone */
NNIK_NN_INLINE int32_t nnik_nn_clamp(int32_t w, int32_t lim)
{
    int8_t top = (int8_t)(w >> 24);
    if (top >= 32 || top < -32)
        w = w > lim ? lim : (w < -lim ? -lim : w);
    return w;
}

/* w + rnd(a b, 8 q), clamped to +-lim: one learning update of a master word */
NNIK_NN_INLINE int32_t nnik_nn_update(int32_t w, int16_t a, int16_t b, uint8_t s, int32_t lim)
{
    return nnik_nn_clamp(w + nnik_nn_asr(nnik_nn_mac(NNIK_NN_HALF(s), a, b), s & ~7), lim);
}

/* One hidden unit's row of first-layer updates: w[i] += rnd(a x[i], 8 Q1) for the 4 inputs (Q1 =
 * NNIK_NN_S1 >> 3 whole bytes; rnd adds the top bit of the bytes dropped), then the exact clamp
 * where a new word may have left +-2^30.  On the AVR one inline block per word: the product by
 * AVR201's muls16x16_32, the byte shift by register choice, and bits 31 and 30 compared to flag a
 * word that may need the clamp.  Elsewhere plain C.  The same value everywhere. */
#define NNIK_NN_Q1 (NNIK_NN_S1 >> 3)
#if defined(__GNUC__) && defined(__AVR__)
#if NNIK_NN_Q1 == 0
#define NNIK_NN_ROW_ADD "add %A[w], %A[p]\n\tadc %B[w], %B[p]\n\tadc %C[w], %C[p]\n\tadc %D[w], %D[p]\n\t"
#elif NNIK_NN_Q1 == 1
#define NNIK_NN_ROW_ADD "lsl %A[p]\n\tadc %A[w], %B[p]\n\tadc %B[w], %C[p]\n\tadc %C[w], %D[p]\n\tadc %D[w], %[s]\n\t"
#elif NNIK_NN_Q1 == 2
#define NNIK_NN_ROW_ADD "lsl %B[p]\n\tadc %A[w], %C[p]\n\tadc %B[w], %D[p]\n\tadc %C[w], %[s]\n\tadc %D[w], %[s]\n\t"
#else
#define NNIK_NN_ROW_ADD "lsl %C[p]\n\tadc %A[w], %D[p]\n\tadc %B[w], %[s]\n\tadc %C[w], %[s]\n\tadc %D[w], %[s]\n\t"
#endif
static void nnik_nn_row(int32_t *w, int16_t a, const int16_t *x)
{
    uint8_t i, flag = 0;
    for (i = 0; i < NNIK_NN_IN; i++) {
        int16_t xv = x[i];
        int32_t p, v = w[i];
        uint8_t s, t;
        __asm__("clr %[s]\n\t"
                "muls %B[a], %B[x]\n\t"
                "mov %C[p], r0\n\t"
                "mov %D[p], r1\n\t"
                "mul %A[a], %A[x]\n\t"
                "mov %A[p], r0\n\t"
                "mov %B[p], r1\n\t"
                "mulsu %B[a], %A[x]\n\t"
                "sbc %D[p], %[s]\n\t"
                "add %B[p], r0\n\t"
                "adc %C[p], r1\n\t"
                "adc %D[p], %[s]\n\t"
                "mulsu %B[x], %A[a]\n\t"
                "sbc %D[p], %[s]\n\t"
                "add %B[p], r0\n\t"
                "adc %C[p], r1\n\t"
                "adc %D[p], %[s]\n\t"
                "clr __zero_reg__\n\t"
                "sbrc %D[p], 7\n\t"
                "com %[s]\n\t"
                NNIK_NN_ROW_ADD
                "mov %[t], %D[w]\n\t"
                "lsl %[t]\n\t"
                "eor %[t], %D[w]\n\t"
                "or %[f], %[t]"
                : [w] "+r"(v), [p] "=&r"(p), [s] "=&r"(s), [t] "=&r"(t), [f] "+r"(flag)
                : [a] "a"(a), [x] "a"(xv));
        w[i] = v;
    }
    if (flag & 0x80)
        for (i = 0; i < NNIK_NN_IN; i++)
            w[i] = w[i] > NNIK_NN_W1_LIM ? NNIK_NN_W1_LIM : (w[i] < -NNIK_NN_W1_LIM ? -NNIK_NN_W1_LIM : w[i]);
}
#else
static void nnik_nn_row(int32_t *w, int16_t a, const int16_t *x)
{
    uint8_t i;
    for (i = 0; i < NNIK_NN_IN; i++)
        w[i] = nnik_nn_update(w[i], a, x[i], NNIK_NN_S1, NNIK_NN_W1_LIM);
}
#endif

/* net k's weights from the initial ones (flash), the cache cleared; returns their low halves' sum */
static uint16_t nnik_nn_load(nnik_nn_t *n, uint8_t k)
{
    uint8_t j, i;
    uint16_t sum = 0;
    for (j = 0; j < NNIK_NN_HID; j++) {
        for (i = 0; i < NNIK_NN_IN; i++) {
            n->w1[j][i] = NNIK_RD_I32(&nnik_nn_w1_init[(uint8_t)(k * (NNIK_NN_HID * NNIK_NN_IN) + j * NNIK_NN_IN + i)]);
            sum += (uint16_t)n->w1[j][i];
        }
        n->w2[j] = NNIK_RD_I32(&nnik_nn_w2_init[(uint8_t)(k * NNIK_NN_HID + j)]);
        sum += (uint16_t)n->w2[j];
        n->h[j] = 0;
    }
    n->u = 0;
    n->primed = 0;
    return sum;
}

/* One tick of one net, learning and forward fused per hidden unit: when the net is primed (a cached
 * forward pass) and the anti-windup allows, hidden unit j's weights learn from the cache (inputs
 * n->x, output n->h[j]) and delta_out d; then a_j and h_j from the new inputs x and the updated row.
 * Returns the Q8 duty accumulator; *sum follows the master words' low halves. */
#if defined(__GNUC__)
__attribute__((noinline))
#endif
static int32_t nnik_nn_step(nnik_nn_t *n, const int16_t x[NNIK_NN_IN], int16_t d, uint16_t *sum)
{
    uint8_t j, i;
    int32_t y = 0;
    int32_t *w;
    uint16_t s = 0;
    if (n->primed && !((n->u >= NNIK_DUTY_MAX && d > 0) || (n->u <= -NNIK_DUTY_MAX && d < 0))) {
        int16_t d2 = nnik_nn_rnd16(d, NNIK_NN_S2 & 7);
        w = &n->w1[0][0];
        for (j = 0; j < NNIK_NN_HID; j++) {
            int16_t h = n->h[j];
            int32_t w2 = n->w2[j];
            int16_t g = (int16_t)(32767 - nnik_nn_shr15(nnik_nn_mac(0, h, h)));
            int16_t t = nnik_ctl_s16(nnik_nn_asr(nnik_nn_mac(0, d, (int16_t)(w2 >> 16)), 12));
            int16_t dh = nnik_nn_rnd16(nnik_nn_shr15(nnik_nn_mac(0, t, g)), NNIK_NN_S1 & 7);
            n->w2[j] = nnik_nn_update(w2, d2, h, NNIK_NN_S2, NNIK_NN_W2_LIM);
            nnik_nn_row(w, dh, n->x);
            w += NNIK_NN_IN;
        }
    }
    w = &n->w1[0][0];
    for (j = 0; j < NNIK_NN_HID; j++) {
        int32_t a = 0;
        const int16_t *xi = x;
        int16_t h;
        for (i = 0; i < NNIK_NN_IN; i++, w++) {
            a = nnik_nn_mac(a, (int16_t)(*w >> 16), *xi++);
            s += (uint16_t)*w;
        }
        h = nnik_tanh(nnik_ctl_s16(nnik_nn_asr(a, 12)));
        n->h[j] = h;
        y = nnik_nn_mac(y, (int16_t)(n->w2[j] >> 16), h);
        s += (uint16_t)n->w2[j];
    }
    for (i = 0; i < NNIK_NN_IN; i++)
        n->x[i] = x[i];
    n->primed = 1;
    *sum += s;
    return nnik_nn_asr(y, NNIK_NN_OUT_SHIFT);
}

#endif /* NNIK_CTL_NN_H */
