/*
 * Host tests of the TekBot board application with a simulated hardware layer: motors stop
 * when the link goes quiet, without a goal and on a commanded stop; onboard decisions are
 * libqnav's; offboard commands are applied and expire; policy uploads are checked before
 * use; corrupted frames are not acted on; and the board runs against navbridge's core in
 * one process (memq:// LCM) in both modes.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "bridge.h"
#include "qnav/drive.h"
#include "qnav/link.h"
#include "qnav/tekbot.h"
#include "qnav_odometry_t.h"
#include "qnav_waypoints_t.h"
#include "sim_hal.h"

typedef struct {
    sim_hal_t sim;
    qnav_board_hal_t hal;
    qnav_board_t bot;
    qnav_link_tx_t btx;           /* the bridge's sender */
    qnav_link_rx_t brx;           /* the bridge's receiver */
    uint32_t read_upto;           /* bytes of from_board already decoded */
    uint32_t scans, telemetry, acks;
    qnav_link_command_t last_tel;
    qnav_link_command_t prev_tel;     /* the onboard decision before last_tel */
    qnav_cdeg_t pose_heading_cdeg;    /* the last POSE frame's heading */
    qnav_cdeg_t tel_yaw_cdeg;         /* the heading last_tel was decided at (its tick's POSE) */
    qnav_cdeg_t prev_tel_yaw_cdeg;    /* and prev_tel's */
    uint16_t last_scan_seq;
    qnav_link_scan_t last_scan;
    qnav_link_policy_ack_t last_ack;
    uint32_t pose_clears, pose_grown_mm; /* the map's verdicts the POSE frames carried */
} bench_t;

static bench_t g;

/* The previous decision as the board's step saw it with last_tel's scan (its carry, from
 * the decision before and the turn made since): a reference step gets the same. */
static qnav_cdeg_t tel_prev_heading(void)
{
    return g.telemetry > 1u ? qnav_ctrl_prev_heading(g.prev_tel.heading_deg, g.prev_tel_yaw_cdeg,
                                                     g.tel_yaw_cdeg)
                            : 0;
}

/* The bench with `sectors` sonar sectors; with_table: the HAL has a table area. */
static void bench_start_with(uint16_t sectors, int with_table)
{
    qnav_board_config_t cfg;
    uint16_t k;
    memset(&g, 0, sizeof g);
    sim_hal_init(&g.sim, &g.hal);
    if (with_table) {
        sim_hal_table(&g.sim, &g.hal);
    }
    g.sim.n_ranges = sectors;
    for (k = 0; k < sectors; ++k) {
        g.sim.ranges_mm[k] = (qnav_mm_t)(1500 + 250 * k);
    }
    qnav_tekbot_config_default(&cfg);
    cfg.ctrl.n_sectors = sectors;
    assert_int_equal(qnav_board_init(&g.bot, &cfg, &g.hal), QNAV_BOARD_OK);
    qnav_link_tx_init(&g.btx);
    qnav_link_rx_init(&g.brx);
}

static void bench_start(uint16_t sectors)
{
    bench_start_with(sectors, 0);
}

static void to_board(uint8_t id, const uint8_t *p, int32_t n)
{
    uint8_t wire[QNAV_LINK_MAX_WIRE(QNAV_LINK_MAX_PAYLOAD)];
    int32_t w;
    assert_true(n >= 0);
    w = qnav_link_encode(&g.btx, id, p, (uint16_t)n, wire, sizeof wire);
    assert_true(w > 0);
    sim_hal_to_board(&g.sim, wire, (uint32_t)w);
}

static void heartbeat(uint8_t mode, uint8_t state)
{
    qnav_link_heartbeat_t hb = {0, mode, state, 0, 0, 0};
    uint8_t p[QNAV_LINK_HEARTBEAT_BYTES];
    to_board(QNAV_LINK_MSG_HEARTBEAT, p, qnav_link_heartbeat_pack(&hb, p, sizeof p));
}

static void goal(uint16_t id, qnav_cdeg_t bearing)
{
    qnav_link_goal_t gl = {id, bearing, 3000};
    uint8_t p[QNAV_LINK_GOAL_BYTES];
    to_board(QNAV_LINK_MSG_GOAL, p, qnav_link_goal_pack(&gl, p, sizeof p));
}

static void command(qnav_deg_t heading, qnav_q1_15_t speed, uint8_t flags)
{
    qnav_link_command_t c = {0, heading, speed, 20000, flags, 0};
    uint8_t p[QNAV_LINK_COMMAND_BYTES];
    to_board(QNAV_LINK_MSG_COMMAND, p, qnav_link_command_pack(&c, p, sizeof p));
}

/* Decode what the board sent since last time. */
static void read_board(void)
{
    qnav_link_frame_t f;
    while (g.read_upto < g.sim.from_board_n) {
        if (!qnav_link_rx_feed(&g.brx, g.sim.from_board[g.read_upto++], &f)) {
            continue;
        }
        if (f.msg_id == QNAV_LINK_MSG_SCAN) {
            assert_int_equal(qnav_link_scan_unpack(f.payload, f.len, &g.last_scan), 0);
            g.last_scan_seq = f.seq;
            g.scans++;
        } else if (f.msg_id == QNAV_LINK_MSG_COMMAND) {
            g.prev_tel = g.last_tel;
            g.prev_tel_yaw_cdeg = g.tel_yaw_cdeg;
            g.tel_yaw_cdeg = g.pose_heading_cdeg; /* a tick's POSE comes before its decision */
            assert_int_equal(qnav_link_command_unpack(f.payload, f.len, &g.last_tel), 0);
            g.telemetry++;
        } else if (f.msg_id == QNAV_LINK_MSG_POSE) {
            qnav_link_pose_t ps;
            assert_int_equal(qnav_link_pose_unpack(f.payload, f.len, &ps), 0);
            g.pose_heading_cdeg = ps.heading_cdeg;
            g.pose_clears += ps.escape_clear;
            g.pose_grown_mm += ps.escape_grow_mm;
        } else if (f.msg_id == QNAV_LINK_MSG_POLICY_ACK) {
            assert_int_equal(qnav_link_policy_ack_unpack(f.payload, f.len, &g.last_ack), 0);
            g.acks++;
        }
    }
}

/* Advance the simulated clock in 10 ms steps, polling the board. */
static void run_ms(uint32_t ms)
{
    uint32_t t;
    for (t = 0; t < ms; t += 10) {
        g.sim.now_ms += 10;
        qnav_board_poll(&g.bot);
        read_board();
    }
}

/* Keep the link alive in the given mode for ms (heartbeat every 100 ms). */
static void run_with_heartbeats(uint8_t mode, uint8_t state, uint32_t ms)
{
    uint32_t t;
    for (t = 0; t < ms; t += 100) {
        heartbeat(mode, state);
        run_ms(100);
    }
}

/* Offboard for ticks ticks (100 ms each), a heartbeat and the same command every tick. */
static void offboard_commands(qnav_deg_t heading, qnav_q1_15_t speed, uint32_t ticks)
{
    uint32_t t;
    for (t = 0; t < ticks; ++t) {
        heartbeat(QNAV_LINK_MODE_OFFBOARD, 0);
        command(heading, speed, 0);
        run_ms(100);
    }
}

