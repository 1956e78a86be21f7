/*
 * nnik_servo.c - the closed-loop runtime on the Uno: encoder decoding, PWM, the tick (see
 * nnik_servo.h for the pin map). Compiles to nothing but on an ATmega328P-class AVR.
 */
#if defined(__AVR_ATmega328P__) || defined(__AVR_ATmega328__) || defined(__AVR_ATmega168__)
#include <avr/interrupt.h>
#include <avr/io.h>

#include "nnik_ctl.h"
#include "nnik_servo_config.h" /* the controller; NNIK_SERVO_OCR1A in an exported library */
#include "nnik_servo.h"

volatile int32_t nnik_servo_count[2];
volatile int32_t nnik_servo_pos[2];
volatile int16_t nnik_servo_duty[2];
volatile uint16_t nnik_servo_sum;
#if defined(NNIK_CTL_NN_AXES) || defined(NNIK_CTL_NN_VECTOR)
#define NNIK_SERVO_LEARNS 1 /* the controller keeps weights: their checksum is published each tick */
#endif
static uint8_t enc_prev;         /* PINC's four encoder bits at the last interrupt */
static volatile uint16_t enc16[2]; /* the counts modulo 2^16: the interrupt's 16-bit work */
static uint16_t enc16_seen[2];   /* enc16 when nnik_servo_count was last brought up to date */

/* count change for (previous state << 2 | new state), a state being A | B << 1 (Gray order
 * 0 1 3 2 forward); 0 for no change and for a skipped state (both pins changed: a lost edge) */
static const int8_t QDEC[16] = {0, 1, -1, 0, -1, 0, 0, 1, 1, 0, 0, -1, 0, -1, 1, 0};

ISR(PCINT1_vect)
{
    uint8_t now = PINC & 0x0F;
    uint8_t prev = enc_prev;
    enc_prev = now;
    enc16[0] += (int16_t)QDEC[(uint8_t)((prev & 3) << 2) | (now & 3)];
    enc16[1] += (int16_t)QDEC[(uint8_t)(prev & 0x0C) | (now >> 2)];
}

/* nnik_servo_count brought up to date from the 16-bit counts (interrupts off; fewer than 32,768
 * counts since the last call: the tick calls it every tick) */
static void enc_update(void)
{
    uint8_t a;
    for (a = 0; a < 2; a++) {
        uint16_t c = enc16[a];
        nnik_servo_count[a] += (int16_t)(c - enc16_seen[a]);
        enc16_seen[a] = c;
    }
}

void nnik_servo_begin(int32_t x, int32_t y)
{
    nnik_servo_count[0] = x;
    nnik_servo_count[1] = y;
    nnik_ctl_reset();
    DDRC &= (uint8_t)~0x0F;                               /* encoder inputs */
    DDRB |= _BV(PB0) | _BV(PB3) | _BV(PB5);               /* DIR X, PWM X, busy */
    DDRD |= _BV(PD3) | _BV(PD7);                          /* PWM Y, DIR Y */
    PORTB &= (uint8_t)~(_BV(PB0) | _BV(PB3) | _BV(PB5));
    PORTD &= (uint8_t)~(_BV(PD3) | _BV(PD7));
    enc_prev = PINC & 0x0F;
    PCMSK1 = 0x0F;
    PCIFR = _BV(PCIF1);
    PCICR |= _BV(PCIE1);
    TCCR2A = _BV(WGM21) | _BV(WGM20);                     /* fast PWM, outputs off (duty 0) */
    TCCR2B = _BV(CS21);                                   /* /8: 7.8 kHz */
    OCR2A = 0;
    OCR2B = 0;
    TCCR1A = 0;
    TCCR1B = _BV(WGM12) | _BV(CS11);                      /* CTC on OCR1A, /8 */
    OCR1A = NNIK_SERVO_OCR1A;
    TCNT1 = 0;
    TIFR1 = _BV(OCF1A);
    TIMSK1 = _BV(OCIE1A);
}

ISR(TIMER1_COMPA_vect)
{
    int32_t pos[2], ref[2];
    int16_t duty[2];
    uint8_t a;
    enc_update();                  /* interrupts are off: both counts at the same instant */
    pos[0] = nnik_servo_count[0];
    pos[1] = nnik_servo_count[1];
    sei();                         /* the encoder may preempt the computation from here on */
    nnik_servo_pos[0] = pos[0];
    nnik_servo_pos[1] = pos[1];
    nnik_servo_reference(ref);
    PORTB |= _BV(PB5);
    nnik_ctl_tick(ref, pos, duty);
    a = (uint8_t)(duty[0] < 0 ? -duty[0] : duty[0]);
    if (duty[0] < 0)
        PORTB |= _BV(PB0);
    else
        PORTB &= (uint8_t)~_BV(PB0);
    OCR2A = a;
    if (a)
        TCCR2A |= _BV(COM2A1);
    else
        TCCR2A &= (uint8_t)~_BV(COM2A1);
    a = (uint8_t)(duty[1] < 0 ? -duty[1] : duty[1]);
    if (duty[1] < 0)
        PORTD |= _BV(PD7);
    else
        PORTD &= (uint8_t)~_BV(PD7);
    OCR2B = a;
    if (a)
        TCCR2A |= _BV(COM2B1);
    else
        TCCR2A &= (uint8_t)~_BV(COM2B1);
    nnik_servo_duty[0] = duty[0];
    nnik_servo_duty[1] = duty[1];
    PORTB &= (uint8_t)~_BV(PB5);
#ifdef NNIK_SERVO_LEARNS
    nnik_servo_sum = nnik_ctl_sum; /* after the busy pin: the check's copy, not the controller's work */
#endif
}
#endif
