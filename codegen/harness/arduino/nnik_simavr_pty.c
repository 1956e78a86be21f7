/*
 * nnik_simavr_pty - run a G-code sketch (examples/NAME_gcode) on a simulated ATmega328P (simavr,
 * 16 MHz) with its UART0 on a pseudo-terminal, so that an unmodified G-code sender can open
 * /dev/pts/N (at any baud rate: the simulated UART takes one byte per 10 bit times of 115200)
 * and drive it as a real Uno on a USB port.  Simulated time is held to wall time (SPEED, below),
 * so the sender's timeouts and the firmware's timers agree.
 *
 * usage: nnik_simavr_pty FIRMWARE.elf EVENTS_FILE [MAX_SECONDS [SPEED [LINK]]]
 *   stdout     "PTY /dev/pts/N" once the terminal is open, then "C <cycle>" every 10 ms of wall
 *              time: the simulated clock, by which a test bounds its waits (a loaded host runs
 *              the chip slower than wall time)
 *   EVENTS_FILE, with cycle times, as nnik_simavr_job's:
 *     R <cycle> <text>         a line the firmware sent
 *     H <cycle> <text>         a line the host sent (realtime bytes left out)
 *     X <cycle> <hex>          a realtime byte the host sent ('?' '!' '~' 0x18, or >= 0x80)
 *     S <cycle> <motor> <dir>  a rising STEP edge (PD2, PD3) and its DIR level (PD5, PD6)
 *     M <cycle>                the segment marker (PD4) changed
 *     B <cycle> <0|1>          the busy pin (PB0)
 *     T <cycle> <duty>         the tool's PWM (Timer2 OCR2A) changed
 *     Z <cycle>                the chip was reset: a program opened the terminal (below)
 *     E <cycle> <state> 0      the end: "stopped" (SIGTERM/SIGINT), "timeout", "halted", "crashed"
 * The chip starts 0.2 s after a program first opens the terminal, and a program opening it again
 * resets it 0.2 s later, as opening a real Uno's USB port does (DTR): the sender then reads the
 * banner, whatever it flushed on opening.
 *   MAX_SECONDS  simulated seconds before the end (0 or absent: none)
 *   SPEED        simulated seconds per wall second at most (default 1: real time; 0: unpaced)
 *   LINK         a symlink to the terminal to create (and remove at the end)
 */
#define _GNU_SOURCE
#include <errno.h>
#include <fcntl.h>
#include <pty.h>
#include <sys/inotify.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#include "nnik_simavr_wire.h"
#include <simavr/sim_avr.h>
#include <simavr/sim_elf.h>
#include <simavr/sim_irq.h>
#include <simavr/avr_ioport.h>
#include <simavr/avr_uart.h>
#include <simavr/avr_timer.h>
#include <simavr/avr_extint.h>

#define CLOCK_HZ 16000000ULL
#define SLICE_CYCLES 16000ULL /* 1 ms of the chip between looks at the terminal */

static avr_t *avr;
static avr_irq_t *uart_in;
static FILE *ev;
static int master = -1, xoff;
static volatile sig_atomic_t stop;
static unsigned char in_buf[4096], out_buf[65536];
static size_t in_len, in_pos, out_len;
static char chip_line[512], host_line[512];
static size_t chip_len, host_len;
static int pin_state[2][8];
static int duty_seen;

static void on_signal(int sig)
{
    (void)sig;
    stop = 1;
}

static void log_host(unsigned char c)
{
    if (c == '?' || c == '!' || c == '~' || c == 0x18 || c >= 0x80) {
        fprintf(ev, "X %llu %02x\n", (unsigned long long)avr->cycle, c);
        return;
    }
    if (c == '\n' || c == '\r') {
        if (c == '\n' || host_len) {
            host_line[host_len] = 0;
            fprintf(ev, "H %llu %s\n", (unsigned long long)avr->cycle, host_line);
        }
        host_len = 0;
        return;
    }
    if (host_len < sizeof host_line - 1)
        host_line[host_len++] = (char)c;
}

