/*
 * A simulated TekBot hardware layer for host tests: a settable clock, sonar ranges and
 * heading, recorded motor outputs, and two byte queues standing in for the UART (what the
 * bridge sent to the board, what the board sent to the bridge).
 */
#ifndef QNAV_TESTS_SIM_HAL_H
#define QNAV_TESTS_SIM_HAL_H

#include <stdint.h>

#include "qnav/board_hal.h"

#define SIM_HAL_QUEUE 65536

typedef struct {
    uint32_t now_ms;
    uint16_t n_ranges;
    qnav_mm_t ranges_mm[64];
    qnav_cdeg_t heading_cdeg;
    qnav_q1_15_t left, right;       /* last motors_set */
    uint32_t motor_calls;
    uint8_t to_board[SIM_HAL_QUEUE];
    uint32_t to_board_head, to_board_tail;
    uint8_t from_board[SIM_HAL_QUEUE];
    uint32_t from_board_n;
} sim_hal_t;

/* Reset the simulated hardware and fill hal with functions over it. */
void sim_hal_init(sim_hal_t *sim, qnav_board_hal_t *hal);

/* Queue bytes for the board to read. */
void sim_hal_to_board(sim_hal_t *sim, const uint8_t *bytes, uint32_t n);

#endif /* QNAV_TESTS_SIM_HAL_H */
