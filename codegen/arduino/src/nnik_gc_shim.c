/*
 * nnik_gc_shim.c - TEMPORARY, branch grbl only (see nnik_gc_shim.h): nnik_gc_byte / nnik_gc_eol /
 * nnik_gc_place over today's nnik_gc_line.  Its error numbers come from today's messages (a
 * rough map); the rewritten engine gives grbl's own.
 */
#include <string.h>

#include "nnik_gc_shim.h"
#include "nnik_gcode_config.h"

#ifdef NNIK_GC_SHIM

nnik_gc_shim_t nnik_gc_shim;

void nnik_gc_byte(nnik_gc_t *g, uint8_t c)
{
    nnik_gc_shim_t *s = &nnik_gc_shim;
    (void)g;
    if (s->raw_len < NNIK_GC_LINE_MAX)
        s->raw[s->raw_len++] = (char)c;
    else
        s->over |= 2;
    if (s->comment) { /* grbl's protocol.c: inside a comment only ')' matters */
        if (c == ')' && s->comment == 1)
            s->comment = 0;
    } else if (c <= ' ' || c == '/') {
        /* blanks, control characters, block delete: dropped */
    } else if (c == '(') {
        s->comment = 1;
    } else if (c == ';') {
        s->comment = 2;
    } else if (s->len >= NNIK_GC_CLEAN_MAX - 1) {
        s->over |= 1;
    } else {
        s->line[s->len++] = (char)(c >= 'a' && c <= 'z' ? c - 32 : c);
    }
}

/* today's messages -> grbl's error numbers: a rough map (the rewritten engine gives grbl's own) */
static int8_t code_of(const char *m)
{
    if (m[0] == 'l')
        return -11; /* line too long */
    if (m[0] == 'b' || m[0] == 'n' || (m[0] == 't' && m[4] == 'm' && m[5] == 'a'))
        return -2; /* bad number, number too large, too many decimals */
    if (m[0] == 'r')
        return -25; /* repeated word */
    if (m[0] == 'a' || m[0] == 'R')
        return -33; /* arcs */
    return -20; /* unsupported command */
}

static void reset_reader(nnik_gc_shim_t *s)
{
    s->line[s->len] = 0;
    s->len = s->raw_len = s->over = s->comment = 0;
}

int8_t nnik_gc_eol(nnik_gc_t *g)
{
    nnik_gc_shim_t *s = &nnik_gc_shim;
    int8_t r, pause = 0;
    uint8_t i, k;
    const char *run = s->raw;
    if (s->over & 1) {
        g->line_no++;
        reset_reader(s);
        return -11;
    }
    if (s->len == 0) {
        reset_reader(s);
        return NNIK_GC_OK;
    }
    s->line[s->len] = 0;
    s->raw[s->raw_len] = 0;
    if (s->line[0] == '$') {
        reset_reader(s);
        return NNIK_GC_DOLLAR;
    }
    if (s->over & 2)
        run = s->line; /* a long comment: the cleaned line (no checksum then) */
    /* M0 (pause) and M1 (optional stop: ignored, as grbl 1.1) are not today's engine's: strip */
    for (i = 0; s->line[i]; i++) {
        uint16_t v = 0;
        if (s->line[i] != 'M')
            continue;
        for (k = (uint8_t)(i + 1); s->line[k] >= '0' && s->line[k] <= '9' && k < i + 4; k++)
            v = (uint16_t)(v * 10 + (s->line[k] - '0'));
        if (k == i + 1 || v > 1 || s->line[k] == '.' || (s->line[k] >= '0' && s->line[k] <= '9'))
            continue;
        pause = v == 0 ? 1 : 2;
        memmove(&s->line[i], &s->line[k], (size_t)(s->len - k + 1));
        run = s->line;
        break;
    }
    r = nnik_gc_line(g, run);
    reset_reader(s);
    if (r < 0)
        return code_of(g->msg);
    if (pause == 1) {
        nnik_gc_flush(g);
        return NNIK_GC_PAUSE;
    }
    return r ? NNIK_GC_SYNC : NNIK_GC_OK;
}

void nnik_gc_place(nnik_gc_t *g, const int32_t pt[2])
{
    int32_t in[2];
    nnik_gc_init(g, g->emit);
    g->pt[0] = g->pos[0] = pt[0];
    g->pt[1] = g->pos[1] = pt[1];
    in[0] = NNIK_GC_ORIGIN_X_UM + pt[0];
    in[1] = NNIK_GC_ORIGIN_Y_UM + pt[1];
    NNIK_GC_IK(in, g->steps); /* the motors' steps at every sample are the IK of its point */
    nnik_pl_init(&g->pl, g->pt);
    nnik_sh_init(&g->sh, g->pt);
    memset(&nnik_gc_shim, 0, sizeof nnik_gc_shim);
}

#endif
