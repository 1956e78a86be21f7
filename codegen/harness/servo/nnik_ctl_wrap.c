/* nnik_ctl_wrap.c - the controller's tick behind the AVR harness's call (in = ref x, ref y, pos x,
 * pos y; out = duty x, y): the harness times this call, so its cycles include this wrapper's few
 * (a call and two stores).  The harness's vectors run in order in one program, so the controller's
 * state carries from tick to tick as on the chip; it starts reset (zeroed statics). */
#include "nnik_ctl.h"

int8_t nnik_ctl_ik(const int32_t in[4], int32_t out[2])
{
    int16_t d[2];
    nnik_ctl_tick(in, in + 2, d);
    out[0] = d[0];
    out[1] = d[1];
    return 0;
}
