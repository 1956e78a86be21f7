/*
 * nnik_plan.c - the planner's blocks: a block's length, unit vector, limits, its junction with the
 * block before and the backward pass (once a block; the sampler is nnik_plan_sample.c).  See
 * nnik_plan.h for the planner's rules and roundings; the narrower arithmetic paths below give the
 * same values as the wide ones (cheaper on AVR), nothing else.
 */
#include "nnik_plan.h"
#include "nnik_imath.h"

#if NNIK_PL_N < 2 || NNIK_PL_N > 64
#error "NNIK_PL_N must be 2..64"
#endif

#define IDX(pl, k) NNIK_PL_IDX(pl, k)
#define Q30 (1L << 30)

static uint32_t uabs32(int32_t v) { return v < 0 ? (uint32_t)0 - (uint32_t)v : (uint32_t)v; }

/* a * b = (the result) 2^32 + *lo (libgcc's 32 x 32 -> 64 product, linked anyway: small and as
 * fast as 16-bit pieces; one function, so each call site stays small) */
#ifdef __GNUC__
__attribute__((noinline))
#endif
static uint32_t mul32(uint32_t a, uint32_t b, uint32_t *lo)
{
#if defined(__GNUC__) && defined(__AVR__)
    union { /* AVR is little-endian: w[1] is p >> 32, by byte moves (avr-gcc calls a shift loop) */
        uint64_t p;
        uint32_t w[2];
    } v;
    v.p = (uint64_t)a * b;
    *lo = v.w[0];
    return v.w[1];
#else
    uint64_t p = (uint64_t)a * b;
    *lo = (uint32_t)p;
    return (uint32_t)(p >> 32);
#endif
}

/* floor(a * L / n), n > 0, at most 2^32 - 1 (an axis' limit on the block's acceleration) */
#ifdef __GNUC__
__attribute__((noinline))
#endif
static uint32_t acc_axis(uint32_t a, uint32_t L, uint32_t n)
{
    uint32_t hi, lo;
    hi = mul32(a, L, &lo);
    return hi >= n ? 0xFFFFFFFFUL : nnik_div64_32(hi, lo, n); /* hi >= n: a quotient >= 2^32 */
}

void nnik_pl_init(nnik_plan_t *pl, const int32_t p[2])
{
    pl->head = pl->count = 0;
    pl->start[0] = pl->last[0] = p[0];
    pl->start[1] = pl->last[1] = p[1];
    pl->r_um = 0;
    pl->r_fr = 0;
    pl->v = 0;
    pl->feed = -1;
    pl->feed_vn = 0;
}

uint8_t nnik_pl_ready(const nnik_plan_t *pl, uint8_t flushing)
{
    return pl->count == NNIK_PL_N || (flushing && pl->count);
}

/* min(a * b, 2^32 - 1) */
static uint32_t mul_sat(uint32_t a, uint32_t b)
{
    uint32_t lo;
    return mul32(a, b, &lo) ? 0xFFFFFFFFUL : lo;
}

/* min(floor(a * b / 2^16), 2^32 - 1) */
static uint32_t mul_sh16_sat(uint32_t a, uint32_t b)
{
    uint32_t lo, hi = mul32(a, b, &lo);
    return hi >> 16 ? 0xFFFFFFFFUL : (hi << 16) | (lo >> 16);
}

/* v << e and v >> e (e < 32), a byte at a time first: the same value, not an e-step loop */
#ifdef __GNUC__
__attribute__((noinline)) /* one copy each: flash */
#endif
static uint32_t shl_bytes(uint32_t v, uint8_t e)
{
    for (; e >= 8; e -= 8)
        v <<= 8;
    return v << e;
}

#ifdef __GNUC__
__attribute__((noinline)) /* one copy each: flash */
#endif
static uint32_t shr_bytes(uint32_t v, uint8_t e)
{
    for (; e >= 8; e -= 8)
        v >>= 8;
    return v >> e;
}

/* floor((a0 b0 + a1 b1) / 2^30) of unit vectors (|a|, |b| <= 2^30: |the sum| <= 2^60).  On AVR
 * from the sum's words s = hi 2^32 + lo: floor(s / 2^30) = 4 hi + (lo >> 30) exactly (|hi| <=
 * 2^28: no overflow), not by libgcc's 64-bit shift (a 30-step loop over 8 bytes). */
