/*
 * The one board core, on the simulated ATmega128 and on the host. Under simavr (the real
 * TekBot image, qnav-simavr-board --eeprom): a committed upload survives a reset (a power
 * cycle of the MCU with its EEPROM kept), a corrupted store falls back to the built-in
 * policy, and a power cut in the middle of writing a new policy keeps the one before it;
 * navbridge reports from the board's heartbeat which policy runs. And the scan stream the
 * AVR image recorded, played into the SIL robot (the same core compiled for the host),
 * gives the same command stream, also after the AVR compiled the uploaded network into its
 * flash and stepped in table mode.
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
#include <lcm/eventlog.h>

#include "fakeboard.h"
#include "qnav/link.h"
#include "qnav/policy_io.h"
#include "qnav_command_t.h"
#include "qnav_scan_t.h"
#include "test_proc.h"

static char g_dir[256];
static char g_p1[300], g_p2[300];   /* two network policies */
static uint16_t g_crc1, g_crc2, g_builtin_crc;

static uint16_t write_net(const char *path, uint16_t mult)
{
    qnav_policy_t p;
    char perr[QNAV_POLICY_IO_ERRLEN];
    uint16_t k;
    qnav_policy_net_zero(&p, 12);
    for (k = 0; k < QNAV_NET_WEIGHTS(12); ++k) {
        *qnav_net_weight(&p.u.net, k) = (qnav_q8_8_t)((int)((k * mult) % 1536u) - 768);
    }
    assert_int_equal(qnav_policy_write(path, &p, "store test", perr, sizeof perr), 0);
    return qnav_link_policy_crc(&p);
}

static int setup(void **state)
{
    qnav_policy_t p;
    (void)state;
    if (qnav_test_tmpdir_make(g_dir, sizeof g_dir, "qnav_core_test") != 0) {
        return -1;
    }
    snprintf(g_p1, sizeof g_p1, "%s/p1.policy", g_dir);
    snprintf(g_p2, sizeof g_p2, "%s/p2.policy", g_dir);
    g_crc1 = write_net(g_p1, 613u);
    g_crc2 = write_net(g_p2, 977u);
    qnav_policy_prob_default(&p);
    g_builtin_crc = qnav_link_policy_crc(&p);
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    return qnav_test_tmpdir_remove(g_dir);
}

/* A robot program (the simavr board or the SIL robot) that makes the pty link `link`,
 * with navbridge on it; both run to their end: the robot exits 0, then navbridge, its
 * pty gone, 1 (link lost). Their outputs land in <dir>/<tag>-robot.out and <tag>-nb.err. */
static void trial(const char *const *robot, const char *link, const char *const *bridge,
                  const char *tag)
{
    char r_out[300], r_err[300], nb_out[300], nb_err[300];
    pid_t pr, pn;
    snprintf(r_out, sizeof r_out, "%s/%s-robot.out", g_dir, tag);
    snprintf(r_err, sizeof r_err, "%s/%s-robot.err", g_dir, tag);
    snprintf(nb_out, sizeof nb_out, "%s/%s-nb.out", g_dir, tag);
    snprintf(nb_err, sizeof nb_err, "%s/%s-nb.err", g_dir, tag);
    pr = qnav_test_spawn(robot, r_out, r_err);
    assert_true(pr > 0);
    assert_int_equal(qnav_test_wait_path(link, QNAV_TEST_WAIT_MS), 0);
    pn = qnav_test_spawn(bridge, nb_out, nb_err);
    assert_true(pn > 0);
    assert_int_equal(qnav_test_wait_exit(pr), 0);
    assert_int_equal(wait_exit_within(pn, QNAV_TEST_WAIT_MS), 1); /* link lost */
}

/* One power cycle of the simavr board (EEPROM file ee, optional power cut after `cut`
 * changed bytes, optional flash file fl kept across cycles) for `seconds` simulated
 * seconds with navbridge onboard (uploading `upload` when not NULL). navbridge's stderr
 * lands in nb_text, the board's stdout in sa_text. */
