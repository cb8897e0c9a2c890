/*
 * End-to-end tests of the navbridge program against a fake board on a pseudo-terminal:
 * offboard commands equal libqnav's for every scan, corrupted and replayed frames are not
 * answered, the watchdog stops the robot within its timeout, SIGTERM and SIGINT stop the
 * robot before exit, a recorded trial replays to identical commands, a policy uploads to
 * an onboard board, and bad options or files fail with one line. LCM is memq:// (nothing
 * leaves the process).
 */
#define _XOPEN_SOURCE 700
#define _DEFAULT_SOURCE
#include <setjmp.h>
#include <signal.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cmocka.h>

#include "fakeboard.h"
#include "qnav/ctrl.h"
#include "qnav/link.h"
#include "qnav/policy_io.h"
#include "qnav_command_t.h"
#include "test_proc.h"

#include <lcm/eventlog.h>

static char g_dir[256];
static char g_policy[300];

static const char *const EXE = NAVBRIDGE_EXE;

static int setup_dir(void **state)
{
    qnav_policy_t p;
    char err[QNAV_POLICY_IO_ERRLEN];
    uint16_t k;
    (void)state;
    if (qnav_test_tmpdir_make(g_dir, sizeof g_dir, "qnav_navbridge_test") != 0) {
        return -1;
    }
    /* a network policy with spread weights: its commands differ from the default's */
    qnav_policy_net_zero(&p, 6);
    for (k = 0; k < QNAV_NET_WEIGHTS(6); ++k) {
        *qnav_net_weight(&p.u.net, k) = (qnav_q8_8_t)((int)((k * 977u) % 2048u) - 1024);
    }
    snprintf(g_policy, sizeof g_policy, "%s/net.policy", g_dir);
    return qnav_policy_write(g_policy, &p, "test network", err, sizeof err);
}

static int teardown_dir(void **state)
{
    (void)state;
    return qnav_test_tmpdir_remove(g_dir);
}

/* A scan with an obstacle that moves with i, and a bearing that sweeps. */
static uint16_t scan_payload(int i, uint16_t n, uint8_t *out, qnav_link_scan_t *s)
{
    uint16_t k;
    memset(s, 0, sizeof *s);
    s->board_ms = (uint32_t)(i * 100);
    s->goal_bearing_cdeg = (qnav_cdeg_t)(((i * 2377) % 36000) - 18000);
    s->max_range_mm = 5000;
    s->n_sectors = n;
    for (k = 0; k < n; ++k) {
        s->ranges_mm[k] =
            (qnav_mm_t)(k == (uint16_t)(i % n) ? 300 : 200 + (k * 613 + i * 97) % 5200);
    }
    return (uint16_t)qnav_link_scan_pack(s, out, QNAV_LINK_MAX_PAYLOAD);
}

/* The command libqnav gives for scan s after the decision whose heading was prev_deg (the
 * bridge carries it from tick to tick; these scans turn the robot by nothing). */
static void expected_command(const qnav_policy_t *p, const qnav_link_scan_t *s,
                             qnav_deg_t prev_deg, qnav_ctrl_output_t *out)
{
    qnav_ctrl_config_t cfg;
    qnav_ctrl_t c;
    qnav_ctrl_input_t in = {0};
    qnav_ctrl_config_default(&cfg);
    cfg.n_sectors = s->n_sectors;
    cfg.max_range_mm = s->max_range_mm;
    assert_int_equal(qnav_ctrl_init(&c, &cfg, p), QNAV_OK);
    in.ranges_mm = s->ranges_mm;
    in.goal_bearing_cdeg = s->goal_bearing_cdeg;
    in.prev_heading_cdeg = (qnav_cdeg_t)(prev_deg * 100);
    qnav_ctrl_step(&c, &in, out, NULL);
}

/* Wait for the bridge's first heartbeat: it is up and reading. */
static void wait_bridge_up(fakeboard_t *fb)
{
    uint8_t p[64];
    assert_true(fakeboard_wait(fb, QNAV_LINK_MSG_HEARTBEAT, 3000, p, sizeof p, NULL) > 0);
}

/* Read frames until a COMMAND answering scan_seq arrives (others skipped). */
static int wait_command_for(fakeboard_t *fb, uint16_t scan_seq, qnav_link_command_t *c)
{
    uint8_t p[64];
    int64_t end = fakeboard_ms() + 2000;
    while (fakeboard_ms() < end) {
        int n = fakeboard_wait(fb, QNAV_LINK_MSG_COMMAND, 200, p, sizeof p, NULL);
        if (n > 0 && qnav_link_command_unpack(p, (uint16_t)n, c) == QNAV_LINK_OK &&
            (c->flags & QNAV_LINK_CMD_STOP) == 0 && c->scan_seq == scan_seq) {
            return 0;
        }
    }
    return -1;
}

