/*
 * The board core (qnav/board.h): link frames in, a 10 Hz control tick, scans, pose,
 * telemetry and heartbeats out, the drive through the HAL, uploads kept in non-volatile
 * storage. No heap, integers only, no file-scope state: everything lives in the caller's
 * qnav_board_t.
 */
#include "qnav/board.h"

#include "qnav/drive.h"

#include <stddef.h>
#include <string.h>

#include "board_store.h"
#include "board_table.h"

/* Most UART bytes handled per receive, so one poll never starves the tick. */
#define UART_BURST 128u

/* Ticks between configuration reports (1 s at 10 Hz; 66 bytes each). */
#define CONFIG_EVERY 10u

/* Largest wheel travel integrated in one piece, um: keeps travel * cos in Q2.14 inside
 * int32 (131000 * 16384 < 2^31). */
#define STEP_MAX_UM INT32_C(131000)

void qnav_board_config_default(qnav_board_config_t *cfg)
{
    if (cfg == NULL) {
        return;
    }
    qnav_ctrl_config_default(&cfg->ctrl);
    cfg->tick_ms = 100;
    cfg->link_timeout_ms = 300;
    cfg->track_mm = 180;
    cfg->um_per_count = 1000;
    cfg->turn_full_deg = 90;
    cfg->nvm_offset = 0;
    cfg->controller = "body";
}

/* Where a CONFIG report goes: the pairs of a qnav_link_config_t (m), or straight into a
 * packed payload (p, cap bytes: the board's own report, without a struct on its stack). */
typedef struct {
    qnav_link_config_t *m;
    uint8_t *p;
    uint16_t cap;
} report_t;

/* One more (key, value) in the report, as far as it has room. */
static void report_field(report_t *r, uint8_t key, int32_t value)
{
    if (r->p != NULL) {
        (void)qnav_link_config_append(r->p, r->cap, key, value);
    } else if (r->m->n < QNAV_LINK_CONFIG_MAX_FIELDS) {
        r->m->key[r->m->n] = key;
        r->m->value[r->m->n] = value;
        r->m->n++;
    }
}

static void report_robot(const qnav_board_config_t *cfg, report_t *r)
{
#define QNAV_BOARD_REPORT_FIELD(id, name, member) report_field(r, (uint8_t)(id), (int32_t)cfg->member);
    QNAV_BOARD_ROBOT_FIELDS(QNAV_BOARD_REPORT_FIELD)
#undef QNAV_BOARD_REPORT_FIELD
}

static void report_map(const qnav_board_map_info_t *info, report_t *r)
{
#define QNAV_BOARD_REPORT_MAP_FIELD(id, name, member) report_field(r, (uint8_t)(id), (int32_t)info->member);
    QNAV_BOARD_MAP_FIELDS(QNAV_BOARD_REPORT_MAP_FIELD)
#undef QNAV_BOARD_REPORT_MAP_FIELD
}

/* A report into the pairs of m (appended to those it holds). */
static report_t into_struct(qnav_link_config_t *m)
{
    report_t r;
    r.m = m;
    r.p = NULL;
    r.cap = 0u;
    return r;
}

void qnav_board_config_report(const qnav_board_config_t *cfg, qnav_link_config_t *m)
{
    report_t r;
    if (cfg == NULL || m == NULL) {
        return;
    }
    r = into_struct(m);
    m->n = 0;
    report_robot(cfg, &r);
}

/* v little-endian at p; the byte after it. */
static uint8_t *put_le16(uint8_t *p, uint16_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
    return p + 2;
}

/* v at p; the byte after it. */
static uint8_t *put_le8(uint8_t *p, uint8_t v)
{
    p[0] = v;
    return p + 1;
}

/* A map configuration's field in the CRC's bytes, and how many it takes. */
#define PUT_MAP_FIELD(name, bits) p = put_le##bits(p, cfg->name);
#define MAP_FIELD_BYTES(name, bits) +(bits) / 8

