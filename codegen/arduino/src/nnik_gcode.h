/*
 * nnik_gcode.h - an RS274 interpreter with grbl 1.1's meaning (widened where real files need it)
 * that turns G-code lines into joint-space segments through the generated IK.  Portable C99
 * (integer arithmetic only), no Arduino dependency: the sketch examples/NAME_gcode feeds it bytes
 * from its UART and steps the motors, and nnik's Python model (nnik.firmware.gcode) repeats it bit
 * for bit.  docs/gcode.md lists what is supported, noted and refused.
 *
 * Reading (nnik_gc_read.c): bytes as grbl's protocol layer reads them: blanks and control
 * characters and '/' dropped, '(' to the first ')' and ';' to the end are comments, lower case
 * raised, 79 characters fit (error 11 beyond); a '%' line is ignored, '*nn' is Marlin's checksum.
 * Words (nnik_gc_parse.c): grbl's letters plus E (Marlin), H, O, Q; within a modal group the last
 * word wins.  Execution (nnik_gcode.c; the tool's word nnik_gc_tool.c): G0 G1 G2 G3 (I J K or R, every plane) G5 (Marlin's Bezier) G4
 * G10 L2/L20 G17-G19 G20 G21 G28 G28.1 G30 G30.1 G43.1 G49 G53 G54-G59 G80 G90 G91 G90.1 G91.1
 * G92 G92.1 G93 G94, M0 M2 M30 M3 M4 M5 M400 M82 M83 M300 (a servo pen), F S T; other M codes
 * and setup codes are accepted and do nothing.
 *
 * Motion: a line is one planner block; an arc is cut into quarter turns and those by bisection
 * until every chord is <= NNIK_GC_SEG_UM, a Bezier into equal steps of t, each chord a block
 * (nnik_plan.h).  The planner's fixed-rate samples (NNIK_GC_SAMPLE_HZ) pass the input shaper
 * (nnik_shaper.h); the engine calls the IK on every shaped sample (plus the work origin) and hands
 * the steps from the previous sample to emit() with the sample's ticks.
 *
 * Start and soft reset: nnik_gc_init.c.  Shared integer maths: nnik_imath.c.  No two of these files
 * call each other (tests/firmware/test_c_calls.py).
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

#define NNIK_GC_LINE_MAX 79 /* grbl's 80-byte line buffer */

#ifndef NNIK_GC_WCS
#define NNIK_GC_WCS 1
#endif
#define NNIK_GC_N_WCS (NNIK_GC_WCS ? 6 : 1)

/* 1: a block that finds the planner full is held back and its line answered at once
 * (nnik_gc_ahead): the stepper keeps being fed while the sender's next line travels.  About
 * 380 B of flash and 15 B of RAM: on by default on the ATmega2560 only (-D to choose). */
#ifndef NNIK_GC_HOLD
#if defined(__AVR_ATmega2560__)
#define NNIK_GC_HOLD 1
#else
#define NNIK_GC_HOLD 0
#endif
#endif

/* results of nnik_gc_eol */
#define NNIK_GC_OK 0     /* done (an empty, comment or '%' line too) */
#define NNIK_GC_SYNC 1   /* done; answer after the motion has finished (M2, M30, M400) */
#define NNIK_GC_PAUSE 2  /* M0: the motion up to here runs, then a feed hold until cycle start */
#define NNIK_GC_DOLLAR 3 /* a '$' line: g->line holds it (cleaned) for the front end */
/* -1..-99: -N is grbl's error:N; NNIK_GC_ALARM(n): ALARM:n (2: a target beyond the travel) */
#define NNIK_GC_ALARM(n) (-100 - (n))

typedef struct nnik_gc nnik_gc_t;
typedef void (*nnik_gc_emit_fn)(nnik_gc_t *g, const int32_t steps[2], uint32_t ticks);

