/*
 * navbridge's core (bridge.h): link frames in, commands and LCM messages out, a watchdog
 * that stops the robot when the board goes quiet, and the onboard policy upload. No I/O of
 * its own: bytes leave through the write callback, messages through LCM and the log.
 */
#define _GNU_SOURCE /* getrandom */
#include "bridge.h"

#include <errno.h>
#include <string.h>
#include <sys/random.h>
#include <sys/types.h>
#include <time.h>

#include <math.h>

#include "qnav/board.h"
#include "qnav/clock.h"

#include "qnav/fixed_host.h"
#include "qnav_link_status_t.h"
#include "qnav_odometry_t.h"
#include "qnav_path_qualities_t.h"

/* Largest encoded LCM message we publish (path qualities: 360 * 6 bytes + header). */
#define PUBLISH_BUF 4096

int64_t qnav_bridge_utime(void)
{
    return qnav_wall_us();
}

uint16_t qnav_bridge_policy_crc(const qnav_policy_t *policy)
{
    return qnav_link_policy_crc(policy);
}

static int bridge_ctrl_reinit(qnav_bridge_ctrl_t *bc)
{
    qnav_ctrl_carry_reset(&bc->carry);
    return bc->method != NULL &&
           qnav_nav_init(&bc->nav, bc->method, &bc->cfg, &bc->policy) == QNAV_OK;
}

uint16_t qnav_bridge_config_crc(const qnav_ctrl_config_t *cfg, const char *controller)
{
    /* the fields a robot profile decides (the board's CONFIG list, one home), each as its
     * key and its value in 4 little-endian bytes; the scan's two set to 0 */
    qnav_board_config_t bc;
    uint8_t b[6 * 64];
    uint16_t n = 0;
    const char *name = controller != NULL ? controller : QNAV_BRIDGE_DEFAULT_CONTROLLER;
    memset(&bc, 0, sizeof bc);
    bc.ctrl = *cfg;
    bc.ctrl.n_sectors = 0u;
    bc.ctrl.max_range_mm = 0u;
#define QNAV_CRC_FIELD(id, field, member)                                                   \
    b[n++] = (uint8_t)(id);                                                                 \
    b[n++] = (uint8_t)(((uint32_t)bc.member) & 0xFFu);                                      \
    b[n++] = (uint8_t)((((uint32_t)bc.member) >> 8) & 0xFFu);                               \
    b[n++] = (uint8_t)((((uint32_t)bc.member) >> 16) & 0xFFu);                              \
    b[n++] = (uint8_t)(((uint32_t)bc.member) >> 24);
    QNAV_BOARD_ROBOT_FIELDS(QNAV_CRC_FIELD)
#undef QNAV_CRC_FIELD
    return qnav_link_crc16(qnav_link_crc16(0xFFFFu, b, n), (const uint8_t *)name,
                           (uint16_t)strlen(name));
}

void qnav_bridge_ctrl_init(qnav_bridge_ctrl_t *bc, const qnav_ctrl_config_t *cfg,
                           const char *controller, const qnav_policy_t *policy)
{
    memset(bc, 0, sizeof *bc);
    bc->cfg = *cfg;
    bc->policy = *policy;
    bc->policy_crc = qnav_bridge_policy_crc(policy);
    bc->config_crc = qnav_bridge_config_crc(cfg, controller);
    bc->method = qnav_nav_find(controller != NULL ? controller : QNAV_BRIDGE_DEFAULT_CONTROLLER);
    bc->ready = bridge_ctrl_reinit(bc);
}

/* The scan's sector count, 0 when out of range; the controller re-made when the scan's
 * sectors or range differ from its configuration. */
static int bridge_ctrl_sync(qnav_bridge_ctrl_t *bc, const qnav_scan_t *scan)
{
    int n = scan->n_sectors;
    if (n < 1 || n > QNAV_MAX_SECTORS) {
        n = 0;
    }
    if (n > 0 && scan->max_range_mm > 0 && scan->max_range_mm <= 65535 &&
        (n != bc->cfg.n_sectors || scan->max_range_mm != bc->cfg.max_range_mm || !bc->ready)) {
        bc->cfg.n_sectors = (uint16_t)n;
        bc->cfg.max_range_mm = (qnav_mm_t)scan->max_range_mm;
        bc->ready = bridge_ctrl_reinit(bc);
    }
    return n;
}

void qnav_bridge_ctrl_input(qnav_bridge_ctrl_t *bc, const qnav_scan_t *scan, uint32_t range_mm,
                            qnav_cdeg_t yaw_cdeg, qnav_nav_input_t *rec)
{
    qnav_ctrl_input_t in = {0};
    (void)bridge_ctrl_sync(bc, scan);
    in.goal_bearing_cdeg = scan->goal_bearing_cdeg;
    qnav_ctrl_carry_input(&bc->carry, (uint16_t)scan->goal_id, range_mm, yaw_cdeg, &in);
    memset(rec, 0, sizeof *rec);
    rec->utime = scan->utime;
    rec->scan_seq = scan->seq;
    rec->goal_id = scan->goal_id;
    rec->goal_range_mm = in.goal_range_mm;
    rec->prev_heading_cdeg = in.prev_heading_cdeg;
    rec->config_crc = bc->config_crc;
}

