/*
 * nnik_gcode.c - see nnik_gcode.h.  Every rounding here is spelled out because
 * nnik.firmware.gcode (Python) repeats it bit for bit: numbers are parsed to whole micrometres
 * with round half away from zero, arc midpoints are rounded half away from zero, square roots
 * are floors; the planner (nnik_plan.c) and the shaper (nnik_shaper.c) state theirs.
 */
#include "nnik_gcode.h"
#include "nnik_gcode_config.h"
#include "nnik_flash.h"

#if NNIK_GC_SEG_UM < 100 || NNIK_GC_SEG_UM > 5000
#error "NNIK_GC_SEG_UM must be 100..5000 um"
#endif
#if NNIK_GC_TICK_HZ > 12000
#error "NNIK_GC_TICK_HZ above 12 kHz overflows the 32-bit tick count"
#endif

#if defined(__GNUC__)
#define NNIK_NOINLINE __attribute__((noinline)) /* a rare path kept out of nnik_gc_line: ~1 KB less on AVR */
#else
#define NNIK_NOINLINE
#endif

#define POS_LIMIT 268435455L /* 2^28 - 1 um: arc sums stay in int32, products in int64 */
#define MIN_FEED 1000L       /* um per minute */
#define ARC_STACK 32
#define SAMPLE_TICKS (NNIK_GC_TICK_HZ / NNIK_GC_SAMPLE_HZ) /* stepper ticks per sample */
#if NNIK_GC_TICK_HZ % NNIK_GC_SAMPLE_HZ
#error "NNIK_GC_SAMPLE_HZ must divide NNIK_GC_TICK_HZ"
#endif
#define TOOL_SCALED 0x100 /* a tool word: duty | TOOL_SCALED (M4: duty * the segment's speed / feed) */
#define S_FULL (NNIK_GC_S_MAX * 1000L) /* S at full power, in thousandths */

#if NNIK_GC_S_MAX < 1 || NNIK_GC_S_MAX > 9999
#error "NNIK_GC_S_MAX must be 1..9999"
#endif

static NNIK_FLASH const char M_LONG[] = "line too long";
static NNIK_FLASH const char M_COMMENT[] = "unterminated comment";
static NNIK_FLASH const char M_CHAR[] = "unexpected character";
static NNIK_FLASH const char M_WORD[] = "unsupported word %c";
static NNIK_FLASH const char M_BADNUM[] = "bad number after %c";
static NNIK_FLASH const char M_BIG[] = "number too large after %c";
static NNIK_FLASH const char M_DEC[] = "too many decimals after %c";
static NNIK_FLASH const char M_INT[] = "%c needs a whole number";
static NNIK_FLASH const char M_CMD[] = "unsupported %c%d";
static NNIK_FLASH const char M_REPEAT[] = "repeated word %c";
static NNIK_FLASH const char M_TWO[] = "two motion commands";
static NNIK_FLASH const char M_IJ[] = "I/J need G2 or G3";
static NNIK_FLASH const char M_RG[] = "R needs G2 or G3";
static NNIK_FLASH const char M_ARCIJ[] = "arc needs I, J or R";
static NNIK_FLASH const char M_RIJ[] = "arc with both R and I/J";
static NNIK_FLASH const char M_RFULL[] = "R arc ends at its start";
static NNIK_FLASH const char M_CHORD[] = "arc chord longer than 2|R|";
static NNIK_FLASH const char M_FEED[] = "feed below 1 mm/min";
static NNIK_FLASH const char M_RANGE[] = "coordinate out of range";
static NNIK_FLASH const char M_R0[] = "arc radius is zero";
static NNIK_FLASH const char M_OFF[] = "arc end is off the circle";
static NNIK_FLASH const char M_CMDF[] = "unsupported G%d.%c";
static NNIK_FLASH const char M_SUMBAD[] = "bad checksum";
static NNIK_FLASH const char M_SUM[] = "checksum mismatch";
static NNIK_FLASH const char M_PAUSE[] = "M%d pause not supported";
static NNIK_FLASH const char M_NONMODAL[] = "two non-modal commands";
static NNIK_FLASH const char M_AXES[] = "G%d needs X or Y";
static NNIK_FLASH const char M_WITH[] = "G%d with a motion command";
static NNIK_FLASH const char M_DWELL[] = "G4 needs P >= 0";
static NNIK_FLASH const char M_P[] = "P needs G4";
static NNIK_FLASH const char M_TOOL2[] = "two tool commands";
static NNIK_FLASH const char M_NEG[] = "negative %c";
static NNIK_FLASH const char M_ZG[] = "Z needs G0 to G3";