void qnav_board_map_info(const qnav_map_config_t *cfg, uint32_t bytes,
                         qnav_board_map_info_t *info)
{
    /* every field, little-endian, in the struct's order: the CRC's bytes */
    uint8_t b[0 QNAV_MAP_CONFIG_FIELDS(MAP_FIELD_BYTES)];
    uint8_t *p = b;
    if (info == NULL) {
        return;
    }
    memset(info, 0, sizeof *info);
    if (cfg == NULL) {
        return;
    }
    info->on = 1u;
    info->bytes = bytes;
    info->cell_mm = cfg->cell_mm;
    info->reach_mm = cfg->reach_mm;
    info->compact = cfg->compact;
    QNAV_MAP_CONFIG_FIELDS(PUT_MAP_FIELD)
    info->crc = qnav_link_crc16(QNAV_LINK_CRC16_INIT, b, (uint16_t)(p - b));
}

void qnav_board_map_report(const qnav_board_map_info_t *info, qnav_link_config_t *m)
{
    report_t r;
    if (info == NULL || m == NULL) {
        return;
    }
    r = into_struct(m);
    report_map(info, &r);
}

/* The stored policy when one is whole and the controller takes it, else the built-in. */
static void load_policy(qnav_board_t *bot)
{
    const qnav_ctrl_config_t *cc = &bot->cfg.ctrl;
    qnav_policy_t stored;
    uint16_t crc = 0;
    uint8_t slot = 0xFFu;
    uint8_t seq = 0;
    bot->store_slot = 0xFFu;
    bot->store_seq = 0;
    if (qnav_board_store_load(&bot->hal, bot->cfg.nvm_offset, &stored, &crc, &slot, &seq)) {
        /* the slot is remembered even if refused, so the next commit keeps it intact */
        bot->store_slot = slot;
        bot->store_seq = seq;
        if (qnav_nav_init_named(&bot->nav, bot->cfg.controller, cc, &stored) == QNAV_OK) {
            bot->policy = stored;
            bot->policy_crc = crc;
            bot->policy_source = QNAV_BOARD_POLICY_STORED;
            bot->ctrl_ready = 1;
            qnav_board_table_start(bot);
            return;
        }
    }
    qnav_policy_prob_default(&bot->policy);
    bot->policy_source = QNAV_BOARD_POLICY_BUILTIN;
    bot->ctrl_ready = (uint8_t)(qnav_nav_init_named(&bot->nav, bot->cfg.controller, cc,
                                                    &bot->policy) == QNAV_OK);
    bot->policy_crc = qnav_link_policy_crc(&bot->policy);
    qnav_board_table_start(bot);
}

qnav_board_status_t qnav_board_init(qnav_board_t *bot, const qnav_board_config_t *cfg,
                                    const qnav_board_hal_t *hal)
{
    if (bot == NULL || cfg == NULL || hal == NULL || hal->millis == NULL ||
        hal->sonar_read == NULL || hal->heading_cdeg == NULL || hal->drive == NULL ||
        hal->uart_read == NULL || hal->uart_write == NULL) {
        return QNAV_BOARD_E_NULL;
    }
    if (cfg->ctrl.n_sectors < 1u || cfg->ctrl.n_sectors > QNAV_LINK_MAX_SECTORS ||
        cfg->ctrl.max_range_mm == 0u || cfg->tick_ms == 0u || cfg->link_timeout_ms == 0u ||
        cfg->um_per_count == 0u) {
        return QNAV_BOARD_E_CONFIG;
    }
    /* everything starts at zero (no mode, no goal, link not heard, counters 0, pose at
     * the origin) */
    memset(bot, 0, sizeof *bot);
    bot->cfg = *cfg;
    bot->hal = *hal;
    qnav_link_rx_init(&bot->rx);
    qnav_link_tx_init(&bot->tx);
    qnav_link_upload_init(&bot->buf.upload);
    bot->cmd.flags = QNAV_LINK_CMD_STOP;
    bot->hal.drive(bot->hal.ctx, 0, 0, bot->rolling);
    load_policy(bot);
    if (bot->hal.odometry_read != NULL) {
        bot->hal.odometry_read(bot->hal.ctx, &bot->odo_left, &bot->odo_right);
    }
    bot->pose.heading_cdeg = bot->hal.heading_cdeg(bot->hal.ctx);
    bot->next_tick_ms = bot->hal.millis(bot->hal.ctx);
    return bot->ctrl_ready ? QNAV_BOARD_OK : QNAV_BOARD_E_CTRL;
}

