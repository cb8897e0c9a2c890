// The simulator's C API (qnav/sim.h): handles over the C++ objects, exceptions turned into
// statuses and one-line messages. Nothing here throws across the C boundary.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <algorithm>
#include <cstring>
#include <memory>
#include <new>
#include <string>

#include "capi_internal.hpp"
#include "qnav/fixed_host.h"
#include "qnav/paths.hpp"
#include "error.hpp"
#include "tomlread.hpp"
#include "worldgen.hpp"

#ifndef QNAV_SIM_DATA_DIR
#define QNAV_SIM_DATA_DIR "data"
#endif

namespace {

void put_err(char *err, std::size_t errlen, const std::string &msg) {
    if (!err || errlen == 0) return;
    std::snprintf(err, errlen, "%s", msg.c_str());
}

template <typename F>
qnav_sim_status_t guarded(char *err, std::size_t errlen, F &&f) {
    try {
        f();
        return QNAV_SIM_OK;
    } catch (const qnav::SimError &e) {
        put_err(err, errlen, e.what());
        return e.status();
    } catch (const std::bad_alloc &) {
        put_err(err, errlen, "out of memory");
        return QNAV_SIM_E_NOMEM;
    } catch (const std::exception &e) {
        put_err(err, errlen, e.what());
        return QNAV_SIM_E_PARSE;
    }
}

// A *_load: resolve spec in the data folder kind, read the file and hand its text to
// parse (the matching *_parse); what names the argument in messages.
template <typename T>
qnav_sim_status_t load_spec(const char *spec, const char *kind, const char *what,
                            qnav_sim_status_t (*parse)(const char *, size_t, const char *, T **,
                                                       char *, size_t),
                            T **out, char *err, std::size_t errlen) {
    if (!out) return QNAV_SIM_E_NULL;
    *out = nullptr;
    if (!spec) {
        put_err(err, errlen, std::string(what) + ": null path");
        return QNAV_SIM_E_NULL;
    }
    std::string text, path;
    const qnav_sim_status_t st = guarded(err, errlen, [&] {
        path = qnav::resolve_data_spec(spec, kind);
        text = qnav::TomlReader::read_file(path);
    });
    if (st != QNAV_SIM_OK) return st;
    return parse(text.data(), text.size(), path.c_str(), out, err, errlen);
}

}  // namespace

namespace qnav {
std::string resolve_data_spec(const char *spec, const char *kind) {
    std::string s(spec);
    const bool is_path = s.find('/') != std::string::npos ||
                         (s.size() > 5 && s.compare(s.size() - 5, 5, ".toml") == 0);
    if (is_path) return s;
    return qnav::resource_dir("QNAV_DATA_DIR", "data", QNAV_SIM_DATA_DIR) + "/" + kind + "/" + s + ".toml";
}

int robot_spec_map(const std::string &spec, std::string *base) {
    static const std::string kMap = "map";  // after a '+' or a '-'
    const std::size_t n = kMap.size() + 1;
    if (spec.size() <= n || spec.compare(spec.size() - kMap.size(), kMap.size(), kMap) != 0) return 0;
    const char sign = spec[spec.size() - n];
    if (sign != '+' && sign != '-') return 0;
    *base = spec.substr(0, spec.size() - n);
    return sign == '+' ? 1 : -1;
}
}  // namespace qnav

