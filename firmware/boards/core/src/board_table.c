/*
 * Table mode on the board (qnav/board.h, "Table mode on the board"): an uploaded 2-input
 * network compiled, a page at a time, into the HAL's table area, then read by the step in
 * table mode. Private to the core: board.c calls qnav_board_table_start() whenever the
 * controller was made from a new policy.
 */
#include "board_table.h"

#include <stddef.h>
#include <string.h>

#include "qnav/flash.h"

/* One u16 of the area, read as the controller reads tables (LPM on an AVR). */
static uint16_t area_u16(const qnav_board_hal_t *hal, uint16_t at)
{
    return QNAV_FLASH_READ_U16(hal->table_area + at);
}

static uint8_t area_fits(const qnav_board_hal_t *hal)
{
    return (uint8_t)(hal->table_area != NULL && hal->table_write_page != NULL &&
                     hal->table_page_bytes >= 2u &&
                     hal->table_page_bytes <= QNAV_BOARD_TABLE_PAGE_MAX &&
                     (hal->table_page_bytes & 1u) == 0u &&
                     (uint32_t)hal->table_pages * hal->table_page_bytes >= QNAV_BOARD_TABLE_BYTES);
}

/* The path-quality controller of a running 2-input network, or NULL (no table for it). */
static qnav_ctrl_t *network_ctrl(qnav_board_t *bot)
{
    if (!QNAV_WITH_TABLE || !bot->ctrl_ready || bot->policy.kind != QNAV_POLICY_NET ||
        bot->policy.u.net.inputs != QNAV_NET_INPUTS_PAPER) {
        return NULL;
    }
    return qnav_nav_paths(&bot->nav);
}

/* The record's u16 at index i (0 magic, 1 format and rank, 2 policy CRC, 3 keys' CRC). */
static uint16_t record_word(const qnav_board_t *bot, const qnav_ctrl_t *ctrl, uint8_t i)
{
    switch (i) {
    case 0:
        return QNAV_BOARD_TABLE_MAGIC;
    case 1:
        return (uint16_t)(QNAV_BOARD_TABLE_FORMAT | (uint16_t)qnav_ctrl_rank(ctrl) * 256u);
    case 2:
        return bot->policy_crc;
    default:
        return bot->table_crc;
    }
}

/* Whether the area holds this policy's table whole: the record, the keys' CRC, and one
 * key of every level as the network gives it (a table a different key function made). */
static uint8_t area_holds(qnav_board_t *bot, const qnav_ctrl_t *ctrl)
{
    const qnav_board_hal_t *hal = &bot->hal;
    uint16_t crc = QNAV_LINK_CRC16_INIT;
    uint16_t at;
    uint8_t i;
    for (i = 0; i < 3u; ++i) {
        if (area_u16(hal, (uint16_t)(QNAV_BOARD_TABLE_KEY_BYTES + 2u * i)) != record_word(bot, ctrl, i)) {
            return 0;
        }
    }
    for (at = 0; at < QNAV_BOARD_TABLE_KEY_BYTES; at = (uint16_t)(at + 2u)) {
        const uint16_t w = area_u16(hal, at);
        uint8_t b[2];
        memcpy(b, &w, sizeof b);
        crc = qnav_link_crc16(crc, b, 2u);
    }
    if (area_u16(hal, (uint16_t)(QNAV_BOARD_TABLE_KEY_BYTES + 6u)) != crc) {
        return 0;
    }
    for (i = 0; i < QNAV_DIST_LEVELS; ++i) {
        const uint8_t d = (uint8_t)(((uint16_t)i * 47u) % (QNAV_DTHETA_MAX + 1u));
        const uint16_t k = (uint16_t)((uint16_t)i * (QNAV_DTHETA_MAX + 1u) + d);
        if ((qnav_qkey_t)area_u16(hal, (uint16_t)(2u * k)) != qnav_ctrl_key(ctrl, i, d)) {
            return 0;
        }
    }
    return 1;
}

/* The controller reads the area from now on; on a refusal (none expected: the network
 * took the same configuration) it is made again from the policy, and the area left. */
static void use_area(qnav_board_t *bot, qnav_ctrl_t *ctrl)
{
    qnav_ctrl_config_t cfg;
    const qnav_rank_t rank = qnav_ctrl_rank(ctrl);
    qnav_nav_config(qnav_nav_method(&bot->nav), &bot->cfg.ctrl, &cfg);
    if (qnav_ctrl_init_table(ctrl, &cfg, (const qnav_qkey_t *)(const void *)bot->hal.table_area,
                             rank) == QNAV_OK) {
        bot->table_state = QNAV_BOARD_TABLE_IN_USE;
        return;
    }
    bot->table_state = QNAV_BOARD_TABLE_NONE;
    bot->ctrl_ready = (uint8_t)(qnav_nav_init_named(&bot->nav, bot->cfg.controller, &bot->cfg.ctrl,
                                                    &bot->policy) == QNAV_OK);
}

