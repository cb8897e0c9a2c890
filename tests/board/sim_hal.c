/*
 * The scripted robot (sim_hal.h).
 */
#include "sim_hal.h"

#include <string.h>

#include "qnav/board.h"
#include "qnav/drive.h"
#include "qnav/robot_tekbot.h"

static uint32_t sim_millis(void *ctx)
{
    return ((sim_hal_t *)ctx)->now_ms;
}

static uint16_t sim_sonar(void *ctx, qnav_mm_t *ranges, uint16_t max)
{
    sim_hal_t *s = (sim_hal_t *)ctx;
    uint16_t n = s->n_ranges < max ? s->n_ranges : max;
    memcpy(ranges, s->ranges_mm, n * sizeof ranges[0]);
    return n;
}

static qnav_cdeg_t sim_heading(void *ctx)
{
    return ((sim_hal_t *)ctx)->heading_cdeg;
}

static void sim_odometry(void *ctx, int32_t *left, int32_t *right)
{
    sim_hal_t *s = (sim_hal_t *)ctx;
    *left = s->left_counts;
    *right = s->right_counts;
}

static void sim_drive(void *ctx, qnav_deg_t heading, qnav_q1_15_t speed, qnav_q1_15_t rolling)
{
    sim_hal_t *s = (sim_hal_t *)ctx;
    s->drive_heading = heading;
    s->drive_speed = speed;
    s->drive_rolling = rolling;
    qnav_drive_mix(heading, speed, rolling, QNAV_ROBOT_TEKBOT_TURN_FULL_DEG, &s->left, &s->right);
    s->motor_calls++;
}

static int16_t sim_uart_read(void *ctx)
{
    sim_hal_t *s = (sim_hal_t *)ctx;
    if (s->to_board_tail == s->to_board_head) {
        return -1;
    }
    return s->to_board[s->to_board_tail++ % SIM_HAL_QUEUE];
}

static void sim_uart_write(void *ctx, const uint8_t *b, uint16_t n)
{
    sim_hal_t *s = (sim_hal_t *)ctx;
    uint16_t i;
    for (i = 0; i < n && s->from_board_n < SIM_HAL_QUEUE; ++i) {
        s->from_board[s->from_board_n++] = b[i];
    }
}

static uint8_t sim_nvm_read(void *ctx, uint16_t addr, uint8_t *out, uint16_t n)
{
    sim_hal_t *s = (sim_hal_t *)ctx;
    if ((uint32_t)addr + n > SIM_HAL_NVM) {
        return 0;
    }
    memcpy(out, &s->nvm[addr], n);
    return 1;
}

static uint8_t sim_nvm_write(void *ctx, uint16_t addr, const uint8_t *b, uint16_t n)
{
    sim_hal_t *s = (sim_hal_t *)ctx;
    uint16_t i;
    if ((uint32_t)addr + n > SIM_HAL_NVM) {
        return 0;
    }
    for (i = 0; i < n; ++i) {
        if (s->nvm_cut_after != 0u && s->nvm_written >= s->nvm_cut_after) {
            return 0; /* the power is gone: nothing more reaches the EEPROM */
        }
        s->nvm[addr + i] = b[i];
        s->nvm_written++;
    }
    return 1;
}

void sim_hal_init(sim_hal_t *sim, qnav_board_hal_t *hal)
{
    memset(sim, 0, sizeof *sim);
    memset(sim->nvm, 0xFF, sizeof sim->nvm);
    sim->now_ms = 1000;
    hal->ctx = sim;
    hal->millis = sim_millis;
    hal->sonar_read = sim_sonar;
    hal->heading_cdeg = sim_heading;
    hal->odometry_read = sim_odometry;
    hal->drive = sim_drive;
    hal->uart_read = sim_uart_read;
    hal->uart_write = sim_uart_write;
    hal->nvm_read = sim_nvm_read;
    hal->nvm_write = sim_nvm_write;
    hal->nvm_bytes = SIM_HAL_NVM;
    hal->table_area = NULL;
    hal->table_page_bytes = 0;
    hal->table_pages = 0;
    hal->table_write_page = NULL;
}

