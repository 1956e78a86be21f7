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
    NNIK_ISQRT_BODY(uint32_t, v);
}

uint32_t nnik_div64_32(uint32_t hi, uint32_t lo, uint32_t d)
{
    uint8_t i, top;
    for (i = 0; i < 32; i++) { /* restoring division, one bit a step; hi < d throughout; the
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
}

uint32_t nnik_isqrt64(uint64_t v)
{
    return nnik_isqrt_hl((uint32_t)(v >> 32), (uint32_t)v);
}

uint32_t nnik_isqrt_hl(uint32_t hi, uint32_t lo)
{
    uint32_t r, rl, tl;
    uint8_t i, rx, tx;
    if (!hi)
        return nnik_isqrt32(lo); /* 32-bit arithmetic: far cheaper on AVR */
    /* digit by digit: the root of the high word, then the low word's 16 bit pairs, with the
     * remainder (<= 2 r < 2^33, shifted: < 2^35) in 40 bits (rx:rl), by 32-bit steps */
    r = nnik_isqrt32(hi);
    rl = hi - r * r;
    rx = 0;
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
    return r;
}

int32_t nnik_div_round(int64_t a, uint32_t b)
{
    uint64_t u = a < 0 ? (uint64_t)(-a) : (uint64_t)a;
    int32_t q;
    if (u < 0x40000000UL && b < 0x40000000UL) /* the same value by 32-bit division: far cheaper on AVR */
        q = (int32_t)((2 * (uint32_t)u + b) / (2 * b));
    else
        q = (int32_t)((2 * u + b) / (2 * (uint64_t)b));
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
    return (int64_t)x * (int64_t)r;
}
