/*
 * nnik_imath_host.c - the G-code engine's integer maths (nnik_imath.c) on the host, for the
 * tests: each stdin line "s V" answers floor(sqrt(V)) by nnik_isqrt64, "d HI LO D" answers
 * floor((HI 2^32 + LO) / D) by nnik_div64_32 (HI < D), one decimal a line.
 */
#include <inttypes.h>
#include <stdio.h>

#include "nnik_imath.h"

int main(void)
{
    unsigned long long v, hi, lo, d;
    char op;
    while (scanf(" %c", &op) == 1) {
        if (op == 's' && scanf("%llu", &v) == 1)
            printf("%" PRIu32 "\n", nnik_isqrt64((uint64_t)v));
        else if (op == 'd' && scanf("%llu %llu %llu", &hi, &lo, &d) == 3)
            printf("%" PRIu32 "\n", nnik_div64_32((uint32_t)hi, (uint32_t)lo, (uint32_t)d));
        else
            return 1;
    }
    return 0;
}