/* message = flash template with %c -> ch, %d -> num */
static int8_t fail(nnik_gc_t *g, const char *tmpl, char ch, int32_t num)
{
    uint8_t i = 0, k;
    char c, digits[11];
    while ((c = (char)NNIK_RD_U8(tmpl++)) != 0 && i < sizeof g->msg - 12) {
        if (c != '%') {
            g->msg[i++] = c;
            continue;
        }
        c = (char)NNIK_RD_U8(tmpl++);
        if (c == 'c') {
            g->msg[i++] = ch;
        } else {
            uint32_t u = num < 0 ? (uint32_t)0 - (uint32_t)num : (uint32_t)num;
            if (num < 0)
                g->msg[i++] = '-';
            k = 0;
            do {
                digits[k++] = (char)('0' + u % 10);
                u /= 10;
            } while (u);
            while (k)
                g->msg[i++] = digits[--k];
        }
    }
    g->msg[i] = 0;
    return -1;
}

/* floor(sqrt(v)) bit by bit, in the width of T (one body for both widths) */
#define NNIK_ISQRT_BODY(T, v)                                                                   \
    T r = 0, b = (T)1 << (sizeof(T) * 8 - 2);                                                   \
    while (b > v)                                                                               \
        b >>= 2;                                                                                \
    while (b) {                                                                                 \
        if (v >= r + b) {                                                                       \
            v -= r + b;                                                                         \
            r = (r >> 1) + b;                                                                   \
        } else {                                                                                \
            r >>= 1;                                                                            \
        }                                                                                       \
        b >>= 2;                                                                                \
    }                                                                                           \
    return (uint32_t)r

uint32_t nnik_isqrt32(uint32_t v)
{
    NNIK_ISQRT_BODY(uint32_t, v);
}

uint32_t nnik_isqrt64(uint64_t v)
{
    if (v < 0x100000000ULL)
        return nnik_isqrt32((uint32_t)v); /* 32-bit arithmetic: far cheaper on AVR */
    {
        NNIK_ISQRT_BODY(uint64_t, v);
    }
}

void nnik_gc_init(nnik_gc_t *g, nnik_gc_emit_fn emit)
{
    int32_t in[2];
    in[0] = NNIK_GC_ORIGIN_X_UM;
    in[1] = NNIK_GC_ORIGIN_Y_UM;
    g->pos[0] = g->pos[1] = 0;
    g->off[0] = g->off[1] = 0;
    NNIK_GC_IK(in, g->steps);
    g->feed = NNIK_GC_FEED_UM_MIN;
    g->line_no = 0;
    g->segments = 0;
    g->blocks = 0;
    g->samples = 0;
    g->overspeed = 0;
    g->settle = 0;
    g->tail_tool = 0;
    g->clamped = 0;
    g->pt[0] = g->pt[1] = 0;
    nnik_pl_init(&g->pl, g->pt);
    nnik_sh_init(&g->sh, g->pt);
    g->motion = 0;
    g->spindle = 0;
    g->s = 0;
    g->z = 0;
    g->tool = g->last_tool = 0;
    g->duty = 0;
    g->inch = 0;
    g->relative = 0;
    g->emit = emit;
    g->msg[0] = 0;
}

int8_t nnik_gc_too_long(nnik_gc_t *g)
{
    g->line_no++;
    return fail(g, M_LONG, 0, 0);
}

/* ---------------------------------------------------------------- motion */
static int32_t iabs32(int32_t v) { return v < 0 ? -v : v; }

/* One stepper segment per sample: shape the planned point, IK, steps from the last sample, and
 * the sample's ticks (stretched to the larger step count if the motors would need more than one
 * step per tick: an overspeed, counted).  M4: the duty scales by the sample's planned speed over
 * its block's nominal speed. */