static int moving(void)
{
    return g.sim.left != 0 || g.sim.right != 0;
}

static void test_board_is_stopped_until_it_hears_the_bridge(void **state)
{
    (void)state;
    bench_start(8);
    run_ms(1000);
    assert_false(moving());
    assert_true(g.sim.motor_calls >= 10u); /* set to 0 every tick, not just once */
    assert_true(g.scans >= 9u);            /* scans go out regardless, to find the bridge */
}

static void test_onboard_board_drives_with_libqnav_decision(void **state)
{
    qnav_ctrl_t c;
    qnav_board_config_t bc;
    qnav_ctrl_config_t cc;
    qnav_policy_t p;
    qnav_ctrl_input_t in = {0};
    qnav_ctrl_output_t want;
    (void)state;
    bench_start(16); /* the TekBot profile's sector count */
    g.sim.heading_cdeg = 1000;
    goal(1, 5500);
    run_with_heartbeats(QNAV_LINK_MODE_ONBOARD, 0, 500);
    assert_true(moving());
    assert_true(g.telemetry > 0u);
    /* the telemetry is exactly libqnav's step on the reported scan */
    assert_int_equal(g.last_scan.goal_bearing_cdeg, 4500);
    qnav_tekbot_config_default(&bc);
    cc = bc.ctrl; /* the board's controller is configured by its robot's profile */
    qnav_policy_prob_default(&p);
    assert_int_equal(qnav_ctrl_init(&c, &cc, &p), QNAV_OK);
    in.ranges_mm = g.last_scan.ranges_mm;
    in.goal_bearing_cdeg = g.last_scan.goal_bearing_cdeg;
    in.prev_heading_cdeg = tel_prev_heading();
    qnav_ctrl_step(&c, &in, &want, NULL);
    assert_int_equal(g.last_tel.heading_deg, want.heading_deg);
    assert_int_equal(g.last_tel.speed, want.speed);
    assert_int_equal(g.last_tel.quality, want.quality);
    assert_int_equal(g.last_tel.scan_seq, g.last_scan_seq);
}

static void test_board_stops_motors_when_link_goes_quiet(void **state)
{
    uint32_t t, quiet_ms = 0;
    (void)state;
    bench_start(8);
    goal(1, 0);
    run_with_heartbeats(QNAV_LINK_MODE_ONBOARD, 0, 500);
    assert_true(moving());
    /* nothing from the bridge any more: stopped within timeout + one tick */
    for (t = 0; t < 1000 && moving(); t += 10) {
        run_ms(10);
        quiet_ms += 10;
    }
    assert_false(moving());
    assert_true(quiet_ms >= 300u);
    assert_true(quiet_ms <= 300u + 100u + 10u);
    assert_int_equal(g.bot.stats.link_lost, 1);
}

static void test_board_without_goal_stays_stopped(void **state)
{
    (void)state;
    bench_start(8);
    run_with_heartbeats(QNAV_LINK_MODE_ONBOARD, 0, 600);
    assert_false(moving());
    assert_true(g.telemetry > 0u);
    assert_true((g.last_tel.flags & QNAV_LINK_CMD_STOP) != 0u);
}

static void test_offboard_board_applies_commands_and_drops_stale_ones(void **state)
{
    uint32_t t;
    (void)state;
    bench_start(8);
    goal(1, 0);
    offboard_commands(0, 16384, 5);
    assert_int_equal(g.sim.left, 16384);
    assert_int_equal(g.sim.right, 16384);
    assert_int_equal(g.telemetry, 0); /* offboard: the board does not decide */
    /* heartbeats continue but commands stop: the last command expires */
    for (t = 0; t < 5; ++t) {
        heartbeat(QNAV_LINK_MODE_OFFBOARD, 0);
        run_ms(100);
    }
    assert_false(moving());
}

static void test_stop_command_holds_until_the_bridge_clears_it(void **state)
{
    (void)state;
    bench_start(8);
    goal(1, 0);
    run_with_heartbeats(QNAV_LINK_MODE_ONBOARD, 0, 300);
    assert_true(moving());
    command(0, 0, QNAV_LINK_CMD_STOP);
    run_ms(100);
    assert_false(moving());
    run_with_heartbeats(QNAV_LINK_MODE_ONBOARD, QNAV_LINK_STATE_STOPPED, 300);
    assert_false(moving());
    run_with_heartbeats(QNAV_LINK_MODE_ONBOARD, 0, 300);
    assert_true(moving());
}

/* A decision of speed 0 toward a heading turns the robot in place, as the simulator's robot
 * turns (the board used to stand still: a robot boxed in by near readings, whose controller
 * can only turn, froze). Offboard and onboard; with the link lost it stops. */
static void test_a_decision_of_speed_0_turns_in_place(void **state)
{
    uint16_t k;
    (void)state;
    bench_start(8);
    goal(1, 0);
    offboard_commands(120, 0, 3);
    assert_int_equal(g.sim.drive_speed, 0);
    assert_true(g.sim.right > 0);
    assert_int_equal(g.sim.left, -g.sim.right);

    bench_start(16);
    for (k = 0; k < 16; ++k) {
        g.sim.ranges_mm[k] = 60; /* boxed in: no path has room to move */
    }
    goal(1, 9000);
    run_with_heartbeats(QNAV_LINK_MODE_ONBOARD, 0, 500);
    assert_true(g.telemetry > 0);
    assert_int_equal(g.last_tel.speed, 0);
    assert_true(g.last_tel.heading_deg != 0);
    assert_false(g.last_tel.flags & QNAV_LINK_CMD_STOP);
    assert_true(moving());
    assert_int_equal(g.sim.left, -g.sim.right);
    run_ms(1500); /* the link goes quiet: the board stops */
    assert_false(moving());
}

/* The core measures how fast the robot rolls from the encoders (the last tick's mean
 * travel) and gives it to the drive: a turn in place while the wheels still roll forward
 * brakes first (both wheels 0), and turns once they have stopped. */
static void test_a_turn_in_place_brakes_while_the_encoders_say_the_robot_rolls(void **state)
{
    int32_t full;
    uint32_t t;
    (void)state;
    bench_start(8);
    goal(1, 0);
    /* counts a tick at v_max */
    full = (int32_t)((uint32_t)g.bot.cfg.ctrl.v_max_mm_s * g.bot.cfg.tick_ms /
                     g.bot.cfg.um_per_count);
    assert_true(full >= 4);
    for (t = 0; t < 3; ++t) { /* rolling at full speed, told to turn round at speed 0 */
        g.sim.left_counts += full;
        g.sim.right_counts += full;
        offboard_commands(120, 0, 1);
    }
    assert_true(g.sim.drive_rolling > QNAV_DRIVE_STOPPED);
    assert_int_equal(g.sim.drive_heading, 120);
    assert_int_equal(g.sim.left, 0); /* braking */
    assert_int_equal(g.sim.right, 0);
    offboard_commands(120, 0, 2); /* the wheels have stopped: it turns in place */
    assert_int_equal(g.sim.drive_rolling, 0);
    assert_true(g.sim.right > 0);
    assert_int_equal(g.sim.left, -g.sim.right);
    g.sim.left_counts += 1; /* a count forward in a tick, far below 1/8 of v_max: it brakes */
    offboard_commands(120, 0, 1);
    assert_true(g.sim.drive_rolling > 0 && g.sim.drive_rolling < QNAV_DRIVE_STOPPED);
    assert_int_equal(g.sim.left, 0);
    assert_int_equal(g.sim.right, 0);
}