/* Wait for a STOP command; returns 0 when one came. */
static int wait_stop(fakeboard_t *fb, int timeout_ms)
{
    uint8_t p[64];
    qnav_link_command_t c;
    int64_t end = fakeboard_ms() + timeout_ms;
    while (fakeboard_ms() < end) {
        int n = fakeboard_wait(fb, QNAV_LINK_MSG_COMMAND, (int)(end - fakeboard_ms()), p,
                               sizeof p, NULL);
        if (n > 0 && qnav_link_command_unpack(p, (uint16_t)n, &c) == QNAV_LINK_OK &&
            (c.flags & QNAV_LINK_CMD_STOP) != 0) {
            assert_int_equal(c.speed, 0);
            return 0;
        }
    }
    return -1;
}

/* Copy a log, changing the speed of the n-th non-stop command by one LSB. */
static void tamper_log(const char *in, const char *out, int nth)
{
    lcm_eventlog_t *r = lcm_eventlog_create(in, "r");
    lcm_eventlog_t *w = lcm_eventlog_create(out, "w");
    lcm_eventlog_event_t *ev;
    int seen = 0;
    assert_non_null(r);
    assert_non_null(w);
    while ((ev = lcm_eventlog_read_next_event(r)) != NULL) {
        qnav_command_t c;
        uint8_t buf[256];
        if (strcmp(ev->channel, "QNAV_COMMAND") == 0 &&
            qnav_command_t_decode(ev->data, 0, ev->datalen, &c) > 0 && c.stop_reason == 0 &&
            seen++ == nth) {
            void *orig = ev->data;
            int32_t orig_len = ev->datalen;
            c.speed_q15 = (int16_t)(c.speed_q15 ^ 1);
            ev->datalen = qnav_command_t_encode(buf, 0, (int)sizeof buf, &c);
            ev->data = buf;
            assert_int_equal(lcm_eventlog_write_event(w, ev), 0);
            ev->data = orig; /* buf is ours: give the event back its own data */
            ev->datalen = orig_len;
            lcm_eventlog_free_event(ev);
            continue;
        }
        assert_int_equal(lcm_eventlog_write_event(w, ev), 0);
        lcm_eventlog_free_event(ev);
    }
    lcm_eventlog_destroy(r);
    lcm_eventlog_destroy(w);
}

static void test_offboard_commands_equal_libqnav_and_replay_identically(void **state)
{
    char log[320], bad_log[320], out[320], err[320], text[4096];
    const char *args[] = {"--lcm-url", "memq://", "--policy", g_policy, "--log", log, NULL};
    fakeboard_t fb;
    qnav_policy_t policy;
    char perr[QNAV_POLICY_IO_ERRLEN];
    int i;
    qnav_deg_t prev = 0;
    (void)state;
    snprintf(log, sizeof log, "%s/trial.lcmlog", g_dir);
    snprintf(bad_log, sizeof bad_log, "%s/tampered.lcmlog", g_dir);
    snprintf(out, sizeof out, "%s/replay.out", g_dir);
    snprintf(err, sizeof err, "%s/replay.err", g_dir);
    assert_int_equal(qnav_policy_read(g_policy, &policy, perr, sizeof perr), 0);
    assert_int_equal(fakeboard_start(&fb, EXE, g_dir, args), 0);
    wait_bridge_up(&fb);

    for (i = 0; i < 40; ++i) {
        uint8_t p[QNAV_LINK_MAX_PAYLOAD];
        qnav_link_scan_t s;
        qnav_link_command_t c;
        qnav_ctrl_output_t want;
        uint16_t seq = fb.tx.next_seq;
        uint16_t n = scan_payload(i, i < 20 ? 16 : 32, p, &s);
        assert_int_equal(fakeboard_send(&fb, QNAV_LINK_MSG_SCAN, p, n), 0);
        assert_int_equal(wait_command_for(&fb, seq, &c), 0);
        expected_command(&policy, &s, prev, &want);
        prev = want.heading_deg;
        assert_int_equal(c.heading_deg, want.heading_deg);
        assert_int_equal(c.speed, want.speed);
        assert_int_equal(c.quality, want.quality);
        assert_int_equal(c.flags, want.flags);
    }
    /* SIGTERM: a stop reaches the board, then a clean exit */
    kill(fb.pid, SIGTERM);
    assert_int_equal(wait_stop(&fb, QNAV_TEST_WAIT_MS), 0);
    assert_int_equal(fakeboard_signal_and_wait(&fb, 0, QNAV_TEST_WAIT_MS), 0);
    fakeboard_close(&fb);

    {
        const char *replay[] = {EXE, "--replay", log, "--policy", g_policy, NULL};
        const char *wrong[] = {EXE, "--replay", log, NULL}; /* default policy */
        const char *tampered[] = {EXE, "--replay", bad_log, "--policy", g_policy, NULL};
        assert_int_equal(run_program(replay, out, err), 0);
        assert_true(read_text(out, text, sizeof text) > 0);
        assert_non_null(strstr(text, "40 commands compared: 40 identical, 0 differ"));
        /* another policy: nothing comparable, refused */
        assert_int_equal(run_program(wrong, out, err), 1);
        assert_true(read_text(out, text, sizeof text) > 0);
        assert_non_null(strstr(text, "40 from another policy"));
        /* one command changed by one LSB: caught */
        tamper_log(log, bad_log, 17);
        assert_int_equal(run_program(tampered, out, err), 1);
        assert_true(read_text(out, text, sizeof text) > 0);
        assert_non_null(strstr(text, "39 identical, 1 differ"));
    }
}

