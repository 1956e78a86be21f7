/*
 * nnik_gc_tool.h - the tool's word (duty 0..255, | TOOL_SCALED for M4) that the G-code engine
 * hands the planner with each block and rest, from the modal state and the job's rule
 * (nnik/firmware/gcode/interpreter.py repeats it).  Internal to the G-code engine.  What is a
 * constant or one call for the build's tool and rule is inline here; nnik_gc_tool.c holds the rest.
 */
#ifndef NNIK_GC_TOOL_H
#define NNIK_GC_TOOL_H

#include <stdint.h>

#include "nnik_gcode.h"
#include "nnik_gcode_config.h"

#ifndef NNIK_GC_RULE
#define NNIK_GC_RULE 0 /* 0 s, 1 z, 2 e, 3 m300, 4 none */
#endif

#define TOOL_SCALED 0x100 /* M4: the power follows the planned speed */
#if NNIK_GC_TOOL == 1
#define OFF_DUTY NNIK_GC_PEN_UP_DUTY
#else
#define OFF_DUTY 0
#endif

/* the tool at rest (a dwell, the end of a line that changed it): a pen-like tool's down or up by
 * the rule (s, z, m300; up under e and none), a laser's off */
#define NNIK_GC_IDLE_BY_STATE (NNIK_GC_TOOL == 1 && (NNIK_GC_RULE == 0 || NNIK_GC_RULE == 1 || NNIK_GC_RULE == 3))
#if NNIK_GC_IDLE_BY_STATE
#if defined(__GNUC__)
__attribute__((pure)) /* reads *g only: two calls on one state are one */
#endif
uint16_t nnik_gc_idle_tool(const nnik_gc_t *g);
#else
static inline uint16_t nnik_gc_idle_tool(const nnik_gc_t *g)
{
    (void)g;
    return OFF_DUTY;
}
#endif

/* the tool over a move: rapid for G0, extrude for a Marlin move whose E grows */
#if NNIK_GC_RULE == 0 && NNIK_GC_TOOL != 1
uint16_t nnik_gc_laser_tool(const nnik_gc_t *g, uint8_t rapid); /* a laser's S (M3, M4), off in G0 */
#endif
static inline uint16_t nnik_gc_move_tool(const nnik_gc_t *g, uint8_t rapid, uint8_t extrude)
{
    (void)rapid;
#if NNIK_GC_RULE == 0 && NNIK_GC_TOOL != 1
    (void)extrude;
    return nnik_gc_laser_tool(g, rapid);
#elif NNIK_GC_RULE == 2
    (void)g;
#if NNIK_GC_TOOL == 1
    return extrude ? NNIK_GC_PEN_DOWN_DUTY : OFF_DUTY;
#else
    return extrude ? 255 : 0;
#endif
#else
    (void)extrude;
    return nnik_gc_idle_tool(g); /* a pen-like tool: as at rest; a laser under rule z, m300 or none: off */
#endif
}

#endif /* NNIK_GC_TOOL_H */
