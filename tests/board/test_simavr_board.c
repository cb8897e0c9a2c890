/*
 * The TekBot firmware image (built with avr-gcc for the ATmega128) running under simavr
 * against the navbridge program: navbridge uploads a network policy over the link, the
 * board runs libqnav on the simulated MCU and reports its decisions, and replaying the
 * recorded trial through the host's controller gives the same commands bit for bit. The
 * test waits on events (the board's pty, the upload's acknowledgement, commands in the
 * log), never on a wall-clock budget, so a loaded machine only makes it slower.
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
#include "qnav_command_t.h"

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

static void test_firmware_in_simavr_runs_uploaded_network_bit_identical_to_host(void **state)
{
    char policy[300], link[300], log[300], sa_out[300], sa_err[300], nb_out[300], nb_err[300];
    char rp_out[300], rp_err[300], text[4096], perr[QNAV_POLICY_IO_ERRLEN];
    const char *board[] = {SIMAVR_BOARD_EXE, "--elf", TEKBOT_ELF, "--link", link, NULL};
    const char *bridge[] = {NAVBRIDGE_EXE, "--device", link, "--lcm-url", "memq://",
                            "--mode", "onboard", "--policy", policy, "--upload", "--goal",
                            "20", "--log", log, "--timeout-ms", "3000", NULL};
    const char *replay[] = {NAVBRIDGE_EXE, "--replay", log, "--policy", policy, NULL};
    qnav_policy_t p;
    unsigned scans = 0, compared = 0;
    uint16_t k;
    pid_t pb, pn;
    int i;
    (void)state;
    snprintf(policy, sizeof policy, "%s/net.policy", g_dir);
    snprintf(link, sizeof link, "%s/link", g_dir);
    snprintf(log, sizeof log, "%s/trial.lcmlog", g_dir);
    snprintf(sa_out, sizeof sa_out, "%s/sa.out", g_dir);
    snprintf(sa_err, sizeof sa_err, "%s/sa.err", g_dir);
    snprintf(nb_out, sizeof nb_out, "%s/nb.out", g_dir);
    snprintf(nb_err, sizeof nb_err, "%s/nb.err", g_dir);
    snprintf(rp_out, sizeof rp_out, "%s/rp.out", g_dir);
    snprintf(rp_err, sizeof rp_err, "%s/rp.err", g_dir);
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
        cmocka_unit_test(test_firmware_in_simavr_runs_uploaded_network_bit_identical_to_host),
        cmocka_unit_test(test_simavr_board_refuses_link_path_that_is_a_file),
        cmocka_unit_test(test_two_simavr_boards_get_their_own_ptys),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
