/*
 * nnik_gc_segments.c - the interpreter's blocks into the planner (nnik_plan.c) and the planner's
 * samples out: the shaper (nnik_shaper.c), the IK, the step counts and the stepper's segment
 * (g->emit).  Split from nnik_gcode.c, whose motion it carries; nnik/firmware/gcode/interpreter.py
 * and sampler.py repeat it bit for bit.  Every block end passes the job's frame transform
 * (p * NNIK_GC_SCALE_Q16 / 2^16 + shift, rounded half up) when the build has one.
 */
#include "nnik_gc_block.h"
#include "nnik_gc_tool.h"
#include "nnik_gcode_config.h"
#include "nnik_imath.h"

#if NNIK_GC_TICK_HZ > 12000
#error "NNIK_GC_TICK_HZ above 12 kHz overflows the 32-bit tick count"
#endif
#ifndef NNIK_GC_FRAME
#define NNIK_GC_FRAME 0 /* 1: the job's frame transform (--fit, --scale, --offset) */
#endif
#ifndef NNIK_GC_SOFT_LIMITS
#define NNIK_GC_SOFT_LIMITS 0 /* 1: ALARM:2 on a block end beyond the travel */
#endif

#define SAMPLE_TICKS (NNIK_GC_TICK_HZ / NNIK_GC_SAMPLE_HZ)
#if NNIK_GC_TICK_HZ % NNIK_GC_SAMPLE_HZ
#error "NNIK_GC_SAMPLE_HZ must divide NNIK_GC_TICK_HZ"
#endif

/* the tool's duty; M4: the power follows the planned speed, duty * min(v, vn) / vn (no
 * division at or above vn: a cruise costs none) */
static uint8_t m4_duty(uint16_t tool, uint32_t v, uint32_t vn)
{
    if ((tool & TOOL_SCALED) && v < vn)
        return (uint8_t)((uint32_t)(uint8_t)tool * v / vn);
    return (uint8_t)tool;
}

/* a sample s of the plan (or of the shaper's tail) through the shaper, the IK and the step counts
 * to the stepper */
static void out_sample(nnik_gc_t *g, const nnik_pl_sample_t *s)
{
    int32_t out[2], d[2];
    uint32_t ticks, a;
    uint8_t duty = m4_duty(s->tool, s->v, s->vn);
    nnik_sh_step(&g->sh, s->p, duty, s->moved, g->pt); /* the tool's progress: the path length moved */
#if NNIK_GC_ORIGIN_X_UM == 0 && NNIK_GC_ORIGIN_Y_UM == 0
    if (NNIK_GC_IK(g->pt, out)) /* the work origin at the machine's 0: the shaped point as it is */
        g->clamped++;
#else
    {
        int32_t in[2];
        in[0] = NNIK_GC_ORIGIN_X_UM + g->pt[0];
        in[1] = NNIK_GC_ORIGIN_Y_UM + g->pt[1];
        if (NNIK_GC_IK(in, out))
            g->clamped++;
    }
#endif
    d[0] = out[0] - g->steps[0];
    d[1] = out[1] - g->steps[1];
    ticks = (uint32_t)nnik_iabs32(d[0]);
    a = (uint32_t)nnik_iabs32(d[1]);
    if (ticks < a)
        ticks = a;
    if (ticks > SAMPLE_TICKS) /* a motor needs more steps than the sample has ticks */
        g->overspeed++;
    else
        ticks = SAMPLE_TICKS;
#if NNIK_SH_LEN > 0
    g->duty = g->sh.duty; /* the tool where the shaped head is (nnik_shaper.h) */
#else
    g->duty = duty;
#endif
    g->steps[0] = out[0];
    g->steps[1] = out[1];
    g->segments++;
    g->emit(g, d, ticks);
}

/* every sample: inline at its callers' loops (no call, no registers saved a sample) */
#ifdef __GNUC__
__attribute__((always_inline))
#endif
static inline void sample(nnik_gc_t *g)
{
    nnik_pl_sample_t s;
    nnik_pl_sample(&g->pl, &s);
    g->settle = NNIK_SH_LEN;
    g->tail_tool = s.tool;
    g->samples++;
    out_sample(g, &s);
}

#if NNIK_GC_HOLD
/* the held block into the planner, after the samples the planner owes before it (a push's) */
static void commit(nnik_gc_t *g)
{
    if (!g->pending)
        return;
    while (nnik_pl_ready(&g->pl, 0))
        sample(g);
    nnik_pl_push(&g->pl, g->pend[0], g->pend[1], g->pend[2], g->pend_tool);
    g->pending = 0;
}

uint8_t nnik_gc_ahead(nnik_gc_t *g)
{
    if (!g->pending)
        return 0;
    if (nnik_pl_ready(&g->pl, 0))
        sample(g);
    else
        commit(g);
    return 1;
}
#else
#define commit(g) ((void)0)
#endif

void nnik_gc_flush(nnik_gc_t *g)
{
    nnik_pl_sample_t s; /* the shaper's tail: at rest where the plan ended, the last tool word */
    commit(g);
    while (nnik_pl_ready(&g->pl, 1))
        sample(g);
    s.p[0] = g->pl.start[0];
    s.p[1] = g->pl.start[1];
    s.v = s.moved = 0;
    s.vn = 1;
    s.tool = g->tail_tool;
    while (g->settle) {
        g->settle--;
        out_sample(g, &s);
    }
}

/* a segment without steps, once the planned motion is at rest */
void nnik_gc_rest(nnik_gc_t *g, uint32_t ticks, uint16_t t)
{
    int32_t d[2] = {0, 0};
    nnik_gc_flush(g);
    g->tool = g->last_tool = t;
    g->duty = (uint8_t)t;
    g->segments++;
    g->emit(g, d, ticks);
}

/* a block to the machine point p (X, Y): the transform, the soft limits, the planner */
int8_t nnik_gc_push(nnik_gc_t *g, const int32_t p[2], int32_t feed)
{
    int32_t e[2];
    e[0] = p[0];
    e[1] = p[1];
#if NNIK_GC_FRAME
    e[0] = (int32_t)(((int64_t)p[0] * NNIK_GC_SCALE_Q16 + 32768) >> 16) + NNIK_GC_SHIFT_X_UM;
    e[1] = (int32_t)(((int64_t)p[1] * NNIK_GC_SCALE_Q16 + 32768) >> 16) + NNIK_GC_SHIFT_Y_UM;
#endif
#if NNIK_GC_SOFT_LIMITS
    if (e[0] < NNIK_GC_MIN_X_UM || e[0] > NNIK_GC_MAX_X_UM || e[1] < NNIK_GC_MIN_Y_UM || e[1] > NNIK_GC_MAX_Y_UM) {
        g->alarm = 2;
        return NNIK_GC_ALARM(2);
    }
#endif
    if (g->check)
        return 0;
#if NNIK_GC_HOLD
    commit(g);
    g->pend[0] = e[0];
    g->pend[1] = e[1];
    g->pend[2] = feed;
    g->pend_tool = g->tool;
    g->pending = 1;
    if (!nnik_pl_ready(&g->pl, 0))
        commit(g); /* else held until the head block is left (nnik_gc_ahead) */
#else
    while (nnik_pl_ready(&g->pl, 0))
        sample(g);
    nnik_pl_push(&g->pl, e[0], e[1], feed, g->tool);
#endif
    g->last_tool = g->tool;
    g->blocks++;
    return 0;
}
