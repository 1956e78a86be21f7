/*
 * nnik_grbl.h - grbl 1.1's serial interface in front of the G-code engine (nnik_gcode.h), so
 * that grbl senders (UGS, cncjs, bCNC, LaserGRBL, LightBurn, grbl-streamer) drive the sketch.
 * Portable C99: the board's side (receive interrupt, stepper queue, sleep) is the "port" below,
 * which the sketch implements; docs/grbl_interface.md lists every answer and every difference
 * from grbl 1.1h.
 *
 * What it does, as grbl's protocol.c / system.c / report.c do:
 *   - prints "Grbl 1.1h ['$' for help]" at start and after a soft reset (Ctrl-X);
 *   - feeds every received byte to the engine's line reader (nnik_gc_byte) and at '\n' or '\r'
 *     runs the line (nnik_gc_eol) and answers "ok", "error:N" or "ALARM:N";
 *   - realtime bytes, which the port's receive interrupt takes out of the stream and flags in
 *     nnik_grbl_rt: '?' status report, '!' feed hold, '~' cycle start / resume, 0x18 soft reset;
 *   - '$' lines: $ $$ $# $G $I $N $C $X $H, $N=V (accepted only with the compiled value).
 * Lines end in '\n' (grbl sends "\r\n"; senders split on '\n').
 */
#ifndef NNIK_GRBL_H
#define NNIK_GRBL_H

#include <stdint.h>

#include "nnik_gcode.h"

#ifdef __cplusplus
extern "C" {
#endif

/* the receive buffer for character counting, as grbl's (a power of two up to 128: the port's ring
 * counts in 8 bits); $I reports it, nnik job's sender (chip.rx_buffer_bytes) reads it here */
#define NNIK_GRBL_RX_SIZE 128

/* realtime requests: the port's receive interrupt sets nnik_grbl_rt[NNIK_RT_...] = 1 (one byte
 * each, so that clearing one never loses another), nnik_grbl_poll() acts on them */
#define NNIK_RT_STATUS 0 /* '?' */
#define NNIK_RT_HOLD 1   /* '!' (the port has already told its stepper to hold) */
#define NNIK_RT_RESUME 2 /* '~' */
#define NNIK_RT_RESET 3  /* 0x18 (the port has already told its stepper to halt) */
extern volatile uint8_t nnik_grbl_rt[4];

/* the engine's fields the front end and the sketch read (as in the engine being rewritten on
 * main; the shim fakes the ones today's engine lacks) */
#ifndef GC_LINE
#define GC_LINE(g) ((g)->line)           /* the cleaned line; a '$' line after NNIK_GC_DOLLAR */
#define GC_LEN(g) ((g)->len)             /* its length so far; 0 before nnik_gc_eol drops it */
#define GC_CHECK(g) ((g)->check)         /* check mode */
#define GC_PLANE(g) ((g)->plane)         /* 0..2: G17..G19 */
#define GC_WCS(g) ((g)->wcs)             /* 0..5: G54..G59 */
#define GC_INVT(g) ((g)->inverse_time)   /* G93 */
#define GC_COOLANT(g) ((g)->coolant)     /* bit 0: M7, bit 1: M8 */
#define GC_TOOLNO(g) ((g)->tool_no)      /* T */
#define GC_Z(g) ((g)->mp[2])             /* Z, um */
#define GC_COORD(g, i, a) ((i) < NNIK_GC_N_WCS ? (g)->coord[i][a] : 0) /* G54..G59 offsets, um */
#define GC_HOME(g, i, a) ((g)->home[i][a])   /* G28, G30 */
#define GC_G92(g, a) ((g)->g92[a])
#define GC_TLO(g) ((g)->tlo)
#endif

/* ---- the port: the sketch implements these ---- */
void nnik_port_putc(char c);      /* send one byte (may wait for the UART) */
int16_t nnik_port_getc(void);     /* the next received byte that is not a realtime one; -1: none */
uint8_t nnik_port_rx_free(void);  /* bytes free in the receive buffer */
uint8_t nnik_port_busy(void);     /* 1 while the stepper has a segment running or queued */
uint8_t nnik_port_held(void);     /* 1 once a feed hold has brought the stepper to a stop */
void nnik_port_hold(uint8_t on);  /* 1: decelerate and stop at a segment's end; 0: resume */
uint8_t nnik_port_quiet(void);    /* 1: no byte for a while and the stepper's queue nearly dry */
uint8_t nnik_port_room(void);     /* 1: the stepper's queue has room for a segment (the sketch is busy) */
void nnik_port_idle(void);        /* sleep until an interrupt, unless a byte or request waits */
/* where the motors are: the engine's last sample less the queued segments not yet started */
void nnik_port_where(int32_t pt[2]);
/* soft reset: stop at the end of the running segment, drop the queue, the tool off and the
 * receive buffer empty; pt: where the motors stopped (um).  1 if they were moving. */
uint8_t nnik_port_stop(int32_t pt[2]);

/* the engine (one: the front end reads its fields directly, which is smaller on an AVR) */
extern nnik_gc_t nnik_gc;

/* The protocol's main loop, on nnik_gc once the sketch has initialised it (nnik_gc_init):
 * print the banner, serve lines forever. */
void nnik_grbl_run(void);

/* Realtime requests: a status report, hold, resume, reset (which does not return).  The port
 * calls it while it waits (emit with the queue full); nnik_grbl_wait() also sleeps. */
void nnik_grbl_poll(void);
void nnik_grbl_wait(void);

#ifdef __cplusplus
}
#endif

#endif /* NNIK_GRBL_H */