/* The escape scenario below: ticks, the board's distance to its goal (constant: no
 * progress, so the escape starts to follow a boundary), and what its map did each tick. */
#define ESC_TICKS 70
#define ESC_GOAL_MM 3000u
#define ESC_CLEAR_AT 32  /* the board's plan jumped: memory cleared */
#define ESC_GROW_AT 45   /* its new plan 0.4 m longer: memory grown */
#define ESC_STALE_AT 56  /* a clear reported for another tick's scan: must not count */

/* The scan of tick i, driven to goal 1. */
static uint16_t escape_scan(int i, uint8_t *out, qnav_link_scan_t *s)
{
    (void)scan_payload(i, 16, out, s);
    s->goal_id = 1u;
    return (uint16_t)qnav_link_scan_pack(s, out, QNAV_LINK_MAX_PAYLOAD);
}

/* libqnav's decisions over the scenario, carrying the escape memory as the board does,
 * with the map's clear and growth applied at the ticks given (-1: never). */
static void escape_model(const qnav_policy_t *p, int clear_at, int grow_at, int stale_at,
                         qnav_ctrl_output_t *outs)
{
    qnav_ctrl_config_t cfg;
    qnav_ctrl_t c;
    qnav_ctrl_carry_t carry;
    int i;
    qnav_ctrl_config_default(&cfg);
    cfg.n_sectors = 16;
    cfg.max_range_mm = 5000;
    assert_int_equal(qnav_ctrl_init(&c, &cfg, p), QNAV_OK);
    qnav_ctrl_carry_reset(&carry);
    for (i = 0; i < ESC_TICKS; ++i) {
        uint8_t buf[QNAV_LINK_MAX_PAYLOAD];
        qnav_link_scan_t s;
        qnav_ctrl_input_t in = {0};
        (void)escape_scan(i, buf, &s);
        in.ranges_mm = s.ranges_mm;
        in.goal_bearing_cdeg = s.goal_bearing_cdeg;
        qnav_ctrl_carry_input(&carry, 1u, ESC_GOAL_MM, 0, &in); /* the pose reports heading 0 */
        if (i == clear_at || i == stale_at) {
            memset(&in.escape, 0, sizeof in.escape);
        }
        qnav_escape_grow(&in.escape, i == grow_at ? 400u : 0u);
        qnav_ctrl_step(&c, &in, &outs[i], NULL);
        qnav_ctrl_carry_output(&carry, &outs[i]);
    }
}

/* Whether two decision sequences differ at some tick. */
static int decisions_differ(const qnav_ctrl_output_t *a, const qnav_ctrl_output_t *b)
{
    int i;
    for (i = 0; i < ESC_TICKS; ++i) {
        if (a[i].heading_deg != b[i].heading_deg || a[i].speed != b[i].speed) {
            return 1;
        }
    }
    return 0;
}

/* Issue 18: the board's map clears or grows the escape memory when its plan jumps or
 * grows, and says so in its POSE; navbridge's offboard controller applies that to its own
 * memory, so it decides as an onboard board with the map does, for exactly the tick the
 * POSE belongs to (a report whose board time is not the scan's is not applied). */
static void test_offboard_escape_takes_the_boards_map_verdicts(void **state)
{
    const char *args[] = {"--lcm-url", "memq://", "--policy", g_policy, NULL};
    static qnav_ctrl_output_t want[ESC_TICKS], plain[ESC_TICKS], stale[ESC_TICKS];
    fakeboard_t fb;
    qnav_policy_t policy;
    char perr[QNAV_POLICY_IO_ERRLEN];
    int i;
    (void)state;
    assert_int_equal(qnav_policy_read(g_policy, &policy, perr, sizeof perr), 0);
    escape_model(&policy, ESC_CLEAR_AT, ESC_GROW_AT, -1, want);
    escape_model(&policy, -1, -1, -1, plain);
    escape_model(&policy, ESC_CLEAR_AT, ESC_GROW_AT, ESC_STALE_AT, stale);
    /* the scenario is one where the verdicts change decisions, stale one included */
    assert_true(decisions_differ(want, plain));
    assert_true(decisions_differ(want, stale));

    assert_int_equal(fakeboard_start(&fb, EXE, g_dir, args), 0);
    wait_bridge_up(&fb);
    for (i = 0; i < ESC_TICKS; ++i) {
        uint8_t p[QNAV_LINK_MAX_PAYLOAD];
        qnav_link_pose_t pose;
        qnav_link_scan_t s;
        qnav_link_command_t c;
        uint16_t seq;
        memset(&pose, 0, sizeof pose);
        pose.board_ms = (uint32_t)(i * 100) + (i == ESC_STALE_AT ? 1u : 0u);
        pose.goal_id = 1u;
        pose.goal_distance_mm = ESC_GOAL_MM;
        pose.escape_clear = (uint8_t)(i == ESC_CLEAR_AT || i == ESC_STALE_AT);
        pose.escape_grow_mm = i == ESC_GROW_AT ? 400u : 0u;
        assert_int_equal(qnav_link_pose_pack(&pose, p, sizeof p), (int)QNAV_LINK_POSE_BYTES);
        assert_int_equal(fakeboard_send(&fb, QNAV_LINK_MSG_POSE, p, QNAV_LINK_POSE_BYTES), 0);
        seq = fb.tx.next_seq;
        assert_int_equal(fakeboard_send(&fb, QNAV_LINK_MSG_SCAN, p, escape_scan(i, p, &s)), 0);
        assert_int_equal(wait_command_for(&fb, seq, &c), 0);
        assert_int_equal(c.heading_deg, want[i].heading_deg);
        assert_int_equal(c.speed, want[i].speed);
    }
    kill(fb.pid, SIGTERM);
    assert_int_equal(wait_stop(&fb, QNAV_TEST_WAIT_MS), 0);
    assert_int_equal(fakeboard_signal_and_wait(&fb, 0, QNAV_TEST_WAIT_MS), 0);
    fakeboard_close(&fb);
}