static void out_sample(nnik_gc_t *g, const int32_t p[2], uint16_t tool, uint32_t v, uint32_t vn)
{
    int32_t in[2], out[2], d[2];
    uint32_t ticks = SAMPLE_TICKS, a;
    nnik_sh_step(&g->sh, p, g->pt);
    in[0] = NNIK_GC_ORIGIN_X_UM + g->pt[0];
    in[1] = NNIK_GC_ORIGIN_Y_UM + g->pt[1];
    if (NNIK_GC_IK(in, out))
        g->clamped++;
    d[0] = out[0] - g->steps[0];
    d[1] = out[1] - g->steps[1];
    a = (uint32_t)iabs32(d[0]);
    if (ticks < a)
        ticks = a;
    a = (uint32_t)iabs32(d[1]);
    if (ticks < a)
        ticks = a;
    if (ticks != SAMPLE_TICKS)
        g->overspeed++;
    g->duty = (uint8_t)tool;
    if (tool & TOOL_SCALED) /* M4: the power follows the planned speed */
        g->duty = (uint8_t)((uint32_t)(uint8_t)tool * (v < vn ? v : vn) / vn);
    g->steps[0] = out[0];
    g->steps[1] = out[1];
    g->segments++;
    g->emit(g, d, ticks);
}

static void sample(nnik_gc_t *g)
{
    nnik_pl_sample_t s;
    nnik_pl_sample(&g->pl, &s);
    g->settle = NNIK_SH_LEN;
    g->tail_tool = s.tool;
    g->samples++;
    out_sample(g, s.p, s.tool, s.v, s.vn);
}

void nnik_gc_flush(nnik_gc_t *g)
{
    int32_t p[2];
    while (nnik_pl_ready(&g->pl, 1))
        sample(g);
    p[0] = g->pl.start[0]; /* at rest at the last block's end: the shaper's tail holds it */
    p[1] = g->pl.start[1];
    while (g->settle) {
        g->settle--;
        out_sample(g, p, g->tail_tool, 0, 1);
    }
}

/* A block from g->pos to (x, y), once the planner has room (sampling the head block if full). */
static void seg_to(nnik_gc_t *g, int32_t x, int32_t y, int32_t feed)
{
    while (nnik_pl_ready(&g->pl, 0))
        sample(g);
    nnik_pl_push(&g->pl, g->off[0] + x, g->off[1] + y, feed, g->tool);
    g->last_tool = g->tool;
    g->pos[0] = x;
    g->pos[1] = y;
    g->blocks++;
}

static void line_to(nnik_gc_t *g, int32_t x, int32_t y, int32_t feed)
{
    if (x == g->pos[0] && y == g->pos[1])
        return;
    seg_to(g, x, y, feed);
}

/* round(a / b) half away from zero, b > 0 */
static int32_t div_round(int64_t a, uint32_t b)
{
    uint64_t u = a < 0 ? (uint64_t)(-a) : (uint64_t)a;
    int32_t q;
    if (u < 0x40000000UL && b < 0x40000000UL) /* the same value by 32-bit division: far cheaper on AVR */
        q = (int32_t)((2 * (uint32_t)u + b) / (2 * b));
    else
        q = (int32_t)((2 * u + b) / (2 * (uint64_t)b));
    return a < 0 ? -q : q;
}

/* x^2 + y^2; with 16-bit operands in 32-bit arithmetic (the same value, far cheaper on AVR) */
static uint64_t sq2(int32_t x, int32_t y)
{
    if (x > -32768L && x < 32768L && y > -32768L && y < 32768L)
        return (uint32_t)(x * x) + (uint32_t)(y * y);
    return (uint64_t)((int64_t)x * x) + (uint64_t)((int64_t)y * y);
}

/* x * r, r >= 0, likewise */
static int64_t mul_r(int32_t x, uint32_t r)
{
    if (x > -65536L && x < 65536L && r < 65536UL) {
        uint32_t p = (uint32_t)(x < 0 ? -x : x) * r;
        return x < 0 ? -(int64_t)p : (int64_t)p;
    }
    return (int64_t)x * (int64_t)r;
}

