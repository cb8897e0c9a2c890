/*
 * qnav-sil-robot: software in the loop. The board core (firmware/boards/core, the code the
 * TekBot runs) plays the robot board on a pseudo-terminal with the Box2D simulator as its
 * hardware (sil_hal.c), so that simulator -> board core -> link -> navbridge -> LCM runs
 * on one machine without hardware. Each 0.1 s simulated tick the core senses, decides
 * (onboard) or applies navbridge's last command (offboard), drives and reports, then the
 * simulation advances. With --lockstep it waits for navbridge's answer to each scan
 * instead of the wall clock, so a trial runs as fast as the bridge answers and is
 * repeatable. --playback LOG replays a recorded scan stream (e.g. the simavr board's)
 * into the same core instead of the simulator. --nvm FILE is the board's EEPROM.
 */
#define _XOPEN_SOURCE 700
#define _DEFAULT_SOURCE
#include <errno.h>
#include <fcntl.h>
#include <getopt.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#include <lcm/lcm.h>

#include "ptylink.h"
#include "qnav/board.h"
#include "qnav/cli.h"
#include "qnav/clock.h"
#include "qnav/sim.h"
#include "qnav_pose_t.h"
#include "robot_board.h"
#include "sil_hal.h"

static volatile sig_atomic_t g_quit = 0;

static void on_signal(int sig)
{
    g_quit = sig;
}

typedef struct {
    const char *robot, *env, *link, *lcm_url, *nvm, *playback;
    double sectors, seed, episode, noise, reply_ms, wait_s, tick_ms;
    int lockstep, pose, have_start;
    double start_x, start_y, start_deg;
} options_t;

static void usage(FILE *f)
{
    fprintf(f,
            "usage: qnav-sil-robot [--robot NAME|FILE] [--env NAME|FILE] [--sectors N]\n"
            "                      [--seed N] [--episode N] [--noise P] [--link PATH]\n"
            "                      [--start X:Y:DEG] [--nvm FILE] [--playback LOG]\n"
            "                      [--lockstep | --tick-ms N] [--reply-ms N] [--wait-s N]\n"
            "                      [--lcm-url URL | --pose]\n"
            "  --robot, --env   robot profile and environment (tekbot, open): the board\n"
            "                   core runs the configuration generated from the profile,\n"
            "                   and plans position goals over a map when it has a [map]\n"
            "                   (not with --playback)\n"
            "  --sectors N      sonar sectors (0 = the profile's default)\n"
            "  --seed, --episode  simulator seed and episode seed (1, 1)\n"
            "  --noise P        sensor, actuation and wheel-slip (odometry) noise level p (0)\n"
            "  --link PATH      also make PATH a symlink to the pty (for navbridge --device)\n"
            "  --start X:Y:DEG  start pose in the world frame (m, m, deg CCW from +x) instead\n"
            "                   of a random one from the environment's start zones\n"
            "  --nvm FILE       the board's non-volatile storage (made erased if absent);\n"
            "                   default: RAM only\n"
            "  --playback LOG   feed the QNAV_SCAN stream of an LCM log to the board core\n"
            "                   (recorded with --robot's configuration) instead of the\n"
            "                   simulator\n"
            "  --lockstep       wait for each reply instead of the 0.1 s wall clock\n"
            "  --tick-ms N      wall-clock period of a 0.1 s simulated tick (100; smaller\n"
            "                   runs faster than real time)\n"
            "  --reply-ms N     longest wait for the bridge's command each tick (300)\n"
            "  --wait-s N       how long to wait for navbridge to appear (30)\n"
            "  --pose           publish the true QNAV_POSE on LCM's default bus; --lcm-url on\n"
            "                   URL\n"
            "  --help, --version  this text; the version\n");
}

