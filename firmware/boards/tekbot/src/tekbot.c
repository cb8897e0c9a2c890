/*
 * The TekBot board application (qnav/tekbot.h): link frames in, a 10 Hz control tick,
 * scans, telemetry and heartbeats out, motors through the HAL. No heap, integers only,
 * no file-scope state: everything lives in the caller's qnav_tekbot_t.
 */
#include "qnav/tekbot.h"

#include <stddef.h>
#include <string.h>

/* Most UART bytes handled per poll, so one poll never starves the tick. */
#define UART_BURST 128u

/* Turn part at |heading| >= 90 deg: half of full wheel speed, Q1.15. */
#define TURN_MAX ((int32_t)16384)

void qnav_tekbot_config_default(qnav_tekbot_config_t *cfg)
{
    if (cfg == NULL) {
        return;
    }
    cfg->n_sectors = 8;
    cfg->max_range_mm = 5000;
    cfg->tick_ms = 100;
    cfg->link_timeout_ms = 300;
    cfg->spin_deg = 60;
    cfg->body_radius_mm = 120;
    cfg->safety_mm = 50;
    cfg->sonar_offset_mm = 120;
    cfg->v_max_mm_s = 500;
    cfg->decel_mm_s2 = 2000;
    cfg->controller = "body";
}

/* The controller configuration this board's sonar and body give. */
static void ctrl_config(const qnav_tekbot_config_t *cfg, qnav_ctrl_config_t *cc)
{
    qnav_ctrl_config_default(cc);
    cc->n_sectors = cfg->n_sectors;
    cc->max_range_mm = cfg->max_range_mm;
    cc->body_radius_mm = cfg->body_radius_mm;
    cc->safety_mm = cfg->safety_mm;
    cc->sensor_offset_mm = cfg->sonar_offset_mm;
    cc->v_max_mm_s = cfg->v_max_mm_s;
    cc->decel_mm_s2 = cfg->decel_mm_s2;
}

static qnav_q1_15_t sat_q15(int32_t v)
{
    if (v > 32767L) {
        return 32767;
    }
    if (v < -32767L) {
        return -32767;
    }
    return (qnav_q1_15_t)v;
}

void qnav_tekbot_mix(qnav_deg_t heading_deg, qnav_q1_15_t speed, qnav_deg_t spin_deg,
                     qnav_q1_15_t *left, qnav_q1_15_t *right)
{
    int32_t h = heading_deg;
    int32_t mag = h < 0 ? -h : h;
    int32_t fwd;
    int32_t turn;
    if (left == NULL || right == NULL) {
        return;
    }
    if (speed <= 0) {
        *left = 0;
        *right = 0;
        return;
    }
    if (spin_deg < 1) {
        spin_deg = 1;
    }
    fwd = mag >= spin_deg ? 0 : ((int32_t)speed * (spin_deg - mag)) / spin_deg;
    turn = (mag >= 90 ? TURN_MAX : (TURN_MAX * mag) / 90) * (h < 0 ? -1 : 1);
    /* counter-clockwise (positive) heading: the right wheel runs faster */
    *left = sat_q15(fwd - turn);
    *right = sat_q15(fwd + turn);
}

