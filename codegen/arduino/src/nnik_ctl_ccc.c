/* nnik_ctl_ccc.c - Koren's cross-coupled controller in integers (Python spec:
 * nnik/implementations/servo/ccc.py); compiled in when nnik_servo_config.h defines NNIK_CTL_CCC.
 * The Arduino-library PID per axis (nnik_ctl_pid_axis.h) plus a PD on the contour error
 * eps = -e_x sin + e_y cos, fed back along the path's normal (-sin, cos); the direction is the
 * reference's chord over NNIK_CTL_WIN ticks normalised with an integer square root of 256 l2 (Q14). */
#include "nnik_servo_config.h"

#ifdef NNIK_CTL_CCC
#include "nnik_ctl.h"
#include "nnik_ctl_pid_axis.h"
#include "nnik_imath.h"

#define NNIK_CCC_UC_MAX (3L << 15) /* 384 duty: sin * uc fits int32 */
#define NNIK_CCC_CHORD_MAX 2047L /* l2 << 8 fits 32 bits */

static nnik_pid_axis_t nnik_ccc_x, nnik_ccc_y;
static int32_t nnik_ccc_ring[2][2 * NNIK_CTL_WIN];
static int16_t nnik_ccc_sin, nnik_ccc_cos, nnik_ccc_eps;
static uint8_t nnik_ccc_idx, nnik_ccc_primed;

void nnik_ctl_reset(void)
{
    nnik_ccc_x.integral = 0;
    nnik_ccc_y.integral = 0;
    nnik_ccc_sin = 0;
    nnik_ccc_cos = 0;
    nnik_ccc_idx = 0;
    nnik_ccc_primed = 0;
}

/* the path's direction (sin, cos in Q14) from ref[k] - ref[k - W]; held on a short chord */
static void nnik_ccc_direction(const int32_t ref[2])
{
    int16_t d[2];
    uint8_t i, j, old = (uint8_t)((nnik_ccc_idx + NNIK_CTL_WIN) & (2 * NNIK_CTL_WIN - 1));
    uint32_t l2;
    for (i = 0; i < 2; i++) {
        if (!nnik_ccc_primed)
            for (j = 0; j < 2 * NNIK_CTL_WIN; j++)
                nnik_ccc_ring[i][j] = ref[i];
        d[i] = (int16_t)nnik_ctl_sat(ref[i] - nnik_ccc_ring[i][old], NNIK_CCC_CHORD_MAX);
        nnik_ccc_ring[i][nnik_ccc_idx] = ref[i];
    }
    nnik_ccc_idx = (uint8_t)((nnik_ccc_idx + 1) & (2 * NNIK_CTL_WIN - 1));
    l2 = (uint32_t)((int32_t)d[0] * d[0]) + (uint32_t)((int32_t)d[1] * d[1]);
    if (l2 >= (uint32_t)NNIK_CCC_MIN_CHORD * NNIK_CCC_MIN_CHORD) {
        int32_t inv = (int32_t)((1UL << 28) / nnik_isqrt32(l2 << 8));
        nnik_ccc_sin = (int16_t)(((int32_t)d[1] * inv + (1L << 9)) >> 10);
        nnik_ccc_cos = (int16_t)(((int32_t)d[0] * inv + (1L << 9)) >> 10);
    }
}

void nnik_ctl_tick(const int32_t ref[2], const int32_t pos[2], int16_t duty[2])
{
    int32_t ax = nnik_pid_axis(&nnik_ccc_x, nnik_ccc_primed, ref[0], pos[0], NNIK_KP_X, NNIK_KI_X, NNIK_KD_X);
    int32_t ay = nnik_pid_axis(&nnik_ccc_y, nnik_ccc_primed, ref[1], pos[1], NNIK_KP_Y, NNIK_KI_Y, NNIK_KD_Y);
    int16_t ex = nnik_ctl_s16(ref[0] - pos[0]), ey = nnik_ctl_s16(ref[1] - pos[1]), eps, deps;
    int32_t uc;
    nnik_ccc_direction(ref);
    eps = nnik_ctl_s16(((int32_t)ey * nnik_ccc_cos - (int32_t)ex * nnik_ccc_sin) >> 10);
    deps = nnik_ccc_primed ? nnik_ctl_s16((int32_t)eps - nnik_ccc_eps) : 0;
    nnik_ccc_eps = eps;
    uc = nnik_ctl_sat((nnik_ctl_term(NNIK_KCP, eps) + nnik_ctl_term(NNIK_KCD, deps)) >> 4, NNIK_CCC_UC_MAX);
    duty[0] = nnik_ctl_duty(ax + ((-(int32_t)nnik_ccc_sin * uc) >> 14));
    duty[1] = nnik_ctl_duty(ay + (((int32_t)nnik_ccc_cos * uc) >> 14));
    nnik_ccc_primed = 1;
}
#else
typedef int nnik_ctl_ccc_unused; /* not this build's controller */
#endif
