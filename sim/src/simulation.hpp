// One simulation context: a Box2D world holding the arena walls and obstacles as one
// static body and the robot as a dynamic disc; the drive model (heading controller,
// acceleration-limited wheels, slip), the analytic sonar, noise, collision recovery, and
// the episode's figures (paper Eq. 1-3). The C API in capi.cpp is a thin shell over this.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <vector>

#include "env.hpp"
#include "qnav/nav.h"
#include "qnav/map.h"
#include "qnav/sim.h"
#include "qnav/rng.hpp"
#include "robot.hpp"
#include "sonar.hpp"

class b2World;
class b2Body;

namespace qnav {

struct SimConfig {
    std::uint16_t n_sectors = 16;   // 1..360 (0 resolved to the profile's default before)
    double sensor_noise = 0;        // p_s
    double actuation_noise = 0;     // p_a
    std::uint64_t seed = 1;
    double episode_limit_s = 0;     // 0 = environment's
    qnav_sim_fitness_rule_t fitness = QNAV_SIM_FITNESS_PROGRESS;
    // The map's grid against the world's walls, degrees in [0, 360): a board's grid is its
    // heading sensor's frame, at no particular angle to a room's walls; negative: drawn
    // per episode (qnav_sim_config_t.map_frame_deg; docs/sim.md, "The map's grid").
    double map_frame_deg = -1;
    // > 0: each episode's map starts surveyed from a grid of points this far apart
    // (qnav_sim_config_t.survey_m; docs/sim.md, "A known world"); 0: off.
    double survey_m = 0;
};

// Where time went (only counted when profiling is on), seconds.
struct SimProfile {
    double physics_s = 0, sonar_s = 0, controller_s = 0;
    double map_s = 0;  // marking the map and planning over it (a profile with a map)
};

struct CollisionMark {
    std::uint32_t tick;  // tick at which it was detected
    Vec2 robot;          // robot centre, m
    Vec2 contact;        // contact point, m
};

class Simulation {
public:
    Simulation(const RobotProfile &robot, const Environment &env, const SimConfig &cfg);
    ~Simulation();
    Simulation(const Simulation &) = delete;
    Simulation &operator=(const Simulation &) = delete;

    void reset(std::uint64_t episode_seed);
    // Move the robot (at rest) to a pose; the episode's figures restart from there.
    void place(double x_m, double y_m, double heading_rad);
    void command(double heading_deg, double speed);
    void advance();
    bool started() const { return started_; }
    bool done() const { return done_; }

    const qnav_sim_scan_t &scan() const { return scan_; }
    qnav_sim_state_t state() const;
    qnav_sim_result_t result() const;
    qnav_sim_sample_t sample() const;
    const std::vector<CollisionMark> &collision_marks() const { return marks_; }

    // Whole episode with a libqnav controller; throws SimError on a mismatched controller.
    // Any controller of the table in qnav/nav.h (reset at the start of the episode).
    qnav_sim_result_t run_episode(qnav_nav_t *nav, std::uint64_t episode_seed,
                                  qnav_sim_trace_fn trace, void *user);
    qnav_sim_result_t run_episode(const qnav_ctrl_t *ctrl, std::uint64_t episode_seed,
                                  qnav_sim_trace_fn trace, void *user);
    // The loop both run_episode()s share: scan -> step(self) -> command -> advance.
    using StepFn = void (*)(void *self, const qnav_ctrl_input_t *in, qnav_ctrl_output_t *out);
    qnav_sim_result_t run_episode_with(StepFn step, void *self, std::uint16_t n_sectors,
                                       qnav_mm_t max_range_mm, std::uint64_t episode_seed,
                                       qnav_sim_trace_fn trace, void *user);

    void set_profiling(bool on) { profiling_ = on; }
    // Benchmark reference only: the straightforward way (a Box2D ray cast per degree for
    // the sonar, a Box2D step every tick). Same noise and clipping; not bit-identical.
    void set_reference_mode(bool on) { reference_ = on; }
    SimProfile &profile() { return prof_; }

    const Environment &env() const { return env_; }
    const RobotProfile &robot() const { return robot_; }
    const SimConfig &config() const { return cfg_; }
    // The profile's map (qnav/map.h) in its frame, or null when the profile has none.
    const qnav_map_t *map() const { return map_mem_.empty() ? nullptr : &map_; }
    // A point of the map's frame in the world's (the episode's turn of the grid undone).
    Vec2 map_to_world(Vec2 p) const { return turned(p, -map_turn_); }
    std::uint16_t max_range_mm() const { return max_range_mm_; }
    double sonar_cone_rad() const { return sonar_.cone(); }

private:
    // Speed along the heading (m/s) and the destination's centre (m): what state(),
    // sample() and result() report.
    double forward_speed() const;
    Vec2 dest() const { return Vec2{env_.dest_x_m, env_.dest_y_m}; }
    void build_world();
    void compute_scan();
    void init_map();
    void place_map();
    void survey_map();
    qnav_mm_t reading_mm(double range_m) const;
    void guide_scan();
    void drive_substep(double dt);
    void recovery_wheels();
    void heading_wheels(double dt);
    void drive_targets(double heading_rad, double speed);
    qnav_q1_15_t encoder_rolling();
    void move_body(double omega_a, double v_lat, double dt);
    bool touching(Vec2 *contact);
    void start_recovery(Vec2 contact);

