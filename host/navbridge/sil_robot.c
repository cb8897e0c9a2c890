/*
 * qnav-sil-robot: software in the loop. The Box2D simulator plays the robot board on a
 * pseudo-terminal, speaking the same serial link as the TekBot firmware, so that
 * simulator -> link -> navbridge -> LCM runs on one machine without hardware. Each 0.1 s
 * tick it sends the simulated scan (and the destination bearing), takes navbridge's
 * command for that scan (offboard) or runs libqnav itself (onboard, accepting policy
 * uploads), and advances the simulation. With --lockstep it waits for each reply instead
 * of the wall clock, so a trial runs as fast as the bridge answers and is repeatable.
 */
#define _XOPEN_SOURCE 700
#define _DEFAULT_SOURCE
#include <errno.h>
#include <fcntl.h>
#include <getopt.h>
#include <math.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#include <lcm/lcm.h>

#include "qnav/ctrl.h"
#include "qnav/link.h"
#include "qnav/sim.h"
#include "qnav_pose_t.h"
#include "serial.h"

static volatile sig_atomic_t g_quit = 0;

static void on_signal(int sig)
{
    g_quit = sig;
}

static int64_t mono_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000 + ts.tv_nsec / 1000000;
}

static int64_t utime_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return (int64_t)ts.tv_sec * 1000000 + ts.tv_nsec / 1000;
}

typedef struct {
    int fd;                       /* pty master */
    qnav_link_rx_t rx;
    qnav_link_tx_t tx;
    qnav_link_upload_t upload;
    uint8_t mode;                 /* bridge's requested mode (0 until heard) */
    int stop_held;                /* bridge holds a stop */
    int64_t last_rx_ms;
    int have_cmd;
    qnav_link_command_t cmd;      /* newest command from the bridge */
    qnav_ctrl_t ctrl;             /* onboard controller */
    qnav_ctrl_config_t ccfg;
    qnav_policy_t policy;
    uint16_t policy_crc;
} robot_t;

static void send_frame(robot_t *r, uint8_t id, const uint8_t *p, int32_t len)
{
    uint8_t wire[QNAV_LINK_MAX_WIRE(QNAV_LINK_MAX_PAYLOAD)];
    int32_t n;
    if (len < 0) {
        return;
    }
    n = qnav_link_encode(&r->tx, id, p, (uint16_t)len, wire, sizeof wire);
    if (n > 0) {
        /* a port nobody reads drops the frame, like a UART with no listener */
        (void)qnav_serial_write_all(r->fd, wire, (size_t)n);
    }
}

static uint16_t blob_crc(const qnav_policy_t *p)
{
    uint8_t blob[QNAV_LINK_POLICY_MAX_BYTES];
    int32_t n = qnav_link_policy_to_blob(p, blob, sizeof blob);
    return n > 0 ? qnav_link_crc16(QNAV_LINK_CRC16_INIT, blob, (uint16_t)n) : 0u;
}

