// Loading and checking robot profiles from TOML (format in docs/sim.md).
#include "robot.hpp"

#include <algorithm>
#include <cmath>

#include "error.hpp"
#include "geometry.hpp"
#include "tomlread.hpp"
#include "qnav/sim.h"

namespace qnav {

// [body], [drive] and [slip]: the robot's size and how it moves.
static void parse_motion(const TomlReader &r, RobotProfile &p) {
    const toml::table &root = r.root();
    const toml::table &body = r.table(root, "body");
    r.only_keys(body, {"radius_m", "mass_kg", "wheel_base_m"});
    p.radius_m = r.number(body, "radius_m", 0.01, 2.0);
    p.mass_kg = r.number(body, "mass_kg", 0.01, 1000.0);
    p.wheel_base_m = r.number(body, "wheel_base_m", 0.01, 4.0);
    if (p.wheel_base_m > 2.0 * p.radius_m)
        r.fail(body, "'wheel_base_m' is wider than the body (2 * radius_m)");

    const toml::table &drive = r.table(root, "drive");
    r.only_keys(drive, {"v_max_mps", "accel_mps2", "decel_mps2", "turn_rate_max_dps",
                        "heading_gain_per_s", "limits", "full_speed_quality", "model", "brake_first"});
    p.v_max_mps = r.number(drive, "v_max_mps", 0.01, 20.0);
    p.full_speed_quality = r.number(drive, "full_speed_quality", 0.01, 1.0);
    p.accel_mps2 = r.number(drive, "accel_mps2", 0.01, 100.0);
    p.decel_mps2 = r.number(drive, "decel_mps2", 0.01, 100.0);
    p.turn_rate_max_dps = r.number(drive, "turn_rate_max_dps", 1.0, 3600.0);
    p.heading_gain_per_s = r.number(drive, "heading_gain_per_s", 0.1, 100.0);
    // the mixer's full turn: a degree of heading asks heading_gain_per_s of turn rate, but
    // never a full-wheel-speed turn short of 90 deg (a slow robot keeps the measured mixer:
    // docs/sim.md, "A turn in the robot's own units")
    p.turn_full_deg = static_cast<std::uint16_t>(std::clamp(
        std::lround(2.0 * p.v_max_mps / (p.wheel_base_m * p.heading_gain_per_s) * 180.0 / kPi), 90L,
        360L));
    if (drive.get("limits")) {
        const std::string limits = r.string(drive, "limits");
        if (limits != "wheel" && limits != "body")
            r.fail(*drive.get("limits"), "'limits' must be \"wheel\" or \"body\"");
        p.body_limits = limits == "body";
    }
    if (drive.get("model")) {
        const std::string model = r.string(drive, "model");
        if (model != "heading" && model != "mix")
            r.fail(*drive.get("model"), "'model' must be \"heading\" or \"mix\"");
        p.drive_mix = model == "mix";
        if (p.drive_mix && p.body_limits)
            r.fail(*drive.get("model"), "'model' \"mix\" drives each wheel: not with limits = \"body\"");
    }
    if (const toml::node *bf = drive.get("brake_first")) {
        if (!bf->is_boolean()) r.fail(*bf, "'brake_first' must be true or false");
        p.brake_first = bf->value_or(true);
        if (p.drive_mix && !p.brake_first)
            r.fail(*bf, "'brake_first' = false is the heading model's ablation: the mix always brakes first");
    }

    const toml::table &slip = r.table(root, "slip");
    r.only_keys(slip, {"turn", "lateral_s"});
    p.slip_turn = r.number(slip, "turn", 0.0, 0.9);
    p.slip_lateral_s = r.number(slip, "lateral_s", 0.0, 1.0);
}

// The least k_safe a profile's safe_m gives: P_safe at the sonar's range at least
// 1 - e^-4 = 0.98. Below it a short sonar's open paths lose speed (the speed is the
// quality): a 1.5 m TekBot summed 557.7 at k_safe 2.4, 565.7 at 4 (docs/architecture.md,
// "The safety scale in metres").
static constexpr double kOpenPathKSafe = 4.0;

// [sonar], then the optional [noise] and [probabilistic].
static void parse_sensing(const TomlReader &r, RobotProfile &p) {
    const toml::table &root = r.root();
    const toml::table &sonar = r.table(root, "sonar");
    r.only_keys(sonar, {"range_min_m", "range_max_m", "offset_m", "default_sectors", "cone_deg"});
    p.range_min_m = r.number(sonar, "range_min_m", 0.0, 10.0);
    p.range_max_m = r.number(sonar, "range_max_m", 0.05, 65.0);
    if (p.range_min_m >= p.range_max_m)
        r.fail(*sonar.get("range_min_m"), "'range_min_m' must be below 'range_max_m'");
    p.sonar_offset_m = r.number(sonar, "offset_m", 0.0, p.radius_m);
    p.default_sectors =
        static_cast<std::uint16_t>(r.integer(sonar, "default_sectors", 1, 360));
    p.cone_deg = r.number(sonar, "cone_deg", 0.0, 180.0, true, 0.0);

    if (root.get("noise")) {
        const toml::table &noise = r.table(root, "noise");
        r.only_keys(noise, {"sensor", "actuation"});
        p.noise_sensor = r.number(noise, "sensor", 0.0, 1.0, true, 0.0);
        p.noise_actuation = r.number(noise, "actuation", 0.0, 1.0, true, 0.0);
    }

    if (root.get("probabilistic")) {
        const toml::table &prob = r.table(root, "probabilistic");
        r.only_keys(prob, {"k_goal", "k_safe", "safe_m", "keep", "full_speed_quality"});
        p.prob_k_goal = r.number(prob, "k_goal", 1.0 / 256.0, 64.0);
        // P_safe's steepness, the paper's k_safe, is per sonar range (P_safe = 1 - e^(-k_safe
        // ell/(L-1)), ell/(L-1) the reading over range_max_m); safe_m gives it in metres,
        // k_safe = range_max_m / safe_m, but at least kOpenPathKSafe: a path open as far as
        // the sonar sees counts as safe. A profile whose range changes keeps its tuning
        // (docs/architecture.md, "The safety scale in metres").
        if (prob.get("safe_m")) {
            if (prob.get("k_safe"))
                r.fail(*prob.get("k_safe"), "give 'k_safe' or 'safe_m', not both (k_safe = range_max_m / safe_m)");
            const double safe_m = r.number(prob, "safe_m", p.range_max_m / 64.0, 256.0 * p.range_max_m);
            p.prob_k_safe = std::max(p.range_max_m / safe_m, kOpenPathKSafe);
        } else if (prob.get("k_safe")) {
            p.prob_k_safe = r.number(prob, "k_safe", 1.0 / 256.0, 64.0);
        } else {
            r.fail(prob, "missing key 'safe_m' (or the paper's 'k_safe')");
        }
        if (prob.get("keep")) p.prob_keep = r.number(prob, "keep", 0.0, 1.0);
        // its own speed law: a product of probabilities sits lower than a network's output
        // (docs/architecture.md, "The speed at full quality"); absent: [drive]'s
        if (prob.get("full_speed_quality"))
            p.prob_full_speed_quality = r.number(prob, "full_speed_quality", 0.01, 1.0);
    }
}

// [clearance], [odometry] and [control]: what the controller and the board are given.
static void parse_controller_settings(const TomlReader &r, RobotProfile &p) {
    const toml::table &root = r.root();
    const toml::table &cl = r.table(root, "clearance");
    r.only_keys(cl, {"safety_m", "speed_guard", "wedge_pct", "wedge_deg", "wedge_near_m"});
    p.safety_m = r.number(cl, "safety_m", 0.0, 10.0);
    if (cl.get("wedge_pct"))
        p.wedge_pct = static_cast<std::uint8_t>(r.integer(cl, "wedge_pct", 0, 100));
    // the same placement as an angle: a wedge's share of it follows the sector count
    // (docs/architecture.md, "A reading's core as an angle")
    if (const toml::node *deg = cl.get("wedge_deg")) {
        if (cl.get("wedge_pct"))
            r.fail(*deg, "'wedge_deg' and 'wedge_pct' both place a reading on its wedge: give one");
        p.wedge_deg = r.number(cl, "wedge_deg", 0.0, 360.0);
    }
    const toml::node *near = cl.get("wedge_near_m");
    if (near && near->is_string()) {
        if (r.string(cl, "wedge_near_m") != "stopping")
            r.fail(*near, "'wedge_near_m' must be a distance in m or \"stopping\"");
        // the robot's stopping distance from full speed, a tick to react and then braking at
        // decel_mps2: a reading nearer than that at a wedge's edge is one the robot could not
        // stop for once it turned out to lie on its way (docs/sim.md, "A robot that brakes
        // slowly")
        p.wedge_near_m = std::min(65.0, p.v_max_mps * QNAV_SIM_TICK_S + p.v_max_mps * p.v_max_mps / (2.0 * p.decel_mps2));
    } else {
        p.wedge_near_m = r.number(cl, "wedge_near_m", 0.0, 65.0, true, p.wedge_near_m);
    }
    const toml::node *guard = cl.get("speed_guard");
    if (!guard) r.fail(cl, "missing 'speed_guard' (true or false)");
    if (!guard->is_boolean()) r.fail(*guard, "'speed_guard' must be true or false");
    p.speed_guard = guard->value_or(true);

    const toml::table &odo = r.table(root, "odometry");
    r.only_keys(odo, {"um_per_count", "err_scale_pct", "err_turn_pct", "err_curve_deg_m"});
    p.um_per_count = static_cast<std::uint32_t>(r.integer(odo, "um_per_count", 1, 65535));
    p.odom_err_scale_pct = r.number(odo, "err_scale_pct", 0.0, 50.0, true, p.odom_err_scale_pct);
    p.odom_err_turn_pct = r.number(odo, "err_turn_pct", 0.0, 50.0, true, p.odom_err_turn_pct);
    p.odom_err_curve_deg_m = r.number(odo, "err_curve_deg_m", 0.0, 90.0, true, p.odom_err_curve_deg_m);

    const toml::table &ctl = r.table(root, "control");
    r.only_keys(ctl, {"tick_ms"});
    p.tick_ms = static_cast<std::uint32_t>(r.integer(ctl, "tick_ms", 1, 60000));
    if (p.tick_ms != static_cast<std::uint32_t>(QNAV_SIM_TICK_S * 1000.0 + 0.5))
        r.fail(*ctl.get("tick_ms"), "'tick_ms' must be 100: the simulator's tick is fixed "
                                    "(QNAV_SIM_TICK_S, DESIGN.md section 4)");
}

// The optional [escape] and [map], and [recovery]: what the robot does when stuck or in
// collision.
static void parse_escape_and_recovery(const TomlReader &r, RobotProfile &p) {
    const toml::table &root = r.root();
    if (root.get("escape")) {
        const toml::table &es = r.table(root, "escape");
        r.only_keys(es, {"stall_s", "follow_m", "follow_s"});
        p.escape_stall_s = r.number(es, "stall_s", 0.0, 25.5, true, p.escape_stall_s);
        p.escape_follow_m = r.number(es, "follow_m", 0.0, 65.0, true, p.escape_follow_m);
        p.escape_follow_s = r.number(es, "follow_s", 1.0, 109.0, true, p.escape_follow_s);
    }

    if (root.get("map")) {
        const toml::table &mp = r.table(root, "map");
        r.only_keys(mp, {"on", "cell_m", "reach_m", "look_m", "plan_s", "near_m", "near_cost", "arc_deg",
                         "arc_width_m", "sight", "escape_grow", "refuse_s", "refuse_life_s", "pass_m", "compact",
                         "grow_steps", "bytes", "noise", "forget_reach_m", "opening_m", "unknown_cost",
                         "align_samples", "turn_back_s"});
        bool on = true;
        if (const toml::node *o = mp.get("on")) {
            if (!o->is_boolean()) r.fail(*o, "'on' must be true or false");
            on = o->value_or(true);
        }
        p.map_cell_m = r.number(mp, "cell_m", 0.02, 1.0);
        if (!on) {  // described for a board that has the RAM, switched on by NAME+map
            p.map_off_cell_m = p.map_cell_m;
            p.map_cell_m = 0.0;
        }
        p.map_reach_m = r.number(mp, "reach_m", 0.1, 40.0, true, p.map_reach_m);
        p.map_look_m = r.number(mp, "look_m", 0.0, 65.0, true, p.map_look_m);
        p.map_plan_s = r.number(mp, "plan_s", 0.1, 25.5, true, p.map_plan_s);
        p.map_near_m = r.number(mp, "near_m", 0.0, 65.0, true, p.map_near_m);
        p.map_near_cost = r.number(mp, "near_cost", 0.0, 25.5, true, p.map_near_cost);
        p.map_unknown_cost = r.number(mp, "unknown_cost", 0.0, 25.5, true, p.map_unknown_cost);
        if (p.map_near_cost + p.map_unknown_cost > 25.5)
            r.fail(*mp.get("unknown_cost"), "'near_cost' + 'unknown_cost' must be at most 25.5 cell sides");
        p.map_arc_deg = r.number(mp, "arc_deg", 0.0, 360.0, true, p.map_arc_deg);
        p.map_arc_width_m = r.number(mp, "arc_width_m", 0.0, 65.0, true, p.map_arc_width_m);
        if (mp.get("align_samples"))
            p.map_align_samples = static_cast<std::uint8_t>(r.integer(mp, "align_samples", 0, 255));
        p.map_turn_back_s = r.number(mp, "turn_back_s", 0.0, 25.5, true, p.map_turn_back_s);
        p.map_forget_reach_m = r.number(mp, "forget_reach_m", 0.0, 65.0, true, p.map_forget_reach_m);
        p.map_opening_m = r.number(mp, "opening_m", 0.0, 65.0, true, p.map_opening_m);
        if (mp.get("noise")) p.map_noise = r.number(mp, "noise", 0.0, 1.0);
        if (mp.get("sight")) p.map_sight = r.integer(mp, "sight", 0, 1) != 0;
        if (mp.get("escape_grow")) p.map_escape_grow = r.integer(mp, "escape_grow", 0, 1) != 0;
        p.map_refuse_s = r.number(mp, "refuse_s", 0.0, 25.5, true, p.map_refuse_s);
        p.map_refuse_life_s = r.number(mp, "refuse_life_s", 0.1, 6553.5, true, p.map_refuse_life_s);
        if (mp.get("pass_m")) p.map_pass_m = r.number(mp, "pass_m", 0.0, 10.0);
        if (mp.get("bytes")) p.map_bytes = static_cast<std::uint32_t>(r.integer(mp, "bytes", 1, 16777216));
        if (const toml::node *c = mp.get("compact")) {
            if (!c->is_boolean()) r.fail(*c, "'compact' must be true or false");
            p.map_compact = c->value_or(false);
        }
        if (const toml::node *g = mp.get("grow_steps"); g && !p.map_compact)
            r.fail(*g, "'grow_steps' is a compact map's (compact = true)");
        if (p.map_compact) {  // 4 bits a cell: no bits for near costs; refused cells marked occupied
            if (const toml::node *n = mp.get("near_cost"); n && n->value_or(0.0) != 0.0)
                r.fail(*n, "'near_cost' must be 0 in a compact map (it has no bits for it)");
            p.map_near_cost = 0.0;
            if (const toml::node *n = mp.get("unknown_cost"); n && n->value_or(0.0) != 0.0)
                r.fail(*n, "'unknown_cost' must be 0 in a compact map (its plan counts steps only)");
            if (!mp.get("refuse_s")) p.map_refuse_s = 0.0;  // a compact map refuses only when told to
            if (mp.get("grow_steps"))
                p.map_grow_steps = static_cast<std::uint8_t>(r.integer(mp, "grow_steps", 0, 255));
            const double cell = p.map_cell_m > 0 ? p.map_cell_m : p.map_off_cell_m;
            if (cell <= p.radius_m + p.safety_m)
                r.fail(*mp.get("cell_m"), "a compact map's 'cell_m' must exceed [body] radius_m + [clearance] "
                                          "safety_m (a cell is blocked when it is occupied)");
        }
    }

    const toml::table &rec = r.table(root, "recovery");
    r.only_keys(rec, {"ticks", "back_ticks", "back_speed_mps", "turn_deg"});
    p.recovery_ticks = static_cast<std::uint32_t>(r.integer(rec, "ticks", 1, 1000));
    p.recovery_back_ticks =
        static_cast<std::uint32_t>(r.integer(rec, "back_ticks", 0, 1000));
    if (p.recovery_back_ticks > p.recovery_ticks)
        r.fail(*rec.get("back_ticks"), "'back_ticks' exceeds 'ticks'");
    p.recovery_back_speed_mps = r.number(rec, "back_speed_mps", 0.0, p.v_max_mps);
    p.recovery_turn_deg = r.number(rec, "turn_deg", 0.0, 360.0);
}

RobotProfile parse_robot_profile(std::string_view text, const std::string &name) {
    TomlReader r(text, name);
    const toml::table &root = r.root();
    r.only_keys(root, {"name", "body", "drive", "slip", "sonar", "noise", "recovery", "probabilistic",
                      "clearance", "odometry", "control", "escape", "map"});
    RobotProfile p;
    p.name = r.string(root, "name");
    if (p.name.empty()) r.fail(root, "'name' must not be empty");
    parse_motion(r, p);
    parse_sensing(r, p);
    parse_controller_settings(r, p);
    parse_escape_and_recovery(r, p);
    return p;
}

}  // namespace qnav
