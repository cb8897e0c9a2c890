// qnav-sim: the simulator's command-line program. `run` simulates a policy file (or the
// hand-tuned probabilistic policy) in a named environment with a chosen robot, sector
// count and noise, prints the episode's figures (paper Eq. 1-3) and writes its picture;
// `draw-env` draws an environment like the paper's Fig. 6; `gen-env` writes a world of a
// family (worldgen.hpp) or a random environment of a given density; `bench` measures
// episodes per second per core with the time split into physics, sonar, the map (when on) and controller. Bad input: one line, non-zero exit.
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include <fcntl.h>
#include <stdexcept>
#include <sys/stat.h>
#include <unistd.h>

#include <CLI/CLI.hpp>

#include "qnav/cli.hpp"

#include "capi_internal.hpp"
#include "error.hpp"
#include "qnav/ctrl.h"
#include "qnav/nav.h"
#include "qnav/sim.h"
#include "robot_board.h"
#include "qnav/rng.hpp"
#include "svg.hpp"
#include "worldgen.hpp"
#ifdef QNAV_SIM_HAVE_POLICYIO
#include "qnav/policy_io.h"
#endif

namespace {

using qnav::SimError;

struct Loaded {
    qnav_sim_robot_t *robot = nullptr;
    qnav_sim_env_t *env = nullptr;
    qnav_sim_t *sim = nullptr;
    ~Loaded() {
        qnav_sim_destroy(sim);
        qnav_sim_env_free(env);
        qnav_sim_robot_free(robot);
    }
};

// A failed write of an output file: a failure at run time (exit 1), not bad input (2).
struct WriteError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

// Write text to path through a temporary file renamed into place. The temporary is made
// exclusively (mkstemp) beside path, so a symlink planted there is never followed.
void write_output(const std::string &path, const std::string &text) {
    const std::size_t slash = path.find_last_of('/');
    std::string tmp = (slash == std::string::npos ? std::string() : path.substr(0, slash + 1)) + "." +
                      path.substr(slash == std::string::npos ? 0 : slash + 1) + ".tmp.XXXXXX";
    const int fd = ::mkostemp(tmp.data(), O_CLOEXEC);
    if (fd < 0) throw WriteError(path + ": cannot write (" + std::strerror(errno) + ")");
    std::size_t off = 0;
    bool ok = ::fchmod(fd, 0644) == 0;
    while (ok && off < text.size()) {
        const ssize_t n = ::write(fd, text.data() + off, text.size() - off);
        if (n < 0 && errno == EINTR) continue;
        ok = n > 0;
        if (ok) off += static_cast<std::size_t>(n);
    }
    const std::string why = std::strerror(errno);
    if (::close(fd) != 0 || !ok) {
        ::unlink(tmp.c_str());
        throw WriteError(path + ": cannot write (" + why + ")");
    }
    if (std::rename(tmp.c_str(), path.c_str()) != 0) {
        const std::string e = std::strerror(errno);
        ::unlink(tmp.c_str());
        throw WriteError(path + ": cannot rename into place (" + e + ")");
    }
}

void check(qnav_sim_status_t st, const char *err) {
    if (st != QNAV_SIM_OK) throw SimError(st, err);
}

void load(Loaded &l, const std::string &robot, const std::string &env) {
    char err[QNAV_SIM_ERRLEN] = "";
    check(qnav_sim_robot_load(robot.c_str(), &l.robot, err, sizeof err), err);
    check(qnav_sim_env_load(env.c_str(), &l.env, err, sizeof err), err);
}

void make_sim(Loaded &l, int sectors, double ps, double pa, std::uint64_t seed,
              qnav_sim_fitness_rule_t fitness = QNAV_SIM_FITNESS_PROGRESS, double limit_factor = 1.0,
              double map_frame_deg = -1.0, double survey_m = 0.0) {
    char err[QNAV_SIM_ERRLEN] = "";
    qnav_sim_config_t cfg;
    qnav_sim_config_default(&cfg);
    if (limit_factor != 1.0) {
        qnav_sim_env_info_t ei;
        qnav_sim_env_info(l.env, &ei);
        cfg.episode_limit_s = limit_factor * ei.episode_limit_s;
    }
    cfg.fitness = fitness;
    cfg.n_sectors = static_cast<std::uint16_t>(sectors);
    cfg.sensor_noise = ps;
    cfg.actuation_noise = pa;
    cfg.seed = seed;
    cfg.map_frame_deg = map_frame_deg;
    cfg.survey_m = survey_m;
    check(qnav_sim_create(l.robot, l.env, &cfg, &l.sim, err, sizeof err), err);
}

// The policy file at path, or (empty path) the probabilistic policy tuned for the robot.
qnav_policy_t read_policy(const std::string &path, const qnav_sim_robot_t *robot) {
    qnav_policy_t pol;
    if (path.empty()) {
        qnav_sim_robot_prob_policy(robot, &pol);
        return pol;
    }
#ifdef QNAV_SIM_HAVE_POLICYIO
    char err[QNAV_POLICY_IO_ERRLEN] = "";
    if (qnav_policy_read(path.c_str(), &pol, err, sizeof err) != 0)
        throw SimError(QNAV_SIM_E_PARSE, err);
    return pol;
#else
    throw SimError(QNAV_SIM_E_PARAM, "--policy: this build has no policy-file reader (qnav_policyio)");
#endif
}

// Initialise ctrl for sim from a policy, in network/probabilistic or table mode (bench).
void init_ctrl(const qnav_sim_t *sim, const qnav_policy_t &pol, bool table,
               std::vector<qnav_qkey_t> &table_buf, qnav_ctrl_t *ctrl) {
    qnav_ctrl_config_t cc;
    qnav_sim_ctrl_config(sim, &cc);
    if (table) {
        table_buf.assign(QNAV_QTABLE_ENTRIES, 0);
        const qnav_status_t st = qnav_ctrl_init_compiled(ctrl, &cc, &pol, table_buf.data());
        if (st != QNAV_OK)
            throw SimError(QNAV_SIM_E_PARAM, "policy: table mode failed (status " + std::to_string(st) + ")");
        return;
    }
    const qnav_status_t st = qnav_ctrl_init(ctrl, &cc, &pol);
    if (st != QNAV_OK)
        throw SimError(QNAV_SIM_E_PARAM, "policy: rejected by qnav_ctrl_init (status " + std::to_string(st) + ")");
}

// Names of every controller in libqnav's table, for messages: "body, literal, vfh".
std::string controller_names() {
    std::string s;
    for (std::uint8_t i = 0; i < qnav_nav_count(); ++i) s += (i ? ", " : "") + std::string(qnav_nav_method_at(i)->name);
    return s;
}

// What a controller of libqnav's table is, in --controller's help (a row without a line
// here is listed by its name alone: the list itself is the table's).
struct ControllerHelp {
    const char *name, *what;
};
constexpr ControllerHelp kControllerHelp[] = {
    {"body", "obstacles enlarged by the robot's radius + safety distance, speed guard, rank by pre-activation"},
    {"literal", "the paper's per-sector reading (ablation)"},
    {"vfh", "VFH+ (Ulrich & Borenstein 1998), no policy"},
};

// "NAME: what; NAME: what; ..." over libqnav's controller table, in its order.
std::string controller_help() {
    std::string s;
    for (std::uint8_t i = 0; i < qnav_nav_count(); ++i) {
        const std::string name = qnav_nav_method_at(i)->name;
        s += (i ? "; " : "") + name;
        for (const ControllerHelp &h : kControllerHelp)
            if (name == h.name) s += std::string(": ") + h.what;
    }
    return s;
}

// Initialise nav as the controller called name (libqnav's table, qnav/nav.h) for sim;
// table: compile a path-quality controller's policy into table mode.
void init_nav(const qnav_sim_t *sim, const std::string &name, const qnav_policy_t &pol, bool table,
              std::vector<qnav_qkey_t> &table_buf, qnav_nav_t *nav) {
    const qnav_nav_method_t *m = qnav_nav_find(name.c_str());
    if (!m) throw SimError(QNAV_SIM_E_PARAM, "--controller: no controller '" + name + "' (" + controller_names() + ")");
    qnav_ctrl_config_t cc;
    qnav_sim_ctrl_config(sim, &cc);
    qnav_status_t st = qnav_nav_init(nav, m, &cc, &pol);
    if (st != QNAV_OK)
        throw SimError(QNAV_SIM_E_PARAM, "--controller " + name + ": " + qnav_status_str(st));
    if (!table) return;
    qnav_ctrl_t *ctrl = qnav_nav_paths(nav);
    if (!ctrl) throw SimError(QNAV_SIM_E_PARAM, "--table: controller " + name + " has no quality table");
    qnav_ctrl_config_t own;
    qnav_nav_config(m, &cc, &own);
    table_buf.assign(QNAV_QTABLE_ENTRIES, 0);
    st = qnav_ctrl_build_table(ctrl, table_buf.data());
    if (st == QNAV_OK) st = qnav_ctrl_init_table(ctrl, &own, table_buf.data(), qnav_ctrl_rank(ctrl));
    if (st != QNAV_OK) throw SimError(QNAV_SIM_E_PARAM, std::string("--table: ") + qnav_status_str(st));
}

void print_result(unsigned long long episode, const qnav_sim_result_t &r) {
    std::printf("episode %llu: %s in %u ticks  l %.3f m  beta_l %.3f m  tau_l %.1f s  "
                "beta_tau %.2f s  f1 %.3f  f2 %.3f  tau_c %u  collisions %u  R %.3f\n",
                episode, r.reached ? "reached" : "not reached", r.ticks, r.l, r.beta_l, r.tau_l,
                r.beta_tau, r.f1, r.f2, r.tau_c, r.collisions, r.R);
}

struct RunOpts {
    std::string robot = "pioneer3dx", env = "dense", policy, svg, trace, fitness = "progress";
    int sectors = 0;
    double ps = -1, pa = -1;
    std::uint64_t seed = 1, episode = 0;
    unsigned episodes = 1;
    double limit_factor = 1.0;  // times the environment's episode time limit
    double map_frame = -1;      // the map's grid against the walls, deg; < 0: drawn per episode
    double survey = 0;          // > 0: each episode's map starts surveyed from a grid this far apart, m
    bool table = false;
    std::string controller = "body";  // a name in libqnav's controller table (qnav/nav.h)
    long svg_tick = -1;
};

// One episode's samples as they come: the trajectory rows (first episode, --trace), the
// picture's path and the sonar at the chosen tick or the last one before the end (first
// episode, --svg), and the heading change for the smoothness figure (every episode).
struct EpisodeRecord {
    const qnav::Simulation &sim;
    bool want_pic, want_trace;
    long svg_tick;
    qnav::EpisodePicture pic;
    std::string csv = "tick,x_m,y_m,heading_rad,speed_mps,cmd_heading_deg,cmd_speed,recovering,collided,escape_side,"
                      "goal_bearing_deg,goal_range_m\n";
    bool have_last = false;
    double last_heading = 0, turn_deg = 0;

