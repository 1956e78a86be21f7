/*
 * nnik_gc_geom.h - arcs and Bezier curves cut into chords in integers (nnik/firmware/gcode/
 * geometry.py repeats them).  Internal to the G-code engine.
 */
#ifndef NNIK_GC_GEOM_H
#define NNIK_GC_GEOM_H

#include <stdint.h>

#define NNIK_GC_ARC_STACK 16 /* bisections: chords of 100 um from any piece shorter than 6.5 m */

/* The chord ends of an arc or a Bezier, one at a time (the caller pushes each block from its own
 * shallow stack): start, then next() until it returns 0. */
typedef struct {
    int32_t cur[2], e[2], stack[NNIK_GC_ARC_STACK][2];
    uint32_t r;
    uint8_t top, ccw, last, bezier;
    /* Bezier */
    int32_t d[3][2], q[2];
    uint32_t n, k, n3;
} nnik_gc_chords_t;

/* The centre of an R-form arc as an offset ij from its start, for the chord (x, y) and the
 * radius rad (not zero; negative: the long way round), ccw for G3: 0, or -33 (grbl's invalid
 * target: an end at the start, or a chord longer than 2|R| beyond the end tolerance). */
int8_t nnik_gc_r_centre(int32_t x, int32_t y, int32_t rad, uint8_t ccw, int32_t ij[2]);

/* The arc from (c0, c1) to (e0, e1) (offsets from the centre), radius r: quarter turns, each
 * bisected until every chord is <= NNIK_GC_SEG_UM (a full circle when the end is the start);
 * next() gives each chord end (an offset from the centre) in order. */
void nnik_gc_arc_start(nnik_gc_chords_t *it, int32_t c0, int32_t c1, int32_t e0, int32_t e1, uint32_t r, uint8_t ccw);

/* The cubic p0 c1 c2 p3 (X, Y) at t = k / n, k = 1..n, n = the control polygon's length /
 * NNIK_GC_SEG_UM rounded up (1..1024): p0 + the cubic's offset from p0, rounded half away from
 * zero; next() gives each point (absolute). */
void nnik_gc_bezier_start(nnik_gc_chords_t *it, const int32_t p0[2], const int32_t c1[2], const int32_t c2[2],
                          const int32_t p3[2]);

uint8_t nnik_gc_chords_next(nnik_gc_chords_t *it, int32_t q[2]);

#endif /* NNIK_GC_GEOM_H */