static void fill_command(const qnav_bridge_ctrl_t *bc, const qnav_scan_t *scan,
                         const qnav_ctrl_output_t *out, qnav_command_t *cmd)
{
    memset(cmd, 0, sizeof *cmd);
    cmd->utime = scan->utime;
    cmd->scan_seq = scan->seq;
    cmd->heading_deg = out->heading_deg;
    cmd->speed_q15 = out->speed;
    cmd->quality_q15 = out->quality;
    cmd->speed = QNAV_Q1_15_TO_REAL(out->speed);
    cmd->quality = QNAV_Q1_15_TO_REAL(out->quality);
    cmd->flags = (int8_t)out->flags;
    cmd->stop_reason = QNAV_STOP_NONE;
    cmd->source = QNAV_SOURCE_BRIDGE;
    cmd->policy_crc = bc->policy_crc;
}

void qnav_bridge_ctrl_step(qnav_bridge_ctrl_t *bc, const qnav_scan_t *scan,
                           const qnav_nav_input_t *rec, qnav_command_t *cmd,
                           int16_t *qualities)
{
    qnav_mm_t ranges[QNAV_MAX_SECTORS];
    qnav_ctrl_input_t in = {0};
    qnav_ctrl_output_t out;
    int k;
    int n = bridge_ctrl_sync(bc, scan);

    for (k = 0; k < n; ++k) {
        int32_t r = scan->ranges_mm[k];
        ranges[k] = (qnav_mm_t)(r < 0 ? 0 : (r > 65535 ? 65535 : r));
    }
    in.ranges_mm = ranges;
    in.goal_bearing_cdeg = scan->goal_bearing_cdeg;
    /* the heading qnav_bridge_ctrl_input was given (live), kept for the next tick's previous
     * heading; a logged record brings the previous heading itself */
    qnav_ctrl_carry_input(&bc->carry, (uint16_t)scan->goal_id,
                          rec->goal_range_mm < 0 ? 0u : (uint32_t)rec->goal_range_mm,
                          bc->carry.yaw_cdeg, &in);
    in.prev_heading_cdeg = rec->prev_heading_cdeg; /* as recorded (the same, live) */
    qnav_escape_follow_plan(&in.escape, rec->escape_clear,
                            (uint16_t)(rec->escape_grow_mm < 0        ? 0
                                       : rec->escape_grow_mm > 65535 ? 65535
                                                                     : rec->escape_grow_mm));
    if (qualities != NULL) {
        memset(qualities, 0, sizeof(int16_t) * QNAV_PATHS);
    }
    if (n == 0 || !bc->ready) {
        /* a scan the controller cannot take: the step reports not-ready and stops */
        qnav_nav_t dead;
        memset(&dead, 0, sizeof dead);
        qnav_nav_step(&dead, &in, &out);
    } else if (qualities != NULL && qnav_nav_paths(&bc->nav) != NULL) {
        /* the path-quality controllers also give every path's quality for lcm-spy */
        qnav_ctrl_step(qnav_nav_paths(&bc->nav), &in, &out, qualities);
    } else {
        qnav_nav_step(&bc->nav, &in, &out);
    }
    qnav_ctrl_carry_output(&bc->carry, &out);
    fill_command(bc, scan, &out, cmd);
}

void qnav_bridge_config_default(qnav_bridge_config_t *cfg)
{
    memset(cfg, 0, sizeof *cfg);
    cfg->mode = QNAV_LINK_MODE_OFFBOARD;
    cfg->timeout_ms = 300;
    cfg->heartbeat_ms = 100;
    cfg->status_ms = 500;
    cfg->controller = QNAV_BRIDGE_DEFAULT_CONTROLLER;
    qnav_ctrl_config_default(&cfg->ctrl);
    qnav_policy_prob_default(&cfg->policy);
}

void qnav_bridge_publish(qnav_bridge_t *b, const char *channel, const void *data, int len)
{
    if (b->lcm != NULL) {
        lcm_publish(b->lcm, channel, data, (unsigned int)len);
    }
    if (b->log != NULL) {
        lcm_eventlog_event_t ev;
        memset(&ev, 0, sizeof ev);
        ev.timestamp = qnav_bridge_utime();
        ev.channellen = (int32_t)strlen(channel);
        ev.datalen = len;
        ev.channel = (char *)channel;
        ev.data = (void *)data;
        lcm_eventlog_write_event(b->log, &ev);
        fflush(b->log->f);
    }
}

#define PUBLISH(b, ch, T, msg)                                                              \
    do {                                                                                    \
        uint8_t buf_[PUBLISH_BUF];                                                          \
        int n_ = T##_encode(buf_, 0, (int)sizeof buf_, (msg));                              \
        if (n_ > 0) {                                                                       \
            qnav_bridge_publish((b), (ch), buf_, n_);                                       \
        }                                                                                   \
    } while (0)

static void write_wire(void *user, const uint8_t *bytes, uint16_t n)
{
    qnav_bridge_t *b = (qnav_bridge_t *)user;
    if (b->write != NULL) {
        b->write(b->write_user, bytes, n);
    }
}

static void send_frame(qnav_bridge_t *b, uint8_t id, const uint8_t *payload, int32_t len)
{
    uint8_t wire[QNAV_LINK_MAX_WIRE(QNAV_LINK_MAX_PAYLOAD)];
    qnav_link_send(&b->tx, id, payload, len, wire, (uint16_t)sizeof wire, write_wire, b);
}

