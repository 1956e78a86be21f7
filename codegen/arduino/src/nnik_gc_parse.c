/*
 * nnik_gc_parse.c - a cleaned line's words (nnik/firmware/gcode/parse.py repeats it).  Numbers are
 * exact decimals: up to 9 integer digits (more: error 2), decimals past the sixth dropped.  G and
 * M codes are read as code10 = number * 10 + its first decimal.  Within a modal group the last
 * word wins.  A setup M code (anything this machine does not act on) ends the line: the rest are
 * its arguments, and the line does nothing.
 */
#include "nnik_gc_block.h"
#include "nnik_flash.h"
#include "nnik_gcode_config.h"

#ifndef NNIK_GC_MARLIN
#define NNIK_GC_MARLIN 0
#endif
#ifndef NNIK_GC_RULE
#define NNIK_GC_RULE 0
#endif

static const char *scan(const char *s, nnik_num_t *n, int8_t *err)
{
    uint8_t digits = 0, idig = 0, nd = 0;
    n->ip = n->fr = 0;
    n->nd = 0;
    if (*s == '+' || *s == '-')
        if (*s++ == '-')
            n->nd = NUM_NEG;
    while (*s >= '0' && *s <= '9') {
        if (idig == 9) {
            *err = -2;
            return s;
        }
        n->ip = n->ip * 10 + (uint32_t)(*s++ - '0');
        idig++;
    }
    digits = idig;
    if (*s == '.') {
        s++;
        while (*s >= '0' && *s <= '9') {
            if (nd < 6) {
                n->fr = n->fr * 10 + (uint32_t)(*s - '0');
                nd++;
            }
            s++;
            digits++;
        }
    }
    n->nd |= nd;
    if (!digits)
        *err = *s == '#' || *s == '[' ? -41 : -2;
    return s;
}

int32_t nnik_gc_um(const nnik_num_t *n, uint8_t inch)
{
    uint32_t scale = inch ? 25400UL : 1000UL, p = 1, f, v;
    uint8_t k, nd = NUM_ND(n);
    for (k = 0; k < nd; k++)
        p *= 10;
    if (nd < 6)
        f = (n->fr * scale + p / 2) / p;
    else /* six decimals: fr * 25400 needs 35 bits */
        f = (uint32_t)(((uint64_t)n->fr * scale + p / 2) / p);
    if (n->ip > (uint32_t)NNIK_GC_SAT / scale)
        v = (uint32_t)NNIK_GC_SAT;
    else
        v = n->ip * scale + f;
    if (v > (uint32_t)NNIK_GC_SAT)
        v = (uint32_t)NNIK_GC_SAT;
    return (n->nd & NUM_NEG) ? -(int32_t)v : (int32_t)v;
}

#define SET(field, val) (b->field = (uint8_t)(val))

