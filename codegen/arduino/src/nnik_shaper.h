/*
 * nnik_shaper.h - input shaping of the sampled Cartesian trajectory, per axis.  Portable C99,
 * integer only; nnik/firmware/gcode/shaper.py repeats it bit for bit.
 *
 * For each axis, NNIK_SH_N (1..10) impulses of amplitude A_i (Q15, summing to exactly 32768) at
 * delays d_i (whole samples, 0 <= d_i <= NNIK_SH_LEN; an axis with fewer pads with A_i = 0 at
 * d_i = 0, and an unshaped axis of a shaped machine is one tap of 32768 at 0):
 *     shaped[n] = p[n] + ((16384 - sum_i A_i * W_i[n]) >> 15),   W_i[n] = p[n] - p[n - d_i]
 * (an arithmetic shift: floor), which is round half up of sum_i A_i * p[n - d_i] / 32768.  Before
 * the first sample every past p is the start point.  The memory holds the per-sample increments
 * p[n] - p[n-1] as int16 (NNIK_SH_LEN of them per axis: 2 * 2 * NNIK_SH_LEN bytes) and the running
 * window sums W_i as int16; nnik.firmware.config checks that NNIK_SH_LEN * (the largest move per
 * sample + 2 um) < 2^15, so every |W| < 2^15 and the sum of A_i W_i < 2^31.  NNIK_SH_LEN 0: no shaper, the samples pass unchanged, no memory.
 *
 * The tool follows the shaped head (nnik_sh_tool; nnik/firmware/gcode/tool_shaper.py repeats it):
 * the arc length run by the planner, Q[n] (increments ds = ceil(v / 2^15): half micrometres),
 * goes through axis 0's taps like a position: the head's shaped arc length is Qs[n] = Q[n] - lag[n],
 * lag = (16384 + sum_i A_i (Q[n] - Q[n - d_i])) >> 15.  The duty of sample n is the planned duty of
 * sample m, the first sample at or after the previous m (and n - NNIK_SH_LEN) with Q[m] >= Qs[n]:
 * the tool switches when the shaped head reaches the planned switch, not when the plan does.  M4's
 * planned duty is scaled by the shaped speed over the planned one, Qs[n] - Qs[n-1] over ds[m]
 * (capped at 255).  The memory: ds (bit 15: M4) and the planned duty of the last NNIK_SH_LEN + 1
 * samples, the window sums of ds, the last lag, the pointer's delay k and Q[n] - Q[n - k].
 */
#ifndef NNIK_SHAPER_H
#define NNIK_SHAPER_H

#include <stdint.h>

#include "nnik_gcode_config.h"

#ifdef __cplusplus
extern "C" {
#endif

#ifndef NNIK_SH_LEN
#define NNIK_SH_LEN 0
#endif

typedef struct {
    int32_t last[2]; /* p[n-1] */
#if NNIK_SH_LEN > 0
    int16_t inc[2][NNIK_SH_LEN];
    int16_t w[2][NNIK_SH_N];
    uint8_t at; /* slot of the next increment */
    uint16_t ds[NNIK_SH_LEN + 1]; /* the tool's ring: arc increments, half um (bit 15: M4) */
    uint8_t pd[NNIK_SH_LEN + 1];  /* and the planned duty */
    uint16_t u[NNIK_SH_N];        /* window sums of ds */
    uint16_t lag, e;              /* the last lag; Q[n] - Q[n - k] */
    uint8_t k, tat;               /* the tool's delay in samples; the ring's newest slot */
#endif
} nnik_shaper_t;

void nnik_sh_init(nnik_shaper_t *sh, const int32_t p[2]);

/* the shaped point of the next sample p */
void nnik_sh_step(nnik_shaper_t *sh, const int32_t p[2], int32_t out[2]);

#if NNIK_SH_LEN > 0
/* the duty for the next sample, planned at speed v (Q16 um/sample) with duty pd (m4: scaled) */
uint8_t nnik_sh_tool(nnik_shaper_t *sh, uint32_t v, uint8_t pd, uint8_t m4);
#endif

#ifdef __cplusplus
}
#endif

#endif /* NNIK_SHAPER_H */
