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

/* floor(sqrt(v)) */
uint32_t nnik_isqrt32(uint32_t v);
uint32_t nnik_isqrt64(uint64_t v);

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
