/*
 * nnik_gc_shim.h - TEMPORARY, branch grbl only: the byte-wise reader that the rewritten engine
 * (nnik_gcode.c) will offer, on top of today's nnik_gc_line(), so that the grbl front end
 * (nnik_grbl.c) builds and runs before the engine lands.  Remove nnik_gc_shim.c/.h and the
 * include in nnik_grbl.h when merging; the GC_* accessors then read the engine's own fields
 * (the defaults at the top of nnik_grbl.c).
 *
 * What the front end needs from the engine (the contract):
 *   nnik_gc_byte(g, c)   one byte of a line (never '\n' or '\r'), cleaned as grbl's protocol.c
 *   nnik_gc_eol(g)       run the line, reset the reader; NNIK_GC_OK / SYNC / PAUSE / DOLLAR,
 *                        -N (error:N), NNIK_GC_ALARM(n)
 *   nnik_gc_place(g, pt) as nnik_gc_init (modal state, G92, planner, shaper, reader), but the
 *                        machine stands at pt (um, machine less the work origin), the motors at
 *                        IK(origin + pt) as after any sample: the soft reset, which keeps the
 *                        position as grbl does
 *   g->line, g->len      the cleaned line so far (upper case, no blanks or comments) and its
 *                        length; after nnik_gc_eol returned DOLLAR, g->line holds the '$' line,
 *                        NUL-terminated.  Setting g->len = 0 before nnik_gc_eol drops the line
 *                        (it then answers NNIK_GC_OK): the alarm lock (error:9)
 *   g->check             1: check mode (parse, change the modal state, emit nothing)
 *   g->motion g->plane g->inch g->relative g->wcs g->inverse_time g->spindle g->coolant
 *   g->tool_no g->feed (um/min) g->s (thousandths)     for $G and the status report
 *   g->pt[2], g->mp[2]   the last shaped sample (um) and Z
 *   g->coord[6][3], g->g92[3], g->home[2][3], g->tlo   $# and the status report's WCO
 *   g->pl.count          blocks in the planner (nnik_plan.h): Run while > 0, and Bf
 */
#ifndef NNIK_GC_SHIM_H
#define NNIK_GC_SHIM_H

#include <stdint.h>

#include "nnik_gcode.h"

#ifdef __cplusplus
extern "C" {
#endif

#ifndef NNIK_GC_OK
#define NNIK_GC_SHIM 1
#define NNIK_GC_OK 0
#define NNIK_GC_SYNC 1
#define NNIK_GC_PAUSE 2
#define NNIK_GC_DOLLAR 3
#define NNIK_GC_ALARM(n) (-100 - (n))
#define NNIK_GC_CLEAN_MAX 80 /* grbl's line buffer: 79 characters after cleaning */

typedef struct {
    char line[NNIK_GC_CLEAN_MAX];       /* cleaned: upper case, no blanks, no comments */
    char raw[NNIK_GC_LINE_MAX + 1];     /* as received, for nnik_gc_line (checksums) */
    uint8_t len, raw_len, over, comment; /* comment: 1 in '(', 2 after ';' */
    uint8_t check;
} nnik_gc_shim_t;
extern nnik_gc_shim_t nnik_gc_shim;

void nnik_gc_byte(nnik_gc_t *g, uint8_t c);
int8_t nnik_gc_eol(nnik_gc_t *g);
void nnik_gc_place(nnik_gc_t *g, const int32_t pt[2]);

/* the fields, where today's engine has them or the shim fakes them */
#define GC_LINE(g) (nnik_gc_shim.line)
#define GC_LEN(g) (nnik_gc_shim.len)
#define GC_CHECK(g) (nnik_gc_shim.check)
#define GC_PLANE(g) 0
#define GC_WCS(g) 0
#define GC_INVT(g) 0
#define GC_COOLANT(g) 0
#define GC_TOOLNO(g) 0
#define GC_Z(g) ((g)->z)
#define GC_COORD(g, i, a) 0
#define GC_HOME(g, i, a) 0
#define GC_G92(g, a) ((a) < 2 ? (g)->off[a] : 0)
#define GC_TLO(g) 0
#endif

#ifdef __cplusplus
}
#endif

#endif /* NNIK_GC_SHIM_H */
