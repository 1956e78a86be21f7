/* nnik_shaper.c - see nnik_shaper.h. */
#include "nnik_shaper.h"

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
static NNIK_FLASH const uint16_t AMPS[2][NNIK_SH_N] = NNIK_SH_AMPS;
static NNIK_FLASH const uint8_t DELAYS[2][NNIK_SH_N] = NNIK_SH_DELAYS;
#endif

void nnik_sh_init(nnik_shaper_t *sh, const int32_t p[2])
{
    uint8_t a;
#if NNIK_SH_LEN > 0
    uint8_t *z = (uint8_t *)sh;
    uint16_t i;
    for (i = 0; i < sizeof *sh; i++)
        z[i] = 0;
    sh->ms = NNIK_SH_LEN - 1; /* m: the sample before the first */
#endif
    for (a = 0; a < 2; a++)
        sh->last[a] = p[a];
}

#if NNIK_SH_LEN > 0
#if defined(__GNUC__)
#define NNIK_SH_NOINLINE __attribute__((noinline))
#else
#define NNIK_SH_NOINLINE
#endif

/* the tool of the sample whose slot was just written (its progress dq), the shaped head lag
 * behind in progress (nnik_shaper.h) */
static void tool_step(nnik_shaper_t *sh, uint8_t at, uint16_t dq, uint16_t lag)
{
    uint16_t e = (uint16_t)(sh->e + dq);
    uint8_t k = (uint8_t)(sh->k + 1), j = sh->ms;
    sh->pd[at] = sh->t;
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
static int16_t shr15(int32_t v)
{
    return (int16_t)(2 * (int16_t)(v >> 16) + (int16_t)((uint16_t)v >> 15));
}

/* the lag -floor((16384 - S) / 2^15) = floor((S + 16383) / 2^15) of the progress' sum
 * 0 <= S <= 2^15 (255 NNIK_SH_LEN) < 2^31 (amplitudes and progress >= 0), by byte moves */
static uint16_t lag(int32_t S)
{
    uint32_t v = (uint32_t)S + 16383;
    return (uint16_t)(((uint16_t)(v >> 16) << 1) | ((uint16_t)v >> 15));
}

/* *S += A dw: 0 at a steady speed, no multiply; the sum stays in memory (no register for it
 * across the taps: a smaller frame to save) */
static inline void tap(int32_t *S, uint16_t A, int16_t dw)
{
    if (dw)
        *S += (int32_t)A * dw;
}
#endif

void nnik_sh_step(nnik_shaper_t *sh, const int32_t p[2], int32_t out[2])
{
#if NNIK_SH_LEN > 0
    uint8_t at = sh->at, k, dq;
    int16_t dx = (int16_t)(p[0] - sh->last[0]), dy = (int16_t)(p[1] - sh->last[1]);
    uint32_t fr = sh->fr + sh->moved; /* the path length moved, Q16 um, less whole units taken */
    /* this sample's progress in units, fr >> NNIK_SH_PSH (<= 255: nnik.machine.ranges), from
     * fr's bytes: no shift loop */
#if NNIK_SH_PSH <= 16
    dq = (uint8_t)(((uint8_t)(fr >> 16) << (16 - NNIK_SH_PSH)) | ((uint8_t)(fr >> 8) >> (NNIK_SH_PSH - 8)));
#else
    dq = (uint8_t)(((uint8_t)(fr >> 24) << (24 - NNIK_SH_PSH)) | ((uint8_t)(fr >> 16) >> (NNIK_SH_PSH - 16)));
#endif
    sh->fr = fr & ((1UL << NNIK_SH_PSH) - 1);
#if NNIK_SH_SAME /* both axes on the same taps: one ring index */
    for (k = 0; k < NNIK_SH_N; k++) { /* W_k += inc[n] - inc[n - dk] (read before the slot is written) */
        uint8_t d = NNIK_RD_U8(&DELAYS[0][k]);
        if (d) {
            uint16_t A = NNIK_RD_U16(&AMPS[0][k]);
            uint8_t j = at >= d ? (uint8_t)(at - d) : (uint8_t)(at + NNIK_SH_LEN - d);
            tap(&sh->s[0], A, (int16_t)(dx - sh->inc[0][j]));
            tap(&sh->s[1], A, (int16_t)(dy - sh->inc[1][j]));
            tap(&sh->s[2], A, (int16_t)dq - sh->pq[j]);
        }
    }
#else
    for (k = 0; k < NNIK_SH_N; k++) { /* W_k += inc[n] - inc[n - dk] (read before the slot is written) */
        uint8_t d0 = NNIK_RD_U8(&DELAYS[0][k]), d1 = NNIK_RD_U8(&DELAYS[1][k]), j;
        if (d0) { /* X and the progress Q, with axis 0's taps */
            uint16_t A = NNIK_RD_U16(&AMPS[0][k]);
            j = at >= d0 ? (uint8_t)(at - d0) : (uint8_t)(at + NNIK_SH_LEN - d0);
            tap(&sh->s[0], A, (int16_t)(dx - sh->inc[0][j]));
            tap(&sh->s[2], A, (int16_t)dq - sh->pq[j]);
        }
        if (d1) {
            j = at >= d1 ? (uint8_t)(at - d1) : (uint8_t)(at + NNIK_SH_LEN - d1);
            tap(&sh->s[1], NNIK_RD_U16(&AMPS[1][k]), (int16_t)(dy - sh->inc[1][j]));
        }
    }
#endif
    /* |S| < 2^30: nnik.firmware.config checks |W| < 2^15 */
    out[0] = p[0] + shr15(16384 - sh->s[0]);
    out[1] = p[1] + shr15(16384 - sh->s[1]);
    sh->last[0] = p[0];
    sh->last[1] = p[1];
    sh->inc[0][at] = dx;
    sh->inc[1][at] = dy;
    sh->pq[at] = dq;
    tool_step(sh, at, dq, lag(sh->s[2]));
    sh->at = (uint8_t)(at + 1 == NNIK_SH_LEN ? 0 : at + 1);
#else
    uint8_t a;
    for (a = 0; a < 2; a++) {
        out[a] = p[a];
        sh->last[a] = p[a];
    }
#endif
}
