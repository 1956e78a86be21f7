/*
 * nnik_plan_sample.c - the planner's fixed-rate sampler: each sample's speed (the brake test,
 * can_go, and the search between the speeds that may and may not go) and its point.  It runs
 * every sample, so the G-code build compiles it without -mcall-prologues (nnik/firmware/gcode/
 * chip.py HOT_SOURCES); the blocks' planning (nnik_plan.c) keeps the shared register saves.
 * See nnik_plan.h for the rules and roundings.
 */
#include "nnik_plan.h"
#include "nnik_imath.h"

#define IDX(pl, k) NNIK_PL_IDX(pl, k)

/* rem <= c, rem = r_um + r_fr / 65536 um: the sample reaches the block's end */
static uint8_t reaches(uint32_t c, uint32_t r_um, uint16_t r_fr)
{
    uint32_t ch = c >> 16;
    if ((uint16_t)c > r_fr)
        ch++; /* borrow: rem - c = (r_um - ch) * 65536 + (r_fr - c) mod 65536 */
    return r_um < ch || (r_um == ch && (uint16_t)(r_fr - (uint16_t)c) == 0);
}

/* t >> 9 of t < 2^25, by byte moves: no 9-step shift loop */
static uint16_t shr9(uint32_t t)
{
    return (uint16_t)(((uint16_t)(t >> 16) << 7) | ((uint16_t)t >> 9));
}

/* after moving c this sample (rem > c left), can the block still brake to its exit e?  Toward
 * a junction (e > 0) by (x^2 - e^2) / (2 acc) with x = c - NNIK_PL_ALPHA (nnik_plan.c brake_acc()
 * proves it); toward a stop (e = 0: the sampler lands on the end at most at acc, can_go) by its
 * own steps c - acc, c - 2 acc, ..., which need at most (c - acc / 2)^2 / (2 acc) (equal at
 * c = k acc, a convex bound between).  So it can when x <= e (c <= acc toward a stop), or when
 * D = rem - c (Q16 um) holds 2 acc D >= x^2 - e^2 (x = c - floor(acc / 2) toward a stop), rounded
 * up as 2^18 P,
 * P = ceil(x / 512)^2 - floor(e / 512)^2, and D rounded down: it passes when d = floor(D / 65536)
 * (whole um) > dbig, else it needs floor(floor(acc / 32) floor(D / 2048) / 2) >= P. */
static uint8_t can_brake(uint32_t c, uint32_t r_um, uint16_t r_fr, const nnik_pl_block_t *b)
{
    uint32_t d, p, ch = c >> 16, x = c;
    uint16_t cq, eq;
    if (c <= (b->exit ? b->exit + NNIK_PL_ALPHA : b->acc))
        return 1;
    if ((uint16_t)c > r_fr)
        ch++;
    d = r_um - ch;
    if (d > b->dbig) /* 2 acc d > 2^32 - 1 > any 4 P */
        return 1;
    x -= b->exit ? NNIK_PL_ALPHA : b->acc >> 1;
    cq = shr9(x + 511); /* < 2^24: <= 2^15 */
    eq = shr9(b->exit);
    p = nnik_mul16(cq, cq) - nnik_mul16(eq, eq);
    /* floor(acc / 32) floor(D / 2048) <= acc (d + 1) < 2^31 + 2^23 below dbig (and d << 5 wraps
     * only when acc < 32: then the product is 0) */
    return (((b->acc >> 5) * ((d << 5) | ((uint16_t)(r_fr - (uint16_t)c) >> 11))) >> 1) >= p;
}

/* may the sample go at c?  Each block end it reaches it lands on when it is a stop (exit 0) and
 * the distance left to it, rem (Q16, <= c), is at most that block's acc (the step to rest; the
 * step from v to rem is within the head block's acc by the brake test that let v go:
 * (v - acc / 2)^2 / (2 acc) >= v - acc), else passes at most at the junction's limit jmax; and the
 * block it ends in can still brake to its exit. */
