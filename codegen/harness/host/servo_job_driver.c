/* servo_job_driver.c - the stored job's player (codegen/arduino/src/nnik_servo_job.c) on the host:
 * prints the reference of each of argv[1] ticks, "x y" a line (nnik's check against its model). */
#include <stdio.h>
#include <stdlib.h>

#include "nnik_servo_job.h"

int main(int argc, char **argv)
{
    long n = argc > 1 ? atol(argv[1]) : 0, k;
    int32_t ref[2];
    nnik_servo_job_begin();
    for (k = 0; k < n; k++) {
        nnik_servo_job_next(ref);
        printf("%ld %ld\n", (long)ref[0], (long)ref[1]);
    }
    return 0;
}