static void power_cycle(const char *ee, const char *cut, const char *fl, const char *seconds,
                        const char *upload, char *nb_text, char *sa_text, int cap)
{
    char link[300], path[300];
    const char *board[14] = {SIMAVR_BOARD_EXE, "--elf", TEKBOT_ELF, "--link", link, "--eeprom",
                             ee, "--seconds", seconds};
    int n = 9;
    if (cut != NULL) {
        board[n++] = "--power-cut-after";
        board[n++] = cut;
    }
    if (fl != NULL) {
        board[n++] = "--flash";
        board[n++] = fl;
    }
    board[n] = NULL;
    const char *bridge[] = {NAVBRIDGE_EXE, "--device", link, "--lcm-url", "memq://",
                            "--mode", "onboard", "--timeout-ms", "3000",
                            upload ? "--policy" : NULL, upload, "--upload", NULL};
    snprintf(link, sizeof link, "%s/link", g_dir);
    trial(board, link, bridge, "cycle");
    snprintf(path, sizeof path, "%s/cycle-nb.err", g_dir);
    assert_true(read_text(path, nb_text, cap) > 0);
    snprintf(path, sizeof path, "%s/cycle-robot.out", g_dir);
    assert_true(read_text(path, sa_text, cap) > 0);
    print_message("%s", nb_text);
}

static void expect_runs(const char *nb_text, const char *which, uint16_t crc)
{
    char want[128];
    snprintf(want, sizeof want, "runs its %s policy (crc 0x%04x)", which, crc);
    assert_non_null(strstr(nb_text, want));
}

static void copy_file(const char *from, const char *to)
{
    char buf[8192];
    FILE *f = fopen(from, "rb");
    FILE *t = fopen(to, "wb");
    size_t n;
    assert_non_null(f);
    assert_non_null(t);
    n = fread(buf, 1, sizeof buf, f);
    assert_int_equal(fwrite(buf, 1, n, t), n);
    fclose(f);
    assert_int_equal(fclose(t), 0);
}

static void test_committed_policy_survives_a_reset_of_the_avr(void **state)
{
    char ee[300], keep[300], nb[4096], sa[4096];
    (void)state;
    snprintf(ee, sizeof ee, "%s/reset.eeprom", g_dir);
    snprintf(keep, sizeof keep, "%s/p1.eeprom", g_dir);
    power_cycle(ee, NULL, NULL, "3", g_p1, nb, sa, sizeof nb);
    expect_runs(nb, "built-in", g_builtin_crc);   /* a new board: erased EEPROM */
    assert_non_null(strstr(nb, "policy upload: ok"));
    expect_runs(nb, "uploaded", g_crc1);
    power_cycle(ee, NULL, NULL, "1.5", NULL, nb, sa, sizeof nb);
    expect_runs(nb, "uploaded", g_crc1);          /* loaded from EEPROM at boot */
    assert_null(strstr(nb, "built-in"));
    copy_file(ee, keep);
}

static void test_corrupted_store_falls_back_to_the_built_in_policy(void **state)
{
    char ee[300], keep[300], nb[4096], sa[4096];
    FILE *f;
    int byte;
    (void)state;
    snprintf(ee, sizeof ee, "%s/corrupt.eeprom", g_dir);
    snprintf(keep, sizeof keep, "%s/p1.eeprom", g_dir);
    assert_int_equal(access(keep, R_OK), 0); /* made by the reset test */
    copy_file(keep, ee);
    /* one bit of the stored blob flipped (slot 0: 8 header bytes, then the blob) */
    f = fopen(ee, "r+b");
    assert_non_null(f);
    assert_int_equal(fseek(f, 20, SEEK_SET), 0);
    byte = fgetc(f);
    assert_int_equal(fseek(f, 20, SEEK_SET), 0);
    fputc(byte ^ 0x04, f);
    assert_int_equal(fclose(f), 0);
    power_cycle(ee, NULL, NULL, "1.5", NULL, nb, sa, sizeof nb);
    expect_runs(nb, "built-in", g_builtin_crc);
    assert_null(strstr(nb, "uploaded"));
}

static void test_power_cut_while_writing_a_policy_keeps_the_one_before(void **state)
{
    char ee[300], keep[300], nb[4096], sa[4096];
    (void)state;
    snprintf(ee, sizeof ee, "%s/cut.eeprom", g_dir);
    snprintf(keep, sizeof keep, "%s/p1.eeprom", g_dir);
    assert_int_equal(access(keep, R_OK), 0);
    copy_file(keep, ee);
    /* uploading p2: the power goes after 12 of its ~110 bytes reached the EEPROM */
    power_cycle(ee, "12", NULL, "3", g_p2, nb, sa, sizeof nb);
    assert_non_null(strstr(sa, "power cut after"));
    power_cycle(ee, NULL, NULL, "1.5", NULL, nb, sa, sizeof nb);
    expect_runs(nb, "uploaded", g_crc1);
    assert_null(strstr(nb, "built-in"));
}

