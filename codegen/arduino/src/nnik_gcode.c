/*
 * nnik_gcode.c - see nnik_gcode.h.  The interpreter and the motion it hands to the planner (the
 * engine's start: nnik_gc_init.c; the tool's word: nnik_gc_tool.c; the planner's blocks in and
 * its samples out to the shaper, the IK and the stepper: nnik_gc_segments.c);
 * nnik/firmware/gcode/interpreter.py repeats it bit for bit.  Positions are machine micrometres
 * less the work origin (mp: X, Y and the tool's Z); an absolute target is the value plus the
 * active work offset (G54..G59 by G10), the G92 offset and for Z the tool length offset; G53
 * takes machine values; G91 adds to the position.  Every block end passes the job's frame
 * transform (p * NNIK_GC_SCALE_Q16 / 2^16 + shift, rounded half up) when the build has one.
 */
#include "nnik_gc_block.h"
#include "nnik_gc_geom.h"
#include "nnik_gc_tool.h"
#include "nnik_gcode_config.h"
#include "nnik_imath.h"

#ifndef NNIK_GC_MARLIN
#define NNIK_GC_MARLIN 0
#endif
#ifndef NNIK_GC_M300_DOWN
#define NNIK_GC_M300_DOWN 40000L
#endif

#define POS_LIMIT 268435455L /* 2^28 - 1 um */
#define MIN_FEED 1000L       /* um per minute */
#define DWELL_MS_MAX 16777215L

#if defined(__GNUC__)
#define NOINLINE __attribute__((noinline))
#else
#define NOINLINE
#endif

/* ---------------------------------------------------------------- moves */
NOINLINE static int8_t line_to(nnik_gc_t *g, const int32_t t[3], int32_t feed, uint8_t rapid, uint8_t extrude)
{
    g->mp[2] = t[2];
    g->tool = nnik_gc_move_tool(g, rapid, extrude);
    if (t[0] != g->mp[0] || t[1] != g->mp[1]) {
        int8_t r = nnik_gc_push(g, t, feed);
        if (r)
            return r;
        g->mp[0] = t[0];
        g->mp[1] = t[1];
    }
    return 0;
}

/* an arc's or a curve's chord ends, from exec's static state (pushed from exec's own frame: the
 * planner and the IK below a push need the stack) */
/* a line's words until its motion starts, then its chords: the two never live at once (RAM) */
static union {
    nnik_blk_t blk;
    nnik_gc_chords_t chords;
} scratch;
#define chords (scratch.chords)
static uint8_t ax0, ax1, per_point; /* the arc's plane axes; Z per chord end (G18/G19) */

static void chords_start(nnik_gc_t *g, uint8_t motion, const int32_t c[2], const int32_t c1[2], const int32_t c2[2],
                         const int32_t tgt[3], uint32_t rad)
{
#if NNIK_GC_G5
    if (motion == 5) {
        nnik_gc_bezier_start(&chords, g->mp, c1, c2, tgt);
        return;
    }
#else
    (void)c1;
    (void)c2;
#endif
    nnik_gc_arc_start(&chords, g->mp[ax0] - c[0], g->mp[ax1] - c[1], tgt[ax0] - c[0], tgt[ax1] - c[1], rad, motion == 3);
}

/* the next chord end as a machine point p (X Y Z); 0 at the end */
static uint8_t chord_next(nnik_gc_t *g, uint8_t motion, const int32_t c[2], int32_t p[3])
{
    static int32_t q[2];
    if (!nnik_gc_chords_next(&chords, q))
        return 0;
    p[0] = g->mp[0];
    p[1] = g->mp[1];
    p[2] = g->mp[2];
    if (motion == 5) {
        p[0] = q[0];
        p[1] = q[1];
    } else {
        p[ax0] = c[0] + q[0];
        p[ax1] = c[1] + q[1];
    }
    return 1;
}

#if NNIK_GC_G93
/* G93: the move takes 1/F minutes: feed = length * F (F in thousandths per minute) */
static int32_t inverse_feed(uint32_t length, int32_t inv_f)
{
    uint64_t f = (uint64_t)length * (uint32_t)inv_f / 1000;
    return f < (uint64_t)MIN_FEED ? MIN_FEED : (f > 0x7fffffffUL ? 0x7fffffffL : (int32_t)f);
}
#endif

