/* nnik_ctl_wrap_sum.c - nnik_ctl_wrap.c for a controller that keeps a weights' checksum (the neural
 * ones): the harness's call also answers nnik_ctl_sum after the tick (out = duty x, y, sum). */
#include "nnik_ctl.h"

extern uint16_t nnik_ctl_sum;

int8_t nnik_ctl_ik(const int32_t in[4], int32_t out[3])
{
    int16_t d[2];
    nnik_ctl_tick(in, in + 2, d);
    out[0] = d[0];
    out[1] = d[1];
    out[2] = nnik_ctl_sum;
    return 0;
}
