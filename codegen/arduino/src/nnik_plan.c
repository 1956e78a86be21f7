/*
 * nnik_plan.c - see nnik_plan.h for the planner's rules and roundings; the narrower arithmetic
 * paths below give the same values as the wide ones (cheaper on AVR), nothing else.
 */
#include "nnik_plan.h"
#include "nnik_imath.h"

#if NNIK_PL_N < 2 || NNIK_PL_N > 64
#error "NNIK_PL_N must be 2..64"
#endif

#define IDX(pl, k) ((uint8_t)(((pl)->head + (k)) % NNIK_PL_N))
#define Q30 (1L << 30)

static uint32_t uabs32(int32_t v) { return v < 0 ? (uint32_t)0 - (uint32_t)v : (uint32_t)v; }

/* floor(n * 2^30 / L) for 0 <= n <= L */
static uint32_t q30_div(uint32_t n, uint32_t L)
{
    if (L < 0x10000UL) { /* two 32-bit long-division steps: 16 bits, then 14 */
        uint32_t q = (n << 16) / L, r = (n << 16) % L;
        return (q << 14) + (r << 14) / L;
    }
    return (uint32_t)(((uint64_t)n << 30) / L);
}

/* floor(a * L / n), n > 0 (an axis' limit on the block's acceleration) */
static uint32_t acc_axis(uint32_t a, uint32_t L, uint32_t n)
{
    if (L < 0x400UL && a < 0x400000UL) /* a * L < 2^32 */
        return a * L / n;
    {
        uint64_t v = (uint64_t)a * L / n;
        return v > 0xFFFFFFFFUL ? 0xFFFFFFFFUL : (uint32_t)v;
    }
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

/* the junction's speed limit between blocks a and b (b follows a) */
static uint32_t junction(const nnik_pl_block_t *a, const nnik_pl_block_t *b)
{
    int64_t dot = ((int64_t)a->u[0] * b->u[0] + (int64_t)a->u[1] * b->u[1]) >> 30;
    uint32_t lim = a->vn < b->vn ? a->vn : b->vn, sn, r, acc;
    uint64_t vj2;
    if (dot <= -Q30)
        return 0; /* a reversal: stop */
    if (dot > Q30)
        dot = Q30;
    sn = nnik_isqrt64((uint64_t)(Q30 + dot) << 29);
    if (sn >= (uint32_t)Q30)
        r = 0x7FFFFFFFUL;
    else {
        uint64_t t = ((uint64_t)sn << 16) / ((uint32_t)Q30 - sn);
        r = t > 0x7FFFFFFFUL ? 0x7FFFFFFFUL : (uint32_t)t;
    }
    acc = a->acc < b->acc ? a->acc : b->acc;
    vj2 = (uint64_t)acc * NNIK_GC_JDEV_UM * r;
    if (vj2 >= (uint64_t)lim * lim)
        return lim;
    return nnik_isqrt64(vj2);
}

/* exit speeds from the last block back; stops where an exit does not change */
static void backward(nnik_plan_t *pl)
{
    int8_t k;
    pl->q[IDX(pl, pl->count - 1)].exit = 0;
    for (k = (int8_t)pl->count - 2; k >= 0; k--) {
        nnik_pl_block_t *b = &pl->q[IDX(pl, k)];
        const nnik_pl_block_t *n = &pl->q[IDX(pl, k + 1)];
        uint64_t t = (uint64_t)n->acc * n->len, e2;
        uint32_t ex = b->jmax;
        if (t < (1ULL << 40)) {
            e2 = (uint64_t)n->exit * n->exit + (t << 17);
            if ((uint64_t)ex * ex > e2)
                ex = nnik_isqrt64(e2);
        }
        if (ex == b->exit)
            return;
        b->exit = ex;
    }
}

void nnik_pl_push(nnik_plan_t *pl, int32_t x, int32_t y, int32_t feed, uint16_t tool)
{
    int32_t dx = x - pl->last[0], dy = y - pl->last[1];
    uint32_t ax = uabs32(dx), ay = uabs32(dy), L, acc = 0xFFFFFFFFUL, a;
    nnik_pl_block_t *b;
    if (!dx && !dy)
        return;
    L = nnik_isqrt64((uint64_t)ax * ax + (uint64_t)ay * ay);
    b = &pl->q[IDX(pl, pl->count)];
    b->end[0] = x;
    b->end[1] = y;
    b->len = L;
    b->u[0] = (int32_t)q30_div(ax, L);
    b->u[1] = (int32_t)q30_div(ay, L);
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
    if (ax) {
        a = acc_axis(NNIK_GC_ACC_X, L, ax);
        if (a < acc)
            acc = a;
    }
    if (ay) {
        a = acc_axis(NNIK_GC_ACC_Y, L, ay);
        if (a < acc)
            acc = a;
    }
    b->acc = acc;
    b->dbig = 0xFFFFFFFFUL / (2 * acc); /* acc <= a_axis * sqrt(2) < 2^23: 32-bit division */
    b->tool = tool;
    b->jmax = 0;
    b->exit = 0;
    if (pl->count)
        pl->q[IDX(pl, pl->count - 1)].jmax = junction(&pl->q[IDX(pl, pl->count - 1)], b);
    else { /* the head, from rest at its start */
        pl->r_um = L;
        pl->r_fr = 0;
    }
    pl->count++;
    pl->last[0] = x;
    pl->last[1] = y;
    backward(pl);
}

/* after moving c this sample, can the block still brake to its exit speed?  The remaining
 * distance rem = r_um + r_fr / 65536 um; d = floor((rem - c) / 65536) by 32-bit pieces. */
static uint8_t can_brake(uint32_t c, uint32_t r_um, uint16_t r_fr, const nnik_pl_block_t *b)
{
    uint32_t d, cq, eq, ch = c >> 16;
    if (c <= b->exit)
        return 1;
    if ((uint16_t)c > r_fr)
        ch++; /* borrow: d = r_um - ch, rem - c = d * 65536 + (r_fr - c) mod 65536 */
    if (r_um < ch || (r_um == ch && (uint16_t)(r_fr - (uint16_t)c) == 0))
        return 0; /* rem <= c */
    d = r_um - ch;
    if (d > b->dbig) /* 2 acc d > 2^32 - 1 > any 4 ceil(c / 512)^2 */
        return 1;
    cq = (c + 511) >> 9;
    eq = b->exit >> 9;
    return 2 * b->acc * d >= 4 * (cq * cq - eq * eq);
}

/* floor(u * s / 2^30), |u| <= 2^30, s < 2^29, by 16-bit products (no 64-bit arithmetic) */
static int32_t mul_q30(int32_t u, uint32_t s)
{
    uint32_t a = u < 0 ? (uint32_t)0 - (uint32_t)u : (uint32_t)u;
    uint16_t ah = (uint16_t)(a >> 16), al = (uint16_t)a, sh = (uint16_t)(s >> 16), sl = (uint16_t)s;
    uint32_t lo = (uint32_t)al * sl, mid = (uint32_t)ah * sl + (uint32_t)al * sh, hi = (uint32_t)ah * sh;
    uint32_t plo = lo + (mid << 16), q;
    hi += (mid >> 16) + (plo < lo);
    q = (hi << 2) | (plo >> 30);
    if (u >= 0)
        return (int32_t)q;
    return -(int32_t)(q + ((plo & 0x3FFFFFFFUL) != 0));
}

void nnik_pl_sample(nnik_plan_t *pl, nnik_pl_sample_t *out)
{
    nnik_pl_block_t *b = &pl->q[pl->head];
    uint32_t v = pl->v, c, fl, o, ch;
    uint8_t stop = 0;
    if (v < b->vn)
        c = v + b->acc < b->vn ? v + b->acc : b->vn;
    else if (v > b->vn)
        c = (v > b->acc && v - b->acc > b->vn) ? v - b->acc : b->vn;
    else
        c = v;
    if (!can_brake(c, pl->r_um, pl->r_fr, b)) {
        c = v < b->vn ? v : b->vn; /* hold (not at rest: the sample must move) */
        if (!c || !can_brake(c, pl->r_um, pl->r_fr, b)) {
            fl = b->exit;
            if (fl < (b->acc >> 2))
                fl = b->acc >> 2;
            if (fl < 1)
                fl = 1;
            c = v > b->acc ? v - b->acc : 0;
            if (c < fl)
                c = fl;
        }
    }
    out->v = c;
    /* rem -= c; past the end: o = c - rem carries into the next blocks */
    ch = c >> 16;
    if ((uint16_t)c > pl->r_fr)
        ch++;
    if (pl->r_um > ch || (pl->r_um == ch && (uint16_t)(pl->r_fr - (uint16_t)c) != 0)) {
        pl->r_um -= ch;
        pl->r_fr = (uint16_t)(pl->r_fr - (uint16_t)c);
    } else {
        o = c - ((pl->r_um << 16) + pl->r_fr); /* rem <= c < 2^24 here */
        for (;;) {
            pl->start[0] = b->end[0];
            pl->start[1] = b->end[1];
            pl->head = (uint8_t)(pl->head + 1 == NNIK_PL_N ? 0 : pl->head + 1);
            pl->count--;
            if (!b->exit || !pl->count) { /* a stop: exactly on the end, at rest */
                stop = 1;
                c = 0;
                pl->r_um = pl->q[pl->head].len; /* the next block (if any) starts from its start */
                pl->r_fr = 0;
                break;
            }
            b = &pl->q[pl->head];
            if (b->len >= 256 || o < (b->len << 16)) { /* o < 2^24: a block of 256 um or more holds it */
                uint32_t r = (b->len << 16) - o; /* the low 32 bits: r_fr, and r_um by parts */
                pl->r_fr = (uint16_t)r;
                pl->r_um = b->len - (o >> 16) - ((uint16_t)o != 0);
                break;
            }
            o -= b->len << 16;
        }
    }
    pl->v = c;
    out->vn = b->vn;
    out->tool = b->tool;
    if (stop) {
        out->p[0] = b->end[0];
        out->p[1] = b->end[1];
    } else {
        uint32_t s_um = b->len - pl->r_um - (pl->r_fr != 0); /* floor(L - rem) */
        out->p[0] = pl->start[0] + mul_q30(b->u[0], s_um);
        out->p[1] = pl->start[1] + mul_q30(b->u[1], s_um);
    }
}