/* the work offset of axis k in system wcs with the tool length offset tlo: machine = work + it */
NOINLINE static int32_t woff(const nnik_gc_t *g, uint8_t wcs, int32_t tlo, uint8_t k)
{
    return g->coord[wcs][k] + g->g92[k] + (k == 2 ? tlo : 0);
}

/* ---------------------------------------------------------------- the line */
#define V(w) (&b.v[w])
/* letters read in the block's units (inches after G20): lengths and F */
#define LENGTHS ((1U << W_E) | (1U << W_F) | (1U << W_I) | (1U << W_J) | (1U << W_K) | (1U << W_Q) | (1U << W_R) | \
                 (1U << W_X) | (1U << W_Y) | (1U << W_Z))
#define HASW(w) HAS(&b, w)

static const uint8_t PLANE_AXES[3][2] = {{0, 1}, {2, 0}, {1, 2}};

int8_t nnik_gc_exec(nnik_gc_t *g)
{
#define b (scratch.blk) /* static: a small stack frame is far smaller code on AVR (ldd reaches 63 B) */
    int8_t r;
    uint8_t inch, rel, plane, arc_abs, inverse, wcs, motion, nm, k, axes = 0, moving, axis_nm, extrude = 0;
    uint8_t e_rel, e_move, seg_blocks, end_stop, end_wait, end_tool;
    uint16_t used = (1U << W_F) | (1U << W_T) | (1U << W_S);
    static int32_t u[W_COUNT];
    static int32_t tgt[3], c[2], c1[2], c2[2]; /* static: the stack under an arc's chord is deep */
    int32_t feed, inv_f = 0, tlo, e_tgt, dwell_ms = -1;
    uint32_t rad = 0;
    uint32_t blk0;
    static int32_t p[3];

    r = nnik_gc_parse(g->line, &b);
    if (r)
        return r;
    if (b.noted_line)
        return NNIK_GC_OK;
    motion = b.motion == UNSET ? g->motion : b.motion;
    if ((HASW(W_F) && (V(W_F)->nd & NUM_NEG)) || (HASW(W_T) && (V(W_T)->nd & NUM_NEG)) ||
        (HASW(W_S) && (V(W_S)->nd & NUM_NEG)) || (HASW(W_P) && (V(W_P)->nd & NUM_NEG) && (motion != 5 || b.nonmodal != NM_NONE)))
        return -4;
    if (HASW(W_T) && V(W_T)->ip > 255)
        return -38;
    inch = b.inch == UNSET ? g->inch : b.inch;
    for (k = 0; k < W_COUNT; k++) /* every value once: lengths (and F, P of G5) in the block's units */
        if (HASW(k))
            u[k] = nnik_gc_um(V(k), inch && ((1U << k) & LENGTHS));
    rel = b.relative == UNSET ? g->relative : b.relative;
    plane = b.plane == UNSET ? g->plane : b.plane;
    arc_abs = b.arc_abs == UNSET ? g->arc_abs : b.arc_abs;
    inverse = b.inverse == UNSET ? g->inverse_time : b.inverse;
    wcs = b.wcs == UNSET ? g->wcs : b.wcs;
    nm = b.nonmodal;
    if (b.m300 && !HASW(W_S))
        return -28;
    if (b.g64)
        used |= (1U << W_P) | (1U << W_Q);
    for (k = 0; k < 3; k++)
        if (HASW(W_X + k))
            axes |= (uint8_t)(1U << k);
    tlo = g->tlo;
    if (b.tlo == 1) {
        if (!HASW(W_Z))
            return -37;
        tlo = u[W_Z];
        used |= 1U << W_Z;
        axes &= (uint8_t)~4U;
    } else if (b.tlo == 0) {
        tlo = 0;
    } else if (b.tlo == 2) {
        used |= 1U << W_H;
    }
    e_move = NNIK_GC_MARLIN && HASW(W_E) && nm != NM_G92;
    axis_nm = nm == NM_G10 || nm == NM_G28 || nm == NM_G30 || nm == NM_G92;
    if ((axes || e_move) && axis_nm && b.motion != UNSET && b.motion != 80)
        return -24;
    moving = (axes || e_move) && !axis_nm;
    if (moving && motion == 80)
        return -31;
    if ((b.motion == 2 || b.motion == 3) && !axis_nm && !axes) /* an arc written without its end */
        return -32;
    /* feed */
    feed = g->feed;
    if (HASW(W_F)) {
        if (inverse) {
            inv_f = nnik_gc_um(V(W_F), 0);
            if (inv_f < 1)
                return -22;
        } else {
            feed = u[W_F];
            if (feed < MIN_FEED)
                return -22;
        }
    }
    if (inverse && moving && motion != 0 && !HASW(W_F))
        return -22;
    /* targets */
    if (nm == NM_G53 && moving && motion > 1)
        return -30;
    for (k = 0; k < 3; k++) {
        int32_t val;
        tgt[k] = g->mp[k];
        if (!(axes & (1U << k)))
            continue;
        val = u[W_X + k];
        if (nm == NM_G53 || nm == NM_G92 || nm == NM_G10)
            tgt[k] = val;
        else if (rel)
            tgt[k] = g->mp[k] + val;
        else
            tgt[k] = val + woff(g, wcs, tlo, k);
        if (tgt[k] > POS_LIMIT || tgt[k] < -POS_LIMIT)
            return -33;
        used |= (uint16_t)(1U << (W_X + k));
    }
    /* E */
    e_rel = b.e_rel == UNSET ? g->e_rel : b.e_rel;
    if (b.relative != UNSET && b.e_rel == UNSET)
        e_rel = b.relative;
    e_tgt = g->e;
    if (HASW(W_E)) {
        int32_t ev = u[W_E];
        used |= 1U << W_E;
        if (ev > POS_LIMIT || ev < -POS_LIMIT)
            return -33;
        if (nm == NM_G92 || !e_rel) {
            e_tgt = ev;
            extrude = nm != NM_G92 && ev > g->e;
        } else {
            extrude = ev > 0;
        }
    }
    /* checks of the non-modal commands */
    if (nm == NM_G4) {
        if (NNIK_GC_MARLIN && HASW(W_S) && !HASW(W_P)) {
            dwell_ms = u[W_S];
        } else if (HASW(W_P)) {
            dwell_ms = nnik_gc_um(V(W_P), 0);
            if (NNIK_GC_MARLIN)
                dwell_ms = (dwell_ms + 500) / 1000;
        } else if (NNIK_GC_MARLIN) {
            dwell_ms = 0; /* Marlin: G4 alone waits for nothing */
        } else {
            return -28;
        }
        used |= 1U << W_P;
        if (dwell_ms > DWELL_MS_MAX)
            dwell_ms = DWELL_MS_MAX;
    }
#if NNIK_GC_WCS
    if (nm == NM_G10) {
        if (!HASW(W_L) || !HASW(W_P))
            return -28;
        used |= (1U << W_L) | (1U << W_P);
        if ((NUM_ND(V(W_L)) && V(W_L)->fr) || (V(W_L)->ip != 2 && V(W_L)->ip != 20))
            return -20;
        if (V(W_P)->ip > 6 || (NUM_ND(V(W_P)) && V(W_P)->fr))
            return -29;
        if (!axes)
            return -26;
    }
#endif
    if (nm == NM_G92 && !axes && !HASW(W_E))
        return -26;
    /* arcs and curves: checked before anything changes */
    ax0 = 0;
    ax1 = 1;
    per_point = 0;
    if (moving && (motion == 2 || motion == 3)) {
        uint8_t a0 = PLANE_AXES[plane][0], a1 = PLANE_AXES[plane][1], lin = (uint8_t)(3 - a0 - a1);
        int32_t off[2], x, y, cur[2], e[2];
        uint32_t re;
        if (!(axes & ((1U << a0) | (1U << a1))))
            return -32;
        if (NNIK_GC_PLANES && plane && tgt[lin] != g->mp[lin])
            return -20;
        x = tgt[a0] - g->mp[a0];
        y = tgt[a1] - g->mp[a1];
        if (HASW(W_R)) {
            int32_t rr = u[W_R];
            used |= 1U << W_R;
            if (rr == 0)
                return -33;
            r = nnik_gc_r_centre(x, y, rr, motion == 3, off);
            if (r)
                return r;
        } else {
            uint8_t o0 = (uint8_t)(W_I + a0), o1 = (uint8_t)(W_I + a1);
            if (!HASW(o0) && !HASW(o1))
                return -35;
            used |= (uint16_t)((1U << o0) | (1U << o1));
            off[0] = HASW(o0) ? u[o0] : 0;
            off[1] = HASW(o1) ? u[o1] : 0;
            if (arc_abs) {
                off[0] += woff(g, wcs, tlo, a0) - g->mp[a0];
                off[1] += woff(g, wcs, tlo, a1) - g->mp[a1];
            }
        }
        c[0] = g->mp[a0] + off[0];
        c[1] = g->mp[a1] + off[1];
        if (nnik_iabs32(c[0]) > POS_LIMIT || nnik_iabs32(c[1]) > POS_LIMIT)
            return -33;
        cur[0] = g->mp[a0] - c[0];
        cur[1] = g->mp[a1] - c[1];
        e[0] = tgt[a0] - c[0];
        e[1] = tgt[a1] - c[1];
        rad = nnik_isqrt64(nnik_sq2(cur[0], cur[1]));
        if (rad == 0)
            return -33;
        re = nnik_isqrt64(nnik_sq2(e[0], e[1]));
        if (re == 0 || (re > rad ? re - rad : rad - re) > 5 + rad / 1000)
            return -33;
        ax0 = a0;
        ax1 = a1;
        per_point = NNIK_GC_PLANES && plane != 0;
#if NNIK_GC_G5
    } else if (moving && motion == 5) {
        if (plane)
            return -20;
        if (!HASW(W_P) || !HASW(W_Q))
            return -28;
        used |= (1U << W_I) | (1U << W_J) | (1U << W_P) | (1U << W_Q);
        if (HASW(W_I) || HASW(W_J)) {
            c1[0] = g->mp[0] + (HASW(W_I) ? u[W_I] : 0);
            c1[1] = g->mp[1] + (HASW(W_J) ? u[W_J] : 0);
        } else if (g->motion == 5 && g->bez_ok) {
            c1[0] = 2 * g->mp[0] - g->bez[0];
            c1[1] = 2 * g->mp[1] - g->bez[1];
        } else {
            return -28;
        }
        c2[0] = tgt[0] + nnik_gc_um(V(W_P), inch);
        c2[1] = tgt[1] + u[W_Q];
        if (nnik_iabs32(c1[0]) > POS_LIMIT || nnik_iabs32(c1[1]) > POS_LIMIT || nnik_iabs32(c2[0]) > POS_LIMIT ||
            nnik_iabs32(c2[1]) > POS_LIMIT)
            return -33;
#endif
    }
    if (b.have & (uint16_t)~used & (uint16_t)((1U << W_COUNT) - 1))
        return -36;

    /* ---- commit: the modal state, then the action */
    if (HASW(W_F) && !inverse)
        g->feed = feed;
    if (HASW(W_S) && !b.m300 && !(nm == NM_G4 && NNIK_GC_MARLIN && !HASW(W_P)))
        g->s = u[W_S];
    if (HASW(W_T))
        g->tool_no = (uint8_t)V(W_T)->ip;
    if (b.spindle != UNSET)
        g->spindle = b.spindle == 5 ? 0 : b.spindle;
    if (b.coolant != UNSET)
        g->coolant = b.coolant == 9 ? 0 : (uint8_t)(g->coolant | (1U << (b.coolant - 7)));
    if (b.m300)
        g->pen = u[W_S] <= NNIK_GC_M300_DOWN;
    g->plane = plane;
    g->inch = inch;
    g->relative = rel;
    g->arc_abs = arc_abs;
    g->inverse_time = inverse;
    g->tlo = tlo;
    g->wcs = wcs;
    g->e_rel = e_rel;
    if (b.motion != UNSET)
        g->motion = b.motion;
    blk0 = g->blocks;
    r = 0;
    if (nm == NM_G4) {
        uint32_t ms = (uint32_t)dwell_ms;
        uint32_t t = ms / 1000 * NNIK_GC_TICK_HZ + ms % 1000 * NNIK_GC_TICK_HZ / 1000;
        if (t && !g->check)
            nnik_gc_rest(g, t, nnik_gc_idle_tool(g));
#if NNIK_GC_WCS
    } else if (nm == NM_G10) {
        uint8_t p = V(W_P)->ip ? (uint8_t)(V(W_P)->ip - 1) : g->wcs;
        for (k = 0; k < 3; k++)
            if (axes & (1U << k))
                g->coord[p][k] = V(W_L)->ip == 2 ? u[W_X + k] : g->mp[k] - g->g92[k] - (k == 2 ? g->tlo : 0) - u[W_X + k];
#endif
    } else if (nm == NM_G92) {
        for (k = 0; k < 3; k++)
            if (axes & (1U << k))
                g->g92[k] = g->mp[k] - g->coord[g->wcs][k] - (k == 2 ? g->tlo : 0) - u[W_X + k];
    } else if (nm == NM_G92_1) {
        g->g92[0] = g->g92[1] = g->g92[2] = 0;
#if NNIK_GC_WCS
    } else if (nm == NM_G28_1 || nm == NM_G30_1) {
        for (k = 0; k < 3; k++)
            g->home[nm == NM_G30_1][k] = g->mp[k];
#endif
    } else if (nm == NM_G28 || nm == NM_G30) {
        const int32_t *stored = g->home[nm == NM_G30];
        int32_t dest[3];
        if (axes && !NNIK_GC_MARLIN)
            r = line_to(g, tgt, NNIK_GC_MAX_FEED_UM_MIN, 1, 0);
        for (k = 0; k < 3; k++)
            dest[k] = (axes & (1U << k)) || !axes ? stored[k] : g->mp[k];
        if (!r)
            r = line_to(g, dest, NNIK_GC_MAX_FEED_UM_MIN, 1, 0);
    }
    /* what the end of the line needs from its words: the chords reuse their memory below */
    end_stop = b.stop;
    end_wait = b.wait;
    end_tool = b.spindle != UNSET || HASW(W_S) || (axes & 4) || b.m300;
    if (!r && moving) {
        if (motion <= 1) {
            int32_t f = motion == 0 ? (int32_t)NNIK_GC_MAX_FEED_UM_MIN : g->feed;
#if NNIK_GC_G93
            if (inv_f && motion)
                f = inverse_feed(nnik_isqrt64(nnik_sq2(tgt[0] - g->mp[0], tgt[1] - g->mp[1])), inv_f);
#endif
            r = line_to(g, tgt, f, motion == 0, extrude);
        } else {
            int32_t f = g->feed;
#if NNIK_GC_G93
            if (inv_f) { /* G93: the chords' length first */
                uint32_t len = 0;
                int32_t last[2];
                last[0] = g->mp[0];
                last[1] = g->mp[1];
                chords_start(g, motion, c, c1, c2, tgt, rad);
                while (chord_next(g, motion, c, p)) {
                    len += nnik_isqrt64(nnik_sq2(p[0] - last[0], p[1] - last[1]));
                    last[0] = p[0];
                    last[1] = p[1];
                }
                f = inverse_feed(len, inv_f);
            }
#endif
            if (!per_point) {
                g->mp[2] = tgt[2];
                g->tool = nnik_gc_move_tool(g, 0, extrude);
            }
            chords_start(g, motion, c, c1, c2, tgt, rad);
            while (!r && chord_next(g, motion, c, p)) {
                if (per_point) {
                    g->mp[2] = p[2];
                    g->tool = nnik_gc_move_tool(g, 0, extrude);
                }
                if (p[0] != g->mp[0] || p[1] != g->mp[1]) {
                    r = nnik_gc_push(g, p, f);
                    g->mp[0] = p[0];
                    g->mp[1] = p[1];
                }
            }
            g->mp[2] = tgt[2];
        }
    }
    if (r)
        return r;
    if (motion == 5 && moving) {
        g->bez[0] = c2[0];
        g->bez[1] = c2[1];
        g->bez_ok = 1;
    } else if (moving) {
        g->bez_ok = 0;
    }
    g->e = e_tgt;
    if (end_stop == 2 || end_stop == 30) { /* program end as grbl: G1 G17 G90 G94 G54, M5 M9 */
        g->motion = 1;
        g->plane = 0;
        g->relative = 0;
        g->inverse_time = 0;
        g->wcs = 0;
        g->spindle = 0;
        g->coolant = 0;
    }
    seg_blocks = g->blocks != blk0;
    if ((end_tool || end_stop == 2 || end_stop == 30) && !seg_blocks &&
        g->last_tool != nnik_gc_idle_tool(g) && (NNIK_GC_TOOL == 1 || nnik_gc_move_tool(g, 0, 0) == 0) && !g->check)
        nnik_gc_rest(g, 1, nnik_gc_idle_tool(g));
    if (end_wait || end_stop == 0 || end_stop == 2 || end_stop == 30) {
        if (!g->check)
            nnik_gc_flush(g);
        return end_stop == 0 ? NNIK_GC_PAUSE : NNIK_GC_SYNC;
    }
    return NNIK_GC_OK;
}
#undef b
#undef chords