static int32_t q30_dot(const int32_t a[2], const int32_t b[2])
{
    int64_t s = (int64_t)a[0] * b[0] + (int64_t)a[1] * b[1];
#if defined(__GNUC__) && defined(__AVR__)
    union { /* little-endian */
        int64_t s;
        uint32_t w[2];
    } v;
    v.s = s;
    return (int32_t)v.w[1] * 4 + (int32_t)((uint8_t)(v.w[0] >> 24) >> 6);
#else
    return (int32_t)(s >> 30);
#endif
}

/* the square of the junction's speed limit between blocks a and b (b follows a), Q16, before the
 * feeds' cap (2^32 - 1: straight on); see nnik_plan.h */
static uint32_t junction2(const nnik_pl_block_t *a, const nnik_pl_block_t *b)
{
    int32_t dot = q30_dot(a->u, b->u) - NNIK_PL_DOT_MARGIN;
    uint32_t sn, r, hi[2], wl, w2, aj;
    uint8_t k = 0, e;
    if (dot <= -Q30 + NNIK_PL_REVERSAL)
        return 0; /* a reversal: stop */
    if (dot >= Q30 - NNIK_PL_REVERSAL)
        return 0xFFFFFFFFUL; /* straight on: the feeds' */
    sn = nnik_isqrt32((uint32_t)(Q30 + dot) << 1); /* sin(theta / 2), Q16 */
    hi[0] = uabs32(b->u[0] - a->u[0]) + 4; /* |w_i| + 4 >= the exact w = u2 - u1's (|u| <= 2^30: no overflow) */
    hi[1] = uabs32(b->u[1] - a->u[1]) + 4;
    for (; (hi[0] | hi[1]) >= 0x800000UL; k += 8) { /* 8 halvings at once, by a byte move: ceil(ceil(x / 2) / 2)
                                                   * = ceil(x / 4), and while the larger is >= 2^23 the loop
                                                   * below would run 8 steps at least (it stays >= 2^16) */
        hi[0] = (hi[0] + 255) >> 8;
        hi[1] = (hi[1] + 255) >> 8;
    }
    for (; (hi[0] | hi[1]) >= 0x8000UL; k++) { /* to 15 bits, halving, rounded up */
        hi[0] = (hi[0] + 1) >> 1;
        hi[1] = (hi[1] + 1) >> 1;
    }
    /* each hi_i is at most the exact |w_i| 2^-k + 9: |hi| - 13 <= |w| 2^-k */
    w2 = nnik_mul16((uint16_t)hi[0], (uint16_t)hi[0]) + nnik_mul16((uint16_t)hi[1], (uint16_t)hi[1]);
    wl = nnik_isqrt32(w2);
    wl = wl > 13 ? wl - 13 : 0;
    /* the junction's acceleration: the axis limit along w, min_i a_i |w| / |w_i|, on the axis
     * that binds (a_x hi_y < a_y hi_x: x) */
#if NNIK_GC_ACC_X == NNIK_GC_ACC_Y
    aj = acc_axis(NNIK_GC_ACC_X, wl, hi[0] > hi[1] ? hi[0] : hi[1]);
#else
    {
        uint32_t xl, yl, xh = mul32(NNIK_GC_ACC_X, hi[1], &xl), yh = mul32(NNIK_GC_ACC_Y, hi[0], &yl);
        uint8_t i = xh > yh || (xh == yh && xl > yl);
        aj = acc_axis(i ? NNIK_GC_ACC_Y : NNIK_GC_ACC_X, wl, hi[i]);
    }
#endif
    if (aj > 0x7FFFFFUL)
        aj = 0x7FFFFFUL;
    /* r = sin / (1 - sin) = 4 sin (1 + sin) / |w|^2, Q16: floor(S 2^14 / w2) 2^(32 - 2k), S = sin (1 + sin)
     * Q32 (33 bits: sh 2^32 + sl; w2 >= 2^28 when k > 0: the quotient holds 16 bits or more); at most 2^31 - 1 */
    {
        uint32_t sl = (sn << 16) + nnik_mul16((uint16_t)sn, (uint16_t)sn), t = sl >> 16, l = sl << 16;
        uint8_t sh = sl < (sn << 16);
        /* S 2^14 = r 2^32 + (sl << 14): sl >> 18 = (sl >> 16) >> 2 and sl << 14 = ((sl << 16) >> 2)
         * with sl's bits 16, 17 on top, by byte moves first (avr-gcc -Os shifts by 14 or 18 in a
         * loop; the empty asm keeps the byte moves apart) */
        NNIK_KEEP16(t);
        NNIK_KEEP16(l);
        r = (sh ? 0x4000UL : 0) | (t >> 2);
        l = (l >> 2) | ((uint32_t)(uint8_t)((uint8_t)t << 6) << 24);
        r = nnik_div64_32(r, l, w2); /* r < 2^15 < w2: past the straight-on test |w| > 2^20 (Q30), k >= 6 */
        if (k < 16) {
            e = (uint8_t)(32 - 2 * k);
            r = r > shr_bytes(0x7FFFFFFFUL, e) ? 0x7FFFFFFFUL : shl_bytes(r, e);
        } else
            r = shr_bytes(r, (uint8_t)(2 * k - 32));
    }
    return mul_sh16_sat(mul_sat(aj, NNIK_GC_JDEV_UM), r);
}

