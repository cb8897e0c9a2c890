// libqnavpy (qnavpy_capi.h): the Python package's entry points over the simulator, libqnav's
// controller table, the policy files and simevo's SimRunner. Nothing here decides anything
// itself: an episode stepped from Python makes the same calls in the same order as
// qnav_sim_run_episode_nav (qnav-sim run), and evaluate runs SimRunner::run as simevo eval
// does. C++ exceptions end here as a status and one line in err.
#include "qnavpy_capi.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "capi_internal.hpp"
#include "qnav/fixed_host.h"
#include "qnav/nav.h"
#include "qnav/policy_io.h"
#include "qnav/sim.h"
#include "rng.h"
#include "sim_runner.h"
#include "task.h"

namespace {

constexpr int kErrStatus = -1;

int fail(char *err, size_t errlen, const std::string &msg, int status = kErrStatus) {
    if (err && errlen) std::snprintf(err, errlen, "%s", msg.c_str());
    return status;
}

// Run f, turning any exception into a status and its message.
template <typename F>
int guarded(char *err, size_t errlen, F &&f) {
    try {
        return f();
    } catch (const std::bad_alloc &) {
        return fail(err, errlen, "out of memory", QNAV_SIM_E_NOMEM);
    } catch (const std::exception &e) {
        return fail(err, errlen, e.what());
    }
}

// Whether Python's integer names a policy kind (qnav_policy_kind_name knows every one), so
// that it may be switched on as a qnav_policy_kind_t.
bool known_kind(int32_t kind) {
    return kind >= 0 && kind <= UINT8_MAX && qnav_policy_kind_name(static_cast<uint8_t>(kind)) != nullptr;
}

// The number of weights a policy of this shape has (0 for no kind).
int32_t weight_count(int32_t kind, int32_t hidden, int32_t inputs) {
    if (!known_kind(kind)) return 0;
    switch (static_cast<qnav_policy_kind_t>(kind)) {
    case QNAV_POLICY_PROB:
        return 2;
    case QNAV_POLICY_NET:
        return static_cast<int32_t>(QNAV_NET_WEIGHTS_IN(static_cast<uint32_t>(hidden), static_cast<uint32_t>(inputs)));
    }
    return 0;
}

// The policy (kind, hidden, inputs, weights) as libqnav's struct; false with a message
// when the shape is not one (the policy files' and libqnav's own check decide).
bool to_policy(int32_t kind, int32_t hidden, int32_t inputs, const int16_t *w, int32_t nw,
               qnav_policy_t *p, std::string *why) {
    std::memset(p, 0, sizeof *p);
    if (!known_kind(kind)) {
        *why = std::string("policy: ") + qnav_policy_status_str(QNAV_POLICY_E_KIND);
        return false;
    }
    switch (static_cast<qnav_policy_kind_t>(kind)) {
    case QNAV_POLICY_PROB:
        if (nw != 2) {
            *why = "policy: a probabilistic policy has 2 parameters (k_goal, k_safe), not " + std::to_string(nw);
            return false;
        }
        p->kind = QNAV_POLICY_PROB;
        p->u.prob.k_goal = w[0];
        p->u.prob.k_safe = w[1];
        break;
    case QNAV_POLICY_NET: {
        if (hidden < 1 || hidden > QNAV_MAX_HIDDEN || (inputs != 2 && inputs != 3)) {
            *why = std::string("policy: ") + qnav_policy_status_str(hidden < 1 || hidden > QNAV_MAX_HIDDEN
                                                                        ? QNAV_POLICY_E_HIDDEN
                                                                        : QNAV_POLICY_E_INPUTS);
            return false;
        }
        qnav_policy_net_zero_inputs(p, static_cast<uint8_t>(hidden), static_cast<uint8_t>(inputs));
        const uint16_t n = qnav_net_weight_count(&p->u.net);
        if (nw != n) {
            *why = "policy: a network of " + std::to_string(hidden) + " hidden units and " + std::to_string(inputs) +
                   " inputs has " + std::to_string(n) + " weights, not " + std::to_string(nw);
            return false;
        }
        for (uint16_t k = 0; k < n; ++k) *qnav_net_weight(&p->u.net, k) = w[k];
        break;
    }
    }
    const qnav_policy_status_t st = qnav_policy_validate(p);
    if (st != QNAV_POLICY_OK) {
        *why = std::string("policy: ") + qnav_policy_status_str(st);
        return false;
    }
    return true;
}

void from_policy(const qnav_policy_t &p, int32_t *kind, int32_t *hidden, int32_t *inputs, int16_t *w,
                 int32_t *nw) {
    *kind = p.kind;
    *hidden = 0;
    *inputs = 0;
    *nw = 0;
    switch (static_cast<qnav_policy_kind_t>(p.kind)) {
    case QNAV_POLICY_PROB:
        w[0] = p.u.prob.k_goal;
        w[1] = p.u.prob.k_safe;
        *nw = 2;
        break;
    case QNAV_POLICY_NET: {
        qnav_net_t net = p.u.net;
        *hidden = net.hidden;
        *inputs = net.inputs;
        const uint16_t n = qnav_net_weight_count(&net);
        for (uint16_t k = 0; k < n; ++k) w[k] = *qnav_net_weight(&net, k);
        *nw = n;
        break;
    }
    }
}

std::string controller_names() {
    std::string s;
    for (uint8_t i = 0; i < qnav_nav_count(); ++i) s += (i ? ", " : "") + std::string(qnav_nav_method_at(i)->name);
    return s;
}

qnav_sim_status_t load_robot(const char *spec, qnav_sim_robot_t **out, char *err, size_t errlen) {
    return qnav_sim_robot_load(spec, out, err, errlen);
}

}  // namespace