static uint64_t chord2(const int32_t a[2], const int32_t b[2])
{
    return sq2(b[0] - a[0], b[1] - a[1]);
}

/* Bisect the arc cur -> end (vectors from the centre, at most a quarter turn) until every
 * chord is <= SEG; midpoints are (a + b) scaled to radius r. */
static void arc_piece(nnik_gc_t *g, const int32_t c[2], int32_t cur[2], const int32_t end[2], uint32_t r,
                      int32_t feed)
{
    static int32_t stack[ARC_STACK][2];
    uint8_t top = 0;
    const uint64_t seg2 = (uint64_t)NNIK_GC_SEG_UM * NNIK_GC_SEG_UM;
    stack[0][0] = end[0];
    stack[0][1] = end[1];
    top = 1;
    while (top) {
        int32_t *b = stack[top - 1];
        if (chord2(cur, b) <= seg2 || top == ARC_STACK) {
            cur[0] = b[0];
            cur[1] = b[1];
            top--;
            seg_to(g, c[0] + cur[0], c[1] + cur[1], feed);
        } else {
            int32_t mx = cur[0] + b[0], my = cur[1] + b[1];
            uint32_t m = nnik_isqrt64(sq2(mx, my));
            stack[top][0] = div_round(mul_r(mx, r), m);
            stack[top][1] = div_round(mul_r(my, r), m);
            top++;
        }
    }
}

static void arc_to(nnik_gc_t *g, const int32_t c[2], const int32_t end[2], uint32_t r, int8_t dir,
                   int32_t feed)
{
    int32_t cur[2], e[2], nxt[2];
    cur[0] = g->pos[0] - c[0];
    cur[1] = g->pos[1] - c[1];
    e[0] = end[0] - c[0];
    e[1] = end[1] - c[1];
    for (;;) {
        int64_t cross = (int64_t)cur[0] * e[1] - (int64_t)cur[1] * e[0];
        int64_t dot = (int64_t)cur[0] * e[0] + (int64_t)cur[1] * e[1];
        if (dir < 0)
            cross = -cross;
        if (cross > 0 && dot >= 0) {
            arc_piece(g, c, cur, e, r, feed);
            return;
        }
        nxt[0] = dir > 0 ? -cur[1] : cur[1];
        nxt[1] = dir > 0 ? cur[0] : -cur[0];
        arc_piece(g, c, cur, nxt, r, feed);
    }
}

/* The centre of an R-form arc as an offset ij from its start, for the chord (x, y) and the
 * radius rad (not zero; negative: the long way round), dir > 0 for G3; 0 or an error template.
 *     ij = (x, y) / 2 + sign * (-y, x) * s / (2 d),  s = floor(sqrt(4 rad^2 - d^2))
 * (s = 0 when the chord is longer than 2|rad| by at most the end tolerance), rounded half away
 * from zero, with d = |(x, y)| taken as floor(d * 2^k) / 2^k, 2^29 <= d * 2^k < 2^30: every
 * product stays below 2^61.  The centre lies left of the chord for G3 with a positive R. */
NNIK_NOINLINE static const char *r_centre(int32_t x, int32_t y, int32_t rad, int8_t dir, int32_t ij[2])
{
    uint64_t d2 = sq2(x, y), d2s = d2, r2x4;
    uint32_t ra = (uint32_t)iabs32(rad), s = 0, ds;
    int32_t xs = x, ys = y; /* (x, y) * 2^k: |.| <= d * 2^k < 2^30 */
    if (d2 == 0)
        return M_RFULL;
    r2x4 = 4 * (uint64_t)ra * ra;
    if (r2x4 < d2) {
        if (nnik_isqrt64(d2) > 2 * ra + 5 + ra / 1000)
            return M_CHORD;
    } else {
        s = nnik_isqrt64(r2x4 - d2);
    }
    while (d2s < (1ULL << 58)) {
        d2s <<= 2;
        xs *= 2;
        ys *= 2;
    }
    ds = nnik_isqrt64(d2s);
    if ((dir > 0) != (rad > 0)) {
        xs = -xs;
        ys = -ys;
    }
    ij[0] = div_round(mul_r(x, ds) - mul_r(ys, s), 2 * ds);
    ij[1] = div_round(mul_r(y, ds) + mul_r(xs, s), 2 * ds);
    return 0;
}

