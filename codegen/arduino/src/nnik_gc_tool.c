/* nnik_gc_tool.c - see nnik_gc_tool.h */
#include "nnik_gc_tool.h"

#if NNIK_GC_IDLE_BY_STATE
#if NNIK_GC_RULE == 1
static int32_t work_z(const nnik_gc_t *g)
{
    return g->mp[2] - (g->coord[g->wcs][2] + g->g92[2] + g->tlo);
}
#endif

uint16_t nnik_gc_idle_tool(const nnik_gc_t *g)
{
#if NNIK_GC_RULE == 1
    uint8_t down = work_z(g) <= NNIK_GC_PEN_Z_UM;
#elif NNIK_GC_RULE == 0
    uint8_t down = g->spindle && g->s > 0;
#else
    uint8_t down = g->pen;
#endif
    return down ? NNIK_GC_PEN_DOWN_DUTY : NNIK_GC_PEN_UP_DUTY;
}
#endif

#if NNIK_GC_RULE == 0 && NNIK_GC_TOOL != 1
#define S_FULL (NNIK_GC_S_MAX * 1000L)

uint16_t nnik_gc_laser_tool(const nnik_gc_t *g, uint8_t rapid)
{
    uint16_t t;
    if (rapid || !g->spindle)
        return 0;
    t = (uint16_t)((uint32_t)(g->s < S_FULL ? g->s : S_FULL) * 255UL / (uint32_t)S_FULL);
    return g->spindle == 4 ? t | TOOL_SCALED : t;
}
#endif