static uint8_t can_go(const nnik_plan_t *pl, uint32_t c)
{
    const nnik_pl_block_t *b = &pl->q[pl->head];
    uint32_t r_um = pl->r_um, rem;
    uint16_t r_fr = pl->r_fr;
    uint8_t k = 0;
    while (reaches(c, r_um, r_fr)) {
        rem = (r_um << 16) + r_fr; /* rem <= c < 2^24 */
        if (!b->exit)
            return rem <= b->acc;
        if (c > b->jmax)
            return 0;
        b = &pl->q[IDX(pl, ++k)]; /* exit > 0: b is not the last block */
        rem += b->lfr;
        r_fr = (uint16_t)rem;
        r_um = b->len + (rem >> 16);
    }
    return can_brake(c, r_um, r_fr, b);
}

/* the fastest speed the sampler finds from lo, which may go, toward hi, which may not: lo + d
 * for d = (hi - lo) / 2, then halved each time (floor), 4 times, kept each time it may go: within
 * (hi - lo) / 16 of the fastest when may-go is monotone between them */
static uint32_t fastest(const nnik_plan_t *pl, uint32_t lo, uint32_t hi)
{
    uint32_t d = (hi - lo) >> 1;
    uint8_t k = 4;
    do {
        if (can_go(pl, lo + d))
            lo += d;
        d >>= 1;
    } while (--k && d);
    return lo;
}

/* floor(u * s / 2^30), |u| <= 2^30, s < 2^29 */
#ifdef __GNUC__
__attribute__((always_inline)) /* one call site (the loop over the axes): no call, no register saves */
#endif
static inline int32_t mul_q30(int32_t u, uint32_t s)
{
    uint32_t a = u < 0 ? (uint32_t)0 - (uint32_t)u : (uint32_t)u, plo, hi, q;
#if defined(__GNUC__) && defined(__AVR__) && defined(__AVR_HAVE_MUL__)
    if ((uint16_t)(s >> 16)) { /* 65.536 mm or more along the block (rare): libgcc's 32 x 32 -> 64 */
        union { /* little-endian: the words by byte moves */
            uint64_t p;
            uint32_t w[2];
        } v;
        v.p = (uint64_t)a * s;
        plo = v.w[0];
        hi = v.w[1];
    } else {
        /* a s (s < 2^16) = hi 2^32 + plo (hi < 2^16) by the 8 byte products, column by column
         * (byte k of the product gets every a_i s_j with i + j = k; the three bytes from k up hold
         * the column's sum and carries: the sum of the columns up to k is below 2^(8k + 18), so
         * nothing carries past byte k + 2, and past byte 5 not at all) */
        uint16_t s16 = (uint16_t)s, h16;
        uint8_t z;
        __asm__("clr %A0\n\tclr %B0\n\tclr %C0\n\tclr %D0\n\tclr %A1\n\tclr %B1\n\tclr %2\n\t"
                "mul %A3,%A4\n\tadd %A0,r0\n\tadc %B0,r1\n\tadc %C0,%2\n\t"
                "mul %A3,%B4\n\tadd %B0,r0\n\tadc %C0,r1\n\tadc %D0,%2\n\t"
                "mul %B3,%A4\n\tadd %B0,r0\n\tadc %C0,r1\n\tadc %D0,%2\n\t"
                "mul %B3,%B4\n\tadd %C0,r0\n\tadc %D0,r1\n\tadc %A1,%2\n\t"
                "mul %C3,%A4\n\tadd %C0,r0\n\tadc %D0,r1\n\tadc %A1,%2\n\t"
                "mul %C3,%B4\n\tadd %D0,r0\n\tadc %A1,r1\n\tadc %B1,%2\n\t"
                "mul %D3,%A4\n\tadd %D0,r0\n\tadc %A1,r1\n\tadc %B1,%2\n\t"
                "mul %D3,%B4\n\tadd %A1,r0\n\tadc %B1,r1\n\t"
                "clr __zero_reg__"
                : "=&r"(plo), "=&r"(h16), "=&r"(z)
                : "r"(a), "r"(s16));
        hi = h16;
    }
#else
    {
        uint16_t ah = (uint16_t)(a >> 16), al = (uint16_t)a, sh = (uint16_t)(s >> 16), sl = (uint16_t)s;
        uint32_t lo = nnik_mul16(al, sl), mid = nnik_mul16(ah, sl) + nnik_mul16(al, sh);
        hi = nnik_mul16(ah, sh);
        plo = lo + (mid << 16);
        hi += (mid >> 16) + (plo < lo);
    }
#endif
    q = (hi << 2) | ((uint8_t)(plo >> 24) >> 6); /* plo >> 30 by its top byte: no 30-step shift loop */
    if (u >= 0)
        return (int32_t)q;
    return -(int32_t)(q + ((plo & 0x3FFFFFFFUL) != 0));
}

