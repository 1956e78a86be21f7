/* nnik_ctl_pid.c - the Arduino PID library's PID per axis, in integers (see nnik_ctl_pid_axis.h);
 * compiled in when nnik_servo_config.h defines NNIK_CTL_PID. */
#include "nnik_servo_config.h"

#ifdef NNIK_CTL_PID
#include "nnik_ctl.h"
#include "nnik_ctl_pid_axis.h"

static nnik_pid_axis_t nnik_pid_x, nnik_pid_y;
static uint8_t nnik_pid_primed;

void nnik_ctl_reset(void)
{
    nnik_pid_x.integral = 0;
    nnik_pid_y.integral = 0;
    nnik_pid_primed = 0;
}

void nnik_ctl_tick(const int32_t ref[2], const int32_t pos[2], int16_t duty[2])
{
    duty[0] = nnik_ctl_duty(nnik_pid_axis(&nnik_pid_x, nnik_pid_primed, ref[0], pos[0],
                                          NNIK_KP_X, NNIK_KI_X, NNIK_KD_X));
    duty[1] = nnik_ctl_duty(nnik_pid_axis(&nnik_pid_y, nnik_pid_primed, ref[1], pos[1],
                                          NNIK_KP_Y, NNIK_KI_Y, NNIK_KD_Y));
    nnik_pid_primed = 1;
}
#else
typedef int nnik_ctl_pid_unused; /* not this build's controller */
#endif
