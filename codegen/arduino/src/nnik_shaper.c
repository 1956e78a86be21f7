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
#endif
    for (a = 0; a < 2; a++) {
        sh->last[a] = p[a];
    }
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

#if NNIK_SH_LEN > 0
#define RING (NNIK_SH_LEN + 1)
#define BACK(at, j) ((uint8_t)((at) >= (j) ? (at) - (j) : (at) + RING - (j)))

uint8_t nnik_sh_tool(nnik_shaper_t *sh, uint32_t v, uint8_t pd, uint8_t m4)
{
    uint16_t ds = (uint16_t)((v + 0x7fffUL) >> 15), e, lag, *u = sh->u;
    uint32_t sum = 16384;
    int32_t vs;
    uint8_t at = (uint8_t)(sh->tat + 1 == RING ? 0 : sh->tat + 1), i, k, j;
    sh->tat = at;
    sh->ds[at] = m4 ? (uint16_t)(ds | 0x8000U) : ds;
    sh->pd[at] = pd;
    for (i = 0; i < NNIK_SH_N; i++) {
        uint8_t dk = NNIK_RD_U8(&DELAYS[0][i]);
        if (dk) { /* U += ds[n] - ds[n - dk]: |U| < 2^16 (nnik.firmware.config) */
            u[i] = (uint16_t)(u[i] + ds - (sh->ds[BACK(at, dk)] & 0x7fffU));
            sum += (uint32_t)NNIK_RD_U16(&AMPS[0][i]) * u[i];
        }
    }
    lag = (uint16_t)(sum >> 15);
    k = (uint8_t)(sh->k + 1);
    e = (uint16_t)(sh->e + ds); /* mod 2^16: exact again once k <= NNIK_SH_LEN */
    while (k > NNIK_SH_LEN || e > lag) {
        k--;
        e = (uint16_t)(e - (sh->ds[BACK(at, k)] & 0x7fffU));
    }
    sh->k = k;
    sh->e = e;
    vs = (int32_t)ds - lag + sh->lag; /* the shaped arc length's increment */
    sh->lag = lag;
    j = BACK(at, k);
    pd = sh->pd[j];
    if ((sh->ds[j] & 0x8000U) && (sh->ds[j] & 0x7fffU)) {
        uint32_t d = vs > 0 ? (uint32_t)pd * (uint32_t)vs / (sh->ds[j] & 0x7fffU) : 0;
        pd = (uint8_t)(d > 255 ? 255 : d);
    }
    return pd;
}
#endif
