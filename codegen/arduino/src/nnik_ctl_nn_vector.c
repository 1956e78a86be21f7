/* nnik_ctl_nn_vector.c - the vectorial neural controller, one online-learning 4-8-1 network on the
 * contour error's magnitude (Python spec: nnik/implementations/servo/nn/nn_vector.py; the network:
 * nnik_ctl_nn.h); compiled in when nnik_servo_config.h defines NNIK_CTL_NN_VECTOR.
 *   m = isqrt(ex^2 + ey^2) (e saturated to int16);  inputs m, m - m1, m - 2 m1 + m2, |R| (the
 *   reference >> NNIK_NN_R_SHIFT, per component saturated to int16; the octagonal estimate
 *   max + 3/8 min of the components' magnitudes), scaled into Q3.12
 *   learn with delta_out = the scaled m (only the Jacobian's sign), then U = the net's duty
 *   split (OUR RECONSTRUCTION of the seed's eqs. 25-26): U_a = U (e_a / m) c_a, c_a = J_max / J_a
 *   (Q8: NNIK_NN_CX, NNIK_NN_CY); the unit vector in Q14 from one division; m = 0: no output. */
#include "nnik_servo_config.h"

#ifdef NNIK_CTL_NN_VECTOR
#include "nnik_ctl_nn.h"

uint16_t nnik_ctl_sum = NNIK_NN_SUM_INIT; /* the weights' checksum after the last tick (or reset) */

static nnik_nn_t nnik_nnv_net = {nnik_nn_w1, nnik_nn_w2, {0}, {0}, 0, 0};
static int32_t nnik_nnv_m1, nnik_nnv_m2;
static uint8_t nnik_nnv_primed, nnik_nnv_phase;

void nnik_ctl_reset(void)
{
    nnik_nn_load(&nnik_nnv_net);
    nnik_ctl_sum = NNIK_NN_SUM_INIT;
    nnik_nnv_primed = 0;
    nnik_nnv_phase = 0;
}

/* t * t (unsigned) and e * b (signed by unsigned), 16 x 16 -> 32: on the AVR inline products
 * (libgcc's are calls); the same values everywhere */
#if defined(__GNUC__) && defined(__AVR__)
static inline __attribute__((always_inline)) uint32_t nnik_nnv_sq(uint16_t t)
{
    uint32_t p;
    uint8_t z;
    __asm__("clr %[z]\n\tmul %B[t], %B[t]\n\tmovw %C[p], r0\n\tmul %A[t], %A[t]\n\tmovw %A[p], r0\n\t"
            "mul %A[t], %B[t]\n\tadd %B[p], r0\n\tadc %C[p], r1\n\tadc %D[p], %[z]\n\t"
            "add %B[p], r0\n\tadc %C[p], r1\n\tadc %D[p], %[z]\n\tclr __zero_reg__"
            : [p] "=&r"(p), [z] "=&r"(z)
            : [t] "r"(t));
    return p;
}

static inline __attribute__((always_inline)) int32_t nnik_nnv_mulsu(int16_t e, uint16_t b)
{
    int32_t p;
    uint8_t z;
    __asm__("clr %[z]\n\tmulsu %B[e], %B[b]\n\tmovw %C[p], r0\n\tmul %A[e], %A[b]\n\tmovw %A[p], r0\n\t"
            "mulsu %B[e], %A[b]\n\tsbc %D[p], %[z]\n\tadd %B[p], r0\n\tadc %C[p], r1\n\tadc %D[p], %[z]\n\t"
            "mul %B[b], %A[e]\n\tadd %B[p], r0\n\tadc %C[p], r1\n\tadc %D[p], %[z]\n\tclr __zero_reg__"
            : [p] "=&r"(p), [z] "=&r"(z)
            : [e] "a"(e), [b] "a"(b));
    return p;
}
#else
static uint32_t nnik_nnv_sq(uint16_t t)
{
    return (uint32_t)t * t;
}

static int32_t nnik_nnv_mulsu(int16_t e, uint16_t b)
{
    return (int32_t)e * (int32_t)b;
}
#endif

/* floor(sqrt(v)) for v < 2^31 (nnik_isqrt32's value), the root's bits from the top: its high byte
 * from v's top half by 8 x 8 squares, its low byte by 16 x 16 squares (8 steps each, no loop over
 * 32-bit shifts) */
static uint16_t nnik_nnv_isqrt(uint32_t v)
{
    uint16_t top = (uint16_t)(v >> 16), t;
    uint8_t hi = 0, lo = 0, bit;
    for (bit = 0x80; bit; bit >>= 1) {
        uint8_t h = (uint8_t)(hi | bit);
        if ((uint16_t)((uint16_t)h * h) <= top)
            hi = h;
    }
    for (bit = 0x80; bit; bit >>= 1) {
        t = (uint16_t)(((uint16_t)hi << 8) | (uint8_t)(lo | bit));
        if (nnik_nnv_sq(t) <= v)
            lo = (uint8_t)(lo | bit);
    }
    return (uint16_t)(((uint16_t)hi << 8) | lo);
}

/* 2^30 / m for m >= 1 (restoring division: the dividend's bits below its top one are zeros, so
 * each step doubles the remainder r < m and takes m off when it can).  On the AVR an inline loop on
 * a remainder of one byte (m < 256) or two (m >= 256: the first 7 steps leave r = 128 < m, quotient
 * bits 0), the quotient's bits shifted in inverted (the carry of the compare) and complemented
 * after (libgcc's 32-bit division: about 1.5x the cycles).  The same value everywhere. */
