/*
 * Generic host driver for any generated nnik IK function (MLP, float or LUT baseline).
 *
 *   cc -std=c99 -DIK_FN=NAME_lut_ik -DIK_HEADER='"NAME_lut.h"' [-DIK_N_IN=2 -DIK_N_OUT=2] \
 *      -I codegen/runtime -I <dir of NAME_lut.h> ik_driver.c NAME_lut.c [-lm]
 *
 * Reads whitespace-separated integers from stdin, IK_N_IN per call (micrometres), and prints
 * one line per call: the IK_N_OUT outputs, then the returned flag. Exit 0 at end of input,
 * 2 on a malformed or incomplete record.
 */
#include <stdio.h>
#include <stdint.h>

#ifndef IK_FN
#error "define IK_FN, e.g. -DIK_FN=galvo_cba2012_lut_ik"
#endif
#ifndef IK_HEADER
#error "define IK_HEADER, e.g. -DIK_HEADER='\"galvo_cba2012_lut.h\"'"
#endif
#include IK_HEADER

#ifndef IK_N_IN
#define IK_N_IN 2
#endif
#ifndef IK_N_OUT
#define IK_N_OUT 2
#endif

int main(void)
{
    int32_t in[IK_N_IN];
    int32_t out[IK_N_OUT];
    long long v;
    int i, r;
    int8_t flag;

    for (;;) {
        for (i = 0; i < IK_N_IN; i++) {
            r = scanf("%lld", &v);
            if (r != 1) {
                if (i == 0 && r == EOF) {
                    return 0;
                }
                fprintf(stderr, "ik_driver: bad or incomplete input record\n");
                return 2;
            }
            if (v < INT32_MIN || v > INT32_MAX) {
                fprintf(stderr, "ik_driver: input %lld is not an int32\n", v);
                return 2;
            }
            in[i] = (int32_t)v;
        }
        for (i = 0; i < IK_N_OUT; i++) {
            out[i] = 0;
        }
        flag = IK_FN(in, out);
        for (i = 0; i < IK_N_OUT; i++) {
            printf("%ld ", (long)out[i]);
        }
        printf("%d\n", (int)flag);
    }
}