    EpisodeRecord(const qnav::Simulation &s, bool pic_wanted, bool trace_wanted, long tick)
        : sim(s), want_pic(pic_wanted), want_trace(trace_wanted), svg_tick(tick) {}
    void add(const qnav_sim_sample_t &smp) {
        if (have_last) turn_deg += std::fabs(std::remainder(smp.heading_rad - last_heading, 2 * M_PI)) * 180.0 / M_PI;
        have_last = true;
        last_heading = smp.heading_rad;
        if (want_trace) {
            char line[256];
            std::snprintf(line, sizeof line, "%u,%.6f,%.6f,%.6f,%.4f,%d,%.4f,%d,%d,%d,%.2f,%.3f\n", smp.tick,
                          smp.x_m, smp.y_m, smp.heading_rad, smp.speed_mps, smp.cmd_heading_deg, smp.cmd_speed,
                          smp.recovering ? 1 : 0, smp.collided ? 1 : 0, smp.escape_side, smp.goal_bearing_deg,
                          smp.goal_range_m);
            csv += line;
        }
        if (!want_pic) return;
        pic.path.push_back({smp.x_m, smp.y_m});
        if (static_cast<long>(smp.tick) <= std::max(0L, svg_tick)) {
            pic.sonar_tick = smp.tick;
            pic.sonar_pos = {smp.x_m, smp.y_m};
            pic.sonar_heading = smp.heading_rad;
            pic.sonar_ranges_m.clear();
            for (unsigned k = 0; k < sim.config().n_sectors; ++k) pic.sonar_ranges_m.push_back(sim.scan().ranges_mm[k] / 1000.0);
            snapshot_map();
        }
    }

