/*
 * nnik_gcode_host - the G-code engine (codegen/arduino/src/nnik_gcode.c) with a model's IK,
 * compiled for the host: G-code lines on stdin, on stdout one "S d0 d1 ticks x y duty" per segment
 * (steps, ticks, the shaped point in um: machine less the work origin, the tool's duty last; one per
 * planner sample, shaper tail sample or rest) and one "R <answer>" per line ("ok" or
 * "error: line N: ...", as the sketch answers).  nnik's tests compare it with the Python model.
 */
#include <stdio.h>
#include <string.h>

#include "nnik_gcode.h"

static void emit(nnik_gc_t *g, const int32_t d[2], uint32_t ticks)
{
    printf("S %ld %ld %lu %ld %ld %u\n", (long)d[0], (long)d[1], (unsigned long)ticks,
           (long)g->pt[0], (long)g->pt[1], (unsigned)g->duty);
}

int main(void)
{
    static nnik_gc_t gc;
    char line[4096];
    nnik_gc_init(&gc, emit);
    printf("I %ld %ld\n", (long)gc.steps[0], (long)gc.steps[1]);
    while (fgets(line, sizeof line, stdin)) {
        size_t n = strlen(line);
        int8_t r;
        if (n && line[n - 1] == '\n')
            line[--n] = 0;
        r = n > NNIK_GC_LINE_MAX ? nnik_gc_too_long(&gc) : nnik_gc_line(&gc, line);
        if (r < 0)
            printf("R error: line %lu: %s\n", (unsigned long)gc.line_no, gc.msg);
        else
            printf("R ok\n");
    }
    nnik_gc_flush(&gc); /* the end of the job, as the simavr harness's final M400 */
    printf("O %lu\n", (unsigned long)gc.overspeed);
    return 0;
}
