/* nnik_imath.c - see nnik_imath.h */
#include "nnik_imath.h"

/* floor(sqrt(v)) bit by bit, in the width of T (one body for both widths) */
#define NNIK_ISQRT_BODY(T, v)                                                                   \
    T r = 0, b = (T)1 << (sizeof(T) * 8 - 2);                                                   \
    while (b > v)                                                                               \
        b >>= 2;                                                                                \
    while (b) {                                                                                 \
        if (v >= r + b) {                                                                       \
            v -= r + b;                                                                         \
            r = (r >> 1) + b;                                                                   \
        } else {                                                                                \
            r >>= 1;                                                                            \
        }                                                                                       \
        b >>= 2;                                                                                \
    }                                                                                           \
    return (uint32_t)r

uint32_t nnik_isqrt32(uint32_t v)
{
#if defined(__GNUC__) && defined(__AVR__)
    /* Digit by digit in AVR assembly (about two thirds of the C's cycles): 16 steps, each shifts
     * v's top bit pair into the remainder rm, doubles the root r and subtracts the trial
     * t = 2 r + 1 (4 r + 1 of the old r) from rm when rm >= t, setting r's new bit 0.  The
     * remainder stays <= 2 r <= 2^17 - 2 (shifted: < 2^19) and t < 2^18: 3 bytes each; r < 2^16:
     * 2 bytes.  The same floor(sqrt(v)) as the bit-by-bit C below (tests/firmware/gcode/
     * test_imath_avr.py checks it on simavr against Python's math.isqrt). */
    uint16_t r = 0;
    uint32_t rm = 0, t;
    uint8_t n = 16;
    while (n > 4 && !(uint8_t)(v >> 24)) { /* a zero top byte: 4 steps that leave r = rm = 0 */
        v <<= 8;
        n -= 4;
    }
    __asm__("1:  lsl %A0\n\trol %B0\n\trol %C0\n\trol %D0\n\trol %A1\n\trol %B1\n\trol %C1\n\t"
            "lsl %A0\n\trol %B0\n\trol %C0\n\trol %D0\n\trol %A1\n\trol %B1\n\trol %C1\n\t"
            "lsl %A2\n\trol %B2\n\t"
            "mov %A3,%A2\n\tmov %B3,%B2\n\tclr %C3\n\tlsl %A3\n\trol %B3\n\trol %C3\n\tinc %A3\n\t"
            "cp %A1,%A3\n\tcpc %B1,%B3\n\tcpc %C1,%C3\n\t"
            "brcs 2f\n\t"
            "sub %A1,%A3\n\tsbc %B1,%B3\n\tsbc %C1,%C3\n\t"
            "inc %A2\n"
            "2:  dec %4\n\t"
            "brne 1b"
            : "+r"(v), "+r"(rm), "+r"(r), "=&r"(t), "+r"(n));
    return r;
#else
    NNIK_ISQRT_BODY(uint32_t, v);
#endif
}

uint32_t nnik_div_steps(uint32_t hi, uint32_t lo, uint32_t d, uint8_t n)
{
#if defined(__GNUC__) && defined(__AVR__)
    /* The same restoring division as the C below, step for step, in AVR assembly (about half the
     * cycles: avr-gcc moves each 32-bit shift through a temporary).  Per step, hi:lo shifts left
     * one bit; the carry out of hi is the bit `top`; when it is set or hi >= d, d is subtracted
     * (mod 2^32) and the quotient bit enters lo's bottom (0 after the shift, so inc sets it). */
    __asm__("1:  lsl %A1\n\trol %B1\n\trol %C1\n\trol %D1\n\t"
            "rol %A0\n\trol %B0\n\trol %C0\n\trol %D0\n\t"
            "brcs 2f\n\t"
            "cp %A0,%A3\n\tcpc %B0,%B3\n\tcpc %C0,%C3\n\tcpc %D0,%D3\n\t"
            "brcs 3f\n"
            "2:  sub %A0,%A3\n\tsbc %B0,%B3\n\tsbc %C0,%C3\n\tsbc %D0,%D3\n\t"
            "inc %A1\n"
            "3:  dec %2\n\t"
            "brne 1b"
            : "+r"(hi), "+r"(lo), "+r"(n)
            : "r"(d));
    return lo;
#else
    uint8_t i, top;
    for (i = 0; i < n; i++) { /* restoring division, one bit a step; hi < d throughout; the
                                * quotient's bits enter lo from below as the dividend leaves it */
        top = (uint8_t)((uint8_t)(hi >> 24) >> 7); /* the bit shifted out: the value is then > d */
        hi = (hi << 1) | (uint8_t)((uint8_t)(lo >> 24) >> 7);
        lo <<= 1;
        if (top || hi >= d) {
            hi -= d; /* mod 2^32: the true remainder, below d */
            lo |= 1;
        }
    }
    return lo;
#endif
}

/* v >> 32: on AVR by reading the high word (little-endian), not libgcc's 64-bit shift loop */
static uint32_t hi32(uint64_t v)
{
#if defined(__GNUC__) && defined(__AVR__)
    union {
        uint64_t v;
        uint32_t w[2];
    } u;
    u.v = v;
    return u.w[1];
#else
    return (uint32_t)(v >> 32);
#endif
}

uint32_t nnik_isqrt64(uint64_t v)
{
    return nnik_isqrt_hl(hi32(v), (uint32_t)v);
}