static void pump(void)
{
    while (!xoff && in_pos < in_len) {
        log_host(in_buf[in_pos]);
        avr_raise_irq(uart_in, in_buf[in_pos++]);
    }
    if (in_pos == in_len)
        in_pos = in_len = 0;
}

static void on_xon(struct avr_irq_t *irq, uint32_t value, void *param)
{
    (void)irq; (void)value; (void)param;
    xoff = 0;
    pump();
}

static void on_xoff(struct avr_irq_t *irq, uint32_t value, void *param)
{
    (void)irq; (void)value; (void)param;
    xoff = 1;
}

static void on_uart(struct avr_irq_t *irq, uint32_t value, void *param)
{
    (void)irq; (void)param;
    if (out_len < sizeof out_buf)
        out_buf[out_len++] = (unsigned char)value;
    if (value != '\n') {
        if (chip_len < sizeof chip_line - 1 && value != '\r')
            chip_line[chip_len++] = (char)value;
        return;
    }
    chip_line[chip_len] = 0;
    chip_len = 0;
    fprintf(ev, "R %llu %s\n", (unsigned long long)avr->cycle, chip_line);
}

static void on_pin(struct avr_irq_t *irq, uint32_t value, void *param)
{
    int code = (int)(intptr_t)param; /* port * 8 + bit */
    int port = code / 8, bit = code % 8;
    (void)irq;
    value = value ? 1 : 0;
    if ((int)value == pin_state[port][bit])
        return;
    pin_state[port][bit] = (int)value;
    if (port == 1 && (bit == 2 || bit == 3) && value)
        fprintf(ev, "S %llu %d %d\n", (unsigned long long)avr->cycle, bit - 2, pin_state[1][bit + 3]);
    else if (port == 1 && bit == 4)
        fprintf(ev, "M %llu\n", (unsigned long long)avr->cycle);
    else if (port == 0 && bit == 0)
        fprintf(ev, "B %llu %u\n", (unsigned long long)avr->cycle, value);
}

static void on_pwm(struct avr_irq_t *irq, uint32_t value, void *param)
{
    (void)irq; (void)param;
    if ((int)value == duty_seen)
        return;
    duty_seen = (int)value;
    fprintf(ev, "T %llu %u\n", (unsigned long long)avr->cycle, value);
}

/* the chip asleep: no host sleep (simavr's default sleeps the sleeping time away in real
 * time); the loop below paces simulated time instead */
static double wall_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

/* the terminal: what the host wrote into the chip's receive side, what the chip sent out */
static void exchange(void)
{
    ssize_t n;
    if (in_len < sizeof in_buf) {
        n = read(master, in_buf + in_len, sizeof in_buf - in_len);
        if (n > 0)
            in_len += (size_t)n;
    }
    pump();
    if (out_len) {
        n = write(master, out_buf, out_len);
        if (n > 0) {
            memmove(out_buf, out_buf + n, out_len - (size_t)n);
            out_len -= (size_t)n;
        }
    }
}

