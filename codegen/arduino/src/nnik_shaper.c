/* nnik_shaper.c - see nnik_shaper.h. */
#include "nnik_shaper.h"

#if NNIK_SH_LEN > 0
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

/* max(|dx|, |dy|) of the increments in slot j: the progress of that sample */
NNIK_SH_NOINLINE static uint16_t progress(const nnik_shaper_t *sh, uint8_t j)
{
    int16_t x = sh->inc[0][j], y = sh->inc[1][j];
    uint16_t ax = (uint16_t)(x < 0 ? -x : x), ay = (uint16_t)(y < 0 ? -y : y);
    return ax > ay ? ax : ay;
}

/* the tool of the sample whose slot was just written, the shaped head lag behind in progress
 * (nnik_shaper.h) */
static void tool_step(nnik_shaper_t *sh, uint8_t at, uint16_t lag)
{
    uint16_t e = (uint16_t)(sh->e + progress(sh, at));
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
#endif

void nnik_sh_step(nnik_shaper_t *sh, const int32_t p[2], int32_t out[2])
{
    uint8_t a;
#if NNIK_SH_LEN > 0
    uint8_t at = sh->at;
    int16_t d2 = 0, dd[2]; /* this sample's progress and increments (the rows take them last) */
    uint16_t lag = 0;
    for (a = 0; a < 3; a++) { /* X, Y, and the progress Q with axis 0's taps */
        int16_t d = a < 2 ? (int16_t)(p[a] - sh->last[a]) : d2, *inc = sh->inc[a & 1];
        int32_t sum = sh->s[a];
        const uint16_t *amp = AMPS[a & 1];
        const uint8_t *del = DELAYS[a & 1];
        uint8_t k;
        for (k = 0; k < NNIK_SH_N; k++) {
            uint8_t dk = NNIK_RD_U8(del + k);
            if (dk) { /* W_k += inc[n] - inc[n - dk] (read before the slot is written): S += A_k that */
                uint8_t j = at >= dk ? (uint8_t)(at - dk) : (uint8_t)(at + NNIK_SH_LEN - dk);
                int16_t dw = (int16_t)(d - (a < 2 ? inc[j] : (int16_t)progress(sh, j)));
                if (dw) { /* 0 at a steady speed: no multiply */
                    uint16_t A = NNIK_RD_U16(amp + k);
                    sum += (int32_t)A * dw;
                }
            }
        }
        sh->s[a] = sum;
        sum = (16384 - sum) >> 15; /* |S| < 2^30: nnik.firmware.config checks |W| < 2^15 */
        if (a < 2) {
            dd[a] = d;
            out[a] = p[a] + sum;
            sh->last[a] = p[a];
            if (d < 0)
                d = (int16_t)-d;
            if (d > d2)
                d2 = d;
        } else {
            lag = (uint16_t)-sum;
        }
    }
    sh->inc[0][at] = dd[0];
    sh->inc[1][at] = dd[1];
    tool_step(sh, at, lag);
    sh->at = (uint8_t)(at + 1 == NNIK_SH_LEN ? 0 : at + 1);
#else
    for (a = 0; a < 2; a++) {
        out[a] = p[a];
        sh->last[a] = p[a];
    }
#endif
}