void nnik_pl_sample(nnik_plan_t *pl, nnik_pl_sample_t *out)
{
    nnik_pl_block_t *b = &pl->q[pl->head];
    uint32_t v = pl->v, c, fl, o, ch, l16;
    uint8_t stop = 0;
    if (v < b->vn)
        c = v + b->acc < b->vn ? v + b->acc : b->vn;
    else if (v > b->vn)
        c = (v > b->acc && v - b->acc > b->vn) ? v - b->acc : b->vn;
    else
        c = v;
    if (!can_go(pl, c)) {
        o = c;                     /* up may not go */
        c = v < b->vn ? v : b->vn; /* hold (not at rest: the sample must move) */
        fl = 0;
        if (!c || c >= o || !can_go(pl, c)) { /* hold may not go either */
            if (c)
                o = c;
            fl = b->acc >> 2; /* the floor, on the way down only */
            if (fl < 1)
                fl = 1;
            c = v > b->acc ? v - b->acc : 0;
            if (c < b->exit && b->exit < v && can_go(pl, b->exit))
                c = b->exit; /* down to the exit if it may go at it */
            if (c && !can_go(pl, c))
                o = c; /* down may not go: no search */
        }
        if (c)
            c = fastest(pl, c, o);
        if (c < fl)
            c = fl;
    }
    out->v = out->moved = c;
    /* rem -= c; past the end: o = c - rem carries into the next blocks */
    if (!reaches(c, pl->r_um, pl->r_fr)) {
        ch = (c >> 16) + ((uint16_t)c > pl->r_fr);
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
                out->moved = out->v - o; /* o: past the end */
                c = 0;
                pl->r_um = pl->q[pl->head].len; /* the next block (if any) starts from its start */
                pl->r_fr = pl->q[pl->head].lfr;
                break;
            }
            b = &pl->q[pl->head];
            l16 = (b->len << 16) | b->lfr; /* its length, Q16 (the low 32 bits) */
            if (b->len >= 256 || o < l16) { /* o < 2^24: a block of 256 um or more holds it */
                pl->r_fr = (uint16_t)(b->lfr - (uint16_t)o); /* rem = length - o, by parts */
                pl->r_um = b->len - (o >> 16) - ((uint16_t)o > b->lfr);
                break;
            }
            o -= l16;
        }
    }
    pl->v = c;
    out->vn = b->vn;
    out->tool = b->tool;
    if (stop) {
        out->p[0] = b->end[0];
        out->p[1] = b->end[1];
    } else {
        uint32_t s_um = b->len - pl->r_um - (pl->r_fr > b->lfr); /* floor(length - rem) */
        uint8_t i;
        for (i = 0; i < 2; i++)
            out->p[i] = pl->start[i] + mul_q30(b->u[i], s_um);
    }
}
