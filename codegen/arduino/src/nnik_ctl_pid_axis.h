/*
 * nnik_ctl_pid_axis.h - one axis of the Arduino PID library's PID (br3ttb v1.2.1, P on error,
 * derivative on measurement, integral and output clamped), in integers; used by the PID and by the
 * cross-coupled controller.  Python spec: nnik/implementations/servo/pid.py (PidAxis).
 */
#ifndef NNIK_CTL_PID_AXIS_H
#define NNIK_CTL_PID_AXIS_H

#include "nnik_ctl_fix.h"

#define NNIK_CTL_I_MAX ((int32_t)NNIK_DUTY_MAX << NNIK_CTL_Q_INT)

typedef struct {
    int32_t integral; /* Q16 duty, within +-NNIK_CTL_I_MAX */
    int32_t last;     /* the position at the last tick */
} nnik_pid_axis_t;

/* The axis' Q8 output before rounding; primed == 0 on the first tick after a reset. */
static inline int32_t nnik_pid_axis(nnik_pid_axis_t *s, uint8_t primed, int32_t ref, int32_t pos,
                                    uint16_t kp, uint16_t ki, uint16_t kd)
{
    int16_t e = nnik_ctl_s16(ref - pos);
    int16_t d_in = primed ? nnik_ctl_s16(pos - s->last) : 0;
    s->last = pos;
    s->integral = nnik_ctl_sat(s->integral + nnik_ctl_sat((int32_t)e * (int32_t)ki, 2 * NNIK_CTL_I_MAX),
                               NNIK_CTL_I_MAX);
    return nnik_ctl_term(kp, e) + (s->integral >> (NNIK_CTL_Q_INT - NNIK_CTL_Q_OUT)) - nnik_ctl_term(kd, d_in);
}

#endif /* NNIK_CTL_PID_AXIS_H */