/* the junction's speed limit between blocks a and b (b follows a): floor(sqrt(j2 2^16)) of its
 * square j2 (Q16), see nnik_plan.h */
static uint32_t junction(const nnik_pl_block_t *a, const nnik_pl_block_t *b)
{
    uint32_t lim = a->vn < b->vn ? a->vn : b->vn, j2 = junction2(a, b);
    if (j2 == 0xFFFFFFFFUL)
        return lim;
    j2 = nnik_isqrt_hl(j2 >> 16, j2 << 16);
    return j2 < lim ? j2 : lim;
}

/* The acceleration the backward pass brakes by over block k + 1: the least of its own and of
 * every block a sample may start in and land in it from (block k, and each block m before it
 * while the whole um of the blocks between are at most max(vn_m, acc_m) >> 16: a sample of m
 * travels at most max(vn_m, acc_m), and must travel farther than the blocks between).
 *
 * Why the sampler then never passes a junction above its limit (the defect this fixes: braking by
 * block k + 1's own acc, a sample that passes the junction at the exit could land up to its own
 * travel into block k + 1, above the braking curve there when acc_{k+1} > acc_k; the next samples,
 * braking by acc_{k+1}, then passed its end above its exit).  On the path position y, let F(y) =
 * e^2 + 2 acc (distance to the block's end) in the block y lies in (e its exit): the square of
 * the speed from which the block can still brake, and al = NNIK_PL_ALPHA, at most half of every
 * block's acc (MachineConfig.brake_alpha_q16).  Every speed the sampler accepts by can_go()
 * toward a junction satisfies (c - al)^2 <= F(y) where it lands (c - al <= e, or the brake test,
 * which gives (c - al)^2 - e^2 <= 2 acc R with R the exact distance left: ceil and floor there
 * only tighten it), and passes its junctions at most at their limits.  The fallback c' = c - a
 * (a: the head block's acc, a sample from y to y' = y + c') keeps it:  (c' - al)^2 =
 * (c - al)^2 - 2 a c' - a (a - 2 al) <= F(y) - 2 a (y' - y).  The backward pass gives
 * exit_i^2 <= exit_{i+1}^2 + 2 a_i' L_{i+1} with a_i' <= a for every block
 * the sample can start in (this function), so, summing over the blocks between, F(y) - F(y')
 * <= 2 a (y' - y) (where the landing block's acc exceeds a, its own F falls slower than by a
 * from a height at least 2 (acc - a) L above the bound) and F(y) - 2 a (J - y) <= exit^2 at each
 * junction J it passes: (c' - al)^2 <= F(y') and c' <= exit + al <= jmax there (the backward
 * pass caps each exit at jmax - al).  With al = 0 this is the continuous rule (a margin of a^2);
 * al = a / 2 is the staircase's exact credit, the float planner's mean speed over a sample that
 * starts on its braking curve.  Toward a stop the test counts the sampler's own steps
 * (c - acc / 2).  The floor (acc >> 2) only acts when c < a + floor: toward a stop the sample
 * lands exactly on the end; else it passes its own block's end at most at the exit (the backward
 * pass makes exits under the floor stops).
 * (Not covered: a floor-speed sample that lands past a junction into a block of less than half
 * its acc may sit above F there by one step of that block's acc.)  Exits only rise as blocks
 * arrive and as blocks leave the queue (a only rises), so F only rises: an accepted state
 * stays safe.  Every candidate is within acc of v: each speed change is within its limit. */
static uint32_t brake_acc(const nnik_plan_t *pl, uint8_t k, uint32_t a)
{
    uint8_t i = IDX(pl, k);
    const nnik_pl_block_t *b = &pl->q[i];
    uint16_t gap = 0; /* whole um: at most the lengths between, so never too few blocks */
    for (;;) {
        if (b->acc < a)
            a = b->acc;
        if (!k-- || b->len >= 256) /* a block of 256 um or more: beyond a sample's travel (< 2^24) */
            return a;
        gap += (uint8_t)b->len;
        i = (uint8_t)((i ? i : NNIK_PL_N) - 1);
        b = &pl->q[i];
        if (gap > (uint8_t)(b->vn >> 16) && gap > (uint8_t)(b->acc >> 16)) /* speeds < 2^24 */
            return a;
    }
}

