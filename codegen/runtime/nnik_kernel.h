/*
 * nnik_kernel.h - primitives of nnik's "fast" MLP kernel.  A NAME.c generated with
 * kernel = "fast" (nnik.fixedpoint.quantize(..., kernel="fast")) includes this header and
 * runs its network on one of three implementations, all bit-exact with the Python integer
 * model (nnik.fixedpoint.IntegerModel):
 *
 *   NNIK_KERNEL_AVR  avr-gcc: the whole network in one asm statement built from the
 *                    assembler macros NNIK_AVR_ASM_MACROS (hardware MUL, LPM tables)
 *   NNIK_KERNEL_P18  SDCC pic16: the network in one __asm__ statement built from the
 *                    NNIK_P18_* string macros (MULLW/MULWF, TBLRD tables)
 *   NNIK_KERNEL_C    anything else (host gcc, XC8, CCS, ...): portable C99 value primitives
 *
 * -DNNIK_PORTABLE forces NNIK_KERNEL_C on any compiler; -DNNIK_INSTRUMENT (host checks) also
 * does, with exact int64 accumulators.  Network shapes the assembly paths do not cover
 * (see nnik/fastc_avr.py, nnik/fastc_p18.py) use the value primitives on AVR/PIC18 too.
 *
 * Conventions: "u" operands are offset binary (x + 32768 as uint16: x * w = xu * w - 32768 w,
 * and the generator folds -32768 * sum(w) into each accumulator's start value, so every
 * product is unsigned); accumulators are int32 values held modulo 2^32 (partial sums may
 * wrap, final ones are in range by nnik's range analysis).  Cycle counts below are exact
 * for straight-line code (AVR: CPU cycles; PIC18: instruction cycles, Fosc/4).
 *
 * ---- value primitives (static inline; avr-gcc inline asm on AVR, C elsewhere) ---------------
 *   nnik_acc_t nnik_macu(nnik_acc_t acc, uint16_t xu, uint16_t w)    acc + xu * w
 *   nnik_acc_t nnik_msubu(nnik_acc_t acc, uint16_t xu, uint16_t w)   acc - xu * w
 *       16x16 -> 32 multiply-accumulate.  AVR: 4 MUL, 22 cycles (+2 LDI per constant w)
 *   nnik_acc_t nnik_macs(nnik_acc_t acc, uint16_t xu, int16_t w)     acc + xu * w, w signed
 *       (output layer looped over flash tables).  AVR: nnik_macu + a conditional subtract
 *   nnik_acc_t nnik_mac16(nnik_acc_t acc, int16_t x, int16_t w)      acc + x * w, signed
 *       (hidden layers looped over flash tables; C on every compiler)
 *   int16_t nnik_xs16(uint16_t xu)            xu - 32768: offset binary back to int16
 *   uint16_t nnik_tu16(uint32_t acc)          (acc >> 16) ^ 0x8000: top half, offset binary
 *   uint16_t nnik_tu_shr(uint32_t acc, sh)    ((int32)acc >> sh) + 32768 as uint16, 1 <= sh
 *       <= 23 (constant), the result must fit int16: the tanh input.  AVR: sh = 16 is free,
 *       sh = 15 costs 5 cycles, other sh a loop
 *   uint16_t nnik_lerp_u16(const uint16_t *p, uint8_t f)
 *       p[0] + (((p[1] - p[0]) * f + 128) >> 8), p in flash, p[1] >= p[0]: one step of the
 *       fast tanh table.  AVR: 4 LPM + 2 MUL, 25 cycles once Z holds p
 *   uint16_t nnik_shr24_16(uint32_t v, k)     (uint16_t)(v >> k), 0 <= k <= 8, v < 2^(k+16):
 *       the layer-1 input pre-shift.  AVR: 6 cycles per step of k
 *   int32_t nnik_out_shr(uint32_t o, n)       (int32)o >> n (n constant): output rounding
 *       (the rounding half is in o's start value).  AVR: n >= 16 is a 16-bit shift, 4/step
 *   int32_t nnik_s32(uint32_t u)              u as a two's complement int32 (no UB)
 *   nnik_shr32(u, k), nnik_sar32(v, k)        32-bit logical / arithmetic right shifts
 *       (macros; under SDCC done bytewise, see below)
 *
 * ---- AVR assembler macros (GNU as; NNIK_AVR_ASM_MACROS ... NNIK_AVR_ASM_PURGE) ---------------
 *   A block that uses them starts with the string NNIK_AVR_ASM_MACROS and ends with
 *   NNIK_AVR_ASM_PURGE (so each asm statement defines and removes them).  Arguments are
 *   registers (a0..a3 = bytes of a 32-bit value, low first) and constants; "up" marks
 *   registers that must be r16..r31 (LDI/SUBI/CPI).  r0 and r1 are scratch: the block must
 *   end with "clr r1".  z is a register holding 0.
 *     nnik_ldi32  a0..a3(up), K                      a = K                               4
 *     nnik_macu   a0..a3, x0,x1, W, t0,t1(up), z     a += x * W (0 <= W < 65536)         22
 *     nnik_msubu  a0..a3, x0,x1, W, t0,t1(up), z     a -= x * W                          22
 *     nnik_macu8  a0..a3, x0,x1, W, t0(up), z        a += x * W, W < 256                 12
 *     nnik_msubu8 a0..a3, x0,x1, W, t0(up), z        a -= x * W, W < 256                 12
 *     nnik_in     a0..a3(up), x0,x1, LO, SPAN, C, K, t(up)
 *         v = 4 bytes from Z+ (int32); w = v - LO clamped to [0, SPAN] (T flag set when
 *         clamped); x = (w + C) >> K (3-byte shift, K <= 8)          in domain: 27 + 3 K
 *         = nnik_inw (the clamp: w in a0..a2; 22 cycles in domain) + nnik_inx a0,a1,a2(up),
 *         x0,x1, C, K (5 + 3 K)
 *     nnik_ldi48  r0..r5(up), KLO, KHI               r = KHI:KLO (48-bit)                 6
 *     nnik_mac48  r0..r5, w0,w1,w2, A, t(up), z       r += w * A (48 += 24 x 32 unsigned,
 *     nnik_msub48 r0..r5, w0,w1,w2, A, t(up), z       r -= w * A   A constant; zero bytes of
 *         A are skipped): the affine base of residual models           70 (all 4 bytes of A)
 *     nnik_tanh8  h0,h1, th,tf, TAB, t0,t1, z         h = fast tanh, node step 2^8, of the
 *         offset-binary input (th ^ 0x80):tf; TAB the table in flash; Z clobbered          28
 *     nnik_tanh7  h0,h1, th,tf, TAB, t0,t1, z         the same, node step 2^7 (tf clobbered) 33
 *     nnik_tanhs  h0,h1, th,tf, TAB, S, t0,t1, z      the same for any node step 2^S, 4 <= S
 *         <= 8 (tf clobbered)                                                      34 + S
 *     nnik_satge  a0..a3(up), LIM, VAL, t(up)         if (int32)a >= LIM: a = VAL   in range: 9
 *     nnik_satlt  a0..a3(up), LIM, VAL, t(up)         if (int32)a < LIM: a = VAL    in range: 9
 *     nnik_out    a0..a3, N, t0,t1,t2                 (int32)a >> N, 16 <= N < 24, stored to
 *         X+ (4 bytes)                                                       12 + 2 (N - 16)
 *
 * ---- PIC18 (SDCC pic16) macros: gpasm text for __asm__("...") -----------------------------
 *   Each expands to a string literal; a generated model strings them into one __asm__.  A, X,
 *   V, H, Y, FL are string literals naming byte addresses in the RAM bank the caller selected
 *   with BANKSEL ("_name+8"); K, W, LO, SPAN, C, TAB are integer literals or symbols.  SFRs
 *   are used by address (PRODL 0xFF3, PRODH 0xFF4, TABLAT 0xFF5, TBLPTRL/H/U 0xFF6..8, WREG
 *   0xFE8, STATUS 0xFD8); TBLPTRU must hold UPPER(TAB).
 *     NNIK_P18_SET32(A, K)          A = K (4 bytes)                                     8
 *     NNIK_P18_MACU(A, X, W)        A += X * W (32 += 16 x 16 unsigned, 4 MULLW)         31
 *     NNIK_P18_MSUBU(A, X, W)       A -= X * W                                          31
 *     NNIK_P18_MACU8(A, X, W)       A += X * W, W < 256 (2 MULLW)                        17
 *     NNIK_P18_MSUBU8(A, X, W)      A -= X * W, W < 256                                 17
 *     NNIK_P18_TANH8(H, Y, A, TAB)  H = fast tanh, node step 2^8, of the offset-binary input
 *         (A+3 ^ 0x80):A+2; Y a 2-byte scratch                                           43
 *     NNIK_P18_TANH7(H, Y, A, TAB)  the same, node step 2^7 (A+2 clobbered)               51
 *     NNIK_P18_IN(V, X, FL, LO, SPAN, C, K, L)  V (int32) -> V - LO clamped to [0, SPAN]
 *         (FL = 1 if clamped), + C; then K x NNIK_P18_SHR24_1(V) and X = V[0..1];
 *         L: a label prefix unique in the file                               in domain: 27
 *     NNIK_P18_TCOPY(Y, A), NNIK_P18_SAR16(Y), NNIK_P18_FSHL(A), NNIK_P18_TANHS_(H, Y, A, TAB, K)
 *         the fast tanh for any node step 2^S (4 <= S <= 8): TCOPY, (S - 1) x SAR16,
 *         (8 - S) x FSHL, TANHS_ with K = 2^(16 - S)                                59 + S
 *     NNIK_P18_SATGE(A, LIM, VAL, L)   if (int32)A >= LIM: A = VAL (L: label prefix)
 *     NNIK_P18_SATLT(A, LIM, VAL, L)   if (int32)A < LIM: A = VAL         in range: 11 to 14
 *     NNIK_P18_SHL1_4(A)            A[0..3] <<= 1                                         5
 *     NNIK_P18_INW(V, FL, LO, SPAN, L) + NNIK_P18_INX(V, C)  the two halves of NNIK_P18_IN
 *     NNIK_P18_SHR24_1(V)           V[0..2] >>= 1, logical                                4
 *     residual / output stage:
 *     NNIK_P18_SET48(R, KLO, KHI)   R = KHI:KLO (6 bytes)                                12
 *     NNIK_P18_P48(op, opc, R, O, WB, B)  PROD = byte WB * B, added at R+O, R+O+1 with
 *         op/opc = "addwf"/"addwfc" or "subwf"/"subwfb"; then NNIK_P18_C48_0 and one
 *         NNIK_P18_C48(opc, R, O) per higher byte carries it; NNIK_P18_P48TOP(op, R, WB, B)
 *         for the top byte (R+5)                                          6 (+1 +1 per byte)
 *     NNIK_P18_SHL48_1(R)           R[1..5] <<= 1                                         5
 *     NNIK_P18_SAR32_1(A), NNIK_P18_SAR32_8(A)   A >>= 1, A >>= 8 (arithmetic)        5, 10
 *     NNIK_P18_ADD32C(A, K), NNIK_P18_ADD32(A, S)  A += K, A += S (4 bytes)             8, 8
 *     NNIK_P18_SAR1_2(A)            A[2..3] >>= 1, arithmetic                             3
 *     NNIK_P18_SHL1(A)              A[1..3] <<= 1 (A[1] bit 0 gets junk: for tanh input
 *                                   shifts 8..15, where only A[1]'s top bits are used)    3
 *     NNIK_P18_OUT_(A)              A = (int16)A[2..3] sign-extended to int32, in place    9
 */
