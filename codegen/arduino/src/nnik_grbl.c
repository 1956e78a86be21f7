/*
 * nnik_grbl.c - see nnik_grbl.h.  The numbers (error:N, ALARM:N) and the texts are grbl 1.1h's
 * (gnea/grbl: protocol.c, system.c, report.c); docs/grbl_interface.md lists the differences.
 */
#include <setjmp.h>

#include "nnik_grbl.h"
#include "nnik_grbl_config.h"
#include "nnik_flash.h"

volatile uint8_t nnik_grbl_rt[4];

nnik_gc_t nnik_gc;
#define gc (&nnik_gc)
static jmp_buf top;          /* the soft reset lands here */
static uint8_t alarm;        /* the alarm number: G-code locked until $X or a reset */
static uint8_t hold;         /* a feed hold (or M0) waits for '~' */
static uint8_t wco_count;    /* status reports until the next WCO field */
static int32_t check_pt[2]; /* where the machine stood when check mode began */

static NNIK_FLASH const char settings[] = NNIK_GRBL_SETTINGS;

#define TEXT_(x) #x
#define TEXT(x) TEXT_(x)
#define RX_SIZE_TEXT TEXT(NNIK_GRBL_RX_SIZE)

static void puts_f(const char *s)
{
    char c;
    while ((c = (char)NNIK_RD_U8(s++)) != 0)
        nnik_port_putc(c);
}

#define PUTS(str)                                                                                  \
    do {                                                                                           \
        static NNIK_FLASH const char s_[] = str;                                                   \
        puts_f(s_);                                                                                \
    } while (0)

/* v in decimal, less its first `skip` digits */
static void put_num(uint32_t v, uint8_t skip)
{
    char d[10];
    uint8_t k = 0;
    do {
        d[k++] = (char)('0' + v % 10);
        v /= 10;
    } while (v);
    k -= skip;
    while (k)
        nnik_port_putc(d[--k]);
}

#define put_u32(v) put_num((v), 0)

/* v thousandths (um, or a setting) as grbl prints mm: three decimals */
static void put_milli(int32_t v)
{
    uint32_t u = (uint32_t)v;
    if (v < 0) {
        nnik_port_putc('-');
        u = 0u - u;
    }
    put_u32(u / 1000);
    nnik_port_putc('.');
    put_num(u % 1000 + 1000, 1);
}

static void put_xyz(int32_t x, int32_t y, int32_t z)
{
    put_milli(x);
    nnik_port_putc(',');
    put_milli(y);
    nnik_port_putc(',');
    put_milli(z);
}

/* the work offset: the active G54..G59 + G92 (+ the tool length on Z), as grbl's WCO */
static int32_t wco(uint8_t a)
{
    return GC_COORD(gc, GC_WCS(gc), a) + GC_G92(gc, a) + (a == 2 ? GC_TLO(gc) : 0);
}

static void msg_f(const char *s)
{
    PUTS("[MSG:");
    puts_f(s);
    PUTS("]\n");
}

#define MSG(str)                                                                                   \
    do {                                                                                           \
        static NNIK_FLASH const char m_[] = str;                                                   \
        msg_f(m_);                                                                                 \
    } while (0)

/* motion planned or running: grbl's Run (and its "not idle" for $ commands) */
static uint8_t busy(void)
{
#if NNIK_GC_HOLD
    return nnik_port_busy() || gc->pl.count || gc->pending;
#else
    return nnik_port_busy() || gc->pl.count;
#endif
}