static int parse_num(const char *opt, const char *s, double lo, double hi, double *out)
{
    char *end = NULL;
    double v;
    errno = 0;
    v = strtod(s, &end);
    if (errno != 0 || end == s || *end != '\0' || !(v >= lo && v <= hi)) {
        fprintf(stderr, "qnav-sil-robot: --%s %s: expected a number in %g..%g\n", opt, s, lo,
                hi);
        return -1;
    }
    *out = v;
    return 0;
}

static int parse_start(const char *s, options_t *o)
{
    char tail;
    if (sscanf(s, "%lf:%lf:%lf%c", &o->start_x, &o->start_y, &o->start_deg, &tail) != 3 ||
        !isfinite(o->start_x) || !isfinite(o->start_y) || !isfinite(o->start_deg)) {
        fprintf(stderr, "qnav-sil-robot: --start %s: expected X:Y:DEG (metres, metres, "
                        "degrees)\n", s);
        return -1;
    }
    o->have_start = 1;
    return 0;
}

/* Options into o; 0 to run, 1 when --help/--version printed, 2 on bad usage. */
static int parse_options(int argc, char **argv, options_t *o)
{
    static const struct option opts[] = {
        {"robot", required_argument, NULL, 'r'},   {"env", required_argument, NULL, 'e'},
        {"sectors", required_argument, NULL, 'n'}, {"seed", required_argument, NULL, 's'},
        {"episode", required_argument, NULL, 'E'}, {"noise", required_argument, NULL, 'p'},
        {"link", required_argument, NULL, 'l'},    {"lockstep", no_argument, NULL, 'L'},
        {"reply-ms", required_argument, NULL, 'R'}, {"wait-s", required_argument, NULL, 'w'},
        {"lcm-url", required_argument, NULL, 'u'}, {"pose", no_argument, NULL, 'P'},
        {"tick-ms", required_argument, NULL, 'T'}, {"nvm", required_argument, NULL, 'N'},
        {"playback", required_argument, NULL, 'B'}, {"start", required_argument, NULL, 'S'},
        {"help", no_argument, NULL, 'h'},          {"version", no_argument, NULL, 'V'},
        {NULL, 0, NULL, 0}};
    int c;
    memset(o, 0, sizeof *o);
    o->robot = "tekbot";
    o->env = "open";
    o->seed = o->episode = 1;
    o->reply_ms = 300;
    o->wait_s = 30;
    o->tick_ms = 100;
    opterr = 0;
    while ((c = getopt_long(argc, argv, "", opts, NULL)) != -1) {
        switch (c) {
        case 'r': o->robot = optarg; break;
        case 'e': o->env = optarg; break;
        case 'l': o->link = optarg; break;
        case 'u': o->lcm_url = optarg; o->pose = 1; break;
        case 'P': o->pose = 1; break;
        case 'L': o->lockstep = 1; break;
        case 'N': o->nvm = optarg; break;
        case 'B': o->playback = optarg; break;
        case 'S': if (parse_start(optarg, o)) return 2; break;
        case 'n': if (parse_num("sectors", optarg, 0, 360, &o->sectors)) return 2; break;
        case 's': if (parse_num("seed", optarg, 0, 1e15, &o->seed)) return 2; break;
        case 'E': if (parse_num("episode", optarg, 0, 1e15, &o->episode)) return 2; break;
        case 'p': if (parse_num("noise", optarg, 0, 1, &o->noise)) return 2; break;
        case 'R': if (parse_num("reply-ms", optarg, 1, 60000, &o->reply_ms)) return 2; break;
        case 'w': if (parse_num("wait-s", optarg, 0, 3600, &o->wait_s)) return 2; break;
        case 'T': if (parse_num("tick-ms", optarg, 1, 10000, &o->tick_ms)) return 2; break;
        case 'h': usage(stdout); return 1;
        case 'V': fputs(QNAV_CLI_VERSION_LINE("qnav-sil-robot"), stdout); return 1;
        default:
            fprintf(stderr, "qnav-sil-robot: %s: unknown option or missing value (see --help)\n",
                    argv[optind - 1]);
            return 2;
        }
    }
    if (optind < argc) {
        fprintf(stderr, "qnav-sil-robot: %s: unexpected argument (see --help)\n", argv[optind]);
        return 2;
    }
    return 0;
}

