/*
 * The TekBot firmware image (built with avr-gcc for the ATmega128) running under simavr
 * against the navbridge program: navbridge uploads a network policy over the link, the
 * board runs libqnav on the simulated MCU and reports its decisions, and replaying the
 * recorded trial through the host's controller gives the same commands bit for bit.
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

#include "fakeboard.h"
#include "test_proc.h"
#include "qnav/policy_io.h"

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

static void test_firmware_in_simavr_runs_uploaded_network_bit_identical_to_host(void **state)
{
    char policy[300], link[300], log[300], sa_out[300], sa_err[300], nb_out[300], nb_err[300];
    char rp_out[300], rp_err[300], text[4096], perr[QNAV_POLICY_IO_ERRLEN];
    const char *board[] = {SIMAVR_BOARD_EXE, "--elf", TEKBOT_ELF, "--link", link,
                           "--seconds", "4", NULL};
    const char *bridge[] = {NAVBRIDGE_EXE, "--device", link, "--lcm-url", "memq://",
                            "--mode", "onboard", "--policy", policy, "--upload", "--goal",
                            "20", "--log", log, NULL};
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
    assert_int_equal(qnav_test_wait_path(link, 4000), 0);
    pn = qnav_test_spawn(bridge, nb_out, nb_err);
    assert_true(pn > 0);
    assert_int_equal(qnav_test_wait_exit(pb), 0);
    assert_int_equal(wait_exit_within(pn, 3000), 3); /* simavr's pty closed: link lost */
    assert_true(read_text(sa_out, text, sizeof text) > 0);
    assert_non_null(strstr(text, "stopped after 4.00 simulated s (done)"));
    assert_true(read_text(nb_err, text, sizeof text) > 0);
    print_message("%s", text);
    assert_non_null(strstr(text, "policy upload: ok"));

    i = run_program(replay, rp_out, rp_err);
    assert_true(read_text(rp_out, text, sizeof text) > 0);
    print_message("%s", text);
    assert_int_equal(i, 0);
    assert_non_null(strstr(text, "identical, 0 differ"));
    assert_non_null(strstr(text, "replay: "));
    assert_int_equal(sscanf(strstr(text, "replay: "), "replay: %u scans, %u commands compared",
                            &scans, &compared), 2);
    /* 4 s at 10 Hz: most ticks after the upload carry a network decision */
    assert_true(scans >= 30u);
    assert_true(compared >= 20u);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_firmware_in_simavr_runs_uploaded_network_bit_identical_to_host),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