static void test_corrupted_goal_is_not_acted_on(void **state)
{
    uint8_t wire[64], p[QNAV_LINK_GOAL_BYTES];
    qnav_link_goal_t gl = {0x0101u, 0x0202, 0x01020304u};
    int32_t w;
    (void)state;
    bench_start(8);
    w = qnav_link_encode(&g.btx, QNAV_LINK_MSG_GOAL, p,
                         (uint16_t)qnav_link_goal_pack(&gl, p, sizeof p), wire, sizeof wire);
    assert_true(w > 8);
    wire[6] ^= 0x10;
    sim_hal_to_board(&g.sim, wire, (uint32_t)w);
    run_with_heartbeats(QNAV_LINK_MODE_ONBOARD, 0, 500);
    assert_false(moving());
    assert_int_equal(g.last_scan.goal_id, 0);
    assert_true(qnav_link_rx_dropped_total(&g.bot.rx) >= 1u);
}

/* Upload a policy blob to the board in chunks, with the given CRC in the commit. */
static void upload(const qnav_policy_t *pol, int break_crc)
{
    assert_int_equal(sim_hal_upload(&g.sim, &g.btx, pol, break_crc ? 0x0100u : 0u), 0);
}

static void test_uploaded_policy_is_used_and_a_bad_one_is_refused(void **state)
{
    qnav_policy_t net;
    uint16_t k, crc_before;
    (void)state;
    bench_start(8);
    heartbeat(QNAV_LINK_MODE_ONBOARD, 0);
    run_ms(100);
    crc_before = g.bot.policy_crc;
    qnav_policy_net_zero(&net, 4);
    for (k = 0; k < QNAV_NET_WEIGHTS(4); ++k) {
        *qnav_net_weight(&net.u.net, k) = (qnav_q8_8_t)(k * 300 - 2000);
    }
    upload(&net, 1);
    heartbeat(QNAV_LINK_MODE_ONBOARD, 0);
    run_ms(100);
    assert_int_equal(g.acks, 1);
    assert_int_equal(g.last_ack.status, QNAV_LINK_ACK_BAD_CRC);
    assert_int_equal(g.bot.policy_crc, crc_before);
    assert_int_equal(g.bot.policy.kind, QNAV_POLICY_PROB);

    upload(&net, 0);
    heartbeat(QNAV_LINK_MODE_ONBOARD, 0);
    run_ms(100);
    assert_int_equal(g.acks, 2);
    assert_int_equal(g.last_ack.status, QNAV_LINK_ACK_OK);
    assert_int_equal(g.bot.policy.kind, QNAV_POLICY_NET);
    assert_int_equal(g.bot.policy.u.net.w_out[3], net.u.net.w_out[3]);
    assert_int_not_equal(g.bot.policy_crc, crc_before);
    assert_int_equal(g.last_ack.crc, g.bot.policy_crc);
}

/* navbridge's upload carries a 2-input network's row shapes: the board's init copies them
 * instead of evaluating every row; the policy's CRC stays that of its weights, as a
 * start-up from the store (which keeps no shapes) computes it. */
static void test_an_uploaded_network_takes_the_row_shapes_it_carries(void **state)
{
    qnav_policy_t net;
    qnav_board_config_t cfg;
    uint16_t k, crc;
    (void)state;
    bench_start(8);
    heartbeat(QNAV_LINK_MODE_ONBOARD, 0);
    run_ms(100);
    qnav_policy_net_zero(&net, 6);
    for (k = 0; k < QNAV_NET_WEIGHTS(6); ++k) {
        *qnav_net_weight(&net.u.net, k) = (qnav_q8_8_t)(k * 733 - 9000);
    }
    upload(&net, 0);
    heartbeat(QNAV_LINK_MODE_ONBOARD, 0);
    run_ms(100);
    assert_int_equal(g.last_ack.status, QNAV_LINK_ACK_OK);
    assert_int_equal(qnav_ctrl_shapes_carried(qnav_nav_paths(&g.bot.nav)), 1);
    crc = qnav_link_policy_crc(&net);
    assert_int_equal(g.bot.policy_crc, crc);
    assert_int_equal(g.last_ack.crc, crc);

    /* a restart loads the stored policy and computes its shapes: the same CRC */
    cfg = g.bot.cfg;
    assert_int_equal(qnav_board_init(&g.bot, &cfg, &g.hal), QNAV_BOARD_OK);
    assert_int_equal(qnav_board_policy_source(&g.bot), QNAV_BOARD_POLICY_STORED);
    assert_int_equal(qnav_ctrl_shapes_carried(qnav_nav_paths(&g.bot.nav)), 0);
    assert_int_equal(g.bot.policy_crc, crc);
}

/* The rest of a table build at once (a board polls thousands of times a tick). */
static void finish_table(void)
{
    uint32_t n = 0;
    while (qnav_board_table_work(&g.bot)) {
        assert_true(++n < 10000u);
    }
}

/* A restart of the board (a power cycle: storage and table area kept); the bench hears
 * its frames numbered from the start again, as the bridge does. */
static void restart(void)
{
    qnav_board_config_t cfg = g.bot.cfg;
    assert_int_equal(qnav_board_init(&g.bot, &cfg, &g.hal), QNAV_BOARD_OK);
    qnav_link_rx_reset_seq(&g.brx);
}

/* A 2-input network of H hidden units whose weights follow seed. */
static void some_network(qnav_policy_t *net, uint8_t hidden, unsigned seed)
{
    uint16_t k;
    qnav_policy_net_zero(net, hidden);
    for (k = 0; k < QNAV_NET_WEIGHTS(hidden); ++k) {
        *qnav_net_weight(&net->u.net, k) = (qnav_q8_8_t)((int)((k * seed) % 3001u) - 1500);
    }
}

/* The area holds net's table, key for key. */
static void assert_area_holds(const qnav_policy_t *net)
{
    static qnav_qkey_t want[QNAV_QTABLE_ENTRIES];
    qnav_ctrl_t ref;
    qnav_ctrl_config_t cc;
    qnav_nav_config(qnav_nav_find("body"), &g.bot.cfg.ctrl, &cc);
    assert_int_equal(qnav_ctrl_init(&ref, &cc, net), QNAV_OK);
    assert_int_equal(qnav_ctrl_build_table(&ref, want), QNAV_OK);
    assert_memory_equal(g.sim.table, want, sizeof want);
}

/* Table mode on the board (qnav/board.h): an uploaded 2-input network is compiled into the
 * HAL's table area a page at a time between ticks, then the controller reads it. The
 * area's keys are qnav_ctrl_build_table()'s and the decisions the network's; a restart
 * finds the table whole and uses it without writing; a changed key makes a restart build
 * it again; a failed page write leaves the network step driving. */
