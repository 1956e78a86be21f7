/*
 * nnik_simavr_servo - the closed-loop co-simulation's chip: the servo firmware (nnik_servo.c with
 * nnik_servo_feed.c) on a simulated ATmega328P (simavr, 16 MHz), in lockstep with a plant over
 * stdin/stdout, one tick per exchange (binary, little-endian int32).
 *
 * usage: nnik_simavr_servo FIRMWARE.elf PERIOD SUBSTEPS FEED COUNT POS X0 Y0 [SUM]
 *   PERIOD    the tick in cycles ((OCR1A + 1) * 8)
 *   SUBSTEPS  the plant's substeps per tick
 *   FEED, COUNT, POS  the SRAM addresses of nnik_servo_feed, nnik_servo_count, nnik_servo_pos
 *   X0, Y0    the start counts (the encoder pins start in their phase; the counts are written
 *             once the firmware's set-up sleeps, before the first tick)
 *   SUM       the SRAM address of nnik_servo_sum (uint16: a learning controller's weight checksum);
 *             0 or absent: none (a controller that does not learn; its answer is 0)
 *   FEED 0: a firmware with its own reference (an exported sketch playing its stored job, which
 *             sets its start counts itself): no reference is written, the references sent are
 *             ignored, and the awake cycles count the sketch's main loop too (it does not sleep)
 * request k: ref_x, ref_y, then SUBSTEPS rows (count_x, count_y): the plant's count at the end of
 *   each substep of the tick before tick k (request 0: the start counts). Each count change is
 *   a run of quadrature edges on PC0..PC3; substep j's edges are spread evenly over the j-th of
 *   SUBSTEPS equal slices of the window from GUARD cycles after the last tick's interrupt ended
 *   to GUARD cycles before tick k's (the plant holds the tick's duty from its start, as the
 *   Python model does; no edge meets the latch).
 * answer k (13 int32): duty x, duty y (OCR2A/B, 0 when the output is disconnected, negative when
 *   the DIR pin is high), the latched counts x, y, the busy cycles (D13 high, less the encoder
 *   interrupts nested in it), the tick interrupt's cycles (entry to return, less nested ones),
 *   the encoder interrupts' cycles and their number since the last answer, the awake cycles since
 *   the last answer (the main loop sleeps, so these are all interrupt work), the longest encoder
 *   interrupt, the chip's encoder counts x, y now, the weight checksum nnik_servo_sum (0 without SUM).
 * UART: with NNIK_SERVO_UART=PATH in the environment, every byte the chip sends on UART0 is
 *   appended to PATH as it leaves the simulated transmitter (simavr paces it at the baud rate).
 * An interrupt's cycles run from the cycle its vector is taken (simavr's instruction boundary,
 * the wake-up included) to the cycle its reti returns (the stack pointer back above its entry).
 *
 * usage 2 (the edge-rate sweep): nnik_simavr_servo -r RATE TICKS FIRMWARE.elf PERIOD COUNT
 *   after tick 0, both axes move forward at RATE edges/s each (Y half an edge interval after X),
 *   the edges running through the ticks' computations, for TICKS ticks; then the edges stop, two
 *   more ticks run, and it prints "edges N counted X Y awake_max A late_max L": lost counts are
 *   N - X, N - Y; A the most awake cycles in one tick period; L the latest a tick's computation
 *   ended after its due time (the whole run when a tick was starved: the encoder interrupt has
 *   the higher priority).
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <simavr/sim_avr.h>
#include <simavr/sim_elf.h>
#include <simavr/sim_irq.h>
#include <simavr/sim_cycle_timers.h>
#include <simavr/avr_ioport.h>
#include <simavr/avr_extint.h>
#include <simavr/avr_uart.h>

#define CLOCK_HZ 16000000UL
#define VEC_BYTES 4      /* the ATmega328P's vector slot: a jmp, 4 bytes */
#define VEC_PCINT1 4
#define VEC_TIMER1_COMPA 11
#define GUARD 200        /* cycles kept free of edges after the tick's end and before the next */
#define MAX_EDGES 1000000
#define MAX_DEPTH 8
#define R_PORTB 0x25
#define R_PORTD 0x2B
#define R_TCCR2A 0xB0
#define R_OCR2A 0xB3
#define R_OCR2B 0xB4
#define ANSWER 13        /* int32 per answer */

struct edge {
    uint64_t cycle;
    int axis, dir;
};
struct frame {
    int vec;
    uint64_t start, nested;
    unsigned sp;
};

