/*
 * The board firmware images (built with avr-gcc for the ATmega128, one per robot from its
 * generated configuration) running under simavr against the navbridge program: navbridge
 * uploads a network policy over the link, the board runs libqnav on the simulated MCU and
 * reports its decisions, and the recorded scan stream driven through the simulator's
 * controller (configured from the robot's profile by qnav_sim_ctrl_config) and through
 * navbridge --replay --robot gives the same commands bit for bit, for the TekBot and the
 * Pioneer 3-DX. A board of another robot is refused, by navbridge and by the simavr
 * runner, with one line naming the field. The tests wait on events (the board's pty, the
 * upload's acknowledgement, commands in the log), never on a wall-clock budget, so a
 * loaded machine only makes it slower.
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
#include <sys/wait.h>
#include <unistd.h>

#include <cmocka.h>
#include <lcm/eventlog.h>

#include "fakeboard.h"
#include "test_proc.h"
#include "qnav/policy_io.h"
#include "qnav/sim.h"
#include "qnav_command_t.h"
#include "qnav_nav_input_t.h"
#include "qnav_scan_t.h"

static char g_dir[256];

static int setup(void **state)
{
    (void)state;
    return qnav_test_tmpdir_make(g_dir, sizeof g_dir, "qnav_simavr_test");
}

static int teardown(void **state)
{
    (void)state;
    return qnav_test_tmpdir_remove(g_dir);
}

/* Decisions in the LCM log at path so far: commands that are not stops (what --replay
 * compares); 0 while the log does not exist yet. */
static int count_decisions(const char *path)
{
    lcm_eventlog_t *log = lcm_eventlog_create(path, "r");
    lcm_eventlog_event_t *ev;
    int n = 0;
    if (log == NULL) {
        return 0;
    }
    while ((ev = lcm_eventlog_read_next_event(log)) != NULL) {
        qnav_command_t c;
        if (strcmp(ev->channel, "QNAV_COMMAND") == 0 &&
            qnav_command_t_decode(ev->data, 0, ev->datalen, &c) >= 0) {
            n += c.stop_reason == 0 && c.scan_seq >= 0; /* QNAV_STOP_NONE */
        }
        lcm_eventlog_free_event(ev);
    }
    lcm_eventlog_destroy(log);
    return n;
}

/* Wait (up to a limit far above any normal run) until the log holds at least n
 * decisions. 0, or -1. */
static int wait_decisions(const char *path, int n)
{
    int waited;
    for (waited = 0; count_decisions(path) < n; waited += 50) {
        if (waited > QNAV_TEST_WAIT_MS) {
            return -1;
        }
        usleep(50000);
    }
    return 0;
}

/* The logged scan stream through the simulator's own controller for robot (a context of
 * that profile: qnav_sim_ctrl_config), compared with the board's logged decisions, scan
 * by scan. Returns the number of decisions compared; fails on any difference. */