static void send_command(qnav_bridge_t *b, const qnav_command_t *c, int stop)
{
    qnav_link_command_t lc;
    uint8_t p[QNAV_LINK_COMMAND_BYTES];
    memset(&lc, 0, sizeof lc);
    lc.scan_seq = (uint16_t)(c->scan_seq < 0 ? 0 : c->scan_seq);
    lc.heading_deg = stop ? 0 : c->heading_deg;
    lc.speed = stop ? 0 : c->speed_q15;
    lc.quality = c->quality_q15;
    lc.flags = (uint8_t)((uint8_t)c->flags | (stop ? QNAV_LINK_CMD_STOP : 0u));
    send_frame(b, QNAV_LINK_MSG_COMMAND, p, qnav_link_command_pack(&lc, p, sizeof p));
}

/* A bare stop on the wire, repeated because a single frame may be lost. */
static void send_stop(qnav_bridge_t *b)
{
    qnav_command_t c;
    memset(&c, 0, sizeof c);
    c.scan_seq = -1;
    send_command(b, &c, 1);
}

static void send_heartbeat(qnav_bridge_t *b)
{
    qnav_link_heartbeat_t hb;
    uint8_t p[QNAV_LINK_HEARTBEAT_BYTES];
    memset(&hb, 0, sizeof hb);
    hb.uptime_ms = (uint32_t)(b->now_ms - b->started_ms);
    hb.mode = b->cfg.mode;
    hb.state = (uint8_t)((b->last_rx_ms >= 0 && b->now_ms - b->last_rx_ms <=
                                                    (int64_t)b->cfg.timeout_ms
                              ? QNAV_LINK_STATE_LINK_OK
                              : 0u) |
                         (b->watchdog_stop || b->shutting_down ? QNAV_LINK_STATE_STOPPED : 0u) |
                         (b->bc.ready ? QNAV_LINK_STATE_POLICY : 0u));
    hb.rx_ok = (uint16_t)b->rx.stats.frames_ok;
    hb.rx_dropped = (uint16_t)qnav_link_rx_dropped_total(&b->rx);
    hb.policy_crc = b->bc.policy_crc;
    send_frame(b, QNAV_LINK_MSG_HEARTBEAT, p, qnav_link_heartbeat_pack(&hb, p, sizeof p));
}

static void send_goal(qnav_bridge_t *b)
{
    uint8_t p[QNAV_LINK_GOAL_BYTES];
    send_frame(b, QNAV_LINK_MSG_GOAL, p, qnav_link_goal_pack(&b->goal, p, sizeof p));
}

/* A stop: sent to the board and published once per event. */
static void command_stop(qnav_bridge_t *b, int8_t reason)
{
    qnav_command_t c;
    memset(&c, 0, sizeof c);
    c.utime = qnav_bridge_utime();
    c.scan_seq = -1;
    c.flags = (int8_t)QNAV_LINK_CMD_STOP;
    c.stop_reason = reason;
    c.source = QNAV_SOURCE_BRIDGE;
    c.policy_crc = b->bc.policy_crc;
    send_command(b, &c, 1);
    PUBLISH(b, QNAV_CH_COMMAND, qnav_command_t, &c);
}

static void publish_status(qnav_bridge_t *b)
{
    qnav_link_status_t s;
    memset(&s, 0, sizeof s);
    s.utime = qnav_bridge_utime();
    s.mode = (int8_t)b->cfg.mode;
    s.rx_frames = (int64_t)b->rx.stats.frames_ok;
    s.tx_frames = (int64_t)b->tx.frames_sent;
    s.rx_bytes = (int64_t)b->rx_bytes;
    s.drop_cobs = b->rx.stats.dropped[QNAV_LINK_DROP_COBS];
    s.drop_short = b->rx.stats.dropped[QNAV_LINK_DROP_SHORT];
    s.drop_overflow = b->rx.stats.dropped[QNAV_LINK_DROP_OVERFLOW];
    s.drop_crc = b->rx.stats.dropped[QNAV_LINK_DROP_CRC];
    s.drop_unknown = b->rx.stats.dropped[QNAV_LINK_DROP_UNKNOWN];
    s.drop_length = b->rx.stats.dropped[QNAV_LINK_DROP_LENGTH];
    s.drop_seq = b->rx.stats.dropped[QNAV_LINK_DROP_SEQ];
    s.seq_gaps = b->rx.stats.seq_gaps;
    s.last_heartbeat_age_ms =
        b->last_heartbeat_ms < 0 ? -1 : (int32_t)(b->now_ms - b->last_heartbeat_ms);
    s.last_scan_age_ms = b->last_scan_ms < 0 ? -1 : (int32_t)(b->now_ms - b->last_scan_ms);
    s.watchdog_stop = (int8_t)(b->watchdog_stop != 0);
    s.board_rx_ok = b->board_hb.rx_ok;
    s.board_rx_dropped = b->board_hb.rx_dropped;
    s.board_state = (int8_t)b->board_hb.state;
    s.board_policy_crc = b->board_hb.policy_crc;
    s.last_upload_status = b->last_upload_status;
    PUBLISH(b, QNAV_CH_LINK_STATUS, qnav_link_status_t, &s);
}

void qnav_bridge_init(qnav_bridge_t *b, const qnav_bridge_config_t *cfg, lcm_t *lcm,
                      lcm_eventlog_t *log, qnav_bridge_write_fn write, void *write_user,
                      int64_t now_ms)
{
    memset(b, 0, sizeof *b);
    b->cfg = *cfg;
    b->lcm = lcm;
    b->log = log;
    b->write = write;
    b->write_user = write_user;
    qnav_link_rx_init(&b->rx);
    qnav_link_tx_init(&b->tx);
    qnav_bridge_ctrl_init(&b->bc, &cfg->ctrl, cfg->controller, &cfg->policy);
    b->now_ms = now_ms;
    b->started_ms = now_ms;
    b->last_scan_ms = -1;
    b->last_heartbeat_ms = -1;
    b->last_rx_ms = -1;
    b->next_heartbeat_ms = now_ms;
    b->next_status_ms = now_ms + cfg->status_ms;
    b->upload_state = cfg->upload ? QNAV_BRIDGE_UPLOAD_WAITING : QNAV_BRIDGE_UPLOAD_IDLE;
    b->last_upload_status = QNAV_BRIDGE_UPLOAD_NONE_YET;
}

