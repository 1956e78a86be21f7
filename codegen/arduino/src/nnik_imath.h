/*
 * nnik_imath.h - the integer maths the G-code engine and the planner share: floor square roots
 * and a division rounded half away from zero.  Portable C99; nnik's Python model repeats each.
 */
#ifndef NNIK_IMATH_H
#define NNIK_IMATH_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* |v| */
static inline int32_t nnik_iabs32(int32_t v) { return v < 0 ? -v : v; }

/* a * b, 16 x 16 -> 32 bits.  avr-gcc 5 turns the product of halves cut from 32-bit values into
 * a 32 x 32 __mulsi3 (about twice the cycles); the empty asm keeps each operand 16-bit, so it
 * calls __umulhisi3.  The same value everywhere. */
#if defined(__GNUC__) && defined(__AVR__)
#define NNIK_KEEP16(x) __asm__("" : "+r"(x))
#else
#define NNIK_KEEP16(x) ((void)0)
#endif
static inline uint32_t nnik_mul16(uint16_t a, uint16_t b)
{
    NNIK_KEEP16(a);
    NNIK_KEEP16(b);
    return (uint32_t)a * b;
}

/* floor(sqrt(v)) */
uint32_t nnik_isqrt32(uint32_t v);
uint32_t nnik_isqrt64(uint64_t v);
/* floor(sqrt(hi 2^32 + lo)): no 64-bit value to build (a 64-bit shift is a loop on AVR) */
uint32_t nnik_isqrt_hl(uint32_t hi, uint32_t lo);

/* n steps of restoring division of hi:lo by d, hi < d: the quotient's bits enter lo from below
 * as the dividend leaves it; 32 steps give floor((hi 2^32 + lo) / d), and 16 steps with lo's low
 * half 0 give floor((hi 2^16 + (lo >> 16)) / d) < 2^16 (lo ends as the quotient) */
uint32_t nnik_div_steps(uint32_t hi, uint32_t lo, uint32_t d, uint8_t n);

/* floor((hi 2^32 + lo) / d) for hi < d (the quotient fits 32 bits), by 32-bit steps: far
 * cheaper on AVR than a 64-bit division */
static inline uint32_t nnik_div64_32(uint32_t hi, uint32_t lo, uint32_t d) { return nnik_div_steps(hi, lo, d, 32); }

/* round(a / b) half away from zero, b > 0 (32-bit division where the operands allow) */
int32_t nnik_div_round(int64_t a, uint32_t b);

/* x^2 + y^2 (32-bit arithmetic for 16-bit operands) */
uint64_t nnik_sq2(int32_t x, int32_t y);

/* x * r, r >= 0 (32-bit arithmetic where it fits) */
int64_t nnik_mul_r(int32_t x, uint32_t r);

#ifdef __cplusplus
}
#endif

#endif /* NNIK_IMATH_H */