#if defined(__GNUC__) && defined(__AVR__)
/* the loop: STEP doubles the remainder R and takes the divisor M off when it can (label 3 when not) */
#define NNIK_NNV_DIV(STEP, R, M)                                                                    \
    __asm__(STEP "clc\n3:\n\trol %A[q]\n\trol %B[q]\n\trol %C[q]\n\trol %D[q]\n\tdec %[n]\n\tbrne 1b\n\t"         \
            "com %A[q]\n\tcom %B[q]\n\tcom %C[q]\n\tcom %D[q]"                                            \
            : [q] "+r"(q), [r] "+r"(R), [n] "+r"(n)                                                  \
            : [m] "r"(M))
static uint32_t nnik_nnv_inv(uint16_t m)
{
    uint32_t q = 0xFFFFFFFFUL;
    uint16_t r;
    uint8_t n, r8, m8 = (uint8_t)m;
    if (m == 1)
        return 1UL << 30;
    if (m < 256) {
        r8 = 1;
        n = 30;
        NNIK_NNV_DIV("1:\n\tlsl %[r]\n\tbrcs 2f\n\tcp %[r], %[m]\n\tbrcs 3f\n2:\n\tsub %[r], %[m]\n\t", r8, m8);
    } else {
        r = 128;
        n = 23;
        NNIK_NNV_DIV("1:\n\tlsl %A[r]\n\trol %B[r]\n\tbrcs 2f\n\tcp %A[r], %A[m]\n\tcpc %B[r], %B[m]\n\tbrcs 3f\n"
                     "2:\n\tsub %A[r], %A[m]\n\tsbc %B[r], %B[m]\n\t",
                     r, m);
    }
    return q;
}
#else
static uint32_t nnik_nnv_inv(uint16_t m)
{
    return (1UL << 30) / m;
}
#endif

static int16_t nnik_nnv_split(int16_t u, int16_t e, int32_t inv, int16_t c)
{
    /* unit = (e inv + 2^15) >> 16 (Q14, |e| <= m) by the halves of inv (0 .. 2^30): e (inv >> 16) +
     * the rounded top half of e (inv & 0xFFFF), mod 2^16 (unsigned: no overflow) */
    int16_t unit = (int16_t)(uint16_t)((uint16_t)e * (uint16_t)(inv >> 16) +
                                       (uint16_t)((nnik_nnv_mulsu(e, (uint16_t)inv) + (1L << 15)) >> 16));
    int16_t t = (int16_t)nnik_nn_asr(nnik_nn_mac(1L << 10, u, unit), 11); /* Q3 duty */
    return nnik_ctl_duty(nnik_nn_asr(nnik_nn_mac(0, t, c), 3));
}

void nnik_ctl_tick(const int32_t ref[2], const int32_t pos[2], int16_t duty[2])
{
    int16_t ex = nnik_ctl_s16(ref[0] - pos[0]), ey = nnik_ctl_s16(ref[1] - pos[1]), x[NNIK_NN_IN];
    int16_t rx = nnik_ctl_s16(ref[0] >> NNIK_NN_R_SHIFT), ry = nnik_ctl_s16(ref[1] >> NNIK_NN_R_SHIFT), lo;
    int32_t m, m1, m2, r;
    m = (int32_t)nnik_nnv_isqrt((uint32_t)nnik_nn_mac(0, ex, ex) + (uint32_t)nnik_nn_mac(0, ey, ey));
    rx = rx < 0 ? (int16_t)-rx : rx; /* |R|: max + 3/8 min (s16 saturates at -32767: no overflow) */
    ry = ry < 0 ? (int16_t)-ry : ry;
    if (rx < ry) {
        lo = rx;
        rx = ry;
    } else {
        lo = ry;
    }
    r = (int32_t)rx + ((3 * (int32_t)lo) >> 3);
    m1 = nnik_nnv_primed ? nnik_nnv_m1 : m;
    m2 = nnik_nnv_primed ? nnik_nnv_m2 : m1;
    x[0] = NNIK_NN_SCALE(m, NNIK_NN_IN_SHIFT_0);
    x[1] = NNIK_NN_SCALE(m - m1, NNIK_NN_IN_SHIFT_1);
    x[2] = NNIK_NN_SCALE(m - 2 * m1 + m2, NNIK_NN_IN_SHIFT_2);
    x[3] = NNIK_NN_SCALE(r, NNIK_NN_IN_SHIFT_3);
    nnik_nnv_m2 = m1;
    nnik_nnv_m1 = m;
    nnik_ctl_sum = 0;
    nnik_nnv_net.u = nnik_ctl_duty(nnik_nn_step(&nnik_nnv_net, x, x[0], nnik_nnv_phase, &nnik_ctl_sum));
    nnik_nnv_primed = 1;
    nnik_nnv_phase = (uint8_t)((nnik_nnv_phase + 1) & (NNIK_NN_W1_EVERY - 1));
    if (m == 0) {
        duty[0] = 0;
        duty[1] = 0;
    } else {
        int32_t inv = (int32_t)nnik_nnv_inv((uint16_t)m);
        duty[0] = nnik_nnv_split(nnik_nnv_net.u, ex, inv, NNIK_NN_CX);
        duty[1] = nnik_nnv_split(nnik_nnv_net.u, ey, inv, NNIK_NN_CY);
    }
}
#else
typedef int nnik_ctl_nn_vector_unused; /* not this build's controller */
#endif