static void test_corrupted_and_replayed_scans_are_not_answered(void **state)
{
    const char *args[] = {"--lcm-url", "memq://", NULL};
    uint8_t p[QNAV_LINK_MAX_PAYLOAD], wire[QNAV_LINK_MAX_WIRE(QNAV_LINK_MAX_PAYLOAD)];
    uint8_t q[64];
    fakeboard_t fb;
    qnav_link_scan_t s;
    qnav_link_command_t c;
    qnav_link_tx_t old;
    uint16_t n, seq;
    int32_t w;
    int got;
    (void)state;
    assert_int_equal(fakeboard_start(&fb, EXE, g_dir, args), 0);
    wait_bridge_up(&fb);
    n = scan_payload(1, 16, p, &s);

    /* a good scan is answered */
    old = fb.tx;
    seq = fb.tx.next_seq;
    assert_int_equal(fakeboard_send(&fb, QNAV_LINK_MSG_SCAN, p, n), 0);
    assert_int_equal(wait_command_for(&fb, seq, &c), 0);

    /* the same frame again (old sequence number): dropped */
    w = qnav_link_encode(&old, QNAV_LINK_MSG_SCAN, p, n, wire, sizeof wire);
    assert_true(w > 0);
    assert_int_equal(write(fb.master, wire, (size_t)w), w);
    /* a corrupted frame with a fresh number: dropped */
    w = qnav_link_encode(&fb.tx, QNAV_LINK_MSG_SCAN, p, n, wire, sizeof wire);
    wire[w / 2] = (uint8_t)(wire[w / 2] == 0x5A ? 0x5B : 0x5A);
    assert_int_equal(write(fb.master, wire, (size_t)w), w);
    /* no command answers either within 150 ms (the watchdog is 300 ms) */
    got = 0;
    {
        int64_t end = fakeboard_ms() + 150;
        while (fakeboard_ms() < end) {
            int m = fakeboard_wait(&fb, QNAV_LINK_MSG_COMMAND, 50, q, sizeof q, NULL);
            if (m > 0 && qnav_link_command_unpack(q, (uint16_t)m, &c) == QNAV_LINK_OK &&
                (c.flags & QNAV_LINK_CMD_STOP) == 0) {
                got++;
            }
        }
    }
    assert_int_equal(got, 0);
    /* and the next good frame is answered again */
    seq = fb.tx.next_seq;
    assert_int_equal(fakeboard_send(&fb, QNAV_LINK_MSG_SCAN, p, n), 0);
    assert_int_equal(wait_command_for(&fb, seq, &c), 0);
    assert_int_equal(fakeboard_signal_and_wait(&fb, SIGINT, QNAV_TEST_WAIT_MS), 0);
    fakeboard_close(&fb);
}

static void test_watchdog_stops_robot_within_its_timeout(void **state)
{
    const char *args[] = {"--lcm-url", "memq://", "--timeout-ms", "300", NULL};
    uint8_t p[QNAV_LINK_MAX_PAYLOAD];
    fakeboard_t fb;
    qnav_link_scan_t s;
    qnav_link_command_t c;
    int64_t t_last, elapsed;
    int i;
    (void)state;
    assert_int_equal(fakeboard_start(&fb, EXE, g_dir, args), 0);
    wait_bridge_up(&fb);
    for (i = 0; i < 5; ++i) {
        uint16_t seq = fb.tx.next_seq;
        uint16_t n = scan_payload(i, 16, p, &s);
        assert_int_equal(fakeboard_send(&fb, QNAV_LINK_MSG_SCAN, p, n), 0);
        assert_int_equal(wait_command_for(&fb, seq, &c), 0);
    }
    t_last = fakeboard_ms();
    /* scans stop: a stop must come after about 300 ms (tolerant bounds: loaded machine) */
    assert_int_equal(wait_stop(&fb, QNAV_TEST_WAIT_MS), 0);
    elapsed = fakeboard_ms() - t_last;
    print_message("watchdog stop after %lld ms (timeout 300 ms)\n", (long long)elapsed);
    assert_true(elapsed >= 250);
    assert_true(elapsed <= 1300);
    assert_int_equal(fakeboard_signal_and_wait(&fb, SIGTERM, QNAV_TEST_WAIT_MS), 0);
    fakeboard_close(&fb);
}

