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
    for (a = 0; a < 2; a++) {
        sh->last[a] = p[a];
#if NNIK_SH_LEN > 0
        {
            uint8_t k;
            for (k = 0; k < NNIK_SH_LEN; k++)
                sh->inc[a][k] = 0;
            for (k = 0; k < NNIK_SH_N; k++)
                sh->w[a][k] = 0;
        }
#endif
    }
#if NNIK_SH_LEN > 0
    sh->at = 0;
#endif
}

void nnik_sh_step(nnik_shaper_t *sh, const int32_t p[2], int32_t out[2])
{
    uint8_t a;
    for (a = 0; a < 2; a++) {
#if NNIK_SH_LEN > 0
        int16_t d = (int16_t)(p[a] - sh->last[a]), *inc = sh->inc[a];
        int32_t sum = 16384;
        int16_t *w = sh->w[a];
        const uint16_t *amp = AMPS[a];
        const uint8_t *del = DELAYS[a];
        uint8_t k, at = sh->at;
        for (k = 0; k < NNIK_SH_N; k++, w++) {
            uint8_t dk = NNIK_RD_U8(del + k);
            if (dk) { /* W += inc[n] - inc[n - dk] (read before the slot is written) */
                uint8_t j = at >= dk ? (uint8_t)(at - dk) : (uint8_t)(at + NNIK_SH_LEN - dk);
                *w = (int16_t)((int32_t)*w + d - inc[j]); /* |W| < 2^15: nnik.firmware.config checks it */
                sum -= (int32_t)NNIK_RD_U16(amp + k) * *w;
            }
        }
        inc[at] = d;
        out[a] = p[a] + (sum >> 15);
#else
        out[a] = p[a];
#endif
        sh->last[a] = p[a];
    }
#if NNIK_SH_LEN > 0
    sh->at = (uint8_t)(sh->at + 1 == NNIK_SH_LEN ? 0 : sh->at + 1);
#endif
}
