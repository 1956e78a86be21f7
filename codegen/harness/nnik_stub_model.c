/*
 * Reference stub with the model API, used to measure the model's own flash and
 * RAM: the harness is linked once with the real model and once with this stub,
 * and the difference of the two images is reported as the model's contribution
 * (including any runtime/libm routines only the model pulls in).
 *
 * Compiled with -DNNIK_IK=<NAME>_ik -DNNIK_N_IN=.. -DNNIK_N_OUT=..
 */
#include <stdint.h>

int8_t NNIK_IK(const int32_t in_um[NNIK_N_IN], int32_t out[NNIK_N_OUT])
{
    uint8_t i;
    for (i = 0; i < NNIK_N_OUT; i++)
        out[i] = in_um[i < NNIK_N_IN ? i : 0];
    return 0;
}