static void test_an_uploaded_network_is_compiled_into_the_table_area(void **state)
{
    qnav_policy_t net;
    qnav_ctrl_t ref;
    qnav_ctrl_config_t cc;
    qnav_ctrl_input_t in = {0};
    qnav_ctrl_output_t out;
    uint32_t pages;
    uint16_t k;
    (void)state;
    bench_start_with(16, 1);
    heartbeat(QNAV_LINK_MODE_ONBOARD, 0);
    run_ms(100);
    assert_int_equal(qnav_board_table_state(&g.bot), QNAV_BOARD_TABLE_NONE); /* built-in */
    some_network(&net, 12, 733u);
    upload(&net, 0);
    heartbeat(QNAV_LINK_MODE_ONBOARD, 0);
    run_ms(100);
    assert_int_equal(g.acks, 1);
    assert_int_equal(g.last_ack.status, QNAV_LINK_ACK_OK);
    assert_int_equal(qnav_board_table_state(&g.bot), QNAV_BOARD_TABLE_BUILDING);
    assert_true(g.bot.table_at > 0u); /* polls between ticks made keys */
    finish_table();
    goal(1, 5500);
    run_with_heartbeats(QNAV_LINK_MODE_ONBOARD, 0, 500);
    assert_int_equal(qnav_board_table_state(&g.bot), QNAV_BOARD_TABLE_IN_USE);
    assert_int_equal(g.bot.stats.tables_built, 1);
    assert_int_equal(g.sim.table_pages_written, SIM_HAL_TABLE_PAGES);
    assert_true(moving());

    assert_area_holds(&net);
    qnav_nav_config(qnav_nav_find("body"), &g.bot.cfg.ctrl, &cc);
    assert_int_equal(qnav_ctrl_init(&ref, &cc, &net), QNAV_OK);
    in.ranges_mm = g.last_scan.ranges_mm;
    in.goal_bearing_cdeg = g.last_scan.goal_bearing_cdeg;
    in.prev_heading_cdeg = tel_prev_heading();
    qnav_ctrl_step(&ref, &in, &out, NULL);
    assert_int_equal(g.last_tel.heading_deg, out.heading_deg);
    assert_int_equal(g.last_tel.speed, out.speed);

    pages = g.sim.table_pages_written;
    restart();
    assert_int_equal(qnav_board_table_state(&g.bot), QNAV_BOARD_TABLE_IN_USE);
    assert_int_equal(g.bot.stats.tables_reused, 1);
    run_with_heartbeats(QNAV_LINK_MODE_ONBOARD, 0, 500);
    assert_int_equal(g.sim.table_pages_written, pages);

    g.sim.table[2 * 1000 + 1] ^= 0x40u; /* one key of level 5 */
    restart();
    assert_int_equal(qnav_board_table_state(&g.bot), QNAV_BOARD_TABLE_BUILDING);
    /* a page of 128 keys is made in 32 calls of 4 keys, then written in a call of its own */
    for (k = 0; k < 32u; ++k) {
        assert_int_equal(qnav_board_table_need_ms(&g.bot), QNAV_BOARD_TABLE_KEYS_MS);
        assert_int_equal(qnav_board_table_work(&g.bot), 1);
    }
    assert_int_equal(g.sim.table_pages_written, pages);
    assert_int_equal(qnav_board_table_need_ms(&g.bot), QNAV_BOARD_TABLE_WRITE_MS);
    assert_int_equal(qnav_board_table_work(&g.bot), 1);
    assert_int_equal(g.sim.table_pages_written, pages + 1u);
    finish_table();
    assert_int_equal(qnav_board_table_state(&g.bot), QNAV_BOARD_TABLE_IN_USE);
    assert_int_equal(g.sim.table_pages_written, pages + SIM_HAL_TABLE_PAGES);
    assert_area_holds(&net);

    g.sim.table[0] ^= 0x01u;
    g.sim.table_fail_after = g.sim.table_pages_written + 3u;
    restart();
    goal(2, 5500); /* a restart forgets the goal */
    finish_table();
    run_with_heartbeats(QNAV_LINK_MODE_ONBOARD, 0, 500);
    assert_int_equal(qnav_board_table_state(&g.bot), QNAV_BOARD_TABLE_NONE);
    assert_int_equal(g.bot.stats.table_writes_failed, 1);
    assert_true(g.bot.ctrl_ready);
    assert_true(moving());
}

/* An upload and a table build share one buffer (qnav/board.h, qnav_board_t.buf): an upload
 * that arrives mid-build takes it, and the build starts again when the upload ends,
 * whether its commit is taken, refused, or never comes (the link lost). No table is
 * built from a page the upload wrote over. */
static void test_an_upload_mid_build_takes_the_buffer_and_the_build_starts_again(void **state)
{
    qnav_policy_t a, b;
    qnav_link_policy_chunk_t c = {0};
    uint8_t p[QNAV_LINK_CHUNK_MAX_BYTES];
    uint16_t k;
    (void)state;
    bench_start_with(16, 1);
    heartbeat(QNAV_LINK_MODE_ONBOARD, 0);
    run_ms(100);
    some_network(&a, 12, 733u);
    some_network(&b, 8, 911u);
    upload(&a, 0);
    heartbeat(QNAV_LINK_MODE_ONBOARD, 0);
    run_ms(100);
    assert_int_equal(g.last_ack.status, QNAV_LINK_ACK_OK);
    assert_int_equal(qnav_board_table_state(&g.bot), QNAV_BOARD_TABLE_BUILDING);
    assert_true(g.bot.table_at > 0u && g.bot.table_at < QNAV_BOARD_TABLE_BYTES);

    /* b arrives mid-build: taken, and its table built from the start */
    upload(&b, 0);
    heartbeat(QNAV_LINK_MODE_ONBOARD, 0);
    run_ms(100);
    assert_int_equal(g.acks, 2);
    assert_int_equal(g.last_ack.status, QNAV_LINK_ACK_OK);
    assert_int_equal(g.bot.policy.u.net.hidden, 8);
    assert_int_equal(qnav_board_table_state(&g.bot), QNAV_BOARD_TABLE_BUILDING);
    finish_table();
    assert_int_equal(qnav_board_table_state(&g.bot), QNAV_BOARD_TABLE_IN_USE);
    assert_int_equal(g.bot.stats.tables_built, 1); /* a's was never finished */
    assert_area_holds(&b);

    /* a commit refused mid-build: the build starts again */
    g.sim.table[2 * 1000 + 1] ^= 0x40u;
    restart();
    heartbeat(QNAV_LINK_MODE_ONBOARD, 0);
    for (k = 0; k < 40u; ++k) {
        assert_int_equal(qnav_board_table_work(&g.bot), 1);
    }
    upload(&a, 1);
    heartbeat(QNAV_LINK_MODE_ONBOARD, 0);
    run_ms(100);
    assert_int_equal(g.last_ack.status, QNAV_LINK_ACK_BAD_CRC);
    assert_int_equal(g.bot.policy.u.net.hidden, 8);
    assert_int_equal(qnav_board_table_state(&g.bot), QNAV_BOARD_TABLE_BUILDING);
    finish_table();
    assert_int_equal(qnav_board_table_state(&g.bot), QNAV_BOARD_TABLE_IN_USE);
    assert_area_holds(&b);

    /* an upload's first chunk, then nothing: the build waits for the link's loss */
    g.sim.table[2 * 1000 + 1] ^= 0x40u;
    restart();
    heartbeat(QNAV_LINK_MODE_ONBOARD, 0);
    run_ms(100);
    assert_int_equal(qnav_board_table_state(&g.bot), QNAV_BOARD_TABLE_BUILDING);
    c.total = 40;
    c.len = 20;
    memset(c.data, 0x5A, c.len);
    to_board(QNAV_LINK_MSG_POLICY_CHUNK, p, qnav_link_policy_chunk_pack(&c, p, sizeof p));
    run_ms(100);
    assert_int_equal(qnav_board_table_state(&g.bot), QNAV_BOARD_TABLE_NONE);
    run_ms(g.bot.cfg.link_timeout_ms + 100u);
    assert_int_equal(g.bot.stats.link_lost, 1);
    assert_int_equal(qnav_board_table_state(&g.bot), QNAV_BOARD_TABLE_BUILDING);
    finish_table();
    assert_int_equal(qnav_board_table_state(&g.bot), QNAV_BOARD_TABLE_IN_USE);
    assert_area_holds(&b);
}

