/*
 * navbridge: joins an LCM bus and the serial link to a robot board (or the SIL robot on a
 * pseudo-terminal). Offboard mode runs libqnav here on the board's scans and streams
 * commands back; onboard mode relays goals and telemetry and can upload a policy file to
 * the board. Everything is published on LCM. When the board goes quiet for --timeout-ms
 * it commands a stop; SIGINT/SIGTERM/SIGHUP stop the robot before exiting (status 0); a port that
 * hangs up ends it with status 1 (link lost), and so does a board of another link
 * protocol version (one line saying which). With --robot it runs the controller
 * configuration of that robot's profile and refuses a board whose reported configuration
 * differs (one line naming the field, status 1). --replay re-runs a
 * recorded trial's scans through the controller and checks the commands are identical.
 */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <getopt.h>
#include <limits.h>
#include <math.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#include <lcm/eventlog.h>
#include <lcm/lcm.h>

#include "bridge.h"
#include "qnav/cli.h"
#include "qnav/clock.h"
#include "qnav/policy_io.h"
#include "qnav_goal_t.h"
#include "replay.h"
#include "robot_board.h"
#include "serial.h"

static volatile sig_atomic_t g_stop_signal = 0;

static void on_signal(int sig)
{
    g_stop_signal = sig;
}

static void usage(FILE *f)
{
    fprintf(f,
            "usage: navbridge --device PATH [--baud N] [--lcm-url URL] [--mode offboard|onboard]\n"
            "                 [--policy FILE] [--upload] [--timeout-ms N] [--log FILE]\n"
            "                 [--goal DEG[:METRES] | --goal-at X:Y | --waypoints X:Y,...]\n"
            "                 [--goal-radius M] [--controller NAME] [--robot NAME|FILE]\n"
            "                 [--lcm-goals]\n"
            "       navbridge --replay LOG [--policy FILE] [--controller NAME] [--robot NAME|FILE]\n"
            "  --device PATH      serial port to the board (or the SIL robot's pty)\n"
            "  --baud N           serial rate, default 57600\n"
            "  --lcm-url URL      LCM provider URL, default LCM's own default\n"
            "  --mode M           offboard (bridge runs libqnav, default) or onboard\n"
            "  --policy FILE      policy file; default: hand-tuned probabilistic policy\n"
            "  --controller NAME  offboard controller: body (default), literal, vfh\n"
            "  --robot NAME|FILE  robot profile (data/robots): the controller runs its\n"
            "                     configuration, and a board reporting another is refused\n"
            "  --upload           onboard: upload --policy to the board at start\n"
            "  --timeout-ms N     stop the robot after N ms without scans/heartbeats (300)\n"
            "  --log FILE         also write every published message to an LCM log\n"
            "  --goal DEG[:M]     start with a goal: bearing in the board's heading frame,\n"
            "                     degrees CCW, optional distance in metres\n"
            "  --goal-at X:Y      start with a position goal: metres in the board's odometry\n"
            "                     frame (origin and x axis = its pose at start-up)\n"
            "  --waypoints X:Y,.. start with a route of up to 16 such points; the next is\n"
            "                     sent when the board's pose is within --goal-radius M (0.3)\n"
            "                     of the current one (at most one of --goal, --goal-at,\n"
            "                     --waypoints)\n"
            "  --lcm-goals        also take goals and routes from LCM, on the channels\n"
            "                     QNAV_GOAL_<token> and QNAV_WAYPOINTS_<token> printed at\n"
            "                     start (a new random token each run); without it navbridge\n"
            "                     takes goals only from its command line and does not listen\n"
            "                     on LCM at all (docs/hil.md, \"Who may move the robot\")\n"
            "  --replay LOG       re-run LOG's scans, compare with its commands, exit\n"
            "  --help, --version  this text; the version\n");
}

/* Parse a whole decimal number in [lo, hi]; 0 or -1. */
static int parse_long(const char *s, long lo, long hi, long *out)
{
    char *end = NULL;
    long v;
    errno = 0;
    v = strtol(s, &end, 10);
    if (errno != 0 || end == s || *end != '\0' || v < lo || v > hi) {
        return -1;
    }
    *out = v;
    return 0;
}

