/*
 * Software in the loop, end to end: qnav-sil-robot (the Box2D simulator playing the board
 * on a pty) and navbridge drive the simulated robot to its destination; the trial, logged,
 * replays to identical commands. Once on memq:// with navbridge --log, once on a real
 * udpm:// bus recorded by lcm-logger inside a private network namespace (skipped when
 * `unshare -n` is not permitted). No packet leaves the machine. When the robot's episode
 * ends its pty closes and navbridge exits with status 1 (link lost).
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
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmocka.h>
#include <lcm/eventlog.h>

#include "fakeboard.h"
#include "test_proc.h"
#include "qnav/link.h"
#include "qnav/policy_io.h"
#include "qnav_odometry_t.h"

static char g_dir[256];

static int setup(void **state)
{
    (void)state;
    setenv("QNAV_DATA_DIR", QNAV_DATA_DIR, 1);
    return qnav_test_tmpdir_make(g_dir, sizeof g_dir, "qnav_sil_test");
}

static int teardown(void **state)
{
    (void)state;
    return qnav_test_tmpdir_remove(g_dir);
}

/* Count events per channel of interest in an LCM log. */
static void count_channels(const char *path, int *scan, int *cmd, int *qual, int *status,
                           int *pose)
{
    lcm_eventlog_t *log = lcm_eventlog_create(path, "r");
    lcm_eventlog_event_t *ev;
    assert_non_null(log);
    *scan = *cmd = *qual = *status = *pose = 0;
    while ((ev = lcm_eventlog_read_next_event(log)) != NULL) {
        *scan += strcmp(ev->channel, "QNAV_SCAN") == 0;
        *cmd += strcmp(ev->channel, "QNAV_COMMAND") == 0;
        *qual += strcmp(ev->channel, "QNAV_QUALITIES") == 0;
        *status += strcmp(ev->channel, "QNAV_LINK_STATUS") == 0;
        *pose += strcmp(ev->channel, "QNAV_POSE") == 0;
        lcm_eventlog_free_event(ev);
    }
    lcm_eventlog_destroy(log);
}

/* The destination the SIL robot printed, as navbridge --goal-at's value (odometry frame);
 * the robot prints it before it makes its link and says "link on", which the callers wait
 * for. */
static void destination_of(const char *sil_out, char *goal, size_t len)
{
    char text[2048];
    const char *at;
    size_t n = 0;
    assert_true(read_text(sil_out, text, sizeof text) > 0);
    at = strstr(text, "--goal-at ");
    assert_non_null(at);
    at += strlen("--goal-at ");
    while (n + 1 < len && at[n] != ')' && at[n] != '\0') {
        goal[n] = at[n];
        n++;
    }
    goal[n] = '\0';
}

/* navbridge --replay log (with --robot robot unless NULL): every decision identical, and
 * every scan replayed with its logged goal distance and previous heading. */
static void replay_robot_is_identical(const char *log, const char *robot)
{
    char out[320], err[320], text[2048];
    const char *argv[] = {NAVBRIDGE_EXE, "--replay", log, "--robot", robot, NULL};
    unsigned long scans = 0, with_input = 0;
    if (robot == NULL) {
        argv[3] = NULL;
    }
    snprintf(out, sizeof out, "%s/replay.out", g_dir);
    snprintf(err, sizeof err, "%s/replay.err", g_dir);
    assert_int_equal(run_program(argv, out, err), 0);
    assert_true(read_text(out, text, sizeof text) > 0);
    print_message("%s", text);
    assert_non_null(strstr(text, "identical, 0 differ"));
    assert_int_equal(sscanf(text, "replay: %lu scans,", &scans), 1);
    assert_non_null(strstr(text, "; "));
    assert_int_equal(sscanf(strstr(text, "; "), "; %lu scans with their logged", &with_input), 1);
    assert_int_equal(with_input, scans);
}

static void replay_is_identical(const char *log)
{
    replay_robot_is_identical(log, NULL);
}

/* The files of one SIL trial named tag in g_dir: the robot's and navbridge's output. */
typedef struct {
    char sil_out[300], sil_err[300], nb_out[300], nb_err[300];
} trial_files_t;

/* Run a SIL robot (sil) and then navbridge (nb, whose --goal-at value is goal) to the
 * end of the episode, the files named by tag: the robot's end closes the pty and navbridge
 * sees the hang-up and leaves with 1. Returns the robot's exit status (0: destination
 * reached). */
