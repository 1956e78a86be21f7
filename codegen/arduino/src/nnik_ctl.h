/*
 * nnik_ctl.h - the closed-loop XY table's controller (issue 28): one of nnik_ctl_pid.c,
 * nnik_ctl_pdff.c, nnik_ctl_ccc.c, chosen by the generated nnik_servo_config.h (NNIK_CTL_PID,
 * NNIK_CTL_PDFF or NNIK_CTL_CCC) with its gains.  Integer arithmetic only; nnik's Python model
 * (nnik/implementations/servo/) is the specification, matched bit for bit.
 */
#ifndef NNIK_CTL_H
#define NNIK_CTL_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Forget the state (integral, last position, reference history): the next tick starts afresh. */
void nnik_ctl_reset(void);

/* One tick: the reference and the encoder counts (x, y) in, the duty (x, y) in
 * [-NNIK_DUTY_MAX, NNIK_DUTY_MAX] out (sign: direction). */
void nnik_ctl_tick(const int32_t ref[2], const int32_t pos[2], int16_t duty[2]);

/* A learning controller's (nnik_ctl_nn_*.c): its weights' checksum after the last tick (or reset),
 * the sum of every weight's int32 master word modulo 2^16, the Python model's checksum(). The
 * runtime (nnik_servo.c) publishes it each tick as nnik_servo_sum for the co-simulation's check. */
extern uint16_t nnik_ctl_sum;

#ifdef __cplusplus
}
#endif

#endif /* NNIK_CTL_H */