/* --waypoints X:Y[,X:Y...] (metres) into w; 0 or -1. */
static int parse_route(const char *s, qnav_waypoints_t *w)
{
    const char *p = s;
    memset(w, 0, sizeof *w);
    for (;;) {
        char *end = NULL;
        double x, y;
        if (w->n >= QNAV_BRIDGE_MAX_WAYPOINTS) {
            return -1;
        }
        x = strtod(p, &end);
        if (end == p || *end != ':') {
            return -1;
        }
        p = end + 1;
        y = strtod(p, &end);
        if (end == p || !(fabs(x) <= 2e6) || !(fabs(y) <= 2e6)) {
            return -1;
        }
        w->x_m[w->n] = x;
        w->y_m[w->n] = y;
        w->n++;
        if (*end == '\0') {
            return 0;
        }
        if (*end != ',') {
            return -1;
        }
        p = end + 1;
    }
}

/* --robot: the board configuration its profile gives. */
typedef struct {
    const char *name;
    qnav_board_config_t expected;
} robot_check_t;

static int check_board_config(void *user, const qnav_link_config_t *m, char *line, size_t len)
{
    return qnav_robot_board_diff(m, &((robot_check_t *)user)->expected, line, len);
}

/* Load --robot into rc and cfg (controller configuration, check); 0 or 2 after one line. */
static int use_robot(const char *spec, robot_check_t *rc, qnav_bridge_config_t *cfg)
{
    char err[QNAV_SIM_ERRLEN];
    qnav_sim_robot_t *robot = NULL;
    if (qnav_sim_robot_load(spec, &robot, err, sizeof err) != QNAV_SIM_OK) {
        fprintf(stderr, "navbridge: --robot: %s\n", err);
        return 2;
    }
    qnav_robot_board_config(robot, &rc->expected);
    qnav_sim_robot_free(robot);
    rc->name = spec;
    cfg->ctrl = rc->expected.ctrl;
    cfg->check_config = check_board_config;
    cfg->check_user = rc;
    return 0;
}

static int write_serial(void *user, const uint8_t *bytes, size_t n)
{
    return qnav_serial_write_all(*(int *)user, bytes, n);
}