/* The board configuration: the one generated from the robot's profile (the simulator's
 * sector count when --sectors overrides the profile's). A playback must be a recording of
 * that robot: 0, or -1 after one line naming the field that differs. */
static int board_config(const options_t *o, const qnav_sim_robot_t *robot, qnav_sim_t *sim,
                        const sil_hal_t *hal, qnav_board_config_t *bc)
{
    qnav_robot_board_config(robot, bc);
    if (sim != NULL) {
        qnav_sim_ctrl_config(sim, &bc->ctrl);
        return 0;
    }
    if (o->sectors > 0) {
        bc->ctrl.n_sectors = (uint16_t)o->sectors;
    }
    if (hal->playback[0].n_sectors != bc->ctrl.n_sectors ||
        hal->playback[0].max_range_mm != bc->ctrl.max_range_mm) {
        int sectors = hal->playback[0].n_sectors != bc->ctrl.n_sectors;
        fprintf(stderr, "qnav-sil-robot: --playback %s: recorded scans differ from robot '%s': "
                        "%s %u != %u\n", o->playback, o->robot,
                sectors ? "n_sectors" : "max_range_mm",
                sectors ? (unsigned)hal->playback[0].n_sectors
                        : (unsigned)hal->playback[0].max_range_mm,
                sectors ? (unsigned)bc->ctrl.n_sectors : (unsigned)bc->ctrl.max_range_mm);
        return -1;
    }
    return 0;
}

/* The pty, raw from the start; the slave stays open so the master never sees EIO while
 * navbridge is not (yet) attached. Returns the master or -1; *slave its name. */
static int open_pty(char **slave)
{
    struct termios tio;
    int slave_keep;
    int fd = posix_openpt(O_RDWR | O_NOCTTY);
    if (fd < 0 || grantpt(fd) != 0 || unlockpt(fd) != 0 || (*slave = ptsname(fd)) == NULL) {
        fprintf(stderr, "qnav-sil-robot: cannot create a pseudo-terminal: %s\n",
                strerror(errno));
        return -1;
    }
    slave_keep = open(*slave, O_RDWR | O_NOCTTY);
    if (slave_keep >= 0 && tcgetattr(slave_keep, &tio) == 0) {
        cfmakeraw(&tio);
        tcsetattr(slave_keep, TCSANOW, &tio);
    }
    fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) | O_NONBLOCK);
    return fd;
}

/* Receive for up to wait_ms, handing every byte to the board core. */
static void pump(qnav_board_t *bot, sil_hal_t *hal, int wait_ms)
{
    int64_t until = qnav_mono_ms() + wait_ms;
    do {
        (void)sil_hal_wait_rx(hal, (int)(until - qnav_mono_ms()));
        qnav_board_receive(bot);
    } while (!g_quit && qnav_mono_ms() < until);
}

static void publish_true_pose(lcm_t *lcm, qnav_sim_t *sim)
{
    qnav_sim_state_t st;
    qnav_pose_t ps;
    qnav_sim_state(sim, &st);
    memset(&ps, 0, sizeof ps);
    ps.utime = qnav_wall_us();
    ps.tick = (int32_t)st.tick;
    ps.x_m = st.x_m;
    ps.y_m = st.y_m;
    ps.heading_deg = st.heading_rad * 180.0 / M_PI;
    ps.speed_mps = st.speed_mps;
    ps.goal_distance_m = st.goal_distance_m;
    ps.recovering = st.recovering;
    ps.collisions = (int32_t)st.collisions;
    ps.reached = st.reached;
    qnav_pose_t_publish(lcm, "QNAV_POSE", &ps);
}

