/* nnik_gc_geom.c - see nnik_gc_geom.h.  Every rounding is spelled out for the Python model. */
#include "nnik_gc_geom.h"
#include "nnik_gcode_config.h"
#include "nnik_gc_block.h"
#include "nnik_imath.h"

#if NNIK_GC_SEG_UM < 100 || NNIK_GC_SEG_UM > 5000
#error "NNIK_GC_SEG_UM must be 100..5000 um"
#endif

#define BEZIER_NMAX 1024

int8_t nnik_gc_r_centre(int32_t x, int32_t y, int32_t rad, uint8_t ccw, int32_t ij[2])
{
    uint64_t d2 = nnik_sq2(x, y), d2s = d2, r2x4;
    uint32_t ra = (uint32_t)nnik_iabs32(rad), s = 0, ds;
    int32_t xs = x, ys = y; /* (x, y) * 2^k: |.| <= d * 2^k < 2^30 */
    if (d2 == 0)
        return -33;
    r2x4 = 4 * (uint64_t)ra * ra;
    if (r2x4 < d2) {
        if (nnik_isqrt64(d2) > 2 * ra + 5 + ra / 1000)
            return -33;
    } else {
        s = nnik_isqrt64(r2x4 - d2);
    }
    while (d2s < (1ULL << 58)) {
        d2s <<= 2;
        xs *= 2;
        ys *= 2;
    }
    ds = nnik_isqrt64(d2s);
    if (ccw != (rad > 0)) {
        xs = -xs;
        ys = -ys;
    }
    ij[0] = nnik_div_round(nnik_mul_r(x, ds) - nnik_mul_r(ys, s), 2 * ds);
    ij[1] = nnik_div_round(nnik_mul_r(y, ds) + nnik_mul_r(xs, s), 2 * ds);
    return 0;
}

void nnik_gc_arc_start(nnik_gc_chords_t *it, int32_t c0, int32_t c1, int32_t e0, int32_t e1, uint32_t r, uint8_t ccw)
{
    it->cur[0] = c0;
    it->cur[1] = c1;
    it->e[0] = e0;
    it->e[1] = e1;
    it->r = r;
    it->ccw = ccw;
    it->top = 0;
    it->last = 0;
    it->bezier = 0;
}

#if NNIK_GC_G5
void nnik_gc_bezier_start(nnik_gc_chords_t *it, const int32_t p0[2], const int32_t c1[2], const int32_t c2[2],
                          const int32_t p3[2])
{
    uint32_t poly, n;
    uint8_t a;
    for (a = 0; a < 2; a++) {
        it->q[a] = p0[a];
        it->d[0][a] = c1[a] - p0[a];
        it->d[1][a] = c2[a] - p0[a];
        it->d[2][a] = p3[a] - p0[a];
    }
    poly = nnik_isqrt64(nnik_sq2(it->d[0][0], it->d[0][1])) + nnik_isqrt64(nnik_sq2(c2[0] - c1[0], c2[1] - c1[1])) +
           nnik_isqrt64(nnik_sq2(p3[0] - c2[0], p3[1] - c2[1]));
    n = (poly + NNIK_GC_SEG_UM - 1) / NNIK_GC_SEG_UM;
    if (n < 1)
        n = 1;
    if (n > BEZIER_NMAX)
        n = BEZIER_NMAX;
    it->n = n;
    it->n3 = n * n * n;
    it->k = 0;
    it->bezier = 1;
}

/* w * d, |d| < 2^30, w < 2^31 */
static int64_t wmul(uint32_t w, int32_t d)
{
    return (int64_t)w * d;
}

static uint8_t bezier_next(nnik_gc_chords_t *it, int32_t out[2])
{
    uint32_t u, w[3], k;
    uint8_t a;
    if (it->k == it->n)
        return 0;
    k = ++it->k;
    u = it->n - k;
    w[0] = 3 * u * u * k; /* each < 4 n^3 / 9 < 2^30 */
    w[1] = 3 * u * k * k;
    w[2] = k * k * k;
    for (a = 0; a < 2; a++)
        out[a] = it->q[a] + nnik_div_round(wmul(w[0], it->d[0][a]) + wmul(w[1], it->d[1][a]) + wmul(w[2], it->d[2][a]),
                                           it->n3);
    return 1;
}
#endif

uint8_t nnik_gc_chords_next(nnik_gc_chords_t *it, int32_t q[2])
{
    const uint64_t seg2 = (uint64_t)NNIK_GC_SEG_UM * NNIK_GC_SEG_UM;
#if NNIK_GC_G5
    if (it->bezier)
        return bezier_next(it, q);
#endif
    if (!it->top) { /* the next quarter turn, or the end's piece */
        int32_t *t = it->stack[0];
        int64_t cross, dot;
        if (it->last)
            return 0;
        cross = (int64_t)it->cur[0] * it->e[1] - (int64_t)it->cur[1] * it->e[0];
        dot = (int64_t)it->cur[0] * it->e[0] + (int64_t)it->cur[1] * it->e[1];
        if (!it->ccw)
            cross = -cross;
        if (cross > 0 && dot >= 0) {
            t[0] = it->e[0];
            t[1] = it->e[1];
            it->last = 1;
        } else {
            t[0] = it->ccw ? -it->cur[1] : it->cur[1];
            t[1] = it->ccw ? it->cur[0] : -it->cur[0];
        }
        it->top = 1;
    }
    for (;;) { /* bisect until the chord from cur is short enough */
        int32_t *b = it->stack[it->top - 1];
        if (nnik_sq2(b[0] - it->cur[0], b[1] - it->cur[1]) <= seg2 || it->top == NNIK_GC_ARC_STACK) {
            it->cur[0] = q[0] = b[0];
            it->cur[1] = q[1] = b[1];
            it->top--;
            return 1;
        } else {
            int32_t mx = it->cur[0] + b[0], my = it->cur[1] + b[1];
            uint32_t m = nnik_isqrt64(nnik_sq2(mx, my));
            it->stack[it->top][0] = nnik_div_round(nnik_mul_r(mx, it->r), m);
            it->stack[it->top][1] = nnik_div_round(nnik_mul_r(my, it->r), m);
            it->top++;
        }
    }
}