static int drive_trial(const char *const *sil, const char *const *nb, const char *tag,
                       char *goal, size_t goal_len, trial_files_t *f)
{
    pid_t ps, pn;
    int status;
    snprintf(f->sil_out, sizeof f->sil_out, "%s/sil%s.out", g_dir, tag);
    snprintf(f->sil_err, sizeof f->sil_err, "%s/sil%s.err", g_dir, tag);
    snprintf(f->nb_out, sizeof f->nb_out, "%s/nb%s.out", g_dir, tag);
    snprintf(f->nb_err, sizeof f->nb_err, "%s/nb%s.err", g_dir, tag);
    ps = qnav_test_spawn(sil, f->sil_out, f->sil_err);
    assert_true(ps > 0);
    assert_int_equal(qnav_test_wait_text(f->sil_out, "link on", QNAV_TEST_WAIT_MS), 0);
    destination_of(f->sil_out, goal, goal_len);
    pn = qnav_test_spawn(nb, f->nb_out, f->nb_err);
    assert_true(pn > 0);
    status = qnav_test_wait_exit(ps);
    assert_int_equal(wait_exit_within(pn, QNAV_TEST_WAIT_MS), 1);
    return status;
}

static void test_sil_robot_reaches_destination_through_navbridge_over_memq(void **state)
{
    char link[300], log[300];
    char text[2048], goal[64];
    /* lockstep is about repeatability: a loaded machine may take more than 300 ms to answer */
    const char *sil[] = {SIL_EXE, "--lockstep", "--reply-ms", "3000", "--link", link, NULL};
    const char *nb[] = {NAVBRIDGE_EXE, "--device", link, "--lcm-url", "memq://", "--log", log,
                        "--goal-at", goal, NULL};
    trial_files_t f;
    int scan, cmd, qual, status, pose;
    (void)state;
    snprintf(link, sizeof link, "%s/link", g_dir);
    snprintf(log, sizeof log, "%s/memq.lcmlog", g_dir);
    assert_int_equal(drive_trial(sil, nb, "", goal, sizeof goal, &f), 0);
    assert_true(read_text(f.nb_err, text, sizeof text) > 0);
    assert_non_null(strstr(text, "device hung up: link lost"));
    assert_true(read_text(f.sil_out, text, sizeof text) > 0);
    print_message("%s", text);
    assert_non_null(strstr(text, "reached yes"));
    assert_non_null(strstr(text, " 0 ticks without a command"));
    count_channels(log, &scan, &cmd, &qual, &status, &pose);
    assert_true(scan > 20);
    assert_true(cmd >= scan);
    assert_int_equal(qual, scan);
    assert_true(status > 0);
    replay_is_identical(log);
}

/* The Pioneer 3-DX as a second platform: the SIL robot runs the board core with the
 * configuration generated from its profile; navbridge --robot pioneer3dx accepts it and
 * drives it to the destination, navbridge --robot tekbot refuses it with one line. */
static void test_sil_pioneer3dx_is_driven_by_its_robot_and_refused_by_another(void **state)
{
    char link[300], log[300], sil_out[300], sil_err[300], nb_out[300], nb_err[300];
    char text[2048], goal[64];
    const char *sil[] = {SIL_EXE, "--robot", "pioneer3dx", "--lockstep", "--reply-ms", "3000",
                         "--link", link, NULL};
    const char *wrong[] = {NAVBRIDGE_EXE, "--device", link, "--lcm-url", "memq://",
                           "--goal-at", goal, "--robot", "tekbot", NULL};
    const char *nb[] = {NAVBRIDGE_EXE, "--device", link, "--lcm-url", "memq://", "--log", log,
                        "--goal-at", goal, "--robot", "pioneer3dx", NULL};
    const char *replay[] = {NAVBRIDGE_EXE, "--replay", log, "--robot", "pioneer3dx", NULL};
    pid_t ps, pn;
    (void)state;
    snprintf(link, sizeof link, "%s/link-p3dx", g_dir);
    snprintf(log, sizeof log, "%s/p3dx.lcmlog", g_dir);
    snprintf(sil_out, sizeof sil_out, "%s/sil-p3dx.out", g_dir);
    snprintf(sil_err, sizeof sil_err, "%s/sil-p3dx.err", g_dir);
    snprintf(nb_out, sizeof nb_out, "%s/nb-p3dx.out", g_dir);
    snprintf(nb_err, sizeof nb_err, "%s/nb-p3dx.err", g_dir);

    /* a TekBot bridge: refused at the board's first CONFIG report */
    ps = qnav_test_spawn(sil, sil_out, sil_err);
    assert_true(ps > 0);
    assert_int_equal(qnav_test_wait_path(link, 4000), 0);
    destination_of(sil_out, goal, sizeof goal);
    pn = qnav_test_spawn(wrong, nb_out, nb_err);
    assert_true(pn > 0);
    assert_int_equal(wait_exit_within(pn, 30000), 1);
    assert_true(read_text(nb_err, text, sizeof text) > 0);
    print_message("%s", text);
    assert_non_null(strstr(text, "navbridge: board configuration differs from robot 'tekbot': "
                                 "max_range_mm 5000 != 2500\n"));
    assert_int_equal(kill(ps, SIGTERM), 0);
    assert_true(qnav_test_wait_exit(ps) >= 0);

    /* its own bridge drives it to the destination */
    snprintf(sil_out, sizeof sil_out, "%s/sil-p3dx2.out", g_dir);
    snprintf(link, sizeof link, "%s/link-p3dx2", g_dir);
    ps = qnav_test_spawn(sil, sil_out, sil_err);
    assert_true(ps > 0);
    assert_int_equal(qnav_test_wait_path(link, 4000), 0);
    destination_of(sil_out, goal, sizeof goal);
    pn = qnav_test_spawn(nb, nb_out, nb_err);
    assert_true(pn > 0);
    assert_int_equal(qnav_test_wait_exit(ps), 0); /* 0: destination reached */
    assert_int_equal(wait_exit_within(pn, 3000), 1);
    assert_true(read_text(sil_out, text, sizeof text) > 0);
    print_message("%s", text);
    assert_non_null(strstr(text, "reached yes"));
    /* the bridge's controller ran the profile's configuration: the replay with it agrees */
    snprintf(nb_out, sizeof nb_out, "%s/rp-p3dx.out", g_dir);
    assert_int_equal(run_program(replay, nb_out, nb_err), 0);
    assert_true(read_text(nb_out, text, sizeof text) > 0);
    assert_non_null(strstr(text, "identical, 0 differ"));
}