static unsigned compare_with_simulator(const char *log_path, const char *robot,
                                       const qnav_policy_t *p)
{
    char err[QNAV_SIM_ERRLEN];
    qnav_sim_robot_t *rb = NULL;
    qnav_sim_env_t *env = NULL;
    qnav_sim_t *sim = NULL;
    qnav_sim_config_t sc;
    qnav_ctrl_config_t cc;
    static qnav_ctrl_t ctrl;
    static qnav_scan_t scans[64];
    static int32_t seqs[64];
    static qnav_cdeg_t prevs[64]; /* each scan's previous heading, as the board read it */
    qnav_nav_input_t rec;
    unsigned next = 0, compared = 0;
    lcm_eventlog_t *log;
    lcm_eventlog_event_t *ev;
    assert_int_equal(qnav_sim_robot_load(robot, &rb, err, sizeof err), QNAV_SIM_OK);
    assert_int_equal(qnav_sim_env_load("open", &env, err, sizeof err), QNAV_SIM_OK);
    qnav_sim_config_default(&sc);
    assert_int_equal(qnav_sim_create(rb, env, &sc, &sim, err, sizeof err), QNAV_SIM_OK);
    qnav_sim_ctrl_config(sim, &cc);
    assert_int_equal(qnav_ctrl_init(&ctrl, &cc, p), QNAV_OK);
    memset(seqs, 0xFF, sizeof seqs);
    memset(&rec, 0, sizeof rec);
    rec.scan_seq = -1;
    log = lcm_eventlog_create(log_path, "r");
    assert_non_null(log);
    while ((ev = lcm_eventlog_read_next_event(log)) != NULL) {
        if (strcmp(ev->channel, "QNAV_NAV_INPUT") == 0) {
            /* published just before its scan */
            assert_true(qnav_nav_input_t_decode(ev->data, 0, ev->datalen, &rec) >= 0);
        } else if (strcmp(ev->channel, "QNAV_SCAN") == 0) {
            assert_true(qnav_scan_t_decode(ev->data, 0, ev->datalen, &scans[next]) >= 0);
            assert_int_equal(rec.scan_seq, scans[next].seq);
            prevs[next] = (qnav_cdeg_t)rec.prev_heading_cdeg;
            /* the board scans with the profile's sonar */
            assert_int_equal(scans[next].n_sectors, cc.n_sectors);
            assert_int_equal(scans[next].max_range_mm, cc.max_range_mm);
            seqs[next] = scans[next].seq;
            next = (next + 1u) % 64u;
        } else if (strcmp(ev->channel, "QNAV_COMMAND") == 0) {
            qnav_command_t c;
            unsigned k;
            assert_true(qnav_command_t_decode(ev->data, 0, ev->datalen, &c) >= 0);
            for (k = 0; k < 64u && c.stop_reason == 0 && c.scan_seq >= 0 &&
                        (uint16_t)c.policy_crc == qnav_link_policy_crc(p); ++k) {
                qnav_mm_t ranges[QNAV_MAX_SECTORS];
                qnav_ctrl_input_t in = {0};
                qnav_ctrl_output_t out;
                int i;
                if (seqs[k] != c.scan_seq) {
                    continue;
                }
                for (i = 0; i < scans[k].n_sectors; ++i) {
                    ranges[i] = (qnav_mm_t)scans[k].ranges_mm[i];
                }
                in.ranges_mm = ranges;
                in.goal_bearing_cdeg = scans[k].goal_bearing_cdeg;
                in.prev_heading_cdeg = prevs[k];
                qnav_ctrl_step(&ctrl, &in, &out, NULL);
                assert_int_equal(out.heading_deg, c.heading_deg);
                assert_int_equal(out.speed, c.speed_q15);
                assert_int_equal(out.quality, c.quality_q15);
                assert_int_equal(out.flags, c.flags);
                compared++;
                break;
            }
        }
        lcm_eventlog_free_event(ev);
    }
    lcm_eventlog_destroy(log);
    qnav_sim_destroy(sim);
    qnav_sim_env_free(env);
    qnav_sim_robot_free(rb);
    return compared;
}

/* One robot's trial: its image under simavr, navbridge --robot uploading a network, 30
 * decisions; then the simulator's controller and navbridge --replay on the log. */