    // The map's occupied cells now, for the picture: each cell's corners in the world (the
    // map's grid is turned against the world by the simulator, docs/sim.md "The map's
    // grid", and may turn itself to the walls: [map] align_samples).
    void snapshot_map() {
        const qnav_map_t *m = sim.map();
        if (!m) return;
        const std::int32_t cell = m->cfg.cell_mm;
        // grid-frame point (x, y), mm, in the world, m
        const auto world = [&](std::int32_t x, std::int32_t y) {
            qnav_map_grid_to_pose(m, &x, &y);
            return sim.map_to_world({x / 1000.0, y / 1000.0});
        };
        pic.map_drawn = true;
        pic.map_occupied.clear();
        for (std::int32_t j = 0; j < m->ny; ++j)
            for (std::int32_t i = 0; i < m->nx; ++i) {
                const std::int32_t x = m->x0_mm + i * cell, y = m->y0_mm + j * cell;
                std::int32_t cx = x + cell / 2, cy = y + cell / 2;
                qnav_map_grid_to_pose(m, &cx, &cy);
                if (qnav_map_evidence(m, cx, cy) < QNAV_MAP_OCCUPIED) continue;
                pic.map_occupied.push_back({world(x, y), world(x + cell, y), world(x + cell, y + cell), world(x, y + cell)});
            }
    }
};

// The first episode's --trace and --svg files.
void write_episode_files(const RunOpts &o, const qnav::Simulation &sim, const qnav_sim_robot_info_t &ri,
                         EpisodeRecord &rec, std::uint64_t episode, const qnav_sim_result_t &r) {
    if (rec.want_trace) {
        write_output(o.trace, rec.csv);
        std::printf("trajectory: %s\n", o.trace.c_str());
    }
    if (!rec.want_pic) return;
    rec.pic.collisions = sim.collision_marks();
    rec.pic.cone_rad = sim.sonar_cone_rad();
    rec.pic.reached = r.reached;
    char cap[256];
    std::snprintf(cap, sizeof cap, "%s, %s, %u sectors, episode %llu: R %.2f, %s, sonar at tick %u", ri.name,
                  sim.env().name.c_str(), sim.config().n_sectors, static_cast<unsigned long long>(episode), r.R,
                  r.reached ? "reached" : "not reached", rec.pic.sonar_tick);
    rec.pic.caption = cap;
    write_output(o.svg, qnav::render_svg(sim.env(), ri.radius_m, &rec.pic));
    std::printf("picture: %s\n", o.svg.c_str());
}

// What the episodes of one run add up to.
struct RunTotals {
    double sum_r = 0, path_m = 0, turn_deg = 0;
    unsigned reached = 0;
    unsigned long long tau_c = 0;

