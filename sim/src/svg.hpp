// Pictures: an environment drawn like the paper's Fig. 6 (obstacles, yellow start zones,
// the destination, orange straight lines that reach it unobstructed) and an episode on top
// (path, collision points, the sonar sectors at one tick), as SVG text.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "env.hpp"
#include "simulation.hpp"

namespace qnav {

struct EpisodePicture {
    std::vector<Vec2> path;               // robot centre per tick, m
    std::vector<CollisionMark> collisions;
    bool reached = false;
    // Sonar at one tick (drawn when n_sectors > 0).
    std::uint32_t sonar_tick = 0;
    Vec2 sonar_pos;                       // robot centre, m
    double sonar_heading = 0;             // rad, world frame
    std::vector<double> sonar_ranges_m;   // reported ranges (from the body surface), m
    double range_max_m = 0;
    double cone_rad = 0;                  // each sector's wedge, rad (0: 2*pi/N)
    // The map at that tick (drawn when map_drawn): the corners of each occupied cell in the
    // world, m (the map's grid may be turned against the world's, and its pose drift).
    bool map_drawn = false;
    std::vector<std::array<Vec2, 4>> map_occupied;
    std::string caption;
};

// SVG of env; robot_radius_m sets the clearance of the direct lines and the robot's size;
// episode may be null.
std::string render_svg(const Environment &env, double robot_radius_m,
                       const EpisodePicture *episode);

}  // namespace qnav