int main(int argc, char **argv)
{
    static const struct option opts[] = {
        {"device", required_argument, NULL, 'd'},  {"baud", required_argument, NULL, 'b'},
        {"lcm-url", required_argument, NULL, 'u'}, {"mode", required_argument, NULL, 'm'},
        {"policy", required_argument, NULL, 'p'},  {"upload", no_argument, NULL, 'U'},
        {"timeout-ms", required_argument, NULL, 't'}, {"log", required_argument, NULL, 'l'},
        {"replay", required_argument, NULL, 'r'},  {"help", no_argument, NULL, 'h'},
        {"goal", required_argument, NULL, 'g'},    {"version", no_argument, NULL, 'V'},
        {"goal-at", required_argument, NULL, 'A'}, {"waypoints", required_argument, NULL, 'W'},
        {"goal-radius", required_argument, NULL, 'G'},
        {"controller", required_argument, NULL, 'c'},
        {"robot", required_argument, NULL, 'R'},
        {"lcm-goals", no_argument, NULL, 'L'},
        {NULL, 0, NULL, 0}};
    static robot_check_t robot_check;
    const char *robot_spec = NULL;
    const char *device = NULL, *lcm_url = NULL, *policy_path = NULL, *log_path = NULL;
    const char *replay_path = NULL;
    long baud = 57600, timeout_ms = 300;
    int have_goal = 0, have_route = 0, goal_options = 0, lcm_goals = 0;
    double goal_radius = 0.3;
    qnav_waypoints_t route;
    qnav_goal_t start_goal;
    char err[QNAV_POLICY_IO_ERRLEN];
    qnav_bridge_config_t cfg;
    static qnav_bridge_t bridge;
    lcm_t *lcm;
    lcm_eventlog_t *log = NULL;
    int fd, c, exit_code = 0, hung_up = 0;
    struct sigaction sa;

    qnav_bridge_config_default(&cfg);
    opterr = 0;
    while ((c = getopt_long(argc, argv, "", opts, NULL)) != -1) {
        switch (c) {
        case 'd': device = optarg; break;
        case 'u': lcm_url = optarg; break;
        case 'p': policy_path = optarg; break;
        case 'c':
            if (qnav_nav_find(optarg) == NULL) {
                fprintf(stderr, "navbridge: --controller %s: no such controller (body, literal, vfh)\n",
                        optarg);
                return 2;
            }
            cfg.controller = optarg;
            break;
        case 'l': log_path = optarg; break;
        case 'R': robot_spec = optarg; break;
        case 'r': replay_path = optarg; break;
        case 'U': cfg.upload = 1; break;
        case 'L': lcm_goals = 1; break;
        case 'b':
            if (parse_long(optarg, 1, LONG_MAX, &baud) != 0 || !qnav_serial_baud_ok(baud)) {
                fprintf(stderr, "navbridge: --baud %s: unsupported rate (" QNAV_SERIAL_RATES ")\n",
                        optarg);
                return 2;
            }
            break;
        case 't':
            if (parse_long(optarg, 20, 60000, &timeout_ms) != 0) {
                fprintf(stderr, "navbridge: --timeout-ms %s: expected a whole number of "
                                "milliseconds in 20..60000\n", optarg);
                return 2;
            }
            break;
        case 'm':
            if (strcmp(optarg, "offboard") == 0) {
                cfg.mode = QNAV_LINK_MODE_OFFBOARD;
            } else if (strcmp(optarg, "onboard") == 0) {
                cfg.mode = QNAV_LINK_MODE_ONBOARD;
            } else {
                fprintf(stderr, "navbridge: --mode %s: expected offboard or onboard\n", optarg);
                return 2;
            }
            break;
        case 'g': {
            char *end = NULL;
            double deg = strtod(optarg, &end);
            double dist = 0.0;
            if (end != optarg && *end == ':') {
                char *end2 = NULL;
                dist = strtod(end + 1, &end2);
                end = (end2 == end + 1) ? end : end2;
            }
            if (end == optarg || *end != '\0' || !(deg >= -180.0 && deg <= 180.0) ||
                !(dist >= 0.0 && dist <= 2000.0)) {
                fprintf(stderr, "navbridge: --goal %s: expected DEG[:METRES], DEG in "
                                "-180..180, METRES in 0..2000\n", optarg);
                return 2;
            }
            memset(&start_goal, 0, sizeof start_goal);
            start_goal.goal_id = 1;
            start_goal.bearing_cdeg = (int16_t)(deg >= 180.0 ? -18000 : (int)(deg * 100.0));
            start_goal.distance_mm = (int32_t)(dist * 1000.0);
            have_goal = 1;
            goal_options++;
            break;
        }
        case 'A':
        case 'W':
            if (parse_route(optarg, &route) != 0 || (c == 'A' && route.n != 1)) {
                fprintf(stderr, "navbridge: --%s %s: expected %s in metres in the odometry "
                                "frame, within +-2000 km\n", c == 'A' ? "goal-at" : "waypoints",
                        optarg, c == 'A' ? "X:Y" : "X:Y[,X:Y...] (at most 16)");
                return 2;
            }
            have_route = 1;
            goal_options++;
            break;
        case 'G': {
            char *end = NULL;
            goal_radius = strtod(optarg, &end);
            if (end == optarg || *end != '\0' || !(goal_radius > 0.0 && goal_radius <= 1000.0)) {
                fprintf(stderr, "navbridge: --goal-radius %s: expected metres in (0, 1000]\n",
                        optarg);
                return 2;
            }
            break;
        }
        case 'h': usage(stdout); return 0;
        case 'V': fputs(QNAV_CLI_VERSION_LINE("navbridge"), stdout); return 0;
        default:
            if (optopt != 0 && strncmp(argv[optind - 1], "--", 2) == 0) {
                const struct option *o = opts;
                while (o->name != NULL && o->val != optopt) {
                    ++o;
                }
                fprintf(stderr, "navbridge: --%s: missing its value (see --help)\n",
                        o->name != NULL ? o->name : "?");
            } else {
                fprintf(stderr, "navbridge: %s: unknown option (see --help)\n",
                        argv[optind - 1]);
            }
            return 2;
        }
    }
    if (optind < argc) {
        fprintf(stderr, "navbridge: %s: unexpected argument (see --help)\n", argv[optind]);
        return 2;
    }
    if (goal_options > 1) {
        fprintf(stderr, "navbridge: --goal, --goal-at, --waypoints: give one of them, once "
                        "(the robot would silently follow only the last)\n");
        return 2;
    }
    cfg.timeout_ms = (uint32_t)timeout_ms;
    if (robot_spec != NULL && use_robot(robot_spec, &robot_check, &cfg) != 0) {
        return 2;
    }
    if (policy_path != NULL) {
        if (qnav_policy_read(policy_path, &cfg.policy, err, sizeof err) != 0) {
            fprintf(stderr, "%s\n", err);
            return 2;
        }
    }
    if (cfg.upload && (policy_path == NULL || cfg.mode != QNAV_LINK_MODE_ONBOARD)) {
        fprintf(stderr, "navbridge: --upload: needs --mode onboard and --policy FILE\n");
        return 2;
    }

    if (replay_path != NULL) {
        qnav_replay_result_t res;
        if (qnav_replay_log(replay_path, &cfg.ctrl, cfg.controller, &cfg.policy, &res, stdout, err,
                            sizeof err) != 0) {
            fprintf(stderr, "navbridge: %s\n", err);
            return 2;
        }
        printf("replay: %llu scans, %llu commands compared: %llu identical, %llu differ "
               "(not compared: %llu stops, %llu from another policy)\n",
               (unsigned long long)res.scans, (unsigned long long)res.compared,
               (unsigned long long)res.identical, (unsigned long long)res.differ,
               (unsigned long long)res.stops, (unsigned long long)res.other_policy);
        if (res.compared == 0) {
            fprintf(stderr, "navbridge: %s: no commands answering scans in this log\n",
                    replay_path);
            return 1;
        }
        return res.differ == 0 ? 0 : 1;
    }

    if (device == NULL) {
        fprintf(stderr, "navbridge: --device: required (see --help)\n");
        return 2;
    }
    fd = qnav_serial_open(device, baud, err, sizeof err);
    if (fd < 0) {
        fprintf(stderr, "navbridge: %s\n", err);
        return 2;
    }
    lcm = lcm_create(lcm_url);
    if (lcm == NULL) {
        fprintf(stderr, "navbridge: --lcm-url %s: cannot join the LCM bus\n",
                lcm_url != NULL ? lcm_url : "(default)");
        close(fd);
        return 2;
    }
    if (log_path != NULL) {
        log = lcm_eventlog_create(log_path, "w");
        if (log == NULL) {
            fprintf(stderr, "navbridge: --log %s: %s\n", log_path, strerror(errno));
            lcm_destroy(lcm);
            close(fd);
            return 2;
        }
    }

    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    sigaction(SIGHUP, &sa, NULL); /* a dropped ssh session: stop the robot too */
    signal(SIGPIPE, SIG_IGN);

    qnav_bridge_init(&bridge, &cfg, lcm, log, write_serial, &fd, qnav_mono_ms());
    bridge.diag = stderr;
    if (lcm_goals) {
        char token[QNAV_BRIDGE_TOKEN_HEX + 1];
        if (qnav_bridge_token_make(token, sizeof token) != 0 ||
            qnav_bridge_subscribe(&bridge, token) != 0) {
            fprintf(stderr, "navbridge: --lcm-goals: cannot make a run token and subscribe "
                            "to it: %s\n", strerror(errno));
            exit_code = 1;
        } else {
            /* the operator's tools publish here; a goal on any other channel is ignored */
            printf("navbridge: goals from LCM for this run only: qnav.goal_t on %s, "
                   "qnav.waypoints_t on %s\n", bridge.goal_channel, bridge.route_channel);
            fflush(stdout);
        }
    }
    if (have_goal) {
        start_goal.utime = qnav_bridge_utime();
        qnav_bridge_on_goal(&bridge, &start_goal, qnav_mono_ms());
    }
    if (have_route) {
        route.utime = qnav_bridge_utime();
        route.route_id = 1;
        route.radius_m = goal_radius;
        (void)qnav_bridge_on_waypoints(&bridge, &route, qnav_mono_ms(), err, sizeof err);
    }
    fprintf(stderr, "navbridge: %s mode on %s at %ld baud, watchdog %ld ms\n",
            cfg.mode == QNAV_LINK_MODE_OFFBOARD ? "offboard" : "onboard", device, baud,
            timeout_ms);

    while (exit_code == 0 && !g_stop_signal) {
        struct pollfd p[2];
        /* without --lcm-goals LCM is only written to: asking udpm for its file descriptor
         * would open its receive socket (bound to every address: docs/hil.md) */
        int lfd = lcm_goals ? lcm_get_fileno(lcm) : -1;
        int n;
        p[0].fd = fd;
        p[0].events = POLLIN;
        p[0].revents = 0;
        p[1].fd = lfd;
        p[1].events = POLLIN;
        p[1].revents = 0;
        n = poll(p, 2, 10);
        if (n < 0 && errno != EINTR) {
            fprintf(stderr, "navbridge: poll: %s\n", strerror(errno));
            exit_code = 1;
            break;
        }
        if (n > 0 && (p[0].revents & (POLLIN | POLLHUP | POLLERR))) {
            uint8_t buf[512];
            ssize_t r = read(fd, buf, sizeof buf);
            if (r > 0) {
                qnav_bridge_on_bytes(&bridge, buf, (size_t)r, qnav_mono_ms());
            } else if (r == 0 || (errno != EAGAIN && errno != EINTR)) {
                /* end of file on a serial port: unplugged adapter, or the SIL robot or
                 * simavr board (pty master) has gone */
                fprintf(stderr, "navbridge: %s: %s: link lost\n", device,
                        r == 0 ? "device hung up" : strerror(errno));
                exit_code = 1;
                hung_up = 1;
                break;
            }
        }
        if (n > 0 && (p[1].revents & POLLIN)) {
            bridge.now_ms = qnav_mono_ms();
            lcm_handle_timeout(lcm, 0);
        }
        if (bridge.config_refused) {
            fprintf(stderr, "navbridge: board configuration differs from robot '%s': %s\n",
                    robot_check.name, bridge.config_diff);
            exit_code = 1; /* docs/cli.md: a failure at run time */
            break;
        }
        if (bridge.refused_protocol != 0) {
            fprintf(stderr, "navbridge: %s: the board speaks link protocol %u, this navbridge "
                            "speaks %u: flash firmware of this release or run the navbridge of "
                            "the board's (docs/hil.md, \"Versions\")\n", device,
                    (unsigned)bridge.refused_protocol, (unsigned)QNAV_LINK_PROTOCOL_VERSION);
            exit_code = 1; /* docs/cli.md: a failure at run time */
            break;
        }
        qnav_bridge_poll(&bridge, qnav_mono_ms());
    }
    /* stop the robot before leaving, whatever made us leave */
    qnav_bridge_shutdown(&bridge, qnav_mono_ms());
    if (!hung_up) {
        tcdrain(fd);
    }
    if (g_stop_signal) {
        fprintf(stderr, "navbridge: %s: robot stopped, exiting\n",
                g_stop_signal == SIGINT ? "SIGINT" : g_stop_signal == SIGHUP ? "SIGHUP" : "SIGTERM");
    }
    qnav_bridge_unsubscribe(&bridge);
    if (log != NULL) {
        lcm_eventlog_destroy(log);
    }
    lcm_destroy(lcm);
    close(fd);
    return exit_code;
}
