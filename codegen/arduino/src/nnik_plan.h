/*
 * nnik_plan.h - the motion planner and the fixed-rate sampler of the G-code firmware.  Portable
 * C99, integer arithmetic only; nnik/firmware/gcode/planner.py repeats it bit for bit.
 *
 * Units.  Positions are whole micrometres in the machine frame less the work origin.  A sample
 * is 1 / NNIK_GC_SAMPLE_HZ s.  Speeds are Q16 micrometres per sample (v = um/sample * 65536),
 * accelerations Q16 micrometres per sample squared, unit vectors Q30.
 *
 * Blocks.  A G-code line is one block, an arc chord is one block.  With n = dx^2 + dy^2 and f the
 * count of 2-bit shifts that brings m = n 4^f into [2^60, 2^62): Lq = isqrt(m) (sqrt(n) 2^f, 31
 * bits), Lc = Lq, plus 1 when Lq^2 != m.  A block holds its end point, its length
 * floor(sqrt(n) 2^16) as len (um) and lfr (Q16 fraction; lfr = Lq >> (f - 16), or Lq << (16 - f)
 * when f < 16), its unit vector u = trunc((|d| 2^f) 2^30 / Lc) per axis with d's sign (so
 * |u| <= 1 and the distance along it is the path's own), its nominal speed
 * vn = floor(min(F, NNIK_GC_MAX_FEED_UM_MIN) * 65536 / (60 * SAMPLE_HZ)) and its acceleration
 * acc = min over the moving axes of floor(a_axis * Lq / (|d_axis| 2^f)) (a_axis / |u_axis|, grbl's
 * block acceleration, rounded down).
 *
 * Lookahead.  The queue holds NNIK_PL_N blocks.  When a block arrives, the junction with the
 * block before it gets its speed limit (grbl 1.1's junction deviation, every rounding downward):
 *     dot = floor((u1x u2x + u1y u2y) / 2^30) - NNIK_PL_DOT_MARGIN (at most the exact cosine: each u
 *     component is within 2 of the exact one); dot <= -2^30 + NNIK_PL_REVERSAL (grbl's cosine
 *     0.999999): a reversal, 0; dot >= 2^30 - NNIK_PL_REVERSAL: straight on, min(vn1, vn2);
 *     else sin(theta/2) = sn = isqrt((2^30 + dot) << 1) (Q16) and, with w = u2 - u1 per axis,
 *     hi_i = |w_i| + 4 halved (rounded up) k times to 15 bits (hi_i >= the exact |w_i| 2^-k),
 *     w2 = hi_x^2 + hi_y^2, wl = isqrt(w2) - 13 (at most the exact |w| 2^-k; 0 if below);
 *     grbl's r = sin / (1 - sin) = 4 sin (1 + sin) / |w|^2 (no cancellation near straight on) as
 *     r = floor(S 2^14 / w2) 2^(32 - 2k) (at most 2^31 - 1; shifted down when k > 16), S = sn (2^16 + sn);
 *     the junction's acceleration (grbl: the axis limit along w) aj = min(min_i floor(a_i wl / hi_i), 2^23 - 1);
 *     j2 = min(floor(min(aj JDEV_UM, 2^32 - 1) r / 2^16), 2^32 - 1) (Q16: um^2 / sample^2 * 65536),
 *     jmax = min(vn1, vn2) when j2 = 2^32 - 1, else min(vn1, vn2, isqrt(j2 2^16)),
 * and a backward pass sets every exit speed: the last block's exit is 0, and going back
 *     exit_i = min(jmax_i - NNIK_PL_ALPHA (0 below), isqrt(exit_{i+1}^2 + (t << 17))), t = a len_{i+1} + (a lfr_{i+1} >> 16),
 * a the least acc of block i + 1 and of the blocks a sample may start in and land in it from
 * (block i, and each block m before it while the whole um (len) of the blocks between sum to at
 * most max(vn_m, acc_m) >> 16; nnik_plan.c brake_acc() proves why) (jmax_i itself when t >= 2^40 or jmax^2 <= the sum); an exit below acc_i >> 2 (the sampler's
 * floor) becomes 0, a stop; the pass stops where an exit does not change.  There is no forward
 * pass: the sampler below never changes speed by more than acc per sample.
 *
 * Determinism.  The sampler runs only on blocks whose exit speed is final: while the queue is
 * full (it runs until the head block has been left behind, then the parser adds the next block)
 * or when the queue is flushed (M400, M2, M30, G4, a tool change, the end of the job: it runs
 * until the last block ends at rest).  What it produces therefore depends only on the order of
 * the blocks and flushes, never on serial timing, and the Python model repeats it exactly.
 *
 * Sampling.  The state is the head block, the distance s along it (Q16 um; rem = its length - s)
 * and the speed v.  Each sample takes up = v + acc (at most vn; above vn: v - acc, at least vn)
 * when it "may go"; else, when hold = min(v, vn) (not 0) may go, the fastest that may go between
 * hold and up, else down = v - acc (0 below acc; or the exit ve when v - acc < ve < v and ve may
 * go) and, when down may go, the fastest between down and hold (up when hold is 0): lo + d for
 * d = (hi - lo) >> 1, halved each time, 4 times, kept where it may go; at least max(acc >> 2, 1).
 * A speed c may go when every block end it reaches (rem <= c, adding the next block's length to
 * rem each time) it passes at most at that junction's limit jmax, or, at a stop's end (exit 0),
 * lands on it: the distance left there, rem (Q16), is at most that block's acc (and v - rem is
 * within acc by the brake test below); and the block it ends in can still brake: x <= ve (c <= acc
 * toward a stop), or with D = rem - c (Q16 um) 2 acc D >= x^2 - ve^2, x = c - NNIK_PL_ALPHA toward
 * a junction (ve > 0: the continuous need, less the credit of the sampler's steps; nnik_plan.c
 * brake_acc() proves it), x = c - floor(acc / 2) toward a stop (the sampler's own steps
 * down, c - acc, c - 2 acc, ..., then the landing: at most (c - acc / 2)^2 / (2 acc)), the right
 * side rounded up as 2^18 (ceil(x / 512)^2 - floor(ve / 512)^2) = 2^18 P (speeds below 2^24, 256 um
 * per sample, so every product fits 32 bits) and D rounded down: with d = floor(D / 65536)
 * (whole um) it passes when d > floor((2^32 - 1) / (2 acc)) (dbig, kept per block), else it needs
 * floor(floor(acc / 32) floor(D / 2048) / 2) >= P (D in 1/32 um: a stop's last samples are not held back).
 * Then s += c; at
 * or past the end of a block with exit 0 the sample lands exactly on its end and v = 0 (a stop);
 * past the end of any other block the remainder carries into the next.  The point is
 * start + ((u * floor(s / 65536)) >> 30) per axis (arithmetic shift: floor), or the end point.
 */
