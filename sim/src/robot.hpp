// Robot profiles: the physical description of a two-wheeled robot with a caster and a
// ring of sonar (data/robots/*.toml, format in docs/sim.md). Loaded once, immutable,
// shared by every context that simulates that robot.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "qnav/ctrl.h"
#include "qnav/map.h"

namespace qnav {

struct RobotProfile {
    std::string name;
    // body
    double radius_m = 0.2;          // collision radius (circumscribed circle), m
    double mass_kg = 5.0;           // mass, kg
    double wheel_base_m = 0.3;      // distance between the driven wheels, m
    // drive
    double v_max_mps = 0.5;         // maximum wheel / forward speed, m/s
    double full_speed_quality = 0.9; // the chosen path's quality commanded at v_max (speed
                                     // linear below it; paper: 0.9), (0, 1]
    double accel_mps2 = 1.0;        // wheel acceleration limit (speeding up), m/s^2
    double decel_mps2 = 1.0;        // wheel deceleration limit (slowing down), m/s^2
    // where accel_mps2 / decel_mps2 act (docs/sim.md, "Drive model"): on each wheel, or on
    // the body's forward speed and turn rate separately (the Pioneer's ARCOS servo:
    // translational and rotational profiles, so braking does not wait for a turn)
    bool body_limits = false;       // [drive] limits = "wheel" (false) or "body" (true)
    // [drive] model: "heading" (false), a heading controller turning the body to each
    // decision; "mix" (true), each decision mixed into two wheel speeds open-loop as the
    // board does (qnav_drive_mix; the TekBot's board drives its motors so), each wheel at
    // accel / decel
    bool drive_mix = false;
    // [drive] brake_first (model "heading"): a decision without a forward part while the
    // robot rolls faster than v_max / 8 holds the heading and brakes first, as the mix does
    // (qnav_drive_brakes_first; docs/sim.md, "Brake, then turn"); false: the ablation
    bool brake_first = true;
    double turn_rate_max_dps = 180; // turn-rate limit of the heading controller, deg/s
    double heading_gain_per_s = 4;  // heading controller: turn rate = gain * error, 1/s
    // model "mix": where the mixer's turn part reaches full wheel speed, deg: the heading
    // whose turn rate at heading_gain_per_s is full wheel speed's, 2 v_max / (b gain) rad,
    // 90..360 (docs/sim.md, "A turn in the robot's own units")
    std::uint16_t turn_full_deg = 90;
    // slip
    double slip_turn = 0.0;         // fraction of the wheel turn rate lost at full speed
    double slip_lateral_s = 0.0;    // sideways skid speed per (speed * turn rate), s
    // sonar
    double range_min_m = 0.05;      // closer obstacles read this, m
    double range_max_m = 3.0;       // farther obstacles are not seen (read max), m
    double sonar_offset_m = 0.2;    // robot centre to where ranges are measured from (the
                                    // transducers), m; the sonar reaches range_max_m beyond it
    std::uint16_t default_sectors = 16;
    double cone_deg = 0.0;          // physical cone of one reading, deg; 0 = 360/N (see
                                    // docs/sim.md); wider cones overlap, at most 180
    // what libqnav's clearance uses (qnav_sim_robot_ctrl_config): obstacle enlargement by
    // radius_m + safety_m, and the speed guard with decel_mps2
    double safety_m = 0.05;         // safety distance d_s, m ([clearance], required)
    bool speed_guard = true;        // cap the speed at what the path's clearance stops in
    std::uint8_t wedge_pct = 100;   // a reading blocks the central wedge_pct % of its
                                    // sector's wedge before enlargement (docs/architecture.md)
    double wedge_deg = -1.0;        // or the central wedge_deg of it, whatever the sector
                                    // count (wedge_pct from it per count); < 0: wedge_pct
    double wedge_near_m = 0.0;      // nearer readings block their whole wedge, m
    // leaving dead ends (libqnav's escape; docs/architecture.md, "Leaving dead ends")
    double escape_stall_s = 2.0;    // time without progress before following a boundary,
                                    // s; 0: no escape
    double escape_follow_m = 0.5;   // paths with less clearance are blocked when following, m
    double escape_follow_s = 20.0;  // first follow of one side at most, s
    // the map and its plan above the controller (libqnav qnav/map.h; docs/architecture.md,
    // "A map and a plan"); map_cell_m 0: none
    double map_cell_m = 0.0;        // cell side, m
    double map_off_cell_m = 0.0;    // [map] on = false: the cell side NAME+map switches on
    double map_reach_m = 2.0;       // readings mark cells out to this distance, m
    double map_look_m = 1.0;        // the sub-goal lies this far along the plan, m
    double map_plan_s = 1.0;        // time between plans, s
    double map_near_m = 0.2;        // cells this much beyond the body's reach of a wall...
    double map_near_cost = 1.0;     // ...cost this much more to cross, in cell sides
    double map_unknown_cost = 0.0;  // a cell not yet seen costs this much more, cell sides
    std::uint8_t map_align_samples = 0;  // wall readings before the grid turns to the walls; 0: never
    double map_turn_back_s = 0.0;   // a plan turned back is followed after this long; 0: at once
    double map_noise = -1.0;        // [map] noise: the range noise the map allows for (its
                                    // noise_pct); < 0: [noise] sensor
    double map_arc_deg = 22.5;      // arcs marked within this angle about the wedge's centre
    double map_arc_width_m = 0.0;   // ...and within this width across at the reading's range; 0: any
    double map_forget_reach_m = 0.0;  // after a forget, only readings this near mark; 0: all
    double map_opening_m = 0.0;       // a range peak whose wedge spans more than twice this marks no arc; 0: all mark
    bool map_sight = true;          // the sub-goal kept in a straight line's sight
    bool map_escape_grow = true;    // a longer plan grows the escape's distances with it
    double map_refuse_s = 3.0;      // no progress along the plan this long: its next cells refused
    double map_refuse_life_s = 20.0;  // for this long
    bool map_compact = false;       // 4 bits a cell (qnav_map_config_t.compact)
    std::uint8_t map_grow_steps = 16;  // compact: plan steps grown a tick at most (0: no bound)
    std::uint32_t map_bytes = 0;    // the board's memory for the map, placed at each goal as the
                                    // board places it (qnav_map_place); 0: over the whole arena
    std::optional<double> map_pass_m;  // the controller's passing distance (the enlargement's,
                                       // qnav_ctrl_config_t.pass_mm) when the map guides it,
                                       // m; none: safety_m, as without a map
    // the odometry's errors, drawn once an episode with these standard deviations (all 0:
    // the map's pose is the true one): distance scale (wheel diameter), rotation scale
    // (wheel track), a curve (unequal wheels: heading error per metre driven)
    double odom_err_scale_pct = 0.0;
    double odom_err_turn_pct = 0.0;
    double odom_err_curve_deg_m = 0.0;
    // what only the board needs (qnav-sim robot-header)
    std::uint32_t um_per_count = 1000;  // wheel travel per encoder count, micrometres
    std::uint32_t tick_ms = 100;        // control tick, ms (the simulator's QNAV_SIM_TICK_S)
    // typical noise levels (used by the CLI when none are given)
    double noise_sensor = 0.0;      // p_s
    double noise_actuation = 0.0;   // p_a
    // collision recovery manoeuvre
    std::uint32_t recovery_ticks = 10;      // whole manoeuvre, ticks of 0.1 s
    std::uint32_t recovery_back_ticks = 5;  // of which backing up, ticks
    double recovery_back_speed_mps = 0.2;   // backing-up speed, m/s
    double recovery_turn_deg = 60;          // turn away from the obstacle after, deg
    // the probabilistic policy hand-tuned for this robot (paper §3.2); 0 = libqnav default
    double prob_k_goal = 0.0;               // P_goal steepness, (0, 64]
    double prob_k_safe = 0.0;               // P_safe steepness, (0, 64]
    double prob_keep = 0.0;                 // holding the heading: margin of quality, [0, 1]
    double prob_full_speed_quality = 0.0;   // its quality at v_max; 0: [drive] full_speed_quality
};

// Whether the profile draws odometry errors (the map's pose is then dead-reckoned).
inline bool has_odometry_errors(const RobotProfile &p) {
    return p.odom_err_scale_pct > 0 || p.odom_err_turn_pct > 0 || p.odom_err_curve_deg_m > 0;
}

// Parse a profile (TOML text); name is used in error messages. Throws SimError.
RobotProfile parse_robot_profile(std::string_view text, const std::string &name);

// The controller configuration a profile gives at n_sectors (0: the profile's default):
// the one mapping from a robot description to libqnav (the simulator, the board header
// generator and navbridge all call it). Fields the profile does not decide keep
// qnav_ctrl_config_default()'s values.
void robot_ctrl_config(const RobotProfile &p, std::uint16_t n_sectors, qnav_ctrl_config_t *cfg);

// The map's configuration a profile's [map] gives (libqnav qnav/map.h), beside the
// controller's; cell_mm 0 when the profile has none. Its range noise (noise_pct) is the
// profile's [map] noise, else its [noise] sensor, whatever a run draws: the board made from
// the profile is told the same (docs/architecture.md, "The map's range noise").
void robot_map_config(const RobotProfile &p, qnav_map_config_t *cfg);

}  // namespace qnav