static avr_t *avr;
static FILE *out; /* the answers: stdout, which simavr's own messages leave (they go to stderr) */
static avr_irq_t *pin_c[4];
static int phase[2];
static struct edge *edges;
static size_t n_edges, next_edge;
static struct frame frames[MAX_DEPTH];
static int depth;
static uint64_t enc_cycles, enc_n, enc_max, tick_cycles, awake, tick_entry, tick_end;
static int tick_done;
static uint64_t busy_rise, busy_enc0, busy_cycles;

static FILE *uart_log; /* NNIK_SERVO_UART's file, or NULL */

static void on_uart(struct avr_irq_t *irq, uint32_t value, void *param)
{
    (void)irq; (void)param;
    fputc((int)(value & 0xFF), uart_log);
}

static void capture_uart(void)
{
    const char *path = getenv("NNIK_SERVO_UART");
    uint32_t flags = 0;
    if (!path || !*path)
        return;
    uart_log = fopen(path, "wb");
    if (!uart_log) {
        fprintf(stderr, "cannot write %s\n", path);
        exit(2);
    }
    avr_ioctl(avr, AVR_IOCTL_UART_GET_FLAGS('0'), &flags);
    flags &= ~(uint32_t)(AVR_UART_FLAG_STDIO | AVR_UART_FLAG_POLL_SLEEP);
    avr_ioctl(avr, AVR_IOCTL_UART_SET_FLAGS('0'), &flags);
    avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUTPUT), on_uart, NULL);
}

static const int GRAY[4] = {0, 1, 3, 2}; /* phase -> A | B << 1 */

static void set_pins(int axis, int level_both)
{
    avr_raise_irq(pin_c[2 * axis], level_both & 1);
    avr_raise_irq(pin_c[2 * axis + 1], (level_both >> 1) & 1);
}

static avr_cycle_count_t fire_edges(avr_t *a, avr_cycle_count_t when, void *param)
{
    (void)param;
    if (when < a->cycle)
        when = a->cycle;
    while (next_edge < n_edges && edges[next_edge].cycle <= when) {
        struct edge *e = &edges[next_edge++];
        phase[e->axis] = (phase[e->axis] + e->dir) & 3;
        set_pins(e->axis, GRAY[phase[e->axis]]);
    }
    return next_edge < n_edges ? edges[next_edge].cycle : 0;
}

static void schedule(void)
{
    next_edge = 0;
    if (n_edges)
        avr_cycle_timer_register(avr, edges[0].cycle - avr->cycle, fire_edges, NULL);
}

static void on_busy(struct avr_irq_t *irq, uint32_t value, void *param)
{
    (void)irq; (void)param;
    if (value) {
        busy_rise = avr->cycle;
        busy_enc0 = enc_cycles;
    } else if (busy_rise) {
        busy_cycles = avr->cycle - busy_rise - (enc_cycles - busy_enc0);
        busy_rise = 0;
    }
}

static unsigned sp_now(void)
{
    return avr->data[R_SPL] | ((unsigned)avr->data[R_SPH] << 8);
}

/* one instruction (or one sleep), with the interrupt and awake accounting */
static int step(void)
{
    uint64_t c0 = avr->cycle;
    int running = avr->state == cpu_Running;
    int rc = avr_run(avr);
    if (running) /* a SLEEP's step also skips the slept cycles: only its own cycle is awake */
        awake += avr->state == cpu_Running ? avr->cycle - c0 : 1;
    while (depth && sp_now() > frames[depth - 1].sp) { /* reti: the frame's return address popped */
        struct frame *f = &frames[--depth];
        uint64_t d = avr->cycle - f->start;
        if (depth)
            frames[depth - 1].nested += d;
        if (f->vec == VEC_PCINT1) {
            enc_cycles += d - f->nested;
            enc_n++;
            if (d - f->nested > enc_max)
                enc_max = d - f->nested;
        } else if (f->vec == VEC_TIMER1_COMPA) {
            tick_cycles = d - f->nested;
            tick_end = avr->cycle;
            tick_done = 1;
        }
    }
    if (avr->pc == VEC_PCINT1 * VEC_BYTES || avr->pc == VEC_TIMER1_COMPA * VEC_BYTES) {
        if (depth == MAX_DEPTH) {
            fprintf(stderr, "interrupts nested deeper than %d\n", MAX_DEPTH);
            exit(2);
        }
        frames[depth].vec = (int)(avr->pc / VEC_BYTES);
        frames[depth].start = avr->cycle;
        frames[depth].nested = 0;
        frames[depth].sp = sp_now();
        if (frames[depth].vec == VEC_TIMER1_COMPA)
            tick_entry = avr->cycle;
        depth++;
    }
    if (rc == cpu_Done || rc == cpu_Crashed) {
        fprintf(stderr, "the firmware %s at cycle %llu\n", rc == cpu_Done ? "halted" : "crashed",
                (unsigned long long)avr->cycle);
        exit(2);
    }
    return rc;
}

