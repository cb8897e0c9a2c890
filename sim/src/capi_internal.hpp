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
// A robot spec's map switch: NAME+map (the profile with its [map] switched on) gives +1,
// NAME-map (the profile without a map, its [map] kept described) -1, both with NAME in
// *base; 0 (base untouched) for any other spec.
int robot_spec_map(const std::string &spec, std::string *base);
}  // namespace qnav
