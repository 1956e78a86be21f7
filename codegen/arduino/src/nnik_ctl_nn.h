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
 *   first-layer rows: those of units j = k mod NNIK_NN_W1_EVERY on tick k since the reset (8 / EVERY a tick)
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
#define NNIK_NN_OWN_REGS static __attribute__((noinline)) /* a block that needs many registers */
#else
#define NNIK_NN_INLINE static inline
#define NNIK_NN_OWN_REGS static
#endif

#define NNIK_NN_IN 4
#define NNIK_NN_HID 8
#define NNIK_NN_W1_LIM (1L << 30)
#define NNIK_NN_W2_LIM (1L << 29)

/* a raw integer input into Q3.12 by 2^s (s a constant, -12 .. 12), saturated to +-32767 (the
 * product of the saturated value and 2^s fits 16 bits: a 16-bit shift) */
#define NNIK_NN_POS(s) ((s) >= 0 ? (s) : 0)
#define NNIK_NN_SCALE(raw, s)                                                                                  \
    ((s) >= 0 ? (int16_t)((int16_t)nnik_ctl_sat((raw), 32767L >> NNIK_NN_POS(s)) * (int16_t)(1 << NNIK_NN_POS(s))) \
              : nnik_ctl_s16(nnik_nn_asr((raw), NNIK_NN_POS(-(s)))))

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
 * cycles with its call; elsewhere plain C.  The same value everywhere.  NNIK_NN_MAC_ASM is its text
 * for operands named A and B (in r16..r23), the accumulator acc and a zeroed register z; the caller
 * clears __zero_reg__ (r1) afterwards. */
#if defined(__GNUC__) && defined(__AVR__)
#define NNIK_NN_MAC_ASM(A, B)                                                                          \
    "muls %B[" A "], %B[" B "]\n\tadd %C[acc], r0\n\tadc %D[acc], r1\n\t"                                \
    "mul %A[" A "], %A[" B "]\n\tadd %A[acc], r0\n\tadc %B[acc], r1\n\tadc %C[acc], %[z]\n\tadc %D[acc], %[z]\n\t" \
    "mulsu %B[" A "], %A[" B "]\n\tsbc %D[acc], %[z]\n\tadd %B[acc], r0\n\tadc %C[acc], r1\n\tadc %D[acc], %[z]\n\t" \
    "mulsu %B[" B "], %A[" A "]\n\tsbc %D[acc], %[z]\n\tadd %B[acc], r0\n\tadc %C[acc], r1\n\tadc %D[acc], %[z]\n\t"