#ifndef NNIK_KERNEL_H
#define NNIK_KERNEL_H

#include <stdint.h>
#include "nnik_flash.h"

#if defined(__AVR__) && defined(__GNUC__) && !defined(NNIK_PORTABLE) && !defined(NNIK_INSTRUMENT)
#define NNIK_KERNEL_AVR 1
#elif (defined(__SDCC_pic16) || defined(SDCC_pic16)) && !defined(NNIK_PORTABLE) && !defined(NNIK_INSTRUMENT)
#define NNIK_KERNEL_P18 1
#else
#define NNIK_KERNEL_C 1
#endif

#ifdef NNIK_INSTRUMENT
typedef int64_t nnik_acc_t;
#else
typedef uint32_t nnik_acc_t;
#endif

#if defined(__GNUC__)
#define NNIK_INLINE static inline __attribute__((always_inline))
#else
#define NNIK_INLINE static inline
#endif

/* SDCC compiles every static function it sees: a PIC18 model whose assembly covers the
   whole call defines NNIK_P18_ASM_ONLY before including this header to leave them out */
#if !(defined(NNIK_KERNEL_P18) && defined(NNIK_P18_ASM_ONLY))
/* u as two's complement int32 without implementation-defined conversion */
NNIK_INLINE int32_t nnik_s32(uint32_t u)
{
    return (u & 0x80000000UL) ? (int32_t)-(int32_t)(~u) - 1 : (int32_t)u;
}

/* offset binary xu (x + 32768) back to the int16 x, without implementation-defined conversion */
NNIK_INLINE int16_t nnik_xs16(uint16_t xu)
{
    return (xu & 0x8000u) ? (int16_t)(uint16_t)(xu - 32768u) : (int16_t)((int16_t)xu - 32767 - 1);
}

/* acc + x * w, signed int16 x int16 (layers looped over flash tables; exact in both
   accumulator types) */
