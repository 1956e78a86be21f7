/*
 * nnik_gcode_host - the G-code engine (codegen/arduino/src/nnik_gcode.c and its parts) with a
 * model's IK, compiled for the host: G-code lines on stdin (bytes; '\n' ends a line), on stdout one
 * "S d0 d1 ticks x y duty" per segment (steps, ticks, the shaped point in um: machine less the
 * work origin, the tool's duty last) and one "R <answer>" per line: "ok", "error:N", "ALARM:N" or
 * "$" (a $ line, the front end's).  nnik's tests compare it with the Python model.
 */
#include <stdio.h>

#include "nnik_gcode.h"

static void emit(nnik_gc_t *g, const int32_t d[2], uint32_t ticks)
{
    printf("S %ld %ld %lu %ld %ld %u\n", (long)d[0], (long)d[1], (unsigned long)ticks,
           (long)g->pt[0], (long)g->pt[1], (unsigned)g->duty);
}

int main(void)
{
    static nnik_gc_t gc;
    int c;
    nnik_gc_init(&gc, emit);
    printf("I %ld %ld\n", (long)gc.steps[0], (long)gc.steps[1]);
    while ((c = getchar()) != EOF) {
        int8_t r;
        if (c != '\n') {
            nnik_gc_byte(&gc, (uint8_t)c);
            continue;
        }
        r = nnik_gc_eol(&gc);
        if (r == NNIK_GC_DOLLAR)
            printf("R $\n");
        else if (r <= -100)
            printf("R ALARM:%d\n", -100 - r);
        else if (r < 0)
            printf("R error:%d\n", -r);
        else
            printf("R ok\n");
    }
    nnik_gc_flush(&gc); /* the end of the job, as the simavr harness's final M400 */
    printf("O %lu\n", (unsigned long)gc.overspeed);
    return 0;
}
