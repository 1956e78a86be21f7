/*
 * nnik_servo.h - the closed-loop XY table's firmware runtime on the Uno (ATmega328P, 16 MHz;
 * issue 28): two quadrature encoders, two sign-magnitude PWM outputs and the controller's tick.
 *
 * Pin map (docs/closed_loop.md):
 *   encoders  X A = A0 (PC0), X B = A1 (PC1), Y A = A2 (PC2), Y B = A3 (PC3): one PCINT1
 *             interrupt for all four pins, 4x quadrature decoding by a transition table
 *   PWM       Timer2 fast PWM 8-bit (prescaler 8: 7.8 kHz), X on D11 (OC2A, PB3), Y on D3
 *             (OC2B, PD3); duty 0 disconnects the output (fast PWM's OCR 0 would still pulse)
 *   DIR       X = D8 (PB0), Y = D7 (PD7): high for a negative duty
 *   tick      Timer1 CTC (prescaler 8, OCR1A = NNIK_SERVO_OCR1A: 9999 = 5 ms)
 *   busy      D13 (PB5) high while the tick computes (the controller and the outputs' writes)
 *
 * The tick interrupt latches both counts with interrupts off, re-enables interrupts (the encoder
 * interrupt may preempt the computation, so no edge waits for it), takes the tick's reference
 * from nnik_servo_reference() (the application's: a stored job, a harness feed), calls
 * nnik_ctl_tick() and writes PWM and DIR.
 */
#ifndef NNIK_SERVO_H
#define NNIK_SERVO_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#ifndef NNIK_SERVO_OCR1A
#define NNIK_SERVO_OCR1A 9999 /* tick = (OCR1A + 1) * 8 / F_CPU: 5 ms at 16 MHz */
#endif

/* The encoder counts (x, y) as of the last tick (the encoder interrupt counts modulo 2^16; each
 * tick brings these up to date: fewer than 32,768 counts a tick, 6.5 m/s at 2.5 um). */
extern volatile int32_t nnik_servo_count[2];
/* The counts the last tick latched, and its duties (sign: direction). */
extern volatile int32_t nnik_servo_pos[2];
extern volatile int16_t nnik_servo_duty[2];
/* A learning controller's weights' checksum after the last tick (nnik_ctl_sum; 0 for the fixed-gain
 * controllers): volatile, so a link-time optimised sketch keeps it for the co-simulation to read. */
extern volatile uint16_t nnik_servo_sum;

/* Set up the pins, the encoder interrupt, the PWM and the tick (counts start at x, y); the
 * caller enables interrupts. */
void nnik_servo_begin(int32_t x, int32_t y);

/* The application's: the reference (x, y counts) for the tick being computed. Called from the
 * tick interrupt, once per tick, interrupts enabled. */
void nnik_servo_reference(int32_t ref[2]);

#ifdef __cplusplus
}
#endif

#endif /* NNIK_SERVO_H */
