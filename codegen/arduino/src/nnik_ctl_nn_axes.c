/* nnik_ctl_nn_axes.c - one online-learning 4-8-1 network per axis (Python spec:
 * nnik/implementations/servo/nn/nn_axes.py; the network: nnik_ctl_nn.h); compiled in when
 * nnik_servo_config.h defines NNIK_CTL_NN_AXES.  Inputs per axis: e, e - e1, e - 2 e1 + e2 (e = ref -
 * pos saturated to +-2^20) and the reference's speed over NNIK_CTL_WIN ticks, each scaled by
 * 2^NNIK_NN_IN_SHIFT_i into Q3.12.  Each tick: learn from the previous forward pass with this tick's
 * error (delta_out = e J), then forward.  The initial weights: NNIK_NN_W1_INIT / NNIK_NN_W2_INIT. */
#include "nnik_servo_config.h"

#ifdef NNIK_CTL_NN_AXES
#include "nnik_ctl_nn.h"

#define NNIK_NNA_E_MAX (1L << 20)

uint16_t nnik_ctl_sum; /* the weights' checksum after the last tick (or reset) */

static nnik_nn_t nnik_nna_net[2];
static int32_t nnik_nna_e1[2], nnik_nna_e2[2];
static int32_t nnik_nna_ring[2][NNIK_CTL_WIN]; /* ref[k - W] at nnik_nna_idx */
static uint8_t nnik_nna_idx, nnik_nna_primed, nnik_nna_loaded, nnik_nna_phase;

void nnik_ctl_reset(void)
{
    nnik_ctl_sum = (uint16_t)(nnik_nn_load(&nnik_nna_net[0], 0) + nnik_nn_load(&nnik_nna_net[1], 1));
    nnik_nna_idx = 0;
    nnik_nna_primed = 0;
    nnik_nna_phase = 0;
    nnik_nna_loaded = 1;
}

void nnik_ctl_tick(const int32_t ref[2], const int32_t pos[2], int16_t duty[2])
{
    uint8_t a, j;
    if (!nnik_nna_loaded) /* zeroed statics at power-on: start from the initial weights */
        nnik_ctl_reset();
    nnik_ctl_sum = 0;
    for (a = 0; a < 2; a++) {
        nnik_nn_t *n = &nnik_nna_net[a];
        int32_t e = nnik_ctl_sat(ref[a] - pos[a], NNIK_NNA_E_MAX), e1 = e, e2 = e, v;
        int16_t x[NNIK_NN_IN], d;
        if (nnik_nna_primed) {
            e1 = nnik_nna_e1[a];
            e2 = nnik_nna_e2[a];
        } else {
            for (j = 0; j < NNIK_CTL_WIN; j++)
                nnik_nna_ring[a][j] = ref[a];
        }
        v = nnik_ctl_sat(ref[a] - nnik_nna_ring[a][nnik_nna_idx], NNIK_NNA_E_MAX);
        nnik_nna_ring[a][nnik_nna_idx] = ref[a];
        x[0] = NNIK_NN_SCALE(e, NNIK_NN_IN_SHIFT_0);
        x[1] = NNIK_NN_SCALE(e - e1, NNIK_NN_IN_SHIFT_1);
        x[2] = NNIK_NN_SCALE(e - 2 * e1 + e2, NNIK_NN_IN_SHIFT_2);
        x[3] = NNIK_NN_SCALE(v, NNIK_NN_IN_SHIFT_3);
        d = nnik_ctl_s16(nnik_nn_asr(nnik_nn_mac(0, x[0], a ? NNIK_NN_JY : NNIK_NN_JX), 12));
        n->u = nnik_ctl_duty(nnik_nn_step(n, x, d, nnik_nna_phase, &nnik_ctl_sum));
        duty[a] = n->u;
        nnik_nna_e2[a] = e1;
        nnik_nna_e1[a] = e;
    }
    nnik_nna_idx = (uint8_t)((nnik_nna_idx + 1) & (NNIK_CTL_WIN - 1));
    nnik_nna_primed = 1;
    nnik_nna_phase = (uint8_t)((nnik_nna_phase + 1) & (NNIK_NN_W1_EVERY - 1));
}
#else
typedef int nnik_ctl_nn_axes_unused; /* not this build's controller */
#endif