static void report(void)
{
    int32_t p[2];
    uint8_t run = busy();
    nnik_port_putc('<');
    if (alarm) {
        PUTS("Alarm");
    } else if (hold) {
        PUTS("Hold:");
        nnik_port_putc(nnik_port_held() ? '0' : '1');
    } else if (GC_CHECK(gc)) {
        PUTS("Check");
    } else if (run) {
        PUTS("Run");
    } else {
        PUTS("Idle");
    }
    PUTS("|MPos:");
    if (GC_CHECK(gc)) {
        p[0] = check_pt[0];
        p[1] = check_pt[1];
    } else {
        nnik_port_where(p);
    }
    put_xyz(p[0], p[1], GC_Z(gc));
    PUTS("|Bf:");
    put_u32(NNIK_PL_N - gc->pl.count);
    nnik_port_putc(',');
    put_u32(nnik_port_rx_free());
    PUTS("|FS:");
    put_u32(run && !hold ? (uint32_t)gc->feed / 1000 : 0);
    nnik_port_putc(',');
    put_u32(gc->spindle ? (uint32_t)gc->s / 1000 : 0);
    if (!wco_count) { /* as grbl: now and then (every 10th report), and in the first */
        wco_count = 10;
        PUTS("|WCO:");
        put_xyz(wco(0), wco(1), wco(2));
        PUTS("|Ov:100,100,100");
    }
    wco_count--;
    PUTS(">\n");
}

/* a reset: the stepper stops at its segment's end, the engine starts again where the motors are
 * (check mode: where they were when it began), the banner follows from nnik_grbl_run */
static void do_reset(void)
{
    int32_t pt[2];
    uint8_t moved;
    nnik_grbl_rt[NNIK_RT_RESET] = 0;
    moved = nnik_port_stop(pt);
    if (GC_CHECK(gc)) {
        pt[0] = check_pt[0];
        pt[1] = check_pt[1];
        moved = 0;
    }
    nnik_gc_place(gc, pt);
    hold = 0;
    nnik_grbl_rt[NNIK_RT_STATUS] = nnik_grbl_rt[NNIK_RT_HOLD] = nnik_grbl_rt[NNIK_RT_RESUME] = 0;
    if (moved && !alarm) { /* grbl: reset while in motion, the position may be lost */
        alarm = 3;
        PUTS("ALARM:3\n");
    }
    longjmp(top, 1);
}

void nnik_grbl_poll(void)
{
    if (nnik_grbl_rt[NNIK_RT_RESET])
        do_reset();
    if (nnik_grbl_rt[NNIK_RT_STATUS]) {
        nnik_grbl_rt[NNIK_RT_STATUS] = 0;
        report();
    }
    if (nnik_grbl_rt[NNIK_RT_HOLD]) {
        nnik_grbl_rt[NNIK_RT_HOLD] = 0;
        if (!alarm) {
            if (GC_CHECK(gc))
                nnik_port_hold(0); /* nothing moves in check mode */
            else
                hold = 1;
        }
    }
    if (nnik_grbl_rt[NNIK_RT_RESUME]) {
        nnik_grbl_rt[NNIK_RT_RESUME] = 0;
        if (hold && !alarm) {
            hold = 0;
            nnik_port_hold(0);
        }
    }
}

void nnik_grbl_wait(void)
{
    nnik_grbl_poll();
    nnik_port_idle();
}

/* until the motion has finished (M2, M30, M400, M0) */
static void sync(void)
{
    while (busy())
        nnik_grbl_wait();
}

#if NNIK_GRBL_SETTING_WRITE
/* [-]digits[.digits] in thousandths (further decimals cut); 0 without digits */
static const char *milli(const char *s, int32_t *v)
{
    int32_t x = 0, f = 100;
    uint8_t neg = 0, any = 0;
    if (*s == '-') {
        neg = 1;
        s++;
    }
    for (; *s >= '0' && *s <= '9'; s++, any = 1)
        if ((x = x * 10 + (*s - '0')) > 1000000L)
            return 0;
    x *= 1000;
    if (*s == '.')
        for (s++; *s >= '0' && *s <= '9'; s++, f /= 10, any = 1)
            x += (*s - '0') * f;
    if (!any)
        return 0;
    *v = neg ? -x : x;
    return s;
}

