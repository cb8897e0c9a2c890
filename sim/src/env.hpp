// Environments: a rectangular walled arena with circular and box obstacles, start zones
// and one destination (data/envs/*.toml, format in docs/sim.md). Also the random
// environment generator (density, seed) and the writer used by `qnav-sim gen-env`.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "geometry.hpp"

namespace qnav {

struct CircleObstacle {
    double x_m, y_m, r_m;  // centre and radius, m
};
struct BoxObstacle {
    double x_m, y_m, w_m, h_m;  // centre, width (along x before rotation), height, m
    double angle_deg;           // rotation, counter-clockwise, deg
};
struct StartZone {
    double x_m, y_m, w_m, h_m;  // lower-left corner, width, height, m (axis-aligned)
};

struct Environment {
    std::string name;
    std::string source;                  // file (or name) it was read from, for messages
    double width_m = 10, height_m = 10;  // arena [0, width] x [0, height], m
    double dest_x_m = 5, dest_y_m = 9, dest_radius_m = 0.3;
    double episode_limit_s = 30;
    std::vector<StartZone> start_zones;
    std::vector<CircleObstacle> circles;
    std::vector<BoxObstacle> boxes;
    std::vector<int> zone_lines;  // source line of each start zone (for later messages)
    // The robot radius (m) that check_clearance is known to pass for, or -1: the world
    // generator checked it (clearance and a wider path than the walled-in check needs), so
    // a context made for the same robot does not check again. Set only by generate_world.
    double clearance_checked_m = -1;

    // Obstacles as shapes: circles first, then boxes (not the walls).
    std::vector<Shape> obstacle_shapes() const;
    // The four arena walls as segments.
    std::vector<Shape> wall_shapes() const;
};

// Parse and check an environment (TOML text). Throws SimError: _PARSE for malformed
// files, _WORLD for a start zone inside an obstacle or outside the arena, a destination
// overlapping an obstacle or a start zone, an obstacle wholly outside the arena.
Environment parse_environment(std::string_view text, const std::string &name);

// Check that every start zone keeps clearance_m (a robot's radius) from obstacles and
// walls and that a robot of that radius can drive from it to the destination (not walled
// in); throws SimError(QNAV_SIM_E_WORLD, "NAME:LINE: ...") otherwise. Returns at once
// when clearance_m is env.clearance_checked_m.
void check_clearance(const Environment &env, double clearance_m);
// Its first half: every start zone keeps clearance_m from obstacles and walls.
void check_zone_clearance(const Environment &env, double clearance_m);

// A random dense environment: 10 m x 10 m arena, start zones along the bottom, the
// destination at the top, obstacles covering about `density` (0..0.5) of the middle band,
// every start zone connected to the destination for a robot of radius clearance_m.
Environment generate_environment(double density, std::uint64_t seed, double clearance_m);

// TOML text of an environment (the format parse_environment reads).
std::string environment_to_toml(const Environment &env);

// Grid check that a disc of radius clearance_m can drive from the centre of every start
// zone to the destination (cells of cell_m).
bool environment_connected(const Environment &env, double clearance_m, double cell_m = 0.1);

// The cells of cell_m from the origin (nx = ceil(width / cell_m) by ny, cell (i, j) at
// [j * nx + i]) whose centre a disc of radius clearance_m fits on: inside the walls by
// clearance_m, and no obstacle nearer than that.
std::vector<char> free_cells(const Environment &env, double clearance_m, double cell_m, int *nx, int *ny);

// The index of the first start zone that such a disc cannot leave for the destination,
// or -1 when every zone is connected.
int first_walled_in_zone(const Environment &env, double clearance_m, double cell_m = 0.1);

// Steps between 4-neighbouring free cells (free[j * nx + i] != 0, cells cell_m wide from
// the origin) from the free cells whose centre lies in the destination disc (or, when
// there is none and from_goal_cell, from the destination's cell if free) to the centre
// cell of each start zone: one count per zone, -1 where no path leads.
std::vector<int> zone_steps(const Environment &env, const std::vector<char> &free, int nx, int ny,
                            double cell_m, bool from_goal_cell);

}  // namespace qnav