extern "C" {

qnav_sim_status_t qnav_sim_robot_parse(const char *text, size_t len, const char *name,
                                       qnav_sim_robot_t **out, char *err, size_t errlen) {
    if (!out) return QNAV_SIM_E_NULL;
    *out = nullptr;
    if (!text || !name) {
        put_err(err, errlen, "robot: null argument");
        return QNAV_SIM_E_NULL;
    }
    return guarded(err, errlen, [&] {
        auto r = std::make_unique<qnav_sim_robot>();
        r->profile = qnav::parse_robot_profile(std::string_view(text, len), name);
        *out = r.release();
    });
}

qnav_sim_status_t qnav_sim_robot_load(const char *spec, qnav_sim_robot_t **out, char *err,
                                      size_t errlen) {
    // NAME+map: the profile with its [map] switched on; NAME-map: without a map (the paper's
    // robot, and the ablation), its [map] kept described as with on = false
    std::string base;
    const int sw = spec ? qnav::robot_spec_map(spec, &base) : 0;
    if (sw == 0) return load_spec(spec, "robots", "robot", qnav_sim_robot_parse, out, err, errlen);
    const qnav_sim_status_t st = load_spec(base.c_str(), "robots", "robot", qnav_sim_robot_parse, out, err, errlen);
    if (st != QNAV_SIM_OK) return st;
    qnav::RobotProfile &p = (*out)->profile;
    if (sw < 0) {
        if (p.map_cell_m > 0.0) p.map_off_cell_m = p.map_cell_m;
        p.map_cell_m = 0.0;
        return QNAV_SIM_OK;
    }
    if (p.map_cell_m <= 0.0 && p.map_off_cell_m <= 0.0) {
        qnav_sim_robot_free(*out);
        *out = nullptr;
        put_err(err, errlen, std::string("robot '") + spec + "': " + qnav::resolve_data_spec(base.c_str(), "robots") +
                                 " has no [map] section to switch on");
        return QNAV_SIM_E_PARSE;
    }
    if (p.map_cell_m <= 0.0) p.map_cell_m = p.map_off_cell_m;
    return QNAV_SIM_OK;
}

void qnav_sim_robot_free(qnav_sim_robot_t *robot) { delete robot; }

qnav_sim_status_t qnav_sim_env_parse(const char *text, size_t len, const char *name,
                                     qnav_sim_env_t **out, char *err, size_t errlen) {
    if (!out) return QNAV_SIM_E_NULL;
    *out = nullptr;
    if (!text || !name) {
        put_err(err, errlen, "env: null argument");
        return QNAV_SIM_E_NULL;
    }
    return guarded(err, errlen, [&] {
        auto e = std::make_unique<qnav_sim_env>();
        e->env = qnav::parse_environment(std::string_view(text, len), name);
        *out = e.release();
    });
}

qnav_sim_status_t qnav_sim_env_load(const char *spec, qnav_sim_env_t **out, char *err,
                                    size_t errlen) {
    if (out && spec && qnav::is_world_spec(spec)) {
        *out = nullptr;
        return guarded(err, errlen, [&] {
            auto e = std::make_unique<qnav_sim_env>();
            e->env = qnav::load_world(spec);
            *out = e.release();
        });
    }
    return load_spec(spec, "envs", "env", qnav_sim_env_parse, out, err, errlen);
}

const char *qnav_sim_world_families(void) { return qnav::world_family_names(); }

void qnav_sim_env_free(qnav_sim_env_t *env) { delete env; }

void qnav_sim_robot_info(const qnav_sim_robot_t *robot, qnav_sim_robot_info_t *info) {
    if (!robot || !info) return;
    const qnav::RobotProfile &p = robot->profile;
    info->name = p.name.c_str();
    info->radius_m = p.radius_m;
    info->v_max_mps = p.v_max_mps;
    info->accel_mps2 = p.accel_mps2;
    info->decel_mps2 = p.decel_mps2;
    info->turn_rate_max_dps = p.turn_rate_max_dps;
    info->range_min_m = p.range_min_m;
    info->range_max_m = p.range_max_m;
    info->default_sectors = p.default_sectors;
    info->sonar_offset_m = p.sonar_offset_m;
    info->wheel_base_m = p.wheel_base_m;
    info->um_per_count = p.um_per_count;
    info->tick_ms = p.tick_ms;
    info->sensor_noise = p.noise_sensor;
    info->actuation_noise = p.noise_actuation;
    info->turn_full_deg = p.turn_full_deg;
}

void qnav_sim_robot_prob_policy(const qnav_sim_robot_t *robot, qnav_policy_t *policy) {
    if (!policy) return;
    qnav_policy_prob_default(policy);
    if (!robot || robot->profile.prob_k_goal <= 0.0) return;
    policy->u.prob.k_goal = static_cast<qnav_q8_8_t>(std::lround(robot->profile.prob_k_goal * 256.0));
    policy->u.prob.k_safe = static_cast<qnav_q8_8_t>(std::lround(robot->profile.prob_k_safe * 256.0));
}

void qnav_sim_env_info(const qnav_sim_env_t *env, qnav_sim_env_info_t *info) {
    if (!env || !info) return;
    const qnav::Environment &e = env->env;
    info->name = e.name.c_str();
    info->width_m = e.width_m;
    info->height_m = e.height_m;
    info->dest_x_m = e.dest_x_m;
    info->dest_y_m = e.dest_y_m;
    info->dest_radius_m = e.dest_radius_m;
    info->episode_limit_s = e.episode_limit_s;
    info->n_obstacles = static_cast<uint32_t>(e.circles.size() + e.boxes.size());
    info->n_start_zones = static_cast<uint32_t>(e.start_zones.size());
    info->source = e.source.c_str();
}

namespace {
// The fitness rules by name: the one list that parsing, naming and messages read.
struct FitnessRuleName {
    qnav_sim_fitness_rule_t rule;
    const char *name;
};
constexpr FitnessRuleName kFitnessRules[] = {
    {QNAV_SIM_FITNESS_PROGRESS, "progress"},
    {QNAV_SIM_FITNESS_PAPER, "paper"},
};
}  // namespace

const char *qnav_sim_fitness_rule_name(qnav_sim_fitness_rule_t rule) {
    for (const FitnessRuleName &f : kFitnessRules)
        if (f.rule == rule) return f.name;
    return nullptr;
}

qnav_sim_status_t qnav_sim_fitness_rule_parse(const char *name, qnav_sim_fitness_rule_t *rule) {
    if (!name || !rule) return QNAV_SIM_E_NULL;
    for (const FitnessRuleName &f : kFitnessRules) {
        if (std::strcmp(f.name, name) == 0) {
            *rule = f.rule;
            return QNAV_SIM_OK;
        }
    }
    return QNAV_SIM_E_PARAM;
}

const char *qnav_sim_fitness_rule_names(void) {
    static const std::string names = [] {
        std::string s;
        for (const FitnessRuleName &f : kFitnessRules) s += (s.empty() ? "" : ", ") + std::string(f.name);
        return s;
    }();
    return names.c_str();
}

void qnav_sim_config_default(qnav_sim_config_t *cfg) {
    if (!cfg) return;
    cfg->n_sectors = 0;
    cfg->sensor_noise = 0.0;
    cfg->actuation_noise = 0.0;
    cfg->seed = 1;
    cfg->episode_limit_s = 0.0;
    cfg->fitness = QNAV_SIM_FITNESS_PROGRESS;
    cfg->map_frame_deg = -1.0;
    cfg->survey_m = 0.0;
}

qnav_sim_status_t qnav_sim_create(const qnav_sim_robot_t *robot, const qnav_sim_env_t *env,
                                  const qnav_sim_config_t *cfg, qnav_sim_t **out, char *err,
                                  size_t errlen) {
    if (!out) return QNAV_SIM_E_NULL;
    *out = nullptr;
    if (!robot || !env || !cfg) {
        put_err(err, errlen, "create: null robot, env or config");
        return QNAV_SIM_E_NULL;
    }
    auto bad = [&](const char *msg) {
        put_err(err, errlen, msg);
        return QNAV_SIM_E_PARAM;
    };
    if (cfg->n_sectors > QNAV_MAX_SECTORS) return bad("n_sectors: must be 1..360 (0 = profile default)");
    if (!std::isfinite(cfg->sensor_noise) || cfg->sensor_noise < 0 || cfg->sensor_noise > 1)
        return bad("sensor_noise: must be in [0, 1]");
    if (!std::isfinite(cfg->actuation_noise) || cfg->actuation_noise < 0 || cfg->actuation_noise > 1)
        return bad("actuation_noise: must be in [0, 1]");
    if (!std::isfinite(cfg->episode_limit_s) || cfg->episode_limit_s < 0 || cfg->episode_limit_s > 36000)
        return bad("episode_limit_s: must be in [0, 36000] (0 = environment's)");
    if (!qnav_sim_fitness_rule_name(cfg->fitness)) return bad("fitness: not a qnav_sim_fitness_rule_t");
    if (std::isnan(cfg->map_frame_deg) || cfg->map_frame_deg >= 360)
        return bad("map_frame_deg: must be in [0, 360), or negative (drawn per episode)");
    if (!(cfg->survey_m == 0 || (cfg->survey_m >= 0.05 && cfg->survey_m <= 10)))
        return bad("survey_m: must be 0 (off) or in [0.05, 10] m");
    if (cfg->survey_m > 0 && robot->profile.map_cell_m <= 0.0)
        return bad("survey_m: the robot profile has no [map] to survey into");
    return guarded(err, errlen, [&] {
        qnav::check_clearance(env->env, robot->profile.radius_m);
        qnav::SimConfig sc;
        sc.n_sectors = cfg->n_sectors ? cfg->n_sectors : robot->profile.default_sectors;
        sc.sensor_noise = cfg->sensor_noise;
        sc.actuation_noise = cfg->actuation_noise;
        sc.seed = cfg->seed;
        sc.episode_limit_s = cfg->episode_limit_s;
        sc.fitness = cfg->fitness;
        sc.map_frame_deg = cfg->map_frame_deg < 0 ? -1.0 : cfg->map_frame_deg;
        sc.survey_m = cfg->survey_m;
        auto s = std::make_unique<qnav_sim>();
        s->sim = std::make_unique<qnav::Simulation>(robot->profile, env->env, sc);
        *out = s.release();
    });
}

void qnav_sim_destroy(qnav_sim_t *sim) { delete sim; }

void qnav_sim_ctrl_config(const qnav_sim_t *sim, qnav_ctrl_config_t *cfg) {
    if (!sim || !cfg) return;
    qnav::robot_ctrl_config(sim->sim->robot(), sim->sim->config().n_sectors, cfg);
}

void qnav_sim_robot_ctrl_config(const qnav_sim_robot_t *robot, uint16_t n_sectors,
                                qnav_ctrl_config_t *cfg) {
    if (!robot || !cfg) return;
    qnav::robot_ctrl_config(robot->profile, n_sectors, cfg);
}

int qnav_sim_robot_map_config(const qnav_sim_robot_t *robot, qnav_map_config_t *cfg) {
    if (!robot || !cfg || robot->profile.map_cell_m <= 0.0) return 0;
    qnav::robot_map_config(robot->profile, cfg);
    return 1;
}

uint32_t qnav_sim_robot_map_bytes(const qnav_sim_robot_t *robot) {
    return robot && robot->profile.map_cell_m > 0.0 ? robot->profile.map_bytes : 0u;
}

qnav_sim_status_t qnav_sim_run_episode(qnav_sim_t *sim, const qnav_ctrl_t *ctrl,
                                       uint64_t episode_seed, qnav_sim_result_t *res,
                                       qnav_sim_trace_fn trace, void *user) {
    if (!sim || !ctrl || !res) return QNAV_SIM_E_NULL;
    sim->last_error[0] = '\0';
    return guarded(sim->last_error, sizeof sim->last_error,
                   [&] { *res = sim->sim->run_episode(ctrl, episode_seed, trace, user); });
}

qnav_sim_status_t qnav_sim_run_episode_nav(qnav_sim_t *sim, qnav_nav_t *nav, uint64_t episode_seed,
                                           qnav_sim_result_t *res, qnav_sim_trace_fn trace,
                                           void *user) {
    if (!sim || !nav || !res) return QNAV_SIM_E_NULL;
    sim->last_error[0] = '\0';
    return guarded(sim->last_error, sizeof sim->last_error,
                   [&] { *res = sim->sim->run_episode(nav, episode_seed, trace, user); });
}

qnav_sim_status_t qnav_sim_reset(qnav_sim_t *sim, uint64_t episode_seed) {
    if (!sim) return QNAV_SIM_E_NULL;
    sim->last_error[0] = '\0';
    return guarded(sim->last_error, sizeof sim->last_error, [&] { sim->sim->reset(episode_seed); });
}

qnav_sim_status_t qnav_sim_place(qnav_sim_t *sim, double x_m, double y_m, double heading_rad) {
    if (!sim) return QNAV_SIM_E_NULL;
    const qnav::Environment &e = sim->sim->env();
    if (!std::isfinite(x_m) || !std::isfinite(y_m) || !std::isfinite(heading_rad) || x_m < 0 ||
        y_m < 0 || x_m > e.width_m || y_m > e.height_m) {
        put_err(sim->last_error, sizeof sim->last_error, "place: pose outside the arena");
        return QNAV_SIM_E_PARAM;
    }
    sim->last_error[0] = '\0';
    return guarded(sim->last_error, sizeof sim->last_error,
                   [&] { sim->sim->place(x_m, y_m, heading_rad); });
}

const char *qnav_sim_last_error(const qnav_sim_t *sim) { return sim ? sim->last_error : ""; }

qnav_sim_status_t qnav_sim_scan(const qnav_sim_t *sim, qnav_sim_scan_t *scan) {
    if (!sim || !scan) return QNAV_SIM_E_NULL;
    if (!sim->sim->started()) return QNAV_SIM_E_STATE;
    // The whole struct, so that a field added to qnav_sim_scan_t cannot be left unwritten
    // (prev_heading_cdeg once was); sectors past n_sectors hold what the context holds.
    *scan = sim->sim->scan();
    return QNAV_SIM_OK;
}

qnav_sim_status_t qnav_sim_command(qnav_sim_t *sim, const qnav_ctrl_output_t *out) {
    if (!sim || !out) return QNAV_SIM_E_NULL;
    if (!sim->sim->started()) return QNAV_SIM_E_STATE;
    sim->sim->command(out->heading_deg, QNAV_Q1_15_TO_REAL(out->speed));
    return QNAV_SIM_OK;
}

qnav_sim_status_t qnav_sim_command_raw(qnav_sim_t *sim, double heading_deg, double speed) {
    if (!sim) return QNAV_SIM_E_NULL;
    if (!sim->sim->started()) return QNAV_SIM_E_STATE;
    sim->sim->command(heading_deg, speed);
    return QNAV_SIM_OK;
}

qnav_sim_status_t qnav_sim_advance(qnav_sim_t *sim) {
    if (!sim) return QNAV_SIM_E_NULL;
    sim->last_error[0] = '\0';
    return guarded(sim->last_error, sizeof sim->last_error, [&] { sim->sim->advance(); });
}

qnav_sim_status_t qnav_sim_state(const qnav_sim_t *sim, qnav_sim_state_t *state) {
    if (!sim || !state) return QNAV_SIM_E_NULL;
    if (!sim->sim->started()) return QNAV_SIM_E_STATE;
    *state = sim->sim->state();
    return QNAV_SIM_OK;
}

qnav_sim_status_t qnav_sim_result(const qnav_sim_t *sim, qnav_sim_result_t *res) {
    if (!sim || !res) return QNAV_SIM_E_NULL;
    if (!sim->sim->started()) return QNAV_SIM_E_STATE;
    *res = sim->sim->result();
    return QNAV_SIM_OK;
}

void qnav_sim_fitness(qnav_sim_result_t *res, qnav_sim_fitness_rule_t rule) {
    if (!res) return;
    qnav::compute_fitness(res, qnav_sim_fitness_rule_name(rule) ? rule : QNAV_SIM_FITNESS_PROGRESS);
}

}  // extern "C"