typedef struct {
    qnav_board_t bot;
    sil_hal_t hal;
    qnav_sim_t *sim;
    lcm_t *lcm;
    qnav_map_t map;           /* the board core's map, with a profile's [map] */
    qnav_map_config_t map_cfg; /* its configuration (a board placing maps keeps a pointer) */
    void *map_mem;
    uint32_t missed;          /* offboard ticks whose scan got no answer within reply_ms */
    uint32_t ticks;
} robot_t;

/* One simulated tick: the board core's tick, the wait for navbridge's answer (lockstep or
 * paced), the simulator step with the core's drive. */
static void run_tick(robot_t *r, const options_t *o)
{
    int64_t tick_start = qnav_mono_ms();
    uint32_t cmds = qnav_board_stats(&r->bot)->commands;
    uint16_t seq;
    int answered = 0;
    qnav_board_receive(&r->bot);
    qnav_board_tick(&r->bot);
    seq = qnav_board_stats(&r->bot)->last_scan_seq;
    if (r->bot.mode == QNAV_LINK_MODE_OFFBOARD) {
        /* the answer to this scan: the core drives with it from the next tick on */
        while (!g_quit && qnav_mono_ms() - tick_start < (int64_t)o->reply_ms && !answered) {
            pump(&r->bot, &r->hal, 5);
            answered = qnav_board_stats(&r->bot)->commands != cmds &&
                       qnav_board_stats(&r->bot)->last_command_seq == seq;
        }
        r->missed += !answered;
    }
    if (r->sim != NULL) {
        qnav_ctrl_output_t out;
        memset(&out, 0, sizeof out);
        out.heading_deg = r->hal.drive_heading;
        out.speed = r->hal.drive_speed;
        qnav_sim_command(r->sim, &out);
        qnav_sim_advance(r->sim);
        if (r->lcm != NULL) {
            publish_true_pose(r->lcm, r->sim);
        }
    } else {
        r->hal.playback_i++;
    }
    r->ticks++;
    if (!o->lockstep) {
        int64_t left = tick_start + (int64_t)o->tick_ms - qnav_mono_ms();
        if (left > 0) {
            pump(&r->bot, &r->hal, (int)left);
        }
    }
}

/* Where the destination is for navbridge (--goal-at), in the odometry frame. */
static void print_destination(robot_t *r, qnav_sim_env_t *env)
{
    qnav_sim_env_info_t ei;
    double x, y;
    if (r->sim == NULL) {
        return;
    }
    qnav_sim_env_info(env, &ei);
    sil_hal_world_to_odometry(&r->hal, ei.dest_x_m, ei.dest_y_m, &x, &y);
    printf("qnav-sil-robot: destination at %.3f:%.3f m in the odometry frame (navbridge "
           "--goal-at %.3f:%.3f)\n", x / 1000.0, y / 1000.0, x / 1000.0, y / 1000.0);
}

/* A profile with a [map] gives the board core a map, marked from the board's own dead
 * reckoning. With [map] bytes, as the board made from the profile runs it: those bytes,
 * placed at each position goal (qnav_board_place_maps). Without, as a board with the memory
 * for one would: over the arena's bounding box in the odometry frame (plus 1 m for drift;
 * qnav_board_set_map). 0, or 2 after one line when the area needs more cells than a map
 * holds. */