    void add(const qnav_sim_result_t &r, double turn) {
        sum_r += r.R;
        reached += r.reached;
        tau_c += r.tau_c;
        path_m += r.l;
        turn_deg += turn;
    }
    void print(unsigned episodes) const {
        if (episodes <= 1) return;
        std::printf("mean R %.3f over %u episodes, %u reached (%.1f%%)\n", sum_r / episodes, episodes, reached,
                    100.0 * reached / episodes);
        std::printf("recovery ticks %.2f per episode  path %.2f m per episode  heading change %.1f deg/m\n",
                    static_cast<double>(tau_c) / episodes, path_m / episodes, path_m > 0 ? turn_deg / path_m : 0.0);
    }
};

int cmd_run(const RunOpts &o) {
    Loaded l;
    load(l, o.robot, o.env);
    qnav_sim_robot_info_t ri;
    qnav_sim_robot_info(l.robot, &ri);
    qnav_map_config_t mc;
    if (o.survey > 0 && !qnav_sim_robot_map_config(l.robot, &mc))
        throw SimError(QNAV_SIM_E_PARAM, o.robot + ": --survey: the profile has no [map] (or its [map] is off) to survey into");
    const double ps = o.ps >= 0 ? o.ps : ri.sensor_noise;
    const double pa = o.pa >= 0 ? o.pa : ri.actuation_noise;
    qnav_sim_fitness_rule_t rule;
    if (qnav_sim_fitness_rule_parse(o.fitness.c_str(), &rule) != QNAV_SIM_OK)
        throw SimError(QNAV_SIM_E_PARAM, "--fitness: '" + o.fitness + "' is not one of " +
                                             qnav_sim_fitness_rule_names());
    make_sim(l, o.sectors, ps, pa, o.seed, rule, o.limit_factor, o.map_frame, o.survey);
    qnav::Simulation &sim = *l.sim->sim;
    const qnav_policy_t pol = read_policy(o.policy, l.robot);
    std::vector<qnav_qkey_t> tbuf;
    qnav_nav_t nav;
    init_nav(l.sim, o.controller, pol, o.table, tbuf, &nav);
    const bool uses_policy = qnav_nav_method(&nav)->uses_policy != 0;
    if (!uses_policy && !o.policy.empty())
        throw SimError(QNAV_SIM_E_PARAM, "--policy: controller " + o.controller + " takes no policy");
    std::printf("robot %s  env %s  sectors %u  sensor noise %.3f  actuation noise %.3f  seed %llu  "
                "controller %s  fitness %s  policy %s%s\n",
                ri.name, sim.env().name.c_str(), sim.config().n_sectors, ps, pa,
                static_cast<unsigned long long>(o.seed), o.controller.c_str(),
                qnav_sim_fitness_rule_name(rule),
                !uses_policy ? "none" : o.policy.empty() ? "probabilistic (default)" : o.policy.c_str(),
                o.table ? " (table mode)" : "");
    const qnav::RobotProfile &rp = sim.robot();
    if (rp.map_cell_m > 0) {
        if (qnav::has_odometry_errors(rp))
            std::printf("map %g m cells, its pose from odometry with errors (sd) %g %% scale, %g %% turn, "
                        "%g deg/m curve\n",
                        rp.map_cell_m, rp.odom_err_scale_pct, rp.odom_err_turn_pct, rp.odom_err_curve_deg_m);
        else
            std::printf("map %g m cells, its pose the true one\n", rp.map_cell_m);
    }
    RunTotals totals;
    for (unsigned e = 0; e < o.episodes; ++e) {
        const std::uint64_t es = o.episode + e;
        EpisodeRecord rec(sim, e == 0 && !o.svg.empty(), e == 0 && !o.trace.empty(), o.svg_tick);
        auto trace = [](void *user, const qnav_sim_sample_t *smp) { static_cast<EpisodeRecord *>(user)->add(*smp); };
        const qnav_sim_result_t r = sim.run_episode(&nav, es, +trace, &rec);
        print_result(static_cast<unsigned long long>(es), r);
        totals.add(r, rec.turn_deg);
        write_episode_files(o, sim, ri, rec, es, r);
    }
    totals.print(o.episodes);
    return 0;
}

int cmd_draw_env(const std::string &env, const std::string &robot, const std::string &outp) {
    Loaded l;
    load(l, robot, env);
    qnav_sim_robot_info_t ri;
    qnav_sim_robot_info(l.robot, &ri);
    write_output(outp, qnav::render_svg(l.env->env, ri.radius_m, nullptr));
    std::printf("picture: %s\n", outp.c_str());
    return 0;
}

// The board's configuration header for a robot, from the same mapping the simulator uses
// (robot_board.h; docs/hil.md, "One robot description").
int cmd_robot_header(const std::string &robot, const std::string &outp) {
    char err[QNAV_SIM_ERRLEN];
    qnav_sim_robot_t *r = nullptr;
    if (qnav_sim_robot_load(robot.c_str(), &r, err, sizeof err) != QNAV_SIM_OK)
        throw SimError(QNAV_SIM_E_PARSE, err);
    char *buf = nullptr;
    std::size_t len = 0;
    FILE *mem = open_memstream(&buf, &len);
    const int st = mem ? qnav_robot_board_header(r, mem) : -1;
    if (mem) std::fclose(mem);
    qnav_sim_robot_free(r);
    const std::string text = buf ? std::string(buf, len) : std::string();
    std::free(buf);
    if (st != 0) throw WriteError(outp + ": cannot format the header");
    write_output(outp, text);
    std::printf("board configuration header: %s\n", outp.c_str());
    return 0;
}

struct GenOpts {
    double density = -1;  // the old form: -1 = not given
    std::string family, difficulty = "0.5", robot, name, out;
    std::uint64_t seed = 1;
};

// --name lands in a TOML string: refuse what would not stay one line (the writer escapes
// quotes and backslashes).
void check_env_name(const std::string &name) {
    if (name.empty()) throw SimError(QNAV_SIM_E_PARAM, "--name: must not be empty");
    for (const char c : name)
        if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f)
            throw SimError(QNAV_SIM_E_PARAM, "--name: must not contain control characters (newline, tab, ...)");
}