struct qpy_env {
    qnav_sim_robot_t *robot = nullptr;
    qnav_sim_env_t *world = nullptr;
    qnav_sim_t *sim = nullptr;
    qnav_sim_scan_t scan{};
    uint16_t n_sectors = 0;
    qnav_mm_t max_range_mm = 0;
    double sensor_noise = 0, actuation_noise = 0;
    std::vector<qnav_sim_sample_t> trace;
    ~qpy_env() {
        qnav_sim_destroy(sim);
        qnav_sim_env_free(world);
        qnav_sim_robot_free(robot);
    }
};

struct qpy_ctrl {
    qnav_nav_t nav{};
    std::vector<qnav_qkey_t> table;  // table mode: the compiled keys the controller reads
    qnav_ctrl_output_t last{};       // the previous output: its escape memory goes in next
    uint16_t n_sectors = 0;
    qnav_mm_t max_range_mm = 0;
};

namespace {

void write_obs(const qpy_env *e, int32_t *obs_i, double *obs_f) {
    const uint16_t n = e->n_sectors;
    for (uint16_t k = 0; k < n; ++k) obs_i[k] = e->scan.ranges_mm[k];
    obs_i[n] = e->scan.goal_bearing_cdeg;
    obs_i[n + 1] = e->scan.prev_heading_cdeg;
    obs_i[n + 2] = e->scan.goal_range_mm;
    obs_i[n + 3] = e->scan.escape_clear;
    obs_i[n + 4] = e->scan.escape_grow_mm;
    qnav_sim_state_t s;
    (void)qnav_sim_state(e->sim, &s);
    obs_f[0] = s.x_m;
    obs_f[1] = s.y_m;
    obs_f[2] = s.heading_rad;
    obs_f[3] = s.speed_mps;
    obs_f[4] = s.goal_distance_m;
}

void write_result(const qnav_sim_result_t &r, double *res) {
    const double v[QPY_RESULT] = {r.R,      r.f1,       r.f2,        static_cast<double>(r.tau_c),
                                  r.reached ? 1.0 : 0.0, static_cast<double>(r.ticks),
                                  static_cast<double>(r.collisions), r.l, r.beta_l, r.tau_l,
                                  r.beta_tau, r.d_start_m, r.d_end_m, r.start_x_m, r.start_y_m,
                                  r.start_heading_rad};
    std::copy(v, v + QPY_RESULT, res);
}

// The same check qnav_sim_run_episode makes of its controller, with the same words.
bool sensors_match(const qpy_env *e, const qpy_ctrl *c, std::string *why) {
    if (c->n_sectors != e->n_sectors) {
        *why = "controller: n_sectors " + std::to_string(c->n_sectors) + " does not match the simulation's " +
               std::to_string(e->n_sectors);
        return false;
    }
    if (c->max_range_mm != e->max_range_mm) {
        *why = "controller: max_range_mm " + std::to_string(c->max_range_mm) + " does not match the robot's " +
               std::to_string(e->max_range_mm);
        return false;
    }
    return true;
}

void append_sample(void *user, const qnav_sim_sample_t *s) {
    static_cast<std::vector<qnav_sim_sample_t> *>(user)->push_back(*s);
}

}  // namespace

