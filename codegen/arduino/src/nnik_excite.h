/*
 * nnik_excite.h - `nnik excite`'s firmware (issue 28 item 3): the excitation's duty table played
 * as the servo runtime's "controller" (nnik_ctl_tick, one row a tick on both axes, then duty 0:
 * the motors stop), each tick logged as a CSV line for `nnik identify LOG --supply V`:
 *
 *     t,u_x,u_y,count_x,count_y
 *     0.000000,0.498039,-0.250980,40000,30000
 *
 * t = tick index x NNIK_EXCITE_TICK_US in seconds (6 decimals), u = duty / NNIK_DUTY_MAX as a
 * fraction (6 decimals, rounded half away from zero), the counts the tick latched (before its duty
 * acts). The tick interrupt queues each tick's row in a small ring; the sketch's loop formats
 * and sends them. A row the ring had no room for is counted (nnik_excite_lost).
 */
#ifndef NNIK_EXCITE_H
#define NNIK_EXCITE_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define NNIK_EXCITE_LINE_MAX 64 /* a line's bytes, with its LF and the terminating NUL */

/* The next queued tick as a CSV line (with LF) in buf; returns its length, 0 when none is queued. */
uint8_t nnik_excite_line(char buf[NNIK_EXCITE_LINE_MAX]);
/* 1 once every tick of the table has been played (the motors then stay stopped). */
uint8_t nnik_excite_done(void);
/* Rows dropped because the ring was full (the serial link too slow). */
uint16_t nnik_excite_lost(void);

#ifdef __cplusplus
}
#endif

#endif /* NNIK_EXCITE_H */