static void run_robot_trial(const char *elf, const char *robot)
{
    char policy[300], link[300], log[300], sa_out[300], sa_err[300], nb_out[300], nb_err[300];
    char rp_out[300], rp_err[300], text[4096], perr[QNAV_POLICY_IO_ERRLEN];
    const char *board[] = {SIMAVR_BOARD_EXE, "--elf", elf, "--robot", robot, "--link", link,
                           NULL};
    const char *bridge[] = {NAVBRIDGE_EXE, "--device", link, "--lcm-url", "memq://",
                            "--mode", "onboard", "--policy", policy, "--upload", "--goal",
                            "20", "--log", log, "--timeout-ms", "3000", "--robot", robot,
                            NULL};
    const char *replay[] = {NAVBRIDGE_EXE, "--replay", log, "--policy", policy, "--robot",
                            robot, NULL};
    qnav_policy_t p;
    unsigned scans = 0, compared = 0;
    uint16_t k;
    pid_t pb, pn;
    int i;
    snprintf(policy, sizeof policy, "%s/net-%s.policy", g_dir, robot);
    snprintf(link, sizeof link, "%s/link-%s", g_dir, robot);
    snprintf(log, sizeof log, "%s/trial-%s.lcmlog", g_dir, robot);
    snprintf(sa_out, sizeof sa_out, "%s/sa-%s.out", g_dir, robot);
    snprintf(sa_err, sizeof sa_err, "%s/sa-%s.err", g_dir, robot);
    snprintf(nb_out, sizeof nb_out, "%s/nb-%s.out", g_dir, robot);
    snprintf(nb_err, sizeof nb_err, "%s/nb-%s.err", g_dir, robot);
    snprintf(rp_out, sizeof rp_out, "%s/rp-%s.out", g_dir, robot);
    snprintf(rp_err, sizeof rp_err, "%s/rp-%s.err", g_dir, robot);
    qnav_policy_net_zero(&p, 12);
    for (k = 0; k < QNAV_NET_WEIGHTS(12); ++k) {
        *qnav_net_weight(&p.u.net, k) = (qnav_q8_8_t)((int)((k * 613u) % 1536u) - 768);
    }
    assert_int_equal(qnav_policy_write(policy, &p, "simavr test", perr, sizeof perr), 0);
    pb = qnav_test_spawn(board, sa_out, sa_err);
    assert_true(pb > 0);
    assert_int_equal(qnav_test_wait_text(sa_out, "with USART0 on", QNAV_TEST_WAIT_MS), 0);
    pn = qnav_test_spawn(bridge, nb_out, nb_err);
    assert_true(pn > 0);
    if (qnav_test_wait_text(nb_err, "policy upload: ok", QNAV_TEST_WAIT_MS) != 0) {
        if (read_text(nb_err, text, sizeof text) > 0) {
            print_message("navbridge said:\n%s", text);
        }
        kill(pb, SIGTERM);
        kill(pn, SIGTERM);
        fail_msg("no upload acknowledgement within 40 s");
    }
    /* 30 decisions of the uploaded network, then stop the board */
    i = count_decisions(log);
    assert_int_equal(wait_decisions(log, i + 30), 0);
    assert_int_equal(kill(pb, SIGTERM), 0);
    assert_int_equal(qnav_test_wait_exit(pb), 0);
    assert_int_equal(wait_exit_within(pn, QNAV_TEST_WAIT_MS), 1); /* simavr's pty closed: link lost */
    assert_true(read_text(sa_out, text, sizeof text) > 0);
    assert_non_null(strstr(text, "simulated s (signal)"));
    assert_true(read_text(nb_err, text, sizeof text) > 0);
    print_message("%s", text);

    i = run_program(replay, rp_out, rp_err);
    assert_true(read_text(rp_out, text, sizeof text) > 0);
    print_message("%s", text);
    assert_int_equal(i, 0);
    assert_non_null(strstr(text, "identical, 0 differ"));
    assert_non_null(strstr(text, "replay: "));
    assert_int_equal(sscanf(strstr(text, "replay: "), "replay: %u scans, %u commands compared",
                            &scans, &compared), 2);
    /* every decision after the upload is compared: at least the 30 waited for (a loaded
     * machine may slow simavr below real time; navbridge's watchdog is 3 s so that it
     * does not stop the board for that, and stops are not decisions anyway) */
    assert_true(scans >= 30u);
    assert_true(compared >= 30u);

    /* the simulator's controller of the same profile gives the same decisions */
    compared = compare_with_simulator(log, robot, &p);
    print_message("%s: %u board decisions equal to the simulator's controller\n", robot,
                  compared);
    assert_true(compared >= 30u);
}

static void test_tekbot_image_in_simavr_decides_as_the_simulators_controller(void **state)
{
    (void)state;
    run_robot_trial(TEKBOT_ELF, "tekbot");
}