/* Run argv to its end (output in g_dir/tag.out and .err): it must exit 2 after one line
 * on stderr that contains expect. */
static void refused_in_one_line(const char *const *argv, const char *tag, const char *expect)
{
    char out[320], err[320], text[2048];
    snprintf(out, sizeof out, "%s/%s.out", g_dir, tag);
    snprintf(err, sizeof err, "%s/%s.err", g_dir, tag);
    assert_int_equal(run_program(argv, out, err), 2);
    assert_true(read_text(err, text, sizeof text) > 0);
    print_message("%s", text);
    assert_non_null(strstr(text, expect));
    assert_ptr_equal(strchr(text, '\n'), text + strlen(text) - 1); /* one line */
}

/* One lockstep trial of robot (a TekBot spec with its map) in the committed U-pocket world
 * (pocket_tekbot.toml), navbridge in mode ("offboard" or "onboard") with --robot robot
 * logging to log: the robot must reach its destination, its board core running the map
 * the board would. */
static void pocket_trial(const char *robot, const char *mode, const char *log)
{
    char link[300], tag[48], text[2048], goal[64];
    const char *sil[] = {SIL_EXE, "--robot", robot, "--env", POCKET_ENV, "--lockstep",
                         "--reply-ms", "3000", "--link", link, NULL};
    const char *nb[] = {NAVBRIDGE_EXE, "--device", link, "--lcm-url", "memq://", "--log", log,
                        "--goal-at", goal, "--robot", robot, "--mode", mode, NULL};
    trial_files_t f;
    snprintf(link, sizeof link, "%s/link-pocket-%s-%s", g_dir, robot, mode);
    snprintf(tag, sizeof tag, "-pocket-%s-%s", robot, mode);
    assert_int_equal(drive_trial(sil, nb, tag, goal, sizeof goal, &f), 0);
    assert_true(read_text(f.sil_out, text, sizeof text) > 0);
    print_message("%s: %s", mode, text);
    assert_non_null(strstr(text, "reached yes"));
    /* the TekBot's map as its board runs it: the profile's 768 bytes, placed at the goal */
    assert_true(read_text(f.sil_err, text, sizeof text) > 0);
    assert_non_null(strstr(text, "the board core places a map of 300 mm cells in 768 bytes"));
}

/* Issues 17 and 18: in a U-pocket facing the start, the offboard robot leaves the dead end
 * as the onboard one does (navbridge runs the board's escape, fed the board's distance to
 * the goal); both logs, and one of a board running its map, replay identically with the
 * logged goal distance and previous heading on every scan; a replay that does not say
 * which robot is refused. */
