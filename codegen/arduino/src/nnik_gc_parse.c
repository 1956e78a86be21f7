/*
 * nnik_gc_parse.c - a cleaned line's words (nnik/firmware/gcode/parse.py repeats it).  Numbers are
 * exact decimals: up to 9 integer digits (more: error 2), decimals past the sixth dropped.  G and
 * M codes are read as code10 = number * 10 + its first decimal.  Within a modal group the last
 * word wins.  A setup M code (anything this machine does not act on) ends the line: the rest are
 * its arguments, and the line does nothing.
 */
#include "nnik_gc_block.h"
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
        *err = -2;
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

/* a G word: 0, 1 (the line is noted: stop reading) or -N */
static int8_t gword(nnik_blk_t *b, const nnik_num_t *n)
{
    uint16_t c;
    uint8_t nd = NUM_ND(n);
    if (n->nd & NUM_NEG)
        return -20;
    if (nd > 1) {
        uint32_t p = 1;
        uint8_t k;
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
        uint8_t k;
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
    switch (c) {
    case 0: case 10: case 20: case 30: case 50: SET(motion, c / 10); return 0;
    case 800: SET(motion, 80); return 0;
    case 40: SET(nonmodal, NM_G4); return 0;
    case 100: SET(nonmodal, NM_G10); return 0;
    case 280: SET(nonmodal, NM_G28); return 0;
    case 281: SET(nonmodal, NM_G28_1); return 0;
    case 300: SET(nonmodal, NM_G30); return 0;
    case 301: SET(nonmodal, NM_G30_1); return 0;
    case 530: SET(nonmodal, NM_G53); return 0;
    case 920: SET(nonmodal, NM_G92); return 0;
    case 921: SET(nonmodal, NM_G92_1); return 0;
    case 170: case 180: case 190: SET(plane, (c - 170) / 10); return 0;
    case 200: case 210: SET(inch, c == 200); return 0;
    case 900: case 910: SET(relative, c == 910); return 0;
    case 901: case 911: SET(arc_abs, c == 901); return 0;
    case 930: case 940: SET(inverse, c == 930); return 0;
    case 431: SET(tlo, 1); return 0;
    case 490: SET(tlo, 0); return 0;
    case 430: SET(tlo, 2); b->g43 = 1; return 0;
    case 540: case 550: case 560: case 570: case 580: case 590: SET(wcs, (c - 540) / 10); return 0;
    case 400: case 610: return 0;                                  /* grbl's own, nothing to do */
    case 611: case 690: case 970: case 980: case 990: case 150: return 0; /* noted */
    case 640: b->g64 = 1; return 0;
    case 310: case 382: case 383: case 384: case 385: return -43;  /* probing */
    case 591: case 592: case 593: return -29;
    }
    if (c % 10) {
        switch (c - c % 10) {
        case 0: case 10: case 20: case 30: case 50: case 800: case 40: case 100: case 280: case 300: case 530:
        case 920: case 170: case 180: case 190: case 200: case 210: case 900: case 910: case 930: case 940:
        case 540: case 550: case 560: case 570: case 580: case 590:
            return -23;
        }
    }
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
    static const char letters[] = "EFHIJKLPQRSTXYZ";
    int8_t i;
    for (i = 0; i < W_COUNT; i++)
        if (letters[i] == c)
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