static void run_tick(void)
{
    tick_done = 0;
    while (!tick_done)
        step();
}

static int32_t rd32(unsigned addr)
{
    uint32_t v = 0;
    int i;
    for (i = 3; i >= 0; i--)
        v = v << 8 | avr->data[addr + i];
    return (int32_t)v;
}

static void wr32(unsigned addr, int32_t value)
{
    int i;
    for (i = 0; i < 4; i++)
        avr->data[addr + i] = (uint8_t)((uint32_t)value >> (8 * i));
}

static int32_t duty_of(int reg, int com, int dir_reg, int dir_bit)
{
    int32_t d = (avr->data[R_TCCR2A] & com) ? avr->data[reg] : 0;
    return (avr->data[dir_reg] >> dir_bit) & 1 ? -d : d;
}

static void no_host_sleep(avr_t *a, avr_cycle_count_t how_long)
{
    (void)a;
    (void)how_long; /* simavr skips the slept cycles; nothing to wait for on the host */
}

static int cmp_edge(const void *a, const void *b)
{
    const struct edge *x = a, *y = b;
    if (x->cycle != y->cycle)
        return x->cycle < y->cycle ? -1 : 1;
    return x->axis - y->axis;
}

static void load(const char *path)
{
    elf_firmware_t fw;
    int i;
    memset(&fw, 0, sizeof fw);
    if (elf_read_firmware(path, &fw) != 0) {
        fprintf(stderr, "cannot read %s\n", path);
        exit(2);
    }
    avr = avr_make_mcu_by_name("atmega328p");
    if (!avr) {
        fprintf(stderr, "simavr has no atmega328p\n");
        exit(2);
    }
    avr_init(avr);
    avr->frequency = CLOCK_HZ;
    avr->sleep = no_host_sleep;
    for (i = 0; i < 2; i++) /* INT0/INT1 (PD2, PD3: PWM Y) are never enabled: no polling of their low level */
        avr_extint_set_strict_lvl_trig(avr, (uint8_t)i, 0);
    avr_load_firmware(avr, &fw);
    for (i = 0; i < 4; i++)
        pin_c[i] = avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ('C'), i);
    avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ('B'), 5), on_busy, NULL);
    capture_uart();
    edges = malloc(MAX_EDGES * sizeof *edges);
    if (!edges) {
        fprintf(stderr, "out of memory\n");
        exit(2);
    }
}

/* run the set-up until the main loop first sleeps */
static void boot(void)
{
    while (avr->state != cpu_Sleeping)
        step();
}

static int sweep(int argc, char **argv)
{
    double rate;
    long ticks, done = 0;
    uint64_t period, t0, t_end, gap, n = 0, awake_max = 0, win_end, late_max = 0, first;
    unsigned count;
    if (argc != 7) {
        fprintf(stderr, "usage: %s -r RATE TICKS FIRMWARE.elf PERIOD COUNT\n", argv[0]);
        return 2;
    }
    rate = atof(argv[2]);
    ticks = atol(argv[3]);
    period = strtoull(argv[5], NULL, 0);
    count = (unsigned)strtoul(argv[6], NULL, 0);
    load(argv[4]);
    boot();
    run_tick();                     /* tick 0, before any edge */
    first = tick_entry;
    gap = (uint64_t)(CLOCK_HZ / rate + 0.5);
    if (gap < 2 || ticks < 1) {
        fprintf(stderr, "rate too high or no ticks\n");
        return 2;
    }
    t0 = avr->cycle + GUARD;
    t_end = first + (uint64_t)(ticks + 1) * period - GUARD;
    n_edges = 0;
    for (n = 0; t0 + n * gap + gap / 2 < t_end && 2 * n + 2 <= MAX_EDGES; n++) {
        edges[n_edges++] = (struct edge){t0 + n * gap, 0, 1};
        edges[n_edges++] = (struct edge){t0 + n * gap + gap / 2, 1, 1};
    }
    schedule();
    awake = 0;
    win_end = first + period;
    while (avr->cycle < t_end) {
        tick_done = 0;
        step();
        if (tick_done) {            /* tick 1 + done: due at first + (1 + done) * period */
            uint64_t late = tick_end - (first + (uint64_t)(1 + done) * period);
            done++;
            if (late > late_max)
                late_max = late;
        }
        if (avr->cycle >= win_end) { /* the awake cycles of each tick period */
            if (awake > awake_max)
                awake_max = awake;
            awake = 0;
            win_end += period;
        }
    }
    if (done < ticks) /* starved ticks: as late as the run */
        late_max = avr->cycle - first;
    run_tick();
    run_tick();
    fprintf(out, "edges %llu counted %d %d awake_max %llu late_max %llu\n", (unsigned long long)n, rd32(count),
            rd32(count + 4), (unsigned long long)awake_max, (unsigned long long)late_max);
    fflush(out);
    return 0;
}