static void test_sil_offboard_leaves_a_pocket_as_onboard_does_and_replays_identically(
    void **state)
{
    char log[300];
    const char *no_robot[] = {NAVBRIDGE_EXE, "--replay", log, NULL};
    (void)state;
    snprintf(log, sizeof log, "%s/pocket-onboard.lcmlog", g_dir);
    pocket_trial("tekbot", "onboard", log);
    replay_robot_is_identical(log, "tekbot");
    snprintf(log, sizeof log, "%s/pocket-offboard.lcmlog", g_dir);
    pocket_trial("tekbot", "offboard", log);
    replay_robot_is_identical(log, "tekbot");
    /* a board running its map: the goal bearing is the sub-goal's, the previous heading
     * still the robot's own (162 of 183 decisions replayed otherwise when it followed the
     * goal bearing) */
    snprintf(log, sizeof log, "%s/pocket-map-onboard.lcmlog", g_dir);
    pocket_trial("tekbot+map", "onboard", log);
    replay_robot_is_identical(log, "tekbot+map");

    refused_in_one_line(no_robot, "pocket-norobot", "--robot NAME|FILE missing");
}

/* One lockstep trial of episode ep in the wall-gap world (wall_gap.toml) with the robot
 * profile prof and navbridge in mode ("onboard", or "offboard": its controller steers by
 * the bearing the board reports), tagged tag: the SIL robot's exit status (0: reached),
 * its output and its error output in out and err. */
static int wall_gap_trial(const char *prof, const char *ep, const char *mode, const char *tag,
                          char *out, size_t out_len, char *err, size_t err_len)
{
    char link[300], goal[64];
    const char *sil[] = {SIL_EXE, "--robot", prof, "--env", WALL_GAP_ENV, "--episode", ep,
                         "--lockstep", "--reply-ms", "3000", "--link", link, NULL};
    const char *nb[] = {NAVBRIDGE_EXE, "--device", link, "--lcm-url", "memq://", "--goal-at",
                        goal, "--mode", mode, NULL};
    trial_files_t f;
    int status;
    snprintf(link, sizeof link, "%s/link%s", g_dir, tag);
    status = drive_trial(sil, nb, tag, goal, sizeof goal, &f);
    assert_true(read_text(f.sil_out, out, (int)out_len) > 0);
    assert_true(read_text(f.sil_err, err, (int)err_len) > 0);
    return status;
}

/* The TekBot's profile with a [map] of cell_m cells (in place of its own, which is
 * last), written to path. */
static void tekbot_with_map(const char *path, const char *cell_m)
{
    static char profile[16384];
    FILE *f;
    char *own;
    int n = read_text(QNAV_DATA_DIR "/robots/tekbot.toml", profile, (int)sizeof profile);
    assert_true(n > 0 && n < (int)sizeof profile - 1);
    own = strstr(profile, "\n[map]");
    assert_non_null(own);
    own[1] = '\0';
    f = fopen(path, "w");
    assert_non_null(f);
    fprintf(f, "%s\n[map]\ncell_m = %s\n", profile, cell_m);
    assert_int_equal(fclose(f), 0);
}

/* Issue 18: a profile's [map] is run by the board core itself (qnav_board_set_map), marked
 * from the board's own dead reckoning: behind a wall whose gap is far to one side, the
 * robot reaches the destination at least 10 s sooner than the policy alone, which slides
 * along the wall (and arrives within the world's 60 s, or not); a map too large for its
 * cells is refused with one line. */
static void test_sil_board_core_with_a_map_finds_the_far_gap(void **state)
{
    char prof[300], fine[300], text[2048], err[2048];
    const char *eps[] = {"2", "3"}, *modes[] = {"offboard", "onboard"};
    const char *at;
    long with_map = 0, without = 0;
    const char *sil_fine[] = {SIL_EXE, "--robot", fine, "--env", WALL_GAP_ENV, NULL};
    size_t k;
    (void)state;
    snprintf(prof, sizeof prof, "%s/tekbot-map.toml", g_dir);
    tekbot_with_map(prof, "0.1");
    for (k = 0; k < sizeof eps / sizeof eps[0]; ++k) {
        char tag[32];
        snprintf(tag, sizeof tag, "-gap-map-%s", eps[k]);
        assert_int_equal(wall_gap_trial(prof, eps[k], modes[k], tag, text, sizeof text, err,
                                        sizeof err), 0);
        print_message("map, episode %s, %s: %s", eps[k], modes[k], text);
        assert_non_null(strstr(text, "reached yes, "));
        assert_non_null(strstr(text, " 0 collisions"));
        assert_non_null(strstr(err, "the board core plans over a map of 100 mm cells"));
        if (k == 0) {
            at = strstr(text, "reached yes, ");
            with_map = strtol(at + strlen("reached yes, "), NULL, 10);
        }
    }
    /* the contrast: the same episode without the map slides along the wall */
    (void)wall_gap_trial("tekbot-map", "2", "offboard", "-gap-nomap", text, sizeof text, err, sizeof err);
    print_message("no map, episode 2: %s", text);
    at = strstr(text, "reached yes, ");
    without = at != NULL ? strtol(at + strlen("reached yes, "), NULL, 10) : 100000L;
    assert_true(with_map > 0 && without >= with_map + 100);
    assert_null(strstr(err, "plans over a map"));

    /* 4 cm cells over the arena's bounding box in the odometry frame: too many */
    snprintf(fine, sizeof fine, "%s/tekbot-fine.toml", g_dir);
    tekbot_with_map(fine, "0.04");
    refused_in_one_line(sil_fine, "sil-fine", "[map] cells of 40 mm over ");
}

