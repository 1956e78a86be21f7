/*
 * nnik_simavr_wire.h - what both simavr runners (nnik_simavr_job.c, nnik_simavr_pty.c) do once
 * the sketch is loaded: the clock, no host sleeps, INT0/INT1's strict low-level polling off (they
 * share the STEP pins: polled on every cycle while low, 5x the whole run's time; the sketch never
 * enables them), the UART without console echo or poll sleeps, and the pins and the tool's PWM
 * wired to the runner's callbacks (pin codes: port B bit b = b, port D bit b = 8 + b).
 */
#ifndef NNIK_SIMAVR_WIRE_H
#define NNIK_SIMAVR_WIRE_H

#include <stdint.h>

#include <simavr/sim_avr.h>
#include <simavr/sim_irq.h>
#include <simavr/avr_ioport.h>
#include <simavr/avr_uart.h>
#include <simavr/avr_timer.h>
#include <simavr/avr_extint.h>

typedef void (*nnik_irq_fn)(struct avr_irq_t *irq, uint32_t value, void *param);

static void nnik_no_sleep(avr_t *a, avr_cycle_count_t how_long)
{
    (void)a;
    (void)how_long; /* simavr skips the cycles the firmware sleeps through: nothing to wait for */
}

/* returns the UART's input IRQ */
static avr_irq_t *nnik_sim_wire(avr_t *avr, unsigned long clock_hz, nnik_irq_fn on_uart, nnik_irq_fn on_xon,
                                nnik_irq_fn on_xoff, nnik_irq_fn on_pin, nnik_irq_fn on_pwm)
{
    uint32_t flags = 0;
    int i;
    avr->frequency = clock_hz;
    avr->sleep = nnik_no_sleep;
    for (i = 0; i < 8; i++)
        avr_extint_set_strict_lvl_trig(avr, (uint8_t)i, 0);
    avr_ioctl(avr, AVR_IOCTL_UART_GET_FLAGS('0'), &flags);
    flags &= ~(uint32_t)(AVR_UART_FLAG_STDIO | AVR_UART_FLAG_POLL_SLEEP);
    avr_ioctl(avr, AVR_IOCTL_UART_SET_FLAGS('0'), &flags);
    avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUTPUT), on_uart, NULL);
    avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUT_XON), on_xon, NULL);
    avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUT_XOFF), on_xoff, NULL);
    for (i = 2; i <= 7; i++)
        avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ('D'), i), on_pin, (void *)(intptr_t)(8 + i));
    avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ('B'), 0), on_pin, (void *)(intptr_t)0);
    avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_TIMER_GETIRQ('2'), TIMER_IRQ_OUT_PWM0), on_pwm, NULL);
    return avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_INPUT);
}

#endif /* NNIK_SIMAVR_WIRE_H */
