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
    int32_t *w1; /* NNIK_NN_HID rows of NNIK_NN_IN master words, in nnik_nn_w1 */
    int32_t *w2; /* NNIK_NN_HID master words, in nnik_nn_w2 */
    int16_t x[NNIK_NN_IN]; /* the last forward pass' inputs and hidden outputs */
    int16_t h[NNIK_NN_HID];
    int16_t u; /* and its output (duty) */
    uint8_t primed; /* a forward pass is cached */
} nnik_nn_t;

/* the weights in RAM start as the initial ones at power-on (the C start-up copies them, outside any
 * tick); a reset copies them again from the flash copy */
static int32_t nnik_nn_w1[NNIK_NN_NETS * NNIK_NN_HID * NNIK_NN_IN] = NNIK_NN_W1_INIT;
static int32_t nnik_nn_w2[NNIK_NN_NETS * NNIK_NN_HID] = NNIK_NN_W2_INIT;
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

/* sat16(p >> 12) in 16-bit arithmetic: 16 (p >> 16) + (the low half >> 12), the high half
 * deciding the saturation */
NNIK_NN_INLINE int16_t nnik_nn_sat12(int32_t p)
{
    int16_t hi = (int16_t)(p >> 16), r;
    if (hi >= 2048)
        return 32767;
    if (hi < -2048)
        return -32767;
    r = (int16_t)(hi * 16 + (int16_t)((uint16_t)p >> 12));
    return r == -32768 ? -32767 : r;
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

/* Learning updates of n master words: w[i] += rnd(a x[i], 8 q) (q whole bytes; rnd adds the top
 * bit of the bytes dropped), then the exact clamp to +-lim where a new word may have left it.  On
 * the AVR one unrolled inline block: per word the product (AVR201), the byte shift by register
 * choice (NNIK_NN_ADD_<q>), and the top bits compared to flag a word that may need the clamp (bits
 * 31 and 30 differ: beyond +-2^30; bits 31, 30, 29 differ: beyond +-2^29).  Elsewhere plain C.  The
 * same values everywhere.  nnik_nn_unit: a hidden unit's delta and its 4 first-layer words (rate
 * NNIK_NN_S1; nnik_nn_row on the host); nnik_nn_out: the 8 output weights (rate NNIK_NN_S2). */
NNIK_NN_INLINE void nnik_nn_clamp_all(int32_t *w, uint8_t n, int32_t lim)
{
    uint8_t i;
    for (i = 0; i < n; i++)
        w[i] = w[i] > lim ? lim : (w[i] < -lim ? -lim : w[i]);
}

#if defined(__GNUC__) && defined(__AVR__)
#define NNIK_NN_ADD_0 "add %A[v], %A[acc]\n\tadc %B[v], %B[acc]\n\tadc %C[v], %C[acc]\n\tadc %D[v], %D[acc]\n\t"
#define NNIK_NN_ADD_1 "lsl %A[acc]\n\tadc %A[v], %B[acc]\n\tadc %B[v], %C[acc]\n\tadc %C[v], %D[acc]\n\tadc %D[v], %[z]\n\t"
#define NNIK_NN_ADD_2 "lsl %B[acc]\n\tadc %A[v], %C[acc]\n\tadc %B[v], %D[acc]\n\tadc %C[v], %[z]\n\tadc %D[v], %[z]\n\t"
#define NNIK_NN_ADD_3 "lsl %C[acc]\n\tadc %A[v], %D[acc]\n\tadc %B[v], %[z]\n\tadc %C[v], %[z]\n\tadc %D[v], %[z]\n\t"
#if (NNIK_NN_S1 >> 3) == 0
#define NNIK_NN_ADD_W1 NNIK_NN_ADD_0
#elif (NNIK_NN_S1 >> 3) == 1
#define NNIK_NN_ADD_W1 NNIK_NN_ADD_1
#elif (NNIK_NN_S1 >> 3) == 2
#define NNIK_NN_ADD_W1 NNIK_NN_ADD_2
#else
#define NNIK_NN_ADD_W1 NNIK_NN_ADD_3
#endif
#if (NNIK_NN_S2 >> 3) == 0
#define NNIK_NN_ADD_W2 NNIK_NN_ADD_0
#elif (NNIK_NN_S2 >> 3) == 1
#define NNIK_NN_ADD_W2 NNIK_NN_ADD_1
#elif (NNIK_NN_S2 >> 3) == 2
#define NNIK_NN_ADD_W2 NNIK_NN_ADD_2
#else
#define NNIK_NN_ADD_W2 NNIK_NN_ADD_3
#endif
/* acc = A * B (int16 x int16 -> int32, signed): AVR201's muls16x16_32 (no accumulator to clear);
 * z must be zero; clobbers r0, r1 (the caller clears __zero_reg__) */
#define NNIK_NN_MUL_ASM(A, B)                                                                          \
    "muls %B[" A "], %B[" B "]\n\tmovw %C[acc], r0\n\tmul %A[" A "], %A[" B "]\n\tmovw %A[acc], r0\n\t"      \
    "mulsu %B[" A "], %A[" B "]\n\tsbc %D[acc], %[z]\n\tadd %B[acc], r0\n\tadc %C[acc], r1\n\tadc %D[acc], %[z]\n\t" \
    "mulsu %B[" B "], %A[" A "]\n\tsbc %D[acc], %[z]\n\tadd %B[acc], r0\n\tadc %C[acc], r1\n\tadc %D[acc], %[z]\n\t"
/* one master word at Z: += rnd(A * (the int16 at X+, into X), 8 q) by ADD; z: zero during the
 * product, then the sign byte, then the flag's scratch */
#define NNIK_NN_UPD_STEP_AX(ADD, A, X)                                                               \
    "clr %[z]\n\tld %A[" X "], X+\n\tld %B[" X "], X+\n\t" NNIK_NN_MUL_ASM(A, X)                        \
    "ldd %A[v], Z+0\n\tldd %B[v], Z+1\n\tldd %C[v], Z+2\n\tldd %D[v], Z+3\n\t"                          \
    "sbrc %D[acc], 7\n\tcom %[z]\n\t" ADD                                                              \
    "st Z+, %A[v]\n\tst Z+, %B[v]\n\tst Z+, %C[v]\n\tst Z+, %D[v]\n\t"                                   \
    "mov %[z], %D[v]\n\tlsl %[z]\n\teor %[z], %D[v]\n\tor %[f], %[z]\n\t"
#define NNIK_NN_UPD_STEP(ADD) NNIK_NN_UPD_STEP_AX(ADD, "a", "x")
#define NNIK_NN_UPD_OPERANDS                                                                         \
    : [acc] "=&r"(acc), [v] "=&r"(v), [x] "=&a"(xv), [z] "=&r"(z), [f] "=&r"(flag), "+z"(wp), "+x"(x) \
    : [a] "a"(a)                                                                                     \
    : "memory", "r0"
#define NNIK_NN_UPD_LOCALS                                                                           \
    int32_t *wp = w, acc, v;                                                                         \
    int16_t xv;                                                                                      \
    uint8_t flag, z

/* OUT (int16, in r16..r31) = sat16(acc >> 12) (nnik_nn_sat12's value): the top 3 bytes of acc
 * (destroyed) shifted 4 bits fit when the top byte is the sign of the next; S a scratch register */
#define NNIK_NN_SAT12_ASM(OUT, S)                                                                      \
    ".rept 4\n\tasr %D[acc]\n\tror %C[acc]\n\tror %B[acc]\n\t.endr\n\t"                                \
    "mov %[" S "], %C[acc]\n\tlsl %[" S "]\n\tsbc %[" S "], %[" S "]\n\tcp %[" S "], %D[acc]\n\tbrne 2f\n\t"     \
    "mov %A[" OUT "], %B[acc]\n\tmov %B[" OUT "], %C[acc]\n\tcpi %A[" OUT "], 0\n\tbrne 3f\n\t"               \
    "cpi %B[" OUT "], 0x80\n\tbrne 3f\n\tldi %A[" OUT "], 1\n\trjmp 3f\n"                                   \
    "2:\n\tldi %A[" OUT "], 0xFF\n\tldi %B[" OUT "], 0x7F\n\tsbrs %D[acc], 7\n\trjmp 3f\n\t"                 \
    "ldi %A[" OUT "], 0x01\n\tldi %B[" OUT "], 0x80\n"                                                  \
    "3:\n\t"

/* tanh of a hidden sum: nnik_tanh(nnik_nn_sat12(a)), the saturation in an inline block */
NNIK_NN_INLINE int16_t nnik_nn_act(int32_t acc)
{
    int16_t r;
    uint8_t s;
    __asm__(NNIK_NN_SAT12_ASM("r", "s") : [acc] "+r"(acc), [r] "=&d"(r), [s] "=&r"(s));
    return nnik_tanh(r);
}

/* One hidden unit's learning on the AVR in one inline block (the host's nnik_nn_unit, the same
 * values): its delta from its cached output h, its output weight's top half w2 and delta_out d, then
 * its 4 first-layer words.  g = 32767 - (h h >> 15) is 0x7FFF XOR (h h >> 15); t = sat16(d w2 >> 12)
 * from the product's top 3 bytes shifted 4 bits (it fits when the top byte is the sign of the next);
 * dh = (t g >> 15) shifted right S1 & 7 bits, the last bit out (carry) added: rounding half up. */
NNIK_NN_INLINE void nnik_nn_unit(int32_t *w, int16_t h, int16_t w2, int16_t d, const int16_t *x)
{
    int32_t *wp = w, acc, v;
    uint8_t flag, z;
    __asm__("clr %[z]\n\t" NNIK_NN_MUL_ASM("h", "h")
            "lsl %B[acc]\n\trol %C[acc]\n\trol %D[acc]\n\t"
            "mov %A[h], %C[acc]\n\tcom %A[h]\n\tmov %B[h], %D[acc]\n\tcom %B[h]\n\tsubi %B[h], 0x80\n\t"
            NNIK_NN_MUL_ASM("d", "w")
            NNIK_NN_SAT12_ASM("w", "f") NNIK_NN_MUL_ASM("w", "h")
            "lsl %B[acc]\n\trol %C[acc]\n\trol %D[acc]\n\t"
            ".if %[r]\n\t.rept %[r]\n\tasr %D[acc]\n\tror %C[acc]\n\t.endr\n\t"
            "adc %C[acc], %[z]\n\tadc %D[acc], %[z]\n\t.endif\n\t"
            "mov %A[h], %C[acc]\n\tmov %B[h], %D[acc]\n\tclr %[f]\n\t"
            NNIK_NN_UPD_STEP_AX(NNIK_NN_ADD_W1, "h", "d") NNIK_NN_UPD_STEP_AX(NNIK_NN_ADD_W1, "h", "d")
            NNIK_NN_UPD_STEP_AX(NNIK_NN_ADD_W1, "h", "d") NNIK_NN_UPD_STEP_AX(NNIK_NN_ADD_W1, "h", "d")
            "clr __zero_reg__"
            : [acc] "=&r"(acc), [v] "=&r"(v), [z] "=&r"(z), [f] "=&r"(flag), "+z"(wp), "+x"(x), [h] "+a"(h),
              [w] "+a"(w2), [d] "+a"(d)
            : [r] "n"(NNIK_NN_S1 & 7)
            : "memory", "r0");
    if (flag & 0x80)
        nnik_nn_clamp_all(w, NNIK_NN_IN, NNIK_NN_W1_LIM);
}

NNIK_NN_INLINE void nnik_nn_out(int32_t *w, int16_t a, const int16_t *x)
{
    NNIK_NN_UPD_LOCALS;
    __asm__("clr %[f]\n\t" NNIK_NN_UPD_STEP(NNIK_NN_ADD_W2) NNIK_NN_UPD_STEP(NNIK_NN_ADD_W2)
                NNIK_NN_UPD_STEP(NNIK_NN_ADD_W2) NNIK_NN_UPD_STEP(NNIK_NN_ADD_W2) NNIK_NN_UPD_STEP(NNIK_NN_ADD_W2)
                    NNIK_NN_UPD_STEP(NNIK_NN_ADD_W2) NNIK_NN_UPD_STEP(NNIK_NN_ADD_W2) NNIK_NN_UPD_STEP(NNIK_NN_ADD_W2)
                        "clr __zero_reg__" NNIK_NN_UPD_OPERANDS);
    if (flag & 0xC0)
        nnik_nn_clamp_all(w, NNIK_NN_HID, NNIK_NN_W2_LIM);
}
#else
NNIK_NN_INLINE void nnik_nn_row(int32_t *w, int16_t a, const int16_t *x)
{
    uint8_t i;
    for (i = 0; i < NNIK_NN_IN; i++)
        w[i] = nnik_nn_update(w[i], a, x[i], NNIK_NN_S1, NNIK_NN_W1_LIM);
}

NNIK_NN_INLINE int16_t nnik_nn_act(int32_t a)
{
    return nnik_tanh(nnik_nn_sat12(a));
}

NNIK_NN_INLINE void nnik_nn_unit(int32_t *w, int16_t h, int16_t w2, int16_t d, const int16_t *x)
{
    int16_t g = (int16_t)(32767 - nnik_nn_shr15(nnik_nn_mac(0, h, h)));
    int16_t t = nnik_nn_sat12(nnik_nn_mac(0, d, w2));
    nnik_nn_row(w, nnik_nn_rnd16(nnik_nn_shr15(nnik_nn_mac(0, t, g)), NNIK_NN_S1 & 7), x);
}

NNIK_NN_INLINE void nnik_nn_out(int32_t *w, int16_t a, const int16_t *x)
{
    uint8_t i;
    for (i = 0; i < NNIK_NN_HID; i++)
        w[i] = nnik_nn_update(w[i], a, x[i], NNIK_NN_S2, NNIK_NN_W2_LIM);
}
#endif

/* all weights from the initial ones (flash), every net's cache cleared */
static void nnik_nn_load(nnik_nn_t *nets)
{
    uint8_t i;
    for (i = 0; i < NNIK_NN_NETS * NNIK_NN_HID * NNIK_NN_IN; i++)
        nnik_nn_w1[i] = NNIK_RD_I32(&nnik_nn_w1_init[i]);
    for (i = 0; i < NNIK_NN_NETS * NNIK_NN_HID; i++)
        nnik_nn_w2[i] = NNIK_RD_I32(&nnik_nn_w2_init[i]);
    for (i = 0; i < NNIK_NN_NETS; i++) {
        nets[i].u = 0;
        nets[i].primed = 0;
    }
}

/* the first-layer rows of the units j = phase, phase + NNIK_NN_W1_EVERY, ... learn (delta_out d);
 * a function of its own: the unit's inline block needs most of the registers */
NNIK_NN_OWN_REGS void nnik_nn_units(nnik_nn_t *n, int16_t d, uint8_t phase)
{
    uint8_t j;
    for (j = phase; j < NNIK_NN_HID; j += NNIK_NN_W1_EVERY)
        nnik_nn_unit(n->w1 + j * NNIK_NN_IN, n->h[j], (int16_t)(n->w2[j] >> 16), d, n->x);
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
        nnik_nn_units(n, d, phase);
        nnik_nn_out(n->w2, d2, n->h); /* after the rows: delta_h used the forward pass' w2 */
    }
    w = n->w1;
    for (j = 0; j < NNIK_NN_HID; j++, w += NNIK_NN_IN) {
        int32_t a = nnik_nn_dot(w, x, &s);
        int16_t h = nnik_nn_act(a);
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