NNIK_INLINE nnik_acc_t nnik_mac16(nnik_acc_t acc, int16_t x, int16_t w)
{
    int32_t p = (int32_t)x * w;
#ifdef NNIK_INSTRUMENT
    return acc + p;
#else
    return acc + (uint32_t)p;
#endif
}

/*
 * 32-bit shifts: nnik_shr32(u, k) = u >> k (uint32), nnik_sar32(v, k) = v >> k (int32,
 * arithmetic), 0 <= k <= 31.  SDCC 4.2's pic16 port miscompiles some 32-bit right shifts
 * (k = 15 and k = 17..19 seen wrong in gpsim, depending on how its registers overlap), so
 * under SDCC they are done a byte and a bit at a time on uint8_t; elsewhere they are >>.
 */
#if defined(__SDCC) || defined(SDCC)
typedef union { uint32_t u; uint8_t b[4]; } nnik_u32b;

static uint32_t nnik_shr32_fill(uint32_t u, uint8_t k, uint8_t fill)
{
    nnik_u32b x;
    uint8_t c;
    x.u = u;
    while (k >= 8) {
        x.b[0] = x.b[1];
        x.b[1] = x.b[2];
        x.b[2] = x.b[3];
        x.b[3] = fill;
        k -= 8;
    }
    while (k) {
        c = (uint8_t)(fill << 7);
        x.b[0] = (uint8_t)((uint8_t)(x.b[0] >> 1) | (uint8_t)(x.b[1] << 7));
        x.b[1] = (uint8_t)((uint8_t)(x.b[1] >> 1) | (uint8_t)(x.b[2] << 7));
        x.b[2] = (uint8_t)((uint8_t)(x.b[2] >> 1) | (uint8_t)(x.b[3] << 7));
        x.b[3] = (uint8_t)((uint8_t)(x.b[3] >> 1) | c);
        k--;
    }
    return x.u;
}
#define nnik_shr32(u, k) nnik_shr32_fill((uint32_t)(u), (uint8_t)(k), 0)
#define nnik_sar32(v, k) nnik_s32(nnik_shr32_fill((uint32_t)(v), (uint8_t)(k), \
                                                  (uint8_t)(((uint32_t)(v) & 0x80000000UL) ? 0xFF : 0)))
#else
#define nnik_shr32(u, k) ((uint32_t)(u) >> (k))
#define nnik_sar32(v, k) ((int32_t)(v) >> (k))
#endif

#if defined(NNIK_KERNEL_AVR)
/* ------------------------------------------------------------------------------ AVR */