/* The distance to the destination for the escape: the board's own, from its pose report
 * (the board sends it just before each scan, so it is this tick's; after a lost report the
 * last one, a tick older, rather than none, which would clear the escape memory) for the
 * goal the scan is driven to. 0 (no escape) before any report for that goal, and for a
 * bearing-only goal (the board reports 0). */
static uint32_t scan_goal_range(const qnav_bridge_t *b, const qnav_link_scan_t *ls)
{
    return b->have_pose && b->pose_goal_id == ls->goal_id ? b->pose_goal_distance_mm : 0u;
}

/* What the board's map did to the escape memory in the scan's tick (its pose report of the
 * same board time and goal), into rec, once: a lost pose report loses it, and it is never
 * applied to another tick's scan. */
static void scan_escape_verdict(qnav_bridge_t *b, const qnav_link_scan_t *ls,
                                qnav_nav_input_t *rec)
{
    if (b->have_pose && b->pose_goal_id == ls->goal_id && b->pose_board_ms == ls->board_ms) {
        rec->escape_clear = (int8_t)b->pose_escape_clear;
        rec->escape_grow_mm = (int32_t)b->pose_escape_grow_mm;
    }
    b->pose_escape_clear = 0u;
    b->pose_escape_grow_mm = 0u;
}

static void on_scan(qnav_bridge_t *b, const qnav_link_frame_t *f)
{
    qnav_link_scan_t ls;
    qnav_scan_t s;
    qnav_command_t c;
    qnav_path_qualities_t q;
    qnav_nav_input_t rec;
    int k;

    if (qnav_link_scan_unpack(f->payload, f->len, &ls) != QNAV_LINK_OK) {
        return;
    }
    b->last_scan_ms = b->now_ms;
    b->scan_seq = f->seq;
    /* the robot's heading in the scan's tick, for the previous heading: the board's, from
     * its pose report (after a lost report the last one, a tick older); 0 before any */
    b->scan_yaw_cdeg = b->have_pose ? b->pose_heading_cdeg : 0;
    memset(&s, 0, sizeof s);
    s.utime = qnav_bridge_utime();
    s.seq = f->seq;
    s.board_ms = ls.board_ms;
    s.n_sectors = (int16_t)ls.n_sectors;
    s.max_range_mm = ls.max_range_mm;
    s.goal_bearing_cdeg = ls.goal_bearing_cdeg;
    s.goal_id = ls.goal_id;
    for (k = 0; k < ls.n_sectors; ++k) {
        s.ranges_mm[k] = ls.ranges_mm[k];
    }
    qnav_bridge_ctrl_input(&b->bc, &s, scan_goal_range(b, &ls), b->scan_yaw_cdeg, &rec);
    scan_escape_verdict(b, &ls, &rec);
    if (b->cfg.mode == QNAV_LINK_MODE_ONBOARD && b->cfg.check_config == NULL) {
        rec.config_crc = -1; /* the board decides with a configuration nobody checked */
    }
    PUBLISH(b, QNAV_CH_NAV_INPUT, qnav_nav_input_t, &rec);
    PUBLISH(b, QNAV_CH_SCAN, qnav_scan_t, &s);

    if ((b->goal.goal_id != 0u || b->goal_cleared) && ls.goal_id != b->goal.goal_id) {
        send_goal(b); /* the board has not got the current goal (or its clearing) yet */
    }
    memset(&q, 0, sizeof q);
    qnav_bridge_ctrl_step(&b->bc, &s, &rec, &c, q.quality_q15);
    if (b->cfg.mode == QNAV_LINK_MODE_OFFBOARD && !b->shutting_down &&
        (b->cfg.check_config == NULL || b->config_ok)) {
        if (b->watchdog_stop && b->diag != NULL) {
            fprintf(b->diag, "navbridge: scans are back: resuming commands\n");
        }
        b->watchdog_stop = 0;
        send_command(b, &c, 0);
        PUBLISH(b, QNAV_CH_COMMAND, qnav_command_t, &c);
    }
    q.utime = s.utime;
    q.scan_seq = s.seq;
    q.best_deg = c.heading_deg;
    for (k = 0; k < QNAV_PATHS; ++k) {
        q.quality[k] = (float)QNAV_Q1_15_TO_REAL(q.quality_q15[k]);
    }
    PUBLISH(b, QNAV_CH_QUALITIES, qnav_path_qualities_t, &q);
}