int cmd_gen_env(const GenOpts &o) {
    if (!o.name.empty()) check_env_name(o.name);
    qnav::Environment env;
    if (!o.family.empty()) {
        if (o.density >= 0) throw SimError(QNAV_SIM_E_PARAM, "--density: not with --family (use --difficulty)");
        const std::string spec = "gen:" + o.family + ":" + std::to_string(o.seed) + ":" + o.difficulty + ":" +
                                 (o.robot.empty() ? "tekbot" : o.robot);
        env = qnav::load_world(spec);
    } else {
        Loaded l;
        char err[QNAV_SIM_ERRLEN] = "";
        const std::string robot = o.robot.empty() ? "pioneer3dx" : o.robot;
        check(qnav_sim_robot_load(robot.c_str(), &l.robot, err, sizeof err), err);
        env = qnav::generate_environment(o.density >= 0 ? o.density : 0.2, o.seed, l.robot->profile.radius_m);
    }
    if (!o.name.empty()) env.name = o.name;
    const std::string text = qnav::environment_to_toml(env);
    // Check that what we write reads back.
    qnav::parse_environment(text, o.out);
    write_output(o.out, text);
    std::printf("environment %s: %zu circles, %zu boxes, %.0f x %.0f m, limit %.0f s -> %s\n", env.name.c_str(),
                env.circles.size(), env.boxes.size(), env.width_m, env.height_m, env.episode_limit_s, o.out.c_str());
    return 0;
}

struct BenchOpts {
    std::string robot = "pioneer3dx", env = "dense", policy;
    int sectors = 32, hidden = 12;
    unsigned episodes = 1000;
    std::string mode = "table";
    std::uint64_t seed = 1;
    double ps = 0, pa = 0;
    bool fresh = false;
    bool reference = false;
};

