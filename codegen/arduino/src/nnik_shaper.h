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
 * progress Q[n] is its path length: the caller gives moved, the sample's distance along the
 * commanded path (nnik_pl_sample_t.moved, Q16 um), and Q[n] = floor(sum of moved / 2^NNIK_SH_PSH)
 * (units of 2^(NNIK_SH_PSH - 16) um; sh->fr keeps the part below a unit, so rounding never
 * accumulates; nnik.machine.ranges.progress_shift picks the finest unit, at most 1/4 um, in which
 * a sample's increment fits uint8).  Q goes through axis 0's taps as a third axis: the shaped
 * head's progress is Q[n] - lag[n], lag = -((16384 - sum_i A_i (Q[n] - Q[n - d_i])) >> 15)
 * (every window sum <= 255 * 255 < 2^16, the sum < 2^31).  Sample n gets the planned duty (t,
 * given with the step) of sample m, the first at or after the previous m and n - NNIK_SH_LEN + 1
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
#if NNIK_SH_LEN > 0 /* the scalars first, the rings after them: every scalar within an AVR displacement */
    int32_t s[3];            /* sum_i A_i W_i of X, Y and the tool's progress, W_i = p[n] - p[n - d_i] */
    uint32_t fr;             /* the path length moved, Q16 um, not yet a whole unit */
    uint16_t e;              /* Q[n] - Q[m] */
    uint8_t at;              /* slot of the next increment */
    uint8_t k, ms, duty;     /* n - m, m's slot; the tool's duty */
    int16_t inc[2][NNIK_SH_LEN];
    uint8_t pd[NNIK_SH_LEN]; /* the tool: planned duties */
    uint8_t pq[NNIK_SH_LEN]; /* the tool: the plan's progress per sample, in units */
#endif
} nnik_shaper_t;

void nnik_sh_init(nnik_shaper_t *sh, const int32_t p[2]);

/* nnik_sh_step: the shaped point of the next sample p (and with a shaper the tool's sh->duty from
 * t, the sample's planned duty; moved: its path length, Q16 um).  Inline: its one caller (the
 * engine's sample, nnik_gc_segments.c) saves and restores its registers once for both. */
#if defined(__GNUC__)
#define NNIK_SH_INLINE static inline __attribute__((always_inline))
#else
#define NNIK_SH_INLINE static inline
#endif

#if NNIK_SH_LEN > 0
#ifndef NNIK_SH_SAME
#define NNIK_SH_SAME 0
#endif
#if NNIK_SH_LEN > 255 || NNIK_SH_N < 1 || NNIK_SH_N > 10
#error "NNIK_SH_LEN must be 0..255 and NNIK_SH_N 1..10"
#endif
#ifndef NNIK_SH_PSH
#define NNIK_SH_PSH 14 /* the tool's progress unit: 2^(NNIK_SH_PSH - 16) um */
#endif
#if NNIK_SH_PSH < 8 || NNIK_SH_PSH > 24
#error "NNIK_SH_PSH must be 8..24"
#endif
#include "nnik_flash.h"

/* the tool of the sample whose slot was just written (its progress dq), the shaped head lag
 * behind in progress */
NNIK_SH_INLINE void nnik_sh_tool(nnik_shaper_t *sh, uint8_t at, uint8_t t, uint16_t dq, uint16_t lag)
{
    uint16_t e = (uint16_t)(sh->e + dq);
    uint8_t k = (uint8_t)(sh->k + 1), j = sh->ms;
    sh->pd[at] = t;
    while (k > NNIK_SH_LEN - 1 || e > lag) { /* m + 1: its progress leaves Q[n] - Q[m] */
        k--;
        j = (uint8_t)(j + 1 == NNIK_SH_LEN ? 0 : j + 1);
        e = (uint16_t)(e - sh->pq[j]);
    }
    sh->k = k;
    sh->e = e;
    sh->ms = j;
    sh->duty = sh->pd[j];
}

/* floor(v / 2^15) of |v| < 2^30 + 2^14 (|result| < 2^15), by byte moves: no 15-step shift loop */
NNIK_SH_INLINE int16_t nnik_sh_shr15(int32_t v)
{
    return (int16_t)(2 * (int16_t)(v >> 16) + (int16_t)((uint16_t)v >> 15));
}

/* the lag -floor((16384 - S) / 2^15) = floor((S + 16383) / 2^15) of the progress' sum
 * 0 <= S <= 2^15 (255 NNIK_SH_LEN) < 2^31 (amplitudes and progress >= 0), by byte moves */
NNIK_SH_INLINE uint16_t nnik_sh_lag(int32_t S)
{
    uint32_t v = (uint32_t)S + 16383;
    return (uint16_t)(((uint16_t)(v >> 16) << 1) | ((uint16_t)v >> 15));
}

/* S += A w (A < 2^16 unsigned, w signed), the sum kept in registers: on AVR the multiplier in
 * place (no call): Al wl and Ah wl unsigned, wh Al and wh Ah signed by unsigned (mulsu: operands
 * in r16..r23), each added at its byte; elsewhere in C */