/* exit speeds from the last block back; stops where an exit does not change */
static void backward(nnik_plan_t *pl)
{
    int8_t k;
    pl->q[IDX(pl, pl->count - 1)].exit = 0;
    for (k = (int8_t)pl->count - 2; k >= 0; k--) {
        nnik_pl_block_t *b = &pl->q[IDX(pl, k)];
        const nnik_pl_block_t *n = &pl->q[IDX(pl, k + 1)];
        uint32_t a = brake_acc(pl, (uint8_t)k, n->acc);
        uint64_t t = (uint64_t)a * n->len + (((uint64_t)a * n->lfr) >> 16), e2;
        uint32_t ex = b->jmax > NNIK_PL_ALPHA ? b->jmax - NNIK_PL_ALPHA : 0; /* crossed at most alpha above */
        if (t < (1ULL << 40)) {
            e2 = (uint64_t)n->exit * n->exit + (t << 17);
            if ((uint64_t)ex * ex > e2)
                ex = nnik_isqrt64(e2);
        }
        if (ex < (b->acc >> 2))
            ex = 0; /* below the sampler's floor: a stop */
        if (ex == b->exit)
            return;
        b->exit = ex;
    }
}

#if NNIK_GC_MOTOR
/* one motor's n = ceil((|cx dx + cy dy| + d Lc / 2^f) 2^f / 2^15), the row's Q15 coefficients
 * and margin d (nnik/machine/motor_limits.py): n / Lq >= (|J0 . u| + delta) / s, at most
 * sqrt(2) (1 + 2^-14) Lc < 2^32 (max(|cx|, |cy|) + d <= 2^15 + 2); ax, ay = |dx|, |dy| 2^f */
#ifdef __GNUC__
__attribute__((noinline))
#endif
static uint32_t motor_n(int32_t cx, int32_t cy, uint32_t d, int32_t dx, int32_t dy, uint32_t ax, uint32_t ay,
                        uint32_t Lc)
{
    int64_t s = (int64_t)((dx < 0) ? -cx : cx) * ax + (int64_t)((dy < 0) ? -cy : cy) * ay;
    return (uint32_t)(((uint64_t)(s < 0 ? -s : s) + (uint64_t)d * Lc + 0x7FFF) >> 15);
}

/* the motor limits after the IK: per motor, b->vn <= V Lq / n and acc <= A Lq / n (acc_axis: floor),
 * and b->vn <= NNIK_GC_MOTOR_VC (the head's cap of a nonlinear IK; 0: none); returns the acc */
static uint32_t motor_caps(nnik_pl_block_t *b, uint32_t acc, int32_t dx, int32_t dy, uint32_t ax, uint32_t ay,
                           uint32_t Lq, uint32_t Lc)
{
    uint32_t n[2], cap;
    uint8_t i;
    n[0] = motor_n(NNIK_GC_M0_CX, NNIK_GC_M0_CY, NNIK_GC_M0_D, dx, dy, ax, ay, Lc);
    n[1] = motor_n(NNIK_GC_M1_CX, NNIK_GC_M1_CY, NNIK_GC_M1_D, dx, dy, ax, ay, Lc);
    for (i = 0; i < 2; i++) {
        if (!n[i])
            continue;
#if NNIK_GC_MOTOR_V
        cap = acc_axis(i ? NNIK_GC_M1_V : NNIK_GC_M0_V, Lq, n[i]);
        if (cap < b->vn)
            b->vn = cap;
#endif
#if NNIK_GC_MOTOR_A
        cap = acc_axis(i ? NNIK_GC_M1_A : NNIK_GC_M0_A, Lq, n[i]);
        if (cap < acc)
            acc = cap;
#endif
    }
#if NNIK_GC_MOTOR_VC
    if (b->vn > NNIK_GC_MOTOR_VC)
        b->vn = NNIK_GC_MOTOR_VC;
#endif
    (void)cap;
    return acc;
}
#endif