static uint8_t sim_table_write(void *ctx, uint16_t page, const uint8_t *bytes)
{
    sim_hal_t *sim = (sim_hal_t *)ctx;
    if (page >= SIM_HAL_TABLE_PAGES ||
        (sim->table_fail_after != 0u && sim->table_pages_written >= sim->table_fail_after)) {
        return 0;
    }
    memcpy(&sim->table[(uint32_t)page * SIM_HAL_TABLE_PAGE], bytes, SIM_HAL_TABLE_PAGE);
    sim->table_pages_written++;
    return 1;
}

void sim_hal_table(sim_hal_t *sim, qnav_board_hal_t *hal)
{
    memset(sim->table, 0xFF, sizeof sim->table);
    hal->table_area = sim->table;
    hal->table_page_bytes = SIM_HAL_TABLE_PAGE;
    hal->table_pages = SIM_HAL_TABLE_PAGES;
    hal->table_write_page = sim_table_write;
}

void sim_hal_to_board(sim_hal_t *sim, const uint8_t *bytes, uint32_t n)
{
    uint32_t i;
    for (i = 0; i < n; ++i) {
        sim->to_board[sim->to_board_head++ % SIM_HAL_QUEUE] = bytes[i];
    }
}

static int queue_frame(sim_hal_t *sim, qnav_link_tx_t *tx, uint8_t id, const uint8_t *p,
                       int32_t n)
{
    uint8_t wire[QNAV_LINK_MAX_WIRE(QNAV_LINK_MAX_PAYLOAD)];
    int32_t w = n < 0 ? n : qnav_link_encode(tx, id, p, (uint16_t)n, wire, sizeof wire);
    if (w <= 0) {
        return -1;
    }
    sim_hal_to_board(sim, wire, (uint32_t)w);
    return 0;
}

int32_t sim_hal_blob(const qnav_policy_t *pol, uint8_t *blob, uint16_t cap)
{
    qnav_ctrl_config_t cfg;
    qnav_ctrl_t ctrl;
    uint8_t shapes[QNAV_SHAPES_BYTES];
    const uint8_t *carried = NULL;
    qnav_ctrl_config_default(&cfg);
    if (qnav_ctrl_init(&ctrl, &cfg, pol) == QNAV_OK &&
        qnav_ctrl_shapes_save(&ctrl, pol, shapes) == QNAV_OK) {
        carried = shapes;
    }
    return qnav_link_policy_to_blob_carried(pol, carried, blob, cap);
}

int sim_hal_upload(sim_hal_t *sim, qnav_link_tx_t *tx, const qnav_policy_t *pol,
                   uint16_t crc_xor)
{
    uint8_t blob[QNAV_LINK_POLICY_MAX_BYTES], p[QNAV_LINK_CHUNK_MAX_BYTES];
    qnav_link_policy_chunk_t c;
    qnav_link_policy_commit_t cm;
    int32_t n = sim_hal_blob(pol, blob, (uint16_t)sizeof blob);
    uint16_t off = 0;
    if (n <= 0) {
        return -1;
    }
    while (off < (uint16_t)n) {
        uint16_t len = (uint16_t)((uint16_t)n - off);
        len = len > QNAV_LINK_CHUNK_BYTES ? (uint16_t)QNAV_LINK_CHUNK_BYTES : len;
        c.offset = off;
        c.total = (uint16_t)n;
        c.len = (uint8_t)len;
        memcpy(c.data, &blob[off], len);
        if (queue_frame(sim, tx, QNAV_LINK_MSG_POLICY_CHUNK, p,
                        qnav_link_policy_chunk_pack(&c, p, sizeof p)) != 0) {
            return -1;
        }
        off = (uint16_t)(off + len);
    }
    cm.total = (uint16_t)n;
    cm.crc = (uint16_t)(qnav_link_crc16(QNAV_LINK_CRC16_INIT, blob, (uint16_t)n) ^ crc_xor);
    return queue_frame(sim, tx, QNAV_LINK_MSG_POLICY_COMMIT, p,
                       qnav_link_policy_commit_pack(&cm, p, sizeof p));
}