static void test_onboard_watchdog_stops_robot_when_heartbeats_stop(void **state)
{
    const char *args[] = {"--lcm-url", "memq://", "--mode", "onboard", "--timeout-ms", "300",
                          NULL};
    uint8_t p[QNAV_LINK_HEARTBEAT_BYTES];
    fakeboard_t fb;
    qnav_link_heartbeat_t hb = {0, QNAV_LINK_MODE_ONBOARD, QNAV_LINK_STATE_POLICY, 0, 0, 0};
    int64_t t_last, elapsed, end;
    (void)state;
    assert_int_equal(fakeboard_start(&fb, EXE, g_dir, args), 0);
    wait_bridge_up(&fb);
    qnav_link_heartbeat_pack(&hb, p, sizeof p);
    /* heartbeats every 50 ms for 0.6 s: no stop may come meanwhile */
    end = fakeboard_ms() + 600;
    t_last = 0;
    while (fakeboard_ms() < end) {
        assert_int_equal(fakeboard_send(&fb, QNAV_LINK_MSG_HEARTBEAT, p, sizeof p), 0);
        t_last = fakeboard_ms(); /* the watchdog runs from the last heartbeat */
        assert_int_not_equal(wait_stop(&fb, 50), 0);
    }
    assert_int_equal(wait_stop(&fb, QNAV_TEST_WAIT_MS), 0);
    elapsed = fakeboard_ms() - t_last;
    print_message("onboard watchdog stop after %lld ms (timeout 300 ms)\n", (long long)elapsed);
    assert_true(elapsed >= 250);
    assert_true(elapsed <= 1300);
    assert_int_equal(fakeboard_signal_and_wait(&fb, SIGTERM, QNAV_TEST_WAIT_MS), 0);
    fakeboard_close(&fb);
}

/* A terminating signal: a stop reaches the board, then a clean exit naming the signal. */
static void check_signal_stops_robot_before_exit(int sig, const char *said)
{
    const char *args[] = {"--lcm-url", "memq://", "--timeout-ms", "5000", NULL};
    uint8_t p[QNAV_LINK_MAX_PAYLOAD];
    fakeboard_t fb;
    qnav_link_scan_t s;
    qnav_link_command_t c;
    uint16_t seq, n;
    char text[1024];
    assert_int_equal(fakeboard_start(&fb, EXE, g_dir, args), 0);
    wait_bridge_up(&fb);
    seq = fb.tx.next_seq;
    n = scan_payload(3, 8, p, &s);
    assert_int_equal(fakeboard_send(&fb, QNAV_LINK_MSG_SCAN, p, n), 0);
    assert_int_equal(wait_command_for(&fb, seq, &c), 0);
    kill(fb.pid, sig);
    assert_int_equal(wait_stop(&fb, QNAV_TEST_WAIT_MS), 0);
    assert_int_equal(fakeboard_signal_and_wait(&fb, 0, QNAV_TEST_WAIT_MS), 0);
    assert_true(read_text(fb.stderr_path, text, sizeof text) > 0);
    assert_non_null(strstr(text, said));
    fakeboard_close(&fb);
}

static void test_sigint_stops_robot_before_exit(void **state)
{
    (void)state;
    check_signal_stops_robot_before_exit(SIGINT, "SIGINT: robot stopped");
}

static void test_sighup_stops_robot_before_exit(void **state)
{
    (void)state;
    check_signal_stops_robot_before_exit(SIGHUP, "SIGHUP: robot stopped");
}

/* The board's side of an upload in the test below: the first chunk is lost on the line. */
typedef struct {
    qnav_link_upload_t up;
    uint8_t blob[QNAV_LINK_POLICY_MAX_BYTES]; /* the upload buffer at the last commit */
    qnav_policy_t got;                        /* the policy of the last commit */
    int8_t status;                            /* 99 until the first commit */
    int commits;
    int lost;
} board_upload_t;

/* Heartbeats every 50 ms that keep the board in onboard mode. */
static void board_keep_onboard(fakeboard_t *fb, int64_t *next_hb)
{
    qnav_link_heartbeat_t mine = {0, QNAV_LINK_MODE_ONBOARD, QNAV_LINK_STATE_POLICY, 0, 0, 0};
    uint8_t hp[QNAV_LINK_HEARTBEAT_BYTES];
    if (fakeboard_ms() < *next_hb) {
        return;
    }
    qnav_link_heartbeat_pack(&mine, hp, sizeof hp);
    assert_int_equal(fakeboard_send(fb, QNAV_LINK_MSG_HEARTBEAT, hp, sizeof hp), 0);
    *next_hb = fakeboard_ms() + 50;
}

