/*
 * Host check driver for a generated MLP, built with -DNNIK_INSTRUMENT:
 *   cc -DNNIK_MODEL=name -DNNIK_MODEL_HEADER='"name.h"' -DNNIK_INSTRUMENT mlp_check.c name.c
 * stdin: "x_um y_um" per line. stdout: "out0 out1 flag total0 total1" per line, then
 * "overflows N saturations M" after the last input.
 */
#include <inttypes.h>
#include <stdio.h>
#include NNIK_MODEL_HEADER

#define NNIK_CAT(a, b) a##b
#define NNIK_XCAT(a, b) NNIK_CAT(a, b)
#define IK NNIK_XCAT(NNIK_MODEL, _ik)
#define LAST_TOTAL NNIK_XCAT(NNIK_MODEL, _last_total)
#define OVERFLOWS NNIK_XCAT(NNIK_MODEL, _overflows)
#define SATURATIONS NNIK_XCAT(NNIK_MODEL, _saturations)

int main(void)
{
    long x, y;
    while (scanf("%ld %ld", &x, &y) == 2) {
        int32_t in[2];
        int32_t out[2];
        int8_t flag;
        in[0] = (int32_t)x;
        in[1] = (int32_t)y;
        flag = IK(in, out);
        printf("%" PRId32 " %" PRId32 " %d %" PRId32 " %" PRId32 "\n", out[0], out[1], (int)flag, LAST_TOTAL[0],
               LAST_TOTAL[1]);
    }
    printf("overflows %" PRIu32 " saturations %" PRIu32 "\n", OVERFLOWS, SATURATIONS);
    return 0;
}