static void on_board_command(qnav_bridge_t *b, const qnav_link_frame_t *f)
{
    qnav_link_command_t lc;
    qnav_command_t c;
    if (b->cfg.mode != QNAV_LINK_MODE_ONBOARD) {
        return; /* offboard: commands only flow to the board */
    }
    if (qnav_link_command_unpack(f->payload, f->len, &lc) != QNAV_LINK_OK) {
        return;
    }
    memset(&c, 0, sizeof c);
    c.utime = qnav_bridge_utime();
    c.scan_seq = lc.scan_seq;
    c.heading_deg = lc.heading_deg;
    c.speed_q15 = lc.speed;
    c.quality_q15 = lc.quality;
    c.speed = QNAV_Q1_15_TO_REAL(lc.speed);
    c.quality = QNAV_Q1_15_TO_REAL(lc.quality);
    c.flags = (int8_t)(lc.flags & 0x7Fu);
    c.stop_reason = (lc.flags & QNAV_LINK_CMD_STOP) ? QNAV_STOP_BOARD : QNAV_STOP_NONE;
    c.source = QNAV_SOURCE_BOARD;
    c.policy_crc = b->board_hb.policy_crc;
    PUBLISH(b, QNAV_CH_COMMAND, qnav_command_t, &c);
    if (lc.scan_seq == b->scan_seq && !(lc.flags & QNAV_FLAG_NOT_READY)) {
        /* the board decided: its decision, not the bridge's own (shown only), is the
         * previous heading the next QNAV_NAV_INPUT records, as the board reads it */
        b->bc.carry.last_heading_deg = lc.heading_deg;
        b->bc.carry.last_yaw_cdeg = b->scan_yaw_cdeg;
        b->bc.carry.have_last = 1u;
    }
}

/* A board heartbeat: 1 when it is of our protocol version and taken. A board of another
 * version is remembered in refused_protocol and not acted on. */
static int on_board_heartbeat(qnav_bridge_t *b, const qnav_link_frame_t *f)
{
    qnav_link_heartbeat_t hb;
    uint8_t stored;
    uint8_t table;
    if (qnav_link_heartbeat_unpack(f->payload, f->len, &hb) != QNAV_LINK_OK) {
        return 0;
    }
    if (hb.protocol != QNAV_LINK_PROTOCOL_VERSION) {
        b->refused_protocol = hb.protocol == 0u ? 0xFFu : hb.protocol;
        return 0;
    }
    b->board_hb = hb;
    stored = (uint8_t)((hb.state & QNAV_LINK_STATE_STORED) != 0u);
    table = (uint8_t)((hb.state & QNAV_LINK_STATE_TABLE) != 0u);
    if (b->diag != NULL && (!b->heard_board || stored != b->board_stored ||
                            hb.policy_crc != b->board_crc_reported || table != b->board_table)) {
        fprintf(b->diag, "navbridge: board speaks link protocol %u and runs its %s policy "
                         "(crc 0x%04x)%s\n", (unsigned)hb.protocol,
                stored ? "uploaded" : "built-in", hb.policy_crc,
                table ? " from its compiled table (table mode)" : "");
    }
    b->heard_board = 1;
    b->board_stored = stored;
    b->board_table = table;
    b->board_crc_reported = hb.policy_crc;
    return 1;
}

/* The board's robot configuration, checked against the operator's robot (--robot). */
static void on_config(qnav_bridge_t *b, const qnav_link_frame_t *f)
{
    qnav_link_config_t m;
    if (b->cfg.check_config == NULL ||
        qnav_link_config_unpack(f->payload, f->len, &m) != QNAV_LINK_OK) {
        return;
    }
    if (b->cfg.check_config(b->cfg.check_user, &m, b->config_diff, sizeof b->config_diff) == 0) {
        b->config_ok = 1;
    } else {
        b->config_ok = 0;
        b->config_refused = 1;
    }
}

static void send_route_goal(qnav_bridge_t *b)
{
    memset(&b->goal, 0, sizeof b->goal);
    b->goal_cleared = 0;
    if (b->route_k < b->route_n) {
        b->last_goal_id = (uint16_t)(b->last_goal_id == 65535u ? 1u : b->last_goal_id + 1u);
        b->goal.goal_id = b->last_goal_id;
        b->goal.kind = QNAV_LINK_GOAL_POSITION;
        b->goal.x_mm = b->route_x_mm[b->route_k];
        b->goal.y_mm = b->route_y_mm[b->route_k];
    } else {
        b->goal_cleared = 1; /* route done: no goal, the robot stops */
    }
    send_goal(b);
}

/* The board's pose: published, and the route advanced when the current waypoint is
 * within the radius. */
static void on_pose(qnav_bridge_t *b, const qnav_link_frame_t *f)
{
    qnav_link_pose_t lp;
    qnav_odometry_t o;
    if (qnav_link_pose_unpack(f->payload, f->len, &lp) != QNAV_LINK_OK) {
        return;
    }
    b->have_pose = 1;
    b->pose_goal_id = lp.goal_id;
    b->pose_goal_distance_mm = lp.goal_distance_mm;
    b->pose_heading_cdeg = lp.heading_cdeg;
    b->pose_board_ms = lp.board_ms;
    b->pose_escape_clear = lp.escape_clear;
    b->pose_escape_grow_mm = lp.escape_grow_mm;
    if (b->route_n > 0 && b->route_k < b->route_n && lp.goal_id == b->goal.goal_id &&
        b->goal.kind == QNAV_LINK_GOAL_POSITION) {
        double dx = (double)b->route_x_mm[b->route_k] - (double)lp.x_mm;
        double dy = (double)b->route_y_mm[b->route_k] - (double)lp.y_mm;
        if (sqrt(dx * dx + dy * dy) <= (double)b->route_radius_mm) {
            b->route_k++;
            if (b->diag != NULL) {
                fprintf(b->diag, "navbridge: waypoint %d/%d reached at %.3f:%.3f m%s\n",
                        b->route_k, b->route_n, lp.x_mm / 1000.0, lp.y_mm / 1000.0,
                        b->route_k == b->route_n ? ": route done, robot stopped" : "");
            }
            send_route_goal(b);
        }
    }
    memset(&o, 0, sizeof o);
    o.utime = qnav_bridge_utime();
    o.board_ms = lp.board_ms;
    o.x_mm = lp.x_mm;
    o.y_mm = lp.y_mm;
    o.heading_cdeg = lp.heading_cdeg;
    o.goal_id = lp.goal_id;
    o.goal_distance_mm = lp.goal_distance_mm > 0x7FFFFFFFu ? 0x7FFFFFFF
                                                           : (int32_t)lp.goal_distance_mm;
    o.route_id = b->route_id;
    o.waypoint = (int16_t)b->route_k;
    o.waypoints = (int16_t)b->route_n;
    PUBLISH(b, QNAV_CH_ODOMETRY, qnav_odometry_t, &o);
}

