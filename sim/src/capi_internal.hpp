// The C API's opaque types, defined for the simulator's own C++ programs (CLI, pictures)
// that need to reach the C++ objects behind a handle.
#pragma once

#include <memory>

#include "env.hpp"
#include "qnav/sim.h"
#include "robot.hpp"
#include "simulation.hpp"

struct qnav_sim_robot {
    qnav::RobotProfile profile;
};
struct qnav_sim_env {
    qnav::Environment env;
};
struct qnav_sim {
    std::unique_ptr<qnav::Simulation> sim;
    char last_error[QNAV_SIM_ERRLEN] = "";
};

namespace qnav {
// Resolve a robot/env spec: a path is kept, a bare name becomes <data>/<kind>/<name>.toml.
std::string resolve_data_spec(const char *spec, const char *kind);
// A robot spec NAME+map (the profile with its [map] switched on): true and NAME in *base;
// false (base untouched) for any other spec.
bool robot_spec_with_map(const std::string &spec, std::string *base);
}  // namespace qnav