#if defined(__GNUC__) && defined(__AVR__) && defined(__AVR_HAVE_MUL__)
#define NNIK_SH_MAC(S, A, w)                                                                             \
    do {                                                                                                 \
        uint8_t z_;                                                                                      \
        __asm__("clr %[z]\n\tmul %A[a], %A[w]\n\tadd %A[s], r0\n\tadc %B[s], r1\n\tadc %C[s], %[z]\n\t" \
                "adc %D[s], %[z]\n\tmul %B[a], %A[w]\n\tadd %B[s], r0\n\tadc %C[s], r1\n\t"             \
                "adc %D[s], %[z]\n\tmulsu %B[w], %A[a]\n\tsbc %[z], %[z]\n\tadd %B[s], r0\n\t"           \
                "adc %C[s], r1\n\tadc %D[s], %[z]\n\tmulsu %B[w], %B[a]\n\tadd %C[s], r0\n\t"            \
                "adc %D[s], r1\n\tclr __zero_reg__"                                                      \
                : [s] "+r"(S), [z] "=&r"(z_)                                                             \
                : [a] "a"(A), [w] "a"(w));                                                               \
    } while (0)
#else
#define NNIK_SH_MAC(S, A, w) ((S) += (int32_t)(A) * (w))
#endif
#endif

NNIK_SH_INLINE void nnik_sh_step(nnik_shaper_t *sh, const int32_t p[2], uint8_t t, uint32_t moved, int32_t out[2])
{
#if NNIK_SH_LEN > 0
    static NNIK_FLASH const uint16_t AMPS[2][NNIK_SH_N] = NNIK_SH_AMPS;
    static NNIK_FLASH const uint8_t DELAYS[2][NNIK_SH_N] = NNIK_SH_DELAYS;
    uint8_t at = sh->at, k, dq;
    int32_t s0, s1, s2;
    int16_t dx = (int16_t)(p[0] - sh->last[0]), dy = (int16_t)(p[1] - sh->last[1]);
    uint32_t fr = sh->fr + moved; /* the path length moved, Q16 um, less whole units taken */
    /* this sample's progress in units, fr >> NNIK_SH_PSH (<= 255: nnik.machine.ranges), from
     * fr's bytes: no shift loop */
#if NNIK_SH_PSH <= 16
    dq = (uint8_t)(((uint8_t)(fr >> 16) << (16 - NNIK_SH_PSH)) | ((uint8_t)(fr >> 8) >> (NNIK_SH_PSH - 8)));
#else
    dq = (uint8_t)(((uint8_t)(fr >> 24) << (24 - NNIK_SH_PSH)) | ((uint8_t)(fr >> 16) >> (NNIK_SH_PSH - 16)));
#endif
    sh->fr = fr & ((1UL << NNIK_SH_PSH) - 1);
    s0 = sh->s[0];
    s1 = sh->s[1];
    s2 = sh->s[2];
    for (k = 0; k < NNIK_SH_N; k++) { /* W_k += inc[n] - inc[n - dk] (read before the slot is written) */
        uint8_t d0 = NNIK_RD_U8(&DELAYS[0][k]), j;
        int16_t w;
#if !NNIK_SH_SAME
        uint8_t d1 = NNIK_RD_U8(&DELAYS[1][k]);
#endif
        if (d0) { /* X and the progress Q on axis 0's taps (Y too when both axes have the same) */
            uint16_t A = NNIK_RD_U16(&AMPS[0][k]);
            j = at >= d0 ? (uint8_t)(at - d0) : (uint8_t)(at + NNIK_SH_LEN - d0);
            w = (int16_t)(dx - sh->inc[0][j]);
            if (w) /* 0 at a steady speed: no multiply */
                NNIK_SH_MAC(s0, A, w);
#if NNIK_SH_SAME /* one ring index for both axes */
            w = (int16_t)(dy - sh->inc[1][j]);
            if (w)
                NNIK_SH_MAC(s1, A, w);
#endif
            w = (int16_t)((int16_t)dq - sh->pq[j]);
            if (w)
                NNIK_SH_MAC(s2, A, w);
        }
#if !NNIK_SH_SAME
        if (d1) {
            uint16_t A = NNIK_RD_U16(&AMPS[1][k]);
            j = at >= d1 ? (uint8_t)(at - d1) : (uint8_t)(at + NNIK_SH_LEN - d1);
            w = (int16_t)(dy - sh->inc[1][j]);
            if (w)
                NNIK_SH_MAC(s1, A, w);
        }
#endif
    }
    sh->s[0] = s0;
    sh->s[1] = s1;
    sh->s[2] = s2;
    /* |S| < 2^30: nnik.firmware.config checks |W| < 2^15 */
    out[0] = p[0] + nnik_sh_shr15(16384 - s0);
    out[1] = p[1] + nnik_sh_shr15(16384 - s1);
    sh->last[0] = p[0];
    sh->last[1] = p[1];
    sh->inc[0][at] = dx;
    sh->inc[1][at] = dy;
    sh->pq[at] = dq;
    nnik_sh_tool(sh, at, t, dq, nnik_sh_lag(s2));
    sh->at = (uint8_t)(at + 1 == NNIK_SH_LEN ? 0 : at + 1);
#else
    uint8_t a;
    (void)t;
    (void)moved;
    for (a = 0; a < 2; a++) {
        out[a] = p[a];
        sh->last[a] = p[a];
    }
#endif
}

#ifdef __cplusplus
}
#endif

#endif /* NNIK_SHAPER_H */
