/*
 * nnik_ctl_excite.c - the excitation's player behind the controller interface (nnik_ctl.h), and
 * its per-tick log (nnik_excite.h). The duty table is nnik_excite_duties.h (PROGMEM on the AVR).
 */
#include <stdio.h>

#include "nnik_ctl.h"
#include "nnik_excite.h"
#include "nnik_excite_duties.h"

#ifdef __AVR__
#include <avr/interrupt.h>
#define DUTY(k, a) ((int16_t)pgm_read_word(&nnik_excite_duties[k][a]))
#define LOCK() uint8_t sreg_ = SREG; cli()
#define UNLOCK() SREG = sreg_
#else
#define DUTY(k, a) (nnik_excite_duties[k][a])
#define LOCK()
#define UNLOCK()
#endif

#define RING 8 /* rows: 40 ms of slack at 5 ms ticks */

struct row {
    uint16_t k;
    int16_t duty[2];
    int32_t count[2];
};

static struct row ring[RING];
static volatile uint8_t head, tail; /* head: written by the tick; tail: read by the loop */
static volatile uint16_t played, lost;

void nnik_ctl_reset(void)
{
    head = tail = 0;
    played = lost = 0;
}

void nnik_ctl_tick(const int32_t ref[2], const int32_t pos[2], int16_t duty[2])
{
    uint16_t k = played;
    (void)ref;
    if (k >= NNIK_EXCITE_TICKS) {
        duty[0] = duty[1] = 0; /* the end: the motors stop */
        return;
    }
    duty[0] = DUTY(k, 0);
    duty[1] = DUTY(k, 1);
    if ((uint8_t)(head - tail) < RING) {
        struct row *r = &ring[head % RING];
        r->k = k;
        r->duty[0] = duty[0];
        r->duty[1] = duty[1];
        r->count[0] = pos[0];
        r->count[1] = pos[1];
        head++;
    } else {
        lost++;
    }
    played = k + 1;
}

/* duty / NNIK_DUTY_MAX with 6 decimals, rounded half away from zero */
static int fraction(char *s, int16_t d)
{
    uint32_t m = (uint32_t)(d < 0 ? -(int32_t)d : d);
    uint32_t q = (m * 1000000UL + NNIK_DUTY_MAX / 2) / NNIK_DUTY_MAX;
    return sprintf(s, "%s%lu.%06lu", d < 0 ? "-" : "", (unsigned long)(q / 1000000UL),
                   (unsigned long)(q % 1000000UL));
}

uint8_t nnik_excite_line(char buf[NNIK_EXCITE_LINE_MAX])
{
    struct row r;
    uint32_t t;
    int n;
    LOCK();
    if (head == tail) {
        UNLOCK();
        return 0;
    }
    r = ring[tail % RING];
    tail++;
    UNLOCK();
    t = (uint32_t)r.k * NNIK_EXCITE_TICK_US;
    n = sprintf(buf, "%lu.%06lu,", (unsigned long)(t / 1000000UL), (unsigned long)(t % 1000000UL));
    n += fraction(buf + n, r.duty[0]);
    buf[n++] = ',';
    n += fraction(buf + n, r.duty[1]);
    n += sprintf(buf + n, ",%ld,%ld\n", (long)r.count[0], (long)r.count[1]);
    return (uint8_t)n;
}

uint8_t nnik_excite_done(void)
{
    uint8_t done;
    LOCK();
    done = played >= NNIK_EXCITE_TICKS && head == tail;
    UNLOCK();
    return done;
}

uint16_t nnik_excite_lost(void)
{
    uint16_t n;
    LOCK();
    n = lost;
    UNLOCK();
    return n;
}