#define NNIK_AVR_ASM_MACROS \
    ".macro nnik_ldi32 a0, a1, a2, a3, k\n" \
    "ldi \\a0, lo8(\\k)\n ldi \\a1, hi8(\\k)\n ldi \\a2, hlo8(\\k)\n ldi \\a3, hhi8(\\k)\n" \
    ".endm\n" \
    ".macro nnik_macu a0, a1, a2, a3, x0, x1, w, t0, t1, z\n" \
    "ldi \\t0, lo8(\\w)\n ldi \\t1, hi8(\\w)\n" \
    "mul \\x0, \\t0\n add \\a0, r0\n adc \\a1, r1\n adc \\a2, \\z\n adc \\a3, \\z\n" \
    "mul \\x1, \\t1\n add \\a2, r0\n adc \\a3, r1\n" \
    "mul \\x1, \\t0\n add \\a1, r0\n adc \\a2, r1\n adc \\a3, \\z\n" \
    "mul \\x0, \\t1\n add \\a1, r0\n adc \\a2, r1\n adc \\a3, \\z\n" \
    ".endm\n" \
    ".macro nnik_msubu a0, a1, a2, a3, x0, x1, w, t0, t1, z\n" \
    "ldi \\t0, lo8(\\w)\n ldi \\t1, hi8(\\w)\n" \
    "mul \\x0, \\t0\n sub \\a0, r0\n sbc \\a1, r1\n sbc \\a2, \\z\n sbc \\a3, \\z\n" \
    "mul \\x1, \\t1\n sub \\a2, r0\n sbc \\a3, r1\n" \
    "mul \\x1, \\t0\n sub \\a1, r0\n sbc \\a2, r1\n sbc \\a3, \\z\n" \
    "mul \\x0, \\t1\n sub \\a1, r0\n sbc \\a2, r1\n sbc \\a3, \\z\n" \
    ".endm\n" \
    ".macro nnik_macu8 a0, a1, a2, a3, x0, x1, w, t0, z\n" \
    "ldi \\t0, lo8(\\w)\n" \
    "mul \\x0, \\t0\n add \\a0, r0\n adc \\a1, r1\n adc \\a2, \\z\n adc \\a3, \\z\n" \
    "mul \\x1, \\t0\n add \\a1, r0\n adc \\a2, r1\n adc \\a3, \\z\n" \
    ".endm\n" \
    ".macro nnik_msubu8 a0, a1, a2, a3, x0, x1, w, t0, z\n" \
    "ldi \\t0, lo8(\\w)\n" \
    "mul \\x0, \\t0\n sub \\a0, r0\n sbc \\a1, r1\n sbc \\a2, \\z\n sbc \\a3, \\z\n" \
    "mul \\x1, \\t0\n sub \\a1, r0\n sbc \\a2, r1\n sbc \\a3, \\z\n" \
    ".endm\n" \
    ".macro nnik_inw a0, a1, a2, a3, lo, span, t\n" \
    "ld \\a0, Z+\n ld \\a1, Z+\n ld \\a2, Z+\n ld \\a3, Z+\n" \
    "subi \\a0, lo8(\\lo)\n sbci \\a1, hi8(\\lo)\n sbci \\a2, hlo8(\\lo)\n sbci \\a3, hhi8(\\lo)\n" \
    "brlt 1f\n" \
    "cpi \\a0, lo8((\\span) + 1)\n ldi \\t, hi8((\\span) + 1)\n cpc \\a1, \\t\n" \
    "ldi \\t, hlo8((\\span) + 1)\n cpc \\a2, \\t\n ldi \\t, hhi8((\\span) + 1)\n cpc \\a3, \\t\n" \
    "brlo 3f\n" \
    "ldi \\a0, lo8(\\span)\n ldi \\a1, hi8(\\span)\n ldi \\a2, hlo8(\\span)\n rjmp 2f\n" \
    "1: ldi \\a0, 0\n ldi \\a1, 0\n ldi \\a2, 0\n" \
    "2: set\n" \
    "3:\n" \
    ".endm\n" \
    ".macro nnik_inx a0, a1, a2, x0, x1, c, k\n" \
    "subi \\a0, lo8(-(\\c))\n sbci \\a1, hi8(-(\\c))\n sbci \\a2, hlo8(-(\\c))\n" \
    ".rept \\k\n lsr \\a2\n ror \\a1\n ror \\a0\n .endr\n" \
    "mov \\x0, \\a0\n mov \\x1, \\a1\n" \
    ".endm\n" \
    ".macro nnik_in a0, a1, a2, a3, x0, x1, lo, span, c, k, t\n" \
    "nnik_inw \\a0, \\a1, \\a2, \\a3, \\lo, \\span, \\t\n nnik_inx \\a0, \\a1, \\a2, \\x0, \\x1, \\c, \\k\n" \
    ".endm\n" \
    ".macro nnik_ldi48 r0, r1, r2, r3, r4, r5, klo, khi\n" \
    "ldi \\r0, lo8(\\klo)\n ldi \\r1, hi8(\\klo)\n ldi \\r2, hlo8(\\klo)\n ldi \\r3, hhi8(\\klo)\n" \
    "ldi \\r4, lo8(\\khi)\n ldi \\r5, hi8(\\khi)\n" \
    ".endm\n" \
    ".macro nnik_p48 op, opc, p, q, w, t, z, c1, c2, c3, c4\n" \
    "mul \\w, \\t\n \\op \\p, r0\n" \
    ".ifnb \\q\n \\opc \\q, r1\n .endif\n" \
    ".ifnb \\c1\n \\opc \\c1, \\z\n .endif\n .ifnb \\c2\n \\opc \\c2, \\z\n .endif\n" \
    ".ifnb \\c3\n \\opc \\c3, \\z\n .endif\n .ifnb \\c4\n \\opc \\c4, \\z\n .endif\n" \
    ".endm\n" \
    ".macro nnik_mac48x op, opc, r0, r1, r2, r3, r4, r5, w0, w1, w2, a, t, z\n" \
    ".if (\\a) & 0xFF\n ldi \\t, lo8(\\a)\n" \
    "nnik_p48 \\op, \\opc, \\r0, \\r1, \\w0, \\t, \\z, \\r2, \\r3, \\r4, \\r5\n" \
    "nnik_p48 \\op, \\opc, \\r1, \\r2, \\w1, \\t, \\z, \\r3, \\r4, \\r5\n" \
    "nnik_p48 \\op, \\opc, \\r2, \\r3, \\w2, \\t, \\z, \\r4, \\r5\n .endif\n" \
    ".if ((\\a) >> 8) & 0xFF\n ldi \\t, hi8(\\a)\n" \
    "nnik_p48 \\op, \\opc, \\r1, \\r2, \\w0, \\t, \\z, \\r3, \\r4, \\r5\n" \
    "nnik_p48 \\op, \\opc, \\r2, \\r3, \\w1, \\t, \\z, \\r4, \\r5\n" \
    "nnik_p48 \\op, \\opc, \\r3, \\r4, \\w2, \\t, \\z, \\r5\n .endif\n" \
    ".if ((\\a) >> 16) & 0xFF\n ldi \\t, hlo8(\\a)\n" \
    "nnik_p48 \\op, \\opc, \\r2, \\r3, \\w0, \\t, \\z, \\r4, \\r5\n" \
    "nnik_p48 \\op, \\opc, \\r3, \\r4, \\w1, \\t, \\z, \\r5\n" \
    "nnik_p48 \\op, \\opc, \\r4, \\r5, \\w2, \\t, \\z\n .endif\n" \
    ".if ((\\a) >> 24) & 0xFF\n ldi \\t, hhi8(\\a)\n" \
    "nnik_p48 \\op, \\opc, \\r3, \\r4, \\w0, \\t, \\z, \\r5\n" \
    "nnik_p48 \\op, \\opc, \\r4, \\r5, \\w1, \\t, \\z\n" \
    "nnik_p48 \\op, \\opc, \\r5, , \\w2, \\t, \\z\n .endif\n" \
    ".endm\n" \
    ".macro nnik_mac48 r0, r1, r2, r3, r4, r5, w0, w1, w2, a, t, z\n" \
    "nnik_mac48x add, adc, \\r0, \\r1, \\r2, \\r3, \\r4, \\r5, \\w0, \\w1, \\w2, \\a, \\t, \\z\n" \
    ".endm\n" \
    ".macro nnik_msub48 r0, r1, r2, r3, r4, r5, w0, w1, w2, a, t, z\n" \
    "nnik_mac48x sub, sbc, \\r0, \\r1, \\r2, \\r3, \\r4, \\r5, \\w0, \\w1, \\w2, \\a, \\t, \\z\n" \
    ".endm\n" \
    ".macro nnik_tanh8 h0, h1, th, tf, tab, t0, t1, z\n" \
    "mov r30, \\th\n lsl r30\n sbc r31, r31\n" \
    "subi r30, lo8(-((\\tab) + 256))\n sbci r31, hi8(-((\\tab) + 256))\n" \
    "lpm \\h0, Z+\n lpm \\h1, Z+\n lpm \\t0, Z+\n lpm \\t1, Z\n" \
    "sub \\t0, \\h0\n sbc \\t1, \\h1\n" \
    "mul \\t0, \\tf\n lsl r0\n adc \\h0, r1\n adc \\h1, \\z\n" \
    "mul \\t1, \\tf\n add \\h0, r0\n adc \\h1, r1\n" \
    ".endm\n" \
    ".macro nnik_tanh7 h0, h1, th, tf, tab, t0, t1, z\n" \
    "mov r30, \\tf\n lsl r30\n mov r30, \\th\n rol r30\n sbc r31, r31\n lsl r30\n rol r31\n" \
    "subi r30, lo8(-((\\tab) + 512))\n sbci r31, hi8(-((\\tab) + 512))\n lsl \\tf\n" \
    "lpm \\h0, Z+\n lpm \\h1, Z+\n lpm \\t0, Z+\n lpm \\t1, Z\n" \
    "sub \\t0, \\h0\n sbc \\t1, \\h1\n" \
    "mul \\t0, \\tf\n lsl r0\n adc \\h0, r1\n adc \\h1, \\z\n" \
    "mul \\t1, \\tf\n add \\h0, r0\n adc \\h1, r1\n" \
    ".endm\n" \
    ".macro nnik_tanhs h0, h1, th, tf, tab, s, t0, t1, z\n" \
    "mov r30, \\tf\n mov r31, \\th\n .rept (\\s) - 1\n asr r31\n ror r30\n .endr\n andi r30, 0xFE\n" \
    "subi r30, lo8(-((\\tab) + (1 << (16 - (\\s)))))\n sbci r31, hi8(-((\\tab) + (1 << (16 - (\\s)))))\n" \
    ".rept 8 - (\\s)\n lsl \\tf\n .endr\n" \
    "lpm \\h0, Z+\n lpm \\h1, Z+\n lpm \\t0, Z+\n lpm \\t1, Z\n" \
    "sub \\t0, \\h0\n sbc \\t1, \\h1\n" \
    "mul \\t0, \\tf\n lsl r0\n adc \\h0, r1\n adc \\h1, \\z\n" \
    "mul \\t1, \\tf\n add \\h0, r0\n adc \\h1, r1\n" \
    ".endm\n" \
    ".macro nnik_satge a0, a1, a2, a3, lim, val, t\n" \
    "cpi \\a0, lo8(\\lim)\n ldi \\t, hi8(\\lim)\n cpc \\a1, \\t\n ldi \\t, hlo8(\\lim)\n cpc \\a2, \\t\n" \
    "ldi \\t, hhi8(\\lim)\n cpc \\a3, \\t\n brlt 1f\n" \
    "ldi \\a0, lo8(\\val)\n ldi \\a1, hi8(\\val)\n ldi \\a2, hlo8(\\val)\n ldi \\a3, hhi8(\\val)\n1:\n" \
    ".endm\n" \
    ".macro nnik_satlt a0, a1, a2, a3, lim, val, t\n" \
    "cpi \\a0, lo8(\\lim)\n ldi \\t, hi8(\\lim)\n cpc \\a1, \\t\n ldi \\t, hlo8(\\lim)\n cpc \\a2, \\t\n" \
    "ldi \\t, hhi8(\\lim)\n cpc \\a3, \\t\n brge 1f\n" \
    "ldi \\a0, lo8(\\val)\n ldi \\a1, hi8(\\val)\n ldi \\a2, hlo8(\\val)\n ldi \\a3, hhi8(\\val)\n1:\n" \
    ".endm\n" \
    ".macro nnik_out a0, a1, a2, a3, n, t0, t1, t2\n" \
    "mov \\t0, \\a2\n mov \\t1, \\a3\n" \
    ".rept (\\n) - 16\n asr \\t1\n ror \\t0\n .endr\n" \
    "st X+, \\t0\n st X+, \\t1\n lsl \\t1\n sbc \\t2, \\t2\n st X+, \\t2\n st X+, \\t2\n" \
    ".endm\n"
