// World families: the one generator that training, validation and test worlds come from
// (issue 18). A world is named by a spec string, gen:FAMILY:SEED[:DIFFICULTY[:ROBOT]]
// (grammar in docs/sim.md), that every tool accepts wherever an environment is named
// (qnav_sim_env_load). Families: clutter (circles and boxes at a density), gaps (walls
// crossing the arena with one gap each, offset from the straight line), corridor
// (S-shaped and zig-zag corridors, cellular-automaton mazes), pocket (U-pockets facing the
// start, dead ends, clutter) and rooms (rooms joined by doors). Gap, corridor and door
// widths scale with the robot's diameter; every world is checked passable for the
// robot's body and is a pure function of (family, seed, difficulty, robot profile).
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "env.hpp"
#include "robot.hpp"

namespace qnav {

// A parsed world spec. difficulty_milli is the difficulty in thousandths (0..1000), so
// that the spec, the name and the generator agree exactly on the value.
struct WorldSpec {
    std::string family;
    std::uint64_t seed = 0;
    int difficulty_milli = 500;
    std::string robot = "tekbot";  // robot name or file, as qnav_sim_robot_load takes it
};

// True when spec starts with "gen:" (a generated world, not a file or a name).
bool is_world_spec(std::string_view spec);

// Parse "gen:FAMILY:SEED[:DIFFICULTY[:ROBOT]]". Throws SimError(QNAV_SIM_E_PARAM) with one
// line naming the spec and what is wrong (unknown family with the list of families, a
// seed that is not a whole number, a difficulty outside [0, 1] or with more than three
// decimals, an empty field).
WorldSpec parse_world_spec(std::string_view spec);

// The canonical spec, every field spelled out ("gen:clutter:7:0.5:tekbot"): the name of
// the generated environment.
std::string world_spec_name(const WorldSpec &w);

// The family names, comma-separated ("clutter, gaps, corridor, pocket, rooms").
const char *world_family_names();

// What the generator knows about a world beyond its TOML (for tests and pictures).
struct WorldNotes {
    int attempt = 0;                          // 0 = the first layout drawn was passable
    double path_m = 0;                        // longest grid path start zone -> destination, m
    std::vector<std::size_t> pocket_bottoms;  // pocket: index in env.boxes of each U's
                                              // bottom wall that a straight line runs into
    std::vector<std::size_t> pocket_arms;     // pocket: its two arms (pairs, same order)
};

// Generate the world w for this robot profile (w.robot is only its name here). The
// result is what parse_environment reads back from its own TOML (so `gen-env` writes
// exactly the loaded world), its name and source are world_spec_name(w). Throws
// SimError(QNAV_SIM_E_PARAM) for an unknown family, (QNAV_SIM_E_WORLD) when no passable
// layout was found (not seen in the tests' seeds).
Environment generate_world(const WorldSpec &w, const RobotProfile &robot, WorldNotes *notes = nullptr);

// parse_world_spec + load the robot (a name in data/robots or a file) + generate_world.
Environment load_world(std::string_view spec, WorldNotes *notes = nullptr);

// Longest shortest path (m) on a grid of cell_m cells from the centre of any start zone to
// the destination for a disc of radius clearance_m, or -1 when some zone is walled in.
// Obstacles are rasterised over their bounding squares only.
double passable_path_m(const Environment &env, double clearance_m, double cell_m = 0.1);

}  // namespace qnav
