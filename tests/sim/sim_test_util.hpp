// Helpers shared by the simulator's tests: build robots, environments and contexts from
// TOML text or the committed data files, failing the test with the library's message.
#pragma once

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

extern "C" {
#include <cmocka.h>
}

#include <cstdio>
#include <cstring>
#include <string>

#include "qnav/sim.h"

// A 10 m x 10 m arena, one small start zone in a corner, destination at (9, 9); extra
// obstacles appended as TOML.
inline std::string test_env_text(const std::string &extra) {
    return "name = \"test\"\nepisode_limit_s = 20.0\n[arena]\nwidth_m = 10.0\nheight_m = 10.0\n"
           "[destination]\nx_m = 9.0\ny_m = 9.0\nradius_m = 0.3\n"
           "[[start_zone]]\nx_m = 0.5\ny_m = 0.5\nw_m = 0.5\nh_m = 0.5\n" + extra;
}

// The input a step-API caller gives its controller for scan s after output out: the
// ranges, the destination's bearing and range, the last decision, and the escape memory it
// carries, cleared or grown as the map says (qnav_sim_scan_t.escape_clear, escape_grow_mm).
inline qnav_ctrl_input_t step_input(const qnav_sim_scan_t &s, const qnav_ctrl_output_t &out) {
    qnav_ctrl_input_t in{};
    in.ranges_mm = s.ranges_mm;
    in.goal_bearing_cdeg = s.goal_bearing_cdeg;
    in.prev_heading_cdeg = s.prev_heading_cdeg;
    in.goal_range_mm = s.goal_range_mm;
    in.escape = out.escape;
    qnav_escape_follow_plan(&in.escape, s.escape_clear, s.escape_grow_mm);
    return in;
}

// The whole file at path; fails the test when it cannot be opened.
inline std::string read_text_file(const std::string &path) {
    std::FILE *f = std::fopen(path.c_str(), "rb");
    assert_non_null(f);
    std::string text;
    char buf[4096];
    size_t n;
    while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) text.append(buf, n);
    std::fclose(f);
    return text;
}

struct TestSim {
    qnav_sim_robot_t *robot = nullptr;
    qnav_sim_env_t *env = nullptr;
    qnav_sim_t *sim = nullptr;
    ~TestSim() {
        qnav_sim_destroy(sim);
        qnav_sim_env_free(env);
        qnav_sim_robot_free(robot);
    }
};

inline void fail_with(const char *what, const char *err) {
    print_error("%s: %s\n", what, err);
    fail();
}

// robot: a profile name in data/robots, or NAME+map / NAME-map (its map on / off); env_text:
// TOML, or empty to use env_name.
inline void make_test_sim(TestSim &t, const char *robot, const std::string &env_text,
                          const char *env_name, uint16_t sectors, double ps, double pa,
                          uint64_t seed = 1,
                          qnav_sim_fitness_rule_t fitness = QNAV_SIM_FITNESS_PROGRESS) {
    char err[QNAV_SIM_ERRLEN] = "";
    std::string name = robot, sw;
    const std::size_t at = name.size() > 4 ? name.size() - 4 : 0;
    if (name.compare(at, 4, "+map") == 0 || name.compare(at, 4, "-map") == 0) {
        sw = name.substr(at);
        name.resize(at);
    }
    const std::string rpath = std::string(QNAV_TEST_DATA_DIR) + "/robots/" + name + ".toml" + sw;
    if (qnav_sim_robot_load(rpath.c_str(), &t.robot, err, sizeof err) != QNAV_SIM_OK)
        fail_with("robot", err);
    if (!env_text.empty()) {
        if (qnav_sim_env_parse(env_text.data(), env_text.size(), "test.toml", &t.env, err,
                               sizeof err) != QNAV_SIM_OK)
            fail_with("env", err);
    } else {
        const std::string epath = std::string(QNAV_TEST_DATA_DIR) + "/envs/" + env_name + ".toml";
        if (qnav_sim_env_load(epath.c_str(), &t.env, err, sizeof err) != QNAV_SIM_OK)
            fail_with("env", err);
    }
    qnav_sim_config_t cfg;
    qnav_sim_config_default(&cfg);
    cfg.n_sectors = sectors;
    cfg.sensor_noise = ps;
    cfg.actuation_noise = pa;
    cfg.seed = seed;
    cfg.fitness = fitness;
    if (qnav_sim_create(t.robot, t.env, &cfg, &t.sim, err, sizeof err) != QNAV_SIM_OK)
        fail_with("create", err);
}