#define NNIK_AVR_ASM_PURGE \
    ".purgem nnik_ldi32\n .purgem nnik_macu\n .purgem nnik_msubu\n .purgem nnik_macu8\n" \
    ".purgem nnik_msubu8\n .purgem nnik_in\n .purgem nnik_tanh8\n .purgem nnik_tanh7\n" \
    ".purgem nnik_out\n .purgem nnik_tanhs\n .purgem nnik_satge\n .purgem nnik_satlt\n" \
    ".purgem nnik_inw\n .purgem nnik_inx\n .purgem nnik_ldi48\n .purgem nnik_p48\n .purgem nnik_mac48x\n" \
    ".purgem nnik_mac48\n .purgem nnik_msub48\n"


NNIK_INLINE uint32_t nnik_macu(uint32_t acc, uint16_t xu, uint16_t w)
{
    uint8_t z;
    __asm__ (
        "clr  %[z]"            "\n\t"
        "mul  %A[x], %A[w]"    "\n\t"
        "add  %A[acc], r0"     "\n\t"
        "adc  %B[acc], r1"     "\n\t"
        "adc  %C[acc], %[z]"   "\n\t"
        "adc  %D[acc], %[z]"   "\n\t"
        "mul  %B[x], %B[w]"    "\n\t"
        "add  %C[acc], r0"     "\n\t"
        "adc  %D[acc], r1"     "\n\t"
        "mul  %B[x], %A[w]"    "\n\t"
        "add  %B[acc], r0"     "\n\t"
        "adc  %C[acc], r1"     "\n\t"
        "adc  %D[acc], %[z]"   "\n\t"
        "mul  %A[x], %B[w]"    "\n\t"
        "add  %B[acc], r0"     "\n\t"
        "adc  %C[acc], r1"     "\n\t"
        "adc  %D[acc], %[z]"   "\n\t"
        "clr  __zero_reg__"
        : [acc] "+r" (acc), [z] "=&r" (z)
        : [x] "r" (xu), [w] "r" (w));
    return acc;
}

NNIK_INLINE uint32_t nnik_msubu(uint32_t acc, uint16_t xu, uint16_t w)
{
    uint8_t z;
    __asm__ (
        "clr  %[z]"            "\n\t"
        "mul  %A[x], %A[w]"    "\n\t"
        "sub  %A[acc], r0"     "\n\t"
        "sbc  %B[acc], r1"     "\n\t"
        "sbc  %C[acc], %[z]"   "\n\t"
        "sbc  %D[acc], %[z]"   "\n\t"
        "mul  %B[x], %B[w]"    "\n\t"
        "sub  %C[acc], r0"     "\n\t"
        "sbc  %D[acc], r1"     "\n\t"
        "mul  %B[x], %A[w]"    "\n\t"
        "sub  %B[acc], r0"     "\n\t"
        "sbc  %C[acc], r1"     "\n\t"
        "sbc  %D[acc], %[z]"   "\n\t"
        "mul  %A[x], %B[w]"    "\n\t"
        "sub  %B[acc], r0"     "\n\t"
        "sbc  %C[acc], r1"     "\n\t"
        "sbc  %D[acc], %[z]"   "\n\t"
        "clr  __zero_reg__"
        : [acc] "+r" (acc), [z] "=&r" (z)
        : [x] "r" (xu), [w] "r" (w));
    return acc;
}

NNIK_INLINE uint16_t nnik_tu16(uint32_t acc)
{
    return (uint16_t)(acc >> 16) ^ 0x8000u;
}

/* bits sh..sh+15 of acc (sh < 16): shift the top three bytes left, keep the top two */
NNIK_INLINE uint16_t nnik_avr_shl_hi16(uint32_t acc, uint8_t n)
{
    uint16_t r;
    uint8_t lo;
    __asm__ (
        "mov  %[lo], %B[a]"   "\n\t"
        "movw %A[r], %C[a]"   "\n\t"
        "1: lsl %[lo]"        "\n\t"
        "rol  %A[r]"          "\n\t"
        "rol  %B[r]"          "\n\t"
        "dec  %[n]"           "\n\t"
        "brne 1b"
        : [r] "=&r" (r), [lo] "=&r" (lo), [n] "+r" (n)
        : [a] "r" (acc));
    return r;
}

NNIK_INLINE uint16_t nnik_tu_shr(uint32_t acc, uint8_t sh)
{
    if (sh == 16)
        return nnik_tu16(acc);
    if (sh > 16)
        return (uint16_t)((uint16_t)((int16_t)(uint16_t)(acc >> 16) >> (sh - 16)) ^ 0x8000u);
    if (sh == 15) {
        uint16_t r;
        uint8_t lo;
        __asm__ (
            "mov  %[lo], %B[a]"   "\n\t"
            "movw %A[r], %C[a]"   "\n\t"
            "lsl  %[lo]"          "\n\t"
            "rol  %A[r]"          "\n\t"
            "rol  %B[r]"
            : [r] "=&r" (r), [lo] "=&r" (lo)
            : [a] "r" (acc));
        return r ^ 0x8000u;
    }
    if (sh >= 8)
        return nnik_avr_shl_hi16(acc, (uint8_t)(16 - sh)) ^ 0x8000u;
    return (uint16_t)(acc >> sh) ^ 0x8000u;
}