static void test_power_cut_during_the_first_write_leaves_the_built_in_policy(void **state)
{
    char ee[300], nb[4096], sa[4096];
    (void)state;
    snprintf(ee, sizeof ee, "%s/first-cut.eeprom", g_dir);
    power_cycle(ee, "40", NULL, "3", g_p2, nb, sa, sizeof nb);
    assert_non_null(strstr(sa, "power cut after"));
    power_cycle(ee, NULL, NULL, "1.5", NULL, nb, sa, sizeof nb);
    expect_runs(nb, "built-in", g_builtin_crc);
    assert_null(strstr(nb, "uploaded"));
}

/* The table area in the ATmega128's flash across power cycles: a build the power cut
 * short is not used (the next start-up builds it again), and a whole one is used from the
 * first tick of the next start-up. */
static void test_the_flash_table_survives_a_reset_and_a_cut_build_is_made_again(void **state)
{
    char ee[300], fl[300], nb[4096], sa[4096], want[160];
    (void)state;
    snprintf(ee, sizeof ee, "%s/table.eeprom", g_dir);
    snprintf(fl, sizeof fl, "%s/table.flash", g_dir);
    snprintf(want, sizeof want, "runs its uploaded policy (crc 0x%04x) from its compiled table",
             g_crc1);
    power_cycle(ee, NULL, fl, "2", g_p1, nb, sa, sizeof nb); /* the power goes mid-build */
    assert_non_null(strstr(nb, "policy upload: ok"));
    assert_null(strstr(nb, "table mode"));
    power_cycle(ee, NULL, fl, "9", NULL, nb, sa, sizeof nb);
    expect_runs(nb, "uploaded", g_crc1);            /* first: the network, the area refused */
    assert_non_null(strstr(nb, want));              /* then: built again, table mode */
    power_cycle(ee, NULL, fl, "1.5", NULL, nb, sa, sizeof nb);
    snprintf(want, sizeof want,
             "runs its uploaded policy (crc 0x%04x) from its compiled table (table mode)\n",
             g_crc1);
    assert_non_null(strstr(nb, want));
    snprintf(want, sizeof want, "runs its uploaded policy (crc 0x%04x)\n", g_crc1);
    assert_null(strstr(nb, want));                  /* never without the table */
}

/* ---- the same scan stream into the AVR image and into the SIL robot ---- */

#define MAX_SCANS 4096

typedef struct {
    int n;                        /* scans */
    int32_t seq[MAX_SCANS];
    int32_t goal_id[MAX_SCANS];
    int have[MAX_SCANS];          /* the board's command for scan i came */
    qnav_command_t cmd[MAX_SCANS];
} stream_t;

/* Scans in order and the board's command for each (matched by sequence number). */
static void read_stream(const char *path, stream_t *s)
{
    lcm_eventlog_t *log = lcm_eventlog_create(path, "r");
    lcm_eventlog_event_t *ev;
    assert_non_null(log);
    memset(s, 0, sizeof *s);
    while ((ev = lcm_eventlog_read_next_event(log)) != NULL) {
        qnav_scan_t sc;
        qnav_command_t c;
        if (strcmp(ev->channel, "QNAV_SCAN") == 0 && s->n < MAX_SCANS &&
            qnav_scan_t_decode(ev->data, 0, ev->datalen, &sc) >= 0) {
            s->seq[s->n] = sc.seq;
            s->goal_id[s->n] = sc.goal_id;
            s->n++;
        } else if (strcmp(ev->channel, "QNAV_COMMAND") == 0 &&
                   qnav_command_t_decode(ev->data, 0, ev->datalen, &c) >= 0 && c.source == 2) {
            int i;
            for (i = s->n - 1; i >= 0; --i) {
                if (s->seq[i] == c.scan_seq) {
                    s->have[i] = 1;
                    s->cmd[i] = c;
                    break;
                }
            }
        }
        lcm_eventlog_free_event(ev);
    }
    lcm_eventlog_destroy(log);
}

/* A trial recorded into log: the robot program (the simavr board or the SIL robot) with
 * navbridge onboard uploading p1, goal 20 deg. */