static void on_frame(robot_t *r, const qnav_link_frame_t *f)
{
    r->last_rx_ms = mono_ms();
    if (f->msg_id == QNAV_LINK_MSG_HEARTBEAT) {
        qnav_link_heartbeat_t hb;
        if (qnav_link_heartbeat_unpack(f->payload, f->len, &hb) == QNAV_LINK_OK) {
            if (hb.mode == QNAV_LINK_MODE_OFFBOARD || hb.mode == QNAV_LINK_MODE_ONBOARD) {
                r->mode = hb.mode;
            }
            r->stop_held = (hb.state & QNAV_LINK_STATE_STOPPED) != 0;
        }
    } else if (f->msg_id == QNAV_LINK_MSG_COMMAND) {
        qnav_link_command_t c;
        if (qnav_link_command_unpack(f->payload, f->len, &c) == QNAV_LINK_OK) {
            r->cmd = c;
            r->have_cmd = 1;
            if (c.flags & QNAV_LINK_CMD_STOP) {
                r->stop_held = 1;
            } else if (r->mode == QNAV_LINK_MODE_OFFBOARD) {
                r->stop_held = 0;
            }
        }
    } else if (f->msg_id == QNAV_LINK_MSG_POLICY_CHUNK) {
        qnav_link_policy_chunk_t c;
        if (qnav_link_policy_chunk_unpack(f->payload, f->len, &c) == QNAV_LINK_OK) {
            (void)qnav_link_upload_chunk(&r->upload, &c);
        }
    } else if (f->msg_id == QNAV_LINK_MSG_POLICY_COMMIT) {
        qnav_link_policy_commit_t cm;
        qnav_link_policy_ack_t ack;
        qnav_policy_t fresh;
        uint8_t p[QNAV_LINK_POLICY_ACK_BYTES];
        if (qnav_link_policy_commit_unpack(f->payload, f->len, &cm) != QNAV_LINK_OK) {
            return;
        }
        ack.status = qnav_link_upload_commit(&r->upload, &cm, &fresh);
        if (ack.status == QNAV_LINK_ACK_OK) {
            if (qnav_ctrl_init(&r->ctrl, &r->ccfg, &fresh) == QNAV_OK) {
                r->policy = fresh;
                r->policy_crc = cm.crc;
                fprintf(stderr, "qnav-sil-robot: policy uploaded (crc 0x%04x)\n", cm.crc);
            } else {
                /* keep driving with the policy that was running (it passed init before) */
                if (qnav_ctrl_init(&r->ctrl, &r->ccfg, &r->policy) != QNAV_OK) {
                    fprintf(stderr, "qnav-sil-robot: the running policy no longer initialises\n");
                }
                ack.status = QNAV_LINK_ACK_REJECTED;
            }
        }
        ack.reserved = 0;
        ack.crc = r->policy_crc;
        send_frame(r, QNAV_LINK_MSG_POLICY_ACK, p, qnav_link_policy_ack_pack(&ack, p, sizeof p));
    }
}

/* Read whatever the bridge sent, waiting up to wait_ms for the first byte. */
static void pump(robot_t *r, int wait_ms)
{
    struct pollfd p = {r->fd, POLLIN, 0};
    uint8_t buf[512];
    ssize_t n;
    qnav_link_frame_t f;
    if (poll(&p, 1, wait_ms) <= 0 || !(p.revents & POLLIN)) {
        return;
    }
    while ((n = read(r->fd, buf, sizeof buf)) > 0) {
        for (ssize_t i = 0; i < n; ++i) {
            if (qnav_link_rx_feed(&r->rx, buf[i], &f)) {
                on_frame(r, &f);
            }
        }
    }
}