struct nnik_gc {
    int32_t mp[3];        /* machine position, um (X, Y less the work origin; Z the tool's axis) */
    int32_t coord[NNIK_GC_N_WCS][3]; /* G54..G59 work offsets (G54's alone without the wcs option) */
    int32_t g92[3];       /* G92 offset */
    int32_t home[2][3];   /* G28, G30 stored positions */
    int32_t tlo;          /* G43.1 tool length offset (Z) */
    int32_t e;            /* Marlin's E, um */
    int32_t bez[2];       /* the last G5's second control point */
    int32_t steps[2];     /* actuator command at the last sample */
    int32_t feed;         /* um per minute */
    int32_t s;            /* S in thousandths */
    int32_t pt[2];        /* the last shaped point, um (machine less the work origin) */
    uint32_t line_no;     /* lines seen (1 = the first) */
    uint32_t segments;    /* segments emitted (samples and rests) */
    uint32_t blocks;      /* blocks handed to the planner */
    uint32_t samples;     /* planner samples */
    uint32_t overspeed;   /* samples stretched beyond their ticks: a motor needed more steps */
    uint32_t clamped;     /* segment ends the IK clamped to its domain */
    nnik_plan_t pl;
#if NNIK_GC_HOLD
    int32_t pend[3];      /* a block held back while the planner is full: X, Y (um), feed (um/min) */
    uint16_t pend_tool;   /* its tool word */
    uint8_t pending;      /* 1: pend waits for the head block to be left (its line is answered) */
#endif
    nnik_shaper_t sh;
    uint16_t settle;      /* shaper tail samples still owed after the last planner sample */
    uint16_t tail_tool;   /* the tool word of the last planner sample */
    uint16_t tool;        /* the tool word of the blocks being cut: duty, | 0x100 for M4 */
    uint16_t last_tool;   /* the tool word of the last block or rest */
    uint8_t duty;         /* the tool's duty (0..255) for the segment handed to emit() */
    uint8_t motion;       /* 0 1 2 3 5; 80: none (G80) */
    uint8_t plane;        /* 0: G17, 1: G18, 2: G19 */
    uint8_t inch, relative, arc_abs, inverse_time, wcs, e_rel, pen;
    uint8_t spindle;      /* 0 (M5), 3, 4 */
    uint8_t coolant;      /* bit 0: M7, bit 1: M8 */
    uint8_t tool_no;      /* T */
    uint8_t alarm;        /* 0, or the alarm that locks G-code out (error 9) until a reset */
    uint8_t check;        /* 1: check mode ($C): lines are read and change modes, nothing moves */
    uint8_t bez_ok;       /* bez[] holds the last G5's */
    /* the line reader */
    char line[NNIK_GC_LINE_MAX + 1];
    uint8_t len, rd_mode, rd_over, rd_xor, rd_sum_digits, rd_sum_bad, rd_sum_blank;
    uint16_t rd_sum;
    nnik_gc_emit_fn emit; /* takes one segment; may wait for room in the caller's queue */
};

/* Start at machine (0, 0) = the work origin; the motors are taken to be there. */
void nnik_gc_init(nnik_gc_t *g, nnik_gc_emit_fn emit);

/* As init, with the machine standing at pt (um, machine less the work origin) and the motors at
 * IK(origin + pt), the G-code state fresh (a soft reset keeps where the motors are). */
void nnik_gc_place(nnik_gc_t *g, const int32_t pt[2]);

/* One byte of a line as it arrives (not '\n' or '\r'): read as grbl's protocol layer does. */
void nnik_gc_byte(nnik_gc_t *g, uint8_t c);

/* The line ended: run it (NNIK_GC_* or -N), reset the reader. */
int8_t nnik_gc_eol(nnik_gc_t *g);

/* A whole line (no '\n'), byte by byte then its end: the host harness's way in. */
int8_t nnik_gc_line(nnik_gc_t *g, const char *line);

/* The planner runs out to rest and the shaper's tail follows (the end of a job: M400 does it). */
void nnik_gc_flush(nnik_gc_t *g);

/* A block held back (pending: the planner was full when its line came, and the line is answered
 * at once so that the sender's next line travels meanwhile): one sample while the planner is
 * full, else the block goes in.  The planner sees the same pushes and samples in the same order
 * as without holding back (its samples depend on the blocks alone).  1 if it did either. */
#if NNIK_GC_HOLD
uint8_t nnik_gc_ahead(nnik_gc_t *g);
#endif

/* internal: the words of g->line run (nnik_gc_parse.c -> nnik_gcode.c) */
int8_t nnik_gc_exec(nnik_gc_t *g);

/* internal: the line reader's state cleared (nnik_gc_read.c; nnik_gc_place calls it) */
void nnik_gc_read_reset(nnik_gc_t *g);

#ifdef __cplusplus
}
#endif

#endif /* NNIK_GCODE_H */