/* ---------------------------------------------------------------- parsing */
typedef struct {
    uint8_t have, neg, dot, nd;
    uint16_t ip;
    uint32_t fr;
} num_t;

enum { W_X, W_Y, W_I, W_J, W_R, W_F, W_P, W_S, W_Z, W_COUNT };

/* scan [+-]digits[.digits] at *ps; 0 or an error template */
static const char *scan_num(const char **ps, num_t *n)
{
    const char *s = *ps;
    uint8_t digits = 0;
    n->neg = n->dot = n->nd = 0;
    n->ip = 0;
    n->fr = 0;
    if (*s == '+' || *s == '-')
        n->neg = (*s++ == '-');
    while (*s >= '0' && *s <= '9') {
        if (n->ip > 999) /* a fifth digit */
            return M_BIG;
        n->ip = (uint16_t)(n->ip * 10 + (*s++ - '0'));
        digits++;
    }
    if (*s == '.') {
        s++;
        n->dot = 1;
        while (*s >= '0' && *s <= '9') {
            if (n->nd == 6)
                return M_DEC;
            n->fr = n->fr * 10 + (uint32_t)(*s++ - '0');
            n->nd++;
            digits++;
        }
    }
    if (!digits)
        return M_BADNUM;
    *ps = s;
    n->have = 1;
    return 0;
}

/* the number in um (or um/min): int * scale + round_half_up(frac * scale / 10^nd), signed */
static int32_t to_um(const num_t *n, uint8_t inch)
{
    uint32_t scale = inch ? 25400UL : 1000UL, p = 1, f;
    uint8_t k;
    int32_t v;
    for (k = 0; k < n->nd; k++)
        p *= 10;
    if (n->nd < 6)
        f = (n->fr * scale + p / 2) / p;
    else /* six decimals (Inkscape's gcodetools writes %f): fr * 25400 needs 35 bits */
        f = (uint32_t)(((uint64_t)n->fr * scale + p / 2) / p);
    v = (int32_t)((uint32_t)n->ip * scale + f);
    return n->neg ? -v : v;
}

/* the dwell of G4 P (seconds, rounded to ms) in ticks, rounded down; ms < 2^24 */
static uint32_t dwell_ticks(uint32_t ms)
{
    return ms / 1000 * NNIK_GC_TICK_HZ + ms % 1000 * NNIK_GC_TICK_HZ / 1000;
}

/* a segment without steps: ticks of the stepper at rest with the tool word t (fixed), after the
 * planned motion has come to rest (a stop block) */
static void rest(nnik_gc_t *g, uint32_t ticks, uint16_t t)
{
    int32_t d[2] = {0, 0};
    nnik_gc_flush(g);
    g->tool = g->last_tool = t;
    g->duty = (uint8_t)t;
    g->segments++;
    g->emit(g, d, ticks);
}

/* the tool word at rest (laser: off, as grbl's laser mode; pen: up or down by Z) */
static uint16_t idle_tool(const nnik_gc_t *g)
{
#if NNIK_GC_TOOL == 1
    return g->z > NNIK_GC_PEN_Z_UM ? NNIK_GC_PEN_UP_DUTY : NNIK_GC_PEN_DOWN_DUTY;
#else
    (void)g;
    return 0;
#endif
}

/* the tool word of a move (laser: off for rapids and M5, S's duty for M3, scaled for M4) */
static uint16_t move_tool(const nnik_gc_t *g, uint8_t rapid)
{
#if NNIK_GC_TOOL == 1
    (void)rapid;
    return idle_tool(g);
#else
    uint16_t t;
    if (rapid || !g->spindle)
        return 0;
    t = (uint16_t)((uint32_t)(g->s < S_FULL ? g->s : S_FULL) * 255UL / (uint32_t)S_FULL);
    return g->spindle == 4 ? t | TOOL_SCALED : t;
#endif
}