static void send(qnav_board_t *bot, uint8_t id, const uint8_t *payload, int32_t len)
{
    (void)qnav_link_send(&bot->tx, id, payload, len, bot->wire, (uint16_t)sizeof bot->wire,
                         bot->hal.uart_write, bot->hal.ctx);
}

/* A committed upload: switch controllers only when the new one initialises, then keep it
 * in storage. The drive is stopped first: no tick runs while the new controller
 * initialises (a 2-input network's init copies the row shapes the blob carries, or
 * without them evaluates every row of keys, up to about 1.2 s on the ATmega128) and the
 * EEPROM write blocks for milliseconds a byte. The policy's CRC is that of its blob
 * without shapes, as navbridge and a start-up from storage compute it. */
static qnav_status_t init_carried(qnav_board_t *bot, const qnav_policy_t *policy,
                                  const uint8_t *shapes)
{
    return qnav_nav_init_carried(&bot->nav, qnav_nav_find(bot->cfg.controller), &bot->cfg.ctrl,
                                 policy, shapes, shapes != NULL ? QNAV_SHAPES_BYTES : 0u);
}

static void commit_upload(qnav_board_t *bot, const qnav_link_policy_commit_t *cm)
{
    qnav_policy_t fresh;
    qnav_link_policy_ack_t ack;
    uint8_t p[QNAV_LINK_POLICY_ACK_BYTES];
    uint16_t crc;
    int8_t status = qnav_link_upload_commit(&bot->buf.upload, cm, &fresh);

    if (status == QNAV_LINK_ACK_OK) {
        bot->hal.drive(bot->hal.ctx, 0, 0, bot->rolling);
        if (init_carried(bot, &fresh, qnav_link_blob_shapes(bot->buf.upload.blob, cm->total)) ==
            QNAV_OK) {
            bot->policy = fresh;
            bot->policy_crc = qnav_link_policy_crc(&fresh);
            bot->policy_source = QNAV_BOARD_POLICY_UPLOADED;
            bot->ctrl_ready = 1;
            bot->stats.uploads_ok++;
            qnav_board_table_start(bot);
            if (!qnav_board_store_save(&bot->hal, bot->cfg.nvm_offset, &fresh, &crc,
                                       &bot->store_slot, &bot->store_seq)) {
                bot->stats.store_writes_failed++;
            }
        } else {
            /* keep driving with the policy we had */
            bot->ctrl_ready =
                (uint8_t)(qnav_nav_init_named(&bot->nav, bot->cfg.controller, &bot->cfg.ctrl,
                                              &bot->policy) == QNAV_OK);
            qnav_board_table_start(bot);
            status = QNAV_LINK_ACK_REJECTED;
        }
    }
    if (status != QNAV_LINK_ACK_OK) {
        bot->stats.uploads_refused++;
        qnav_board_table_resume(bot);
    }
    ack.status = status;
    ack.reserved = 0;
    ack.crc = bot->policy_crc;
    send(bot, QNAV_LINK_MSG_POLICY_ACK, p, qnav_link_policy_ack_pack(&ack, p, sizeof p));
}

static void on_heartbeat(qnav_board_t *bot, const qnav_link_frame_t *f)
{
    qnav_link_heartbeat_t hb;
    if (qnav_link_heartbeat_unpack(f->payload, f->len, &hb) != QNAV_LINK_OK) {
        return;
    }
    bot->stats.peer_protocol = hb.protocol;
    if (hb.protocol != QNAV_LINK_PROTOCOL_VERSION) {
        /* a bridge of another version: its mode and goals are not ours to follow */
        bot->stats.peer_refused++;
        bot->mode = 0;
        return;
    }
    if (hb.mode == QNAV_LINK_MODE_OFFBOARD || hb.mode == QNAV_LINK_MODE_ONBOARD) {
        bot->mode = hb.mode;
    }
    bot->hold_stop = (uint8_t)((hb.state & QNAV_LINK_STATE_STOPPED) != 0u);
}