// A seeded random network of `hidden` units, weights uniform in [-4, 4] (Q8.8), like a
// member of an early evolving population.
qnav_policy_t random_network(int hidden, std::uint64_t seed, std::uint64_t which) {
    qnav_policy_t pol;
    qnav_policy_net_zero(&pol, static_cast<std::uint8_t>(hidden));
    qnav::Rng rng = qnav::Rng::stream(seed, 0xbe7c, which);
    for (std::uint16_t k = 0; k < QNAV_NET_WEIGHTS(pol.u.net.hidden); ++k)
        *qnav_net_weight(&pol.u.net, k) =
            static_cast<qnav_q8_8_t>(std::lround(rng.uniform(-4.0, 4.0) * 256.0));
    return pol;
}

// The profiled pass's time split: shares of the wall time, then per tick.
static void print_split(const qnav::SimProfile &p, double wall_p, std::uint64_t ticks) {
    const double other = wall_p - p.physics_s - p.sonar_s - p.controller_s - p.map_s;
    const double per_tick = 1e6 / static_cast<double>(ticks);
    std::printf("time split (profiled pass, %.3f s): physics %.1f%%  sonar %.1f%%", wall_p,
                100 * p.physics_s / wall_p, 100 * p.sonar_s / wall_p);
    if (p.map_s > 0) std::printf("  map %.1f%%", 100 * p.map_s / wall_p);
    std::printf("  controller %.1f%%  other %.1f%%\n", 100 * p.controller_s / wall_p, 100 * other / wall_p);
    std::printf("per tick: physics %.2f us  sonar %.2f us", per_tick * p.physics_s, per_tick * p.sonar_s);
    if (p.map_s > 0) std::printf("  map %.2f us", per_tick * p.map_s);
    std::printf("  controller %.2f us\n", per_tick * p.controller_s);
}

int cmd_bench(const BenchOpts &o) {
    Loaded l;
    load(l, o.robot, o.env);
    make_sim(l, o.sectors, o.ps, o.pa, o.seed);
    qnav::Simulation &sim = *l.sim->sim;
    qnav_policy_t pol;
    std::string what;
    if (o.policy == "prob") {
        qnav_sim_robot_prob_policy(l.robot, &pol);
        what = "probabilistic (tuned for the robot)";
    } else if (!o.policy.empty()) {
        pol = read_policy(o.policy, l.robot);
        what = o.policy;
    } else {
        pol = random_network(o.hidden, o.seed, 0);
        what = o.fresh ? "a new random network per episode, " + std::to_string(o.hidden) + " hidden"
                       : "random network, " + std::to_string(o.hidden) + " hidden";
    }
    std::vector<qnav_qkey_t> tbuf;
    qnav_ctrl_t ctrl;
    init_ctrl(l.sim, pol, o.mode == "table", tbuf, &ctrl);
    double build_s = 0;
    sim.set_reference_mode(o.reference);
    using Clock = std::chrono::steady_clock;
    auto pass = [&](bool profiling, std::uint64_t *ticks, double *sum_r) {
        sim.set_profiling(profiling);
        sim.profile() = qnav::SimProfile{};
        *ticks = 0;
        *sum_r = 0;
        const auto t0 = Clock::now();
        for (unsigned e = 0; e < o.episodes; ++e) {
            if (o.fresh) {
                // As in evolution: every episode scores a new network, compiled to a
                // table first in table mode (counted as controller time).
                const auto b0 = Clock::now();
                init_ctrl(l.sim, random_network(o.hidden, o.seed, e + 1), o.mode == "table", tbuf, &ctrl);
                const double b = std::chrono::duration<double>(Clock::now() - b0).count();
                if (profiling) {
                    sim.profile().controller_s += b;
                    build_s += b;
                }
            }
            const qnav_sim_result_t r = sim.run_episode(&ctrl, e, nullptr, nullptr);
            *ticks += r.ticks;
            *sum_r += r.R;
        }
        return std::chrono::duration<double>(Clock::now() - t0).count();
    };
    std::uint64_t ticks;
    double sum_r;
    const double wall = pass(false, &ticks, &sum_r);
    std::uint64_t ticks2;
    double sum_r2;
    const double wall_p = pass(true, &ticks2, &sum_r2);
    const qnav::SimProfile p = sim.profile();
    std::printf("bench%s: robot %s  env %s  sectors %d  policy %s  controller %s mode  episodes %u  "
                "noise %.3f/%.3f\n", o.reference ? " (reference: Box2D ray per degree, Box2D every tick)" : "",
                o.robot.c_str(), sim.env().name.c_str(), o.sectors,
                what.c_str(),
                o.mode.c_str(), o.episodes, o.ps, o.pa);
    std::printf("episodes/s per core: %.1f   (%.0f ticks/s, %.1f ticks/episode, %.2f us/tick, mean R %.3f)\n",
                o.episodes / wall, static_cast<double>(ticks) / wall, static_cast<double>(ticks) / o.episodes,
                1e6 * wall / static_cast<double>(ticks), sum_r / o.episodes);
    print_split(p, wall_p, ticks2);
    if (o.fresh)
        std::printf("controller includes building each network (and its table): %.1f us/episode\n",
                    1e6 * build_s / o.episodes);
    if (ticks != ticks2 || sum_r != sum_r2) {
        std::fprintf(stderr, "bench: profiled and plain passes differ (determinism broken)\n");
        return 1;
    }
    return 0;
}

}  // namespace