static void send_upload(qnav_bridge_t *b);

static const char *ack_str(int8_t status)
{
    switch (status) {
    case QNAV_LINK_ACK_BAD_LENGTH:
        return "chunks missing";
    case QNAV_LINK_ACK_BAD_CRC:
        return "CRC differs";
    case QNAV_LINK_ACK_BAD_POLICY:
        return "not a policy this board reads";
    case QNAV_LINK_ACK_REJECTED:
        return "the controller refused it";
    default:
        return "unknown status";
    }
}

static void on_ack(qnav_bridge_t *b, const qnav_link_frame_t *f)
{
    qnav_link_policy_ack_t a;
    if (qnav_link_policy_ack_unpack(f->payload, f->len, &a) != QNAV_LINK_OK ||
        b->upload_state != QNAV_BRIDGE_UPLOAD_SENT) {
        return;
    }
    b->last_upload_status = a.status;
    b->upload_state = QNAV_BRIDGE_UPLOAD_DONE;
    if ((a.status == QNAV_LINK_ACK_BAD_LENGTH || a.status == QNAV_LINK_ACK_BAD_CRC) &&
        b->upload_tries < QNAV_BRIDGE_UPLOAD_TRIES) {
        /* damaged on the way (a frame lost or corrupted on the line, or dropped while the
         * board was busy): the policy itself was fine, so it is sent again */
        if (b->diag != NULL) {
            fprintf(b->diag, "navbridge: policy upload: the board got it damaged (%s); "
                             "sending it again (try %d of %d)\n",
                    ack_str(a.status),
                    b->upload_tries + 1, QNAV_BRIDGE_UPLOAD_TRIES);
        }
        send_upload(b);
        return;
    }
    if (b->diag != NULL) {
        if (a.status == QNAV_LINK_ACK_OK) {
            fprintf(b->diag, "navbridge: policy upload: ok (crc 0x%04x)\n", a.crc);
        } else {
            fprintf(b->diag, "navbridge: policy upload: refused by the board (status %d: %s)\n",
                    a.status, ack_str(a.status));
        }
    }
}

int32_t qnav_bridge_upload_blob(const qnav_ctrl_config_t *cfg, const char *controller,
                                const qnav_policy_t *policy, uint8_t *out, uint16_t cap)
{
    qnav_ctrl_config_t own;
    qnav_ctrl_t ctrl;
    uint8_t shapes[QNAV_SHAPES_BYTES];
    const uint8_t *carried = NULL;
    const qnav_nav_method_t *m =
        qnav_nav_find(controller != NULL ? controller : QNAV_BRIDGE_DEFAULT_CONTROLLER);
    if (m != NULL) {
        qnav_nav_config(m, cfg, &own);
        if (qnav_ctrl_init(&ctrl, &own, policy) == QNAV_OK &&
            qnav_ctrl_shapes_save(&ctrl, policy, shapes) == QNAV_OK) {
            carried = shapes;
        }
    }
    return qnav_link_policy_to_blob_carried(policy, carried, out, cap);
}

static void send_upload(qnav_bridge_t *b)
{
    uint8_t blob[QNAV_LINK_POLICY_MAX_BYTES];
    uint8_t p[QNAV_LINK_CHUNK_MAX_BYTES];
    qnav_link_policy_chunk_t c;
    qnav_link_policy_commit_t cm;
    int32_t n = qnav_bridge_upload_blob(&b->cfg.ctrl, b->cfg.controller, &b->cfg.policy, blob,
                                        (uint16_t)sizeof blob);
    uint16_t off = 0;
    if (n <= 0) {
        b->upload_state = QNAV_BRIDGE_UPLOAD_DONE;
        b->last_upload_status = QNAV_LINK_ACK_BAD_POLICY;
        return;
    }
    while (off < (uint16_t)n) {
        uint16_t len = (uint16_t)((uint16_t)n - off);
        if (len > QNAV_LINK_CHUNK_BYTES) {
            len = QNAV_LINK_CHUNK_BYTES;
        }
        c.offset = off;
        c.total = (uint16_t)n;
        c.len = (uint8_t)len;
        memcpy(c.data, &blob[off], len);
        send_frame(b, QNAV_LINK_MSG_POLICY_CHUNK, p,
                   qnav_link_policy_chunk_pack(&c, p, sizeof p));
        off = (uint16_t)(off + len);
    }
    cm.total = (uint16_t)n;
    cm.crc = qnav_link_crc16(QNAV_LINK_CRC16_INIT, blob, (uint16_t)n);
    send_frame(b, QNAV_LINK_MSG_POLICY_COMMIT, p,
               qnav_link_policy_commit_pack(&cm, p, sizeof p));
    b->upload_state = QNAV_BRIDGE_UPLOAD_SENT;
    b->upload_tries++;
    b->upload_sent_ms = b->now_ms;
}