/* Only a 2-input network is compiled: the built-in policy and a 3-input network leave the
 * area alone. */
static void test_only_a_two_input_network_uses_the_table_area(void **state)
{
    qnav_policy_t net3;
    uint16_t k;
    (void)state;
    bench_start_with(16, 1);
    run_with_heartbeats(QNAV_LINK_MODE_ONBOARD, 0, 300);
    assert_int_equal(qnav_board_table_state(&g.bot), QNAV_BOARD_TABLE_NONE);
    qnav_policy_net_zero_inputs(&net3, 4, QNAV_NET_INPUTS_PREV);
    for (k = 0; k < qnav_net_weight_count(&net3.u.net); ++k) {
        *qnav_net_weight(&net3.u.net, k) = (qnav_q8_8_t)(k * 211 - 3000);
    }
    upload(&net3, 0);
    run_with_heartbeats(QNAV_LINK_MODE_ONBOARD, 0, 1000);
    assert_int_equal(g.acks, 1);
    assert_int_equal(g.last_ack.status, QNAV_LINK_ACK_OK);
    assert_int_equal(g.bot.policy.u.net.inputs, QNAV_NET_INPUTS_PREV);
    assert_int_equal(qnav_board_table_state(&g.bot), QNAV_BOARD_TABLE_NONE);
    assert_int_equal(g.sim.table_pages_written, 0);
}

static void test_board_ignores_a_bridge_of_another_protocol_version(void **state)
{
    qnav_link_heartbeat_t hb = {0, QNAV_LINK_MODE_ONBOARD, 0, 0, 0, 0};
    uint8_t p[QNAV_LINK_HEARTBEAT_BYTES];
    uint32_t t;
    (void)state;
    bench_start(8);
    goal(1, 0);
    assert_int_equal(qnav_link_heartbeat_pack(&hb, p, sizeof p), QNAV_LINK_HEARTBEAT_BYTES);
    p[12] = QNAV_LINK_PROTOCOL_VERSION + 1u;
    for (t = 0; t < 1000; t += 100) {
        to_board(QNAV_LINK_MSG_HEARTBEAT, p, QNAV_LINK_HEARTBEAT_BYTES);
        run_ms(100);
    }
    assert_int_equal(g.bot.mode, 0);
    assert_int_equal(g.bot.stats.peer_protocol, QNAV_LINK_PROTOCOL_VERSION + 1u);
    assert_true(g.bot.stats.peer_refused >= 9u);
    assert_false(moving());
    assert_int_equal(g.telemetry, 0); /* no onboard decisions either */
}

static void test_pose_integrates_wheel_travel_along_the_heading(void **state)
{
    const qnav_board_pose_t *pose;
    (void)state;
    bench_start(8);
    /* 1 m straight ahead (heading 0): 1000000 um / 6872 um per count = 145.5 counts */
    g.sim.left_counts = 146;
    g.sim.right_counts = 146;
    qnav_board_tick(&g.bot);
    pose = qnav_board_pose(&g.bot);
    assert_int_equal(pose->x_um / 1000, 1003); /* 146 * 6.872 mm */
    assert_int_equal(pose->y_um / 1000, 0);
    /* turn to 90 deg on the spot (wheels opposite), then 1 m: along +y */
    g.sim.left_counts -= 20;
    g.sim.right_counts += 20;
    g.sim.heading_cdeg = 9000;
    qnav_board_tick(&g.bot);
    g.sim.left_counts += 146;
    g.sim.right_counts += 146;
    qnav_board_tick(&g.bot);
    assert_int_equal(pose->x_um / 1000, 1003);
    assert_int_equal(pose->y_um / 1000, 1003);
    assert_int_equal(pose->heading_cdeg, 9000);
    /* backwards 0.5 m at 90 deg: y falls */
    g.sim.left_counts -= 73;
    g.sim.right_counts -= 73;
    qnav_board_tick(&g.bot);
    assert_int_equal(pose->y_um / 1000, 501);
}

static void test_position_goal_bearing_comes_from_the_pose(void **state)
{
    qnav_link_goal_t gl = {7, 0, 0, QNAV_LINK_GOAL_POSITION, 1000, 1000};
    uint8_t p[QNAV_LINK_GOAL_BYTES];
    (void)state;
    bench_start(8);
    to_board(QNAV_LINK_MSG_GOAL, p, qnav_link_goal_pack(&gl, p, sizeof p));
    heartbeat(QNAV_LINK_MODE_ONBOARD, 0);
    run_ms(100);
    /* from the origin facing +x, (1 m, 1 m) is 45 deg to the left */
    assert_int_equal(g.last_scan.goal_id, 7);
    assert_int_equal(g.last_scan.goal_bearing_cdeg, 4500);
    /* facing +y (90 deg) it is 45 deg to the right */
    g.sim.heading_cdeg = 9000;
    heartbeat(QNAV_LINK_MODE_ONBOARD, 0);
    run_ms(100);
    assert_int_equal(g.last_scan.goal_bearing_cdeg, -4500);
}

/* A 16-sector board whose sonar sees a wall 1 m ahead across the three sectors round
 * straight ahead, and nothing else. */
static void start_before_a_wall(void)
{
    uint16_t k;
    bench_start(16);
    for (k = 0; k < 16; ++k) {
        g.sim.ranges_mm[k] = g.bot.cfg.ctrl.max_range_mm;
    }
    g.sim.ranges_mm[15] = g.sim.ranges_mm[0] = g.sim.ranges_mm[1] =
        (qnav_mm_t)(1000 - g.bot.cfg.ctrl.sensor_offset_mm);
}

