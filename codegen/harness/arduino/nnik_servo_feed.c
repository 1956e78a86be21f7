/*
 * nnik_servo_feed.c - the co-simulation build's main and reference (phase A of issue 28's item 5):
 * the harness (nnik_simavr_servo.c) writes each tick's reference into nnik_servo_feed (found by
 * its ELF symbol) before the tick; the main loop sleeps (idle) between interrupts, so every cycle
 * the chip is awake is interrupt work (the harness counts them: the CPU load).
 */
#include <avr/interrupt.h>
#include <avr/sleep.h>

#include "nnik_servo.h"

volatile int32_t nnik_servo_feed[2];

void nnik_servo_reference(int32_t ref[2])
{
    ref[0] = nnik_servo_feed[0];
    ref[1] = nnik_servo_feed[1];
}

int main(void)
{
    nnik_servo_begin(0, 0); /* the harness writes the start counts into nnik_servo_count */
    set_sleep_mode(SLEEP_MODE_IDLE);
    sleep_enable();
    sei();
    for (;;)
        sleep_cpu();
}
