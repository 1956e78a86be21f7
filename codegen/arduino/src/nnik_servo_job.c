/*
 * nnik_servo_job.c - the stored job's player (format in nnik_servo_job.h). On the AVR the bytes
 * are in flash (PROGMEM); elsewhere (nnik's host check) in RAM.
 */
#include "nnik_servo_job.h"
#include "nnik_servo_job_data.h"

#ifdef __AVR__
#include <avr/pgmspace.h>
#define JOB_BYTE(i) pgm_read_byte(&nnik_servo_job_bytes[i])
#else
#define JOB_BYTE(i) (nnik_servo_job_bytes[i])
#endif

static uint32_t at;      /* the next byte */
static uint16_t hold;    /* ticks left in a hold */
static uint8_t repeat;   /* ticks left repeating the last move */
static int8_t last[2];   /* the last move (counts a tick) */
static int32_t ref_now[2];

void nnik_servo_job_begin(void)
{
    at = 0;
    hold = 0;
    repeat = 0;
    last[0] = last[1] = 0;
    ref_now[0] = NNIK_JOB_X0;
    ref_now[1] = NNIK_JOB_Y0;
}

uint8_t nnik_servo_job_running(void)
{
    return hold != 0 || repeat != 0 || at < sizeof nnik_servo_job_bytes;
}

static int32_t read32(uint32_t i)
{
    uint32_t v = 0;
    uint8_t k;
    for (k = 4; k-- > 0;)
        v = v << 8 | JOB_BYTE(i + k);
    return (int32_t)v;
}

void nnik_servo_job_next(int32_t ref[2])
{
    if (hold) {
        hold--;
    } else if (repeat) {
        repeat--;
        ref_now[0] += last[0];
        ref_now[1] += last[1];
    } else if (at < sizeof nnik_servo_job_bytes) {
        uint8_t b = JOB_BYTE(at);
        if (b == 0x88) {
            ref_now[0] = read32(at + 1);
            ref_now[1] = read32(at + 5);
            at += 9;
        } else if (b == 0x08) {
            last[0] = (int8_t)JOB_BYTE(at + 1);
            last[1] = (int8_t)JOB_BYTE(at + 2);
            ref_now[0] += last[0];
            ref_now[1] += last[1];
            at += 3;
        } else if (b == 0x81) {
            repeat = (uint8_t)(JOB_BYTE(at + 1) - 1); /* this tick is the repeat's first */
            ref_now[0] += last[0];
            ref_now[1] += last[1];
            at += 2;
        } else if (b == 0x80) {
            hold = (uint16_t)(JOB_BYTE(at + 1) | (uint16_t)JOB_BYTE(at + 2) << 8);
            at += 3;
            hold--; /* this tick is the hold's first */
        } else {
            last[0] = (int8_t)b >> 4;
            last[1] = (int8_t)(uint8_t)(b << 4) >> 4;
            ref_now[0] += last[0];
            ref_now[1] += last[1];
            at++;
        }
    }
    ref[0] = ref_now[0];
    ref[1] = ref_now[1];
}
