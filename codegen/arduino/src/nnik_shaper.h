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
 * S = sum_i A_i W_i per axis as int32: each sample S += A_i (inc[n] - inc[n - d_i]), skipped where
 * that is 0 (a steady speed); nnik.firmware.config checks that NNIK_SH_LEN * (the largest move per
 * sample + 2 um) < 2^15, so every |W| < 2^15 and |S| < 2^30.  NNIK_SH_LEN 0: no shaper, the samples pass unchanged, no memory.
 *
 * The tool follows the shaped head (nnik/firmware/gcode/tool_shaper.py repeats it).  The plan's
 * progress Q[n] is its path length: the caller sets sh->moved, the sample's distance along the
 * commanded path (nnik_pl_sample_t.moved, Q16 um), and Q[n] = floor(sum of moved / 2^NNIK_SH_PSH)
 * (units of 2^(NNIK_SH_PSH - 16) um; sh->fr keeps the part below a unit, so rounding never
 * accumulates; nnik.machine.ranges.progress_shift picks the finest unit, at most 1/4 um, in which
 * a sample's increment fits uint8).  Q goes through axis 0's taps as a third axis: the shaped
 * head's progress is Q[n] - lag[n], lag = -((16384 - sum_i A_i (Q[n] - Q[n - d_i])) >> 15)
 * (every window sum <= 255 * 255 < 2^16, the sum < 2^31).  Sample n gets the planned duty (sh->t,
 * set before the step) of sample m, the first at or after the previous m and n - NNIK_SH_LEN + 1
 * with Q[m] >= Q[n] - lag[n]: the tool switches when the shaped head reaches the planned switch
 * (sh->duty).  Its memory: the running sum S of Q, the planned duties and progress increments of
 * the last NNIK_SH_LEN samples, the pointer's delay k, m's slot, Q[n] - Q[m] and fr.
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
    int32_t s[3];            /* sum_i A_i W_i of X, Y and the tool's progress, W_i = p[n] - p[n - d_i] */
    uint8_t at; /* slot of the next increment */
    uint8_t pd[NNIK_SH_LEN]; /* the tool: planned duties */
    uint8_t pq[NNIK_SH_LEN]; /* the tool: the plan's progress per sample, in units */
    uint32_t fr;             /* the path length moved, Q16 um, not yet a whole unit */
    uint32_t moved;          /* this sample's path length (Q16 um), set before the step */
    uint16_t e;              /* Q[n] - Q[m] */
    uint8_t k, ms, t, duty;  /* n - m, m's slot; this sample's planned duty; the tool's duty */
#endif
} nnik_shaper_t;

void nnik_sh_init(nnik_shaper_t *sh, const int32_t p[2]);

/* the shaped point of the next sample p (and with a shaper the tool's sh->duty from sh->t) */
void nnik_sh_step(nnik_shaper_t *sh, const int32_t p[2], int32_t out[2]);

#ifdef __cplusplus
}
#endif

#endif /* NNIK_SHAPER_H */