/* With a map, a position goal behind a wall the sonar keeps seeing is steered round it;
 * without one, straight at it. The scripted robot stands at the origin facing +x. */
static void test_a_board_with_a_map_steers_round_what_it_has_seen(void **state)
{
    static uint16_t mem[60 * 60 * 4 + 270];
    qnav_map_t map;
    qnav_map_config_t mc;
    qnav_link_goal_t gl = {9, 0, 0, QNAV_LINK_GOAL_POSITION, 3000, 0};
    uint8_t p[QNAV_LINK_GOAL_BYTES];
    (void)state;
    start_before_a_wall();
    qnav_map_config_default(&mc);
    mc.plan_ticks = 1;
    assert_true(qnav_map_size(&mc, 6000, 6000) <= sizeof mem);
    assert_int_equal(qnav_map_init(&map, &mc, &g.bot.cfg.ctrl, -3000, -3000, 6000, 6000, mem,
                                   sizeof mem),
                     QNAV_OK);
    to_board(QNAV_LINK_MSG_GOAL, p, qnav_link_goal_pack(&gl, p, sizeof p));
    heartbeat(QNAV_LINK_MODE_ONBOARD, 0);
    run_ms(100);
    assert_int_equal(g.last_scan.goal_bearing_cdeg, 0);
    read_board();
    assert_int_equal(g.pose_clears + g.pose_grown_mm, 0);
    assert_int_equal(qnav_board_set_map(&g.bot, &map), 1);
    run_with_heartbeats(QNAV_LINK_MODE_ONBOARD, 0, 500);
    assert_true(qnav_map_evidence(&map, 1000, 50) >= QNAV_MAP_OCCUPIED);
    assert_true(g.last_scan.goal_bearing_cdeg > 2000 || g.last_scan.goal_bearing_cdeg < -2000);
    /* the plan round the wall is longer than the straight one was: the POSE says what
     * that did to the escape memory, for an offboard controller */
    assert_true(g.pose_clears + g.pose_grown_mm > 0);
    assert_int_equal(qnav_board_set_map(&g.bot, NULL), 1);
    g.pose_clears = g.pose_grown_mm = 0;
    run_with_heartbeats(QNAV_LINK_MODE_ONBOARD, 0, 200);
    assert_int_equal(g.last_scan.goal_bearing_cdeg, 0);
    assert_int_equal(g.pose_clears + g.pose_grown_mm, 0);
}

/* A board that places its own maps (qnav_board_place_maps, the compact map a TekBot
 * holds): at each new position goal a map afresh over the square midway to it, steering
 * round the wall as a map the caller gives does; a goal too far for the square gets one
 * that reaches toward it from the robot. The scripted robot stands at the origin facing
 * +x, a wall 1 m ahead. */
static void test_a_board_places_a_map_for_each_goal(void **state)
{
    static uint8_t mem[512];
    static qnav_map_t map;
    qnav_map_config_t mc;
    qnav_link_goal_t gl = {9, 0, 0, QNAV_LINK_GOAL_POSITION, 3000, 0};
    uint8_t p[QNAV_LINK_GOAL_BYTES];
    (void)state;
    start_before_a_wall();
    qnav_map_config_default(&mc);
    mc.compact = 1;
    mc.cell_mm = 400;
    mc.near_cost = 0;
    mc.refuse_ticks = 0;
    mc.plan_ticks = 1;
    assert_int_equal(qnav_board_place_maps(&g.bot, &map, &mc, mem, sizeof mem), 1);
    to_board(QNAV_LINK_MSG_GOAL, p, qnav_link_goal_pack(&gl, p, sizeof p));
    run_with_heartbeats(QNAV_LINK_MODE_ONBOARD, 0, 500);
    /* 512 bytes: 32 x 32 cells of 400 mm, 12.8 m square about (1500, 0) */
    assert_int_equal(map.nx, 32);
    assert_int_equal(map.ny, 32);
    assert_int_equal(map.x0_mm, 1500 - 6400);
    assert_int_equal(map.y0_mm, -6400);
    assert_true(qnav_map_evidence(&map, 1000, 50) >= QNAV_MAP_OCCUPIED);
    assert_true(g.last_scan.goal_bearing_cdeg > 2000 || g.last_scan.goal_bearing_cdeg < -2000);
    /* 20 m away: no square of those cells holds both; the robot 2.4 m (the readings' 2 m
     * and a cell) inside its west edge, the square toward the goal, and round the wall */
    gl.goal_id = 10;
    gl.x_mm = 20000;
    to_board(QNAV_LINK_MSG_GOAL, p, qnav_link_goal_pack(&gl, p, sizeof p));
    run_with_heartbeats(QNAV_LINK_MODE_ONBOARD, 0, 300);
    assert_int_equal(map.x0_mm, -2400);
    assert_int_equal(map.y0_mm, -6400);
    assert_true(g.last_scan.goal_bearing_cdeg > 2000 || g.last_scan.goal_bearing_cdeg < -2000);
    /* a new goal near again: a map afresh about the new midpoint */
    gl.goal_id = 11;
    gl.x_mm = 2000;
    gl.y_mm = 1000;
    to_board(QNAV_LINK_MSG_GOAL, p, qnav_link_goal_pack(&gl, p, sizeof p));
    run_with_heartbeats(QNAV_LINK_MODE_ONBOARD, 0, 300);
    assert_int_equal(map.x0_mm, 1000 - 6400);
    assert_int_equal(map.y0_mm, 500 - 6400);
    assert_true(qnav_map_evidence(&map, 1000, 50) >= QNAV_MAP_OCCUPIED);
    /* off: straight at the goal again */
    assert_int_equal(qnav_board_place_maps(&g.bot, NULL, NULL, NULL, 0), 1);
    run_with_heartbeats(QNAV_LINK_MODE_ONBOARD, 0, 200);
    /* atan2(1000, 2000) = 26.57 deg, the CORDIC's within 1 cdeg */
    assert_true(g.last_scan.goal_bearing_cdeg >= 2656 && g.last_scan.goal_bearing_cdeg <= 2658);
    assert_int_equal(qnav_board_place_maps(NULL, &map, &mc, mem, sizeof mem), 0);
    assert_int_equal(qnav_board_place_maps(&g.bot, &map, NULL, mem, sizeof mem), 0);
}

/* ---- the board against navbridge's core, in one process ---- */

static int bridge_write(void *user, const uint8_t *bytes, size_t n)
{
    (void)user;
    sim_hal_to_board(&g.sim, bytes, (uint32_t)n);
    return 0;
}

static void run_with_bridge(qnav_bridge_t *b, uint32_t ms)
{
    uint32_t t;
    for (t = 0; t < ms; t += 10) {
        g.sim.now_ms += 10;
        qnav_board_poll(&g.bot);
        if (g.read_upto < g.sim.from_board_n) {
            qnav_bridge_on_bytes(b, &g.sim.from_board[g.read_upto],
                                 g.sim.from_board_n - g.read_upto, g.sim.now_ms);
            g.read_upto = g.sim.from_board_n;
        }
        qnav_bridge_poll(b, g.sim.now_ms);
    }
}