/* $N=V with the value the build has (1) */
static uint8_t setting_same(const char *l)
{
    int32_t n, v, have;
    const char *p = settings;
    char buf[16];
    uint8_t k;
    if (!(l = milli(l, &n)) || *l++ != '=' || !(l = milli(l, &v)) || *l)
        return 0;
    while (NNIK_RD_U8(p)) {
        for (k = 0; (buf[k] = (char)NNIK_RD_U8(p)) != '\n' && k < sizeof buf - 1; k++, p++)
            ;
        buf[k] = 0;
        p++;
        if (milli(buf + 1, &have) && have == n) {
            for (k = 1; buf[k] != '='; k++)
                ;
            milli(buf + k + 1, &have);
            return have == v;
        }
    }
    return 0;
}
#endif

static int8_t dollar(const char *l)
{
    char c = l[1];
    uint8_t idle = !busy() && !hold && !GC_CHECK(gc);
    if (!c) {
        PUTS("[HLP:$$ $# $G $I $N $x=val $C $X $H ~ ! ? ctrl-x]\n");
        return 0;
    }
    if (c == '$' || c == 'G' || c == 'C' || c == 'X') {
        if (l[2])
            return -3;
        if (c == '$') {
            if ((busy() || hold) && !GC_CHECK(gc))
                return -8; /* grbl: not during a cycle or a hold */
            puts_f(settings);
        } else if (c == 'G') {
            uint8_t i, v[7];
            v[0] = gc->motion;
            v[1] = (uint8_t)(54 + GC_WCS(gc));
            v[2] = (uint8_t)(17 + GC_PLANE(gc));
            v[3] = (uint8_t)(21 - gc->inch);
            v[4] = (uint8_t)(90 + gc->relative);
            v[5] = (uint8_t)(94 - GC_INVT(gc));
            v[6] = gc->spindle ? gc->spindle : 5;
            PUTS("[GC:");
            for (i = 0; i < 7; i++) {
                if (i)
                    nnik_port_putc(' ');
                nnik_port_putc(i < 6 ? 'G' : 'M');
                put_u32(v[i]);
            }
            if (GC_COOLANT(gc) & 1)
                PUTS(" M7");
            if (GC_COOLANT(gc) & 2)
                PUTS(" M8");
            if (!GC_COOLANT(gc))
                PUTS(" M9");
            PUTS(" T");
            put_u32(GC_TOOLNO(gc));
            PUTS(" F");
            put_u32((uint32_t)gc->feed / 1000);
            PUTS(" S");
            put_u32((uint32_t)gc->s / 1000);
            PUTS("]\n");
        } else if (c == 'C') {
            if (GC_CHECK(gc)) { /* leaving check mode resets, as grbl */
                MSG("Disabled");
                PUTS("ok\n");
                do_reset();
            }
            if (!idle || alarm)
                return -8;
            nnik_port_where(check_pt);
            GC_CHECK(gc) = 1;
            MSG("Enabled");
        } else if (alarm) { /* $X */
            alarm = 0;
            gc->alarm = 0;
            MSG("Caution: Unlocked");
        }
        return 0;
    }
    if (!idle && !alarm)
        return -8; /* the rest wants Idle or Alarm */
    if (c == 'H')
        return -5; /* homing is not enabled ($22=0) */
    if (l[2] == 0 && c == '#') {
        uint8_t i;
        for (i = 0; i < 9; i++) { /* G54..G59, G28, G30, G92 */
            PUTS("[G");
            put_u32(i < 6 ? 54 + i : i == 6 ? 28 : i == 7 ? 30 : 92);
            nnik_port_putc(':');
            if (i < 6)
                put_xyz(GC_COORD(gc, i, 0), GC_COORD(gc, i, 1), GC_COORD(gc, i, 2));
            else if (i < 8)
                put_xyz(GC_HOME(gc, i - 6, 0), GC_HOME(gc, i - 6, 1), GC_HOME(gc, i - 6, 2));
            else
                put_xyz(GC_G92(gc, 0), GC_G92(gc, 1), GC_G92(gc, 2));
            PUTS("]\n");
        }
        PUTS("[TLO:");
        put_milli(GC_TLO(gc));
        PUTS("]\n[PRB:0.000,0.000,0.000:0]\n");
        return 0;
    }
    if (l[2] == 0 && c == 'I') {
        PUTS("[VER:1.1h.nnik:" NNIK_GRBL_BUILD "]\n[OPT:V,");
        put_u32(NNIK_PL_N);
        PUTS("," RX_SIZE_TEXT "]\n"); /* the receive buffer, which character-counting senders read */
        return 0;
    }
    if (l[2] == 0 && c == 'N') {
        PUTS("$N0=\n$N1=\n");
        return 0;
    }
    if (c >= '0' && c <= '9') { /* $N=V: the settings are compiled in */
#if NNIK_GRBL_SETTING_WRITE
        if (setting_same(l + 1))
            return 0;
#endif
        MSG("nnik: settings are compiled in");
    }
    return -3;
}