/* '*nn' at s: the checksum; 0 or an error template */
static const char *checksum(const char *s, uint8_t x)
{
    uint16_t v = 0;
    uint8_t digits = 0;
    while (*s >= '0' && *s <= '9') {
        v = (uint16_t)(v * 10 + (*s++ - '0'));
        if (++digits > 3)
            return M_SUMBAD;
    }
    while (*s == ' ' || *s == '\t' || *s == '\r')
        s++;
    if (!digits || *s || v > 255)
        return M_SUMBAD;
    return v == x ? 0 : M_SUM;
}

static void tool_state(nnik_gc_t *g, const num_t *s, uint8_t spindle, int32_t z)
{
    if (s->have)
        g->s = to_um(s, 0);
    if (spindle != 0xff)
        g->spindle = spindle == 5 ? 0 : spindle;
    g->z = z;
}

int8_t nnik_gc_line(nnik_gc_t *g, const char *line)
{
    char buf[NNIK_GC_LINE_MAX + 1];
    const char *s;
    const char *err;
    uint8_t i = 0, in_comment = 0, wait = 0, motion = 0xff, inch = g->inch, rel = g->relative, x = 0;
    uint8_t nonmodal = 0; /* 4, 28, 92 */
    uint8_t spindle = 0xff;  /* M3, M4, M5 */
    uint32_t blk0 = g->blocks;
    num_t w[W_COUNT];
    int32_t tgt[2], feed, tz;
    char c;

    g->line_no++;
    /* strip blanks and comments, upper-case; '*' ends the line: a checksum of the bytes before */
    for (s = line; (c = *s) != 0; x ^= (uint8_t)c, s++) {
        if (in_comment) {
            if (c == ')')
                in_comment = 0;
            continue;
        }
        if (c == ';')
            break;
        if (c == '*') {
            err = checksum(s + 1, x);
            if (err)
                return fail(g, err, 0, 0);
            break;
        }
        if (c == '(') {
            in_comment = 1;
            continue;
        }
        if (c == ' ' || c == '\t' || c == '\r')
            continue;
        if (i == NNIK_GC_LINE_MAX)
            return fail(g, M_LONG, 0, 0);
        buf[i++] = (c >= 'a' && c <= 'z') ? (char)(c - 32) : c;
    }
    if (in_comment)
        return fail(g, M_COMMENT, 0, 0);
    buf[i] = 0;

    for (i = 0; i < W_COUNT; i++)
        w[i].have = 0;
    if (buf[0] == '%' && !buf[1])
        return 0; /* a program's first or last line ('%'), as CAM posts write it */
    for (s = buf; *s;) {
        num_t n;
        char letter = *s++;
        int8_t idx = -1;
        if (letter < 'A' || letter > 'Z')
            return fail(g, M_CHAR, 0, 0);
        switch (letter) {
        case 'X': idx = W_X; break;
        case 'Y': idx = W_Y; break;
        case 'I': idx = W_I; break;
        case 'J': idx = W_J; break;
        case 'R': idx = W_R; break;
        case 'F': idx = W_F; break;
        case 'P': idx = W_P; break;
        case 'S': idx = W_S; break;
#if NNIK_GC_TOOL == 1
        case 'Z': idx = W_Z; break;
#endif
        case 'N': /* a line number: up to 8 digits, read and ignored */
            for (i = 0; *s >= '0' && *s <= '9'; s++)
                if (++i > 8)
                    return fail(g, M_BIG, letter, 0);
            if (!i)
                return fail(g, M_BADNUM, letter, 0);
            continue;
        case 'G': case 'M': break;
        default: return fail(g, M_WORD, letter, 0);
        }
        err = scan_num(&s, &n);
        if (err)
            return fail(g, err, letter, 0);
        if (idx >= 0) {
            if (w[idx].have)
                return fail(g, M_REPEAT, letter, 0);
            w[idx] = n;
            continue;
        }
        if (letter == 'G' && n.dot && !n.neg && n.nd == 1)
            return fail(g, M_CMDF, (char)('0' + n.fr), n.ip);
        if (n.neg || n.dot)
            return fail(g, M_INT, letter, 0);
        if (letter == 'G') {
            switch (n.ip) {
            case 0: case 1: case 2: case 3:
                if (motion != 0xff)
                    return fail(g, M_TWO, 0, 0);
                motion = (uint8_t)n.ip;
                break;
            case 4: case 28: case 92:
                if (nonmodal)
                    return fail(g, M_NONMODAL, 0, 0);
                nonmodal = (uint8_t)n.ip;
                break;
            case 20: case 21:
                inch = n.ip == 20;
                break;
            case 90: case 91:
                rel = n.ip == 91;
                break;
            case 17: case 40: case 49: case 54: case 64: case 80: case 94:
                break; /* the only plane, compensation, coordinate system, path and feed mode */
            default:
                return fail(g, M_CMD, letter, n.ip);
            }
        } else if (n.ip == 2 || n.ip == 30) {
            wait = 3;
        } else if (n.ip == 400) {
            wait |= 1;
        } else if (n.ip <= 1) {
            return fail(g, M_PAUSE, 0, n.ip);
        } else if (n.ip >= 3 && n.ip <= 5) {
            if (spindle != 0xff)
                return fail(g, M_TOOL2, 0, 0);
            spindle = (uint8_t)n.ip;
        } else {
            return fail(g, M_CMD, letter, n.ip);
        }
    }

    /* check everything before anything changes */
    if (nonmodal && motion != 0xff)
        return fail(g, M_WITH, 0, nonmodal);
    if (w[W_P].have && nonmodal != 4)
        return fail(g, M_P, 0, 0);
    if (w[W_S].have && w[W_S].neg)
        return fail(g, M_NEG, 'S', 0);
    if (w[W_Z].have && nonmodal)
        return fail(g, M_ZG, 0, 0);
    if (motion == 0xff)
        motion = g->motion;
    feed = g->feed;
    if (w[W_F].have) {
        feed = to_um(&w[W_F], inch);
        if (feed < MIN_FEED)
            return fail(g, M_FEED, 0, 0);
    }
    if ((w[W_I].have || w[W_J].have) && (motion < 2 || nonmodal))
        return fail(g, M_IJ, 0, 0);
    if (w[W_R].have && (motion < 2 || nonmodal))
        return fail(g, M_RG, 0, 0);
    for (i = 0; i < 2; i++) {
        tgt[i] = g->pos[i];
        if (w[i].have) {
            int32_t v = to_um(&w[i], inch);
            tgt[i] = rel && nonmodal != 92 ? g->pos[i] + v : v;
        }
        if (tgt[i] > POS_LIMIT || tgt[i] < -POS_LIMIT)
            return fail(g, M_RANGE, 0, 0);
    }
    {
        int32_t z = g->z;
        if (w[W_Z].have) {
            int32_t v = to_um(&w[W_Z], inch);
            z = rel ? z + v : v;
            if (z > POS_LIMIT || z < -POS_LIMIT)
                return fail(g, M_RANGE, 0, 0);
        }
        tz = z;
    }
    if (nonmodal) {
        uint8_t xy = w[W_X].have || w[W_Y].have;
        int32_t v = w[W_P].have ? to_um(&w[W_P], 0) : -1;
        if (nonmodal == 4 && (v < 0 || xy))
            return fail(g, M_DWELL, 0, 0);
        if (nonmodal == 92) {
            int32_t o[2];
            if (!xy)
                return fail(g, M_AXES, 0, 92);
            for (i = 0; i < 2; i++) {
                o[i] = g->off[i] + g->pos[i] - tgt[i];
                if (o[i] > POS_LIMIT || o[i] < -POS_LIMIT)
                    return fail(g, M_RANGE, 0, 0);
            }
            g->off[0] = o[0];
            g->off[1] = o[1];
            g->pos[0] = tgt[0];
            g->pos[1] = tgt[1];
        }
        g->inch = inch;
        g->relative = rel;
        g->feed = feed;
        tool_state(g, &w[W_S], spindle, tz);
        if (nonmodal == 4) {
            uint32_t t = dwell_ticks((uint32_t)v);
            if (t)
                rest(g, t, idle_tool(g));
        } else if (nonmodal == 28) { /* via X Y (if given), then home: where the motors started */
            g->tool = move_tool(g, 1);
            line_to(g, tgt[0], tgt[1], NNIK_GC_MAX_FEED_UM_MIN);
            for (i = 0; i < 2; i++)
                if (w[i].have || !xy)
                    tgt[i] = -g->off[i];
            line_to(g, tgt[0], tgt[1], NNIK_GC_MAX_FEED_UM_MIN);
        }
    } else {
        uint8_t axes = w[W_X].have || w[W_Y].have || w[W_I].have || w[W_J].have || w[W_R].have;
        int32_t c2[2];
        uint32_t r = 0;
        if (axes && motion >= 2) {
            int32_t a0, a1, e0, e1, off[2];
            uint32_t re, tol;
            if (w[W_R].have) {
                int32_t rad = to_um(&w[W_R], inch);
                if (w[W_I].have || w[W_J].have)
                    return fail(g, M_RIJ, 0, 0);
                if (rad == 0)
                    return fail(g, M_R0, 0, 0);
                err = r_centre(tgt[0] - g->pos[0], tgt[1] - g->pos[1], rad, motion == 3 ? 1 : -1, off);
                if (err)
                    return fail(g, err, 0, 0);
            } else if (!w[W_I].have && !w[W_J].have) {
                return fail(g, M_ARCIJ, 0, 0);
            } else {
                off[0] = w[W_I].have ? to_um(&w[W_I], inch) : 0;
                off[1] = w[W_J].have ? to_um(&w[W_J], inch) : 0;
            }
            c2[0] = g->pos[0] + off[0];
            c2[1] = g->pos[1] + off[1];
            if (c2[0] > POS_LIMIT || c2[0] < -POS_LIMIT || c2[1] > POS_LIMIT || c2[1] < -POS_LIMIT)
                return fail(g, M_RANGE, 0, 0);
            a0 = g->pos[0] - c2[0];
            a1 = g->pos[1] - c2[1];
            e0 = tgt[0] - c2[0];
            e1 = tgt[1] - c2[1];
            r = nnik_isqrt64((uint64_t)((int64_t)a0 * a0) + (uint64_t)((int64_t)a1 * a1));
            if (r == 0)
                return fail(g, M_R0, 0, 0);
            re = nnik_isqrt64((uint64_t)((int64_t)e0 * e0) + (uint64_t)((int64_t)e1 * e1));
            tol = 5 + r / 1000;
            if (re == 0 || (re > r ? re - r : r - re) > tol)
                return fail(g, M_OFF, 0, 0);
        }
        /* commit the modal state, then move */
        g->inch = inch;
        g->relative = rel;
        g->motion = motion;
        g->feed = feed;
        tool_state(g, &w[W_S], spindle, tz);
        if (axes) {
            g->tool = move_tool(g, motion == 0);
            int32_t f = motion == 0 ? (int32_t)NNIK_GC_MAX_FEED_UM_MIN : feed;
            if (motion >= 2)
                arc_to(g, c2, tgt, r, motion == 3 ? 1 : -1, f);
            else
                line_to(g, tgt[0], tgt[1], f);
        }
    }
    if (wait & 2) { /* M2/M30 end the program as grbl: G1, G90 */
        g->motion = 1;
        g->relative = 0;
        g->spindle = 0;
    }
    /* a tool word that turns a laser off (M5, S0, M2/M30) or moves the pen, and no segment on
     * this line: the tool changes on the next tick, by a one-tick segment without steps, if the
     * last segment left it otherwise (a new power alone waits for the next cut) */
    if ((spindle != 0xff || w[W_S].have || w[W_Z].have || (wait & 2)) && g->blocks == blk0 &&
        g->last_tool != idle_tool(g) && (NNIK_GC_TOOL == 1 || move_tool(g, 0) == 0))
        rest(g, 1, idle_tool(g));
    if (wait & 1) /* M400, M2, M30: the planner runs out to rest */
        nnik_gc_flush(g);
    return (int8_t)(wait & 1);
}