static void on_frame(qnav_board_t *bot, const qnav_link_frame_t *f, uint32_t now)
{
    bot->last_rx_ms = now;
    bot->heard = 1;
    switch (f->msg_id) {
    case QNAV_LINK_MSG_GOAL: {
        qnav_link_goal_t g;
        if (qnav_link_goal_unpack(f->payload, f->len, &g) == QNAV_LINK_OK) {
            bot->goal = g;
            bot->have_goal = (uint8_t)(g.goal_id != 0u);
        }
        break;
    }
    case QNAV_LINK_MSG_COMMAND: {
        qnav_link_command_t c;
        if (qnav_link_command_unpack(f->payload, f->len, &c) == QNAV_LINK_OK) {
            if (c.flags & QNAV_LINK_CMD_STOP) {
                bot->hold_stop = 1;
            } else if (bot->mode == QNAV_LINK_MODE_OFFBOARD) {
                bot->hold_stop = 0;
            }
            bot->cmd = c;
            bot->cmd_ms = now;
            bot->stats.commands++;
            bot->stats.last_command_seq = c.scan_seq;
        }
        break;
    }
    case QNAV_LINK_MSG_HEARTBEAT:
        on_heartbeat(bot, f);
        break;
    case QNAV_LINK_MSG_POLICY_CHUNK: {
        qnav_link_policy_chunk_t c;
        if (qnav_link_policy_chunk_unpack(f->payload, f->len, &c) == QNAV_LINK_OK) {
            qnav_board_table_yield(bot);
            (void)qnav_link_upload_chunk(&bot->buf.upload, &c);
        }
        break;
    }
    case QNAV_LINK_MSG_POLICY_COMMIT: {
        qnav_link_policy_commit_t cm;
        if (qnav_link_policy_commit_unpack(f->payload, f->len, &cm) == QNAV_LINK_OK) {
            qnav_board_table_yield(bot);
            commit_upload(bot, &cm);
        }
        break;
    }
    default:
        break; /* scans, poses and acks only flow to the bridge */
    }
}

void qnav_board_receive(qnav_board_t *bot)
{
    uint16_t k;
    uint32_t now;
    qnav_link_frame_t f;
    if (bot == NULL) {
        return;
    }
    now = bot->hal.millis(bot->hal.ctx);
    for (k = 0; k < UART_BURST; ++k) {
        int16_t b = bot->hal.uart_read(bot->hal.ctx);
        if (b < 0) {
            break;
        }
        if (qnav_link_rx_feed(&bot->rx, (uint8_t)b, &f)) {
            on_frame(bot, &f, now);
        }
    }
}

void qnav_board_poll(qnav_board_t *bot)
{
    uint32_t now;
    if (bot == NULL) {
        return;
    }
    qnav_board_receive(bot);
    now = bot->hal.millis(bot->hal.ctx);
    if ((int32_t)(now - bot->next_tick_ms) >= 0) {
        bot->next_tick_ms += bot->cfg.tick_ms;
        if ((int32_t)(now - bot->next_tick_ms) > (int32_t)bot->cfg.tick_ms) {
            bot->next_tick_ms = now + bot->cfg.tick_ms; /* fell behind: do not burst */
        }
        qnav_board_tick(bot);
    }
    /* one piece of a table build per poll, so the UART is drained between pieces */
    if (bot->table_state == QNAV_BOARD_TABLE_BUILDING &&
        (int32_t)(bot->next_tick_ms - bot->hal.millis(bot->hal.ctx)) >=
            (int32_t)qnav_board_table_need_ms(bot)) {
        (void)qnav_board_table_work(bot);
    }
}