qnav_tekbot_status_t qnav_tekbot_init(qnav_tekbot_t *bot, const qnav_tekbot_config_t *cfg,
                                      const qnav_board_hal_t *hal)
{
    qnav_ctrl_config_t cc;
    uint8_t blob[QNAV_LINK_POLICY_MAX_BYTES];
    int32_t n;

    if (bot == NULL || cfg == NULL || hal == NULL || hal->millis == NULL ||
        hal->sonar_read == NULL || hal->heading_cdeg == NULL || hal->motors_set == NULL ||
        hal->uart_read == NULL || hal->uart_write == NULL) {
        return QNAV_TEKBOT_E_NULL;
    }
    if (cfg->n_sectors < 1u || cfg->n_sectors > QNAV_LINK_MAX_SECTORS ||
        cfg->max_range_mm == 0u || cfg->tick_ms == 0u || cfg->link_timeout_ms == 0u ||
        cfg->spin_deg < 1 || cfg->spin_deg > 180) {
        return QNAV_TEKBOT_E_CONFIG;
    }
    /* everything starts at zero (no mode, no goal, link not heard, counters 0) */
    memset(bot, 0, sizeof *bot);
    bot->cfg = *cfg;
    bot->hal = *hal;
    qnav_link_rx_init(&bot->rx);
    qnav_link_tx_init(&bot->tx);
    qnav_link_upload_init(&bot->upload);
    bot->cmd.flags = QNAV_LINK_CMD_STOP;

    qnav_policy_prob_default(&bot->policy);
    ctrl_config(cfg, &cc);
    bot->ctrl_ready =
        (uint8_t)(qnav_nav_init_named(&bot->nav, cfg->controller, &cc, &bot->policy) == QNAV_OK);
    n = qnav_link_policy_to_blob(&bot->policy, blob, sizeof blob);
    bot->policy_crc = n > 0 ? qnav_link_crc16(QNAV_LINK_CRC16_INIT, blob, (uint16_t)n) : 0u;
    bot->hal.motors_set(bot->hal.ctx, 0, 0);
    bot->next_tick_ms = bot->hal.millis(bot->hal.ctx);
    return bot->ctrl_ready ? QNAV_TEKBOT_OK : QNAV_TEKBOT_E_CTRL;
}

static void send(qnav_tekbot_t *bot, uint8_t id, const uint8_t *payload, int32_t len)
{
    int32_t n;
    if (len < 0) {
        return;
    }
    n = qnav_link_encode(&bot->tx, id, payload, (uint16_t)len, bot->wire,
                         (uint16_t)sizeof bot->wire);
    if (n > 0) {
        bot->hal.uart_write(bot->hal.ctx, bot->wire, (uint16_t)n);
    }
}

/* A committed upload: switch controllers only when the new one initialises. */
static void commit_upload(qnav_tekbot_t *bot, const qnav_link_policy_commit_t *cm)
{
    qnav_policy_t fresh;
    qnav_ctrl_config_t cc;
    qnav_link_policy_ack_t ack;
    uint8_t p[QNAV_LINK_POLICY_ACK_BYTES];
    int8_t status = qnav_link_upload_commit(&bot->upload, cm, &fresh);

    if (status == QNAV_LINK_ACK_OK) {
        ctrl_config(&bot->cfg, &cc);
        if (qnav_nav_init(&bot->nav, qnav_nav_find(bot->cfg.controller), &cc, &fresh) ==
            QNAV_OK) {
            bot->policy = fresh;
            bot->policy_crc = cm->crc;
            bot->ctrl_ready = 1;
            bot->stats.uploads_ok++;
        } else {
            /* keep driving with the policy we had */
            bot->ctrl_ready = (uint8_t)(qnav_nav_init(&bot->nav, qnav_nav_find(bot->cfg.controller),
                                                      &cc, &bot->policy) == QNAV_OK);
            status = QNAV_LINK_ACK_REJECTED;
        }
    }
    if (status != QNAV_LINK_ACK_OK) {
        bot->stats.uploads_refused++;
    }
    ack.status = status;
    ack.reserved = 0;
    ack.crc = bot->policy_crc;
    send(bot, QNAV_LINK_MSG_POLICY_ACK, p, qnav_link_policy_ack_pack(&ack, p, sizeof p));
}