#ifdef NNIK_FLASH_AVR_PROGMEM
NNIK_INLINE uint16_t nnik_lerp_u16(const uint16_t *p, uint8_t f)
{
    uint16_t y0, y1;
    __asm__ (
        "lpm  %A[y0], Z+"         "\n\t"
        "lpm  %B[y0], Z+"         "\n\t"
        "lpm  %A[y1], Z+"         "\n\t"
        "lpm  %B[y1], Z"          "\n\t"
        "sub  %A[y1], %A[y0]"     "\n\t"
        "sbc  %B[y1], %B[y0]"     "\n\t"
        /* (d * f + 128) >> 8 = dh * f + ((dl * f + 128) >> 8): the rounding bit is bit 7 */
        "mul  %A[y1], %[f]"       "\n\t"
        "lsl  r0"                 "\n\t"
        "adc  %A[y0], r1"         "\n\t"
        "clr  __zero_reg__"       "\n\t"
        "adc  %B[y0], __zero_reg__" "\n\t"
        "mul  %B[y1], %[f]"       "\n\t"
        "add  %A[y0], r0"         "\n\t"
        "adc  %B[y0], r1"         "\n\t"
        "clr  __zero_reg__"
        : [y0] "=&r" (y0), [y1] "=&r" (y1), "+z" (p)
        : [f] "r" (f));
    return y0;
}
#else /* tables moved to RAM by the user (NNIK_FLASH overridden) */
NNIK_INLINE uint16_t nnik_lerp_u16(const uint16_t *p, uint8_t f)
{
    uint16_t y0 = NNIK_RD_U16(p);
    uint16_t d = (uint16_t)(NNIK_RD_U16(p + 1) - y0);
    return (uint16_t)(y0 + (uint16_t)(((uint32_t)d * f + 128u) >> 8));
}
#endif

NNIK_INLINE uint16_t nnik_shr24_16(uint32_t v, uint8_t k)
{
    /* bits k..k+15 of v (v < 2^(k+16)): k steps of a 3-byte logical shift */
    if (k == 0)
        return (uint16_t)v;
    __asm__ (
        "1: lsr  %C[v]"  "\n\t"
        "ror  %B[v]"     "\n\t"
        "ror  %A[v]"     "\n\t"
        "dec  %[k]"      "\n\t"
        "brne 1b"
        : [v] "+r" (v), [k] "+r" (k));
    return (uint16_t)v;
}

NNIK_INLINE int32_t nnik_out_shr(uint32_t o, uint8_t n)
{
    if (n > 16 && n < 32) {
        int16_t t = (int16_t)(uint16_t)(o >> 16);
        uint8_t k = (uint8_t)(n - 16);
        __asm__ (
            "1: asr  %B[t]"  "\n\t"
            "ror  %A[t]"     "\n\t"
            "dec  %[k]"      "\n\t"
            "brne 1b"
            : [t] "+r" (t), [k] "+r" (k));
        return (int32_t)t;
    }
    if (n == 16)
        return (int32_t)(int16_t)(uint16_t)(o >> 16);
    return nnik_s32(o) >> n;
}

NNIK_INLINE uint32_t nnik_macs(uint32_t acc, uint16_t xu, int16_t w)
{
    acc = nnik_macu(acc, xu, (uint16_t)w);
    if (w < 0)
        acc -= (uint32_t)xu << 16;
    return acc;
}

#else
/* ------------------------------------------------------- portable C (and SDCC's C parts) */

NNIK_INLINE nnik_acc_t nnik_macu(nnik_acc_t acc, uint16_t xu, uint16_t w)
{
    return acc + (nnik_acc_t)((uint32_t)xu * w);
}

NNIK_INLINE nnik_acc_t nnik_msubu(nnik_acc_t acc, uint16_t xu, uint16_t w)
{
    return acc - (nnik_acc_t)((uint32_t)xu * w);
}

NNIK_INLINE uint16_t nnik_tu16(uint32_t acc)
{
    return (uint16_t)((uint16_t)nnik_shr32(acc, 16) ^ 0x8000u);
}

NNIK_INLINE uint16_t nnik_tu_shr(uint32_t acc, uint8_t sh)
{
    /* the int16 value of (int32)acc >> sh, in offset binary */
    return (uint16_t)((uint16_t)nnik_sar32(nnik_s32(acc), sh) ^ 0x8000u);
}

NNIK_INLINE uint16_t nnik_lerp_u16(const uint16_t *p, uint8_t f)
{
    uint16_t y0 = NNIK_RD_U16(p);
    uint16_t d = (uint16_t)(NNIK_RD_U16(p + 1) - y0);
    return (uint16_t)(y0 + (uint16_t)(((uint32_t)d * f + 128u) >> 8));
}

NNIK_INLINE uint16_t nnik_shr24_16(uint32_t v, uint8_t k)
{
    return (uint16_t)nnik_shr32(v, k);
}

NNIK_INLINE int32_t nnik_out_shr(uint32_t o, uint8_t n)
{
    return nnik_sar32(nnik_s32(o), n);
}

NNIK_INLINE nnik_acc_t nnik_macs(nnik_acc_t acc, uint16_t xu, int16_t w)
{
#ifdef NNIK_INSTRUMENT
    return acc + (nnik_acc_t)xu * w;
#else
    return acc + (uint32_t)xu * (uint32_t)(int32_t)w;
#endif
}

#endif /* value primitives */
#endif /* !NNIK_P18_ASM_ONLY */

#if defined(NNIK_KERNEL_P18)
/* ----------------------------------------------------------------------- PIC18 (SDCC) */
#define NNIK_P18_S(x) #x
#define NNIK_P18_SET32(A, K) \
    "movlw LOW(" NNIK_P18_S(K) ")\n movwf " A "+0, B\n" \
    "movlw HIGH(" NNIK_P18_S(K) ")\n movwf " A "+1, B\n" \
    "movlw UPPER(" NNIK_P18_S(K) ")\n movwf " A "+2, B\n" \
    "movlw LOW((" NNIK_P18_S(K) ") >> 24)\n movwf " A "+3, B\n"
#define NNIK_P18_ADDP_(op, opc, A, o0) \
    "movf 0xFF3, W, A\n " op " " A "+" o0 ", F, B\n movf 0xFF4, W, A\n " opc " " A "+" o0 "+1, F, B\n"
