/*
 * nnik_simavr_job - run a G-code sketch (examples/NAME_gcode) on a simulated ATmega328P or
 * ATmega2560 (simavr, 16 MHz), send it a job over UART0 as a G-code sender does and record, with
 * cycle times:
 *
 *   R <cycle> <text>        a line the firmware printed (banner, "ok", "error:...", "[MSG:...]")
 *   D <cycle> <text>        the answer to the drain query sent after the job (DRAIN below);
 *                           the cycle is when the motion pin (PD7) last fell: the machine's
 *                           queue ran dry after its last tick (0: no segment ever ran)
 *   S <cycle> <motor> <dir> a rising edge on a STEP pin (motor 0: PD2, 1: PD3) and the DIR
 *                           pin level then (PD5, PD6)
 *   M <cycle>               the segment marker (PD4) changed: a segment started
 *   B <cycle> <0|1>         the busy pin (PB0): a segment is being computed
 *   T <cycle> <duty>        the tool's PWM (Timer2's OCR2A, as simavr's timer reports it in
 *                           fast PWM mode; OC2A is D11 = PB3 on the Uno, D10 = PB4 on the Mega)
 *                           changed
 *   K <sp_low> <ramend>      the lowest stack pointer after start-up, and the RAM's last address
 *   E <cycle> <state> <replies>   the end (state: "done", "halted", "timeout", "crashed")
 *
 * The sketch drives raw PORTD/PORTB bits, the same port bits on both chips.
 *
 * usage: nnik_simavr_job [-m MCU] [-e EVENTS] [-p PROFILE] [-c RX_BYTES] FIRMWARE.elf JOB_LINES MAX_SECONDS
 * JOB_LINES holds the lines to send, one per line (a '\r' ends one too: the firmware answers it,
 * so "\r\n" is a line and an empty one).  The first line with text the firmware prints
 * (its banner: "nnik NAME ready", or grbl's "Grbl 1.1h ['$' for help]") starts the job; a line that
 * starts with "ok" or "error:" answers the oldest line in flight; any other line is only
 * recorded.  The streaming protocol (grbl's wiki, "Interfacing with Grbl"):
 *   send-response (default): one line in flight, the next sent on the answer to the previous;
 *   -c RX_BYTES, character counting: lines go out while the bytes of the lines not yet answered
 *   (each with its '\n') stay within RX_BYTES, the firmware's receive buffer, so that the buffer
 *   never overflows and the next lines wait there while the firmware works; a line longer than
 *   RX_BYTES goes out alone.  After the answer to the last line the harness sends DRAIN (M400: the sketch
 * answers it once its segment queue is empty and the last step is out), so the run covers all
 * the motion however the job ends; the run ends with the answer to DRAIN, after MAX_SECONDS of
 * simulated time, when the firmware halts (the self-test) or when it crashes.
 * With -e, the S/M/B/T events go to the file EVENTS as binary records instead of text lines
 * (struct event below: little-endian uint64 cycle, uint32 tag 'S'/'M'/'B'/'T', int32 value: for
 * S motor | dir << 1, for B the level, for T the duty, for M 0), and stdout keeps R/D/E, each
 * flushed as it is printed (a reader shows the job's progress from the answers).
 * MCU: atmega328p (default) or atmega2560.
 * With -p PROFILE, the cycles of every instruction run while the busy pin (PB0) is high, summed per
 * address, go to PROFILE as lines "<byte address in hex> <cycles>" (nnik.bench.sample_profile).
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "nnik_simavr_wire.h"
#include <simavr/sim_avr.h>
#include <simavr/sim_elf.h>
#include <simavr/sim_irq.h>
#include <simavr/avr_ioport.h>
#include <simavr/avr_uart.h>
#include <simavr/avr_timer.h>
#include <simavr/avr_extint.h>

#define CLOCK_HZ 16000000UL
#define DRAIN "M400\n"

struct event {
    uint64_t cycle;
    uint32_t tag;
    int32_t value;
};

#define EVENT_BUF 4096

static avr_t *avr;
static FILE *events;          /* NULL: events as text lines on stdout */
static struct event ebuf[EVENT_BUF];
static size_t n_ebuf;
static int started;           /* the firmware printed its first line */
static avr_irq_t *uart_in;
static char *job;             /* all lines, '\n'-terminated */
static size_t job_len, job_pos, line_end;
static int n_lines, n_replies, xoff;
static size_t rx_bytes;       /* -c: the receive buffer's bytes (character counting); 0: send-response */
static size_t *flight;        /* the lengths of the lines in flight (sent, not yet answered), a ring */
static size_t n_flight, flight_head, flight_bytes, flight_cap;
static int pin_state[2][8];   /* [port B, D][bit]: last level seen */
static char out_line[256];
static size_t out_len;
static unsigned long long idle_fall; /* the motion pin's last falling edge */
static int duty_seen;                /* the tool's last duty (0 at reset) */
static unsigned sp_low = 0xffff; /* the lowest stack pointer seen */
#define PROF_WORDS (1u << 17)          /* 256 KB of flash */
static unsigned long long *prof;     /* -p: busy cycles per instruction word */