/* Dead reckoning: the mean wheel travel since the last tick along the mid-tick heading. */
static void update_pose(qnav_board_t *bot)
{
    int32_t l = bot->odo_left;
    int32_t r = bot->odo_right;
    int32_t step;
    int16_t c;
    int16_t s;
    qnav_cdeg_t h = bot->hal.heading_cdeg(bot->hal.ctx);
    qnav_cdeg_t h0 = bot->pose.heading_cdeg;
    if (bot->hal.odometry_read != NULL) {
        bot->hal.odometry_read(bot->hal.ctx, &l, &r);
    }
    /* counts wrap at 2^32: differences in unsigned arithmetic; a tick moves far less
     * than 2^15 counts */
    step = (int32_t)(int16_t)(uint16_t)((uint32_t)l - (uint32_t)bot->odo_left) +
           (int32_t)(int16_t)(uint16_t)((uint32_t)r - (uint32_t)bot->odo_right);
    bot->odo_left = l;
    bot->odo_right = r;
    step = (step * (int32_t)bot->cfg.um_per_count) / 2;
    bot->rolling = qnav_drive_rolling(step, bot->cfg.tick_ms, bot->cfg.ctrl.v_max_mm_s);
    qnav_cos_sin_q14((int32_t)h0 + (int32_t)qnav_wrap_cdeg((int32_t)h - (int32_t)h0) / 2,
                       &c, &s);
    /* in pieces that keep piece * cos inside int32 (a long stall moves far in one tick) */
    while (step != 0) {
        int32_t piece = step > STEP_MAX_UM ? STEP_MAX_UM
                                           : (step < -STEP_MAX_UM ? -STEP_MAX_UM : step);
        bot->pose.x_um += (int32_t)((piece * (int32_t)c) / (int32_t)16384);
        bot->pose.y_um += (int32_t)((piece * (int32_t)s) / (int32_t)16384);
        step -= piece;
    }
    bot->pose.heading_cdeg = h;
}

/* Robot-frame destination bearing for the current goal; *dist_mm for a position goal. */
static qnav_cdeg_t goal_bearing(qnav_board_t *bot, uint32_t *dist_mm)
{
    *dist_mm = 0;
    if (!bot->have_goal) {
        return 0;
    }
    if (bot->goal.kind == QNAV_LINK_GOAL_POSITION) {
        int32_t dx = bot->goal.x_mm - bot->pose.x_um / (int32_t)1000;
        int32_t dy = bot->goal.y_mm - bot->pose.y_um / (int32_t)1000;
        qnav_cdeg_t world = qnav_atan2_cdeg(dy, dx, dist_mm);
        return qnav_wrap_cdeg((int32_t)world - (int32_t)bot->pose.heading_cdeg);
    }
    return qnav_wrap_cdeg((int32_t)bot->goal.bearing_cdeg -
                                (int32_t)bot->pose.heading_cdeg);
}

static void send_scan(qnav_board_t *bot, uint32_t now, qnav_cdeg_t bearing)
{
    /* packed straight from the ranges buffer (no second copy on the MCU) */
    uint8_t p[QNAV_LINK_MAX_PAYLOAD];
    uint16_t len = (uint16_t)(QNAV_LINK_SCAN_HEADER_BYTES + 2u * bot->cfg.ctrl.n_sectors);
    uint16_t gid = bot->have_goal ? bot->goal.goal_id : 0u;
    uint16_t k;
    p[0] = (uint8_t)(now & 0xFFu);
    p[1] = (uint8_t)((now >> 8) & 0xFFu);
    p[2] = (uint8_t)((now >> 16) & 0xFFu);
    p[3] = (uint8_t)(now >> 24);
    p[4] = (uint8_t)((uint16_t)bearing & 0xFFu);
    p[5] = (uint8_t)((uint16_t)bearing >> 8);
    p[6] = (uint8_t)(bot->cfg.ctrl.max_range_mm & 0xFFu);
    p[7] = (uint8_t)(bot->cfg.ctrl.max_range_mm >> 8);
    p[8] = (uint8_t)(bot->cfg.ctrl.n_sectors & 0xFFu);
    p[9] = (uint8_t)(bot->cfg.ctrl.n_sectors >> 8);
    p[10] = (uint8_t)(gid & 0xFFu);
    p[11] = (uint8_t)(gid >> 8);
    for (k = 0; k < bot->cfg.ctrl.n_sectors; ++k) {
        p[QNAV_LINK_SCAN_HEADER_BYTES + 2u * k] = (uint8_t)(bot->ranges[k] & 0xFFu);
        p[QNAV_LINK_SCAN_HEADER_BYTES + 2u * k + 1u] = (uint8_t)(bot->ranges[k] >> 8);
    }
    bot->stats.last_scan_seq = bot->tx.next_seq;
    send(bot, QNAV_LINK_MSG_SCAN, p, (int32_t)len);
}

/* The heartbeat, and the pose with the distance to the goal and what the map did to the
 * escape memory this tick (esc: its clear and grow_mm, the rest unused). */
