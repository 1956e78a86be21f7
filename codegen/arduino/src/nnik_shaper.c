/* nnik_shaper.c - see nnik_shaper.h. */
#include "nnik_shaper.h"


void nnik_sh_init(nnik_shaper_t *sh, const int32_t p[2])
{
    uint8_t a;
#if NNIK_SH_LEN > 0
    uint8_t *z = (uint8_t *)sh;
    uint16_t i;
    for (i = 0; i < sizeof *sh; i++)
        z[i] = 0;
    sh->ms = NNIK_SH_LEN - 1; /* m: the sample before the first */
#endif
    for (a = 0; a < 2; a++)
        sh->last[a] = p[a];
}