static void on_frame(qnav_tekbot_t *bot, const qnav_link_frame_t *f, uint32_t now)
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
        }
        break;
    }
    case QNAV_LINK_MSG_HEARTBEAT: {
        qnav_link_heartbeat_t hb;
        if (qnav_link_heartbeat_unpack(f->payload, f->len, &hb) == QNAV_LINK_OK) {
            if (hb.mode == QNAV_LINK_MODE_OFFBOARD || hb.mode == QNAV_LINK_MODE_ONBOARD) {
                bot->mode = hb.mode;
            }
            bot->hold_stop = (uint8_t)((hb.state & QNAV_LINK_STATE_STOPPED) != 0u);
        }
        break;
    }
    case QNAV_LINK_MSG_POLICY_CHUNK: {
        qnav_link_policy_chunk_t c;
        if (qnav_link_policy_chunk_unpack(f->payload, f->len, &c) == QNAV_LINK_OK) {
            (void)qnav_link_upload_chunk(&bot->upload, &c);
        }
        break;
    }
    case QNAV_LINK_MSG_POLICY_COMMIT: {
        qnav_link_policy_commit_t cm;
        if (qnav_link_policy_commit_unpack(f->payload, f->len, &cm) == QNAV_LINK_OK) {
            commit_upload(bot, &cm);
        }
        break;
    }
    default:
        break; /* scans and acks only flow to the bridge */
    }
}

void qnav_tekbot_poll(qnav_tekbot_t *bot)
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
    if ((int32_t)(now - bot->next_tick_ms) >= 0) {
        bot->next_tick_ms += bot->cfg.tick_ms;
        if ((int32_t)(now - bot->next_tick_ms) > (int32_t)bot->cfg.tick_ms) {
            bot->next_tick_ms = now + bot->cfg.tick_ms; /* fell behind: do not burst */
        }
        qnav_tekbot_tick(bot);
    }
}

/* Wrap an angle in 0.01 deg into -18000..17999. */
static qnav_cdeg_t wrap_cdeg(int32_t a)
{
    a %= 36000L;
    if (a < -18000L) {
        a += 36000L;
    } else if (a >= 18000L) {
        a -= 36000L;
    }
    return (qnav_cdeg_t)a;
}