#define NNIK_P18_MACX_(op, opc, A, X, W) \
    "movf " X "+0, W, B\n mullw LOW(" NNIK_P18_S(W) ")\n" NNIK_P18_ADDP_(op, opc, A, "0") \
    "movlw 0\n " opc " " A "+2, F, B\n " opc " " A "+3, F, B\n" \
    "movf " X "+1, W, B\n mullw HIGH(" NNIK_P18_S(W) ")\n" NNIK_P18_ADDP_(op, opc, A, "2") \
    "movf " X "+1, W, B\n mullw LOW(" NNIK_P18_S(W) ")\n" NNIK_P18_ADDP_(op, opc, A, "1") \
    "movlw 0\n " opc " " A "+3, F, B\n" \
    "movf " X "+0, W, B\n mullw HIGH(" NNIK_P18_S(W) ")\n" NNIK_P18_ADDP_(op, opc, A, "1") \
    "movlw 0\n " opc " " A "+3, F, B\n"
#define NNIK_P18_MACX8_(op, opc, A, X, W) \
    "movf " X "+0, W, B\n mullw LOW(" NNIK_P18_S(W) ")\n" NNIK_P18_ADDP_(op, opc, A, "0") \
    "movlw 0\n " opc " " A "+2, F, B\n " opc " " A "+3, F, B\n" \
    "movf " X "+1, W, B\n mullw LOW(" NNIK_P18_S(W) ")\n" NNIK_P18_ADDP_(op, opc, A, "1") \
    "movlw 0\n " opc " " A "+3, F, B\n"
#define NNIK_P18_MACU(A, X, W) NNIK_P18_MACX_("addwf", "addwfc", A, X, W)
#define NNIK_P18_MSUBU(A, X, W) NNIK_P18_MACX_("subwf", "subwfb", A, X, W)
#define NNIK_P18_MACU8(A, X, W) NNIK_P18_MACX8_("addwf", "addwfc", A, X, W)
#define NNIK_P18_MSUBU8(A, X, W) NNIK_P18_MACX8_("subwf", "subwfb", A, X, W)
/* TBLPTR = TAB + W (W = 2 * node index low byte, C = its bit 8) */
#define NNIK_P18_TBLPTR_(TAB) \
    "movwf 0xFF6, A\n clrf 0xFF7, A\n rlcf 0xFF7, F, A\n" \
    "movlw LOW(" NNIK_P18_S(TAB) ")\n addwf 0xFF6, F, A\n" \
    "movlw HIGH(" NNIK_P18_S(TAB) ")\n addwfc 0xFF7, F, A\n"
/* H = y0 + (((y1 - y0) * f + 128) >> 8), TBLPTR at y0, f in the byte F */
#define NNIK_P18_LERP_(H, Y, F) \
    "tblrd*+\n movff 0xFF5, " H "+0\n tblrd*+\n movff 0xFF5, " H "+1\n" \
    "tblrd*+\n movff 0xFF5, " Y "+0\n tblrd*\n movff 0xFF5, " Y "+1\n" \
    "movf " H "+0, W, B\n subwf " Y "+0, F, B\n movf " H "+1, W, B\n subwfb " Y "+1, F, B\n" \
    "movf " F ", W, B\n mulwf " Y "+0, B\n rlcf 0xFF3, W, A\n movf 0xFF4, W, A\n" \
    "addwfc " H "+0, F, B\n movlw 0\n addwfc " H "+1, F, B\n" \
    "movf " F ", W, B\n mulwf " Y "+1, B\n" NNIK_P18_ADDP_("addwf", "addwfc", H, "0")
#define NNIK_P18_TANH8(H, Y, A, TAB) \
    "movf " A "+3, W, B\n xorlw 0x80\n addwf 0xFE8, W, A\n" NNIK_P18_TBLPTR_(TAB) \
    NNIK_P18_LERP_(H, Y, A "+2")
/* 2 * node index = (Tu >> 6) & ~1 (10 bits) via Y; f = tf << 1 */
#define NNIK_P18_TANH7(H, Y, A, TAB) \
    "bcf 0xFD8, 0, A\n rlcf " A "+2, F, B\n movf " A "+3, W, B\n xorlw 0x80\n movwf " Y "+0, B\n" \
    "rlcf " Y "+0, F, B\n clrf " Y "+1, B\n rlcf " Y "+1, F, B\n rlcf " Y "+0, F, B\n rlcf " Y "+1, F, B\n" \
    "movff " Y "+0, 0xFF6\n movff " Y "+1, 0xFF7\n" \
    "movlw LOW(" NNIK_P18_S(TAB) ")\n addwf 0xFF6, F, A\n" \
    "movlw HIGH(" NNIK_P18_S(TAB) ")\n addwfc 0xFF7, F, A\n" NNIK_P18_LERP_(H, Y, A "+2")
/* V (int32 input) -> X (uint16): w = V - LO clamped to [0, SPAN] (FL = 1 if clamped),
   X = (w + C) >> K (3 bytes); L: a prefix for the labels this expansion defines */
#define NNIK_P18_INW(V, FL, LO, SPAN, L) \
    "movlw LOW(" NNIK_P18_S(LO) ")\n subwf " V "+0, F, B\n movlw HIGH(" NNIK_P18_S(LO) ")\n subwfb " V "+1, F, B\n" \
    "movlw UPPER(" NNIK_P18_S(LO) ")\n subwfb " V "+2, F, B\n" \
    "movlw LOW((" NNIK_P18_S(LO) ") >> 24)\n subwfb " V "+3, F, B\n" \
    "bnov " L "n\n bnn " L "b\n bra " L "h\n" L "n:\n bn " L "b\n" L "h:\n" \
    "movlw LOW((" NNIK_P18_S(SPAN) ") + 1)\n subwf " V "+0, W, B\n" \
    "movlw HIGH((" NNIK_P18_S(SPAN) ") + 1)\n subwfb " V "+1, W, B\n" \
    "movlw UPPER((" NNIK_P18_S(SPAN) ") + 1)\n subwfb " V "+2, W, B\n" \
    "movlw LOW(((" NNIK_P18_S(SPAN) ") + 1) >> 24)\n subwfb " V "+3, W, B\n bnc " L "k\n" \
    "movlw LOW(" NNIK_P18_S(SPAN) ")\n movwf " V "+0, B\n movlw HIGH(" NNIK_P18_S(SPAN) ")\n movwf " V "+1, B\n" \
    "movlw UPPER(" NNIK_P18_S(SPAN) ")\n movwf " V "+2, B\n bra " L "s\n" \
    L "b:\n clrf " V "+0, B\n clrf " V "+1, B\n clrf " V "+2, B\n" \
    L "s:\n movlw 1\n movwf " FL ", B\n" L "k:\n"
#define NNIK_P18_INX(V, C) \
    "movlw LOW(" NNIK_P18_S(C) ")\n addwf " V "+0, F, B\n movlw HIGH(" NNIK_P18_S(C) ")\n addwfc " V "+1, F, B\n" \
    "movlw UPPER(" NNIK_P18_S(C) ")\n addwfc " V "+2, F, B\n"
