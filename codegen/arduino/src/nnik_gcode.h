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
 * Motion: a line is cut into ceil(L / NNIK_GC_SEG_UM) equal segments; an arc into quarter
 * turns and those by bisection until every chord is <= NNIK_GC_SEG_UM.  At each segment end the
 * engine calls the IK on the machine position (program position + the work origin), and hands
 * the steps from the previous end and a duration in ticks of NNIK_GC_TICK_HZ to emit():
 *     ticks = max(ceil(chord_um * 60 * TICK_HZ / feed_um_per_min), |d0|, |d1|, 1)
 * (G0 moves at NNIK_GC_RAPID_UM_MIN).
 *
 * Configuration comes from nnik_gcode_config.h (written by `nnik export --arduino`).
 */
#ifndef NNIK_GCODE_H
#define NNIK_GCODE_H

#include <stdint.h>

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
    uint32_t segments;   /* segments emitted */
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

/* floor(sqrt(v)) */
uint32_t nnik_isqrt32(uint32_t v);
uint32_t nnik_isqrt64(uint64_t v);

#ifdef __cplusplus
}
#endif

#endif /* NNIK_GCODE_H */
