/*
 * nnik_servo_job.h - a stored job for the servo runtime: the reference per tick,
 * packed in flash by nnik (nnik.firmware.servo.job_pack), played one tick at a time by
 * nnik_servo_reference(); after its last tick the reference holds. The generated
 * nnik_servo_job_data.h gives NNIK_JOB_X0, NNIK_JOB_Y0 (the start, counts), NNIK_JOB_TICKS and
 * the bytes nnik_servo_job_bytes[]:
 *   0x88, then x, y as int32 little-endian: the reference jumps to (x, y)
 *   0x80, then n as uint16 little-endian: n ticks with the reference held
 *   0x08, then dx, dy as int8: one tick moving by (dx, dy)
 *   0x81, then n as uint8 (n >= 1): n ticks each repeating the last move
 *   any other byte: one tick moving by dx = the high nibble, dy = the low nibble (signed 4-bit)
 */
#ifndef NNIK_SERVO_JOB_H
#define NNIK_SERVO_JOB_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Start the job from its first tick (the reference at the start point). */
void nnik_servo_job_begin(void);
/* The reference for the next tick (x, y counts); the last one once the job is over. */
void nnik_servo_job_next(int32_t ref[2]);
/* 1 while the job has ticks left. */
uint8_t nnik_servo_job_running(void);

#ifdef __cplusplus
}
#endif

#endif /* NNIK_SERVO_JOB_H */
