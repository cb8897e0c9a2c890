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
 * recorded trial's scans through the controller, with the goal distance and previous
 * heading the log records, and checks the commands are identical; it refuses a log whose
 * robot it is not told (status 2).
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

/* The controllers of libqnav's table (qnav/nav.h), ", " between them, the default marked
 * when mark_default: the list is the table's, never a copy. */
static void print_controllers(FILE *f, int mark_default)
{
    uint8_t i;
    for (i = 0; i < qnav_nav_count(); ++i) {
        const char *name = qnav_nav_method_at(i)->name;
        fprintf(f, "%s%s%s", i > 0 ? ", " : "", name,
                mark_default && strcmp(name, QNAV_BRIDGE_DEFAULT_CONTROLLER) == 0 ? " (default)"
                                                                                  : "");
    }
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
            "  --controller NAME  offboard controller: ");
    print_controllers(f, 1);
    fprintf(f,
            "\n"
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
            "  --replay LOG       re-run LOG's scans, compare with its commands, exit;\n"
            "                     needs --robot unless LOG was decided with the default\n"
            "                     configuration (docs/hil.md, \"Record and replay\")\n"
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
    qnav_board_map_info_t expected_map;
} robot_check_t;

static int check_board_config(void *user, const qnav_link_config_t *m, char *line, size_t len)
{
    const robot_check_t *rc = (const robot_check_t *)user;
    return qnav_robot_board_diff(m, &rc->expected, &rc->expected_map, line, len);
}