static void flush_events(void)
{
    if (n_ebuf && fwrite(ebuf, sizeof ebuf[0], n_ebuf, events) != n_ebuf) {
        fprintf(stderr, "cannot write the events\n");
        exit(2);
    }
    n_ebuf = 0;
}

static void event(char tag, int value)
{
    if (!events) {
        if (tag == 'S')
            printf("S %llu %d %d\n", (unsigned long long)avr->cycle, value & 1, value >> 1);
        else if (tag == 'M')
            printf("M %llu\n", (unsigned long long)avr->cycle);
        else
            printf("%c %llu %d\n", tag, (unsigned long long)avr->cycle, value);
        return;
    }
    ebuf[n_ebuf].cycle = avr->cycle;
    ebuf[n_ebuf].tag = (uint32_t)(unsigned char)tag;
    ebuf[n_ebuf].value = value;
    if (++n_ebuf == EVENT_BUF)
        flush_events();
}

/* no host sleep while the firmware sleeps: simavr then skips the cycles to its next timer */
static void pump(void)
{
    while (!xoff && job_pos < line_end)
        avr_raise_irq(uart_in, (uint8_t)job[job_pos++]);
}

/* the next lines the protocol lets out: with none in flight always one; send-response no more,
 * character counting while the bytes in flight fit the receive buffer */
static void queue_lines(void)
{
    while (line_end < job_len) {
        size_t e = line_end, len;
        while (e < job_len && job[e] != '\n' && job[e] != '\r') /* the firmware answers either end */
            e++;
        len = e + 1 - line_end;
        if (n_flight && (!rx_bytes || flight_bytes + len > rx_bytes))
            break;
        flight[(flight_head + n_flight++) % flight_cap] = len;
        flight_bytes += len;
        line_end = e + 1;
    }
    pump();
}

/* the answer to the oldest line in flight */
static void answered(void)
{
    if (!n_flight)
        return;
    flight_bytes -= flight[flight_head];
    flight_head = (flight_head + 1) % flight_cap;
    n_flight--;
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
    int banner, answer;
    (void)irq; (void)param;
    if (value != '\n') {
        if (out_len < sizeof out_line - 1)
            out_line[out_len++] = (char)value;
        return;
    }
    while (out_len && out_line[out_len - 1] == '\r') /* grbl ends its lines with \r\n */
        out_len--;
    out_line[out_len] = 0;
    out_len = 0;
    /* the first line with text: the firmware is ready (grbl's start-up message begins with an
     * empty line); its banner again: a soft reset, after which the next line goes out too */
    banner = (!started && out_line[0]) || strncmp(out_line, "nnik ", 5) == 0 || strncmp(out_line, "Grbl ", 5) == 0;
    started |= banner;
    answer = !banner && (strncmp(out_line, "ok", 2) == 0 || strncmp(out_line, "error:", 6) == 0);
    if (answer && n_replies == n_lines)
        printf("D %llu %s\n", idle_fall, out_line);
    else
        printf("R %llu %s\n", (unsigned long long)avr->cycle, out_line);
    if (events)
        fflush(stdout); /* the reader's progress */
    if (banner) { /* a (re)start: the receive buffer is empty, what was in flight is lost */
        n_flight = flight_bytes = 0;
        line_end = job_pos;
        queue_lines();
    } else if (answer) {
        n_replies++;
        answered();
        queue_lines();
    }
}

static void on_pin(struct avr_irq_t *irq, uint32_t value, void *param)
{
    int code = (int)(intptr_t)param; /* port * 8 + bit */
    int port = code / 8, bit = code % 8;
    int old = pin_state[port][bit];
    (void)irq;
    value = value ? 1 : 0;
    if ((int)value == old)
        return;
    pin_state[port][bit] = (int)value;
    if (port == 1 && (bit == 2 || bit == 3) && value)
        event('S', (bit - 2) | pin_state[1][bit + 3] << 1);
    else if (port == 1 && bit == 4)
        event('M', 0);
    else if (port == 1 && bit == 7 && !value)
        idle_fall = avr->cycle;
    else if (port == 0 && bit == 0)
        event('B', (int)value);
}

static void on_pwm(struct avr_irq_t *irq, uint32_t value, void *param)
{
    (void)irq; (void)param;
    if ((int)value == duty_seen)
        return;
    duty_seen = (int)value;
    event('T', (int)value);
}

