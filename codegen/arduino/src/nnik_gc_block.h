/*
 * nnik_gc_block.h - one line's words, between the parser (nnik_gc_parse.c) and the interpreter
 * (nnik_gcode.c).  Internal to the G-code engine.
 */
#ifndef NNIK_GC_BLOCK_H
#define NNIK_GC_BLOCK_H

#include <stdint.h>

#include "nnik_gcode.h"
#include "nnik_gcode_config.h"

/* build options, as grbl's config.h (each one's flash cost: docs/firmware.md) */
#ifndef NNIK_GC_G5
#define NNIK_GC_G5 1     /* Marlin's G5 cubic Bezier */
#endif
#ifndef NNIK_GC_G93
#define NNIK_GC_G93 1    /* G93 inverse time feed */
#endif
#ifndef NNIK_GC_PLANES
#define NNIK_GC_PLANES 1 /* arcs in G18 and G19 */
#endif
#ifndef NNIK_GC_WCS
#define NNIK_GC_WCS 1    /* G10 L2/L20, G55-G59, G28.1, G30.1 */
#endif

/* a decimal as written: [-]ip.fr with nd fraction digits (up to 9 + 6 digits) */
typedef struct {
    uint32_t ip;
    uint32_t fr;
    uint8_t nd; /* bit 7: negative */
} nnik_num_t;

#define NUM_NEG 0x80
#define NUM_ND(n) ((n)->nd & 0x7f)

/* value letters, in this order */
enum { W_E, W_F, W_H, W_I, W_J, W_K, W_L, W_P, W_Q, W_R, W_S, W_T, W_X, W_Y, W_Z, W_COUNT };
#define HAS(b, w) ((b)->have & (1U << (w)))

/* non-modal commands */
enum { NM_NONE, NM_G4, NM_G10, NM_G28, NM_G28_1, NM_G30, NM_G30_1, NM_G53, NM_G92, NM_G92_1 };

#define UNSET 0xff

typedef struct {
    nnik_num_t v[W_COUNT];
    uint16_t have;
    uint8_t motion, nonmodal, plane, inch, relative, arc_abs, inverse, tlo, wcs;
    uint8_t stop, spindle, coolant, e_rel;
    uint8_t wait, m300, noted_line, g64, g43;
} nnik_blk_t;

/* the words of g->line; 0 or -N (grbl's error:N) */
int8_t nnik_gc_parse(const char *s, nnik_blk_t *b);

/* whole micrometres (or thousandths) of n: ip * scale + round_half_up(fr * scale / 10^nd),
 * signed, saturated at +-2^28 */
int32_t nnik_gc_um(const nnik_num_t *n, uint8_t inch);

#define NNIK_GC_SAT 268435456L /* 2^28 */

/* nnik_gc_segments.c: a segment without steps once the planned motion is at rest; a block to the
 * machine point p (X, Y) through the frame transform and the soft limits into the planner (0, or
 * the alarm's code) */
void nnik_gc_rest(nnik_gc_t *g, uint32_t ticks, uint16_t t);
int8_t nnik_gc_push(nnik_gc_t *g, const int32_t p[2], int32_t feed);

#endif /* NNIK_GC_BLOCK_H */