// The run subcommand's options, into o.
static CLI::App *add_run(CLI::App &app, RunOpts &o) {
    CLI::App *run = app.add_subcommand("run", "simulate a policy and print the episode's figures");
    run->add_option("--policy", o.policy, "policy file (default: the probabilistic policy tuned for the robot)")->check(CLI::ExistingFile);
    run->add_option("--robot", o.robot, "robot profile name or file")->capture_default_str();
    run->add_option("--env", o.env, "environment name, file, or world spec gen:FAMILY:SEED[:DIFFICULTY[:ROBOT]] (docs/sim.md)")->capture_default_str();
    run->add_option("--sectors", o.sectors, "sonar sectors 1..360 (default: the profile's)")->check(CLI::Range(1, 360));
    run->add_option("--sensor-noise", o.ps, "p_s in [0, 1] (default: the profile's typical)")->check(qnav::cli::finite_range(0.0, 1.0));
    run->add_option("--actuation-noise", o.pa, "p_a in [0, 1] (default: the profile's typical)")->check(qnav::cli::finite_range(0.0, 1.0));
    run->add_option("--seed", o.seed, "context seed")->capture_default_str();
    run->add_option("--fitness", o.fitness, "fitness rule: progress (default) or paper (Eq. 1-3 literally; docs/sim.md)")->capture_default_str();
    run->add_option("--episode", o.episode, "first episode seed")->capture_default_str();
    run->add_option("--episodes", o.episodes, "number of episodes")->check(CLI::Range(1u, 1000000u))->capture_default_str();
    run->add_flag("--table", o.table, "run the controller in table mode");
    run->add_option("--controller", o.controller, controller_help())->capture_default_str();
    run->add_option("--limit-factor", o.limit_factor,
                    "episode time limit as a multiple of the environment's (2: judge escapes at twice it)")
        ->check(qnav::cli::finite_range(0.1, 100.0))->capture_default_str();
    run->add_option("--map-frame", o.map_frame,
                    "a profile's [map]: its grid's angle to the arena's walls, deg in [0, 360) (default: drawn "
                    "per episode, as a board's heading sensor lies to a room; 0: aligned, the figures before 0.18)")
        ->check(CLI::Validator(
            [](std::string &s) -> std::string {
                double v = 0.0;
                return CLI::detail::lexical_cast(s, v) && std::isfinite(v) && v >= 0.0 && v < 360.0
                           ? std::string()
                           : "expected a number in [0, 360), got '" + s + "'";
            },
            "NUMBER in [0 - 360)"));
    run->add_option("--survey", o.survey,
                    "a profile's [map]: start each episode's map with what the sonar shows from every point of a "
                    "grid this many metres apart (a known world: what a miss owes to exploring; docs/sim.md)")
        ->check(qnav::cli::finite_range(0.05, 10.0));
    run->add_option("--svg", o.svg, "write the first episode's picture here");
    run->add_option("--trace", o.trace, "write the first episode's trajectory here (CSV, one row per tick)");
    run->add_option("--svg-tick", o.svg_tick, "tick whose sonar sectors are drawn (default 0; past the end: the last tick)")->check(CLI::NonNegativeNumber);
    return run;
}

// The gen-env subcommand's options, into o; *difficulty: the --difficulty option.
static CLI::App *add_gen_env(CLI::App &app, GenOpts &o, CLI::Option **difficulty) {
    CLI::App *gen = app.add_subcommand("gen-env", "write a generated environment file (a world family, or the old density form)");
    gen->add_option("--family", o.family, std::string("world family: ") + qnav_sim_world_families() + " (docs/sim.md)");
    *difficulty = gen->add_option("--difficulty", o.difficulty, "with --family: difficulty in [0, 1], at most 3 decimals")->capture_default_str();
    gen->add_option("--density", o.density, "without --family: fraction of the obstacle band covered, 0..0.5 (default 0.2)")->check(qnav::cli::finite_range(0.0, 0.5));
    gen->add_option("--seed", o.seed, "generator seed")->capture_default_str();
    gen->add_option("--robot", o.robot, "robot that must fit through (default: tekbot with --family, else pioneer3dx)");
    gen->add_option("--name", o.name, "environment name (default: the world spec, or generated-d<density>-s<seed>)");
    gen->add_option("--out", o.out, "TOML file to write")->required();
    return gen;
}

