/*
 * nnik_gc_init.c - the G-code engine's start and soft reset (see nnik_gcode.h): every field of the
 * state cleared, the machine standing at a point and the motors at its IK, the planner, the
 * shaper and the line reader fresh.  It calls into each part and nothing calls back into it.
 */
#include "nnik_gcode.h"
#include "nnik_gcode_config.h"

#define Z_HOME (NNIK_GC_PEN_Z_UM + 5000L) /* G28 and G30's Z until G28.1 / G30.1 store one */

void nnik_gc_init(nnik_gc_t *g, nnik_gc_emit_fn emit)
{
    const int32_t at[2] = {0, 0};
    g->emit = emit;
    nnik_gc_place(g, at);
}

void nnik_gc_place(nnik_gc_t *g, const int32_t pt[2])
{
    uint8_t *p = (uint8_t *)g;
    uint16_t i;
    int32_t in[2], at[2];
    nnik_gc_emit_fn emit = g->emit;
    at[0] = pt[0]; /* pt may lie in *g */
    at[1] = pt[1];
    for (i = 0; i < sizeof *g; i++)
        p[i] = 0;
    g->mp[0] = g->pt[0] = at[0];
    g->mp[1] = g->pt[1] = at[1];
    in[0] = NNIK_GC_ORIGIN_X_UM + at[0];
    in[1] = NNIK_GC_ORIGIN_Y_UM + at[1];
    NNIK_GC_IK(in, g->steps);
    g->feed = NNIK_GC_FEED_UM_MIN;
    g->home[0][2] = g->home[1][2] = Z_HOME;
    nnik_pl_init(&g->pl, g->pt);
    nnik_sh_init(&g->sh, g->pt);
    g->emit = emit;
    nnik_gc_read_reset(g);
}
