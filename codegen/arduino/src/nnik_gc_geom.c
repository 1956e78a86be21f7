/* nnik_gc_geom.c - see nnik_gc_geom.h.  Every rounding is spelled out for the Python model. */
#include "nnik_gc_geom.h"
#include "nnik_gcode_config.h"
#include "nnik_gc_block.h"
#include "nnik_imath.h"

#if NNIK_GC_SEG_UM < 100 || NNIK_GC_SEG_UM > 5000
#error "NNIK_GC_SEG_UM must be 100..5000 um"
#endif

#define ARC_STACK 24 /* a quarter turn of R < 2^28 um needs 23 bisections to 100 um chords */
#define BEZIER_NMAX 1024

static int32_t iabs32(int32_t v) { return v < 0 ? -v : v; }

int8_t nnik_gc_r_centre(int32_t x, int32_t y, int32_t rad, uint8_t ccw, int32_t ij[2])
{
    uint64_t d2 = nnik_sq2(x, y), d2s = d2, r2x4;
    uint32_t ra = (uint32_t)iabs32(rad), s = 0, ds;
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

static void piece(int32_t cur[2], const int32_t end[2], uint32_t r, nnik_gc_point_fn fn, void *ctx)
{
    static int32_t stack[ARC_STACK][2];
    uint8_t top = 1;
    const uint64_t seg2 = (uint64_t)NNIK_GC_SEG_UM * NNIK_GC_SEG_UM;
    stack[0][0] = end[0];
    stack[0][1] = end[1];
    while (top) {
        int32_t *b = stack[top - 1];
        if (nnik_sq2(b[0] - cur[0], b[1] - cur[1]) <= seg2 || top == ARC_STACK) {
            cur[0] = b[0];
            cur[1] = b[1];
            top--;
            fn(ctx, cur);
        } else {
            int32_t mx = cur[0] + b[0], my = cur[1] + b[1];
            uint32_t m = nnik_isqrt64(nnik_sq2(mx, my));
            stack[top][0] = nnik_div_round(nnik_mul_r(mx, r), m);
            stack[top][1] = nnik_div_round(nnik_mul_r(my, r), m);
            top++;
        }
    }
}

void nnik_gc_arc(int32_t c0, int32_t c1, int32_t e0, int32_t e1, uint32_t r, uint8_t ccw, nnik_gc_point_fn fn,
                 void *ctx)
{
    int32_t cur[2], e[2], nxt[2];
    cur[0] = c0;
    cur[1] = c1;
    e[0] = e0;
    e[1] = e1;
    for (;;) {
        int64_t cross = (int64_t)cur[0] * e[1] - (int64_t)cur[1] * e[0];
        int64_t dot = (int64_t)cur[0] * e[0] + (int64_t)cur[1] * e[1];
        if (!ccw)
            cross = -cross;
        if (cross > 0 && dot >= 0) {
            piece(cur, e, r, fn, ctx);
            return;
        }
        nxt[0] = ccw ? -cur[1] : cur[1];
        nxt[1] = ccw ? cur[0] : -cur[0];
        piece(cur, nxt, r, fn, ctx);
    }
}

#if NNIK_GC_G5
/* w * d, |d| < 2^30, w < 2^31 */
static int64_t wmul(uint32_t w, int32_t d)
{
    return (int64_t)w * d;
}

void nnik_gc_bezier(const int32_t p0[2], const int32_t c1[2], const int32_t c2[2], const int32_t p3[2],
                    nnik_gc_point_fn fn, void *ctx)
{
    int32_t d[3][2], q[2];
    uint32_t poly, n, k, n3;
    uint8_t a;
    for (a = 0; a < 2; a++) {
        q[a] = p0[a];
        d[0][a] = c1[a] - p0[a];
        d[1][a] = c2[a] - p0[a];
        d[2][a] = p3[a] - p0[a];
    }
    poly = nnik_isqrt64(nnik_sq2(d[0][0], d[0][1])) + nnik_isqrt64(nnik_sq2(c2[0] - c1[0], c2[1] - c1[1])) +
           nnik_isqrt64(nnik_sq2(p3[0] - c2[0], p3[1] - c2[1]));
    n = (poly + NNIK_GC_SEG_UM - 1) / NNIK_GC_SEG_UM;
    if (n < 1)
        n = 1;
    if (n > BEZIER_NMAX)
        n = BEZIER_NMAX;
    n3 = n * n * n;
    for (k = 1; k <= n; k++) {
        uint32_t u = n - k, w[3];
        int32_t out[2];
        w[0] = 3 * u * u * k; /* each < 4 n^3 / 9 < 2^30 */
        w[1] = 3 * u * k * k;
        w[2] = k * k * k;
        for (a = 0; a < 2; a++)
            out[a] = q[a] + nnik_div_round(wmul(w[0], d[0][a]) + wmul(w[1], d[1][a]) + wmul(w[2], d[2][a]), n3);
        fn(ctx, out);
    }
}
#endif