int main(int argc, char **argv)
{
    uint64_t period;
    int substeps, j, a;
    unsigned feed, count, pos, sum = 0;
    int32_t last[2], start[2], *req, ans[ANSWER];
    long k;
    out = fdopen(dup(1), "wb");
    if (!out || dup2(2, 1) < 0)
        return 2;
    if (argc > 1 && strcmp(argv[1], "-r") == 0)
        return sweep(argc, argv);
    if (argc != 9 && argc != 10) {
        fprintf(stderr, "usage: %s FIRMWARE.elf PERIOD SUBSTEPS FEED COUNT POS X0 Y0 [SUM]\n", argv[0]);
        return 2;
    }
    period = strtoull(argv[2], NULL, 0);
    substeps = atoi(argv[3]);
    feed = (unsigned)strtoul(argv[4], NULL, 0);
    count = (unsigned)strtoul(argv[5], NULL, 0);
    pos = (unsigned)strtoul(argv[6], NULL, 0);
    start[0] = (int32_t)strtol(argv[7], NULL, 0);
    start[1] = (int32_t)strtol(argv[8], NULL, 0);
    if (argc == 10)
        sum = (unsigned)strtoul(argv[9], NULL, 0);
    if (substeps < 1 || period < 8 * GUARD) {
        fprintf(stderr, "bad substeps or period\n");
        return 2;
    }
    load(argv[1]);
    for (a = 0; a < 2; a++) {
        phase[a] = start[a] & 3;
        set_pins(a, GRAY[phase[a]]);
        last[a] = start[a];
    }
    if (feed) { /* the co-simulation build: it sleeps after its set-up; the counts start here */
        boot();
        wr32(count, start[0]);
        wr32(count + 4, start[1]);
    }
    req = malloc((size_t)(2 + 2 * substeps) * sizeof *req);
    for (k = 0;; k++) {
        if (fread(req, sizeof *req, (size_t)(2 + 2 * substeps), stdin) != (size_t)(2 + 2 * substeps))
            break;
        n_edges = 0;
        if (k > 0) {
            uint64_t w0 = tick_end + GUARD, w1 = tick_entry + period - GUARD;
            double slice = (double)(w1 - w0) / substeps;
            if (w1 <= w0) {
                fprintf(stderr, "tick %ld: no time left for edges\n", k);
                return 2;
            }
            for (j = 0; j < substeps; j++)
                for (a = 0; a < 2; a++) {
                    int32_t c = req[2 + 2 * j + a];
                    int64_t d = (int64_t)c - last[a], n = d < 0 ? -d : d, i;
                    if (n_edges + (size_t)n > MAX_EDGES) {
                        fprintf(stderr, "tick %ld: more than %d edges\n", k, MAX_EDGES);
                        return 2;
                    }
                    for (i = 0; i < n; i++)
                        edges[n_edges++] = (struct edge){w0 + (uint64_t)(slice * j + slice * (i + 1) / (n + 1)), a,
                                                         d < 0 ? -1 : 1};
                    last[a] = c;
                }
            qsort(edges, n_edges, sizeof *edges, cmp_edge);
        } else if (req[2] != start[0] || req[3] != start[1]) {
            fprintf(stderr, "request 0: the counts must be the start counts\n");
            return 2;
        }
        schedule();
        if (feed) {
            wr32(feed, req[0]);
            wr32(feed + 4, req[1]);
        }
        awake = enc_cycles = enc_n = enc_max = 0;
        run_tick();
        if (next_edge < n_edges) {
            fprintf(stderr, "tick %ld: %zu edges after the latch\n", k, n_edges - next_edge);
            return 2;
        }
        ans[0] = duty_of(R_OCR2A, 0x80, R_PORTB, 0);
        ans[1] = duty_of(R_OCR2B, 0x20, R_PORTD, 7);
        ans[2] = rd32(pos);
        ans[3] = rd32(pos + 4);
        ans[4] = (int32_t)busy_cycles;
        ans[5] = (int32_t)tick_cycles;
        ans[6] = (int32_t)enc_cycles;
        ans[7] = (int32_t)enc_n;
        ans[8] = (int32_t)awake;
        ans[9] = (int32_t)enc_max;
        ans[10] = rd32(count);
        ans[11] = rd32(count + 4);
        ans[12] = sum ? (int32_t)(avr->data[sum] | (unsigned)avr->data[sum + 1] << 8) : 0;
        if (fwrite(ans, sizeof ans[0], ANSWER, out) != ANSWER)
            return 2;
        fflush(out);
        if (uart_log)
            fflush(uart_log);
    }
    return 0;
}