/* G codes (code10) and what each sets: field << 4 | value */
enum { F_MOTION = 1, F_NONMODAL, F_PLANE, F_INCH, F_REL, F_ARC_ABS, F_INVERSE, F_WCS, F_TLO, F_QUIET, F_ERR };
#define A(f, v) (uint8_t)((f) << 4 | (v))
typedef struct {
    uint16_t code;
    uint8_t act;
} gcode_t;
static NNIK_FLASH const gcode_t G_TABLE[] = {
    {0, A(F_MOTION, 0)}, {10, A(F_MOTION, 1)}, {20, A(F_MOTION, 2)}, {30, A(F_MOTION, 3)}, {50, A(F_MOTION, 5)},
    {800, A(F_MOTION, 15)}, {40, A(F_NONMODAL, NM_G4)}, {100, A(F_NONMODAL, NM_G10)}, {280, A(F_NONMODAL, NM_G28)},
    {281, A(F_NONMODAL, NM_G28_1)}, {300, A(F_NONMODAL, NM_G30)}, {301, A(F_NONMODAL, NM_G30_1)},
    {530, A(F_NONMODAL, NM_G53)}, {920, A(F_NONMODAL, NM_G92)}, {921, A(F_NONMODAL, NM_G92_1)},
    {170, A(F_PLANE, 0)}, {180, A(F_PLANE, 1)}, {190, A(F_PLANE, 2)}, {200, A(F_INCH, 1)}, {210, A(F_INCH, 0)},
    {900, A(F_REL, 0)}, {910, A(F_REL, 1)}, {901, A(F_ARC_ABS, 1)}, {911, A(F_ARC_ABS, 0)}, {930, A(F_INVERSE, 1)},
    {940, A(F_INVERSE, 0)}, {431, A(F_TLO, 1)}, {490, A(F_TLO, 0)}, {430, A(F_TLO, 2)}, {540, A(F_WCS, 0)},
    {550, A(F_WCS, 1)}, {560, A(F_WCS, 2)}, {570, A(F_WCS, 3)}, {580, A(F_WCS, 4)}, {590, A(F_WCS, 5)},
    {400, A(F_QUIET, 0)}, {610, A(F_QUIET, 0)}, {611, A(F_QUIET, 0)}, {690, A(F_QUIET, 0)}, {970, A(F_QUIET, 0)},
    {980, A(F_QUIET, 0)}, {990, A(F_QUIET, 0)}, {150, A(F_QUIET, 0)}, {640, A(F_QUIET, 1)},
    {310, A(F_ERR, 0)}, {382, A(F_ERR, 0)}, {383, A(F_ERR, 0)}, {384, A(F_ERR, 0)}, {385, A(F_ERR, 0)},
    {591, A(F_ERR, 1)}, {592, A(F_ERR, 1)}, {593, A(F_ERR, 1)},
};

static int8_t set_field(nnik_blk_t *b, uint8_t f, uint8_t v)
{
    uint8_t *slot = 0;
    switch (f) {
    case F_MOTION: slot = &b->motion; v = v == 15 ? 80 : v; break;
    case F_NONMODAL: slot = &b->nonmodal; break;
    case F_PLANE: slot = &b->plane; break;
    case F_INCH: slot = &b->inch; break;
    case F_REL: slot = &b->relative; break;
    case F_ARC_ABS: slot = &b->arc_abs; break;
    case F_INVERSE: slot = &b->inverse; break;
    case F_TLO: slot = &b->tlo; b->g43 |= v == 2; break;
    case F_WCS: slot = &b->wcs; break;
    case F_QUIET: b->g64 |= v; return 0;
    default: return v ? -29 : -43; /* probing; G59.x */
    }
    *slot = v;
    return 0;
}

/* a G word: 0, 1 (the line is noted: stop reading) or -N */
static int8_t gword(nnik_blk_t *b, const nnik_num_t *n)
{
    uint16_t c;
    uint8_t k;
    uint8_t nd = NUM_ND(n);
    if (n->nd & NUM_NEG)
        return -20;
    if (nd > 1) {
        uint32_t p = 1;
        for (k = 1; k < nd; k++)
            p *= 10;
        if (n->fr % p)
            return -23;
    }
    if (n->ip > 6553)
        return -20;
    c = (uint16_t)(n->ip * 10);
    if (nd) {
        uint32_t p = 1;
        for (k = 1; k < nd; k++)
            p *= 10;
        c = (uint16_t)(c + n->fr / p);
    }
#if NNIK_GC_MARLIN
    switch (c) {
    case 100: case 110: case 120: case 260: case 270: case 290: case 330: case 340: case 350: case 420:
    case 760: case 4250:
        b->noted_line = 1;
        return 1;
    }
#else
    if (c == 290) {
        b->noted_line = 1;
        return 1;
    }
#endif
    /* words left out of this build */
    if ((!NNIK_GC_G5 && c == 50) || (!NNIK_GC_G93 && c == 930) || (!NNIK_GC_PLANES && (c == 180 || c == 190)) ||
        (!NNIK_GC_WCS && (c == 100 || c == 281 || c == 301 || (c >= 550 && c <= 590 && c % 10 == 0))))
        return -20;
    for (k = 0; k < sizeof G_TABLE / sizeof G_TABLE[0]; k++) {
        uint8_t act;
        if (NNIK_RD_U16(&G_TABLE[k].code) != c)
            continue;
        act = NNIK_RD_U8(&G_TABLE[k].act);
        return set_field(b, act >> 4, act & 15);
    }
    if (c % 10) /* a decimal of a code that has none */
        for (k = 0; k < sizeof G_TABLE / sizeof G_TABLE[0]; k++)
            if (NNIK_RD_U16(&G_TABLE[k].code) == c - c % 10 && NNIK_RD_U8(&G_TABLE[k].act) < (F_TLO << 4))
                return -23;
    return -20; /* canned cycles, cutter compensation, rotation, scaling, polar, lathe modes, ... */
}