#ifndef NNIK_PLAN_H
#define NNIK_PLAN_H

#include <stdint.h>

#include "nnik_gcode_config.h"

#ifdef __cplusplus
extern "C" {
#endif

#ifndef NNIK_PL_N
#define NNIK_PL_N 8 /* blocks of lookahead */
#endif
#ifndef NNIK_PL_ALPHA
#define NNIK_PL_ALPHA 0UL /* Q16 um/sample^2: the brake test's credit, at most half of every block's acc (MachineConfig.brake_alpha_q16) */
#endif
/* the queue's slot k places after the head (unsigned: no 16-bit division) */
#define NNIK_PL_IDX(pl, k) ((uint8_t)((uint8_t)((pl)->head + (k)) % NNIK_PL_N))
#define NNIK_PL_DOT_MARGIN 8 /* Q30: the unit vectors' dot product less this is at most the exact cosine */
#define NNIK_PL_REVERSAL 1073 /* Q30: a dot product within this of -1 is a reversal (grbl: 0.999999) */

typedef struct {
    int32_t end[2];  /* um */
    int32_t u[2];    /* Q30 */
    uint32_t len;    /* um, floor */
    uint16_t lfr;    /* the length's fraction, Q16 (length = len + lfr / 65536 um, floor) */
    uint32_t vn;     /* nominal speed, Q16 um/sample */
    uint32_t acc;    /* Q16 um/sample^2 */
    uint32_t dbig;   /* floor((2^32 - 1) / (2 acc)): the brake test's product fits 32 bits below it */
    uint32_t jmax;   /* speed limit at the junction with the next block (0: none yet) */
    uint32_t exit;   /* planned exit speed */
    uint16_t tool;   /* the tool word of the block (duty | 0x100 for M4) */
} nnik_pl_block_t;

typedef struct {
    nnik_pl_block_t q[NNIK_PL_N];
    uint8_t head, count;
    int32_t start[2]; /* where the head block starts */
    int32_t last[2];  /* where the last block queued ends */
    uint32_t r_um;    /* distance left in the head block: r_um + r_fr / 65536 um (s = L - that) */
    uint16_t r_fr;
    uint32_t v;       /* speed, Q16 um/sample */
    int32_t feed;     /* the feed whose vn is cached below */
    uint32_t feed_vn;
} nnik_plan_t;

/* One sample: the point, the speed used for it, the nominal speed and tool of its block, and the
 * distance moved along the path (Q16 um: v, or on a stop the distance that was left). */
typedef struct {
    int32_t p[2];
    uint32_t v, vn;
    uint16_t tool;
    uint32_t moved;
} nnik_pl_sample_t;

/* At rest at p (um). */
void nnik_pl_init(nnik_plan_t *pl, const int32_t p[2]);

/* Queue a block to (x, y) at feed (um/min) with its tool word; a block of length 0 is dropped.
 * The queue must not be full (nnik_pl_full). */
void nnik_pl_push(nnik_plan_t *pl, int32_t x, int32_t y, int32_t feed, uint16_t tool);

/* 1 while the head block is final and the sampler may run: the queue is full, or flushing and
 * not empty. */
uint8_t nnik_pl_ready(const nnik_plan_t *pl, uint8_t flushing);

/* One sample (only when nnik_pl_ready); pops the blocks it leaves behind. */
void nnik_pl_sample(nnik_plan_t *pl, nnik_pl_sample_t *out);

#ifdef __cplusplus
}
#endif

#endif /* NNIK_PLAN_H */