    RobotProfile robot_;
    Environment env_;
    // the profile's [map] (libqnav qnav/map.h): what the sonar has seen and a plan over it,
    // giving the scan a sub-goal; map_mem_ empty: none
    qnav_map_t map_{};
    qnav_map_config_t map_cfg_{};   // the profile's map, for place_map
    qnav_ctrl_config_t map_ctrl_{};
    std::vector<std::uint16_t> map_mem_;
    SimConfig cfg_;
    SonarRing sonar_;
    std::uint16_t max_range_mm_;
    std::uint32_t limit_ticks_;

    std::unique_ptr<b2World> world_;
    b2Body *body_ = nullptr;

    Rng rng_start_, rng_sensor_, rng_act_, rng_odom_;
    // the map's pose: odometry integrated from the true motion with this episode's errors
    bool odom_on_ = false;  // a map whose pose is odometry with errors (set once, at construction)
    Vec2 odom_pos_{}, odom_last_pos_{};
    Vec2 odom_goal_{}, plan_goal_{};  // the destination in its frame: averaged, and the plan's
    double odom_heading_ = 0, odom_last_heading_ = 0;
    double odom_scale_ = 0, odom_turn_ = 0, odom_curve_ = 0;  // this episode's errors
    void odometry();
    Vec2 anchor_goal(Vec2 at, double heading);
    // the map's grid turned against the world's by map_turn_ (rad) about the arena's centre
    double map_turn_ = 0;
    std::uint64_t world_key_ = 0;  // a hash of the world: turns differ between worlds
    Vec2 turned(Vec2 p, double by) const;
    // cos and sin of the last angle turned() turned by: the map turns every tick by the same
    mutable double turned_by_ = 0, turned_cos_ = 1, turned_sin_ = 0;
    bool started_ = false, done_ = false, reached_ = false;
    std::uint32_t tick_ = 0, tau_c_ = 0, collisions_ = 0;
    std::uint32_t recovery_left_ = 0;
    int recovery_turn_sign_ = 1;    // +1 counter-clockwise, -1 clockwise
    double recovery_back_sign_ = -1;
    bool collided_this_tick_ = false;
    double l_m_ = 0;
    Vec2 start_{}, pos_{};
    double start_heading_ = 0, heading_ = 0;
    double wheel_l_ = 0, wheel_r_ = 0;  // wheel surface speeds, m/s
    double travel_l_m_ = 0, travel_r_m_ = 0;     // each wheel's travel this episode, m
    std::int64_t counts_l_ = 0, counts_r_ = 0;   // their encoder counts at the last tick
    qnav_q1_15_t rolling_ = 0;                   // the forward speed they gave over the last tick
    Vec2 vel_{};                        // body velocity, world frame, m/s
    double clearance_m_ = 0;            // centre to nearest surface after the last step, m
    bool body_stale_ = false;           // Box2D body not moved since free steps
    double cmd_heading_deg_ = 0, cmd_speed_ = 0;  // last command, as given
    qnav_cdeg_t cmd_goal_cdeg_ = 0;                // the scan's destination it answered
    qnav_mm_t cmd_goal_mm_ = 0;
    std::int8_t escape_side_ = 0;                 // the last step's escape side
    double sensed_heading_ = 0;   // heading (with sensor noise) of the current scan, rad
    double prev_world_rad_ = 0;   // last command's heading in the world, rad
    bool have_prev_ = false;      // a command was given since reset
    double target_heading_ = 0, target_speed_ = 0;  // this tick, with actuation noise
    double mix_l_ = 0, mix_r_ = 0;  // [drive] model "mix": this tick's wheel targets, m/s
    bool braking_ = false;  // model "heading": this tick brakes before a turn (brake_first)
    std::vector<double> true_dist_;  // centre distances of the last scan before noise, m
    qnav_sim_scan_t scan_{};
    std::vector<CollisionMark> marks_;

    void reference_scan();
    bool reference_ = false;
    bool profiling_ = false;
    SimProfile prof_;
};

// f1, f2 and R of res under rule (qnav_sim_fitness_rule_t): Eq. 1-3 on l, beta_l, tau_l,
// beta_tau, tau_c; for the progress rule and an episode not reached, f1 from d_start_m and
// d_end_m and f2 = 0.
void compute_fitness(qnav_sim_result_t *res, qnav_sim_fitness_rule_t rule);
// Shortest time to drive d metres from rest with acceleration a and top speed v, s.
double shortest_time(double d_m, double v_max_mps, double accel_mps2);

}  // namespace qnav
