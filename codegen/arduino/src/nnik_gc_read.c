/*
 * nnik_gc_read.c - a line's bytes as grbl's protocol layer reads them (nnik/firmware/gcode/
 * reader.py repeats it): realtime bytes (? ! ~ Ctrl-X, which the front end acts on) and bytes
 * >= 0x80 never reach it; blanks, control characters and '/' are dropped; '(' to the first ')'
 * and ';' to the end are comments; lower case is raised; 79 characters fit, more is error 11.
 * A '%' line is a program delimiter (ignored); '*nn' outside a comment ends the line with
 * Marlin's checksum, the XOR of every byte before the '*' (error 39 malformed, 40 wrong); a ';'
 * comment may follow it.
 */
#include "nnik_gcode.h"

enum { RD_WORDS, RD_PAREN, RD_SEMI, RD_SUM, RD_PERCENT, RD_SUM_END };

void nnik_gc_read_reset(nnik_gc_t *g)
{
    g->len = 0;
    g->rd_mode = RD_WORDS;
    g->rd_over = g->rd_xor = g->rd_sum_digits = g->rd_sum_bad = g->rd_sum_blank = 0;
    g->rd_sum = 0;
}

void nnik_gc_byte(nnik_gc_t *g, uint8_t c)
{
    if (c >= 0x80 || c == '?' || c == '!' || c == '~' || c == 0x18)
        return;
    if (g->rd_mode == RD_SUM_END) /* a ';' comment after the checksum */
        return;
    if (g->rd_mode == RD_SUM) {
        if (c == ';') {
            g->rd_mode = RD_SUM_END;
        } else if (c >= '0' && c <= '9' && !g->rd_sum_blank) {
            if (++g->rd_sum_digits > 3)
                g->rd_sum_bad = 1;
            else
                g->rd_sum = (uint16_t)(g->rd_sum * 10 + (c - '0'));
        } else if (c <= ' ') {
            g->rd_sum_blank = g->rd_sum_digits > 0;
        } else {
            g->rd_sum_bad = 1;
        }
        return;
    }
    if (c == '*' && g->rd_mode == RD_WORDS) {
        g->rd_mode = RD_SUM;
        return;
    }
    g->rd_xor ^= c;
    if (g->rd_mode == RD_PAREN) {
        if (c == ')')
            g->rd_mode = RD_WORDS;
    } else if (g->rd_mode != RD_WORDS) {
        /* a ';' comment or a '%' line */
    } else if (c <= ' ' || c == '/') {
    } else if (c == '(') {
        g->rd_mode = RD_PAREN;
    } else if (c == ';') {
        g->rd_mode = RD_SEMI;
    } else if (c == '%' && !g->len) {
        g->rd_mode = RD_PERCENT;
    } else if (g->len >= NNIK_GC_LINE_MAX) {
        g->rd_over = 1;
    } else {
        g->line[g->len++] = (char)(c >= 'a' && c <= 'z' ? c - 32 : c);
    }
}

int8_t nnik_gc_eol(nnik_gc_t *g)
{
    int8_t r;
    g->line_no++;
    g->line[g->len] = 0;
    if (g->rd_mode >= RD_SUM && g->rd_mode != RD_PERCENT && (g->rd_sum_bad || !g->rd_sum_digits || g->rd_sum > 255))
        r = -39;
    else if (g->rd_mode >= RD_SUM && g->rd_mode != RD_PERCENT && g->rd_sum != g->rd_xor)
        r = -40;
    else if (g->rd_over)
        r = -11;
    else if (!g->len)
        r = NNIK_GC_OK;
    else if (g->line[0] == '$')
        r = NNIK_GC_DOLLAR;
    else if (g->alarm)
        r = -9;
    else
        r = nnik_gc_exec(g);
    nnik_gc_read_reset(g); /* g->line keeps its text (a '$' line's, for the front end) until the next byte */
    return r;
}

int8_t nnik_gc_line(nnik_gc_t *g, const char *line)
{
    while (*line)
        nnik_gc_byte(g, (uint8_t)*line++);
    return nnik_gc_eol(g);
}