uint32_t nnik_isqrt_hl(uint32_t hi, uint32_t lo)
{
    uint32_t r, rl, tl;
    uint8_t rx, tx;
#if !(defined(__GNUC__) && defined(__AVR__))
    uint8_t i;
#endif
    if (!hi)
        return nnik_isqrt32(lo); /* 32-bit arithmetic: far cheaper on AVR */
    /* digit by digit: the root of the high word, then the low word's 16 bit pairs, with the
     * remainder (<= 2 r < 2^33, shifted: < 2^35) in 40 bits (rx:rl), by 32-bit steps */
    r = nnik_isqrt32(hi);
    rl = hi - r * r;
    rx = 0;
#if defined(__GNUC__) && defined(__AVR__)
    /* The same 16 steps as the C below, in AVR assembly (about half the cycles): rx:rl:lo shifts
     * left two bits; r <<= 1; the trial tx:tl = (r << 1) | 1 (the C's 4 r + 1 of the old r: tl's
     * bit 0 is 0 after the shift, so inc sets it); when rx:rl >= tx:tl it is subtracted and r's
     * new bit 0 (0 after the shift) is set. */
    tx = 16; /* the step count until the loop reuses tx for the trial's top byte */
    __asm__("mov __tmp_reg__,%5\n"
            "1:  lsl %A3\n\trol %B3\n\trol %C3\n\trol %D3\n\t"
            "rol %A1\n\trol %B1\n\trol %C1\n\trol %D1\n\trol %2\n\t"
            "lsl %A3\n\trol %B3\n\trol %C3\n\trol %D3\n\t"
            "rol %A1\n\trol %B1\n\trol %C1\n\trol %D1\n\trol %2\n\t"
            "lsl %A0\n\trol %B0\n\trol %C0\n\trol %D0\n\t"
            "mov %A4,%A0\n\tmov %B4,%B0\n\tmov %C4,%C0\n\tmov %D4,%D0\n\tclr %5\n\t"
            "lsl %A4\n\trol %B4\n\trol %C4\n\trol %D4\n\trol %5\n\tinc %A4\n\t"
            "cp %A1,%A4\n\tcpc %B1,%B4\n\tcpc %C1,%C4\n\tcpc %D1,%D4\n\tcpc %2,%5\n\t"
            "brcs 2f\n\t"
            "sub %A1,%A4\n\tsbc %B1,%B4\n\tsbc %C1,%C4\n\tsbc %D1,%D4\n\tsbc %2,%5\n\t"
            "inc %A0\n"
            "2:  dec __tmp_reg__\n\t"
            "brne 1b"
            : "+r"(r), "+r"(rl), "+r"(rx), "+r"(lo), "=&r"(tl), "+r"(tx));
#else
    for (i = 0; i < 16; i++) {
        rx = (uint8_t)((rx << 2) | ((uint8_t)(rl >> 24) >> 6));
        rl = (rl << 2) | ((uint8_t)(lo >> 24) >> 6);
        lo <<= 2;
        tl = (r << 2) | 1; /* the trial 4 r + 1 (tx:tl) */
        tx = (uint8_t)((uint8_t)(r >> 24) >> 6);
        r <<= 1;
        if (rx > tx || (rx == tx && rl >= tl)) {
            rx = (uint8_t)(rx - tx - (rl < tl));
            rl -= tl;
            r |= 1;
        }
    }
#endif
    return r;
}

int32_t nnik_div_round(int64_t a, uint32_t b)
{
    uint64_t u = a < 0 ? (uint64_t)(-a) : (uint64_t)a;
    int32_t q;
    if (u < 0x40000000UL && b < 0x40000000UL) { /* the same value by 32-bit division: far cheaper on AVR */
        uint32_t n = 2 * (uint32_t)u + b, d = 2 * b;
        if ((n >> 16) < d) /* the quotient fits 16 bits: 16 steps of nnik_div_steps, half the 32-bit division's */
            q = (int32_t)nnik_div_steps(n >> 16, n << 16, d, 16);
        else
            q = (int32_t)(n / d);
    } else {
        /* n = 2 u + b (mod 2^64, as before); when 2 b < 2^32 and n's high word is below it, the
         * quotient fits 32 bits and nnik_div64_32 gives the same floor(n / 2 b) as the 64-bit
         * division (libgcc's __udivdi3: thousands of cycles on AVR) */
        uint64_t n = 2 * u + b;
        uint32_t nh = hi32(n);
        if (b < 0x80000000UL && nh < 2 * b)
            q = (int32_t)nnik_div64_32(nh, (uint32_t)n, 2 * b);
        else
            q = (int32_t)(n / (2 * (uint64_t)b));
    }
    return a < 0 ? -q : q;
}

uint64_t nnik_sq2(int32_t x, int32_t y)
{
    if (x > -32768L && x < 32768L && y > -32768L && y < 32768L)
        return (uint32_t)(x * x) + (uint32_t)(y * y);
    return (uint64_t)((int64_t)x * x) + (uint64_t)((int64_t)y * y);
}

int64_t nnik_mul_r(int32_t x, uint32_t r)
{
    if (x > -65536L && x < 65536L && r < 65536UL) {
        uint32_t p = (uint32_t)(x < 0 ? -x : x) * r;
        return x < 0 ? -(int64_t)p : (int64_t)p;
    }
    { /* |x| r < 2^63 by a 32 x 32 -> 64 unsigned product (not libgcc's 64 x 64 __muldi3), then x's sign */
        uint64_t p = (uint64_t)(x < 0 ? (uint32_t)0 - (uint32_t)x : (uint32_t)x) * r;
        return x < 0 ? -(int64_t)p : (int64_t)p;
    }
}