static void answer(int8_t r)
{
    if (r >= 0) {
        PUTS("ok\n");
        return;
    }
    PUTS("error:");
    put_u32((uint32_t)-r);
    nnik_port_putc('\n');
}

/* an alarm from the engine (2: soft limit): hold to a stop, report, wait for the reset */
static void engine_alarm(uint8_t n)
{
    hold = 1;
    nnik_port_hold(1);
    while (!nnik_port_held())
        nnik_grbl_wait();
    alarm = n;
    PUTS("ALARM:");
    put_u32(n);
    nnik_port_putc('\n');
    MSG("Reset to continue");
    for (;;)
        nnik_grbl_wait(); /* '?' answers, Ctrl-X resets (and keeps the alarm) */
}

static void line_end(void)
{
    int8_t r;
    if (alarm && GC_LEN(gc) && GC_LINE(gc)[0] != '$') {
        GC_LEN(gc) = 0; /* grbl's lock: G-code refused in Alarm */
        nnik_gc_eol(gc);
        r = -9;
    } else {
        r = nnik_gc_eol(gc);
    }
    if (r == NNIK_GC_DOLLAR) {
        r = dollar(GC_LINE(gc));
    } else if (r == NNIK_GC_SYNC) {
        sync();
    } else if (r == NNIK_GC_PAUSE) {
        sync();
        if (!GC_CHECK(gc) && !NNIK_GRBL_PAUSE_RESUMES) { /* M0: a feed hold, until '~' */
            hold = 1;
            nnik_port_hold(1);
            while (hold)
                nnik_grbl_wait();
        }
    } else if (r <= -100) {
        engine_alarm((uint8_t)(-100 - r));
    }
    answer(r);
}

void nnik_grbl_run(void)
{
    static uint8_t partial; /* a line has begun */
    setjmp(top);
    partial = 0;
    wco_count = 0;
    PUTS("Grbl 1.1h ['$' for help]\n");
    if (alarm)
        MSG("'$H'|'$X' to unlock");
    for (;;) {
        int16_t c;
        nnik_grbl_poll();
        c = nnik_port_getc();
        if (c < 0) {
            /* nothing more coming: the planner runs out what it holds, to rest (M400's flush) */
            if (!partial && nnik_port_quiet())
                nnik_gc_flush(gc);
#if NNIK_GC_HOLD
            else if (!alarm && gc->pending && nnik_port_room() && nnik_gc_ahead(gc))
                continue; /* while the next line comes: the held block's samples */
#endif
            nnik_port_idle();
        } else if (c == '\n' || c == '\r') {
            partial = 0;
            line_end();
        } else {
            partial = 1;
            nnik_gc_byte(gc, (uint8_t)c);
        }
    }
}