static void test_pioneer3dx_image_in_simavr_decides_as_the_simulators_controller(void **state)
{
    (void)state;
    run_robot_trial(PIONEER3DX_ELF, "pioneer3dx");
}

/* A board built for another robot: navbridge --robot stops at its first CONFIG report with
 * one line naming the field, status 1. Returns navbridge's stderr in text. */
static void bridge_against_board(const char *elf, const char *board_robot,
                                 const char *bridge_robot, const char *tag, char *text, int cap)
{
    char link[300], sa_out[300], sa_err[300], nb_out[300], nb_err[300];
    const char *board[] = {SIMAVR_BOARD_EXE, "--elf", elf, "--robot", board_robot, "--link",
                           link, NULL};
    const char *bridge[] = {NAVBRIDGE_EXE, "--device", link, "--lcm-url", "memq://",
                            "--goal", "20", "--robot", bridge_robot, NULL};
    pid_t pb, pn;
    snprintf(link, sizeof link, "%s/link-refuse-%s", g_dir, tag);
    snprintf(sa_out, sizeof sa_out, "%s/sa-refuse-%s.out", g_dir, tag);
    snprintf(sa_err, sizeof sa_err, "%s/sa-refuse-%s.err", g_dir, tag);
    snprintf(nb_out, sizeof nb_out, "%s/nb-refuse-%s.out", g_dir, tag);
    snprintf(nb_err, sizeof nb_err, "%s/nb-refuse-%s.err", g_dir, tag);
    pb = qnav_test_spawn(board, sa_out, sa_err);
    assert_true(pb > 0);
    assert_int_equal(qnav_test_wait_text(sa_out, "with USART0 on", 20000), 0);
    pn = qnav_test_spawn(bridge, nb_out, nb_err);
    assert_true(pn > 0);
    assert_int_equal(wait_exit_within(pn, 60000), 1);
    assert_int_equal(kill(pb, SIGTERM), 0);
    assert_int_equal(qnav_test_wait_exit(pb), 0);
    assert_true(read_text(nb_err, text, cap) > 0);
    print_message("%s", text);
}

static void test_navbridge_refuses_a_board_of_another_robot_naming_the_field(void **state)
{
    char text[4096], profile[300], toml[8192];
    char *at;
    int n;
    (void)state;
    bridge_against_board(TEKBOT_ELF, "tekbot", "pioneer3dx", "p3dx", text, sizeof text);
    assert_non_null(strstr(text, "navbridge: board configuration differs from robot "
                                 "'pioneer3dx': max_range_mm 2500 != 5000\n"));

    /* the TekBot's profile with another sonar range only: that field is named */
    n = read_text(TEKBOT_PROFILE, toml, sizeof toml);
    assert_true(n > 0);
    at = strstr(toml, "range_max_m = 2.5");
    assert_non_null(at);
    memcpy(at, "range_max_m = 5.0", 17);
    snprintf(profile, sizeof profile, "%s/tekbot-5m.toml", g_dir);
    assert_int_equal(qnav_test_write_text(profile, toml), 0);
    bridge_against_board(TEKBOT_ELF, "tekbot", profile, "5m", text, sizeof text);
    at = strstr(text, "navbridge: board configuration differs from robot '");
    assert_non_null(at);
    assert_non_null(strstr(at, "tekbot-5m.toml': max_range_mm 2500 != 5000\n"));
    assert_null(strchr(strchr(at, '\n') + 1, '\n')); /* one line */
}

/* The simavr runner refuses an image built for another robot than --robot. */
static void test_simavr_board_refuses_an_image_of_another_robot(void **state)
{
    char out[300], err[300], text[2048];
    const char *board[] = {SIMAVR_BOARD_EXE, "--elf", PIONEER3DX_ELF, "--robot", "tekbot",
                           "--seconds", "30", NULL};
    (void)state;
    snprintf(out, sizeof out, "%s/wrong.out", g_dir);
    snprintf(err, sizeof err, "%s/wrong.err", g_dir);
    assert_int_equal(run_program(board, out, err), 1);
    assert_true(read_text(err, text, sizeof text) > 0);
    assert_string_equal(text, "qnav-simavr-board: board configuration differs from robot "
                              "'tekbot': max_range_mm 5000 != 2500\n");
    assert_true(read_text(out, text, sizeof text) > 0);
    assert_non_null(strstr(text, "(refused)"));
}