static void send_status(qnav_board_t *bot, uint32_t now, uint8_t moving, uint32_t dist_mm,
                        const qnav_link_pose_t *esc)
{
    qnav_link_heartbeat_t hb;
    qnav_link_pose_t ps;
    uint8_t p[QNAV_LINK_POSE_BYTES > QNAV_LINK_HEARTBEAT_BYTES ? QNAV_LINK_POSE_BYTES
                                                               : QNAV_LINK_HEARTBEAT_BYTES];
    hb.uptime_ms = now;
    hb.mode = bot->mode;
    hb.state = (uint8_t)((bot->link_ok ? QNAV_LINK_STATE_LINK_OK : 0u) |
                         (moving ? QNAV_LINK_STATE_MOVING : 0u) |
                         (bot->ctrl_ready ? QNAV_LINK_STATE_POLICY : 0u) |
                         (moving ? 0u : QNAV_LINK_STATE_STOPPED) |
                         (bot->policy_source != QNAV_BOARD_POLICY_BUILTIN
                              ? QNAV_LINK_STATE_STORED
                              : 0u) |
                         (bot->table_state == QNAV_BOARD_TABLE_IN_USE ? QNAV_LINK_STATE_TABLE
                                                                      : 0u));
    hb.rx_ok = (uint16_t)bot->rx.stats.frames_ok;
    hb.rx_dropped = (uint16_t)qnav_link_rx_dropped_total(&bot->rx);
    hb.policy_crc = bot->policy_crc;
    hb.protocol = QNAV_LINK_PROTOCOL_VERSION;
    send(bot, QNAV_LINK_MSG_HEARTBEAT, p, qnav_link_heartbeat_pack(&hb, p, sizeof p));
    ps.board_ms = now;
    ps.x_mm = bot->pose.x_um / (int32_t)1000;
    ps.y_mm = bot->pose.y_um / (int32_t)1000;
    ps.heading_cdeg = bot->pose.heading_cdeg;
    ps.goal_id = bot->have_goal ? bot->goal.goal_id : 0u;
    ps.goal_distance_mm = dist_mm;
    ps.escape_clear = esc->escape_clear;
    ps.escape_grow_mm = esc->escape_grow_mm;
    send(bot, QNAV_LINK_MSG_POSE, p, qnav_link_pose_pack(&ps, p, sizeof p));
}

/* The robot configuration this board runs (navbridge --robot compares it with the
 * profile's): when the link comes up, so it precedes the first scan a bridge acts on, and
 * every CONFIG_EVERY ticks for a bridge that attached while the link stayed up. */
static void send_config(qnav_board_t *bot)
{
    qnav_board_map_info_t map;
    uint8_t p[QNAV_LINK_CONFIG_MAX_BYTES];
    report_t r;
    r.m = NULL;
    r.p = p;
    r.cap = (uint16_t)sizeof p;
    p[0] = 0u; /* no pairs yet */
    report_robot(&bot->cfg, &r);
    /* the map it runs: placed at each goal, laid out by the caller, or none */
    if (bot->place_map != NULL) {
        qnav_board_map_info(bot->place_cfg, (uint32_t)bot->place_len, &map);
    } else {
        qnav_board_map_info(bot->map != NULL ? &bot->map->cfg : NULL, 0u, &map);
    }
    report_map(&map, &r);
    send(bot, QNAV_LINK_MSG_CONFIG, p, (int32_t)(1u + 5u * p[0]));
}

/* This tick's decision: the controller's (onboard) or navbridge's fresh command
 * (offboard); zero otherwise. */
static void decide(qnav_board_t *bot, uint32_t now, const qnav_ctrl_input_t *in,
                   qnav_ctrl_output_t *out)
{
    out->heading_deg = 0;
    out->speed = 0;
    out->quality = 0;
    out->flags = 0;
    out->escape = in->escape; /* kept as it was unless the controller decides */
    if (bot->mode == QNAV_LINK_MODE_ONBOARD) {
        qnav_nav_step(&bot->nav, in, out);
    } else if (bot->mode == QNAV_LINK_MODE_OFFBOARD &&
               (now - bot->cmd_ms) <= bot->cfg.link_timeout_ms) {
        out->heading_deg = bot->cmd.heading_deg;
        out->speed = bot->cmd.speed;
        out->quality = bot->cmd.quality;
        out->flags = (uint8_t)(bot->cmd.flags & 0x7Fu);
    }
}

