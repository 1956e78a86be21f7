/*
 * nnik_ctl_fix.h - the fixed-point helpers the controllers share (the Python spec:
 * nnik/implementations/servo/fixed.py).  Errors, speeds and accelerations saturate to int16 before
 * a product; gains are unsigned 16-bit; every product is 16 x 16 -> 32 bits and each term
 * saturates to +-2^28 (Q8 duty) before terms are summed; the output is Q8 duty rounded half up.
 */
#ifndef NNIK_CTL_FIX_H
#define NNIK_CTL_FIX_H

#include <stdint.h>

#define NNIK_CTL_TERM (1L << 28)
#define NNIK_CTL_Q_OUT 8
#define NNIK_CTL_Q_INT 16

static inline int32_t nnik_ctl_sat(int32_t v, int32_t lim)
{
    return v > lim ? lim : (v < -lim ? -lim : v);
}

static inline int16_t nnik_ctl_s16(int32_t v)
{
    return (int16_t)(v > 32767L ? 32767L : (v < -32767L ? -32767L : v));
}

/* gain (unsigned Q) * x, saturated to +-NNIK_CTL_TERM */
static inline int32_t nnik_ctl_term(uint16_t k, int16_t x)
{
    return nnik_ctl_sat((int32_t)x * (int32_t)k, NNIK_CTL_TERM);
}

/* the Q8 accumulator rounded half up (arithmetic shift) and saturated to the duty range */
static inline int16_t nnik_ctl_duty(int32_t acc)
{
    return (int16_t)nnik_ctl_sat((acc + (1L << (NNIK_CTL_Q_OUT - 1))) >> NNIK_CTL_Q_OUT, NNIK_DUTY_MAX);
}

#endif /* NNIK_CTL_FIX_H */