static void board_take_chunk(board_upload_t *b, const uint8_t *p, int n)
{
    qnav_link_policy_chunk_t ch;
    assert_int_equal(qnav_link_policy_chunk_unpack(p, (uint16_t)n, &ch), 0);
    if (b->commits == 0 && !b->lost) {
        b->lost = 1; /* lost on the line */
    } else {
        (void)qnav_link_upload_chunk(&b->up, &ch);
    }
}

/* The first commit must find chunks missing; every commit is acked with its status. */
static void board_take_commit(fakeboard_t *fb, board_upload_t *b, const uint8_t *p, int n)
{
    qnav_link_policy_commit_t cm;
    qnav_link_policy_ack_t ack;
    uint8_t ap[QNAV_LINK_POLICY_ACK_BYTES];
    assert_int_equal(qnav_link_policy_commit_unpack(p, (uint16_t)n, &cm), 0);
    memcpy(b->blob, b->up.blob, sizeof b->blob);
    b->status = qnav_link_upload_commit(&b->up, &cm, &b->got);
    if (b->commits++ == 0) {
        assert_int_equal(b->status, QNAV_LINK_ACK_BAD_LENGTH);
    }
    ack.status = b->status;
    ack.reserved = 0;
    ack.crc = cm.crc;
    qnav_link_policy_ack_pack(&ack, ap, sizeof ap);
    assert_int_equal(fakeboard_send(fb, QNAV_LINK_MSG_POLICY_ACK, ap, sizeof ap), 0);
}

/* Receive chunks and commits until a commit ends in anything but "chunks missing". */
static void board_receive_upload(fakeboard_t *fb, board_upload_t *b)
{
    uint8_t p[QNAV_LINK_MAX_PAYLOAD];
    int64_t next_hb = 0;
    int64_t end = fakeboard_ms() + QNAV_TEST_WAIT_MS; /* a guard only: the loop ends on the ack */
    b->status = 99;
    while (fakeboard_ms() < end && (b->status == 99 || b->status == QNAV_LINK_ACK_BAD_LENGTH)) {
        int n;
        uint16_t seq;
        board_keep_onboard(fb, &next_hb);
        n = fakeboard_wait(fb, 0, 50, p, sizeof p, &seq);
        if (n <= 0) {
            continue;
        }
        if (fb->last_id == QNAV_LINK_MSG_POLICY_CHUNK) {
            board_take_chunk(b, p, n);
        } else if (fb->last_id == QNAV_LINK_MSG_POLICY_COMMIT) {
            board_take_commit(fb, b, p, n);
        }
    }
}

/* The blob navbridge uploads for pol with the default configuration: its weights and,
 * for a 2-input network, its row shapes (so that the board's init copies them). */
static int32_t carried_blob(const qnav_policy_t *pol, uint8_t *out, uint16_t cap)
{
    qnav_ctrl_config_t cfg;
    qnav_ctrl_t ctrl;
    uint8_t shapes[QNAV_SHAPES_BYTES];
    qnav_ctrl_config_default(&cfg);
    assert_int_equal(qnav_ctrl_init(&ctrl, &cfg, pol), QNAV_OK);
    assert_int_equal(qnav_ctrl_shapes_save(&ctrl, pol, shapes), QNAV_OK);
    return qnav_link_policy_to_blob_carried(pol, shapes, out, cap);
}

/* The first upload loses its first chunk on the line: the board answers "chunks missing",
 * and the bridge sends the policy again, which arrives whole. */
static void test_onboard_upload_delivers_the_policy_file_to_the_board(void **state)
{
    const char *args[] = {"--lcm-url", "memq://", "--mode", "onboard", "--policy", g_policy,
                          "--upload", NULL};
    uint8_t p[QNAV_LINK_MAX_PAYLOAD];
    uint8_t want[QNAV_LINK_POLICY_MAX_BYTES];
    fakeboard_t fb;
    qnav_link_heartbeat_t hb;
    board_upload_t board;
    qnav_policy_t file_policy;
    char perr[QNAV_POLICY_IO_ERRLEN], text[2048];
    int32_t nwant;
    (void)state;
    memset(&board, 0, sizeof board);
    assert_int_equal(qnav_policy_read(g_policy, &file_policy, perr, sizeof perr), 0);
    nwant = carried_blob(&file_policy, want, (uint16_t)sizeof want);
    assert_true(nwant > 0);
    qnav_link_upload_init(&board.up);
    assert_int_equal(fakeboard_start(&fb, EXE, g_dir, args), 0);
    /* the bridge asks for onboard mode in its heartbeats */
    assert_true(fakeboard_wait(&fb, QNAV_LINK_MSG_HEARTBEAT, 3000, p, sizeof p, NULL) > 0);
    assert_int_equal(qnav_link_heartbeat_unpack(p, QNAV_LINK_HEARTBEAT_BYTES, &hb), 0);
    assert_int_equal(hb.mode, QNAV_LINK_MODE_ONBOARD);

    board_receive_upload(&fb, &board);
    assert_int_equal(board.status, QNAV_LINK_ACK_OK);
    assert_int_equal(board.commits, 2);
    assert_memory_equal(board.blob, want, (size_t)nwant);
    assert_int_equal(board.got.kind, QNAV_POLICY_NET);
    assert_int_equal(board.got.u.net.hidden, file_policy.u.net.hidden);
    assert_memory_equal(board.got.u.net.w_theta, file_policy.u.net.w_theta,
                        sizeof board.got.u.net.w_theta);
    /* the bridge has read the ack when it says so */
    assert_int_equal(qnav_test_wait_text(fb.stderr_path, "policy upload: ok", QNAV_TEST_WAIT_MS), 0);
    assert_int_equal(fakeboard_signal_and_wait(&fb, SIGTERM, QNAV_TEST_WAIT_MS), 0);
    assert_true(read_text(fb.stderr_path, text, sizeof text) > 0);
    assert_non_null(strstr(text, "policy upload: ok"));
    assert_non_null(strstr(text, "the board got it damaged (chunks missing); sending it again "
                                 "(try 2 of 3)"));
    fakeboard_close(&fb);
}