static void test_sil_robot_onboard_runs_uploaded_policy_and_replays_identically(void **state)
{
    char link[300], log[300], pol[300], sil_out[300], sil_err[300], nb_out[300], nb_err[300];
    char text[4096], perr[QNAV_POLICY_IO_ERRLEN], goal[64];
    const char *sil[] = {SIL_EXE, "--tick-ms", "20", "--link", link, NULL};
    const char *nb[] = {NAVBRIDGE_EXE, "--device", link, "--lcm-url", "memq://", "--mode",
                        "onboard", "--policy", pol, "--upload", "--log", log, "--goal-at",
                        goal, NULL};
    const char *replay[] = {NAVBRIDGE_EXE, "--replay", log, "--policy", pol, "--robot", "tekbot",
                            NULL}; /* the board's robot: its controller configuration */
    qnav_policy_t p;
    pid_t ps, pn;
    int i;
    unsigned scans = 0, compared = 0;
    (void)state;
    snprintf(link, sizeof link, "%s/link-onboard", g_dir);
    snprintf(log, sizeof log, "%s/onboard.lcmlog", g_dir);
    snprintf(pol, sizeof pol, "%s/sharp.policy", g_dir);
    snprintf(sil_out, sizeof sil_out, "%s/sil-on.out", g_dir);
    snprintf(sil_err, sizeof sil_err, "%s/sil-on.err", g_dir);
    snprintf(nb_out, sizeof nb_out, "%s/nb-on.out", g_dir);
    snprintf(nb_err, sizeof nb_err, "%s/nb-on.err", g_dir);
    qnav_policy_prob_default(&p);
    p.u.prob.k_goal = 3 * 256; /* not the board's default: the upload must take */
    assert_int_equal(qnav_policy_write(pol, &p, "sil onboard test", perr, sizeof perr), 0);
    ps = qnav_test_spawn(sil, sil_out, sil_err);
    assert_true(ps > 0);
    assert_int_equal(qnav_test_wait_text(sil_out, "link on", QNAV_TEST_WAIT_MS), 0);
    destination_of(sil_out, goal, sizeof goal);
    pn = qnav_test_spawn(nb, nb_out, nb_err);
    assert_true(pn > 0);
    assert_int_equal(qnav_test_wait_exit(ps), 0);
    assert_int_equal(wait_exit_within(pn, QNAV_TEST_WAIT_MS), 1);
    assert_true(read_text(nb_err, text, sizeof text) > 0);
    assert_non_null(strstr(text, "policy upload: ok"));
    /* the board's heartbeat says which policy runs: first its own, then the upload */
    assert_non_null(strstr(text, "runs its built-in policy"));
    assert_non_null(strstr(text, "runs its uploaded policy"));
    assert_true(read_text(sil_out, text, sizeof text) > 0);
    print_message("%s", text);
    assert_non_null(strstr(text, "reached yes"));
    snprintf(sil_out, sizeof sil_out, "%s/rp-on.out", g_dir);
    snprintf(sil_err, sizeof sil_err, "%s/rp-on.err", g_dir);
    i = run_program(replay, sil_out, sil_err);
    assert_true(read_text(sil_out, text, sizeof text) > 0);
    print_message("%s", text);
    assert_int_equal(i, 0);
    assert_non_null(strstr(text, "identical, 0 differ"));
    assert_int_equal(sscanf(strstr(text, "replay: "), "replay: %u scans, %u commands compared",
                            &scans, &compared), 2);
    assert_true(compared + 20u >= scans); /* all but the ticks before the upload landed */
}

/* One udpm:// trial by udpm_trial.sh in a private network namespace, in dir (skips the
 * test when namespaces or loopback multicast are not permitted). args: the script's
 * arguments after DIR (qnav-spy's path or "-", then robot arguments, "--", navbridge
 * arguments), NULL-ended. Checks the statuses the script reports (expect, e.g.
 * "sil=0 navbridge=1 spy=-"). */
