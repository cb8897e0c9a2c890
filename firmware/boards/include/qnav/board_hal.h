/*
 * The hardware a qnav board application needs, as a small table of functions the board
 * support code fills in: a millisecond tick, the sonar sectors, the heading, the two drive
 * motors and a byte-wise UART. The ATmega128 TekBot fills it from registers
 * (firmware/boards/tekbot/src/hal_avr.c); host tests fill it with a simulated robot.
 * Fixed-width integers only (no int or long): int is 16 bits on AVR.
 */
#ifndef QNAV_BOARD_HAL_H
#define QNAV_BOARD_HAL_H

#include <stdint.h>

#include "qnav/fixed.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    void *ctx; /* passed to every function */

    /* Milliseconds since start-up; wraps at 2^32. */
    uint32_t (*millis)(void *ctx);

    /* Read up to max sonar sectors into ranges_mm (sector k centred on k*360/N deg,
     * robot frame, CCW; mm, no echo = the sonar's maximum range). Returns N read. */
    uint16_t (*sonar_read)(void *ctx, qnav_mm_t *ranges_mm, uint16_t max);

    /* Heading from the inertial sensor or odometry: 0.01 deg, CCW positive, any zero. */
    qnav_cdeg_t (*heading_cdeg)(void *ctx);

    /* Wheel speeds as signed fractions of full speed, Q1.15 (-32767..32767). 0, 0 stops;
     * the application calls it every tick. */
    void (*motors_set)(void *ctx, qnav_q1_15_t left, qnav_q1_15_t right);

    /* One received byte (0..255), or -1 when none is waiting. Never blocks. */
    int16_t (*uart_read)(void *ctx);

    /* Send n bytes (may block until they are queued). */
    void (*uart_write)(void *ctx, const uint8_t *bytes, uint16_t n);
} qnav_board_hal_t;

#ifdef __cplusplus
}
#endif

#endif /* QNAV_BOARD_HAL_H */