static void test_board_and_bridge_drive_together_in_both_modes(void **state)
{
    static qnav_bridge_t b;
    qnav_bridge_config_t cfg;
    qnav_goal_t gl;
    lcm_t *lcm = lcm_create("memq://");
    uint8_t mode;
    (void)state;
    assert_non_null(lcm);
    for (mode = QNAV_LINK_MODE_OFFBOARD; mode <= QNAV_LINK_MODE_ONBOARD; ++mode) {
        bench_start(8);
        qnav_bridge_config_default(&cfg);
        cfg.mode = mode;
        qnav_bridge_init(&b, &cfg, lcm, NULL, bridge_write, NULL, g.sim.now_ms);
        memset(&gl, 0, sizeof gl);
        gl.goal_id = 5;
        gl.bearing_cdeg = 3000;
        qnav_bridge_on_goal(&b, &gl, g.sim.now_ms);
        run_with_bridge(&b, 1000);
        assert_true(moving());
        assert_int_equal(g.bot.mode, mode);
        assert_int_equal(g.bot.goal.goal_id, 5);
        assert_int_equal(b.watchdog_stop, 0);
        assert_true(b.rx.stats.frames_ok >= 20u);
        assert_int_equal(qnav_link_rx_dropped_total(&b.rx), 0);
        /* the bridge shuts down: the board stops at once (stop command) */
        qnav_bridge_shutdown(&b, g.sim.now_ms);
        g.sim.now_ms += 10;
        qnav_board_poll(&g.bot);
        qnav_board_tick(&g.bot);
        assert_false(moving());
    }
    lcm_destroy(lcm);
}

static int discard_write(void *user, const uint8_t *bytes, size_t n)
{
    (void)user;
    (void)bytes;
    (void)n;
    return 0;
}

static int g_odometry_seen, g_last_waypoint;

static void on_odometry(const lcm_recv_buf_t *rbuf, const char *channel,
                        const qnav_odometry_t *msg, void *user)
{
    (void)rbuf;
    (void)channel;
    (void)user;
    g_odometry_seen++;
    g_last_waypoint = msg->waypoint;
}

/* Drive the scripted robot's encoders by d counts along its heading. */
static void roll(int32_t d)
{
    g.sim.left_counts += d;
    g.sim.right_counts += d;
}

static void test_route_from_lcm_advances_within_the_radius_and_stops_at_its_end(void **state)
{
    static qnav_bridge_t b;
    qnav_bridge_config_t cfg;
    qnav_waypoints_t w;
    qnav_odometry_t_subscription_t *sub;
    lcm_t *lcm = lcm_create("memq://");
    (void)state;
    assert_non_null(lcm);
    bench_start(8);
    qnav_bridge_config_default(&cfg);
    cfg.mode = QNAV_LINK_MODE_ONBOARD;
    qnav_bridge_init(&b, &cfg, lcm, NULL, bridge_write, NULL, g.sim.now_ms);
    assert_int_equal(qnav_bridge_subscribe(&b, "run1"), 0);
    assert_string_equal(b.route_channel, "QNAV_WAYPOINTS_run1");
    sub = qnav_odometry_t_subscribe(lcm, QNAV_CH_ODOMETRY, on_odometry, NULL);
    memset(&w, 0, sizeof w);
    w.route_id = 4;
    w.n = 3;
    w.x_m[0] = 1.0;
    w.x_m[1] = 1.0;
    w.y_m[1] = 1.0;
    w.y_m[2] = 1.0;
    w.radius_m = 0.2;
    /* strays: the plain channel and another run's token move nothing */
    assert_int_equal(qnav_waypoints_t_publish(lcm, QNAV_CH_WAYPOINTS, &w), 0);
    assert_int_equal(qnav_waypoints_t_publish(lcm, "QNAV_WAYPOINTS_run2", &w), 0);
    while (lcm_handle_timeout(lcm, 0) > 0) {
    }
    run_with_bridge(&b, 300);
    assert_int_equal(g.bot.have_goal, 0);
    assert_int_equal(b.route_n, 0);
    assert_int_equal(qnav_waypoints_t_publish(lcm, "QNAV_WAYPOINTS_run1", &w), 0);
    while (lcm_handle_timeout(lcm, 0) > 0) { /* the bridge's own telemetry, then the route */
    }
    assert_int_equal(b.route_n, 3);
    run_with_bridge(&b, 500);
    assert_int_equal(g.bot.goal.kind, QNAV_LINK_GOAL_POSITION);
    assert_int_equal(g.bot.goal.x_mm, 1000);
    assert_int_equal(g.bot.goal.y_mm, 0);
    assert_true(moving());
    roll(100); /* 687 mm: not yet within 200 mm */
    run_with_bridge(&b, 300);
    assert_int_equal(g.bot.goal.x_mm, 1000);
    assert_int_equal(g.bot.goal.y_mm, 0);
    roll(46); /* 1003 mm */
    run_with_bridge(&b, 300);
    assert_int_equal(g.bot.goal.y_mm, 1000); /* waypoint 2: (1 m, 1 m) */
    qnav_board_tick(&g.bot); /* this tick's scan read here, not by the bridge */
    read_board();
    assert_int_equal(g.last_scan.goal_bearing_cdeg, 9017); /* from (1003, 0) mm: atan2(1000, -3) */
    g.sim.heading_cdeg = 9000; /* turn on the spot first (pose integrates mid-tick heading) */
    run_with_bridge(&b, 100);
    roll(146);
    run_with_bridge(&b, 300);
    assert_int_equal(g.bot.goal.x_mm, 0); /* waypoint 3: (0, 1 m) */
    assert_int_equal(g.bot.goal.y_mm, 1000);
    g.sim.heading_cdeg = 18000 - 1;
    run_with_bridge(&b, 100);
    roll(146);
    run_with_bridge(&b, 300);
    assert_int_equal(g.bot.have_goal, 0); /* route done: goal cleared */
    assert_false(moving());
    while (lcm_handle_timeout(lcm, 0) > 0) {
    }
    assert_true(g_odometry_seen >= 10);
    assert_int_equal(g_last_waypoint, 3);
    qnav_odometry_t_unsubscribe(lcm, sub);
    qnav_bridge_unsubscribe(&b);
    lcm_destroy(lcm);
}

static void test_bridge_takes_lcm_goals_only_on_a_token_of_letters_and_digits(void **state)
{
    static qnav_bridge_t b;
    qnav_bridge_config_t cfg;
    char tok[QNAV_BRIDGE_TOKEN_HEX + 1], again[QNAV_BRIDGE_TOKEN_HEX + 1];
    lcm_t *lcm = lcm_create("memq://");
    (void)state;
    assert_non_null(lcm);
    qnav_bridge_config_default(&cfg);
    qnav_bridge_init(&b, &cfg, lcm, NULL, bridge_write, NULL, 0);
    assert_int_equal(qnav_bridge_subscribe(&b, NULL), -1);
    assert_int_equal(qnav_bridge_subscribe(&b, ""), -1);
    assert_int_equal(qnav_bridge_subscribe(&b, ".*"), -1); /* a regex would take any */
    assert_int_equal(qnav_bridge_subscribe(&b, "0123456789abcdef0123456789abcdef012345678"),
                     -1);
    assert_null(b.goal_sub);
    assert_int_equal(qnav_bridge_token_make(tok, sizeof tok), 0);
    assert_int_equal(qnav_bridge_token_make(again, sizeof again), 0);
    assert_int_equal(strlen(tok), QNAV_BRIDGE_TOKEN_HEX);
    assert_string_not_equal(tok, again);
    assert_int_equal(qnav_bridge_subscribe(&b, tok), 0);
    assert_int_equal(strncmp(b.goal_channel, "QNAV_GOAL_", 10), 0);
    assert_string_equal(b.goal_channel + 10, tok);
    qnav_bridge_unsubscribe(&b);
    assert_string_equal(b.goal_channel, "");
    lcm_destroy(lcm);
}