static void usage(FILE *f)
{
    fprintf(f,
            "usage: qnav-sil-robot [--robot NAME|FILE] [--env NAME|FILE] [--sectors N]\n"
            "                      [--seed N] [--episode N] [--noise P] [--link PATH]\n"
            "                      [--lockstep | --tick-ms N] [--reply-ms N] [--wait-s N]\n"
            "                      [--lcm-url URL | --pose]\n"
            "  --robot, --env   simulator robot profile and environment (tekbot, open)\n"
            "  --sectors N      sonar sectors (0 = the profile's default)\n"
            "  --seed, --episode  simulator seed and episode seed (1, 1)\n"
            "  --noise P        sensor and actuation noise level p (0)\n"
            "  --link PATH      also make PATH a symlink to the pty (for navbridge --device)\n"
            "  --lockstep       wait for each reply instead of the 0.1 s wall clock\n"
            "  --tick-ms N      wall-clock period of a 0.1 s simulated tick (100; smaller\n"
            "                   runs faster than real time)\n"
            "  --reply-ms N     longest wait for the bridge's command each tick (300)\n"
            "  --wait-s N       how long to wait for navbridge to appear (30)\n"
            "  --pose           publish QNAV_POSE on LCM's default bus; --lcm-url on URL\n");
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

int main(int argc, char **argv)
{
    static const struct option opts[] = {
        {"robot", required_argument, NULL, 'r'},   {"env", required_argument, NULL, 'e'},
        {"sectors", required_argument, NULL, 'n'}, {"seed", required_argument, NULL, 's'},
        {"episode", required_argument, NULL, 'E'}, {"noise", required_argument, NULL, 'p'},
        {"link", required_argument, NULL, 'l'},    {"lockstep", no_argument, NULL, 'L'},
        {"reply-ms", required_argument, NULL, 'R'}, {"wait-s", required_argument, NULL, 'w'},
        {"lcm-url", required_argument, NULL, 'u'}, {"pose", no_argument, NULL, 'P'},
        {"tick-ms", required_argument, NULL, 'T'},
        {"help", no_argument, NULL, 'h'},          {NULL, 0, NULL, 0}};
    const char *robot_spec = "tekbot", *env_spec = "open", *link_path = NULL, *lcm_url = NULL;
    double sectors = 0, seed = 1, episode = 1, noise = 0, reply_ms = 300, wait_s = 30;
    double tick_ms = 100;
    int lockstep = 0, pose = 0, c, rc = 0;
    char err[QNAV_SIM_ERRLEN];
    qnav_sim_robot_t *robot = NULL;
    qnav_sim_env_t *env = NULL;
    qnav_sim_t *sim = NULL;
    qnav_sim_config_t scfg;
    qnav_sim_state_t st;
    qnav_sim_result_t res;
    static qnav_sim_scan_t scan;
    static robot_t r;
    lcm_t *lcm = NULL;
    int slave_keep;
    char *slave;
    struct termios tio;
    struct sigaction sa;
    uint32_t missed = 0;
    int64_t t_start;

    opterr = 0;
    while ((c = getopt_long(argc, argv, "", opts, NULL)) != -1) {
        switch (c) {
        case 'r': robot_spec = optarg; break;
        case 'e': env_spec = optarg; break;
        case 'l': link_path = optarg; break;
        case 'u': lcm_url = optarg; pose = 1; break;
        case 'P': pose = 1; break;
        case 'L': lockstep = 1; break;
        case 'n': if (parse_num("sectors", optarg, 0, 360, &sectors)) return 2; break;
        case 's': if (parse_num("seed", optarg, 0, 1e15, &seed)) return 2; break;
        case 'E': if (parse_num("episode", optarg, 0, 1e15, &episode)) return 2; break;
        case 'p': if (parse_num("noise", optarg, 0, 1, &noise)) return 2; break;
        case 'R': if (parse_num("reply-ms", optarg, 1, 60000, &reply_ms)) return 2; break;
        case 'w': if (parse_num("wait-s", optarg, 0, 3600, &wait_s)) return 2; break;
        case 'T': if (parse_num("tick-ms", optarg, 1, 10000, &tick_ms)) return 2; break;
        case 'h': usage(stdout); return 0;
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
    if (qnav_sim_robot_load(robot_spec, &robot, err, sizeof err) != QNAV_SIM_OK ||
        qnav_sim_env_load(env_spec, &env, err, sizeof err) != QNAV_SIM_OK) {
        fprintf(stderr, "%s\n", err);
        qnav_sim_robot_free(robot);
        return 2;
    }
    qnav_sim_config_default(&scfg);
    scfg.n_sectors = (uint16_t)sectors;
    scfg.sensor_noise = noise;
    scfg.actuation_noise = noise;
    scfg.seed = (uint64_t)seed;
    if (qnav_sim_create(robot, env, &scfg, &sim, err, sizeof err) != QNAV_SIM_OK) {
        fprintf(stderr, "qnav-sil-robot: %s\n", err);
        rc = 2;
        goto out;
    }

    /* the pty: raw from the start; the slave stays open so the master never sees EIO
     * while navbridge is not (yet) attached */
    r.fd = posix_openpt(O_RDWR | O_NOCTTY);
    if (r.fd < 0 || grantpt(r.fd) != 0 || unlockpt(r.fd) != 0 ||
        (slave = ptsname(r.fd)) == NULL) {
        fprintf(stderr, "qnav-sil-robot: cannot create a pseudo-terminal: %s\n",
                strerror(errno));
        rc = 2;
        goto out;
    }
    slave_keep = open(slave, O_RDWR | O_NOCTTY);
    if (slave_keep >= 0 && tcgetattr(slave_keep, &tio) == 0) {
        cfmakeraw(&tio);
        tcsetattr(slave_keep, TCSANOW, &tio);
    }
    fcntl(r.fd, F_SETFL, fcntl(r.fd, F_GETFL) | O_NONBLOCK);
    if (link_path != NULL) {
        unlink(link_path);
        if (symlink(slave, link_path) != 0) {
            fprintf(stderr, "qnav-sil-robot: --link %s: %s\n", link_path, strerror(errno));
            rc = 2;
            goto out;
        }
    }
    printf("qnav-sil-robot: link on %s%s%s\n", slave, link_path ? " = " : "",
           link_path ? link_path : "");
    fflush(stdout);
    if (pose) {
        lcm = lcm_create(lcm_url);
        if (lcm == NULL) {
            fprintf(stderr, "qnav-sil-robot: --lcm-url %s: cannot join the LCM bus\n",
                    lcm_url ? lcm_url : "(default)");
            rc = 2;
            goto out;
        }
    }
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);

    qnav_link_rx_init(&r.rx);
    qnav_link_tx_init(&r.tx);
    qnav_link_upload_init(&r.upload);
    qnav_sim_ctrl_config(sim, &r.ccfg);
    qnav_policy_prob_default(&r.policy);
    r.policy_crc = blob_crc(&r.policy);
    {
        qnav_status_t cst = qnav_ctrl_init(&r.ctrl, &r.ccfg, &r.policy);
        if (cst != QNAV_OK) {
            fprintf(stderr, "qnav-sil-robot: the default policy does not initialise: %s\n",
                    qnav_status_str(cst));
            rc = 2;
            goto out;
        }
    }

    /* wait for navbridge: its heartbeats tell the mode */
    t_start = mono_ms();
    while (!g_quit && r.mode == 0 && mono_ms() - t_start < (int64_t)(wait_s * 1000.0)) {
        pump(&r, 100);
    }
    if (r.mode == 0) {
        fprintf(stderr, "qnav-sil-robot: no navbridge heartbeat on %s within %g s\n", slave,
                wait_s);
        rc = 3;
        goto out;
    }
    qnav_sim_reset(sim, (uint64_t)episode);
    for (;;) {
        uint8_t p[QNAV_LINK_MAX_PAYLOAD];
        qnav_link_scan_t ls;
        qnav_link_heartbeat_t hb;
        qnav_ctrl_output_t out;
        int64_t tick_start = mono_ms();
        uint16_t seq;
        int moving;

        qnav_sim_state(sim, &st);
        if (st.done || g_quit) {
            break;
        }
        qnav_sim_scan(sim, &scan);
        memset(&ls, 0, sizeof ls);
        ls.board_ms = (uint32_t)(st.tick * 100u);
        ls.goal_bearing_cdeg = scan.goal_bearing_cdeg;
        ls.max_range_mm = scan.max_range_mm;
        ls.n_sectors = scan.n_sectors;
        ls.goal_id = 1;
        memcpy(ls.ranges_mm, scan.ranges_mm, scan.n_sectors * sizeof scan.ranges_mm[0]);
        seq = r.tx.next_seq;
        send_frame(&r, QNAV_LINK_MSG_SCAN, p, qnav_link_scan_pack(&ls, p, sizeof p));
        /* heartbeat before any decision, so the bridge labels it with the current policy */
        hb.uptime_ms = (uint32_t)(mono_ms() - t_start);
        hb.mode = r.mode;
        hb.state = (uint8_t)(QNAV_LINK_STATE_LINK_OK | QNAV_LINK_STATE_POLICY |
                             (r.stop_held ? QNAV_LINK_STATE_STOPPED : QNAV_LINK_STATE_MOVING));
        hb.rx_ok = (uint16_t)r.rx.stats.frames_ok;
        hb.rx_dropped = (uint16_t)qnav_link_rx_dropped_total(&r.rx);
        hb.policy_crc = r.policy_crc;
        send_frame(&r, QNAV_LINK_MSG_HEARTBEAT, p, qnav_link_heartbeat_pack(&hb, p, sizeof p));

        memset(&out, 0, sizeof out);
        if (r.mode == QNAV_LINK_MODE_ONBOARD) {
            qnav_ctrl_input_t in = {scan.ranges_mm, scan.goal_bearing_cdeg,
                                    scan.prev_heading_cdeg};
            qnav_link_command_t tel;
            qnav_ctrl_step(&r.ctrl, &in, &out, NULL);
            /* like the board: hold still while stopped or when the bridge went quiet */
            moving = !r.stop_held && mono_ms() - r.last_rx_ms <= 300;
            tel.scan_seq = seq;
            tel.heading_deg = out.heading_deg;
            tel.speed = moving ? out.speed : 0;
            tel.quality = out.quality;
            tel.flags = (uint8_t)(out.flags | (moving ? 0u : QNAV_LINK_CMD_STOP));
            tel.reserved = 0;
            send_frame(&r, QNAV_LINK_MSG_COMMAND, p, qnav_link_command_pack(&tel, p, sizeof p));
            pump(&r, 0);
        } else {
            /* offboard: the command answering this scan, or a stop if it does not come */
            int64_t until = tick_start + (int64_t)reply_ms;
            r.have_cmd = 0;
            while (!g_quit && !(r.have_cmd && r.cmd.scan_seq == seq &&
                                !(r.cmd.flags & QNAV_LINK_CMD_STOP))) {
                int64_t left = until - mono_ms();
                if (left <= 0) {
                    break;
                }
                if (r.have_cmd && (r.cmd.flags & QNAV_LINK_CMD_STOP)) {
                    break;
                }
                r.have_cmd = 0;
                pump(&r, (int)left);
            }
            moving = r.have_cmd && r.cmd.scan_seq == seq && !(r.cmd.flags & QNAV_LINK_CMD_STOP);
            if (moving) {
                out.heading_deg = r.cmd.heading_deg;
                out.speed = r.cmd.speed;
                out.quality = r.cmd.quality;
            } else {
                missed++;
            }
        }
        if (!moving) {
            out.speed = 0;
            out.heading_deg = 0;
        }
        qnav_sim_command(sim, &out);
        qnav_sim_advance(sim);

        if (lcm != NULL) {
            qnav_pose_t ps;
            qnav_sim_state(sim, &st);
            memset(&ps, 0, sizeof ps);
            ps.utime = utime_now();
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
        if (!lockstep) {
            int64_t left = tick_start + (int64_t)tick_ms - mono_ms();
            while (left > 0 && !g_quit) {
                pump(&r, (int)left);
                left = tick_start + (int64_t)tick_ms - mono_ms();
            }
        }
    }
    qnav_sim_state(sim, &st);
    qnav_sim_result(sim, &res);
    printf("qnav-sil-robot: %s: reached %s, %u ticks (%.1f s), %u collisions, "
           "R = %.3f, %u ticks without a command, %lu link frames dropped\n",
           g_quit ? "interrupted" : "episode done", res.reached ? "yes" : "no",
           (unsigned)res.ticks, res.tau_l, (unsigned)res.collisions, res.R, (unsigned)missed,
           (unsigned long)qnav_link_rx_dropped_total(&r.rx));
    fflush(stdout);
    rc = g_quit ? 4 : (res.reached ? 0 : 1);
out:
    if (link_path != NULL) {
        unlink(link_path);
    }
    if (lcm != NULL) {
        lcm_destroy(lcm);
    }
    qnav_sim_destroy(sim);
    qnav_sim_env_free(env);
    qnav_sim_robot_free(robot);
    return rc;
}
