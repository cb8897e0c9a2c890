/*
 * A scripted robot for host tests of the board core: a settable clock, sonar ranges,
 * heading and wheel encoder counts, the recorded drive (and the wheel speeds a TekBot
 * would mix from it), two byte queues standing in for the UART (what the bridge sent to
 * the board, what the board sent to the bridge), and an EEPROM in RAM that can be made to
 * lose power after a number of written bytes.
 */
#ifndef QNAV_TESTS_SIM_HAL_H
#define QNAV_TESTS_SIM_HAL_H

#include <stdint.h>

#include "qnav/board_hal.h"
#include "qnav/link.h"

#define SIM_HAL_QUEUE 65536
#define SIM_HAL_NVM 4096
#define SIM_HAL_TABLE_PAGE 256
#define SIM_HAL_TABLE_PAGES 46   /* the ATmega128's: ceil(QNAV_BOARD_TABLE_BYTES / 256) */

typedef struct {
    uint32_t now_ms;
    uint16_t n_ranges;
    qnav_mm_t ranges_mm[64];
    qnav_cdeg_t heading_cdeg;
    int32_t left_counts, right_counts;
    qnav_deg_t drive_heading;       /* last drive */
    qnav_q1_15_t drive_speed;
    qnav_q1_15_t drive_rolling;     /* the forward speed the core measured (encoders) */
    qnav_q1_15_t left, right;       /* last drive mixed for a TekBot (qnav_drive_mix) */
    uint32_t motor_calls;
    uint8_t to_board[SIM_HAL_QUEUE];
    uint32_t to_board_head, to_board_tail;
    uint8_t from_board[SIM_HAL_QUEUE];
    uint32_t from_board_n;
    uint8_t nvm[SIM_HAL_NVM];       /* erased = 0xFF */
    uint32_t nvm_written;           /* bytes written so far */
    uint32_t nvm_cut_after;         /* power lost after this many written bytes (0 never) */
    uint8_t table[SIM_HAL_TABLE_PAGE * SIM_HAL_TABLE_PAGES]; /* a table area (sim_hal_table) */
    uint32_t table_pages_written;   /* pages written so far */
    uint32_t table_fail_after;      /* page writes after this many fail (0 never) */
} sim_hal_t;

/* Reset the simulated hardware (EEPROM erased) and fill hal with functions over it. */
void sim_hal_init(sim_hal_t *sim, qnav_board_hal_t *hal);

/* Give hal a table area (SIM_HAL_TABLE_PAGES pages of SIM_HAL_TABLE_PAGE bytes, erased to
 * 0xFF), as the ATmega128's flash gives the TekBot board one. sim_hal_init leaves it out. */
void sim_hal_table(sim_hal_t *sim, qnav_board_hal_t *hal);

/* Queue bytes for the board to read. */
void sim_hal_to_board(sim_hal_t *sim, const uint8_t *bytes, uint32_t n);

/* The blob sim_hal_upload sends, as navbridge makes it: the policy's, with a 2-input
 * network's row shapes (default configuration's rank) carried. Bytes or a QNAV_LINK_E_*. */
int32_t sim_hal_blob(const qnav_policy_t *pol, uint8_t *blob, uint16_t cap);

/* Queue a whole policy upload for the board, as navbridge sends it: chunks from tx, then
 * the commit, whose CRC is xored with crc_xor (0: correct). 0, or -1 when pol does not
 * serialise. */
int sim_hal_upload(sim_hal_t *sim, qnav_link_tx_t *tx, const qnav_policy_t *pol,
                   uint16_t crc_xor);

#endif /* QNAV_TESTS_SIM_HAL_H */