/* --link onto a user's file: refused with status 2 and the file untouched (the board used
 * to delete it, and simavr's own uart_pty_connect() deleted /tmp/simavr-uart0). */
static void test_simavr_board_refuses_link_path_that_is_a_file(void **state)
{
    char path[300];
    const char *board[] = {SIMAVR_BOARD_EXE, "--elf", TEKBOT_ELF, "--link", path,
                           "--seconds", "0.1", NULL};
    (void)state;
    snprintf(path, sizeof path, "%s/notes.txt", g_dir);
    assert_int_equal(qnav_test_link_refused(board, path, g_dir), 0);
}

/* Two boards at once: each on its own pty, neither touching the other's link. */
static void test_two_simavr_boards_get_their_own_ptys(void **state)
{
    char l1[300], l2[300], o1[300], o2[300], e1[300], e2[300], t1[256], t2[256];
    const char *b1[] = {SIMAVR_BOARD_EXE, "--elf", TEKBOT_ELF, "--link", l1, NULL};
    const char *b2[] = {SIMAVR_BOARD_EXE, "--elf", TEKBOT_ELF, "--link", l2, NULL};
    ssize_t n1, n2;
    pid_t p1, p2;
    (void)state;
    snprintf(l1, sizeof l1, "%s/link1", g_dir);
    snprintf(l2, sizeof l2, "%s/link2", g_dir);
    snprintf(o1, sizeof o1, "%s/b1.out", g_dir);
    snprintf(o2, sizeof o2, "%s/b2.out", g_dir);
    snprintf(e1, sizeof e1, "%s/b1.err", g_dir);
    snprintf(e2, sizeof e2, "%s/b2.err", g_dir);
    p1 = qnav_test_spawn(b1, o1, e1);
    assert_true(p1 > 0);
    assert_int_equal(qnav_test_wait_text(o1, "with USART0 on", QNAV_TEST_WAIT_MS), 0);
    p2 = qnav_test_spawn(b2, o2, e2);
    assert_true(p2 > 0);
    assert_int_equal(qnav_test_wait_text(o2, "with USART0 on", QNAV_TEST_WAIT_MS), 0);
    n1 = readlink(l1, t1, sizeof t1 - 1);
    n2 = readlink(l2, t2, sizeof t2 - 1);
    assert_true(n1 > 0 && n2 > 0);
    t1[n1] = '\0';
    t2[n2] = '\0';
    assert_string_not_equal(t1, t2);
    assert_int_equal(kill(p1, SIGTERM), 0);
    assert_int_equal(qnav_test_wait_exit(p1), 0);
    assert_int_equal(access(l1, F_OK), -1);
    n2 = readlink(l2, t1, sizeof t1 - 1); /* the second board's link outlives the first */
    assert_true(n2 > 0);
    t1[n2] = '\0';
    assert_string_equal(t1, t2);
    assert_int_equal(kill(p2, SIGTERM), 0);
    assert_int_equal(qnav_test_wait_exit(p2), 0);
    assert_int_equal(access(l2, F_OK), -1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_tekbot_image_in_simavr_decides_as_the_simulators_controller),
        cmocka_unit_test(test_pioneer3dx_image_in_simavr_decides_as_the_simulators_controller),
        cmocka_unit_test(test_navbridge_refuses_a_board_of_another_robot_naming_the_field),
        cmocka_unit_test(test_simavr_board_refuses_an_image_of_another_robot),
        cmocka_unit_test(test_simavr_board_refuses_link_path_that_is_a_file),
        cmocka_unit_test(test_two_simavr_boards_get_their_own_ptys),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