/* A new position goal with qnav_board_place_maps: the map afresh over the square midway
 * between the robot and the goal (qnav_map_place), or none when they do not both fit a cell
 * inside it. */
static void place_map(qnav_board_t *bot)
{
    int32_t x0, y0;
    uint32_t side;
    bot->placed_goal = bot->goal.goal_id;
    bot->map = NULL;
    if (qnav_map_place(bot->place_cfg, bot->place_len, bot->pose.x_um / 1000,
                       bot->pose.y_um / 1000, bot->goal.x_mm, bot->goal.y_mm, &x0, &y0,
                       &side) &&
        qnav_map_init(bot->place_map, bot->place_cfg, &bot->cfg.ctrl, x0, y0, side, side,
                      bot->place_buf, bot->place_len) == QNAV_OK) {
        bot->map = bot->place_map;
    }
}

/* With a map and a position goal: mark this tick's readings, and steer to the plan's
 * sub-goal (in's goal bearing and range; *dist_mm the planned distance). The map clears or
 * grows in's escape memory when its plan jumps or grows; esc gets the same verdict for the
 * POSE, for an offboard controller whose memory the map cannot touch. Reached through
 * bot->map_tick, which only qnav_board_set_map and qnav_board_place_maps set: a firmware
 * that calls neither links no map code. */
static void map_tick(void *board, qnav_ctrl_input_t *in, uint32_t *dist_mm, qnav_link_pose_t *esc)
{
    qnav_board_t *bot = (qnav_board_t *)board;
    if (bot->place_map != NULL && bot->have_goal && bot->goal.kind == QNAV_LINK_GOAL_POSITION &&
        bot->goal.goal_id != bot->placed_goal) {
        place_map(bot);
    }
    if (bot->map != NULL && bot->have_goal && bot->goal.kind == QNAV_LINK_GOAL_POSITION) {
        const qnav_map_pose_t pose = {bot->pose.x_um / (int32_t)1000, bot->pose.y_um / (int32_t)1000,
                                      bot->pose.heading_cdeg};
        int got;
        if (bot->place_map != NULL) { /* a placed map follows the robot */
            (void)qnav_map_follow(bot->map, &pose, bot->goal.x_mm, bot->goal.y_mm);
        }
        qnav_map_observe(bot->map, bot->ranges, &pose);
        got = qnav_map_guide(bot->map, &pose, bot->goal.x_mm, bot->goal.y_mm, in);
        if (got != 0) {
            *dist_mm = in->goal_range_mm;
        }
        esc->escape_clear = (uint8_t)((got & QNAV_MAP_ESCAPE_CLEARED) != 0);
        esc->escape_grow_mm = (got & QNAV_MAP_ESCAPE_GROWN) != 0 ? qnav_map_grown_mm(bot->map) : 0u;
    }
}

/* The link went quiet: the bridge may come back restarted, and an upload under way ends. */
static void on_link_lost(qnav_board_t *bot)
{
    bot->stats.link_lost++;
    qnav_link_rx_reset_seq(&bot->rx);
    if (qnav_board_table_state(bot) != QNAV_BOARD_TABLE_BUILDING) {
        /* (a build owns the shared buffer, and dropped any upload when it began) */
        qnav_link_upload_init(&bot->buf.upload);
        qnav_board_table_resume(bot);
    }
}