NNIK_NN_INLINE int32_t nnik_nn_mac(int32_t acc, int16_t a, int16_t b)
{
    uint8_t z;
    __asm__("clr %[z]\n\t" NNIK_NN_MAC_ASM("a", "b") "clr __zero_reg__"
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

/* sum_i (w[i] >> 16) x[i] over one hidden unit's 4 first-layer master words (the forward pass'
 * hidden sum), and *sum += their low halves (the checksum).  On the AVR one inline block looping
 * over the words (the compiler's own loads cost as much as the product).  The same values. */
#define NNIK_NN_DOT_STEP                                                                             \
    "ld r0, Z+\n\tadd %A[s], r0\n\tld r0, Z+\n\tadc %B[s], r0\n\t"                                      \
    "ld %A[w], Z+\n\tld %B[w], Z+\n\tld %A[x], X+\n\tld %B[x], X+\n\t" NNIK_NN_MAC_ASM("w", "x")
NNIK_NN_INLINE int32_t nnik_nn_dot(const int32_t *wp, const int16_t *xp, uint16_t *sum)
{
    int32_t acc;
    uint16_t s = *sum;
#if defined(__GNUC__) && defined(__AVR__)
    int16_t w, x;
    uint8_t z;
    __asm__("clr %[z]\n\tclr %A[acc]\n\tclr %B[acc]\n\tclr %C[acc]\n\tclr %D[acc]\n\t"
            NNIK_NN_DOT_STEP NNIK_NN_DOT_STEP NNIK_NN_DOT_STEP NNIK_NN_DOT_STEP "clr __zero_reg__"
            : [acc] "=&r"(acc), [w] "=&a"(w), [x] "=&a"(x), [z] "=&r"(z), [s] "+r"(s), "+z"(wp), "+x"(xp)
            :
            : "memory");
#else
    uint8_t i;
    acc = 0;
    for (i = 0; i < NNIK_NN_IN; i++) {
        acc += (int32_t)(int16_t)(wp[i] >> 16) * xp[i];
        s = (uint16_t)(s + (uint16_t)wp[i]);
    }
#endif
    *sum = s;
    return acc;
}

/* One hidden unit's row of first-layer updates: w[i] += rnd(a x[i], 8 Q1) for the 4 inputs (Q1 =
 * NNIK_NN_S1 >> 3 whole bytes; rnd adds the top bit of the bytes dropped), then the exact clamp
 * where a new word may have left +-2^30.  On the AVR one inline block looping over the words: the
 * product (AVR201), the byte shift by register choice, and bits 31 and 30 compared to flag a word
 * that may need the clamp.  Elsewhere plain C.  The same values everywhere. */
#define NNIK_NN_Q1 (NNIK_NN_S1 >> 3)
#if defined(__GNUC__) && defined(__AVR__)
#if NNIK_NN_Q1 == 0
#define NNIK_NN_ROW_ADD "add %A[v], %A[acc]\n\tadc %B[v], %B[acc]\n\tadc %C[v], %C[acc]\n\tadc %D[v], %D[acc]\n\t"
#elif NNIK_NN_Q1 == 1
#define NNIK_NN_ROW_ADD "lsl %A[acc]\n\tadc %A[v], %B[acc]\n\tadc %B[v], %C[acc]\n\tadc %C[v], %D[acc]\n\tadc %D[v], %[z]\n\t"
#elif NNIK_NN_Q1 == 2
#define NNIK_NN_ROW_ADD "lsl %B[acc]\n\tadc %A[v], %C[acc]\n\tadc %B[v], %D[acc]\n\tadc %C[v], %[z]\n\tadc %D[v], %[z]\n\t"
#else
#define NNIK_NN_ROW_ADD "lsl %C[acc]\n\tadc %A[v], %D[acc]\n\tadc %B[v], %[z]\n\tadc %C[v], %[z]\n\tadc %D[v], %[z]\n\t"
#endif
#define NNIK_NN_ROW_STEP                                                                             \
    "clr %[z]\n\tclr %A[acc]\n\tclr %B[acc]\n\tclr %C[acc]\n\tclr %D[acc]\n\tld %A[x], X+\n\tld %B[x], X+\n\t"  \
    "ldd %A[v], Z+0\n\tldd %B[v], Z+1\n\tldd %C[v], Z+2\n\tldd %D[v], Z+3\n\t"                          \
    NNIK_NN_MAC_ASM("a", "x") "clr __zero_reg__\n\tsbrc %D[acc], 7\n\tcom %[z]\n\t" NNIK_NN_ROW_ADD        \
    "std Z+0, %A[v]\n\tstd Z+1, %B[v]\n\tstd Z+2, %C[v]\n\tstd Z+3, %D[v]\n\tadiw r30, 4\n\t"            \
    "mov %[z], %D[v]\n\tlsl %[z]\n\teor %[z], %D[v]\n\tor %[f], %[z]\n\t"
#endif
NNIK_NN_INLINE void nnik_nn_row(int32_t *w, int16_t a, const int16_t *x)
{
    uint8_t i;
#if defined(__GNUC__) && defined(__AVR__)
    int32_t *wp = w, acc, v;
    int16_t xv;
    uint8_t flag, z; /* z: zero during the product, then the sign byte, then the flag's scratch */
    __asm__("clr %[f]\n\t" NNIK_NN_ROW_STEP NNIK_NN_ROW_STEP NNIK_NN_ROW_STEP NNIK_NN_ROW_STEP
            : [acc] "=&r"(acc), [v] "=&r"(v), [x] "=&a"(xv), [z] "=&r"(z), [f] "=&r"(flag),
              "+z"(wp), "+x"(x)
            : [a] "a"(a)
            : "memory");
    if (flag & 0x80)
        for (i = 0; i < NNIK_NN_IN; i++)
            w[i] = w[i] > NNIK_NN_W1_LIM ? NNIK_NN_W1_LIM : (w[i] < -NNIK_NN_W1_LIM ? -NNIK_NN_W1_LIM : w[i]);
#else
    for (i = 0; i < NNIK_NN_IN; i++)
        w[i] = nnik_nn_update(w[i], a, x[i], NNIK_NN_S1, NNIK_NN_W1_LIM);
#endif
}

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

/* One tick of one net: when the net is primed (a cached forward pass) and the anti-windup allows,
 * the weights learn from the cache (inputs n->x, outputs n->h) and delta_out d: every output weight,
 * and the first-layer rows of the units j with j mod NNIK_NN_W1_EVERY == phase; then
 * the forward pass with the new inputs x.
 * Returns the Q8 duty accumulator; *sum follows the master words' low halves. */
#if defined(__GNUC__)
__attribute__((noinline))
#endif
static int32_t nnik_nn_step(nnik_nn_t *n, const int16_t x[NNIK_NN_IN], int16_t d, uint8_t phase, uint16_t *sum)
{
    uint8_t j, i;
    int32_t y = 0;
    int32_t *w;
    uint16_t s = 0;
    if (n->primed && !((n->u >= NNIK_DUTY_MAX && d > 0) || (n->u <= -NNIK_DUTY_MAX && d < 0))) {
        int16_t d2 = nnik_nn_rnd16(d, NNIK_NN_S2 & 7);
        w = &n->w1[0][0];
        for (j = 0; j < NNIK_NN_HID; j++, w += NNIK_NN_IN) {
            int16_t h = n->h[j];
            int32_t w2 = n->w2[j];
            n->w2[j] = nnik_nn_update(w2, d2, h, NNIK_NN_S2, NNIK_NN_W2_LIM);
            if ((j & (NNIK_NN_W1_EVERY - 1)) == phase) {
                int16_t g = (int16_t)(32767 - nnik_nn_shr15(nnik_nn_mac(0, h, h)));
                int16_t t = nnik_ctl_s16(nnik_nn_asr(nnik_nn_mac(0, d, (int16_t)(w2 >> 16)), 12));
                int16_t dh = nnik_nn_rnd16(nnik_nn_shr15(nnik_nn_mac(0, t, g)), NNIK_NN_S1 & 7);
                nnik_nn_row(w, dh, n->x);
            }
        }
    }
    w = &n->w1[0][0];
    for (j = 0; j < NNIK_NN_HID; j++, w += NNIK_NN_IN) {
        int32_t a = nnik_nn_dot(w, x, &s);
        int16_t h = nnik_tanh(nnik_ctl_s16(nnik_nn_asr(a, 12)));
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