static void record(const char *const *robot, const char *link, const char *log,
                   const char *tag)
{
    const char *bridge[] = {NAVBRIDGE_EXE, "--device", link, "--lcm-url", "memq://",
                            "--mode", "onboard", "--policy", g_p1, "--upload", "--goal", "20",
                            "--log", log, "--timeout-ms", "3000", NULL};
    trial(robot, link, bridge, tag);
}

static void test_sil_robot_and_avr_image_command_alike_on_one_scan_stream(void **state)
{
    char avr_log[300], sil_log[300], link[300], path[300], text[2048];
    const char *avr[] = {SIMAVR_BOARD_EXE, "--elf", TEKBOT_ELF, "--link", link, "--seconds", "9",
                         NULL};
    const char *sil[] = {SIL_EXE, "--playback", avr_log, "--tick-ms", "25", "--link", link,
                         NULL};
    static stream_t a, s;
    int i, compared = 0, differ = 0;
    (void)state;
    snprintf(avr_log, sizeof avr_log, "%s/avr.lcmlog", g_dir);
    snprintf(sil_log, sizeof sil_log, "%s/sil.lcmlog", g_dir);
    snprintf(link, sizeof link, "%s/stream-link", g_dir);
    record(avr, link, avr_log, "avr");
    /* within about 5 s of the upload the AVR compiled p1 into its flash table area and
     * steps in table mode (qnav/board.h); the SIL robot has no area and steps the network */
    snprintf(path, sizeof path, "%s/avr-nb.err", g_dir);
    assert_true(read_text(path, text, sizeof text) > 0);
    assert_non_null(strstr(text, "from its compiled table (table mode)"));
    /* the AVR's scans played into the same core built for the host */
    record(sil, link, sil_log, "sil");
    snprintf(path, sizeof path, "%s/sil-robot.out", g_dir);
    assert_true(read_text(path, text, sizeof text) > 0);
    print_message("%s", text);
    assert_non_null(strstr(text, "playback done"));
    read_stream(avr_log, &a);
    read_stream(sil_log, &s);
    assert_int_equal(s.n, a.n); /* one tick of the SIL robot per recorded scan */
    for (i = 0; i < a.n; ++i) {
        const qnav_command_t *x = &a.cmd[i];
        const qnav_command_t *y = &s.cmd[i];
        /* both boards running the uploaded policy towards the same goal */
        if (!a.have[i] || !s.have[i] || x->policy_crc != g_crc1 || y->policy_crc != g_crc1 ||
            a.goal_id[i] != s.goal_id[i] || a.goal_id[i] == 0) {
            continue;
        }
        compared++;
        if (x->heading_deg != y->heading_deg || x->quality_q15 != y->quality_q15 ||
            x->flags != y->flags ||
            (x->stop_reason == 0 && y->stop_reason == 0 && x->speed_q15 != y->speed_q15)) {
            differ++;
            print_message("scan %d: avr %d deg %d/%d, sil %d deg %d/%d\n", i, x->heading_deg,
                          x->speed_q15, x->quality_q15, y->heading_deg, y->speed_q15,
                          y->quality_q15);
        }
    }
    print_message("%d scans, %d commands compared, %d differ\n", a.n, compared, differ);
    for (i = 0; i < a.n && compared == 0; ++i) {
        print_message("scan %d: avr have %d crc 0x%04x goal %d; sil have %d crc 0x%04x goal %d\n",
                      i, a.have[i], (unsigned)a.cmd[i].policy_crc, a.goal_id[i], s.have[i],
                      (unsigned)s.cmd[i].policy_crc, s.goal_id[i]);
    }
    assert_true(compared >= 60); /* 9 s at 10 Hz: table mode's ticks among them */
    assert_int_equal(differ, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_committed_policy_survives_a_reset_of_the_avr),
        cmocka_unit_test(test_corrupted_store_falls_back_to_the_built_in_policy),
        cmocka_unit_test(test_power_cut_while_writing_a_policy_keeps_the_one_before),
        cmocka_unit_test(test_power_cut_during_the_first_write_leaves_the_built_in_policy),
        cmocka_unit_test(test_sil_robot_and_avr_image_command_alike_on_one_scan_stream),
        cmocka_unit_test(test_the_flash_table_survives_a_reset_and_a_cut_build_is_made_again),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