static void test_route_with_a_bad_radius_is_refused_naming_the_field(void **state)
{
    static qnav_bridge_t b;
    qnav_bridge_config_t cfg;
    qnav_waypoints_t w;
    char err[160];
    (void)state;
    qnav_bridge_config_default(&cfg);
    qnav_bridge_init(&b, &cfg, NULL, NULL, bridge_write, NULL, 0);
    memset(&w, 0, sizeof w);
    w.n = 1;
    w.radius_m = 0.0;
    assert_int_equal(qnav_bridge_on_waypoints(&b, &w, 0, err, sizeof err), -1);
    assert_non_null(strstr(err, "waypoints_t.radius_m"));
    w.n = 17;
    assert_int_equal(qnav_bridge_on_waypoints(&b, &w, 0, err, sizeof err), -1);
    assert_non_null(strstr(err, "waypoints_t.n"));
    assert_int_equal(b.route_n, 0);
}

static void test_bridge_reports_no_answer_when_the_board_never_acks_an_upload(void **state)
{
    static qnav_bridge_t b;
    qnav_bridge_config_t cfg;
    qnav_link_tx_t board_tx;
    qnav_link_heartbeat_t hb = {0, QNAV_LINK_MODE_ONBOARD, QNAV_LINK_STATE_POLICY, 0, 0, 0};
    uint8_t p[QNAV_LINK_HEARTBEAT_BYTES];
    uint8_t wire[QNAV_LINK_MAX_WIRE(QNAV_LINK_HEARTBEAT_BYTES)];
    int32_t n;
    int64_t t;
    (void)state;
    qnav_bridge_config_default(&cfg);
    cfg.mode = QNAV_LINK_MODE_ONBOARD;
    cfg.upload = 1;
    qnav_bridge_init(&b, &cfg, NULL, NULL, discard_write, NULL, 0);
    assert_int_equal(b.last_upload_status, QNAV_BRIDGE_UPLOAD_NONE_YET);
    /* the board's first heartbeat starts the upload; no ack ever comes back */
    qnav_link_tx_init(&board_tx);
    n = qnav_link_encode(&board_tx, QNAV_LINK_MSG_HEARTBEAT, p,
                         (uint16_t)qnav_link_heartbeat_pack(&hb, p, sizeof p), wire,
                         (uint16_t)sizeof wire);
    assert_true(n > 0);
    qnav_bridge_on_bytes(&b, wire, (size_t)n, 10);
    for (t = 10; t <= 4 * QNAV_BRIDGE_UPLOAD_WAIT_MS; t += 10) {
        qnav_bridge_poll(&b, t);
    }
    assert_int_equal(b.upload_tries, 3);
    assert_int_equal(b.upload_state, QNAV_BRIDGE_UPLOAD_DONE);
    assert_int_equal(b.last_upload_status, QNAV_BRIDGE_UPLOAD_NO_ANSWER);
}

/* The board reports every field its robot's profile decides, and a bridge that expects
 * another value finds the field by name. */
static void test_board_reports_its_robot_configuration_field_by_field(void **state)
{
    qnav_board_config_t bc;
    qnav_link_config_t m, back;
    uint8_t p[QNAV_LINK_CONFIG_MAX_BYTES];
    int32_t n;
    (void)state;
    qnav_tekbot_config_default(&bc);
    qnav_board_config_report(&bc, &m);
    n = qnav_link_config_pack(&m, p, sizeof p);
    assert_true(n > 0);
    assert_int_equal(qnav_link_config_unpack(p, (uint16_t)n, &back), QNAV_LINK_OK);
    assert_int_equal(back.n, 22);
    assert_int_equal(back.key[0], 1);
    assert_int_equal(back.value[0], bc.ctrl.n_sectors);
    assert_int_equal(back.key[1], 2);
    assert_int_equal(back.value[1], bc.ctrl.max_range_mm);
    assert_int_equal(back.key[back.n - 2], 34);
    assert_int_equal(back.value[back.n - 2], bc.um_per_count);
    assert_int_equal(back.key[back.n - 1], 35);
    assert_int_equal(back.value[back.n - 1], bc.turn_full_deg);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_board_reports_its_robot_configuration_field_by_field),
        cmocka_unit_test(test_board_is_stopped_until_it_hears_the_bridge),
        cmocka_unit_test(test_onboard_board_drives_with_libqnav_decision),
        cmocka_unit_test(test_board_stops_motors_when_link_goes_quiet),
        cmocka_unit_test(test_board_without_goal_stays_stopped),
        cmocka_unit_test(test_offboard_board_applies_commands_and_drops_stale_ones),
        cmocka_unit_test(test_stop_command_holds_until_the_bridge_clears_it),
        cmocka_unit_test(test_a_decision_of_speed_0_turns_in_place),
        cmocka_unit_test(test_a_turn_in_place_brakes_while_the_encoders_say_the_robot_rolls),
        cmocka_unit_test(test_corrupted_goal_is_not_acted_on),
        cmocka_unit_test(test_uploaded_policy_is_used_and_a_bad_one_is_refused),
        cmocka_unit_test(test_an_uploaded_network_takes_the_row_shapes_it_carries),
        cmocka_unit_test(test_an_uploaded_network_is_compiled_into_the_table_area),
        cmocka_unit_test(test_an_upload_mid_build_takes_the_buffer_and_the_build_starts_again),
        cmocka_unit_test(test_only_a_two_input_network_uses_the_table_area),
        cmocka_unit_test(test_board_ignores_a_bridge_of_another_protocol_version),
        cmocka_unit_test(test_pose_integrates_wheel_travel_along_the_heading),
        cmocka_unit_test(test_position_goal_bearing_comes_from_the_pose),
        cmocka_unit_test(test_a_board_with_a_map_steers_round_what_it_has_seen),
        cmocka_unit_test(test_a_board_places_a_map_for_each_goal),
        cmocka_unit_test(test_board_and_bridge_drive_together_in_both_modes),
        cmocka_unit_test(test_route_from_lcm_advances_within_the_radius_and_stops_at_its_end),
        cmocka_unit_test(test_bridge_takes_lcm_goals_only_on_a_token_of_letters_and_digits),
        cmocka_unit_test(test_route_with_a_bad_radius_is_refused_naming_the_field),
        cmocka_unit_test(test_bridge_reports_no_answer_when_the_board_never_acks_an_upload),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