void qnav_board_table_start(qnav_board_t *bot)
{
    qnav_ctrl_t *ctrl = network_ctrl(bot);
    bot->table_state = QNAV_BOARD_TABLE_NONE;
    bot->table_stopped = 0;
    bot->table_at = 0;
    bot->table_done = 0;
    bot->table_crc = QNAV_LINK_CRC16_INIT;
    if (ctrl == NULL || !area_fits(&bot->hal)) {
        return;
    }
    if (area_holds(bot, ctrl)) {
        bot->stats.tables_reused++;
        use_area(bot, ctrl);
        return;
    }
    qnav_link_upload_init(&bot->buf.upload); /* the build owns the buffer now */
    bot->table_state = QNAV_BOARD_TABLE_BUILDING;
}

void qnav_board_table_yield(qnav_board_t *bot)
{
    if (bot->table_state == QNAV_BOARD_TABLE_BUILDING) {
        bot->table_state = QNAV_BOARD_TABLE_NONE;
        bot->table_stopped = 1;
        qnav_link_upload_init(&bot->buf.upload); /* its counts lay under the page */
    }
}

void qnav_board_table_resume(qnav_board_t *bot)
{
    if (bot->table_stopped) {
        qnav_board_table_start(bot);
    }
}

/* The next word of the area as the build writes it (keys, then the record, then 0xFF)
 * into the page buffer; returns 1 when it was a key. */
static uint8_t make_word(qnav_board_t *bot, const qnav_ctrl_t *ctrl)
{
    const uint16_t at = bot->table_at;
    uint8_t *out = &bot->buf.table_page[at % bot->hal.table_page_bytes];
    uint16_t w = 0xFFFFu;
    uint8_t key = 0;
    if (at < QNAV_BOARD_TABLE_KEY_BYTES) {
        const uint16_t k = (uint16_t)(at / 2u);
        const qnav_qkey_t q = qnav_ctrl_key(ctrl, (uint8_t)(k / (QNAV_DTHETA_MAX + 1u)),
                                            (uint8_t)(k % (QNAV_DTHETA_MAX + 1u)));
        memcpy(&w, &q, sizeof w);
        key = 1;
    } else if (at < QNAV_BOARD_TABLE_BYTES) {
        w = record_word(bot, ctrl, (uint8_t)((at - QNAV_BOARD_TABLE_KEY_BYTES) / 2u));
    }
    memcpy(out, &w, 2u);
    if (key) {
        bot->table_crc = qnav_link_crc16(bot->table_crc, out, 2u);
    }
    bot->table_at = (uint16_t)(at + 2u);
    return key;
}

/* A full page waits for its write. */
static uint8_t page_full(const qnav_board_t *bot)
{
    return (uint8_t)(bot->table_at > bot->table_done &&
                     bot->table_at % bot->hal.table_page_bytes == 0u);
}

uint16_t qnav_board_table_need_ms(const qnav_board_t *bot)
{
    if (bot == NULL || bot->table_state != QNAV_BOARD_TABLE_BUILDING) {
        return 0;
    }
    return page_full(bot) ? QNAV_BOARD_TABLE_WRITE_MS : QNAV_BOARD_TABLE_KEYS_MS;
}

uint8_t qnav_board_table_work(qnav_board_t *bot)
{
    qnav_ctrl_t *ctrl;
    uint8_t keys = 0;
    if (bot == NULL || bot->table_state != QNAV_BOARD_TABLE_BUILDING) {
        return 0;
    }
    ctrl = network_ctrl(bot);
    if (ctrl == NULL) {
        bot->table_state = QNAV_BOARD_TABLE_NONE;
        return 0;
    }
    if (!page_full(bot)) {
        do {
            keys = (uint8_t)(keys + make_word(bot, ctrl));
        } while (keys < QNAV_BOARD_TABLE_KEYS_PER_WORK && !page_full(bot));
        return 1;
    }
    if (!bot->hal.table_write_page(bot->hal.ctx,
                                   (uint16_t)(bot->table_at / bot->hal.table_page_bytes - 1u),
                                   bot->buf.table_page)) {
        bot->stats.table_writes_failed++;
        bot->table_state = QNAV_BOARD_TABLE_NONE;
        return 0;
    }
    bot->table_done = bot->table_at;
    if (bot->table_done < QNAV_BOARD_TABLE_BYTES) {
        return 1;
    }
    bot->stats.tables_built++;
    use_area(bot, ctrl);
    return 0;
}

qnav_board_table_state_t qnav_board_table_state(const qnav_board_t *bot)
{
    return bot != NULL ? (qnav_board_table_state_t)bot->table_state : QNAV_BOARD_TABLE_NONE;
}