void qnav_board_tick(qnav_board_t *bot)
{
    qnav_link_command_t tel;
    qnav_link_pose_t esc = {0};
    qnav_ctrl_input_t in = {0};
    qnav_ctrl_output_t out;
    uint8_t p[QNAV_LINK_COMMAND_BYTES];
    uint32_t now;
    uint32_t dist_mm;
    uint16_t n;
    uint16_t k;
    uint16_t scan_seq;
    uint8_t was_ok;
    uint8_t active;
    uint8_t moving;

    if (bot == NULL) {
        return;
    }
    now = bot->hal.millis(bot->hal.ctx);
    bot->stats.ticks++;
    was_ok = bot->link_ok;
    bot->link_ok = (uint8_t)(bot->heard && (now - bot->last_rx_ms) <= bot->cfg.link_timeout_ms);
    if (was_ok && !bot->link_ok) {
        on_link_lost(bot);
    }

    if ((bot->link_ok && !was_ok) || bot->stats.ticks % CONFIG_EVERY == 0u) {
        send_config(bot);
    }

    /* sense */
    update_pose(bot);
    n = bot->hal.sonar_read(bot->hal.ctx, bot->ranges, bot->cfg.ctrl.n_sectors);
    for (k = n; k < bot->cfg.ctrl.n_sectors; ++k) {
        bot->ranges[k] = bot->cfg.ctrl.max_range_mm; /* a missing sonar reads as clear */
    }
    in.ranges_mm = bot->ranges;
    in.goal_bearing_cdeg = goal_bearing(bot, &dist_mm);
    /* the previous decision, seen from where the robot points now (3-input policies), the
     * distance to a position goal (0 for a bearing goal: no escape) and the memory */
    qnav_ctrl_carry_input(&bot->carry, bot->have_goal ? bot->goal.goal_id : 0u, dist_mm,
                          bot->pose.heading_cdeg, &in);
    if (bot->map_tick != NULL) {
        bot->map_tick(bot, &in, &dist_mm, &esc);
    }

    decide(bot, now, &in, &out);
    qnav_ctrl_carry_output(&bot->carry, &out);
    active = (uint8_t)(bot->link_ok && !bot->hold_stop && bot->have_goal && bot->mode != 0u);
    if (!active) {
        out.speed = 0;
    }
    /* a decision of speed 0 toward a heading is a turn in place (the escape's, the speed
     * guard's): the robot moves, as the simulator's does */
    moving = (uint8_t)(active && (out.speed > 0 || out.heading_deg != 0));
    if (!moving) {
        bot->stats.stopped_ticks++;
    }
    /* act: the drive is set every tick, to 0 whenever anything is wrong */
    bot->hal.drive(bot->hal.ctx, active ? out.heading_deg : 0, out.speed, bot->rolling);

    /* report: heartbeat (before the decision, so the bridge labels it with the current
     * policy), pose (before the scan, so navbridge's offboard controller has this tick's
     * distance to the goal with the scan, as the board's own has), scan, onboard decision */
    send_status(bot, now, moving, dist_mm, &esc);
    send_scan(bot, now, in.goal_bearing_cdeg);
    scan_seq = bot->stats.last_scan_seq;
    if (bot->mode == QNAV_LINK_MODE_ONBOARD) {
        tel.scan_seq = scan_seq;
        tel.heading_deg = out.heading_deg;
        tel.speed = out.speed;
        tel.quality = out.quality;
        tel.flags = (uint8_t)(out.flags | (moving ? 0u : QNAV_LINK_CMD_STOP));
        tel.reserved = 0;
        send(bot, QNAV_LINK_MSG_COMMAND, p, qnav_link_command_pack(&tel, p, sizeof p));
    }
}

int qnav_board_set_map(qnav_board_t *bot, qnav_map_t *map)
{
    if (bot == NULL) {
        return 0;
    }
    bot->map = map;
    bot->place_map = NULL;
    bot->map_tick = map != NULL ? map_tick : NULL;
    return 1;
}

int qnav_board_place_maps(qnav_board_t *bot, qnav_map_t *map, const qnav_map_config_t *cfg,
                          void *buf, size_t len)
{
    if (bot == NULL || (map != NULL && (cfg == NULL || buf == NULL))) {
        return 0;
    }
    bot->place_map = map;
    bot->place_cfg = cfg;
    bot->place_buf = buf;
    bot->place_len = len;
    bot->placed_goal = 0u;
    bot->map = NULL;
    bot->map_tick = map != NULL ? map_tick : NULL;
    return 1;
}

const qnav_board_stats_t *qnav_board_stats(const qnav_board_t *bot)
{
    return bot != NULL ? &bot->stats : NULL;
}

const qnav_board_pose_t *qnav_board_pose(const qnav_board_t *bot)
{
    return bot != NULL ? &bot->pose : NULL;
}

qnav_board_policy_source_t qnav_board_policy_source(const qnav_board_t *bot)
{
    return bot != NULL ? (qnav_board_policy_source_t)bot->policy_source
                       : QNAV_BOARD_POLICY_BUILTIN;
}