extern "C" {

const char *qpy_version(void) { return QNAV_VERSION; }
const char *qpy_world_families(void) { return qnav_sim_world_families(); }
const char *qpy_controller_names(void) {
    static const std::string names = controller_names();
    return names.c_str();
}

int qpy_robot_info(const char *spec, double *info, char *name, size_t namelen, int16_t *prob, char *err,
                   size_t errlen) {
    qnav_sim_robot_t *r = nullptr;
    const qnav_sim_status_t st = load_robot(spec, &r, err, errlen);
    if (st != QNAV_SIM_OK) return st;
    qnav_sim_robot_info_t ri;
    qnav_sim_robot_info(r, &ri);
    const double v[12] = {ri.radius_m,    ri.v_max_mps,   ri.accel_mps2,   ri.decel_mps2,
                          ri.turn_rate_max_dps, ri.range_min_m, ri.range_max_m,
                          static_cast<double>(ri.default_sectors), ri.sonar_offset_m, ri.wheel_base_m,
                          ri.sensor_noise, ri.actuation_noise};
    std::copy(v, v + 12, info);
    std::snprintf(name, namelen, "%s", ri.name);
    qnav_policy_t p;
    qnav_sim_robot_prob_policy(r, &p);
    prob[0] = p.u.prob.k_goal;
    prob[1] = p.u.prob.k_safe;
    qnav_sim_robot_free(r);
    return 0;
}

int qpy_world_info(const char *spec, double *info, char *name, size_t namelen, char *err, size_t errlen) {
    qnav_sim_env_t *w = nullptr;
    const qnav_sim_status_t st = qnav_sim_env_load(spec, &w, err, errlen);
    if (st != QNAV_SIM_OK) return st;
    qnav_sim_env_info_t wi;
    qnav_sim_env_info(w, &wi);
    const double v[9] = {wi.width_m, wi.height_m, wi.dest_x_m, wi.dest_y_m, wi.dest_radius_m,
                         wi.episode_limit_s, static_cast<double>(wi.n_obstacles),
                         static_cast<double>(wi.n_start_zones), 0.0};
    std::copy(v, v + 9, info);
    std::snprintf(name, namelen, "%s", wi.name);
    qnav_sim_env_free(w);
    return 0;
}

int qpy_policy_check(int32_t kind, int32_t hidden, int32_t inputs, const int16_t *w, int32_t nw, char *err,
                     size_t errlen) {
    qnav_policy_t p;
    std::string why;
    return to_policy(kind, hidden, inputs, w, nw, &p, &why) ? 0 : fail(err, errlen, why);
}

int qpy_policy_read(const char *path, int32_t *kind, int32_t *hidden, int32_t *inputs, int16_t *w, int32_t *nw,
                    char *err, size_t errlen) {
    return guarded(err, errlen, [&] {
        // simevo's reader: the same "not found" line and the policy files' FILE:LINE lines
        const qnav_policy_t p = qnav::read_policy_file(path);
        from_policy(p, kind, hidden, inputs, w, nw);
        return 0;
    });
}

int qpy_policy_write(const char *path, int32_t kind, int32_t hidden, int32_t inputs, const int16_t *w,
                     int32_t nw, const char *comment, char *err, size_t errlen) {
    qnav_policy_t p;
    std::string why;
    if (!to_policy(kind, hidden, inputs, w, nw, &p, &why)) return fail(err, errlen, why);
    return qnav_policy_write(path, &p, comment, err, errlen) == 0 ? 0 : kErrStatus;
}

int qpy_env_create(const char *robot, const char *world, int32_t sectors, double sensor_noise,
                   double actuation_noise, uint64_t seed, double limit_s, const char *fitness,
                   double map_frame_deg, double survey_m, qpy_env_t **out,
                   char *err, size_t errlen) {
    *out = nullptr;
    return guarded(err, errlen, [&] {
        auto e = std::make_unique<qpy_env>();
        qnav_sim_status_t st = load_robot(robot, &e->robot, err, errlen);
        if (st != QNAV_SIM_OK) return static_cast<int>(st);
        st = qnav_sim_env_load(world, &e->world, err, errlen);
        if (st != QNAV_SIM_OK) return static_cast<int>(st);
        qnav_sim_robot_info_t ri;
        qnav_sim_robot_info(e->robot, &ri);
        qnav_sim_fitness_rule_t rule = QNAV_SIM_FITNESS_PROGRESS;
        if (qnav_sim_fitness_rule_parse(fitness, &rule) != QNAV_SIM_OK)
            return fail(err, errlen,
                        std::string("--fitness: '") + fitness + "' is not one of " + qnav_sim_fitness_rule_names(),
                        QNAV_SIM_E_PARAM);
        if (sectors < 0 || sectors > QNAV_MAX_SECTORS)
            return fail(err, errlen, "n_sectors: must be 1..360 (0 = profile default)", QNAV_SIM_E_PARAM);
        qnav_sim_config_t cfg;
        qnav_sim_config_default(&cfg);
        cfg.n_sectors = static_cast<uint16_t>(sectors);
        cfg.sensor_noise = sensor_noise >= 0 ? sensor_noise : ri.sensor_noise;
        cfg.actuation_noise = actuation_noise >= 0 ? actuation_noise : ri.actuation_noise;
        cfg.seed = seed;
        cfg.episode_limit_s = limit_s;
        cfg.fitness = rule;
        if (map_frame_deg >= 360.0 || std::isnan(map_frame_deg)) {  // qnav-sim run --map-frame's line
            std::ostringstream got;
            got << map_frame_deg;
            return fail(err, errlen, "--map-frame: expected a number in [0, 360), got '" + got.str() + "'",
                        QNAV_SIM_E_PARAM);
        }
        cfg.map_frame_deg = map_frame_deg;
        cfg.survey_m = survey_m;
        st = qnav_sim_create(e->robot, e->world, &cfg, &e->sim, err, errlen);
        if (st != QNAV_SIM_OK) return static_cast<int>(st);
        qnav_ctrl_config_t cc;
        qnav_sim_ctrl_config(e->sim, &cc);
        e->n_sectors = cc.n_sectors;
        e->max_range_mm = cc.max_range_mm;
        e->sensor_noise = cfg.sensor_noise;
        e->actuation_noise = cfg.actuation_noise;
        *out = e.release();
        return 0;
    });
}

void qpy_env_free(qpy_env_t *env) { delete env; }

void qpy_env_params(const qpy_env_t *e, double *params) {
    const qnav::Simulation &s = *e->sim->sim;
    const double limit = s.config().episode_limit_s > 0 ? s.config().episode_limit_s : s.env().episode_limit_s;
    params[0] = e->n_sectors;
    params[1] = e->max_range_mm;
    params[2] = std::max(1.0, std::round(limit / QNAV_SIM_TICK_S));
    params[3] = e->sensor_noise;
    params[4] = e->actuation_noise;
}

int qpy_env_reset(qpy_env_t *e, uint64_t episode_seed, qpy_ctrl_t *ctrl, int32_t *obs_i, double *obs_f,
                  double *info, char *err, size_t errlen) {
    std::string why;
    if (ctrl && !sensors_match(e, ctrl, &why)) return fail(err, errlen, why, QNAV_SIM_E_PARAM);
    const qnav_sim_status_t st = qnav_sim_reset(e->sim, episode_seed);
    if (st != QNAV_SIM_OK) return fail(err, errlen, qnav_sim_last_error(e->sim), st);
    if (ctrl) qpy_ctrl_reset(ctrl);
    (void)qnav_sim_scan(e->sim, &e->scan);
    write_obs(e, obs_i, obs_f);
    qnav_sim_state_t s;
    (void)qnav_sim_state(e->sim, &s);
    const double v[QPY_INFO] = {0, s.done ? 1.0 : 0.0, s.reached ? 1.0 : 0.0, 0, 0, 0, 0, 0, -1, 0};
    std::copy(v, v + QPY_INFO, info);
    return 0;
}

int qpy_env_step(qpy_env_t *e, qpy_ctrl_t *ctrl, double heading_deg, double speed, int32_t *obs_i, double *obs_f,
                 double *info, char *err, size_t errlen) {
    qnav_sim_state_t before;
    if (qnav_sim_state(e->sim, &before) != QNAV_SIM_OK)
        return fail(err, errlen, "step: no episode (call reset first)", QNAV_SIM_E_STATE);
    if (before.done) return fail(err, errlen, "step: the episode is over (call reset)", QNAV_SIM_E_STATE);
    int flags = -1;
    double cmd_heading = heading_deg, cmd_speed = speed;
    if (ctrl) {
        std::string why;
        if (!sensors_match(e, ctrl, &why)) return fail(err, errlen, why, QNAV_SIM_E_PARAM);
        // the loop body of qnav_sim_run_episode_nav: this tick's scan, the previous
        // output's escape memory, one step, its command
        qnav_ctrl_input_t in{};
        in.ranges_mm = e->scan.ranges_mm;
        in.goal_bearing_cdeg = e->scan.goal_bearing_cdeg;
        in.prev_heading_cdeg = e->scan.prev_heading_cdeg;
        in.goal_range_mm = e->scan.goal_range_mm;
        in.escape = ctrl->last.escape;
        qnav_escape_follow_plan(&in.escape, e->scan.escape_clear, e->scan.escape_grow_mm);
        qnav_nav_step(&ctrl->nav, &in, &ctrl->last);
        if (ctrl->last.flags & QNAV_FLAG_NOT_READY)
            return fail(err, errlen, "controller: not initialised (qnav_ctrl_init failed or was not called)",
                        QNAV_SIM_E_PARAM);
        (void)qnav_sim_command(e->sim, &ctrl->last);
        flags = ctrl->last.flags;
        cmd_heading = ctrl->last.heading_deg;
        cmd_speed = QNAV_Q1_15_TO_REAL(ctrl->last.speed);
    } else {
        (void)qnav_sim_command_raw(e->sim, heading_deg, speed);
    }
    const qnav_sim_status_t st = qnav_sim_advance(e->sim);
    if (st != QNAV_SIM_OK) return fail(err, errlen, qnav_sim_last_error(e->sim), st);
    (void)qnav_sim_scan(e->sim, &e->scan);
    write_obs(e, obs_i, obs_f);
    qnav_sim_state_t s;
    (void)qnav_sim_state(e->sim, &s);
    double R = 0;
    if (s.done) {
        qnav_sim_result_t r;
        (void)qnav_sim_result(e->sim, &r);
        R = r.R;
    }
    const double v[QPY_INFO] = {static_cast<double>(s.tick), s.done ? 1.0 : 0.0, s.reached ? 1.0 : 0.0,
                                s.recovering ? 1.0 : 0.0, static_cast<double>(s.collisions),
                                s.collisions > before.collisions ? 1.0 : 0.0, cmd_heading, cmd_speed,
                                static_cast<double>(flags), R};
    std::copy(v, v + QPY_INFO, info);
    return 0;
}

int qpy_env_result(const qpy_env_t *e, double *res, char *err, size_t errlen) {
    qnav_sim_result_t r;
    if (qnav_sim_result(e->sim, &r) != QNAV_SIM_OK)
        return fail(err, errlen, "result: no episode (call reset first)", QNAV_SIM_E_STATE);
    write_result(r, res);
    return 0;
}

int qpy_env_run_episode(qpy_env_t *e, qpy_ctrl_t *ctrl, uint64_t episode_seed, double *res, char *err,
                        size_t errlen) {
    std::string why;
    if (!sensors_match(e, ctrl, &why)) return fail(err, errlen, why, QNAV_SIM_E_PARAM);
    e->trace.clear();
    qnav_sim_result_t r;
    const qnav_sim_status_t st = qnav_sim_run_episode_nav(e->sim, &ctrl->nav, episode_seed, &r, append_sample,
                                                          &e->trace);
    if (st != QNAV_SIM_OK) return fail(err, errlen, qnav_sim_last_error(e->sim), st);
    (void)qnav_sim_scan(e->sim, &e->scan);
    write_result(r, res);
    return 0;
}

int64_t qpy_env_trace(const qpy_env_t *e, double *rows) {
    if (rows) {
        for (const qnav_sim_sample_t &s : e->trace) {
            const double v[QPY_TRACE_COLS] = {static_cast<double>(s.tick), s.x_m, s.y_m, s.heading_rad, s.speed_mps,
                                              static_cast<double>(s.cmd_heading_deg), s.cmd_speed,
                                              s.recovering ? 1.0 : 0.0, s.collided ? 1.0 : 0.0};
            rows = std::copy(v, v + QPY_TRACE_COLS, rows);
        }
    }
    return static_cast<int64_t>(e->trace.size());
}

void qpy_env_shapes(const qpy_env_t *e, double *circles, int32_t *n_circles, double *boxes, int32_t *n_boxes) {
    const qnav::Environment &w = e->world->env;
    *n_circles = static_cast<int32_t>(w.circles.size());
    *n_boxes = static_cast<int32_t>(w.boxes.size());
    for (std::size_t i = 0; circles && i < w.circles.size(); ++i) {
        const double v[3] = {w.circles[i].x_m, w.circles[i].y_m, w.circles[i].r_m};
        std::copy(v, v + 3, circles + 3 * i);
    }
    for (std::size_t i = 0; boxes && i < w.boxes.size(); ++i) {
        const qnav::BoxObstacle &b = w.boxes[i];
        const double v[5] = {b.x_m, b.y_m, b.w_m, b.h_m, b.angle_deg};
        std::copy(v, v + 5, boxes + 5 * i);
    }
}

int qpy_ctrl_create(const char *name, const qpy_env_t *env, const char *robot, int32_t sectors, int32_t max_range_mm,
                    int32_t kind, int32_t hidden, int32_t inputs, const int16_t *w, int32_t nw, int32_t table,
                    qpy_ctrl_t **out, char *err, size_t errlen) {
    *out = nullptr;
    return guarded(err, errlen, [&] {
        const qnav_nav_method_t *m = qnav_nav_find(name);
        if (!m)
            return fail(err, errlen,
                        std::string("--controller: no controller '") + name + "' (" + controller_names() + ")");
        if (sectors < 0 || sectors > QNAV_MAX_SECTORS)
            return fail(err, errlen, "n_sectors: must be 1..360 (0 = profile default)", QNAV_SIM_E_PARAM);
        qnav_ctrl_config_t cc;
        qnav_policy_t pol;
        qnav_policy_prob_default(&pol);
        if (env) {
            qnav_sim_ctrl_config(env->sim, &cc);
            qnav_sim_robot_prob_policy(env->robot, &pol);
        } else if (robot) {
            qnav_sim_robot_t *r = nullptr;
            const qnav_sim_status_t st = load_robot(robot, &r, err, errlen);
            if (st != QNAV_SIM_OK) return static_cast<int>(st);
            qnav_sim_robot_ctrl_config(r, static_cast<uint16_t>(sectors), &cc);
            qnav_sim_robot_prob_policy(r, &pol);
            qnav_sim_robot_free(r);
        } else {
            qnav_ctrl_config_default(&cc);
            if (sectors > 0) cc.n_sectors = static_cast<uint16_t>(sectors);
            if (max_range_mm > 0) cc.max_range_mm = static_cast<qnav_mm_t>(std::min(max_range_mm, 65535));
        }
        std::string why;
        if (kind > 0 && !to_policy(kind, hidden, inputs, w, nw, &pol, &why)) return fail(err, errlen, why);
        if (!m->uses_policy && kind > 0)
            return fail(err, errlen, std::string("--policy: controller ") + name + " takes no policy");
        auto c = std::make_unique<qpy_ctrl>();
        qnav_status_t st = qnav_nav_init(&c->nav, m, &cc, &pol);
        if (st != QNAV_OK)
            return fail(err, errlen, std::string("--controller ") + name + ": " + qnav_status_str(st));
        if (table) {
            // as qnav-sim run --table: the path-quality controller's keys compiled once
            qnav_ctrl_t *paths = qnav_nav_paths(&c->nav);
            if (!paths) return fail(err, errlen, std::string("--table: controller ") + name + " has no quality table");
            qnav_ctrl_config_t own;
            qnav_nav_config(m, &cc, &own);
            c->table.assign(QNAV_QTABLE_ENTRIES, 0);
            st = qnav_ctrl_build_table(paths, c->table.data());
            if (st == QNAV_OK) st = qnav_ctrl_init_table(paths, &own, c->table.data(), qnav_ctrl_rank(paths));
            if (st != QNAV_OK) return fail(err, errlen, std::string("--table: ") + qnav_status_str(st));
        }
        qnav_nav_sensors(&c->nav, &c->n_sectors, &c->max_range_mm);
        *out = c.release();
        return 0;
    });
}

void qpy_ctrl_free(qpy_ctrl_t *ctrl) { delete ctrl; }

void qpy_ctrl_sensors(const qpy_ctrl_t *c, int32_t *n_sectors, int32_t *max_range_mm) {
    *n_sectors = c->n_sectors;
    *max_range_mm = c->max_range_mm;
}

void qpy_ctrl_reset(qpy_ctrl_t *c) {
    qnav_nav_reset(&c->nav);
    c->last = qnav_ctrl_output_t{};
}

int qpy_ctrl_step(qpy_ctrl_t *c, const uint16_t *ranges_mm, int32_t n, int32_t goal_bearing_cdeg,
                  int32_t prev_heading_cdeg, int32_t goal_range_mm, int32_t escape_clear, int32_t escape_grow_mm,
                  int32_t *out, int16_t *qualities, char *err, size_t errlen) {
    if (n != c->n_sectors)
        return fail(err, errlen, "ranges: " + std::to_string(n) + " readings for a controller of " +
                                     std::to_string(c->n_sectors) + " sectors");
    qnav_ctrl_input_t in{};
    in.ranges_mm = ranges_mm;
    in.goal_bearing_cdeg = static_cast<qnav_cdeg_t>(std::clamp(goal_bearing_cdeg, -32768, 32767));
    in.prev_heading_cdeg = static_cast<qnav_cdeg_t>(std::clamp(prev_heading_cdeg, -32768, 32767));
    in.goal_range_mm = static_cast<qnav_mm_t>(std::clamp(goal_range_mm, 0, 65535));
    in.escape = c->last.escape;
    qnav_escape_follow_plan(&in.escape, escape_clear,
                            static_cast<uint16_t>(std::clamp(escape_grow_mm, 0, 65535)));
    qnav_ctrl_t *paths = qnav_nav_paths(&c->nav);
    if (qualities && !paths) return fail(err, errlen, "qualities: VFH+ has no path qualities");
    if (qualities)
        qnav_ctrl_step(paths, &in, &c->last, qualities);  // what the "body"/"literal" row's step does
    else
        qnav_nav_step(&c->nav, &in, &c->last);
    out[0] = c->last.heading_deg;
    out[1] = c->last.speed;
    out[2] = c->last.quality;
    out[3] = c->last.flags;
    return 0;
}

int qpy_ctrl_grid(const qpy_ctrl_t *c, int16_t *keys, int16_t *qualities, int32_t *rank, char *err,
                  size_t errlen) {
    qnav_ctrl_t *paths = qnav_nav_paths(const_cast<qnav_nav_t *>(&c->nav));
    if (!paths) return fail(err, errlen, "grid: VFH+ has no path qualities");
    for (uint8_t lv = 0; lv < QNAV_DIST_LEVELS; ++lv) {
        for (uint16_t d = 0; d <= QNAV_DTHETA_MAX; ++d) {
            const qnav_qkey_t k = qnav_ctrl_key(paths, lv, static_cast<uint8_t>(d));
            keys[lv * (QNAV_DTHETA_MAX + 1) + d] = k;
            qualities[lv * (QNAV_DTHETA_MAX + 1) + d] = qnav_ctrl_key_quality(paths, k);
        }
    }
    *rank = qnav_ctrl_rank(paths);
    return 0;
}

int qpy_evaluate(const char *robot, const char *world, int32_t sectors, double noise, uint64_t seed,
                 const char *fitness, int32_t n_policies, const int32_t *kind, const int32_t *hidden,
                 const int32_t *inputs, const int16_t *w, uint32_t episodes, int32_t jobs, double *R,
                 uint8_t *reached, uint32_t *tau_c, double *f1, double *f2, char *err, size_t errlen) {
    return guarded(err, errlen, [&] {
        qnav_sim_fitness_rule_t rule = QNAV_SIM_FITNESS_PROGRESS;
        if (qnav_sim_fitness_rule_parse(fitness, &rule) != QNAV_SIM_OK)
            throw qnav::UserError(std::string("--fitness: '") + fitness + "' is not one of " +
                                  qnav_sim_fitness_rule_names());
        if (sectors < 0 || sectors > QNAV_MAX_SECTORS)
            throw qnav::UserError("--sectors: Value " + std::to_string(sectors) + " not in range 0 to 360");
        // the context simevo eval makes (scenario_from with one noise level)
        qnav::Scenario sc;
        sc.fitness = rule;
        sc.environment = world;
        sc.robot = robot;
        sc.sectors = static_cast<uint32_t>(sectors);
        sc.sensor_noise = sc.actuation_noise = noise;
        qnav::SimWorlds worlds;
        std::vector<qnav_policy_t> pols(static_cast<std::size_t>(n_policies));
        {
            qnav::SimRunner probe(worlds, sc, seed, true);  // bad robot, world or noise: now
            for (int32_t p = 0; p < n_policies; ++p) {
                std::string why;
                if (kind[p] == QPY_KIND_ROBOT_PROB) {
                    pols[p] = probe.probabilistic_policy();
                } else if (!to_policy(kind[p], hidden[p], inputs[p], w + p * QPY_MAX_WEIGHTS,
                                      weight_count(kind[p], hidden[p], inputs[p]), &pols[p], &why)) {
                    throw qnav::UserError("policy " + std::to_string(p) + ": " + why);
                }
            }
        }
        const uint64_t total = static_cast<uint64_t>(n_policies) * episodes;
        unsigned n_threads = jobs > 0 ? static_cast<unsigned>(jobs) : std::max(1u, std::thread::hardware_concurrency());
        n_threads = static_cast<unsigned>(std::min<uint64_t>(n_threads, std::max<uint64_t>(1, total)));
        std::atomic<uint64_t> next{0};
        std::mutex mu;
        std::string first_error;
        auto work = [&] {
            try {
                qnav::SimRunner runner(worlds, sc, seed, true);
                for (uint64_t i = next++; i < total; i = next++) {
                    const std::size_t p = static_cast<std::size_t>(i / episodes);
                    const uint32_t ep = static_cast<uint32_t>(i % episodes);
                    const qnav::EpisodeOutcome o = runner.run(pols[p], qnav::mix_seed(seed, ep));
                    R[i] = o.R;
                    reached[i] = o.reached ? 1 : 0;
                    tau_c[i] = o.tau_c;
                    f1[i] = o.f1;
                    f2[i] = o.f2;
                }
            } catch (const std::exception &e) {
                std::lock_guard<std::mutex> lock(mu);
                if (first_error.empty()) first_error = e.what();
                next = total;
            }
        };
        std::vector<std::thread> pool;
        for (unsigned t = 1; t < n_threads; ++t) pool.emplace_back(work);
        work();
        for (std::thread &t : pool) t.join();
        if (!first_error.empty()) throw qnav::UserError(first_error);
        return 0;
    });
}

}  // extern "C"
