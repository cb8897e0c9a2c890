// The one mapping from a robot profile to libqnav's controller configuration (kept apart
// from the profile reader, which needs nothing of libqnav).
#include <algorithm>
#include <cmath>

#include "qnav/sim.h"
#include "robot.hpp"

namespace qnav {

// Metres (or m/s, m/s^2) to the controller's integer millimetres, saturated.
static std::uint16_t to_mm(double m) {
    return static_cast<std::uint16_t>(std::min(65535.0, std::round(m * 1000.0)));
}

// A fraction as libqnav's Q1.15, at most 32767 (1.0 is not representable).
static qnav_q1_15_t to_q1_15(double f) {
    return static_cast<qnav_q1_15_t>(std::min(32767L, std::lround(f * 32768.0)));
}

// The share of each wedge a reading blocks at n_sectors: the profile's wedge_pct, or its wedge_deg
// of that count's wedge.
static std::uint8_t robot_wedge_pct(const RobotProfile &p, std::uint16_t n_sectors) {
    if (p.wedge_deg < 0.0) return p.wedge_pct;
    // wedge_deg of an n-sector wedge's 360 / n degrees, in whole percent, at most all of it
    const long pct = std::lround(p.wedge_deg * static_cast<double>(n_sectors) * 100.0 / 360.0);
    return static_cast<std::uint8_t>(std::clamp(pct, 0L, 100L));
}

void robot_ctrl_config(const RobotProfile &p, std::uint16_t n_sectors, qnav_ctrl_config_t *cfg) {
    qnav_ctrl_config_default(cfg);
    cfg->n_sectors = n_sectors ? n_sectors : p.default_sectors;
    cfg->max_range_mm = to_mm(p.range_max_m);
    cfg->body_radius_mm = to_mm(p.radius_m);
    cfg->safety_mm = to_mm(p.safety_m);
    // a map's plan keeps the robot the safety distance off what it has seen, so the
    // controller may pass readings nearer (docs/architecture.md, "Passing distance"); not
    // with wedges wider than 60 degrees, whose reading may lie anywhere across 72-90
    // degrees: the TekBot touched something in about half its episodes at 4 and 5 sectors
    // (docs/results.md, "Fewer sectors with the map")
    constexpr std::uint16_t kPassNearerSectorsMin = 6;
    const bool nearer = p.map_cell_m > 0.0 && cfg->n_sectors >= kPassNearerSectorsMin;
    cfg->pass_mm = to_mm(nearer ? p.map_pass_m.value_or(p.safety_m) : p.safety_m);
    cfg->sensor_offset_mm = to_mm(p.sonar_offset_m);
    cfg->range_min_mm = to_mm(p.range_min_m);
    cfg->v_max_mm_s = to_mm(p.v_max_mps);
    cfg->full_speed_quality = to_q1_15(p.full_speed_quality);
    cfg->decel_mm_s2 = p.speed_guard ? to_mm(p.decel_mps2) : 0;
    cfg->wedge_pct = robot_wedge_pct(p, cfg->n_sectors);
    cfg->wedge_near_mm = to_mm(p.wedge_near_m);
    cfg->escape_stall_ticks = static_cast<std::uint8_t>(std::lround(p.escape_stall_s * 10.0));
    cfg->escape_follow_mm = to_mm(p.escape_follow_m);
    cfg->escape_follow_s = static_cast<std::uint8_t>(std::lround(p.escape_follow_s));
    cfg->keep_pct = static_cast<std::uint8_t>(std::lround(p.prob_keep * 100.0));
    cfg->quality_full_speed = to_q1_15(p.prob_full_speed_quality);
}

namespace {

// qnav_map_config_t.noise_pct for a range noise of sensor_noise (the standard deviation as a
// fraction of the range): that many per cent.
std::uint8_t map_noise_pct(double sensor_noise) {
    return static_cast<std::uint8_t>(std::lround(std::clamp(sensor_noise, 0.0, 1.0) * 100.0));
}

}  // namespace

void robot_map_config(const RobotProfile &p, qnav_map_config_t *cfg) {
    qnav_map_config_default(cfg);
    cfg->noise_pct = map_noise_pct(p.map_noise >= 0.0 ? p.map_noise : p.noise_sensor);
    cfg->cell_mm = to_mm(p.map_cell_m);
    cfg->reach_mm = to_mm(p.map_reach_m);
    cfg->look_mm = to_mm(p.map_look_m);
    cfg->plan_ticks = static_cast<std::uint8_t>(std::clamp(std::lround(p.map_plan_s / QNAV_SIM_TICK_S), 1L, 255L));
    cfg->near_mm = to_mm(p.map_near_m);
    cfg->near_cost = static_cast<std::uint8_t>(std::lround(p.map_near_cost * 10.0));
    cfg->unknown_cost = static_cast<std::uint8_t>(std::lround(p.map_unknown_cost * 10.0));
    cfg->align_samples = p.map_align_samples;
    cfg->turn_back_ticks =
        static_cast<std::uint8_t>(std::clamp(std::lround(p.map_turn_back_s / QNAV_SIM_TICK_S), 0L, 255L));
    cfg->arc_cdeg = static_cast<std::uint16_t>(std::lround(p.map_arc_deg * 100.0));
    cfg->arc_width_mm = to_mm(p.map_arc_width_m);
    cfg->sight = p.map_sight ? 1 : 0;
    cfg->escape_grow = p.map_escape_grow ? 1 : 0;
    cfg->refuse_ticks = static_cast<std::uint8_t>(std::clamp(std::lround(p.map_refuse_s / QNAV_SIM_TICK_S), 0L, 255L));
    cfg->refuse_life_ticks =
        static_cast<std::uint16_t>(std::clamp(std::lround(p.map_refuse_life_s / QNAV_SIM_TICK_S), 1L, 65535L));
    cfg->compact = p.map_compact ? 1 : 0;
    cfg->grow_steps = p.map_grow_steps;
    cfg->forget_reach_mm = to_mm(p.map_forget_reach_m);
    cfg->opening_mm = to_mm(p.map_opening_m);
}

}  // namespace qnav