/* Load --robot into rc and cfg (controller configuration, check); 0 or 2 after one line. */
static int use_robot(const char *spec, robot_check_t *rc, qnav_bridge_config_t *cfg)
{
    char err[QNAV_SIM_ERRLEN];
    if (qnav_robot_board_load(spec, &rc->expected, &rc->expected_map, err, sizeof err) !=
        QNAV_SIM_OK) {
        fprintf(stderr, "navbridge: --robot: %s\n", err);
        return 2;
    }
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

/* Everything the command line says. */
typedef struct {
    const char *robot_spec;
    const char *device;
    const char *lcm_url;
    const char *policy_path;
    const char *log_path;
    const char *replay_path;
    long baud;
    long timeout_ms;
    int have_goal;
    int have_route;
    int goal_options;
    int lcm_goals;
    double goal_radius;
    qnav_waypoints_t route;
    qnav_goal_t start_goal;
    qnav_bridge_config_t cfg;
} options_t;

static const struct option g_opts[] = {
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

/* --goal DEG[:METRES] into o; 0, or 2 after one line. */
static int parse_goal(const char *arg, options_t *o)
{
    char *end = NULL;
    double deg = strtod(arg, &end);
    double dist = 0.0;
    if (end != arg && *end == ':') {
        char *end2 = NULL;
        dist = strtod(end + 1, &end2);
        end = (end2 == end + 1) ? end : end2;
    }
    if (end == arg || *end != '\0' || !(deg >= -180.0 && deg <= 180.0) ||
        !(dist >= 0.0 && dist <= 2000.0)) {
        fprintf(stderr, "navbridge: --goal %s: expected DEG[:METRES], DEG in "
                        "-180..180, METRES in 0..2000\n", arg);
        return 2;
    }
    memset(&o->start_goal, 0, sizeof o->start_goal);
    o->start_goal.goal_id = 1;
    o->start_goal.bearing_cdeg = (int16_t)(deg >= 180.0 ? -18000 : (int)(deg * 100.0));
    o->start_goal.distance_mm = (int32_t)(dist * 1000.0);
    o->have_goal = 1;
    o->goal_options++;
    return 0;
}

/* The options that take a number or a choice (--baud, --timeout-ms, --mode, --controller,
 * --goal-radius) into o; 0, or 2 after one line. */
static int parse_value(int c, const char *arg, options_t *o)
{
    char *end = NULL;
    switch (c) {
    case 'c':
        if (qnav_nav_find(arg) == NULL) {
            fprintf(stderr, "navbridge: --controller %s: no such controller (", arg);
            print_controllers(stderr, 0);
            fprintf(stderr, ")\n");
            return 2;
        }
        o->cfg.controller = arg;
        return 0;
    case 'b':
        if (parse_long(arg, 1, LONG_MAX, &o->baud) != 0 || !qnav_serial_baud_ok(o->baud)) {
            fprintf(stderr, "navbridge: --baud %s: unsupported rate (" QNAV_SERIAL_RATES ")\n",
                    arg);
            return 2;
        }
        return 0;
    case 't':
        if (parse_long(arg, 20, 60000, &o->timeout_ms) != 0) {
            fprintf(stderr, "navbridge: --timeout-ms %s: expected a whole number of "
                            "milliseconds in 20..60000\n", arg);
            return 2;
        }
        return 0;
    case 'm':
        if (strcmp(arg, "offboard") == 0) {
            o->cfg.mode = QNAV_LINK_MODE_OFFBOARD;
        } else if (strcmp(arg, "onboard") == 0) {
            o->cfg.mode = QNAV_LINK_MODE_ONBOARD;
        } else {
            fprintf(stderr, "navbridge: --mode %s: expected offboard or onboard\n", arg);
            return 2;
        }
        return 0;
    default: /* 'G' */
        o->goal_radius = strtod(arg, &end);
        if (end == arg || *end != '\0' || !(o->goal_radius > 0.0 && o->goal_radius <= 1000.0)) {
            fprintf(stderr, "navbridge: --goal-radius %s: expected metres in (0, 1000]\n", arg);
            return 2;
        }
        return 0;
    }
}

/* An option getopt refused: one line naming it. Returns 2. */
static int bad_option(char **argv)
{
    if (optopt != 0 && strncmp(argv[optind - 1], "--", 2) == 0) {
        const struct option *opt = g_opts;
        while (opt->name != NULL && opt->val != optopt) {
            ++opt;
        }
        fprintf(stderr, "navbridge: --%s: missing its value (see --help)\n",
                opt->name != NULL ? opt->name : "?");
    } else {
        fprintf(stderr, "navbridge: %s: unknown option (see --help)\n", argv[optind - 1]);
    }
    return 2;
}

/* One option c (its value in optarg) into o: -1 to go on, else the exit status. */
static int parse_option(int c, char **argv, options_t *o)
{
    switch (c) {
    case 'd': o->device = optarg; break;
    case 'u': o->lcm_url = optarg; break;
    case 'p': o->policy_path = optarg; break;
    case 'l': o->log_path = optarg; break;
    case 'R': o->robot_spec = optarg; break;
    case 'r': o->replay_path = optarg; break;
    case 'U': o->cfg.upload = 1; break;
    case 'L': o->lcm_goals = 1; break;
    case 'c':
    case 'b':
    case 't':
    case 'm':
    case 'G': return parse_value(c, optarg, o) == 0 ? -1 : 2;
    case 'g': return parse_goal(optarg, o) == 0 ? -1 : 2;
    case 'A':
    case 'W':
        if (parse_route(optarg, &o->route) != 0 || (c == 'A' && o->route.n != 1)) {
            fprintf(stderr, "navbridge: --%s %s: expected %s in metres in the odometry "
                            "frame, within +-2000 km\n", c == 'A' ? "goal-at" : "waypoints",
                    optarg, c == 'A' ? "X:Y" : "X:Y[,X:Y...] (at most 16)");
            return 2;
        }
        o->have_route = 1;
        o->goal_options++;
        break;
    case 'h': usage(stdout); return 0;
    case 'V': fputs(QNAV_CLI_VERSION_LINE("navbridge"), stdout); return 0;
    default: return bad_option(argv);
    }
    return -1;
}

/* The whole command line into o (the robot profile and the policy file loaded): -1 to go
 * on, else the exit status. */
static int parse_args(int argc, char **argv, options_t *o, robot_check_t *robot_check)
{
    char err[QNAV_POLICY_IO_ERRLEN];
    int c;
    int rc;
    memset(o, 0, sizeof *o);
    o->baud = 57600;
    o->timeout_ms = 300;
    o->goal_radius = 0.3;
    qnav_bridge_config_default(&o->cfg);
    opterr = 0;
    while ((c = getopt_long(argc, argv, "", g_opts, NULL)) != -1) {
        rc = parse_option(c, argv, o);
        if (rc >= 0) {
            return rc;
        }
    }
    if (optind < argc) {
        fprintf(stderr, "navbridge: %s: unexpected argument (see --help)\n", argv[optind]);
        return 2;
    }
    if (o->goal_options > 1) {
        fprintf(stderr, "navbridge: --goal, --goal-at, --waypoints: give one of them, once "
                        "(the robot would silently follow only the last)\n");
        return 2;
    }
    o->cfg.timeout_ms = (uint32_t)o->timeout_ms;
    if (o->robot_spec != NULL && use_robot(o->robot_spec, robot_check, &o->cfg) != 0) {
        return 2;
    }
    if (o->policy_path != NULL &&
        qnav_policy_read(o->policy_path, &o->cfg.policy, err, sizeof err) != 0) {
        fprintf(stderr, "%s\n", err);
        return 2;
    }
    if (o->cfg.upload && (o->policy_path == NULL || o->cfg.mode != QNAV_LINK_MODE_ONBOARD)) {
        fprintf(stderr, "navbridge: --upload: needs --mode onboard and --policy FILE\n");
        return 2;
    }
    return -1;
}

/* Which configuration replays the log: --robot's, or the built-in default when the log
 * records that its decisions were made with it (QNAV_NAV_INPUT's config_crc). Without
 * --robot, a log that records another configuration or none is refused: a replay with
 * the default would compare against a robot that never drove. 0 to go on, else the exit
 * status after one line. */
static int replay_config_ok(const options_t *o)
{
    uint16_t logged = 0;
    uint16_t ours = qnav_bridge_config_crc(&o->cfg.ctrl, o->cfg.controller);
    int found = qnav_replay_log_config(o->replay_path, &logged);
    if (found < 0) {
        return 0; /* unreadable: qnav_replay_log says why */
    }
    if (o->robot_spec == NULL && found == 0) {
        fprintf(stderr, "navbridge: --replay %s: --robot NAME|FILE missing (the log does not "
                        "record which configuration decided)\n", o->replay_path);
        return 2;
    }
    if (o->robot_spec == NULL && logged != ours) {
        fprintf(stderr, "navbridge: --replay %s: --robot NAME|FILE missing (the log was decided "
                        "with configuration crc 0x%04x, the default is 0x%04x)\n",
                o->replay_path, (unsigned)logged, (unsigned)ours);
        return 2;
    }
    if (found == 1 && logged != ours) {
        fprintf(stderr, "navbridge: --replay %s: decided with configuration crc 0x%04x, "
                        "--robot %s --controller %s gives 0x%04x\n", o->replay_path,
                (unsigned)logged, o->robot_spec, o->cfg.controller, (unsigned)ours);
        return 2;
    }
    return 0;
}

/* navbridge --replay LOG: re-run the log's scans and compare the commands. */
static int run_replay(const options_t *o)
{
    char err[QNAV_POLICY_IO_ERRLEN];
    qnav_replay_result_t res;
    int rc = replay_config_ok(o);
    if (rc != 0) {
        return rc;
    }
    if (qnav_replay_log(o->replay_path, &o->cfg.ctrl, o->cfg.controller, &o->cfg.policy, &res,
                        stdout, err, sizeof err) != 0) {
        fprintf(stderr, "navbridge: %s\n", err);
        return 2;
    }
    printf("replay: %llu scans, %llu commands compared: %llu identical, %llu differ "
           "(not compared: %llu stops, %llu from another policy); %llu scans with their "
           "logged goal distance and previous heading\n",
           (unsigned long long)res.scans, (unsigned long long)res.compared,
           (unsigned long long)res.identical, (unsigned long long)res.differ,
           (unsigned long long)res.stops, (unsigned long long)res.other_policy,
           (unsigned long long)res.with_input);
    if (res.bad_events > 0) {
        fprintf(stderr, "navbridge: %s: %llu events on qnav channels did not decode (a log "
                        "recorded with other LCM types: those events are not replayed)\n",
                o->replay_path, (unsigned long long)res.bad_events);
    }
    if (res.compared == 0) {
        fprintf(stderr, "navbridge: %s: no commands answering scans in this log\n",
                o->replay_path);
        return 1;
    }
    return res.differ == 0 ? 0 : 1;
}

/* The bridge's ends: the serial port, the LCM bus, the optional log. */
typedef struct {
    int fd;
    lcm_t *lcm;
    lcm_eventlog_t *log;
    int hung_up;
} links_t;

/* Open the port, join the bus, open the log; 0, or 2 after one line (nothing left open). */
static int open_links(const options_t *o, links_t *l)
{
    char err[QNAV_POLICY_IO_ERRLEN];
    memset(l, 0, sizeof *l);
    if (o->device == NULL) {
        fprintf(stderr, "navbridge: --device: required (see --help)\n");
        return 2;
    }
    l->fd = qnav_serial_open(o->device, o->baud, err, sizeof err);
    if (l->fd < 0) {
        fprintf(stderr, "navbridge: %s\n", err);
        return 2;
    }
    l->lcm = lcm_create(o->lcm_url);
    if (l->lcm == NULL) {
        fprintf(stderr, "navbridge: --lcm-url %s: cannot join the LCM bus\n",
                o->lcm_url != NULL ? o->lcm_url : "(default)");
        close(l->fd);
        return 2;
    }
    if (o->log_path != NULL) {
        l->log = lcm_eventlog_create(o->log_path, "w");
        if (l->log == NULL) {
            fprintf(stderr, "navbridge: --log %s: %s\n", o->log_path, strerror(errno));
            lcm_destroy(l->lcm);
            close(l->fd);
            return 2;
        }
    }
    return 0;
}

static void catch_signals(void)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    sigaction(SIGHUP, &sa, NULL); /* a dropped ssh session: stop the robot too */
    signal(SIGPIPE, SIG_IGN);
}

/* --lcm-goals and the command line's goal or route, once the bridge runs: 0, or the exit
 * status after one line. */
static int start_goals(options_t *o, qnav_bridge_t *bridge)
{
    char err[QNAV_POLICY_IO_ERRLEN];
    int exit_code = 0;
    if (o->lcm_goals) {
        char token[QNAV_BRIDGE_TOKEN_HEX + 1];
        if (qnav_bridge_token_make(token, sizeof token) != 0 ||
            qnav_bridge_subscribe(bridge, token) != 0) {
            fprintf(stderr, "navbridge: --lcm-goals: cannot make a run token and subscribe "
                            "to it: %s\n", strerror(errno));
            exit_code = 1;
        } else {
            /* the operator's tools publish here; a goal on any other channel is ignored */
            printf("navbridge: goals from LCM for this run only: qnav.goal_t on %s, "
                   "qnav.waypoints_t on %s\n", bridge->goal_channel, bridge->route_channel);
            fflush(stdout);
        }
    }
    if (o->have_goal) {
        o->start_goal.utime = qnav_bridge_utime();
        qnav_bridge_on_goal(bridge, &o->start_goal, qnav_mono_ms());
    }
    if (o->have_route) {
        o->route.utime = qnav_bridge_utime();
        o->route.route_id = 1;
        o->route.radius_m = o->goal_radius;
        /* parse_route's bounds are the bridge's: a refusal here is a bug, said as such */
        if (qnav_bridge_on_waypoints(bridge, &o->route, qnav_mono_ms(), err, sizeof err) != 0) {
            fprintf(stderr, "navbridge: --waypoints: %s\n", err);
            exit_code = 2;
        }
    }
    return exit_code;
}

/* Read the port when it has bytes: 0, or 1 when the link is lost (one line said). */
static int read_port(const options_t *o, links_t *l, qnav_bridge_t *bridge)
{
    uint8_t buf[512];
    ssize_t r = read(l->fd, buf, sizeof buf);
    if (r > 0) {
        qnav_bridge_on_bytes(bridge, buf, (size_t)r, qnav_mono_ms());
    } else if (r == 0 || (errno != EAGAIN && errno != EINTR)) {
        /* end of file on a serial port: unplugged adapter, or the SIL robot or simavr
         * board (pty master) has gone */
        fprintf(stderr, "navbridge: %s: %s: link lost\n", o->device,
                r == 0 ? "device hung up" : strerror(errno));
        l->hung_up = 1;
        return 1;
    }
    return 0;
}

/* A board the bridge refused (another configuration, another protocol): 1 after one
 * line (docs/cli.md: a failure at run time), else 0. */
static int board_refused(const options_t *o, const qnav_bridge_t *bridge,
                         const robot_check_t *robot_check)
{
    if (bridge->config_refused) {
        fprintf(stderr, "navbridge: board configuration differs from robot '%s': %s\n",
                robot_check->name, bridge->config_diff);
        return 1;
    }
    if (bridge->refused_protocol != 0) {
        fprintf(stderr, "navbridge: %s: the board speaks link protocol %u, this navbridge "
                        "speaks %u: flash firmware of this release or run the navbridge of "
                        "the board's (docs/hil.md, \"Versions\")\n", o->device,
                (unsigned)bridge->refused_protocol, (unsigned)QNAV_LINK_PROTOCOL_VERSION);
        return 1;
    }
    return 0;
}

/* Until a signal, a lost link or a refused board: port and bus in, the bridge's periodic
 * work out. Returns the exit status. */
static int bridge_loop(const options_t *o, links_t *l, qnav_bridge_t *bridge,
                       const robot_check_t *robot_check)
{
    while (!g_stop_signal) {
        struct pollfd p[2];
        int n;
        p[0].fd = l->fd;
        p[0].events = POLLIN;
        p[0].revents = 0;
        /* without --lcm-goals LCM is only written to: asking udpm for its file descriptor
         * would open its receive socket (bound to every address: docs/hil.md) */
        p[1].fd = o->lcm_goals ? lcm_get_fileno(l->lcm) : -1;
        p[1].events = POLLIN;
        p[1].revents = 0;
        n = poll(p, 2, 10);
        if (n < 0 && errno != EINTR) {
            fprintf(stderr, "navbridge: poll: %s\n", strerror(errno));
            return 1;
        }
        if (n > 0 && (p[0].revents & (POLLIN | POLLHUP | POLLERR)) && read_port(o, l, bridge)) {
            return 1;
        }
        if (n > 0 && (p[1].revents & POLLIN)) {
            bridge->now_ms = qnav_mono_ms();
            lcm_handle_timeout(l->lcm, 0);
        }
        if (board_refused(o, bridge, robot_check)) {
            return 1;
        }
        qnav_bridge_poll(bridge, qnav_mono_ms());
    }
    return 0;
}

/* navbridge --device PATH: bridge the board and the bus until told to stop; the robot is
 * stopped before it returns, whatever made it stop. */
static int run_bridge(options_t *o, const robot_check_t *robot_check)
{
    static qnav_bridge_t bridge;
    links_t l;
    int exit_code = open_links(o, &l);
    if (exit_code != 0) {
        return exit_code;
    }
    catch_signals();
    qnav_bridge_init(&bridge, &o->cfg, l.lcm, l.log, write_serial, &l.fd, qnav_mono_ms());
    bridge.diag = stderr;
    exit_code = start_goals(o, &bridge);
    fprintf(stderr, "navbridge: %s mode on %s at %ld baud, watchdog %ld ms\n",
            o->cfg.mode == QNAV_LINK_MODE_OFFBOARD ? "offboard" : "onboard", o->device,
            o->baud, o->timeout_ms);
    if (exit_code == 0) {
        exit_code = bridge_loop(o, &l, &bridge, robot_check);
    }
    qnav_bridge_shutdown(&bridge, qnav_mono_ms());
    if (!l.hung_up) {
        tcdrain(l.fd);
    }
    if (g_stop_signal) {
        fprintf(stderr, "navbridge: %s: robot stopped, exiting\n",
                g_stop_signal == SIGINT ? "SIGINT" : g_stop_signal == SIGHUP ? "SIGHUP" : "SIGTERM");
    }
    qnav_bridge_unsubscribe(&bridge);
    if (l.log != NULL) {
        lcm_eventlog_destroy(l.log);
    }
    lcm_destroy(l.lcm);
    close(l.fd);
    return exit_code;
}

int main(int argc, char **argv)
{
    static options_t o;
    static robot_check_t robot_check;
    int rc = parse_args(argc, argv, &o, &robot_check);
    if (rc >= 0) {
        return rc;
    }
    return o.replay_path != NULL ? run_replay(&o) : run_bridge(&o, &robot_check);
}