static int board_map(robot_t *r, const options_t *o, const qnav_sim_robot_t *robot,
                     qnav_sim_env_t *env, const qnav_board_config_t *bc)
{
    qnav_map_config_t mc;
    qnav_sim_env_info_t ei;
    double x0 = 1e12, y0 = 1e12, x1 = -1e12, y1 = -1e12;
    uint32_t cells, w_mm, h_mm;
    size_t bytes;
    int k;
    if (r->sim == NULL || !qnav_sim_robot_map_config(robot, &mc)) {
        return 0;
    }
    /* the profile's, as the board's header has it (the sonar's range noise it assumes) */
    r->map_cfg = mc;
    bytes = qnav_sim_robot_map_bytes(robot);
    if (bytes != 0u) {
        r->map_mem = malloc(bytes);
        if (r->map_mem == NULL ||
            !qnav_board_place_maps(&r->bot, &r->map, &r->map_cfg, r->map_mem, bytes)) {
            fprintf(stderr, "qnav-sil-robot: --robot %s: the board core cannot keep a map of "
                            "%lu bytes\n", o->robot, (unsigned long)bytes);
            return 2;
        }
        fprintf(stderr, "qnav-sil-robot: the board core places a map of %u mm cells in %lu "
                        "bytes at each position goal\n", (unsigned)mc.cell_mm, (unsigned long)bytes);
        return 0;
    }
    qnav_sim_env_info(env, &ei);
    for (k = 0; k < 4; ++k) {
        double x, y;
        sil_hal_world_to_odometry(&r->hal, (k & 1) ? ei.width_m : 0.0, (k & 2) ? ei.height_m : 0.0,
                                  &x, &y);
        x0 = fmin(x0, x - 1000.0);
        y0 = fmin(y0, y - 1000.0);
        x1 = fmax(x1, x + 1000.0);
        y1 = fmax(y1, y + 1000.0);
    }
    w_mm = (uint32_t)ceil(x1 - x0);
    h_mm = (uint32_t)ceil(y1 - y0);
    cells = qnav_map_cells(w_mm, h_mm, mc.cell_mm);
    if (cells == 0u) {
        fprintf(stderr, "qnav-sil-robot: --robot %s: [map] cells of %u mm over %.1f x %.1f m "
                        "are more than a map holds (65 000); use larger cells\n",
                o->robot, (unsigned)mc.cell_mm, w_mm / 1000.0, h_mm / 1000.0);
        return 2;
    }
    bytes = qnav_map_size(&mc, w_mm, h_mm);
    r->map_mem = malloc(bytes);
    if (r->map_mem == NULL ||
        qnav_map_init(&r->map, &mc, &bc->ctrl, (int32_t)floor(x0), (int32_t)floor(y0), w_mm,
                      h_mm, r->map_mem, bytes) != QNAV_OK ||
        !qnav_board_set_map(&r->bot, &r->map)) {
        fprintf(stderr, "qnav-sil-robot: --robot %s: the board core cannot keep a map of %lu "
                        "bytes\n", o->robot, (unsigned long)bytes);
        return 2;
    }
    fprintf(stderr, "qnav-sil-robot: the board core plans over a map of %u mm cells, %.1f x "
                    "%.1f m of the odometry frame (%lu bytes)\n",
            (unsigned)mc.cell_mm, w_mm / 1000.0, h_mm / 1000.0, (unsigned long)bytes);
    return 0;
}