void qnav_bridge_on_bytes(qnav_bridge_t *b, const uint8_t *bytes, size_t n, int64_t now_ms)
{
    size_t i;
    qnav_link_frame_t f;
    b->now_ms = now_ms;
    b->rx_bytes += n;
    for (i = 0; i < n; ++i) {
        if (!qnav_link_rx_feed(&b->rx, bytes[i], &f)) {
            continue;
        }
        b->last_rx_ms = now_ms;
        switch (f.msg_id) {
        case QNAV_LINK_MSG_SCAN:
            on_scan(b, &f);
            break;
        case QNAV_LINK_MSG_COMMAND:
            on_board_command(b, &f);
            break;
        case QNAV_LINK_MSG_POSE:
            on_pose(b, &f);
            break;
        case QNAV_LINK_MSG_HEARTBEAT:
            if (on_board_heartbeat(b, &f)) {
                b->last_heartbeat_ms = now_ms;
                if (b->cfg.mode == QNAV_LINK_MODE_ONBOARD && b->watchdog_stop) {
                    b->watchdog_stop = 0;
                    if (b->diag != NULL) {
                        fprintf(b->diag, "navbridge: heartbeats are back\n");
                    }
                }
            }
            break;
        case QNAV_LINK_MSG_POLICY_ACK:
            on_ack(b, &f);
            break;
        case QNAV_LINK_MSG_CONFIG:
            on_config(b, &f);
            break;
        default:
            break; /* goals and uploads only flow to the board */
        }
    }
}

void qnav_bridge_on_goal(qnav_bridge_t *b, const qnav_goal_t *goal, int64_t now_ms)
{
    b->now_ms = now_ms;
    b->route_n = b->route_k = 0; /* a bearing goal replaces any route */
    b->route_id = 0;
    memset(&b->goal, 0, sizeof b->goal);
    b->goal_cleared = goal->goal_id == 0;
    b->goal.kind = QNAV_LINK_GOAL_BEARING;
    b->goal.goal_id = (uint16_t)goal->goal_id;
    if (goal->goal_id > 0) {
        b->last_goal_id = (uint16_t)goal->goal_id;
    }
    b->goal.bearing_cdeg = goal->bearing_cdeg;
    b->goal.distance_mm = goal->distance_mm < 0 ? 0u : (uint32_t)goal->distance_mm;
    send_goal(b);
}

int qnav_bridge_on_waypoints(qnav_bridge_t *b, const qnav_waypoints_t *w, int64_t now_ms,
                             char *err, size_t errlen)
{
    int k;
    if (w->n < 0 || w->n > QNAV_BRIDGE_MAX_WAYPOINTS) {
        snprintf(err, errlen, "waypoints_t.n: %d: expected 0..%d", w->n,
                 QNAV_BRIDGE_MAX_WAYPOINTS);
        return -1;
    }
    if (w->n > 0 && !(w->radius_m > 0.0 && w->radius_m <= 1000.0)) {
        snprintf(err, errlen, "waypoints_t.radius_m: %g: expected more than 0 and at most "
                              "1000 m", w->radius_m);
        return -1;
    }
    for (k = 0; k < w->n; ++k) {
        if (!(fabs(w->x_m[k]) <= 2e6) || !(fabs(w->y_m[k]) <= 2e6)) {
            snprintf(err, errlen, "waypoints_t.x_m/y_m[%d]: expected finite metres within "
                                  "+-2000 km", k);
            return -1;
        }
    }
    b->now_ms = now_ms;
    b->route_id = w->route_id;
    b->route_n = w->n;
    b->route_k = 0;
    b->route_radius_mm = (int32_t)lround(w->radius_m * 1000.0);
    for (k = 0; k < w->n; ++k) {
        b->route_x_mm[k] = (int32_t)lround(w->x_m[k] * 1000.0);
        b->route_y_mm[k] = (int32_t)lround(w->y_m[k] * 1000.0);
    }
    send_route_goal(b);
    return 0;
}

static void on_lcm_goal(const lcm_recv_buf_t *rbuf, const char *channel,
                        const qnav_goal_t *msg, void *user)
{
    (void)rbuf;
    (void)channel;
    qnav_bridge_on_goal((qnav_bridge_t *)user, msg, ((qnav_bridge_t *)user)->now_ms);
}

static void on_lcm_waypoints(const lcm_recv_buf_t *rbuf, const char *channel,
                             const qnav_waypoints_t *msg, void *user)
{
    qnav_bridge_t *b = (qnav_bridge_t *)user;
    char err[160];
    (void)rbuf;
    if (qnav_bridge_on_waypoints(b, msg, b->now_ms, err, sizeof err) != 0 && b->diag != NULL) {
        fprintf(b->diag, "navbridge: %s: route refused: %s\n", channel, err);
    } else if (b->diag != NULL) {
        fprintf(b->diag, "navbridge: %s: route %d of %d waypoints\n", channel,
                (int)msg->route_id, (int)msg->n);
    }
}

