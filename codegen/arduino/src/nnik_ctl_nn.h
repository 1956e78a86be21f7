/*
 * nnik_ctl_nn.h - the online-learning integer 4-8-1 network both neural controllers share
 * (nnik_ctl_nn_axes.c, nnik_ctl_nn_vector.c; the Python spec: nnik/implementations/servo/nn/net.py,
 * formats in nn/formats.py).  Included by the one compiled controller only (static functions).
 *
 *   x   inputs int16 Q3.12;  w1, w2  int32 master words (Q3.28), the forward pass uses the top 16 bits
 *   a_j = sat16(sum_i (w1_ji >> 16) x_i >> 12)    |w1 >> 16| <= 16384: the sum cannot wrap
 *   h_j = nnik_tanh(a_j)                          Q15 (generated: nnik_nn_tanh.h)
 *   y   = sum_j (w2_j >> 16) h_j                  |w2 >> 16| <= 8192: cannot wrap; Q8 duty = y >> OUT_SHIFT
 * learning with the previous tick's cache and delta_out d (Q3.12):
 *   g_j = 32767 - (h_j h_j >> 15);  dh_j = (sat16(d (w2_j >> 16) >> 12) g_j) >> 15
 *   w2_j += rnd(d h_j, ETA);  w1_ji += rnd(dh_j x_i, ETA + 3);  each clamped (+-2^29, +-2^30)
 *   skipped when the previous output sat at +-NNIK_DUTY_MAX and d pushes it further (anti-windup)
 * Every product is int16 x int16 -> int32.  nnik_ctl_sum: the master words' low halves summed mod 2^16.
 */
#ifndef NNIK_CTL_NN_H
#define NNIK_CTL_NN_H

#include <stdint.h>

#include "nnik_ctl.h"
#include "nnik_ctl_fix.h"
#include "nnik_flash.h"
#include "nnik_imath.h"
#include "nnik_nn_tanh.h"

#define NNIK_NN_IN 4
#define NNIK_NN_HID 8
#define NNIK_NN_W1_LIM (1L << 30)
#define NNIK_NN_W2_LIM (1L << 29)

/* p / 2^s rounded half up (arithmetic shift) */
#define NNIK_NN_RND(p, s) (((p) + ((1L << (s)) >> 1)) >> (s))

/* a raw integer input into Q3.12 by 2^s (s a constant, -12 .. 12), saturated to +-32767 */
#define NNIK_NN_POS(s) ((s) >= 0 ? (s) : 0)
#define NNIK_NN_SCALE(raw, s)                                                                        \
    ((s) >= 0 ? (int16_t)(nnik_ctl_sat((raw), 32767L >> NNIK_NN_POS(s)) * (1L << NNIK_NN_POS(s))) \
              : nnik_ctl_s16((raw) >> NNIK_NN_POS(-(s))))

typedef struct {
    int32_t w1[NNIK_NN_HID][NNIK_NN_IN];
    int32_t w2[NNIK_NN_HID];
    int16_t x[NNIK_NN_IN]; /* the last forward pass' inputs and hidden outputs */
    int16_t h[NNIK_NN_HID];
    int16_t u; /* and its output (duty) */
} nnik_nn_t;

static NNIK_FLASH const int32_t nnik_nn_w1_init[NNIK_NN_NETS * NNIK_NN_HID * NNIK_NN_IN] = NNIK_NN_W1_INIT;
static NNIK_FLASH const int32_t nnik_nn_w2_init[NNIK_NN_NETS * NNIK_NN_HID] = NNIK_NN_W2_INIT;

/* a * b, 16 x 16 -> 32 bits (the empty asm keeps avr-gcc from widening to a 32 x 32 product) */
static inline int32_t nnik_nn_mul(int16_t a, int16_t b)
{
    NNIK_KEEP16(a);
    NNIK_KEEP16(b);
    return (int32_t)a * b;
}

static int32_t nnik_nn_clamp(int32_t w, int32_t lim)
{
    return w > lim ? lim : (w < -lim ? -lim : w);
}

/* net k's weights from the initial ones (flash), the cache cleared; returns their low halves' sum */
static uint16_t nnik_nn_load(nnik_nn_t *n, uint8_t k)
{
    uint8_t j, i;
    uint16_t sum = 0;
    for (j = 0; j < NNIK_NN_HID; j++) {
        for (i = 0; i < NNIK_NN_IN; i++) {
            n->w1[j][i] = NNIK_RD_I32(&nnik_nn_w1_init[(uint8_t)(k * (NNIK_NN_HID * NNIK_NN_IN) + j * NNIK_NN_IN + i)]);
            sum += (uint16_t)n->w1[j][i];
        }
        n->w2[j] = NNIK_RD_I32(&nnik_nn_w2_init[(uint8_t)(k * NNIK_NN_HID + j)]);
        sum += (uint16_t)n->w2[j];
        n->h[j] = 0;
    }
    n->u = 0;
    return sum;
}

/* the Q8 duty accumulator for inputs x; caches x and h; adds the weights' low halves to *sum */
static int32_t nnik_nn_forward(nnik_nn_t *n, const int16_t x[NNIK_NN_IN], uint16_t *sum)
{
    uint8_t j, i;
    int32_t y = 0;
    uint16_t s16 = *sum;
    for (i = 0; i < NNIK_NN_IN; i++)
        n->x[i] = x[i];
    for (j = 0; j < NNIK_NN_HID; j++) {
        int32_t a = 0;
        int16_t h;
        for (i = 0; i < NNIK_NN_IN; i++) {
            int32_t w = n->w1[j][i];
            a += nnik_nn_mul((int16_t)(w >> 16), x[i]);
            s16 += (uint16_t)w;
        }
        h = nnik_tanh(nnik_ctl_s16(a >> 12));
        n->h[j] = h;
        y += nnik_nn_mul((int16_t)(n->w2[j] >> 16), h);
        s16 += (uint16_t)n->w2[j];
    }
    *sum = s16;
    return y >> NNIK_NN_OUT_SHIFT;
}

/* backward with the cached forward pass and delta_out d, then the clamped weight update */
static void nnik_nn_learn(nnik_nn_t *n, int16_t d)
{
    uint8_t j, i;
    if ((n->u >= NNIK_DUTY_MAX && d > 0) || (n->u <= -NNIK_DUTY_MAX && d < 0))
        return; /* anti-windup: the output sat at its limit and d would push it further */
    for (j = 0; j < NNIK_NN_HID; j++) {
        int16_t h = n->h[j];
        int16_t g = (int16_t)(32767 - (int16_t)(nnik_nn_mul(h, h) >> 15));
        int16_t t = nnik_ctl_s16(nnik_nn_mul(d, (int16_t)(n->w2[j] >> 16)) >> 12);
        int16_t dh = (int16_t)(nnik_nn_mul(t, g) >> 15);
        n->w2[j] = nnik_nn_clamp(n->w2[j] + NNIK_NN_RND(nnik_nn_mul(d, h), NNIK_NN_ETA), NNIK_NN_W2_LIM);
        for (i = 0; i < NNIK_NN_IN; i++)
            n->w1[j][i] = nnik_nn_clamp(n->w1[j][i] + NNIK_NN_RND(nnik_nn_mul(dh, n->x[i]), NNIK_NN_ETA + 3),
                                        NNIK_NN_W1_LIM);
    }
}

#endif /* NNIK_CTL_NN_H */