static void run_udpm_trial_in(const char *dir, const char *const *args, const char *expect)
{
    char rc_path[300], text[512], out[300], err[300];
    const char *probe[] = {UNSHARE_EXE, "-n", "true", NULL};
    const char *trial[32] = {UNSHARE_EXE, "-n", "/bin/sh", UDPM_SCRIPT, NAVBRIDGE_EXE, SIL_EXE,
                             dir};
    int k = 7;
    while (*args != NULL && k < 31) {
        trial[k++] = *args++;
    }
    trial[k] = NULL;
    snprintf(out, sizeof out, "%s/probe.out", dir);
    snprintf(err, sizeof err, "%s/probe.err", dir);
    if (run_program(probe, out, err) != 0) {
        print_message("SKIP: `unshare -n` is not permitted here, so the udpm:// trial cannot "
                      "run in a private network namespace (DESIGN.md §7)\n");
        skip();
    }
    snprintf(rc_path, sizeof rc_path, "%s/rc.txt", dir);
    if (run_program(trial, out, err) == 10) {
        print_message("SKIP: cannot configure loopback multicast in the namespace\n");
        skip();
    }
    assert_true(read_text(rc_path, text, sizeof text) > 0);
    print_message("%s", text);
    assert_non_null(strstr(text, expect));
}

/* The same in g_dir with the robot's destination as the goal, watched by qnav-spy when spy
 * is not NULL. */
static void run_udpm_trial(const char *spy, const char *expect)
{
    const char *args[] = {spy != NULL ? spy : "-", NULL};
    run_udpm_trial_in(g_dir, args, expect);
}

static void test_sil_trial_on_udpm_recorded_by_lcm_logger_replays_identically(void **state)
{
    char log[300], text[2048], sil_out[300];
    int scan, cmd, qual, status, pose;
    (void)state;
    snprintf(log, sizeof log, "%s/trial.lcmlog", g_dir);
    snprintf(sil_out, sizeof sil_out, "%s/sil.out", g_dir);
    run_udpm_trial(NULL, "sil=0 navbridge=1 spy=-");
    assert_true(read_text(sil_out, text, sizeof text) > 0);
    assert_non_null(strstr(text, "reached yes"));
    count_channels(log, &scan, &cmd, &qual, &status, &pose);
    print_message("lcm-logger recorded %d scans, %d commands, %d qualities, %d link status, "
                  "%d poses\n", scan, cmd, qual, status, pose);
    /* UDP may lose a datagram on a loaded machine: near-complete, not exact, counts */
    assert_true(scan > 100);
    assert_true(cmd > 100);
    assert_true(qual > 100);
    assert_true(status > 0);
    assert_true(pose > 100);
    replay_is_identical(log);
}

/* Odometry events of an LCM log: how many, and the highest waypoint index reached. */
static void odometry_progress(const char *path, int *n, int *waypoint, int *waypoints)
{
    lcm_eventlog_t *log = lcm_eventlog_create(path, "r");
    lcm_eventlog_event_t *ev;
    assert_non_null(log);
    *n = *waypoint = *waypoints = 0;
    while ((ev = lcm_eventlog_read_next_event(log)) != NULL) {
        qnav_odometry_t o;
        if (strcmp(ev->channel, "QNAV_ODOMETRY") == 0 &&
            qnav_odometry_t_decode(ev->data, 0, ev->datalen, &o) >= 0) {
            (*n)++;
            *waypoint = o.waypoint > *waypoint ? o.waypoint : *waypoint;
            *waypoints = o.waypoints;
        }
        lcm_eventlog_free_event(ev);
    }
    lcm_eventlog_destroy(log);
}

/* Three waypoints through the dense environment (its three rows of obstacles), start
 * at (5, 1.1) m facing +y, so the odometry frame is x = world y - 1.1, y = 5 - world x:
 * the gap in row 1 (4.7, 3.0), the gap in row 2 (4.5, 5.0), the destination (5, 9). */