int qnav_bridge_token_make(char *hex, size_t len)
{
    static const char digits[] = "0123456789abcdef";
    uint8_t raw[QNAV_BRIDGE_TOKEN_HEX / 2];
    size_t got = 0, k;
    if (len < QNAV_BRIDGE_TOKEN_HEX + 1) {
        return -1;
    }
    while (got < sizeof raw) {
        ssize_t n = getrandom(raw + got, sizeof raw - got, 0);
        if (n < 0 && errno == EINTR) {
            continue;
        }
        if (n <= 0) {
            return -1;
        }
        got += (size_t)n;
    }
    for (k = 0; k < sizeof raw; ++k) {
        hex[2 * k] = digits[raw[k] >> 4];
        hex[2 * k + 1] = digits[raw[k] & 15u];
    }
    hex[QNAV_BRIDGE_TOKEN_HEX] = '\0';
    return 0;
}

int qnav_bridge_subscribe(qnav_bridge_t *b, const char *token)
{
    size_t k, n = token != NULL ? strlen(token) : 0;
    if (b->lcm == NULL || n == 0 || n > QNAV_BRIDGE_TOKEN_MAX) {
        return -1;
    }
    /* only letters and digits: the channel is also an LCM subscription regex */
    for (k = 0; k < n; ++k) {
        char c = token[k];
        if (!((c >= '0' && c <= '9') || (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z'))) {
            return -1;
        }
    }
    snprintf(b->goal_channel, sizeof b->goal_channel, "%s_%s", QNAV_CH_GOAL, token);
    snprintf(b->route_channel, sizeof b->route_channel, "%s_%s", QNAV_CH_WAYPOINTS, token);
    b->goal_sub = qnav_goal_t_subscribe(b->lcm, b->goal_channel, on_lcm_goal, b);
    b->route_sub = qnav_waypoints_t_subscribe(b->lcm, b->route_channel, on_lcm_waypoints, b);
    return b->goal_sub != NULL && b->route_sub != NULL ? 0 : -1;
}

void qnav_bridge_unsubscribe(qnav_bridge_t *b)
{
    if (b->lcm != NULL && b->goal_sub != NULL) {
        qnav_goal_t_unsubscribe(b->lcm, b->goal_sub);
    }
    if (b->lcm != NULL && b->route_sub != NULL) {
        qnav_waypoints_t_unsubscribe(b->lcm, b->route_sub);
    }
    b->goal_sub = NULL;
    b->route_sub = NULL;
    b->goal_channel[0] = '\0';
    b->route_channel[0] = '\0';
}

void qnav_bridge_poll(qnav_bridge_t *b, int64_t now_ms)
{
    int64_t last;
    b->now_ms = now_ms;
    if (now_ms >= b->next_heartbeat_ms) {
        send_heartbeat(b);
        b->next_heartbeat_ms = now_ms + b->cfg.heartbeat_ms;
    }
    /* watchdog: the mode's lifeline is scans (offboard) or heartbeats (onboard); before
     * the first one arrives the clock runs from start-up */
    last = b->cfg.mode == QNAV_LINK_MODE_OFFBOARD ? b->last_scan_ms : b->last_heartbeat_ms;
    if (last < 0) {
        last = b->started_ms;
    }
    if (!b->shutting_down && now_ms - last > (int64_t)b->cfg.timeout_ms) {
        if (!b->watchdog_stop) {
            b->watchdog_stop = 1;
            command_stop(b, QNAV_STOP_WATCHDOG);
            b->next_stop_repeat_ms = now_ms + b->cfg.heartbeat_ms;
            /* the board may have restarted: take its next frame whatever its number */
            qnav_link_rx_reset_seq(&b->rx);
            if (b->diag != NULL) {
                fprintf(b->diag, "navbridge: no %s for %lld ms: robot stopped\n",
                        b->cfg.mode == QNAV_LINK_MODE_OFFBOARD ? "scans" : "heartbeats",
                        (long long)(now_ms - last));
            }
        } else if (now_ms >= b->next_stop_repeat_ms) {
            /* repeat on the wire (a stop may be lost) without flooding LCM */
            send_stop(b);
            b->next_stop_repeat_ms = now_ms + b->cfg.heartbeat_ms;
        }
    }
    if (b->upload_state == QNAV_BRIDGE_UPLOAD_WAITING && b->last_heartbeat_ms >= 0) {
        send_upload(b);
    } else if (b->upload_state == QNAV_BRIDGE_UPLOAD_SENT &&
               now_ms - b->upload_sent_ms >
                   (b->cfg.timeout_ms > QNAV_BRIDGE_UPLOAD_WAIT_MS ? (int64_t)b->cfg.timeout_ms
                                                                   : QNAV_BRIDGE_UPLOAD_WAIT_MS)) {
        /* the board's answer is awaited QNAV_BRIDGE_UPLOAD_WAIT_MS, or the watchdog's time
         * when that is longer (a slow link, or simavr slower than real time on a loaded
         * machine) */
        if (b->upload_tries < QNAV_BRIDGE_UPLOAD_TRIES) {
            send_upload(b);
        } else {
            b->upload_state = QNAV_BRIDGE_UPLOAD_DONE;
            b->last_upload_status = QNAV_BRIDGE_UPLOAD_NO_ANSWER;
            if (b->diag != NULL) {
                fprintf(b->diag, "navbridge: policy upload: no answer from the board\n");
            }
        }
    }
    if (now_ms >= b->next_status_ms) {
        publish_status(b);
        b->next_status_ms = now_ms + b->cfg.status_ms;
    }
}

void qnav_bridge_shutdown(qnav_bridge_t *b, int64_t now_ms)
{
    int i;
    b->now_ms = now_ms;
    b->shutting_down = 1;
    command_stop(b, QNAV_STOP_SHUTDOWN);
    for (i = 0; i < 2; ++i) {
        send_stop(b);
    }
    send_heartbeat(b);
    publish_status(b);
}