int main(int argc, char **argv)
{
    elf_firmware_t fw;
    struct termios tio;
    char name[256];
    const char *link_path = argc > 5 ? argv[5] : NULL;
    double max_s = argc > 3 ? atof(argv[3]) : 0, speed = argc > 4 ? atof(argv[4]) : 1.0, t0;
    unsigned long long limit = max_s > 0 ? (unsigned long long)(max_s * CLOCK_HZ) : 0;
    const char *state = "stopped";
    int slave, rc, watch_fd;
    double reset_at = -1, clock_said = 0;
    int started = 0;

    if (argc < 3 || argc > 6) {
        fprintf(stderr, "usage: %s FIRMWARE.elf EVENTS_FILE [MAX_SECONDS [SPEED [LINK]]]\n", argv[0]);
        return 2;
    }
    memset(&fw, 0, sizeof fw);
    if (elf_read_firmware(argv[1], &fw) != 0) {
        fprintf(stderr, "cannot read %s\n", argv[1]);
        return 2;
    }
    ev = fopen(argv[2], "w");
    if (!ev) {
        fprintf(stderr, "cannot write %s\n", argv[2]);
        return 2;
    }
    if (openpty(&master, &slave, name, NULL, NULL) != 0) {
        perror("openpty");
        return 2;
    }
    /* raw, no echo: nothing the chip sends comes back to it before a sender opens the terminal */
    tcgetattr(slave, &tio);
    cfmakeraw(&tio);
    cfsetispeed(&tio, B115200);
    cfsetospeed(&tio, B115200);
    tcsetattr(slave, TCSANOW, &tio);
    fcntl(master, F_SETFL, fcntl(master, F_GETFL) | O_NONBLOCK);
    watch_fd = inotify_init1(IN_NONBLOCK);
    if (watch_fd < 0 || inotify_add_watch(watch_fd, name, IN_OPEN) < 0)
        perror("inotify");
    if (link_path) {
        unlink(link_path);
        if (symlink(name, link_path) != 0)
            perror("symlink");
    }
    signal(SIGTERM, on_signal);
    signal(SIGINT, on_signal);
    signal(SIGPIPE, SIG_IGN);

    avr = avr_make_mcu_by_name("atmega328p");
    if (!avr) {
        fprintf(stderr, "simavr has no atmega328p\n");
        return 2;
    }
    avr_init(avr);
    avr->frequency = CLOCK_HZ;
    avr_load_firmware(avr, &fw);
    uart_in = nnik_sim_wire(avr, CLOCK_HZ, on_uart, on_xon, on_xoff, on_pin, on_pwm);

    printf("PTY %s\n", name);
    fflush(stdout);
    t0 = wall_now();
    while (!stop) {
        unsigned long long end = avr->cycle + SLICE_CYCLES;
        while (started && avr->cycle < end) {
            rc = avr_run(avr);
            if (rc == cpu_Done || rc == cpu_Crashed) {
                state = rc == cpu_Done ? "halted" : "crashed";
                goto out;
            }
        }
        if (!started) { /* no program has opened the terminal yet: the chip waits in reset */
            struct timespec ts = {0, 1000000};
            nanosleep(&ts, NULL);
            t0 = wall_now() - (double)avr->cycle / CLOCK_HZ / (speed > 0 ? speed : 1);
        }
        exchange();
        if (watch_fd >= 0) {
            char evbuf[512];
            if (read(watch_fd, evbuf, sizeof evbuf) > 0) /* opened: reset as DTR would, shortly */
                reset_at = wall_now() + 0.2;
        }
        if (reset_at > 0 && wall_now() >= reset_at && !started) {
            reset_at = -1;
            started = 1;
        } else if (reset_at > 0 && wall_now() >= reset_at) {
            reset_at = -1;
            avr_reset(avr);
            xoff = 0;
            in_len = in_pos = 0;
            chip_len = 0;
            fprintf(ev, "Z %llu\n", (unsigned long long)avr->cycle);
        }
        if (limit && avr->cycle > limit) {
            state = "timeout";
            break;
        }
        if (wall_now() - clock_said >= 0.01) {
            clock_said = wall_now();
            printf("C %llu\n", (unsigned long long)avr->cycle);
            fflush(stdout);
        }
        if (speed > 0) { /* ahead of the wall clock: wait for it */
            double ahead = (double)avr->cycle / CLOCK_HZ / speed - (wall_now() - t0);
            if (ahead > 0.0005) {
                struct timespec ts = {0, (long)((ahead > 0.01 ? 0.01 : ahead) * 1e9)};
                nanosleep(&ts, NULL);
            }
        }
    }
out:
    exchange();
    fprintf(ev, "E %llu %s 0\n", (unsigned long long)avr->cycle, state);
    fclose(ev);
    if (link_path)
        unlink(link_path);
    close(slave);
    close(master);
    return 0;
}