static void test_sil_route_of_three_waypoints_through_dense_replays_identically(void **state)
{
    char dir[300], log[300], text[4096], path[300];
    const char *args[] = {"-", "--env", "dense", "--start", "5:1.1:90", "--", "--waypoints",
                          "1.9:0.3,3.9:0.5,7.9:0", "--goal-radius", "0.4", NULL};
    int n, waypoint, waypoints;
    (void)state;
    snprintf(dir, sizeof dir, "%s/route", g_dir);
    assert_int_equal(mkdir(dir, 0700), 0);
    snprintf(log, sizeof log, "%s/trial.lcmlog", dir);
    run_udpm_trial_in(dir, args, "sil=0 navbridge=1 spy=-");
    snprintf(path, sizeof path, "%s/sil.out", dir);
    assert_true(read_text(path, text, sizeof text) > 0);
    print_message("%s", text);
    assert_non_null(strstr(text, "reached yes")); /* the third waypoint is the destination */
    assert_non_null(strstr(text, " 0 collisions"));
    snprintf(path, sizeof path, "%s/nb.err", dir);
    assert_true(read_text(path, text, sizeof text) > 0);
    print_message("%s", text);
    assert_non_null(strstr(text, "waypoint 1/3 reached"));
    assert_non_null(strstr(text, "waypoint 2/3 reached"));
    odometry_progress(log, &n, &waypoint, &waypoints);
    print_message("lcm-logger recorded %d odometry poses, waypoint index up to %d of %d\n", n,
                  waypoint, waypoints);
    assert_true(n > 50);
    assert_int_equal(waypoints, 3);
    assert_int_equal(waypoint, 2);
    replay_is_identical(log);
}

/* One onboard SIL trial with --nvm; navbridge's stderr into text. */
static void nvm_trial(const char *nvm, const char *pol, int upload, char *text, int cap)
{
    char link[300], goal[64];
    const char *sil[] = {SIL_EXE, "--tick-ms", "10", "--nvm", nvm, "--link", link, NULL};
    const char *nb[] = {NAVBRIDGE_EXE, "--device", link, "--lcm-url", "memq://", "--mode",
                        "onboard", "--goal-at", goal, upload ? "--policy" : NULL, pol,
                        "--upload", NULL};
    trial_files_t f;
    int rc;
    snprintf(link, sizeof link, "%s/link-nvm", g_dir);
    rc = drive_trial(sil, nb, "-nvm", goal, sizeof goal, &f);
    assert_true(read_text(f.sil_out, text, cap) > 0);
    print_message("%s", text);
    assert_int_equal(rc, 0);
    assert_true(read_text(f.nb_err, text, cap) > 0);
}

static void test_sil_robot_keeps_an_uploaded_policy_in_its_nvm_file(void **state)
{
    char nvm[300], pol[300], text[4096], perr[QNAV_POLICY_IO_ERRLEN], want[96];
    qnav_policy_t p;
    (void)state;
    snprintf(nvm, sizeof nvm, "%s/robot.nvm", g_dir);
    snprintf(pol, sizeof pol, "%s/nvm.policy", g_dir);
    qnav_policy_prob_default(&p);
    p.u.prob.k_goal = 3 * 256;
    assert_int_equal(qnav_policy_write(pol, &p, "sil nvm test", perr, sizeof perr), 0);
    snprintf(want, sizeof want, "runs its uploaded policy (crc 0x%04x)", qnav_link_policy_crc(&p));
    nvm_trial(nvm, pol, 1, text, sizeof text);
    assert_non_null(strstr(text, "runs its built-in policy")); /* a new, erased store */
    assert_non_null(strstr(text, want));
    nvm_trial(nvm, pol, 0, text, sizeof text);    /* restarted: loaded from the file */
    assert_non_null(strstr(text, want));
    assert_null(strstr(text, "built-in"));
}

/* --link onto a user's file: refused with status 2, the file untouched (it used to be
 * deleted and replaced by the link). */
static void test_sil_robot_refuses_link_path_that_is_a_file(void **state)
{
    char path[300];
    const char *sil[] = {SIL_EXE, "--wait-s", "0", "--link", path, NULL};
    (void)state;
    snprintf(path, sizeof path, "%s/notes.txt", g_dir);
    assert_int_equal(qnav_test_link_refused(sil, path, g_dir), 0);
}

/* A file put where the link was while the robot runs survives the robot's exit: only the
 * link it made is removed. */
static void test_sil_robot_leaves_a_file_that_replaced_its_link(void **state)
{
    char path[300], out[300], err[300], text[512];
    const char *sil[] = {SIL_EXE, "--wait-s", "60", "--link", path, NULL};
    pid_t ps;
    (void)state;
    snprintf(path, sizeof path, "%s/link-replaced", g_dir);
    snprintf(out, sizeof out, "%s/replaced.out", g_dir);
    snprintf(err, sizeof err, "%s/replaced.err", g_dir);
    ps = qnav_test_spawn(sil, out, err);
    assert_true(ps > 0);
    assert_int_equal(qnav_test_wait_text(out, "link on", QNAV_TEST_WAIT_MS), 0);
    assert_int_equal(unlink(path), 0);
    assert_int_equal(qnav_test_write_text(path, "mine now\n"), 0);
    assert_int_equal(kill(ps, SIGTERM), 0);
    assert_int_equal(qnav_test_wait_exit(ps), 1); /* no navbridge came */
    assert_true(read_text(path, text, sizeof text) > 0);
    assert_string_equal(text, "mine now\n");
}

