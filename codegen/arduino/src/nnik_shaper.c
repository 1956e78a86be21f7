/* nnik_shaper.c - see nnik_shaper.h. */
#include "nnik_shaper.h"

#if NNIK_SH_LEN > 0
#ifndef NNIK_SH_SAME
#define NNIK_SH_SAME 0
#endif
#if NNIK_SH_LEN > 255 || NNIK_SH_N < 1 || NNIK_SH_N > 10
#error "NNIK_SH_LEN must be 0..255 and NNIK_SH_N 1..10"
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

/* max(|x|, |y|): a sample's progress */
static inline uint16_t maxabs(int16_t x, int16_t y)
{
    uint16_t ax = (uint16_t)(x < 0 ? -x : x), ay = (uint16_t)(y < 0 ? -y : y);
    return ax > ay ? ax : ay;
}

/* max(|dx|, |dy|) of the increments in slot j: the progress of that sample */
NNIK_SH_NOINLINE static uint16_t progress(const nnik_shaper_t *sh, uint8_t j)
{
    return maxabs(sh->inc[0][j], sh->inc[1][j]);
}

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
        e = (uint16_t)(e - progress(sh, j));
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
    uint8_t at = sh->at, k;
    int16_t dx = (int16_t)(p[0] - sh->last[0]), dy = (int16_t)(p[1] - sh->last[1]);
    int16_t dq = (int16_t)maxabs(dx, dy); /* this sample's progress (the rows take it last) */
#if NNIK_SH_SAME /* both axes on the same taps: one ring index, the progress from the pair read */
    for (k = 0; k < NNIK_SH_N; k++) { /* W_k += inc[n] - inc[n - dk] (read before the slot is written) */
        uint8_t d = NNIK_RD_U8(&DELAYS[0][k]);
        if (d) {
            uint16_t A = NNIK_RD_U16(&AMPS[0][k]);
            uint8_t j = at >= d ? (uint8_t)(at - d) : (uint8_t)(at + NNIK_SH_LEN - d);
            int16_t x = sh->inc[0][j], y = sh->inc[1][j];
            tap(&sh->s[0], A, (int16_t)(dx - x));
            tap(&sh->s[1], A, (int16_t)(dy - y));
            tap(&sh->s[2], A, (int16_t)(dq - (int16_t)maxabs(x, y)));
        }
    }
#else
    for (k = 0; k < NNIK_SH_N; k++) { /* W_k += inc[n] - inc[n - dk] (read before the slot is written) */
        uint8_t d0 = NNIK_RD_U8(&DELAYS[0][k]), d1 = NNIK_RD_U8(&DELAYS[1][k]), j;
        if (d0) { /* X and the progress Q, with axis 0's taps */
            uint16_t A = NNIK_RD_U16(&AMPS[0][k]);
            j = at >= d0 ? (uint8_t)(at - d0) : (uint8_t)(at + NNIK_SH_LEN - d0);
            tap(&sh->s[0], A, (int16_t)(dx - sh->inc[0][j]));
            tap(&sh->s[2], A, (int16_t)(dq - (int16_t)progress(sh, j)));
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
    tool_step(sh, at, (uint16_t)dq, (uint16_t)-shr15(16384 - sh->s[2]));
    sh->at = (uint8_t)(at + 1 == NNIK_SH_LEN ? 0 : at + 1);
#else
    uint8_t a;
    for (a = 0; a < 2; a++) {
        out[a] = p[a];
        sh->last[a] = p[a];
    }
#endif
}
