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

/* The weights' checksum after the last tick (or reset): the sum of every weight's int32 master word
 * modulo 2^16, the Python model's checksum(). A learning controller (nnik_ctl_nn_*.c) defines and
 * sets it; the runtime (nnik_servo.c) defines it, 0, for the fixed-gain ones. The co-simulation's
 * harness reads it after every tick (volatile: an exported sketch's link-time optimisation
 * would drop a variable the firmware only writes). */
extern volatile uint16_t nnik_ctl_sum;

#ifdef __cplusplus
}
#endif

#endif /* NNIK_CTL_H */