static void test_start_goal_is_relayed_to_the_board(void **state)
{
    const char *args[] = {"--lcm-url", "memq://", "--goal", "-30.5:4", NULL};
    uint8_t p[64];
    fakeboard_t fb;
    qnav_link_goal_t g;
    int n;
    (void)state;
    assert_int_equal(fakeboard_start(&fb, EXE, g_dir, args), 0);
    n = fakeboard_wait(&fb, QNAV_LINK_MSG_GOAL, 3000, p, sizeof p, NULL);
    assert_int_equal(n, QNAV_LINK_GOAL_BYTES);
    assert_int_equal(qnav_link_goal_unpack(p, (uint16_t)n, &g), 0);
    assert_int_equal(g.goal_id, 1);
    assert_int_equal(g.bearing_cdeg, -3050);
    assert_int_equal(g.distance_mm, 4000);
    assert_int_equal(fakeboard_signal_and_wait(&fb, SIGTERM, QNAV_TEST_WAIT_MS), 0);
    fakeboard_close(&fb);
}

/* Run navbridge with args; expect exit 2 and one stderr line containing needle. */
static void expect_refusal(const char *const *argv, const char *needle)
{
    char out[320], err[320], text[1024];
    char *nl;
    snprintf(out, sizeof out, "%s/refuse.out", g_dir);
    snprintf(err, sizeof err, "%s/refuse.err", g_dir);
    assert_int_equal(run_program(argv, out, err), 2);
    assert_true(read_text(err, text, sizeof text) > 0);
    assert_non_null(strstr(text, needle));
    nl = strchr(text, '\n');
    assert_non_null(nl);
    assert_int_equal(nl[1], '\0'); /* exactly one line */
}

/* A board speaking link protocol `version` (1: its 12-byte heartbeat without the
 * version byte) makes navbridge exit with status 1 and one line naming both versions. */
static void check_refuses_board_of_protocol(uint8_t version)
{
    const char *args[] = {"--lcm-url", "memq://", "--mode", "onboard", NULL};
    qnav_link_heartbeat_t hb = {0, QNAV_LINK_MODE_ONBOARD, QNAV_LINK_STATE_POLICY, 0, 0, 0};
    uint8_t p[QNAV_LINK_HEARTBEAT_BYTES];
    char text[2048], want[160];
    const char *line;
    fakeboard_t fb;
    int32_t n;
    assert_int_equal(fakeboard_start(&fb, EXE, g_dir, args), 0);
    wait_bridge_up(&fb);
    n = qnav_link_heartbeat_pack(&hb, p, sizeof p);
    assert_int_equal(n, QNAV_LINK_HEARTBEAT_BYTES);
    if (version == 1u) {
        n = QNAV_LINK_HEARTBEAT_V1_BYTES;
    } else {
        p[12] = version;
    }
    assert_int_equal(fakeboard_send(&fb, QNAV_LINK_MSG_HEARTBEAT, p, (uint16_t)n), 0);
    assert_int_equal(fakeboard_signal_and_wait(&fb, 0, QNAV_TEST_WAIT_MS), 1);
    assert_true(read_text(fb.stderr_path, text, sizeof text) > 0);
    snprintf(want, sizeof want, "the board speaks link protocol %u, this navbridge speaks %u",
             (unsigned)version, (unsigned)QNAV_LINK_PROTOCOL_VERSION);
    line = strstr(text, want);
    assert_non_null(line);
    assert_null(strchr(line, '\n') == NULL ? NULL : strstr(strchr(line, '\n') + 1, "protocol"));
    fakeboard_close(&fb);
}

static void test_board_of_protocol_1_is_refused_with_one_line(void **state)
{
    (void)state;
    check_refuses_board_of_protocol(1);
}

static void test_board_of_a_newer_protocol_is_refused_with_one_line(void **state)
{
    (void)state;
    check_refuses_board_of_protocol(QNAV_LINK_PROTOCOL_VERSION + 1u);
}