#define NNIK_P18_IN(V, X, FL, LO, SPAN, C, K, L) NNIK_P18_INW(V, FL, LO, SPAN, L) NNIK_P18_INX(V, C)
/* output stage of residual models and of e > 0 */
#define NNIK_P18_SAR32_1(A) \
    "rlcf " A "+3, W, B\n rrcf " A "+3, F, B\n rrcf " A "+2, F, B\n rrcf " A "+1, F, B\n rrcf " A "+0, F, B\n"
#define NNIK_P18_SAR32_8(A) \
    "movff " A "+1, " A "+0\n movff " A "+2, " A "+1\n movff " A "+3, " A "+2\n" \
    "movlw 0\n btfsc " A "+3, 7, B\n movlw 0xFF\n movwf " A "+3, B\n"
#define NNIK_P18_ADD32C(A, K) \
    "movlw LOW(" NNIK_P18_S(K) ")\n addwf " A "+0, F, B\n movlw HIGH(" NNIK_P18_S(K) ")\n addwfc " A "+1, F, B\n" \
    "movlw UPPER(" NNIK_P18_S(K) ")\n addwfc " A "+2, F, B\n" \
    "movlw LOW((" NNIK_P18_S(K) ") >> 24)\n addwfc " A "+3, F, B\n"
#define NNIK_P18_ADD32(A, S) \
    "movf " S "+0, W, B\n addwf " A "+0, F, B\n movf " S "+1, W, B\n addwfc " A "+1, F, B\n" \
    "movf " S "+2, W, B\n addwfc " A "+2, F, B\n movf " S "+3, W, B\n addwfc " A "+3, F, B\n"
#define NNIK_P18_SET48(R, KLO, KHI) NNIK_P18_SET32(R, KLO) \
    "movlw LOW(" NNIK_P18_S(KHI) ")\n movwf " R "+4, B\n movlw HIGH(" NNIK_P18_S(KHI) ")\n movwf " R "+5, B\n"
/* one byte product of a 48-bit multiply-accumulate: PROD = byte WB * B, added (op/opc) at
   R+O, R+O+1; NNIK_P18_C48 propagates the carry into one more byte (opc) */
#define NNIK_P18_P48(op, opc, R, O, WB, B) \
    "movf " WB ", W, B\n mullw " NNIK_P18_S(B) "\n" NNIK_P18_ADDP_(op, opc, R, O)
#define NNIK_P18_P48TOP(op, R, WB, B) \
    "movf " WB ", W, B\n mullw " NNIK_P18_S(B) "\n movf 0xFF3, W, A\n " op " " R "+5, F, B\n"
#define NNIK_P18_C48_0 "movlw 0\n"
#define NNIK_P18_C48(opc, R, O) opc " " R "+" O ", F, B\n"
#define NNIK_P18_SHL48_1(R) \
    "rlcf " R "+1, F, B\n rlcf " R "+2, F, B\n rlcf " R "+3, F, B\n rlcf " R "+4, F, B\n rlcf " R "+5, F, B\n"
/* any node step 2^S: Y = T (NNIK_P18_TCOPY), (S - 1) x NNIK_P18_SAR16(Y), (8 - S) x
   NNIK_P18_FSHL(A), then NNIK_P18_TANHS_(H, Y, A, TAB, K) with K = 2^(16 - S) */
#define NNIK_P18_TCOPY(Y, A) "movff " A "+2, " Y "+0\n movff " A "+3, " Y "+1\n"
#define NNIK_P18_SAR16(Y) "rlcf " Y "+1, W, B\n rrcf " Y "+1, F, B\n rrcf " Y "+0, F, B\n"
#define NNIK_P18_FSHL(A) "bcf 0xFD8, 0, A\n rlcf " A "+2, F, B\n"
#define NNIK_P18_TANHS_(H, Y, A, TAB, K) \
    "bcf " Y "+0, 0, B\n movff " Y "+0, 0xFF6\n movff " Y "+1, 0xFF7\n" \
    "movlw LOW((" NNIK_P18_S(TAB) ") + (" NNIK_P18_S(K) "))\n addwf 0xFF6, F, A\n" \
    "movlw HIGH((" NNIK_P18_S(TAB) ") + (" NNIK_P18_S(K) "))\n addwfc 0xFF7, F, A\n" NNIK_P18_LERP_(H, Y, A "+2")
/* if (int32)A >= LIM: A = VAL (GE), if (int32)A < LIM: A = VAL (LT); L a unique label prefix */
#define NNIK_P18_CMP32_(A, LIM) \
    "movlw LOW(" NNIK_P18_S(LIM) ")\n subwf " A "+0, W, B\n movlw HIGH(" NNIK_P18_S(LIM) ")\n subwfb " A "+1, W, B\n" \
    "movlw UPPER(" NNIK_P18_S(LIM) ")\n subwfb " A "+2, W, B\n" \
    "movlw LOW((" NNIK_P18_S(LIM) ") >> 24)\n subwfb " A "+3, W, B\n"
#define NNIK_P18_SATGE(A, LIM, VAL, L) NNIK_P18_CMP32_(A, LIM) \
    "bnov " L "n\n bnn " L "x\n bra " L "s\n" L "n:\n bn " L "x\n" L "s:\n" NNIK_P18_SET32(A, VAL) L "x:\n"
#define NNIK_P18_SATLT(A, LIM, VAL, L) NNIK_P18_CMP32_(A, LIM) \
    "bnov " L "n\n bnn " L "s\n bra " L "x\n" L "n:\n bn " L "s\n bra " L "x\n" L "s:\n" \
    NNIK_P18_SET32(A, VAL) L "x:\n"
/* A[0..3] <<= 1 (for tanh input shifts below 8) */
#define NNIK_P18_SHL1_4(A) "bcf 0xFD8, 0, A\n rlcf " A "+0, F, B\n rlcf " A "+1, F, B\n rlcf " A "+2, F, B\n rlcf " A "+3, F, B\n"
/* one step of a logical right shift of the 3 low bytes of V (after NNIK_P18_IN) */
#define NNIK_P18_SHR24_1(V) "bcf 0xFD8, 0, A\n rrcf " V "+2, F, B\n rrcf " V "+1, F, B\n rrcf " V "+0, F, B\n"
#define NNIK_P18_SAR1_2(A) "rlcf " A "+3, W, B\n rrcf " A "+3, F, B\n rrcf " A "+2, F, B\n"
#define NNIK_P18_SHL1(A) "rlcf " A "+1, F, B\n rlcf " A "+2, F, B\n rlcf " A "+3, F, B\n"
#define NNIK_P18_OUT_(A) \
    "movff " A "+2, " A "+0\n movff " A "+3, " A "+1\n clrf " A "+2, B\n btfsc " A "+1, 7, B\n" \
    "setf " A "+2, B\n movff " A "+2, " A "+3\n"
#endif /* NNIK_KERNEL_P18 */

#endif /* NNIK_KERNEL_H */