/* an M word: 0, 1 (the line is noted) or -N */
static int8_t mword(nnik_blk_t *b, const nnik_num_t *n)
{
    uint16_t c;
    if (n->nd & NUM_NEG)
        return -20;
    if (n->ip > 6553) {
        b->noted_line = 1;
        return 1;
    }
    c = (uint16_t)(n->ip * 10);
    if (NUM_ND(n)) {
        uint32_t p = 1;
        uint8_t k;
        for (k = 1; k < NUM_ND(n); k++)
            p *= 10;
        c = (uint16_t)(c + n->fr / p);
    }
    switch (c) {
    case 0: case 10: case 20: case 300: SET(stop, c / 10); return 0;
    case 30: case 40: case 50: SET(spindle, c / 10); return 0;
    case 70: case 80: case 90: SET(coolant, c / 10); return 0;
    case 60: return 0; /* a tool change on a one-tool machine: noted */
    case 4000: b->wait = 1; return 0;
    case 820: case 830: SET(e_rel, c == 830); return 0;
#if NNIK_GC_RULE == 3
    case 3000: b->m300 = 1; return 0;
#endif
    case 970: case 980: case 990: return -42;
    }
    b->noted_line = 1;
    return 1;
}

static int8_t letter_index(char c)
{
    static NNIK_FLASH const char letters[] = "EFHIJKLPQRSTXYZ";
    int8_t i;
    for (i = 0; i < W_COUNT; i++)
        if ((char)NNIK_RD_U8(&letters[i]) == c)
            return i;
    return -1;
}

int8_t nnik_gc_parse(const char *s, nnik_blk_t *b)
{
    uint8_t i;
    int8_t err = 0, r;
    b->have = 0;
    b->motion = b->nonmodal = b->plane = b->inch = b->relative = b->arc_abs = b->inverse = UNSET;
    b->tlo = b->wcs = b->stop = b->spindle = b->coolant = b->e_rel = UNSET;
    b->nonmodal = NM_NONE;
    b->wait = b->m300 = b->noted_line = b->g64 = b->g43 = 0;
    while (*s) {
        nnik_num_t n;
        char c = *s++;
        if (c == '#' || c == '[' || c == ']')
            return -41;
        if (c < 'A' || c > 'Z')
            return -1;
        if (c == 'O') {
            if (*s == '<')
                return -42;
            s = scan(s, &n, &err);
            if (err)
                return err;
            if (*s)
                return -42;
            continue;
        }
        s = scan(s, &n, &err);
        if (err)
            return err;
        if (c == 'G' || c == 'M') {
            r = c == 'G' ? gword(b, &n) : mword(b, &n);
            if (r < 0)
                return r;
            if (r)
                break;
        } else if (c == 'N') {
            if (n.nd & NUM_NEG)
                return -4;
            if (n.ip > 10000000UL)
                return -27;
        } else {
            int8_t w = letter_index(c);
            if (w < 0 || (w == W_E && !NNIK_GC_MARLIN))
                return -20;
            if (HAS(b, w))
                return -25;
            b->v[w] = n;
            b->have |= (uint16_t)(1U << w);
        }
    }
    if (b->noted_line && (b->motion != UNSET || b->nonmodal != NM_NONE ||
                          (b->have & ((1U << W_X) | (1U << W_Y) | (1U << W_Z)))))
        return -20;
    (void)i;
    return 0;
}