/* The dangling pty link of a killed earlier run is replaced, and removed at exit. */
static void test_sil_robot_replaces_stale_pty_link_and_removes_it_at_exit(void **state)
{
    char path[300], out[300], err[300], target[256];
    const char *sil[] = {SIL_EXE, "--wait-s", "60", "--link", path, NULL};
    ssize_t n;
    pid_t ps;
    (void)state;
    snprintf(path, sizeof path, "%s/link-stale", g_dir);
    snprintf(out, sizeof out, "%s/stale.out", g_dir);
    snprintf(err, sizeof err, "%s/stale.err", g_dir);
    assert_int_equal(symlink("/dev/pts/999999", path), 0);
    ps = qnav_test_spawn(sil, out, err);
    assert_true(ps > 0);
    assert_int_equal(qnav_test_wait_text(out, "link on", QNAV_TEST_WAIT_MS), 0);
    n = readlink(path, target, sizeof target - 1);
    assert_true(n > 9);
    target[n] = '\0';
    assert_string_not_equal(target, "/dev/pts/999999");
    assert_int_equal(strncmp(target, "/dev/pts/", 9), 0);
    assert_int_equal(kill(ps, SIGTERM), 0);
    assert_int_equal(qnav_test_wait_exit(ps), 1);
    assert_int_equal(access(path, F_OK), -1);
    assert_int_equal(readlink(path, target, sizeof target), -1);
}

/* qnav-spy (lcm-spy with the qnav types on OpenJDK 17) under Xvfb, inside a private network
 * namespace during a udpm:// trial: it runs, and decodes every channel of the trial. */
static void test_qnav_spy_under_xvfb_decodes_every_qnav_channel(void **state)
{
    static const char *const channels[] = {"QNAV_SCAN qnav.scan_t ", "QNAV_COMMAND qnav.command_t ",
                                           "QNAV_QUALITIES qnav.path_qualities_t ",
                                           "QNAV_POSE qnav.pose_t ",
                                           "QNAV_LINK_STATUS qnav.link_status_t "};
    char spy_out[300], spy_png[300], text[4096];
    unsigned k, n;
    (void)state;
    if (access(XVFB_EXE, X_OK) != 0) {
        print_message("SKIP: no Xvfb (Debian package xvfb)\n");
        skip();
    }
    snprintf(spy_out, sizeof spy_out, "%s/spy.out", g_dir);
    snprintf(spy_png, sizeof spy_png, "%s/spy.png", g_dir);
    run_udpm_trial(SPY_EXE, "sil=0 navbridge=1 spy=0");
    assert_true(read_text(spy_out, text, sizeof text) > 0);
    print_message("%s", text);
    for (k = 0; k < sizeof channels / sizeof channels[0]; ++k) {
        const char *line = strstr(text, channels[k]);
        assert_non_null(line);
        assert_int_equal(sscanf(line + strlen(channels[k]), "%u", &n), 1);
        assert_true(n > 5u);
    }
    assert_true(read_text(spy_png, text, sizeof text) > 8);
    assert_int_equal(memcmp(text, "\x89PNG", 4), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sil_robot_reaches_destination_through_navbridge_over_memq),
        cmocka_unit_test(test_sil_pioneer3dx_is_driven_by_its_robot_and_refused_by_another),
        cmocka_unit_test(test_sil_robot_onboard_runs_uploaded_policy_and_replays_identically),
        cmocka_unit_test(test_sil_offboard_leaves_a_pocket_as_onboard_does_and_replays_identically),
        cmocka_unit_test(test_sil_board_core_with_a_map_finds_the_far_gap),
        cmocka_unit_test(test_sil_trial_on_udpm_recorded_by_lcm_logger_replays_identically),
        cmocka_unit_test(test_sil_route_of_three_waypoints_through_dense_replays_identically),
        cmocka_unit_test(test_sil_robot_keeps_an_uploaded_policy_in_its_nvm_file),
        cmocka_unit_test(test_sil_robot_refuses_link_path_that_is_a_file),
        cmocka_unit_test(test_sil_robot_leaves_a_file_that_replaced_its_link),
        cmocka_unit_test(test_sil_robot_replaces_stale_pty_link_and_removes_it_at_exit),
        cmocka_unit_test(test_qnav_spy_under_xvfb_decodes_every_qnav_channel),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