void qnav_tekbot_tick(qnav_tekbot_t *bot)
{
    qnav_link_heartbeat_t hb;
    qnav_link_command_t tel;
    qnav_ctrl_input_t in;
    qnav_ctrl_output_t out;
    uint8_t p[QNAV_LINK_MAX_PAYLOAD];
    uint32_t now;
    uint16_t n;
    uint16_t k;
    uint16_t scan_seq;
    uint8_t was_ok;
    uint8_t moving;
    qnav_q1_15_t left;
    qnav_q1_15_t right;
    qnav_cdeg_t heading;

    if (bot == NULL) {
        return;
    }
    now = bot->hal.millis(bot->hal.ctx);
    bot->stats.ticks++;
    was_ok = bot->link_ok;
    bot->link_ok = (uint8_t)(bot->heard && (now - bot->last_rx_ms) <= bot->cfg.link_timeout_ms);
    if (was_ok && !bot->link_ok) {
        bot->stats.link_lost++;
        qnav_link_rx_reset_seq(&bot->rx); /* the bridge may come back restarted */
        qnav_link_upload_init(&bot->upload);
    }

    /* sense */
    n = bot->hal.sonar_read(bot->hal.ctx, bot->ranges, bot->cfg.n_sectors);
    for (k = n; k < bot->cfg.n_sectors; ++k) {
        bot->ranges[k] = bot->cfg.max_range_mm; /* a missing sonar reads as clear */
    }
    heading = bot->hal.heading_cdeg(bot->hal.ctx);
    in.ranges_mm = bot->ranges;
    in.goal_bearing_cdeg = 0;
    if (bot->have_goal) {
        in.goal_bearing_cdeg = wrap_cdeg((int32_t)bot->goal.bearing_cdeg - (int32_t)heading);
    }
    /* the previous decision, seen from where the robot points now */
    in.prev_heading_cdeg =
        bot->have_decision ? wrap_cdeg((int32_t)bot->decided_cdeg - (int32_t)heading) : 0;

    /* decide */
    out.heading_deg = 0;
    out.speed = 0;
    out.quality = 0;
    out.flags = 0;
    if (bot->mode == QNAV_LINK_MODE_ONBOARD) {
        qnav_nav_step(&bot->nav, &in, &out);
        bot->decided_cdeg = wrap_cdeg((int32_t)heading + 100 * (int32_t)out.heading_deg);
        bot->have_decision = 1;
    } else if (bot->mode == QNAV_LINK_MODE_OFFBOARD &&
               (now - bot->cmd_ms) <= bot->cfg.link_timeout_ms) {
        out.heading_deg = bot->cmd.heading_deg;
        out.speed = bot->cmd.speed;
        out.quality = bot->cmd.quality;
        out.flags = (uint8_t)(bot->cmd.flags & 0x7Fu);
    }
    moving = (uint8_t)(bot->link_ok && !bot->hold_stop && bot->have_goal && bot->mode != 0u &&
                       out.speed > 0);
    if (!moving) {
        out.speed = 0;
    }

    /* act: the motors are set every tick, to 0 whenever anything is wrong */
    qnav_tekbot_mix(out.heading_deg, out.speed, bot->cfg.spin_deg, &left, &right);
    bot->hal.motors_set(bot->hal.ctx, left, right);
    if (!moving) {
        bot->stats.stopped_ticks++;
    }

    /* report: scan, heartbeat, onboard decision */
    {
        /* pack the scan straight from the ranges buffer (no second copy on the MCU) */
        uint16_t len = (uint16_t)(QNAV_LINK_SCAN_HEADER_BYTES + 2u * bot->cfg.n_sectors);
        uint32_t t = now;
        p[0] = (uint8_t)(t & 0xFFu);
        p[1] = (uint8_t)((t >> 8) & 0xFFu);
        p[2] = (uint8_t)((t >> 16) & 0xFFu);
        p[3] = (uint8_t)(t >> 24);
        p[4] = (uint8_t)((uint16_t)in.goal_bearing_cdeg & 0xFFu);
        p[5] = (uint8_t)((uint16_t)in.goal_bearing_cdeg >> 8);
        p[6] = (uint8_t)(bot->cfg.max_range_mm & 0xFFu);
        p[7] = (uint8_t)(bot->cfg.max_range_mm >> 8);
        p[8] = (uint8_t)(bot->cfg.n_sectors & 0xFFu);
        p[9] = (uint8_t)(bot->cfg.n_sectors >> 8);
        p[10] = (uint8_t)((bot->have_goal ? bot->goal.goal_id : 0u) & 0xFFu);
        p[11] = (uint8_t)((bot->have_goal ? bot->goal.goal_id : 0u) >> 8);
        for (k = 0; k < bot->cfg.n_sectors; ++k) {
            p[QNAV_LINK_SCAN_HEADER_BYTES + 2u * k] = (uint8_t)(bot->ranges[k] & 0xFFu);
            p[QNAV_LINK_SCAN_HEADER_BYTES + 2u * k + 1u] = (uint8_t)(bot->ranges[k] >> 8);
        }
        scan_seq = bot->tx.next_seq;
        send(bot, QNAV_LINK_MSG_SCAN, p, (int32_t)len);
    }
    /* heartbeat before the decision, so the bridge labels it with the current policy */
    hb.uptime_ms = now;
    hb.mode = bot->mode;
    hb.state = (uint8_t)((bot->link_ok ? QNAV_LINK_STATE_LINK_OK : 0u) |
                         (moving ? QNAV_LINK_STATE_MOVING : 0u) |
                         (bot->ctrl_ready ? QNAV_LINK_STATE_POLICY : 0u) |
                         (moving ? 0u : QNAV_LINK_STATE_STOPPED));
    hb.rx_ok = (uint16_t)bot->rx.stats.frames_ok;
    hb.rx_dropped = (uint16_t)qnav_link_rx_dropped_total(&bot->rx);
    hb.policy_crc = bot->policy_crc;
    send(bot, QNAV_LINK_MSG_HEARTBEAT, p, qnav_link_heartbeat_pack(&hb, p, sizeof p));
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
