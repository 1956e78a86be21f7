/*
 * nnik_gc_geom.h - arcs and Bezier curves cut into chords in integers (nnik/firmware/gcode/
 * geometry.py repeats them).  Internal to the G-code engine.
 */
#ifndef NNIK_GC_GEOM_H
#define NNIK_GC_GEOM_H

#include <stdint.h>

typedef void (*nnik_gc_point_fn)(void *ctx, const int32_t q[2]);

/* The centre of an R-form arc as an offset ij from its start, for the chord (x, y) and the
 * radius rad (not zero; negative: the long way round), ccw for G3: 0, or -33 (grbl's invalid
 * target: an end at the start, or a chord longer than 2|R| beyond the end tolerance). */
int8_t nnik_gc_r_centre(int32_t x, int32_t y, int32_t rad, uint8_t ccw, int32_t ij[2]);

/* The chord ends (offsets from the centre) of the arc from (c0, c1) to (e0, e1), radius r:
 * quarter turns, each bisected until every chord is <= NNIK_GC_SEG_UM (a full circle when the
 * end is the start); fn gets each end in order. */
void nnik_gc_arc(int32_t c0, int32_t c1, int32_t e0, int32_t e1, uint32_t r, uint8_t ccw, nnik_gc_point_fn fn,
                 void *ctx);

/* The points of the cubic p0 c1 c2 p3 (X, Y) at t = k / n, k = 1..n, n = the control polygon's
 * length / NNIK_GC_SEG_UM rounded up (1..1024): p0 + the cubic's offset from p0, rounded half
 * away from zero. */
void nnik_gc_bezier(const int32_t p0[2], const int32_t c1[2], const int32_t c2[2], const int32_t p3[2],
                    nnik_gc_point_fn fn, void *ctx);

#endif /* NNIK_GC_GEOM_H */
