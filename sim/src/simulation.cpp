// One simulation context (see simulation.hpp): world building, the drive model, sensing
// with noise, collision recovery, episode bookkeeping and the fitness of Eq. 1-3.
#include "simulation.hpp"

#include <algorithm>
#include <cstdint>
#include <sstream>
#include <cmath>

#include <box2d/box2d.h>

#include "error.hpp"
#include "qnav/drive.h"
#include "qnav/fixed_host.h"

namespace qnav {

namespace {

constexpr int kSubsteps = 1;           // physics steps per 0.1 s control tick
constexpr int kVelocityIterations = 4;  // one dynamic disc: few iterations suffice
constexpr int kPositionIterations = 2;
constexpr double kTouchSlack_m = 0.012;  // Box2D keeps ~0.01 m polygon skin; touching
                                         // means within the body radius plus this
constexpr double kEta1 = 1.0, kEta2 = 10.0;

// A world coordinate, m -> the map's whole mm (libqnav qnav/map.h).
std::int32_t map_mm(double m) { return static_cast<std::int32_t>(std::lround(m * 1000.0)); }

// Robot-frame degrees -> (-180, 180] in centidegrees as the controller wants them.
qnav_cdeg_t to_cdeg(double rad) {
    double cd = std::round(wrap_pi(rad) * 18000.0 / kPi);
    if (cd >= 18000.0) cd -= 36000.0;
    if (cd < -18000.0) cd += 36000.0;
    return static_cast<qnav_cdeg_t>(cd);
}

double approach(double cur, double target, double accel, double decel, double dt) {
    // Speeding up (same sign, larger magnitude) is limited by accel, everything else
    // (slowing, reversing through zero) by decel.
    const bool speeding_up = (cur >= 0 && target > cur) || (cur <= 0 && target < cur);
    const double step = (speeding_up ? accel : decel) * dt;
    if (target > cur) return std::min(target, cur + step);
    return std::max(target, cur - step);
}

}  // namespace

double shortest_time(double d_m, double v, double a) {
    if (d_m <= 0) return 0.0;
    const double d_acc = v * v / (2.0 * a);
    if (d_m <= d_acc) return std::sqrt(2.0 * d_m / a);
    return v / a + (d_m - d_acc) / v;
}

namespace {
// Eq. 2 and 3: the ratio of actual to best, inverted past the best; 1 when the best is 0.
double ratio_feature(double actual, double best) {
    if (best <= 0) return 1.0;
    return actual <= best ? actual / best : best / actual;
}
}  // namespace

void compute_fitness(qnav_sim_result_t *res, qnav_sim_fitness_rule_t rule) {
    res->fitness = rule;
    if (rule == QNAV_SIM_FITNESS_PAPER || res->reached) {
        res->f1 = ratio_feature(res->l, res->beta_l);
        res->f2 = ratio_feature(res->tau_l, res->beta_tau);
    } else {
        // Not arrived: no reward for time (it would pay circling until the limit), and f1
        // only for the part of the way covered.
        res->f1 = res->d_start_m > 0
                      ? std::clamp((res->d_start_m - res->d_end_m) / res->d_start_m, 0.0, 1.0)
                      : 1.0;
        res->f2 = 0.0;
    }
    res->R = kEta1 * res->f1 + kEta2 * res->f2 - static_cast<double>(res->tau_c);
}


Simulation::Simulation(const RobotProfile &robot, const Environment &env, const SimConfig &cfg)
    : robot_(robot),
      env_(env),
      cfg_(cfg),
      sonar_(env.obstacle_shapes(), env.width_m, env.height_m, cfg.n_sectors,
             robot.range_max_m + robot.sonar_offset_m, robot.cone_deg * kPi / 180.0) {
    max_range_mm_ = static_cast<std::uint16_t>(
        std::min(65535.0, std::round(robot_.range_max_m * 1000.0)));
    const double limit_s = cfg_.episode_limit_s > 0 ? cfg_.episode_limit_s : env_.episode_limit_s;
    limit_ticks_ = static_cast<std::uint32_t>(std::max(1.0, std::round(limit_s / QNAV_SIM_TICK_S)));
    true_dist_.assign(cfg_.n_sectors, kInf);
    scan_.n_sectors = cfg_.n_sectors;
    scan_.max_range_mm = max_range_mm_;
    if (robot_.map_cell_m > 0) init_map();
    // the world's key: its name, arena and destination
    world_key_ = qnav_fnv1a64(env_.name.data(), env_.name.size(), QNAV_FNV1A64_BASIS);
    for (const double v : {env_.width_m, env_.height_m, env_.dest_x_m, env_.dest_y_m})
        world_key_ = qnav_fnv1a64(&v, sizeof v, world_key_);
    odom_on_ = !map_mem_.empty() && has_odometry_errors(robot_);
}

// The profile's [map] over the whole arena (libqnav qnav/map.h; 8 bytes a cell, or half a
// byte with [map] compact), as the board runs it: its range noise is the profile's [noise]
// sensor, whatever this run draws (a board cannot know its sonar is noisier or quieter).
void Simulation::init_map() {
    qnav_map_config_t mc;
    robot_map_config(robot_, &mc);
    const auto mm = [](double m) { return static_cast<std::uint32_t>(std::ceil(m * 1000.0)); };
    robot_ctrl_config(robot_, cfg_.n_sectors, &map_ctrl_);
    map_cfg_ = mc;
    if (robot_.map_bytes > 0) {  // the board's memory, placed at each start (place_map)
        map_mem_.assign((robot_.map_bytes + 1) / 2, 0);
        return;
    }
    // over the arena, or with its grid turned (any turn but none) the square that holds the
    // arena turned any way about its centre
    double w = env_.width_m, h = env_.height_m, x0 = 0, y0 = 0;
    if (cfg_.map_frame_deg != 0) {
        w = h = std::hypot(env_.width_m, env_.height_m);
        x0 = (env_.width_m - w) / 2;
        y0 = (env_.height_m - h) / 2;
    }
    map_mem_.assign((qnav_map_size(&mc, mm(w), mm(h)) + 1) / 2, 0);
    const qnav_ctrl_config_t &cc = map_ctrl_;
    const qnav_status_t st = qnav_map_init(&map_, &mc, &cc, map_mm(x0), map_mm(y0), mm(w), mm(h),
                                           map_mem_.data(), map_mem_.size() * 2);
    if (st != QNAV_OK) {
        std::ostringstream why;
        why << robot_.name << ": [map] cell_m " << robot_.map_cell_m << " for a " << env_.width_m << " x "
            << env_.height_m << " m arena";
        if (w != env_.width_m) why << " (its grid turned any way: a " << w << " m square; --map-frame 0: the arena)";
        why << ": " << qnav_status_str(st);
        throw SimError(QNAV_SIM_E_PARAM, why.str());
    }
}

// A point turned by `by` about the arena's centre: the world's into the map's frame (by
// map_turn_) and back (by -map_turn_). No turn leaves a point exactly as it is.
Vec2 Simulation::turned(Vec2 p, double by) const {
    if (by == 0) return p;
    if (by != turned_by_) {
        turned_by_ = by;
        turned_cos_ = std::cos(by);
        turned_sin_ = std::sin(by);
    }
    const double cx = env_.width_m / 2, cy = env_.height_m / 2, c = turned_cos_, s = turned_sin_;
    const double dx = p.x - cx, dy = p.y - cy;
    return Vec2{cx + c * dx - s * dy, cy + s * dx + c * dy};
}

// A board with [map] bytes of memory for its map starts it afresh at each goal over the
// square those bytes hold, midway between the robot and the goal (qnav_map_place), or
// steers without one when the goal lies too far for it: the robot the board is.
void Simulation::place_map() {
    map_ = qnav_map_t{};
    std::int32_t x0 = 0, y0 = 0;
    std::uint32_t side = 0;
    const Vec2 at = turned(pos_, map_turn_), dest = turned(Vec2{env_.dest_x_m, env_.dest_y_m}, map_turn_);
    if (!qnav_map_place(&map_cfg_, robot_.map_bytes, map_mm(at.x), map_mm(at.y), map_mm(dest.x), map_mm(dest.y),
                        &x0, &y0, &side))
        return;
    const qnav_status_t st =
        qnav_map_init(&map_, &map_cfg_, &map_ctrl_, x0, y0, side, side, map_mem_.data(), robot_.map_bytes);
    if (st != QNAV_OK)
        throw SimError(QNAV_SIM_E_PARAM, robot_.name + ": [map] placed over " + std::to_string(side) +
                                             " mm: " + qnav_status_str(st));
}

Simulation::~Simulation() = default;

void Simulation::build_world() {
    // A fresh world per episode: nothing (contact caches, broad-phase tree shape) carries
    // over from earlier episodes, so an episode depends only on its seeds.
    world_ = std::make_unique<b2World>(b2Vec2(0.0f, 0.0f));
    b2BodyDef sd;
    sd.type = b2_staticBody;
    b2Body *ground = world_->CreateBody(&sd);
    for (const auto &c : env_.circles) {
        b2CircleShape cs;
        cs.m_p.Set(static_cast<float>(c.x_m), static_cast<float>(c.y_m));
        cs.m_radius = static_cast<float>(c.r_m);
        ground->CreateFixture(&cs, 0.0f);
    }
    for (const auto &b : env_.boxes) {
        b2PolygonShape ps;
        ps.SetAsBox(static_cast<float>(b.w_m / 2), static_cast<float>(b.h_m / 2),
                    b2Vec2(static_cast<float>(b.x_m), static_cast<float>(b.y_m)),
                    static_cast<float>(b.angle_deg * kPi / 180.0));
        ground->CreateFixture(&ps, 0.0f);
    }
    // Walls: 1 m thick boxes just outside the arena.
    const float w = static_cast<float>(env_.width_m), h = static_cast<float>(env_.height_m);
    const float t = 0.5f;
    const b2Vec2 centres[4] = {{w / 2, -t}, {w / 2, h + t}, {-t, h / 2}, {w + t, h / 2}};
    const b2Vec2 halves[4] = {{w / 2 + 2 * t, t}, {w / 2 + 2 * t, t}, {t, h / 2 + 2 * t}, {t, h / 2 + 2 * t}};
    for (int i = 0; i < 4; ++i) {
        b2PolygonShape ps;
        ps.SetAsBox(halves[i].x, halves[i].y, centres[i], 0.0f);
        ground->CreateFixture(&ps, 0.0f);
    }
    b2BodyDef bd;
    bd.type = b2_dynamicBody;
    bd.position.Set(static_cast<float>(pos_.x), static_cast<float>(pos_.y));
    bd.angle = static_cast<float>(heading_);
    bd.bullet = false;
    body_ = world_->CreateBody(&bd);
    b2CircleShape rs;
    rs.m_radius = static_cast<float>(robot_.radius_m);
    b2FixtureDef fd;
    fd.shape = &rs;
    fd.density = static_cast<float>(robot_.mass_kg / (kPi * robot_.radius_m * robot_.radius_m));
    fd.friction = 0.0f;  // the robot slides along walls; no contact torque on the disc
    fd.restitution = 0.0f;
    body_->CreateFixture(&fd);
}

void Simulation::reset(std::uint64_t episode_seed) {
    rng_start_ = Rng::stream(cfg_.seed, episode_seed, 1);
    rng_sensor_ = Rng::stream(cfg_.seed, episode_seed, 2);
    rng_act_ = Rng::stream(cfg_.seed, episode_seed, 3);
    rng_odom_ = Rng::stream(cfg_.seed, episode_seed, 4);
    // the map's grid against the world's for the episode, drawn from the world as well (the
    // same episode seed in two worlds: two turns) on stream 5 (no other draw moves)
    map_turn_ = cfg_.map_frame_deg < 0 ? Rng::stream(cfg_.seed ^ world_key_, episode_seed, 5).uniform(0, 2 * kPi)
                                       : cfg_.map_frame_deg * kPi / 180.0;
    // Start zone weighted by area (equal weights when all are points or lines).
    double total = 0;
    for (const auto &z : env_.start_zones) total += z.w_m * z.h_m;
    std::size_t zi = 0;
    const double pick = rng_start_.uniform01();
    if (total > 0) {
        double acc = 0;
        for (zi = 0; zi + 1 < env_.start_zones.size(); ++zi) {
            acc += env_.start_zones[zi].w_m * env_.start_zones[zi].h_m / total;
            if (pick < acc) break;
        }
    } else {
        zi = std::min(env_.start_zones.size() - 1,
                      static_cast<std::size_t>(pick * static_cast<double>(env_.start_zones.size())));
    }
    const StartZone &z = env_.start_zones[zi];
    const double x = z.x_m + rng_start_.uniform01() * z.w_m;
    const double y = z.y_m + rng_start_.uniform01() * z.h_m;
    const double hd = rng_start_.uniform(-kPi, kPi);
    place(x, y, hd);
}

void Simulation::place(double x_m, double y_m, double heading_rad) {
    pos_ = {x_m, y_m};
    heading_ = wrap_pi(heading_rad);
    start_ = pos_;
    start_heading_ = heading_;
    build_world();
    started_ = true;
    done_ = false;
    reached_ = false;
    tick_ = tau_c_ = collisions_ = recovery_left_ = 0;
    collided_this_tick_ = false;
    l_m_ = 0;
    wheel_l_ = wheel_r_ = 0;
    travel_l_m_ = travel_r_m_ = 0;
    counts_l_ = counts_r_ = 0;
    rolling_ = 0;
    mix_l_ = mix_r_ = 0;
    braking_ = false;
    cmd_heading_deg_ = cmd_speed_ = 0;
    cmd_goal_cdeg_ = 0;
    cmd_goal_mm_ = 0;
    escape_side_ = 0;
    have_prev_ = false;
    target_heading_ = heading_;
    target_speed_ = 0;
    marks_.clear();
    vel_ = {0, 0};
    body_stale_ = false;
    if (!map_mem_.empty()) {
        if (robot_.map_bytes > 0)
            place_map();
        else
            qnav_map_reset(&map_);
        if (cfg_.survey_m > 0) survey_map();
        // the odometry's frame is the world's at the start (the destination's bearing and
        // range place it there each tick: anchor_goal)
        odom_pos_ = odom_last_pos_ = pos_;
        odom_heading_ = odom_last_heading_ = heading_;
        odom_goal_ = plan_goal_ = {env_.dest_x_m, env_.dest_y_m};
        odom_scale_ = robot_.odom_err_scale_pct / 100.0 * rng_odom_.normal();
        odom_turn_ = robot_.odom_err_turn_pct / 100.0 * rng_odom_.normal();
        odom_curve_ = robot_.odom_err_curve_deg_m * kPi / 180.0 * rng_odom_.normal();
    }
    Vec2 unused;
    touching(&unused);  // sets clearance_m_
    const double dx = env_.dest_x_m - pos_.x, dy = env_.dest_y_m - pos_.y;
    if (std::sqrt(dx * dx + dy * dy) <= env_.dest_radius_m) reached_ = done_ = true;
    compute_scan();
}

void Simulation::command(double heading_deg, double speed) {
    cmd_heading_deg_ = std::isfinite(heading_deg) ? heading_deg : 0.0;
    cmd_speed_ = std::isfinite(speed) ? std::clamp(speed, 0.0, 1.0) : 0.0;
    cmd_goal_cdeg_ = scan_.goal_bearing_cdeg;
    cmd_goal_mm_ = scan_.goal_range_mm;
    // The decision in the world, from the heading the robot sensed when it made it.
    prev_world_rad_ = sensed_heading_ + cmd_heading_deg_ * kPi / 180.0;
    have_prev_ = true;
}

void Simulation::compute_scan() {
    using Clock = std::chrono::steady_clock;
    Clock::time_point t0;
    if (profiling_) t0 = Clock::now();
    if (reference_)
        reference_scan();
    else
        sonar_.measure(pos_, heading_, true_dist_.data());
    const double ps = cfg_.sensor_noise;
    const double r = robot_.sonar_offset_m, rmax = robot_.range_max_m;
    for (std::uint16_t k = 0; k < cfg_.n_sectors; ++k) {
        double range = true_dist_[k] - r;  // measured from the transducers (sonar offset)
        if (range <= rmax && ps > 0) range *= 1.0 + ps * rng_sensor_.normal();
        scan_.ranges_mm[k] = reading_mm(range);
    }
    double hd = heading_;
    if (ps > 0) hd += ps * kPi * rng_sensor_.normal();
    const double bearing = std::atan2(env_.dest_y_m - pos_.y, env_.dest_x_m - pos_.x) - hd;
    scan_.goal_bearing_cdeg = to_cdeg(bearing);
    const double goal_m = std::hypot(env_.dest_x_m - pos_.x, env_.dest_y_m - pos_.y);
    scan_.goal_range_mm = static_cast<qnav_mm_t>(std::clamp(goal_m * 1000.0 + 0.5, 1.0, 65535.0));
    sensed_heading_ = hd;
    scan_.prev_heading_cdeg = have_prev_ ? to_cdeg(prev_world_rad_ - hd) : 0;
    scan_.escape_clear = 0;
    scan_.escape_grow_mm = 0;
    if (profiling_) prof_.sonar_s += std::chrono::duration<double>(Clock::now() - t0).count();
    if (!map_mem_.empty()) {
        if (profiling_) t0 = Clock::now();
        guide_scan();
        if (profiling_) prof_.map_s += std::chrono::duration<double>(Clock::now() - t0).count();
    }
}

// A range from the transducers as the sonar reports it: none beyond its maximum (no echo),
// none nearer than its minimum.
qnav_mm_t Simulation::reading_mm(double range_m) const {
    const double rmax = robot_.range_max_m;
    const double range = range_m <= rmax ? std::clamp(range_m, robot_.range_min_m, rmax) : rmax;
    return static_cast<qnav_mm_t>(range * 1000.0 + 0.5);  // range >= 0
}

// A known world (survey_m): before the episode the map marks, by its own rules, what the
// sonar shows without noise from every point of a survey_m grid over the arena where the
// body fits, at two headings half a sector apart, so each wedge's centre line is seen
// twice as densely. The episode then drives a map that knows the world as well as this
// sonar and map can (the points: free_cells, where the world generator checks a body fits),
// and a miss is owed to the controller and the plan, not to exploring
// (docs/sim.md, "A known world"). A map that follows the robot keeps what its square holds.
void Simulation::survey_map() {
    std::vector<qnav_mm_t> ranges(cfg_.n_sectors);
    const double step = cfg_.survey_m, half_sector = kPi / cfg_.n_sectors;
    int nx = 0, ny = 0;
    const std::vector<char> fits = free_cells(env_, robot_.radius_m, step, &nx, &ny);
    for (int j = 0; j < ny; ++j) {
        for (int i = 0; i < nx; ++i) {
            if (!fits[cell_index(j * nx + i)]) continue;
            const Vec2 p{(i + 0.5) * step, (j + 0.5) * step};
            for (const double hd : {0.0, half_sector}) {
                sonar_.measure(p, hd, true_dist_.data());
                for (std::uint16_t k = 0; k < cfg_.n_sectors; ++k)
                    ranges[k] = reading_mm(true_dist_[k] - robot_.sonar_offset_m);
                const Vec2 at = turned(p, map_turn_);
                const qnav_map_pose_t pose{map_mm(at.x), map_mm(at.y), to_cdeg(hd + map_turn_)};
                qnav_map_observe(&map_, ranges.data(), &pose);
            }
        }
    }
}

// The map marks what this scan saw from the robot's pose and gives the controller the
// plan's sub-goal. The pose is the true one, or with odometry errors in the profile the
// odometry's (docs/architecture.md, "The map's pose"), in the map's frame: the world's
// turned by this episode's map_turn_ (docs/sim.md, "The map's grid"); the plan's bearing is turned into
// the robot's frame with the heading the map knows: the sensed one on the true pose, the
// odometry's own in its frame.
void Simulation::guide_scan() {
    if (odom_on_) odometry();
    const Vec2 odom_at = odom_on_ ? odom_pos_ : pos_;
    const double odom_hd = odom_on_ ? odom_heading_ : heading_;
    const Vec2 goal = turned(odom_on_ ? anchor_goal(odom_at, odom_hd) : Vec2{env_.dest_x_m, env_.dest_y_m}, map_turn_);
    const Vec2 at = turned(odom_at, map_turn_);
    const double hd = odom_hd + map_turn_;
    const qnav_map_pose_t pose{map_mm(at.x), map_mm(at.y), to_cdeg(hd)};
    if (robot_.map_bytes > 0) qnav_map_follow(&map_, &pose, map_mm(goal.x), map_mm(goal.y));  // as the board's
    qnav_map_observe(&map_, scan_.ranges_mm, &pose);
    const qnav_map_pose_t seen{pose.x_mm, pose.y_mm, odom_on_ ? pose.heading_cdeg : to_cdeg(sensed_heading_ + map_turn_)};
    qnav_ctrl_input_t in{};
    in.goal_bearing_cdeg = scan_.goal_bearing_cdeg;
    in.goal_range_mm = scan_.goal_range_mm;
    const int got = qnav_map_guide(&map_, &seen, map_mm(goal.x), map_mm(goal.y), &in);
    scan_.escape_clear = (got & QNAV_MAP_ESCAPE_CLEARED) ? 1 : 0;
    scan_.escape_grow_mm = (got & QNAV_MAP_ESCAPE_GROWN) ? qnav_map_grown_mm(&map_) : 0;
    if (odom_on_ && (got & QNAV_MAP_DIRECT)) return;  // the destination in sight: its sensed bearing
    scan_.goal_bearing_cdeg = in.goal_bearing_cdeg;
    scan_.goal_range_mm = in.goal_range_mm;
}

// The destination in the odometry's frame, from its sensed bearing and range (the scan's,
// before the map) seen from the odometry's pose: averaged over ticks (the bearing's noise),
// and moved for the plan only when that has moved by more than a cell and a half, so a
// drifting frame does not make a plan a tick.
Vec2 Simulation::anchor_goal(Vec2 at, double heading) {
    const double dir = heading + static_cast<double>(scan_.goal_bearing_cdeg) * kPi / 18000.0;
    const double r = static_cast<double>(scan_.goal_range_mm) / 1000.0;
    odom_goal_.x += 0.05 * (at.x + r * std::cos(dir) - odom_goal_.x);
    odom_goal_.y += 0.05 * (at.y + r * std::sin(dir) - odom_goal_.y);
    if (std::hypot(odom_goal_.x - plan_goal_.x, odom_goal_.y - plan_goal_.y) > 1.5 * robot_.map_cell_m)
        plan_goal_ = odom_goal_;
    return plan_goal_;
}

// Dead reckoning from the wheels: the true motion since the last scan as encoders see it
// (the travel along the heading and the turn; sideways slip unseen), with this episode's
// scale, rotation and curve errors.
void Simulation::odometry() {
    const double turn = wrap_pi(heading_ - odom_last_heading_);
    const Vec2 d = pos_ - odom_last_pos_;
    const double mid = odom_last_heading_ + turn / 2;
    const double ds = d.x * std::cos(mid) + d.y * std::sin(mid);
    const double ds_est = ds * (1.0 + odom_scale_);
    const double turn_est = turn * (1.0 + odom_turn_) + odom_curve_ * std::abs(ds);
    odom_heading_ += turn_est / 2;
    odom_pos_ = {odom_pos_.x + ds_est * std::cos(odom_heading_), odom_pos_.y + ds_est * std::sin(odom_heading_)};
    odom_heading_ = wrap_pi(odom_heading_ + turn_est / 2);
    odom_last_pos_ = pos_;
    odom_last_heading_ = heading_;
}

namespace {
// Closest hit along a ray, ignoring the robot's own fixture.
class ClosestHit : public b2RayCastCallback {
public:
    explicit ClosestHit(const b2Body *self) : self_(self) {}
    float ReportFixture(b2Fixture *fixture, const b2Vec2 &, const b2Vec2 &, float fraction) override {
        if (fixture->GetBody() == self_) return -1.0f;
        if (fraction < best) best = fraction;
        return fraction;
    }
    float best = 2.0f;

private:
    const b2Body *self_;
};
}  // namespace

void Simulation::reference_scan() {
    std::fill(true_dist_.begin(), true_dist_.end(), kInf);
    const double len = robot_.range_max_m + robot_.sonar_offset_m;
    const double w = 2.0 * kPi / cfg_.n_sectors, half = sonar_.cone() / 2;
    const b2Vec2 p1(static_cast<float>(pos_.x), static_cast<float>(pos_.y));
    for (int deg = 0; deg < 360; ++deg) {
        const double a = heading_ + deg * kPi / 180.0;
        const b2Vec2 p2(static_cast<float>(pos_.x + len * std::cos(a)),
                        static_cast<float>(pos_.y + len * std::sin(a)));
        ClosestHit hit(body_);
        world_->RayCast(&hit, p1, p2);
        if (hit.best > 1.0f) continue;
        const double d = static_cast<double>(hit.best) * len;
        for (std::uint16_t k = 0; k < cfg_.n_sectors; ++k)
            if (std::fabs(wrap_pi(deg * kPi / 180.0 - k * w)) <= half + 1e-12)
                true_dist_[k] = std::min(true_dist_[k], d);
    }
}

bool Simulation::touching(Vec2 *contact) {
    // Nearest obstacle or wall surface to the robot centre: touching when within the body
    // radius plus slack; the distance is kept to decide whether the next step needs Box2D.
    const double lim = robot_.radius_m + kTouchSlack_m;
    const double far = robot_.radius_m + robot_.v_max_mps * QNAV_SIM_TICK_S * 4 + 0.5;
    double best = kInf;
    Vec2 best_q{};
    const double wall_d[4] = {env_.width_m - pos_.x, env_.height_m - pos_.y, pos_.x, pos_.y};
    const Vec2 feet[4] = {{env_.width_m, pos_.y}, {pos_.x, env_.height_m}, {0.0, pos_.y}, {pos_.x, 0.0}};
    for (int w = 0; w < 4; ++w) {
        if (wall_d[w] < best) {
            best = wall_d[w];
            best_q = feet[w];
        }
    }
    // Only the shapes near the robot (the sonar's broad phase), in any order: on a tie the
    // lowest-numbered shape gives the contact point, as a scan of every shape in order
    // would (and a wall before any shape).
    const std::vector<Shape> &shapes = sonar_.shapes();
    std::uint32_t best_k = UINT32_MAX;  // shape that gave best; UINT32_MAX: a wall
    sonar_.for_shapes_near(pos_, far, [&](std::uint32_t k) {
        const Shape &s = shapes[k];
        const Vec2 dc = s.c - pos_;
        const double bound = s.r + far;
        if (dot(dc, dc) > bound * bound) return;
        Vec2 q;
        const double d = nearest_point(s, pos_, &q);
        if (d < best || (d == best && best_k != UINT32_MAX && k < best_k)) {
            best = d;
            best_q = q;
            best_k = k;
        }
    });
    clearance_m_ = std::min(best, far);
    if (best <= lim) {
        *contact = best_q;
        return true;
    }
    return false;
}

// The fixed manoeuvre sets the wheels directly: back away, then turn in place.
void Simulation::recovery_wheels() {
    const double b = robot_.wheel_base_m, vmax = robot_.v_max_mps;
    const std::uint32_t phase = robot_.recovery_ticks - recovery_left_;
    if (phase < robot_.recovery_back_ticks) {
        wheel_l_ = wheel_r_ = recovery_back_sign_ * robot_.recovery_back_speed_mps;
    } else {
        const std::uint32_t turn_ticks = robot_.recovery_ticks - robot_.recovery_back_ticks;
        const double omega = recovery_turn_sign_ * robot_.recovery_turn_deg * kPi / 180.0 /
                             (turn_ticks * QNAV_SIM_TICK_S);
        wheel_l_ = std::clamp(-omega * b / 2, -vmax, vmax);
        wheel_r_ = -wheel_l_;
    }
}

// The decision (robot-frame heading, rad; speed fraction) in whole degrees and Q1.15 as a
// board receives it, and the rolling speed the board's encoders measured over the last tick.
struct BoardDecision {
    qnav_deg_t deg;
    qnav_q1_15_t speed, rolling;
};

static qnav_q1_15_t q15(double f) {
    return static_cast<qnav_q1_15_t>(std::lround(std::clamp(f, -1.0, 1.0) * 32767.0));
}

static BoardDecision board_decision(double heading_rad, double speed, qnav_q1_15_t rolling) {
    const long deg = std::lround(wrap_pi(heading_rad) * 180.0 / kPi);
    return {static_cast<qnav_deg_t>(deg <= -180 ? deg + 360 : deg), q15(std::max(speed, 0.0)), rolling};
}

// The robot's forward speed as its board measures it (qnav_board's dead reckoning): the two
// wheels' encoder counts over the last tick ([odometry] um_per_count a count), their mean
// travel as a fraction of v_max (qnav_drive_rolling). A robot that creeps slower than a count
// a tick reads 0 on some ticks and a count on others, as the board's does; the wheels' own
// speed, which the simulator used before 0.20.1, is what no board knows.
qnav_q1_15_t Simulation::encoder_rolling() {
    const double per_count_m = robot_.um_per_count * 1e-6;
    const auto cl = static_cast<std::int64_t>(std::floor(travel_l_m_ / per_count_m));
    const auto cr = static_cast<std::int64_t>(std::floor(travel_r_m_ / per_count_m));
    const std::int64_t counts = (cl - counts_l_) + (cr - counts_r_);
    counts_l_ = cl;
    counts_r_ = cr;
    const std::int64_t step_um = std::clamp<std::int64_t>(counts * robot_.um_per_count / 2, INT32_MIN, INT32_MAX);
    return qnav_drive_rolling(static_cast<std::int32_t>(step_um), static_cast<std::uint16_t>(std::lround(QNAV_SIM_TICK_S * 1000.0)),
                              static_cast<std::uint16_t>(std::lround(robot_.v_max_mps * 1000.0)));
}

// [drive] model "mix": the decision as the board turns it into wheel speeds, held for the
// tick. Model "heading": whether this tick brakes before it turns back (a servo brakes and
// turns at once otherwise).
void Simulation::drive_targets(double heading_rad, double speed) {
    const BoardDecision d = board_decision(heading_rad, speed, rolling_);
    if (!robot_.drive_mix) {
        braking_ = robot_.brake_first && qnav_drive_servo_brakes_first(d.deg, d.rolling) != 0;
        return;
    }
    qnav_q1_15_t l = 0, r = 0;
    qnav_drive_mix(d.deg, d.speed, d.rolling, robot_.turn_full_deg, &l, &r);
    mix_l_ = l / 32767.0 * robot_.v_max_mps;
    mix_r_ = r / 32767.0 * robot_.v_max_mps;
}

// Heading controller: turn rate proportional to the heading error, forward speed
// reduced by cos(error) (no driving while facing away), then per-wheel acceleration
// limits; with model "mix" the wheels go to drive_targets()' speeds instead.
void Simulation::heading_wheels(double dt) {
    const double b = robot_.wheel_base_m, vmax = robot_.v_max_mps;
    if (robot_.drive_mix) {
        wheel_l_ = approach(wheel_l_, mix_l_, robot_.accel_mps2, robot_.decel_mps2, dt);
        wheel_r_ = approach(wheel_r_, mix_r_, robot_.accel_mps2, robot_.decel_mps2, dt);
        return;
    }
    // braking before a turn: no turn and no forward speed asked until the tick's end
    const double e = braking_ ? 0.0 : wrap_pi(target_heading_ - heading_);
    const double wmax = robot_.turn_rate_max_dps * kPi / 180.0;
    const double omega_d = std::clamp(robot_.heading_gain_per_s * e, -wmax, wmax);
    const double v_d = braking_ ? 0.0 : target_speed_ * vmax * std::max(0.0, std::cos(e));
    double tl = v_d - omega_d * b / 2, tr = v_d + omega_d * b / 2;
    const double over = std::max(std::fabs(tl), std::fabs(tr)) / vmax;
    if (over > 1.0) {
        // Keep the turn, give up forward speed.
        const double om = std::clamp(omega_d, -2 * vmax / b, 2 * vmax / b);
        const double v = std::clamp(v_d, -(vmax - std::fabs(om) * b / 2), vmax - std::fabs(om) * b / 2);
        tl = v - om * b / 2;
        tr = v + om * b / 2;
    }
    if (robot_.body_limits) {
        // The limits act on the body (ARCOS: translational and rotational profiles):
        // forward speed at accel/decel, turn rate at the rates the wheel limits give a
        // turn in place (2 accel / b, 2 decel / b); the turn gets what the wheels have
        // left beside the forward speed, so braking never waits for a turn.
        const double v = approach(0.5 * (wheel_l_ + wheel_r_), 0.5 * (tl + tr),
                                  robot_.accel_mps2, robot_.decel_mps2, dt);
        double om = approach((wheel_r_ - wheel_l_) / b, (tr - tl) / b, 2 * robot_.accel_mps2 / b,
                             2 * robot_.decel_mps2 / b, dt);
        const double room = std::max(0.0, vmax - std::fabs(v)) * 2 / b;
        om = std::clamp(om, -room, room);
        wheel_l_ = v - om * b / 2;
        wheel_r_ = v + om * b / 2;
    } else {
        wheel_l_ = approach(wheel_l_, tl, robot_.accel_mps2, robot_.decel_mps2, dt);
        wheel_r_ = approach(wheel_r_, tr, robot_.accel_mps2, robot_.decel_mps2, dt);
    }
}

// Box2D only where a contact is possible this step: far from every obstacle the disc
// moves freely and its motion is integrated here exactly as Box2D would (no forces:
// position += dt * velocity, angle += dt * turn rate). Box2D's step costs about a
// microsecond, most of it in its internal timers.
void Simulation::move_body(double omega_a, double v_lat, double dt) {
    const double reach = robot_.radius_m + (robot_.v_max_mps + std::fabs(v_lat)) * dt * 1.5 + 0.05;
    if (clearance_m_ > reach && !reference_) {
        pos_ = pos_ + dt * vel_;
        heading_ = wrap_pi(heading_ + dt * omega_a);
        body_stale_ = true;
        return;
    }
    if (body_stale_) {
        body_->SetTransform(b2Vec2(static_cast<float>(pos_.x), static_cast<float>(pos_.y)),
                            static_cast<float>(heading_));
        body_stale_ = false;
    }
    body_->SetLinearVelocity(b2Vec2(static_cast<float>(vel_.x), static_cast<float>(vel_.y)));
    body_->SetAngularVelocity(static_cast<float>(omega_a));
    world_->Step(static_cast<float>(dt), kVelocityIterations, kPositionIterations);
    const b2Vec2 p = body_->GetPosition();
    pos_ = {p.x, p.y};
    heading_ = wrap_pi(body_->GetAngle());
    const b2Vec2 bv = body_->GetLinearVelocity();
    vel_ = {bv.x, bv.y};
}

void Simulation::drive_substep(double dt) {
    if (recovery_left_ > 0)
        recovery_wheels();
    else
        heading_wheels(dt);
    const double vmax = robot_.v_max_mps;
    const double v = 0.5 * (wheel_l_ + wheel_r_);
    travel_l_m_ += wheel_l_ * dt;  // what the encoders count: the wheels' own travel, slip or not
    travel_r_m_ += wheel_r_ * dt;
    const double omega = (wheel_r_ - wheel_l_) / robot_.wheel_base_m;
    // Slip: turning loses some of its rate at speed, and the body skids outwards.
    const double omega_a = omega * (1.0 - robot_.slip_turn * std::min(1.0, std::fabs(v) / vmax));
    const double v_lat = -robot_.slip_lateral_s * v * omega_a;
    const double ch = std::cos(heading_), sh = std::sin(heading_);
    vel_ = {v * ch - v_lat * sh, v * sh + v_lat * ch};
    move_body(omega_a, v_lat, dt);
}

void Simulation::start_recovery(Vec2 contact) {
    // Stop the wheels; the fixed manoeuvre starts next tick, backing away from the contact
    // and turning away from its side.
    ++collisions_;
    recovery_left_ = robot_.recovery_ticks;
    wheel_l_ = wheel_r_ = 0;
    const Vec2 d = contact - pos_;
    const double rel = wrap_pi(std::atan2(d.y, d.x) - heading_);
    recovery_back_sign_ = std::cos(rel) >= 0 ? -1.0 : 1.0;
    recovery_turn_sign_ = rel > 0 ? -1 : 1;
    marks_.push_back({tick_, pos_, contact});
}

void Simulation::advance() {
    if (!started_) throw SimError(QNAV_SIM_E_STATE, "advance: no episode (call reset first)");
    if (done_) return;
    using Clock = std::chrono::steady_clock;
    Clock::time_point t0;
    if (profiling_) t0 = Clock::now();
    const bool recovering = recovery_left_ > 0;
    rolling_ = encoder_rolling();  // every tick, as the board's dead reckoning counts
    if (!recovering) {
        double he = cmd_heading_deg_ * kPi / 180.0, sp = cmd_speed_;
        const double pa = cfg_.actuation_noise;
        if (pa > 0) {
            he += pa * kPi * rng_act_.normal();
            sp = std::clamp(sp * (1.0 + pa * rng_act_.normal()), 0.0, 1.0);
        }
        target_heading_ = wrap_pi(heading_ + he);
        target_speed_ = sp;
        drive_targets(he, sp);
    }
    const Vec2 before = pos_;
    const double dt = QNAV_SIM_TICK_S / kSubsteps;
    bool touched = false;
    Vec2 contact{};
    for (int i = 0; i < kSubsteps; ++i) {
        drive_substep(dt);
        if (!recovering && !touched) touched = touching(&contact);
    }
    if (recovering) {
        --recovery_left_;
        ++tau_c_;
    }
    l_m_ += norm(pos_ - before);
    ++tick_;
    // A new collision, or still touching when the manoeuvre ends: start (another) one.
    collided_this_tick_ = recovering ? recovery_left_ == 0 && touching(&contact) : touched;
    if (collided_this_tick_) start_recovery(contact);
    if (profiling_) prof_.physics_s += std::chrono::duration<double>(Clock::now() - t0).count();
    const double dx = env_.dest_x_m - pos_.x, dy = env_.dest_y_m - pos_.y;
    if (dx * dx + dy * dy <= env_.dest_radius_m * env_.dest_radius_m) {
        reached_ = true;
        done_ = true;
    } else if (tick_ >= limit_ticks_) {
        done_ = true;
    }
    if (!done_) compute_scan();
}

double Simulation::forward_speed() const {
    return vel_.x * std::cos(heading_) + vel_.y * std::sin(heading_);
}

qnav_sim_state_t Simulation::state() const {
    qnav_sim_state_t s{};
    s.tick = tick_;
    s.x_m = pos_.x;
    s.y_m = pos_.y;
    s.heading_rad = heading_;
    s.speed_mps = forward_speed();
    s.goal_distance_m = norm(dest() - pos_);
    s.recovering = recovery_left_ > 0;
    s.recovery_ticks_left = recovery_left_;
    s.collisions = collisions_;
    s.done = done_;
    s.reached = reached_;
    return s;
}

qnav_sim_result_t Simulation::result() const {
    qnav_sim_result_t r{};
    r.l = l_m_;
    r.beta_l = std::max(0.0, norm(dest() - start_) - env_.dest_radius_m);
    r.tau_l = tick_ * QNAV_SIM_TICK_S;
    r.beta_tau = shortest_time(r.beta_l, robot_.v_max_mps, robot_.accel_mps2);
    r.d_start_m = r.beta_l;
    r.d_end_m = reached_ ? 0.0
                         : std::max(0.0, norm(dest() - pos_) - env_.dest_radius_m);
    r.tau_c = tau_c_;
    r.reached = reached_;
    r.ticks = tick_;
    r.collisions = collisions_;
    r.start_x_m = start_.x;
    r.start_y_m = start_.y;
    r.start_heading_rad = start_heading_;
    compute_fitness(&r, cfg_.fitness);
    return r;
}

qnav_sim_sample_t Simulation::sample() const {
    qnav_sim_sample_t s{};
    s.tick = tick_;
    s.x_m = pos_.x;
    s.y_m = pos_.y;
    s.heading_rad = heading_;
    s.speed_mps = forward_speed();
    s.cmd_heading_deg = static_cast<qnav_deg_t>(std::lround(cmd_heading_deg_));
    s.cmd_speed = cmd_speed_;
    s.recovering = recovery_left_ > 0;
    s.collided = collided_this_tick_;
    s.escape_side = escape_side_;
    s.goal_bearing_deg = cmd_goal_cdeg_ / 100.0;
    s.goal_range_m = cmd_goal_mm_ / 1000.0;
    return s;
}

namespace {
void step_ctrl(void *self, const qnav_ctrl_input_t *in, qnav_ctrl_output_t *out) {
    qnav_ctrl_step(static_cast<const qnav_ctrl_t *>(self), in, out, nullptr);
}
void step_nav(void *self, const qnav_ctrl_input_t *in, qnav_ctrl_output_t *out) {
    qnav_nav_step(static_cast<qnav_nav_t *>(self), in, out);
}
}  // namespace

qnav_sim_result_t Simulation::run_episode(const qnav_ctrl_t *ctrl, std::uint64_t episode_seed,
                                          qnav_sim_trace_fn trace, void *user) {
    return run_episode_with(step_ctrl, const_cast<qnav_ctrl_t *>(ctrl), ctrl->clr.n_sectors,
                            ctrl->clr.max_range_mm, episode_seed, trace, user);
}

qnav_sim_result_t Simulation::run_episode(qnav_nav_t *nav, std::uint64_t episode_seed,
                                          qnav_sim_trace_fn trace, void *user) {
    std::uint16_t n = 0;
    qnav_mm_t range = 0;
    qnav_nav_sensors(nav, &n, &range);
    if (qnav_nav_method(nav) == nullptr)
        throw SimError(QNAV_SIM_E_PARAM, "controller: not initialised (qnav_nav_init failed or was not called)");
    qnav_nav_reset(nav);
    return run_episode_with(step_nav, nav, n, range, episode_seed, trace, user);
}

qnav_sim_result_t Simulation::run_episode_with(StepFn step, void *self, std::uint16_t n_sectors,
                                               qnav_mm_t max_range_mm, std::uint64_t episode_seed,
                                               qnav_sim_trace_fn trace, void *user) {
    if (n_sectors != cfg_.n_sectors)
        throw SimError(QNAV_SIM_E_PARAM, "controller: n_sectors " + std::to_string(n_sectors) +
                                             " does not match the simulation's " +
                                             std::to_string(cfg_.n_sectors));
    if (max_range_mm != max_range_mm_)
        throw SimError(QNAV_SIM_E_PARAM, "controller: max_range_mm " + std::to_string(max_range_mm) +
                                             " does not match the robot's " +
                                             std::to_string(max_range_mm_));
    using Clock = std::chrono::steady_clock;
    reset(episode_seed);
    if (trace) {
        const qnav_sim_sample_t s = sample();
        trace(user, &s);
    }
    qnav_ctrl_input_t in{};
    in.ranges_mm = scan_.ranges_mm;
    qnav_ctrl_output_t out{};
    while (!done_) {
        in.goal_bearing_cdeg = scan_.goal_bearing_cdeg;
        in.prev_heading_cdeg = scan_.prev_heading_cdeg;
        in.goal_range_mm = scan_.goal_range_mm;
        in.escape = out.escape;
        qnav_escape_follow_plan(&in.escape, scan_.escape_clear, scan_.escape_grow_mm);
        Clock::time_point t0;
        if (profiling_) t0 = Clock::now();
        step(self, &in, &out);
        if (profiling_) prof_.controller_s += std::chrono::duration<double>(Clock::now() - t0).count();
        if (out.flags & QNAV_FLAG_NOT_READY)
            throw SimError(QNAV_SIM_E_PARAM, "controller: not initialised (qnav_ctrl_init failed or was not called)");
        command(out.heading_deg, QNAV_Q1_15_TO_REAL(out.speed));
        escape_side_ = out.escape.side;
        advance();
        if (trace) {
            const qnav_sim_sample_t s = sample();
            trace(user, &s);
        }
    }
    return result();
}

}  // namespace qnav