/* Simulator (or playback), board core and pty up; 0 or an exit status. */
static int start(robot_t *r, const options_t *o, qnav_sim_robot_t **robot,
                 qnav_sim_env_t **env, char **slave)
{
    char err[QNAV_SIM_ERRLEN];
    qnav_sim_config_t scfg;
    qnav_board_config_t bc;
    qnav_board_hal_t hal;
    if (qnav_sim_robot_load(o->robot, robot, err, sizeof err) != QNAV_SIM_OK) {
        fprintf(stderr, "%s\n", err);
        return 2;
    }
    if (o->playback != NULL) {
        if (sil_hal_load_playback(&r->hal, o->playback, err, sizeof err) != 0) {
            fprintf(stderr, "qnav-sil-robot: %s\n", err);
            return 2;
        }
    } else {
        if (qnav_sim_env_load(o->env, env, err, sizeof err) != QNAV_SIM_OK) {
            fprintf(stderr, "%s\n", err);
            return 2;
        }
        qnav_sim_config_default(&scfg);
        scfg.n_sectors = (uint16_t)o->sectors;
        scfg.sensor_noise = o->noise;
        scfg.actuation_noise = o->noise;
        scfg.seed = (uint64_t)o->seed;
        scfg.map_frame_deg = 0.0; /* the simulator's own map guides nothing here: the board
                                     core's does, in the frame of the robot's start */
        if (qnav_sim_create(*robot, *env, &scfg, &r->sim, err, sizeof err) != QNAV_SIM_OK ||
            qnav_sim_reset(r->sim, (uint64_t)o->episode) != QNAV_SIM_OK ||
            (o->have_start && qnav_sim_place(r->sim, o->start_x, o->start_y,
                                             o->start_deg * M_PI / 180.0) != QNAV_SIM_OK)) {
            fprintf(stderr, "qnav-sil-robot: %s\n",
                    r->sim != NULL && o->have_start ? "--start: outside the arena" : err);
            return 2;
        }
    }
    r->hal.sim = r->sim;
    r->hal.nvm_path = o->nvm;
    r->hal.odo_noise = o->noise;
    r->hal.rng = 0x9E3779B97F4A7C15ULL ^ (uint64_t)o->seed; /* never 0 for xorshift */
    r->hal.fd = open_pty(slave);
    if (r->hal.fd < 0) {
        return 2;
    }
    if (board_config(o, *robot, r->sim, &r->hal, &bc) != 0) {
        return 2;
    }
    r->hal.track_m = bc.track_mm / 1000.0;
    r->hal.um_per_count = bc.um_per_count;
    if (sil_hal_init(&r->hal, &hal, err, sizeof err) != 0) {
        fprintf(stderr, "qnav-sil-robot: %s\n", err);
        return 2;
    }
    sil_hal_start_odometry(&r->hal);
    if (qnav_board_init(&r->bot, &bc, &hal) != QNAV_BOARD_OK) {
        fprintf(stderr, "qnav-sil-robot: the board core refused its configuration\n");
        return 2;
    }
    if (board_map(r, o, *robot, *env, &bc) != 0) {
        return 2;
    }
    fprintf(stderr, "qnav-sil-robot: running the %s policy (crc 0x%04x)\n",
            qnav_board_policy_source(&r->bot) == QNAV_BOARD_POLICY_STORED ? "stored"
                                                                         : "built-in",
            r->bot.policy_crc);
    return 0;
}

/* Wait for navbridge: its heartbeats tell the mode. 0, or 1 (docs/cli.md: the trial
 * failed) when none came or it speaks another protocol. */
static int wait_bridge(robot_t *r, const options_t *o, const char *slave)
{
    int64_t t0 = qnav_mono_ms();
    while (!g_quit && r->bot.mode == 0 && qnav_mono_ms() - t0 < (int64_t)(o->wait_s * 1000.0)) {
        pump(&r->bot, &r->hal, 50);
        if (qnav_board_stats(&r->bot)->peer_refused > 0u) {
            fprintf(stderr, "qnav-sil-robot: navbridge on %s speaks link protocol %u, this "
                            "board %u: not following it\n", slave,
                    (unsigned)qnav_board_stats(&r->bot)->peer_protocol,
                    (unsigned)QNAV_LINK_PROTOCOL_VERSION);
            return 1;
        }
    }
    if (r->bot.mode == 0) {
        fprintf(stderr, "qnav-sil-robot: no navbridge heartbeat on %s within %g s\n", slave,
                o->wait_s);
        return 1;
    }
    return 0;
}

