/*
 * nnik_gcode.h - a small RS274 interpreter that turns G-code lines into joint-space segments
 * through the generated IK.  Portable C99 (integer arithmetic only), no Arduino dependency:
 * the sketch examples/NAME_gcode feeds it lines from Serial and steps the motors, and nnik's
 * Python model (nnik.gcode) reproduces it bit for bit.
 *
 * Words: G0 G1 G2 G3 (modal motion), G20/G21 (inch/mm), G90/G91 (absolute/incremental),
 * X Y (end point), I J (arc centre offset from the start, always incremental) or R (arc radius;
 * negative: the arc longer than half a turn; an end at the start, or a chord longer than 2|R|
 * beyond the end tolerance, is an error), F (feed per minute), N (line number, ignored),
 * M400 (wait until the motion is done), M2/M30 (end: wait, then G1 G90 as grbl), G4 P (dwell,
 * seconds: a segment without steps), G92 X Y (set the program position: the motors stay),
 * G28 [X Y] (rapid via X Y, then to where the motors started, the named axes only), and
 * G17 G40 G49 G54 G64 G80 G94 (the only modes there are: accepted, nothing to do).
 * Comments: (...) and ';'.  '*nn' ends a line: the XOR of every byte before the '*' (Marlin).
 *
 * Motion: a line is one planner block; an arc is cut into quarter turns and those by bisection
 * until every chord is <= NNIK_GC_SEG_UM, each chord a block (nnik_plan.h: lookahead, junction
 * deviation, trapezoidal speed).  The planner's fixed-rate samples (NNIK_GC_SAMPLE_HZ) pass the
 * input shaper (nnik_shaper.h); the engine calls the IK on every shaped sample (plus the work
 * origin) and hands the steps from the previous sample to emit() with the sample's ticks,
 * NNIK_GC_TICK_HZ / NNIK_GC_SAMPLE_HZ (more if a motor needs more steps than that: an
 * overspeed, counted).  G0 moves at NNIK_GC_MAX_FEED_UM_MIN, which also caps F.  M400, M2, M30,
 * G4 and a tool change without motion flush the planner (it stops at the last block's end) and
 * then run the shaper's tail (NNIK_SH_LEN samples at rest) before a dwell or tool segment.
 *
 * Configuration comes from nnik_gcode_config.h (written by `nnik export --arduino`).
 */
#ifndef NNIK_GCODE_H
#define NNIK_GCODE_H

#include <stdint.h>

#include "nnik_plan.h"
#include "nnik_shaper.h"

#ifdef __cplusplus
extern "C" {
#endif

#define NNIK_GC_LINE_MAX 95 /* characters per line, comments included */

typedef struct nnik_gc nnik_gc_t;
typedef void (*nnik_gc_emit_fn)(nnik_gc_t *g, const int32_t steps[2], uint32_t ticks);

struct nnik_gc {
    int32_t pos[2];      /* program position, um */
    int32_t off[2];      /* G92: machine position (less the work origin) = pos + off */
    int32_t steps[2];    /* actuator command at pos */
    int32_t feed;        /* um per minute */
    uint32_t line_no;    /* lines seen (1 = the first) */
    uint32_t segments;   /* segments emitted (samples and rests) */
    uint32_t blocks;     /* blocks handed to the planner */
    uint32_t samples;    /* planner samples */
    uint32_t overspeed;  /* samples stretched beyond their ticks: a motor needed more steps */
    uint16_t settle;     /* shaper tail samples still owed after the last planner sample */
    uint16_t tail_tool;  /* the tool word of the last planner sample */
    int32_t pt[2];       /* the last shaped point, um (machine less the work origin) */
    nnik_plan_t pl;
    nnik_shaper_t sh;
    uint32_t clamped;    /* segment ends the IK clamped to its domain */
    int32_t s;           /* S in thousandths (laser power; NNIK_GC_S_MAX = full) */
    int32_t z;           /* Z, um (pen machines: above NNIK_GC_PEN_Z_UM the pen is up) */
    uint16_t tool;       /* the tool word of the segments being cut: duty, | 0x100 for M4 */
    uint16_t last_tool;  /* the tool word of the last segment emitted */
    uint8_t duty;        /* the tool's duty (0..255) for the segment handed to emit() */
    uint8_t spindle;     /* 0 (M5), 3 (M3), 4 (M4) */
    uint8_t motion;      /* 0..3 */
    uint8_t inch;
    uint8_t relative;
    nnik_gc_emit_fn emit; /* takes one segment; may wait for room in the caller's queue */
    char msg[40];         /* the last error, without "error: line N: " */
};

/* Start at program position (0, 0) = the work origin; the motors are taken to be there. */
void nnik_gc_init(nnik_gc_t *g, nnik_gc_emit_fn emit);

/* Run one line (without its newline).  0: done; 1: done, wait until the motion has finished
 * before answering (M2/M30/M400); -1: error, nothing moved, g->msg says why. */
int8_t nnik_gc_line(nnik_gc_t *g, const char *line);

/* Count a line that did not fit the caller's buffer: always -1, "line too long". */
int8_t nnik_gc_too_long(nnik_gc_t *g);

/* The planner runs out to rest and the shaper's tail follows (the end of a job: M400 does it). */
void nnik_gc_flush(nnik_gc_t *g);

/* floor(sqrt(v)) */
uint32_t nnik_isqrt32(uint32_t v);
uint32_t nnik_isqrt64(uint64_t v);

#ifdef __cplusplus
}
#endif

#endif /* NNIK_GCODE_H */
