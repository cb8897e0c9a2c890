/*
 * The policy store (board_store.h): two slots so that a power cut in the middle of a
 * commit never loses the policy committed before it. Slot bytes: [0] 'Q' [1] 'P'
 * [2] format [3] sequence [4..5] blob length LE [6..7] CRC-16 LE over bytes 2..5 and the
 * blob [8..] blob. Write order: magic erased, blob, header, magic.
 */
#include "board_store.h"

#include <stddef.h>

#define MAGIC0 0x51u /* 'Q' */
#define MAGIC1 0x50u /* 'P' */

static uint8_t have_nvm(const qnav_board_hal_t *hal, uint16_t offset)
{
    return (uint8_t)(hal->nvm_read != NULL && hal->nvm_write != NULL &&
                     (uint32_t)offset + QNAV_BOARD_STORE_BYTES <= hal->nvm_bytes);
}

static uint16_t slot_addr(uint16_t offset, uint8_t slot)
{
    return (uint16_t)(offset + (uint16_t)slot * QNAV_BOARD_STORE_SLOT_BYTES);
}

static uint16_t slot_crc(const uint8_t *hdr, const uint8_t *blob, uint16_t len)
{
    uint16_t crc = qnav_link_crc16(QNAV_LINK_CRC16_INIT, &hdr[2], 4u);
    return qnav_link_crc16(crc, blob, len);
}

/* Read one slot: 1 with its sequence, blob CRC and policy when whole and decodable. */
static uint8_t read_slot(const qnav_board_hal_t *hal, uint16_t addr, qnav_policy_t *policy,
                         uint16_t *crc, uint8_t *seq)
{
    uint8_t hdr[QNAV_BOARD_STORE_HEADER_BYTES];
    uint8_t blob[QNAV_LINK_POLICY_WEIGHTS_MAX_BYTES];
    uint16_t len;
    uint16_t want;
    if (!hal->nvm_read(hal->ctx, addr, hdr, (uint16_t)sizeof hdr) || hdr[0] != MAGIC0 ||
        hdr[1] != MAGIC1 || hdr[2] != QNAV_BOARD_STORE_FORMAT) {
        return 0;
    }
    len = (uint16_t)(hdr[4] | ((uint16_t)hdr[5] << 8));
    want = (uint16_t)(hdr[6] | ((uint16_t)hdr[7] << 8));
    if (len == 0u || len > QNAV_LINK_POLICY_WEIGHTS_MAX_BYTES ||
        !hal->nvm_read(hal->ctx, (uint16_t)(addr + QNAV_BOARD_STORE_HEADER_BYTES), blob, len) ||
        slot_crc(hdr, blob, len) != want ||
        qnav_link_policy_from_blob(blob, len, policy) != QNAV_LINK_OK) {
        return 0;
    }
    *crc = qnav_link_crc16(QNAV_LINK_CRC16_INIT, blob, len);
    *seq = hdr[3];
    return 1;
}

uint8_t qnav_board_store_load(const qnav_board_hal_t *hal, uint16_t offset,
                              qnav_policy_t *policy, uint16_t *crc, uint8_t *slot,
                              uint8_t *seq)
{
    qnav_policy_t p[2];
    uint16_t c[2];
    uint8_t s[2];
    uint8_t ok[2];
    uint8_t k;
    uint8_t pick;
    if (!have_nvm(hal, offset)) {
        return 0;
    }
    for (k = 0; k < 2u; ++k) {
        ok[k] = read_slot(hal, slot_addr(offset, k), &p[k], &c[k], &s[k]);
    }
    if (!ok[0] && !ok[1]) {
        return 0;
    }
    /* both whole: the newer by sequence (mod 256, a step of 1..127 ahead is newer) */
    if (ok[0] && ok[1]) {
        pick = (uint8_t)((uint8_t)(s[1] - s[0]) >= 1u && (uint8_t)(s[1] - s[0]) <= 127u);
    } else {
        pick = ok[1];
    }
    *policy = p[pick];
    *crc = c[pick];
    *slot = pick;
    *seq = s[pick];
    return 1;
}

uint8_t qnav_board_store_save(const qnav_board_hal_t *hal, uint16_t offset,
                              const qnav_policy_t *policy, uint16_t *crc, uint8_t *slot,
                              uint8_t *seq)
{
    uint8_t hdr[QNAV_BOARD_STORE_HEADER_BYTES];
    uint8_t blob[QNAV_LINK_POLICY_WEIGHTS_MAX_BYTES];
    static const uint8_t erased[2] = {0xFFu, 0xFFu};
    int32_t n;
    uint16_t len;
    uint16_t sc;
    uint8_t to;
    uint8_t next;
    uint16_t addr;
    if (!have_nvm(hal, offset)) {
        return 0;
    }
    n = qnav_link_policy_to_blob(policy, blob, (uint16_t)sizeof blob);
    if (n <= 0) {
        return 0;
    }
    len = (uint16_t)n;
    to = (uint8_t)(*slot == 0u ? 1u : 0u);
    next = (uint8_t)(*slot == 0xFFu ? 1u : (uint8_t)(*seq + 1u));
    addr = slot_addr(offset, to);
    hdr[0] = MAGIC0;
    hdr[1] = MAGIC1;
    hdr[2] = QNAV_BOARD_STORE_FORMAT;
    hdr[3] = next;
    hdr[4] = (uint8_t)(len & 0xFFu);
    hdr[5] = (uint8_t)(len >> 8);
    sc = slot_crc(hdr, blob, len);
    hdr[6] = (uint8_t)(sc & 0xFFu);
    hdr[7] = (uint8_t)(sc >> 8);
    if (!hal->nvm_write(hal->ctx, addr, erased, 2u) ||
        !hal->nvm_write(hal->ctx, (uint16_t)(addr + QNAV_BOARD_STORE_HEADER_BYTES), blob,
                        len) ||
        !hal->nvm_write(hal->ctx, (uint16_t)(addr + 2u), &hdr[2],
                        (uint16_t)(QNAV_BOARD_STORE_HEADER_BYTES - 2u)) ||
        !hal->nvm_write(hal->ctx, addr, hdr, 2u)) {
        return 0;
    }
    *slot = to;
    *seq = next;
    *crc = qnav_link_crc16(QNAV_LINK_CRC16_INIT, blob, len);
    return 1;
}