static int report(robot_t *r)
{
    qnav_sim_result_t res;
    const qnav_board_pose_t *p = qnav_board_pose(&r->bot);
    if (r->sim == NULL) {
        printf("qnav-sil-robot: playback %s: %u scans, %u ticks without a command, %lu link "
               "frames dropped\n", g_quit ? "interrupted" : "done", (unsigned)r->ticks,
               (unsigned)r->missed, (unsigned long)qnav_link_rx_dropped_total(&r->bot.rx));
        fflush(stdout);
        return g_quit ? 1 : 0;
    }
    qnav_sim_state_t st;
    double tx, ty;
    qnav_sim_result(r->sim, &res);
    qnav_sim_state(r->sim, &st);
    sil_hal_world_to_odometry(&r->hal, st.x_m, st.y_m, &tx, &ty);
    printf("qnav-sil-robot: %s: reached %s, %u ticks (%.1f s), %u collisions, "
           "R = %.3f, %u ticks without a command, %lu link frames dropped, odometry "
           "%.3f:%.3f m (true %.3f:%.3f m)\n",
           g_quit ? "interrupted" : "episode done", res.reached ? "yes" : "no",
           (unsigned)res.ticks, res.tau_l, (unsigned)res.collisions, res.R,
           (unsigned)r->missed, (unsigned long)qnav_link_rx_dropped_total(&r->bot.rx),
           p->x_um / 1e6, p->y_um / 1e6, tx / 1000.0, ty / 1000.0);
    fflush(stdout);
    return res.reached && !g_quit ? 0 : 1; /* docs/cli.md: 1 = the trial failed */
}

static int episode_over(robot_t *r)
{
    qnav_sim_state_t st;
    if (r->sim == NULL) {
        return r->hal.playback_i >= r->hal.playback_n;
    }
    qnav_sim_state(r->sim, &st);
    return st.done;
}

int main(int argc, char **argv)
{
    options_t o;
    static robot_t r;
    qnav_sim_robot_t *robot = NULL;
    qnav_sim_env_t *env = NULL;
    char *slave = NULL;
    char err[256];
    struct sigaction sa;
    int linked = 0;
    int rc = parse_options(argc, argv, &o);
    if (rc != 0) {
        return rc == 1 ? 0 : rc;
    }
    rc = start(&r, &o, &robot, &env, &slave);
    if (rc == 0) {
        /* the destination line is out before the link exists, so a caller that waits for
         * the link (or for "link on") finds it already written (issue 20's race) */
        print_destination(&r, env);
        fflush(stdout);
    }
    if (rc == 0 && o.link != NULL) {
        if (qnav_ptylink_make(o.link, slave, err, sizeof err) != 0) {
            fprintf(stderr, "qnav-sil-robot: %s\n", err);
            rc = 2;
        } else {
            linked = 1;
        }
    }
    if (rc == 0 && o.pose && o.playback == NULL) {
        r.lcm = lcm_create(o.lcm_url);
        if (r.lcm == NULL) {
            fprintf(stderr, "qnav-sil-robot: --lcm-url %s: cannot join the LCM bus\n",
                    o.lcm_url ? o.lcm_url : "(default)");
            rc = 2;
        }
    }
    if (rc == 0) {
        printf("qnav-sil-robot: link on %s%s%s\n", slave, o.link ? " = " : "",
               o.link ? o.link : "");
        fflush(stdout);
        memset(&sa, 0, sizeof sa);
        sa.sa_handler = on_signal;
        sigaction(SIGINT, &sa, NULL);
        sigaction(SIGTERM, &sa, NULL);
        rc = wait_bridge(&r, &o, slave);
    }
    if (rc == 0) {
        while (!g_quit && !episode_over(&r)) {
            run_tick(&r, &o);
        }
        rc = report(&r);
    }
    if (linked) {
        qnav_ptylink_remove(o.link, slave);
    }
    if (r.lcm != NULL) {
        lcm_destroy(r.lcm);
    }
    sil_hal_free(&r.hal);
    free(r.map_mem);
    qnav_sim_destroy(r.sim);
    qnav_sim_env_free(env);
    qnav_sim_robot_free(robot);
    return rc;
}