void nnik_pl_push(nnik_plan_t *pl, int32_t x, int32_t y, int32_t feed, uint16_t tool)
{
    int32_t dx = x - pl->last[0], dy = y - pl->last[1];
    uint32_t ax = uabs32(dx), ay = uabs32(dy), Lq, Lc, acc;
    uint32_t m;
    uint8_t f = 0;
    nnik_pl_block_t *b;
    if (!dx && !dy)
        return;
    { /* m = n 4^f in [2^60, 2^62): sqrt(n) 2^f to 31 bits; f from n's bit length; the components
       * shifted by f, then squared: the same m */
        uint32_t lo, top = 0, l2;
        uint8_t bits = 0;
        if ((ax | ay) < 0x8000UL) /* n < 2^31: by 16 x 16 -> 32 products (the same n) */
            lo = nnik_mul16((uint16_t)ax, (uint16_t)ax) + nnik_mul16((uint16_t)ay, (uint16_t)ay);
        else {
            top = mul32(ax, ax, &lo);
            top += mul32(ay, ay, &l2);
            lo += l2;
            top += lo < l2;
        }
        if (top)
            bits = 32;
        else
            top = lo;
        while (top >> 8) { /* the bit length, a byte at a time first (the same count) */
            top >>= 8;
            bits += 8;
        }
        while (top) {
            top >>= 1;
            bits++;
        }
        if (bits < 61)
            f = (uint8_t)((62 - bits) >> 1);
        ax = shl_bytes(ax, f);
        ay = shl_bytes(ay, f);
        top = mul32(ax, ax, &lo);
        top += mul32(ay, ay, &l2);
        lo += l2;
        top += lo < l2;
        Lq = nnik_isqrt_hl(top, lo);
        l2 = mul32(Lq, Lq, &m);
        Lc = Lq + (l2 != top || m != lo); /* >= sqrt(n) 2^f: |u| <= 1 */
    }
    b = &pl->q[IDX(pl, pl->count)];
    b->end[0] = x;
    b->end[1] = y;
    b->len = shr_bytes(Lq, f);
    b->lfr = (uint16_t)(f >= 16 ? shr_bytes(Lq, (uint8_t)(f - 16)) : shl_bytes(Lq, (uint8_t)(16 - f)));
    /* (|d| 2^f 2^30) / Lc, |d| 2^f <= Lc; ax << 30 (mod 2^32) is ax's low 2 bits on top, by a
     * byte (avr-gcc -Os shifts by 30 in a 30-step loop) */
    b->u[0] = (int32_t)nnik_div64_32(ax >> 2, (uint32_t)(uint8_t)((uint8_t)ax << 6) << 24, Lc);
    b->u[1] = (int32_t)nnik_div64_32(ay >> 2, (uint32_t)(uint8_t)((uint8_t)ay << 6) << 24, Lc);
    if (dx < 0)
        b->u[0] = -b->u[0];
    if (dy < 0)
        b->u[1] = -b->u[1];
    if (feed > NNIK_GC_MAX_FEED_UM_MIN)
        feed = NNIK_GC_MAX_FEED_UM_MIN;
    if (feed != pl->feed) {
        pl->feed = feed;
        pl->feed_vn = (uint32_t)(((uint64_t)(uint32_t)feed << 16) / (60UL * NNIK_GC_SAMPLE_HZ));
    }
    b->vn = pl->feed_vn;
#if NNIK_GC_ACC_X == NNIK_GC_ACC_Y
    acc = acc_axis(NNIK_GC_ACC_X, Lq, ax >= ay ? ax : ay);
#else
    {
        uint32_t xl, yl, xh = mul32(NNIK_GC_ACC_X, ay, &xl), yh = mul32(NNIK_GC_ACC_Y, ax, &yl);
        acc = (xh < yh || (xh == yh && xl <= yl)) ? acc_axis(NNIK_GC_ACC_X, Lq, ax) : acc_axis(NNIK_GC_ACC_Y, Lq, ay);
    }
#endif
#if NNIK_GC_MOTOR
    acc = motor_caps(b, acc, dx, dy, ax, ay, Lq, Lc);
#endif
    b->acc = acc;
    b->dbig = 0xFFFFFFFFUL / (2 * acc); /* acc <= a_axis * sqrt(2) < 2^23: 32-bit division */
    b->tool = tool;
    b->jmax = 0;
    b->exit = 0;
    if (pl->count)
        pl->q[IDX(pl, pl->count - 1)].jmax = junction(&pl->q[IDX(pl, pl->count - 1)], b);
    else { /* the head, from rest at its start */
        pl->r_um = b->len;
        pl->r_fr = b->lfr;
    }
    pl->count++;
    pl->last[0] = x;
    pl->last[1] = y;
    backward(pl);
}
