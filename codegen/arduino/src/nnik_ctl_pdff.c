/* nnik_ctl_pdff.c - PD with velocity and acceleration feedforward per axis, in integers (Python
 * spec: nnik/implementations/servo/pdff.py); compiled in when nnik_servo_config.h defines
 * NNIK_CTL_PDFF.  u = kp e + kd (e - e_prev) + kv v + ka a + kf sign(v), with v and a the
 * reference's first and second differences over NNIK_CTL_WIN ticks (a ring of 2 W references). */
#include "nnik_servo_config.h"

#ifdef NNIK_CTL_PDFF
#include "nnik_ctl.h"
#include "nnik_ctl_fix.h"

#define NNIK_RING (2 * NNIK_CTL_WIN)

static int32_t nnik_pdff_ring[2][NNIK_RING];
static int32_t nnik_pdff_eprev[2];
static uint8_t nnik_pdff_idx, nnik_pdff_primed;

void nnik_ctl_reset(void)
{
    nnik_pdff_idx = 0;
    nnik_pdff_primed = 0;
}

static int16_t nnik_pdff_axis(uint8_t i, int32_t ref, int32_t pos, uint16_t kp, uint16_t kd, uint16_t kv,
                              uint16_t ka, int16_t kf)
{
    int32_t *ring = nnik_pdff_ring[i];
    int32_t old1, old2, e = ref - pos, acc;
    int16_t de, v;
    uint8_t j;
    if (!nnik_pdff_primed) {
        for (j = 0; j < NNIK_RING; j++)
            ring[j] = ref;
        nnik_pdff_eprev[i] = e;
    }
    old2 = ring[nnik_pdff_idx];
    old1 = ring[(nnik_pdff_idx + NNIK_CTL_WIN) & (NNIK_RING - 1)];
    ring[nnik_pdff_idx] = ref;
    de = nnik_ctl_s16(e - nnik_pdff_eprev[i]);
    nnik_pdff_eprev[i] = e;
    v = nnik_ctl_s16(ref - old1);
    acc = nnik_ctl_term(kp, nnik_ctl_s16(e)) + nnik_ctl_term(kd, de) + nnik_ctl_term(kv, v)
          + nnik_ctl_term(ka, nnik_ctl_s16(ref - 2 * old1 + old2));
    if (v > 0)
        acc += (int32_t)kf << NNIK_CTL_Q_OUT;
    else if (v < 0)
        acc -= (int32_t)kf << NNIK_CTL_Q_OUT;
    return nnik_ctl_duty(acc);
}

void nnik_ctl_tick(const int32_t ref[2], const int32_t pos[2], int16_t duty[2])
{
    duty[0] = nnik_pdff_axis(0, ref[0], pos[0], NNIK_KP_X, NNIK_KD_X, NNIK_KV_X, NNIK_KA_X, NNIK_KF_X);
    duty[1] = nnik_pdff_axis(1, ref[1], pos[1], NNIK_KP_Y, NNIK_KD_Y, NNIK_KV_Y, NNIK_KA_Y, NNIK_KF_Y);
    nnik_pdff_idx = (uint8_t)((nnik_pdff_idx + 1) & (NNIK_RING - 1));
    nnik_pdff_primed = 1;
}
#else
typedef int nnik_ctl_pdff_unused; /* not this build's controller */
#endif