// The bench subcommand's options, into o.
static CLI::App *add_bench(CLI::App &app, BenchOpts &o) {
    CLI::App *bench = app.add_subcommand("bench", "episodes per second per core, time split");
    bench->add_option("--robot", o.robot, "robot profile")->capture_default_str();
    bench->add_option("--env", o.env, "environment name, file, or world spec gen:...")->capture_default_str();
    bench->add_option("--sectors", o.sectors, "sonar sectors")->check(CLI::Range(1, 360))->capture_default_str();
    bench->add_option("--hidden", o.hidden, "hidden units of the random network")->check(CLI::Range(1, QNAV_MAX_HIDDEN))->capture_default_str();
    bench->add_option("--policy", o.policy, "policy file, or 'prob' for the hand-tuned policy (default: a random network)")
        ->check(CLI::ExistingFile | CLI::IsMember({"prob"}));
    bench->add_flag("--fresh-network", o.fresh, "a new random network for every episode, as in evolution");
    bench->add_flag("--reference", o.reference, "the straightforward way for comparison: a Box2D ray per degree, Box2D every tick");
    bench->add_option("--episodes", o.episodes, "episodes per pass")->check(CLI::Range(1u, 10000000u))->capture_default_str();
    bench->add_option("--mode", o.mode, "controller mode")->check(CLI::IsMember({"table", "network"}))->capture_default_str();
    bench->add_option("--seed", o.seed, "context and network seed")->capture_default_str();
    bench->add_option("--sensor-noise", o.ps, "p_s")->check(qnav::cli::finite_range(0.0, 1.0))->capture_default_str();
    bench->add_option("--actuation-noise", o.pa, "p_a")->check(qnav::cli::finite_range(0.0, 1.0))->capture_default_str();
    return bench;
}

int main(int argc, char **argv) {
    CLI::App app{"qnav-sim: Box2D simulator of TekBot-class and Pioneer 3-DX robots (docs/sim.md)"};
    app.require_subcommand(1);
    qnav::cli::add_version(app, "qnav-sim");

    RunOpts ro;
    CLI::App *run = add_run(app, ro);

    std::string de_env = "dense", de_robot = "pioneer3dx", de_out;
    CLI::App *draw = app.add_subcommand("draw-env", "draw an environment (like the paper's Fig. 6) to SVG");
    draw->add_option("--env", de_env, "environment name, file, or world spec gen:FAMILY:SEED[:DIFFICULTY[:ROBOT]] (docs/sim.md)")->capture_default_str();
    draw->add_option("--robot", de_robot, "robot whose size sets the direct lines' clearance")->capture_default_str();
    draw->add_option("--out", de_out, "SVG file")->required();

    GenOpts go;
    CLI::Option *g_difficulty = nullptr;
    CLI::App *gen = add_gen_env(app, go, &g_difficulty);

    BenchOpts bo;
    CLI::App *bench = add_bench(app, bo);

    std::string rh_robot = "tekbot", rh_out;
    CLI::App *rh = app.add_subcommand("robot-header", "write a robot's board configuration as a C header (for a firmware build)");
    rh->add_option("--robot", rh_robot, "robot profile (name or file)")->capture_default_str();
    rh->add_option("OUT", rh_out, "header file to write")->required();

    if (const int status = qnav::cli::parse(app, argc, argv, "qnav-sim"); status >= 0) return status;
    try {
        if (*run) return cmd_run(ro);
        if (*draw) return cmd_draw_env(de_env, de_robot, de_out);
        if (*gen) {
            if (g_difficulty->count() > 0 && go.family.empty())
                throw SimError(QNAV_SIM_E_PARAM, "--difficulty: only with --family (the density form takes --density)");
            return cmd_gen_env(go);
        }
        if (*bench) return cmd_bench(bo);
        if (*rh) return cmd_robot_header(rh_robot, rh_out);
    } catch (const SimError &e) {
        // a bad robot, environment or policy file, or an impossible parameter
        std::fprintf(stderr, "%s\n", e.what());
        return QNAV_EXIT_USAGE;
    } catch (const WriteError &e) {
        std::fprintf(stderr, "qnav-sim: %s\n", e.what());
        return QNAV_EXIT_FAILURE;
    } catch (const std::exception &e) {
        std::fprintf(stderr, "qnav-sim: %s\n", e.what());
        return 1;
    }
    return 1;
}