static void test_bad_options_and_files_fail_with_one_line(void **state)
{
    char bad_policy[320];
    FILE *f;
    const char *baud[] = {EXE, "--device", "/dev/null", "--baud", "12345", NULL};
    const char *dev[] = {EXE, "--device", "/nonexistent/ttyX", NULL};
    const char *notty[] = {EXE, "--device", "/dev/null", NULL};
    const char *mode[] = {EXE, "--device", "/dev/null", "--mode", "sideways", NULL};
    const char *tmo[] = {EXE, "--device", "/dev/null", "--timeout-ms", "abc", NULL};
    const char *pol[] = {EXE, "--device", "/dev/null", "--policy", bad_policy, NULL};
    const char *unknown[] = {EXE, "--frobnicate", NULL};
    const char *goal[] = {EXE, "--device", "/dev/null", "--goal", "200", NULL};
    const char *route[] = {EXE, "--device", "/dev/null", "--waypoints", "1:2,3", NULL};
    const char *at[] = {EXE, "--device", "/dev/null", "--goal-at", "1:2,3:4", NULL};
    const char *radius[] = {EXE, "--device", "/dev/null", "--goal-radius", "0", NULL};
    /* two goals at once: refused, not the last one silently followed */
    const char *both[] = {EXE, "--device", "/dev/null", "--goal", "30", "--waypoints", "1:2",
                          NULL};
    const char *goal_at[] = {EXE, "--device", "/dev/null", "--goal-at", "1:2", "--goal", "30",
                             NULL};
    const char *twice[] = {EXE, "--device", "/dev/null", "--goal-at", "1:2", "--goal-at",
                           "3:4", NULL};
    (void)state;
    snprintf(bad_policy, sizeof bad_policy, "%s/bad.policy", g_dir);
    f = fopen(bad_policy, "w");
    assert_non_null(f);
    fputs("qnav-policy 1\nkind banana\n", f);
    fclose(f);
    expect_refusal(baud, "--baud 12345");
    expect_refusal(dev, "/nonexistent/ttyX: No such file or directory");
    expect_refusal(notty, "/dev/null: not a serial port");
    expect_refusal(mode, "--mode sideways");
    expect_refusal(tmo, "--timeout-ms abc");
    expect_refusal(pol, "bad.policy:");
    expect_refusal(unknown, "--frobnicate");
    expect_refusal(goal, "--goal 200");
    expect_refusal(route, "--waypoints 1:2,3");
    expect_refusal(at, "--goal-at 1:2,3:4");
    expect_refusal(radius, "--goal-radius 0");
    expect_refusal(both, "--goal, --goal-at, --waypoints: give one of them, once");
    expect_refusal(goal_at, "--goal, --goal-at, --waypoints: give one of them, once");
    expect_refusal(twice, "--goal, --goal-at, --waypoints: give one of them, once");
}

/* Short unknown options are named as such (it used to say "--?: missing its value"), a
 * long one without its value says so, a file that is not an LCM log is bad input (2), and
 * --version prints the version line. */
static void test_command_line_conventions(void **state)
{
    char notlog[320], out[320], err[320], text[256];
    const char *short_unknown[] = {EXE, "-V", NULL};
    const char *no_value[] = {EXE, "--device", NULL};
    const char *replay[] = {EXE, "--replay", notlog, NULL};
    const char *version[] = {EXE, "--version", NULL};
    (void)state;
    snprintf(notlog, sizeof notlog, "%s/notes.txt", g_dir);
    assert_int_equal(qnav_test_write_text(notlog, "not a log\n"), 0);
    expect_refusal(short_unknown, "navbridge: -V: unknown option (see --help)");
    expect_refusal(no_value, "navbridge: --device: missing its value (see --help)");
    expect_refusal(replay, "notes.txt: not an LCM log");
    snprintf(out, sizeof out, "%s/version.out", g_dir);
    snprintf(err, sizeof err, "%s/version.err", g_dir);
    assert_int_equal(run_program(version, out, err), 0);
    assert_true(read_text(out, text, sizeof text) > 0);
    assert_string_equal(text, "navbridge (qnav) " QNAV_VERSION "\n");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_offboard_commands_equal_libqnav_and_replay_identically),
        cmocka_unit_test(test_offboard_escape_takes_the_boards_map_verdicts),
        cmocka_unit_test(test_corrupted_and_replayed_scans_are_not_answered),
        cmocka_unit_test(test_watchdog_stops_robot_within_its_timeout),
        cmocka_unit_test(test_onboard_watchdog_stops_robot_when_heartbeats_stop),
        cmocka_unit_test(test_sigint_stops_robot_before_exit),
        cmocka_unit_test(test_sighup_stops_robot_before_exit),
        cmocka_unit_test(test_onboard_upload_delivers_the_policy_file_to_the_board),
        cmocka_unit_test(test_start_goal_is_relayed_to_the_board),
        cmocka_unit_test(test_board_of_protocol_1_is_refused_with_one_line),
        cmocka_unit_test(test_board_of_a_newer_protocol_is_refused_with_one_line),
        cmocka_unit_test(test_bad_options_and_files_fail_with_one_line),
        cmocka_unit_test(test_command_line_conventions),
    };
    return cmocka_run_group_tests(tests, setup_dir, teardown_dir);
}