int main(int argc, char **argv)
{
    elf_firmware_t fw;
    FILE *f;
    unsigned long long limit;
    const char *state = "done";
    int i, rc, opt;
    const char *mcu = "atmega328p";

    const char *prof_path = NULL;
    while ((opt = getopt(argc, argv, "m:e:p:c:")) != -1) {
        if (opt == 'c') {
            char *end;
            long n = strtol(optarg, &end, 10);
            if (*end || n < 1) {
                fprintf(stderr, "-c wants the receive buffer's bytes, not %s\n", optarg);
                return 2;
            }
            rx_bytes = (size_t)n;
        } else if (opt == 'p') {
            prof_path = optarg;
            prof = calloc(PROF_WORDS, sizeof *prof);
            if (!prof) {
                fprintf(stderr, "no memory for the profile\n");
                return 2;
            }
        } else if (opt == 'm') {
            mcu = optarg;
        } else if (opt == 'e') {
            events = fopen(optarg, "wb");
            if (!events) {
                fprintf(stderr, "cannot write %s\n", optarg);
                return 2;
            }
        } else {
            optind = argc + 1;
            break;
        }
    }
    if (argc - optind != 3) {
        fprintf(stderr, "usage: %s [-m MCU] [-e EVENTS] [-p PROFILE] [-c RX_BYTES] FIRMWARE.elf JOB_LINES MAX_SECONDS\n",
                argv[0]);
        return 2;
    }
    argv += optind - 1;
    memset(&fw, 0, sizeof fw);
    if (elf_read_firmware(argv[1], &fw) != 0) {
        fprintf(stderr, "cannot read %s\n", argv[1]);
        return 2;
    }
    f = fopen(argv[2], "rb");
    if (!f) {
        fprintf(stderr, "cannot read %s\n", argv[2]);
        return 2;
    }
    fseek(f, 0, SEEK_END);
    job_len = (size_t)ftell(f);
    fseek(f, 0, SEEK_SET);
    job = malloc(job_len + sizeof DRAIN);
    if (!job || fread(job, 1, job_len, f) != job_len) {
        fprintf(stderr, "cannot read %s\n", argv[2]);
        return 2;
    }
    fclose(f);
    for (i = 0; i < (int)job_len; i++)
        n_lines += job[i] == '\n' || job[i] == '\r';
    memcpy(job + job_len, DRAIN, sizeof DRAIN); /* sent after the job's last line */
    job_len += sizeof DRAIN - 1;
    flight_cap = (size_t)n_lines + 2;
    flight = malloc(flight_cap * sizeof *flight);
    if (!flight) {
        fprintf(stderr, "no memory for %d lines\n", n_lines);
        return 2;
    }
    limit = (unsigned long long)(atof(argv[3]) * CLOCK_HZ);

    avr = avr_make_mcu_by_name(mcu);
    if (!avr) {
        fprintf(stderr, "simavr has no %s\n", mcu);
        return 2;
    }
    avr_init(avr);
    avr->frequency = CLOCK_HZ;
    avr_load_firmware(avr, &fw);
    uart_in = nnik_sim_wire(avr, CLOCK_HZ, on_uart, on_xon, on_xoff, on_pin, on_pwm);

    for (;;) {
        unsigned pc0 = avr->pc;
        unsigned long long c0 = avr->cycle;
        int busy0 = prof && avr->state == cpu_Running && pin_state[0][0];
        rc = avr_run(avr);
        if (busy0 && pc0 / 2 < PROF_WORDS)
            prof[pc0 / 2] += avr->cycle - c0;
        {   /* the stack's low-water mark: the lowest stack pointer after start-up */
            unsigned sp = avr->data[R_SPL] | ((unsigned)avr->data[R_SPH] << 8);
            if (sp && sp < sp_low && avr->cycle > 10000)
                sp_low = sp;
        }
        if (rc == cpu_Done || rc == cpu_Crashed) {
            state = rc == cpu_Done ? "halted" : "crashed";
            break;
        }
        if (n_replies > n_lines) { /* DRAIN answered */
            state = "done";
            break;
        }
        if (avr->cycle > limit) {
            state = "timeout";
            break;
        }
    }
    if (events) {
        flush_events();
        if (fclose(events) != 0) {
            fprintf(stderr, "cannot write the events\n");
            return 2;
        }
    }
    if (prof) {
        FILE *pf = fopen(prof_path, "w");
        unsigned w;
        if (!pf) {
            fprintf(stderr, "cannot write %s\n", prof_path);
            return 2;
        }
        for (w = 0; w < PROF_WORDS; w++)
            if (prof[w])
                fprintf(pf, "%x %llu\n", w * 2, prof[w]);
        if (fclose(pf) != 0) {
            fprintf(stderr, "cannot write the profile\n");
            return 2;
        }
    }
    printf("K %u %u\n", sp_low, (unsigned)avr->ramend);
    printf("E %llu %s %d\n", (unsigned long long)avr->cycle, state, n_replies);
    return 0;
}
