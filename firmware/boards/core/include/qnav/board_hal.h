/*
 * The hardware a qnav board needs, as a small table of functions the platform fills in: a
 * millisecond clock, the sonar sectors, the heading, the wheel encoders, the drive, a
 * byte-wise UART and (optionally) non-volatile storage. The board core
 * (qnav/board.h) is written once against this table: the ATmega128 TekBot fills it from
 * registers (firmware/boards/tekbot/src/hal_avr.c), the software-in-the-loop robot from
 * the Box2D simulator (host/navbridge/sil_hal.c), host tests from a scripted robot.
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

    /* Heading from the inertial sensor or odometry: 0.01 deg, CCW positive, 0 at start-up
     * (this zero is the x axis of the odometry frame). */
    qnav_cdeg_t (*heading_cdeg)(void *ctx);

    /* Wheel encoder counts since start-up, forward positive, wrapping at 2^32 (the core
     * takes differences). Optional (NULL: the pose stays at the origin). */
    void (*odometry_read)(void *ctx, int32_t *left_counts, int32_t *right_counts);

    /* Drive: turn towards heading_deg (robot frame, deg, CCW, -179..180) at speed (Q1.15
     * fraction of full speed, 0..32767). Speed 0 with a heading turns in place toward it;
     * heading 0 and speed 0 stop. rolling: the forward speed the encoders measured over
     * the last tick (Q1.15 of full speed; 0 without odometry_read). Called every tick. A
     * differential-drive board turns the three into wheel speeds with qnav_drive_mix()
     * (qnav/drive.h), which brakes before a turn in place while the robot still rolls. */
    void (*drive)(void *ctx, qnav_deg_t heading_deg, qnav_q1_15_t speed, qnav_q1_15_t rolling);

    /* One received byte (0..255), or -1 when none is waiting. Never blocks. */
    int16_t (*uart_read)(void *ctx);

    /* Send n bytes (may block until they are queued). */
    void (*uart_write)(void *ctx, const uint8_t *bytes, uint16_t n);

    /* Non-volatile storage (EEPROM, a flash page, a file), optional (both NULL: uploads
     * live in RAM only). Read or write n bytes at byte address addr (0..nvm_bytes-1);
     * return 1 on success, 0 on failure. A write may be cut by a power loss at any byte. */
    uint8_t (*nvm_read)(void *ctx, uint16_t addr, uint8_t *out, uint16_t n);
    uint8_t (*nvm_write)(void *ctx, uint16_t addr, const uint8_t *bytes, uint16_t n);
    uint16_t nvm_bytes; /* size of the storage, bytes */

    /* A key table area, optional (table_area NULL: none): where the core compiles an
     * uploaded 2-input network into its quality table, so that the step runs in table
     * mode, whose cost does not depend on the policy (qnav/board.h, "Table mode on the
     * board"). table_area is read the way the controller reads tables: program memory on
     * an AVR built with QNAV_TABLES_IN_FLASH, else memory; 2-byte aligned, table_pages
     * pages of table_page_bytes (even, at most QNAV_BOARD_TABLE_PAGE_MAX), together at
     * least QNAV_BOARD_TABLE_BYTES. table_write_page erases page and writes its bytes;
     * 1 on success (read back equal), 0 on failure. A power cut may leave any page half
     * written: the core checks the area before it uses it. */
    const uint8_t *table_area;
    uint16_t table_page_bytes;
    uint16_t table_pages;
    uint8_t (*table_write_page)(void *ctx, uint16_t page, const uint8_t *bytes);
} qnav_board_hal_t;

#ifdef __cplusplus
}
#endif

#endif /* QNAV_BOARD_HAL_H */
