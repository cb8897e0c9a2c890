/*
 * The board core's policy store in non-volatile storage (private to the core; layout in
 * qnav/board.h, QNAV_BOARD_STORE_*).
 */
#ifndef QNAV_BOARD_STORE_H
#define QNAV_BOARD_STORE_H

#include "qnav/board.h"

/* Load the newest whole slot whose blob decodes to a policy: 1 with *policy, its blob's
 * CRC, slot and sequence; 0 when no slot is whole (no storage, erased, corrupt). */
uint8_t qnav_board_store_load(const qnav_board_hal_t *hal, uint16_t offset,
                              qnav_policy_t *policy, uint16_t *crc, uint8_t *slot,
                              uint8_t *seq);

/* Write policy to the slot other than *slot (slot 0 when *slot is 0xFF), with sequence
 * *seq + 1; on success update *slot and *seq and return 1 with *crc the blob's CRC. 0 when
 * there is no storage or a write failed. */
uint8_t qnav_board_store_save(const qnav_board_hal_t *hal, uint16_t offset,
                              const qnav_policy_t *policy, uint16_t *crc, uint8_t *slot,
                              uint8_t *seq);

#endif /* QNAV_BOARD_STORE_H */
