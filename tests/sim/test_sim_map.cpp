// The map above the controller in the simulator (a profile's [map]; docs/architecture.md,
// "A map and a plan"): a wall across the arena with its gap far to one side, which the
// probabilistic policy alone rarely finds in time, and the map's pose taken from odometry
// with errors drawn once an episode (what a board's dead reckoning gives it).
#include "sim_test_util.hpp"

#include "qnav/ctrl.h"
#include "qnav/map.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>

namespace {

// A wall across at y = 5 with a 1 m gap at its east end; the destination straight north of
// the start, beyond the wall.
const char *const kWall =
    "name = \"wall\"\nepisode_limit_s = 60.0\n[arena]\nwidth_m = 10.0\nheight_m = 10.0\n"
    "[destination]\nx_m = 3.0\ny_m = 8.5\nradius_m = 0.4\n"
    "[[start_zone]]\nx_m = 2.5\ny_m = 1.0\nw_m = 1.0\nh_m = 1.0\n"
    "[[box]]\nx_m = 4.25\ny_m = 5.0\nw_m = 8.5\nh_m = 0.2\n";

// The TekBot's profile with extra appended and odometry keys added to its [odometry].
std::string tekbot_with(const std::string &extra, const std::string &odometry = "") {
    std::string text = read_text_file(std::string(QNAV_TEST_DATA_DIR) + "/robots/tekbot.toml");
    const std::size_t map = text.find("\n[map]");  // the profile's own (off, last): extra replaces it
    assert_true(map != std::string::npos);
    text.erase(map + 1);
    const std::size_t at = text.find('\n', text.find("um_per_count", text.find("[odometry]")));
    assert_true(at != std::string::npos);
    return text.insert(at + 1, odometry) + "\n" + extra;
}

struct Run {
    unsigned reached = 0;
    uint32_t ticks = 0;     // summed over the episodes
    uint32_t collisions = 0;
};

// The probabilistic policy with this profile text in kWall: robot, world, context and its
// controller, freed at the end of the scope.
struct WallSim {
    qnav_sim_robot_t *robot = nullptr;
    qnav_sim_env_t *env = nullptr;
    qnav_sim_t *sim = nullptr;
    qnav_ctrl_t ctrl;
    explicit WallSim(const std::string &profile, double sensor_noise = 0.05, double map_frame_deg = -1.0,
                     double survey_m = 0.0) {
        char err[QNAV_SIM_ERRLEN] = "";
        if (qnav_sim_robot_parse(profile.data(), profile.size(), "tekbot-map.toml", &robot, err,
                                 sizeof err) != QNAV_SIM_OK)
            fail_with("robot", err);
        if (qnav_sim_env_parse(kWall, std::strlen(kWall), "wall.toml", &env, err, sizeof err) != QNAV_SIM_OK)
            fail_with("env", err);
        qnav_sim_config_t cfg;
        qnav_sim_config_default(&cfg);
        cfg.n_sectors = 16;
        cfg.sensor_noise = sensor_noise;
        cfg.actuation_noise = 0.01;
        cfg.seed = 3;
        cfg.map_frame_deg = map_frame_deg;
        cfg.survey_m = survey_m;
        if (qnav_sim_create(robot, env, &cfg, &sim, err, sizeof err) != QNAV_SIM_OK) fail_with("sim", err);
        qnav_ctrl_config_t cc;
        qnav_sim_ctrl_config(sim, &cc);
        qnav_policy_t p;
        qnav_sim_robot_prob_policy(robot, &p);
        assert_int_equal(qnav_ctrl_init(&ctrl, &cc, &p), QNAV_OK);
    }
    ~WallSim() {
        qnav_sim_destroy(sim);
        qnav_sim_env_free(env);
        qnav_sim_robot_free(robot);
    }
};

// Episodes 0..n-1 of the probabilistic policy with this profile text in kWall, at this
// sensor noise, the map's grid at this angle to the walls (negative: drawn per episode).
Run run(const std::string &profile, unsigned n, double sensor_noise = 0.05, double map_frame_deg = -1.0) {
    WallSim w(profile, sensor_noise, map_frame_deg);
    Run r;
    for (uint64_t e = 0; e < n; ++e) {
        qnav_sim_result_t res;
        assert_int_equal(qnav_sim_run_episode(w.sim, &w.ctrl, e, &res, nullptr, nullptr), QNAV_SIM_OK);
        r.reached += res.reached ? 1u : 0u;
        r.ticks += res.ticks;
        r.collisions += res.collisions;
    }
    return r;
}

// What the trace's samples say of the destination the controller was given, over one
// episode in kWall: the largest planned distance beyond the straight one from the pose the
// command was made at (the sample before), and how far the given range and bearing stray
// from the straight line's when the map is off.
struct GoalSeen {
    double longest_detour_m = 0;   // max over ticks of given range - straight distance
    double worst_range_err_m = 0;  // without a map: |given - straight|
    double worst_bearing_err_deg = 0;
    double last_x = 0, last_y = 0, last_heading = 0;
    bool have_last = false;
    unsigned ticks = 0;
};

void see_goal(void *user, const qnav_sim_sample_t *s) {
    GoalSeen &g = *static_cast<GoalSeen *>(user);
    if (g.have_last && s->tick > 0) {
        const double dx = 3.0 - g.last_x, dy = 8.5 - g.last_y;  // kWall's destination
        const double straight = std::hypot(dx, dy);
        double bearing = (std::atan2(dy, dx) - g.last_heading) * 180.0 / M_PI;
        bearing = std::remainder(bearing, 360.0);
        g.longest_detour_m = std::max(g.longest_detour_m, s->goal_range_m - straight);
        g.worst_range_err_m = std::max(g.worst_range_err_m, std::fabs(s->goal_range_m - straight));
        g.worst_bearing_err_deg =
            std::max(g.worst_bearing_err_deg, std::fabs(std::remainder(s->goal_bearing_deg - bearing, 360.0)));
        ++g.ticks;
    }
    g.last_x = s->x_m;
    g.last_y = s->y_m;
    g.last_heading = s->heading_rad;
    g.have_last = true;
}

GoalSeen goal_seen(const std::string &profile) {
    WallSim w(profile, 0.0, 0.0);
    GoalSeen g;
    qnav_sim_result_t res;
    assert_int_equal(qnav_sim_run_episode(w.sim, &w.ctrl, 0, &res, see_goal, &g), QNAV_SIM_OK);
    return g;
}

// The trace carries the destination each command answered: without a map the straight one
// (to the scan's mm and its heading's noise-free 0.01 deg), with one the plan's way round
// the wall, metres longer than the straight line once the wall is seen.
void test_the_trace_carries_the_destination_the_controller_was_given(void **) {
    const GoalSeen without = goal_seen(tekbot_with(""));
    const GoalSeen with = goal_seen(tekbot_with("[map]\ncell_m = 0.1\n"));
    print_message("trace: without a map range error %.4f m, bearing error %.3f deg over %u ticks; with "
                  "one the longest detour %.2f m\n",
                  without.worst_range_err_m, without.worst_bearing_err_deg, without.ticks, with.longest_detour_m);
    assert_true(without.ticks > 10);
    assert_true(without.worst_range_err_m < 0.002);
    assert_true(without.worst_bearing_err_deg < 0.02);
    assert_true(with.longest_detour_m > 1.0);
}

void test_the_map_finds_the_gap_the_policy_alone_misses(void **) {
    const Run without = run(tekbot_with(""), 10);
    const Run with = run(tekbot_with("[map]\ncell_m = 0.1\n"), 10);
    print_message("wall with a far gap: %u/10 arrive with the map (%u collisions, %u ticks), %u/10 without (%u ticks)\n",
                  with.reached, with.collisions, with.ticks, without.reached, without.ticks);
    assert_true(with.reached >= 9);
    assert_true(with.reached >= without.reached);
    // the plan leads to the gap; alone, the policy searches along the wall: at least a fifth
    // fewer ticks over the ten (the time-outs counted at the limit)
    assert_true(5u * with.ticks < 4u * without.ticks);
    assert_int_equal(with.collisions, 0);
}

// A board's map lies in its heading sensor's frame, at no particular angle to a room's
// walls: the simulator turns the map's grid by an angle drawn per episode (or the one
// given), and the robot finds the far gap at any turn. The turn reaches the map: the same
// episodes with the grid aligned and turned 30 deg are not the same.
void test_the_maps_grid_is_turned_against_the_walls(void **) {
    const std::string fine = tekbot_with("[map]\ncell_m = 0.1\n");
    unsigned turns = 0;
    uint32_t aligned_ticks = 0;
    for (const double deg : {0.0, 30.0, 45.0, -1.0}) {
        const Run r = run(fine, 10, 0.05, deg);
        print_message("wall with a far gap, the map's grid %s%g deg: %u/10 arrive, %u ticks, %u collisions\n",
                      deg < 0 ? "drawn per episode, not " : "at ", deg < 0 ? 0.0 : deg, r.reached, r.ticks,
                      r.collisions);
        assert_true(r.reached >= 9);
        assert_int_equal(r.collisions, 0);
        if (deg == 0.0) aligned_ticks = r.ticks;
        else turns += r.ticks != aligned_ticks ? 1u : 0u;
    }
    assert_int_equal(turns, 3u);
    // the turn drawn per episode is the episode's: the same context and episodes, the same run
    const Run a = run(fine, 4), b = run(fine, 4);
    assert_int_equal(a.ticks, b.ticks);
}

// In an empty arena a map changes nothing: the TekBot with its compact map arrives in every
// episode, as without. Its plan reaches the robot a few ticks after the start, and until
// then the escape measured the straight distance; the plan's longer way looked like a
// stall, and the robot followed the walls in 6 of 50 episodes (docs/architecture.md, "The
// planned distance").
void test_an_empty_arena_with_the_compact_map_is_no_dead_end(void **) {
    for (const char *robot : {"tekbot+map", "tekbot-map"}) {
        TestSim t;
        make_test_sim(t, robot, "", "open", 16, 0.05, 0.01, 77);
        qnav_ctrl_config_t cc;
        qnav_sim_ctrl_config(t.sim, &cc);
        qnav_policy_t p;
        qnav_sim_robot_prob_policy(t.robot, &p);
        qnav_ctrl_t ctrl;
        assert_int_equal(qnav_ctrl_init(&ctrl, &cc, &p), QNAV_OK);
        unsigned reached = 0, collisions = 0;
        for (uint64_t e = 0; e < 50; ++e) {
            qnav_sim_result_t res;
            assert_int_equal(qnav_sim_run_episode(t.sim, &ctrl, e, &res, nullptr, nullptr), QNAV_SIM_OK);
            reached += res.reached ? 1u : 0u;
            collisions += res.collisions;
        }
        print_message("open, %s: %u/50 arrive within 30 s, %u collisions\n", robot, reached, collisions);
        assert_int_equal(reached, 50);
        assert_int_equal(collisions, 0);
    }
}

// The step API gives a caller who keeps the escape memory what the map did to it: cleared
// (escape_clear) or grown with a longer plan (escape_grow_mm). Applied, the episodes are
// the simulator's own, tick for tick; the wall makes the plan grow.
void test_the_step_api_carries_what_the_map_did_to_the_escape(void **) {
    WallSim w(tekbot_with("[map]\ncell_m = 0.1\n"));
    unsigned grown = 0, cleared = 0;
    for (uint64_t e = 0; e < 4; ++e) {
        qnav_sim_result_t whole, stepped;
        assert_int_equal(qnav_sim_run_episode(w.sim, &w.ctrl, e, &whole, nullptr, nullptr), QNAV_SIM_OK);
        qnav_sim_state_t whole_end, st;
        assert_int_equal(qnav_sim_state(w.sim, &whole_end), QNAV_SIM_OK);
        assert_int_equal(qnav_sim_reset(w.sim, e), QNAV_SIM_OK);
        assert_int_equal(qnav_sim_state(w.sim, &st), QNAV_SIM_OK);
        qnav_ctrl_output_t out{};
        while (!st.done) {
            qnav_sim_scan_t s;
            assert_int_equal(qnav_sim_scan(w.sim, &s), QNAV_SIM_OK);
            const qnav_ctrl_input_t in = step_input(s, out);
            grown += s.escape_grow_mm > 0 ? 1u : 0u;
            cleared += s.escape_clear;
            qnav_ctrl_step(&w.ctrl, &in, &out, nullptr);
            assert_int_equal(qnav_sim_command(w.sim, &out), QNAV_SIM_OK);
            assert_int_equal(qnav_sim_advance(w.sim), QNAV_SIM_OK);
            assert_int_equal(qnav_sim_state(w.sim, &st), QNAV_SIM_OK);
        }
        assert_int_equal(qnav_sim_result(w.sim, &stepped), QNAV_SIM_OK);
        assert_int_equal(stepped.ticks, whole.ticks);
        assert_int_equal(stepped.reached, whole.reached);
        assert_true(st.x_m == whole_end.x_m && st.y_m == whole_end.y_m);
    }
    print_message("wall with a far gap, 4 episodes: the plan grew the escape memory on %u ticks and "
                  "cleared it on %u\n", grown, cleared);
    assert_true(grown > 0);
}

void test_odometry_errors_move_the_maps_pose_only_when_drawn(void **) {
    const std::string map = "[map]\ncell_m = 0.1\n";
    const Run truth = run(tekbot_with(map), 4);
    // errors of 0 are the true pose: the same episodes, tick for tick
    const Run zero = run(tekbot_with(map, "err_scale_pct = 0\nerr_turn_pct = 0\nerr_curve_deg_m = 0\n"), 4);
    assert_int_equal(zero.ticks, truth.ticks);
    assert_int_equal(zero.reached, truth.reached);
    // drawn errors: other episodes, the same ones again for the same seeds
    const std::string drift = "err_scale_pct = 2\nerr_turn_pct = 5\nerr_curve_deg_m = 3\n";
    const Run a = run(tekbot_with(map, drift), 4);
    const Run b = run(tekbot_with(map, drift), 4);
    assert_int_equal(a.ticks, b.ticks);
    assert_int_not_equal(a.ticks, truth.ticks);
    print_message("drifting odometry: %u/4 arrive (true pose %u/4)\n", a.reached, truth.reached);
}

// The one line a profile text is refused with (the test fails if it is accepted).
std::string refusal(const std::string &profile) {
    char err[QNAV_SIM_ERRLEN] = "";
    qnav_sim_robot_t *robot = nullptr;
    assert_int_not_equal(qnav_sim_robot_parse(profile.data(), profile.size(), "bad.toml", &robot, err, sizeof err),
                         QNAV_SIM_OK);
    assert_null(robot);
    print_message("%s\n", err);
    return err;
}

// The first command's planned distance beyond the straight line to kWall's destination, and
// the episode's ticks, with each episode's map surveyed from a survey_m grid (0: none).
struct FirstPlan {
    double detour_m = -1;  // < 0 until the first command's sample
    double last_x = 0, last_y = 0;
    bool have_last = false;
};

void see_first_plan(void *user, const qnav_sim_sample_t *s) {
    FirstPlan &f = *static_cast<FirstPlan *>(user);
    if (f.have_last && s->tick > 0 && f.detour_m < 0)
        f.detour_m = s->goal_range_m - std::hypot(3.0 - f.last_x, 8.5 - f.last_y);
    f.last_x = s->x_m;
    f.last_y = s->y_m;
    f.have_last = true;
}

FirstPlan first_plan(const std::string &profile, double survey_m, uint32_t *ticks) {
    WallSim w(profile, 0.05, -1.0, survey_m);
    FirstPlan f;
    qnav_sim_result_t res;
    assert_int_equal(qnav_sim_run_episode(w.sim, &w.ctrl, 0, &res, see_first_plan, &f), QNAV_SIM_OK);
    assert_true(res.reached);
    assert_int_equal(res.collisions, 0);
    *ticks = res.ticks;
    return f;
}

// A known world (qnav_sim_config_t.survey_m): the wall lies 3.5 m ahead of the start, beyond
// the TekBot's sonar, so a map that starts empty plans straight at it, and a surveyed one
// plans round by the far gap from the first command and arrives sooner, in both layouts.
void test_a_surveyed_map_knows_the_wall_before_the_sonar_sees_it(void **) {
    for (const char *map : {"[map]\ncell_m = 0.1\n", "[map]\ncompact = true\nbytes = 768\ncell_m = 0.3\n"}) {
        uint32_t plain_ticks = 0, known_ticks = 0;
        const FirstPlan plain = first_plan(tekbot_with(map), 0.0, &plain_ticks);
        const FirstPlan known = first_plan(tekbot_with(map), 0.4, &known_ticks);
        print_message("%s: first plan's detour %.2f m unknown, %.2f m surveyed; arrived in %u / %u ticks\n",
                      std::strstr(map, "compact") ? "compact" : "full", plain.detour_m, known.detour_m, plain_ticks,
                      known_ticks);
        assert_true(plain.detour_m >= 0 && plain.detour_m < 1.5);  // near-wall costs, cells
        assert_true(known.detour_m > plain.detour_m + 4.0);          // by the gap at x 8.5..10
        assert_true(known_ticks < plain_ticks);
    }
}

// A survey needs a map to fill and a grid step it can walk.
void test_a_survey_is_refused_without_a_map_or_a_sane_step(void **) {
    const std::string no_map = tekbot_with(""), map = tekbot_with("[map]\ncell_m = 0.1\n");
    const struct {
        const std::string *profile;
        double survey_m;
    } bad[] = {{&no_map, 0.4}, {&map, 0.01}, {&map, 11.0}, {&map, -1.0}, {&map, NAN}};
    for (const auto &b : bad) {
        char err[QNAV_SIM_ERRLEN] = "";
        qnav_sim_robot_t *robot = nullptr;
        qnav_sim_env_t *env = nullptr;
        qnav_sim_t *sim = nullptr;
        assert_int_equal(qnav_sim_robot_parse(b.profile->data(), b.profile->size(), "p.toml", &robot, err, sizeof err),
                         QNAV_SIM_OK);
        assert_int_equal(qnav_sim_env_parse(kWall, std::strlen(kWall), "wall.toml", &env, err, sizeof err),
                         QNAV_SIM_OK);
        qnav_sim_config_t cfg;
        qnav_sim_config_default(&cfg);
        cfg.survey_m = b.survey_m;
        assert_int_equal(qnav_sim_create(robot, env, &cfg, &sim, err, sizeof err), QNAV_SIM_E_PARAM);
        assert_null(sim);
        assert_true(std::string(err).rfind("survey_m: ", 0) == 0);
        qnav_sim_env_free(env);
        qnav_sim_robot_free(robot);
    }
}

void test_bad_odometry_settings_are_refused_by_field(void **) {
    const std::string err = refusal(tekbot_with("[map]\ncell_m = 0.1\n", "err_turn_pct = -1\n"));
    assert_true(err.find("err_turn_pct") != std::string::npos);
    assert_true(err.find("bad.toml") != std::string::npos);
}

// The controller configuration a profile gives (qnav_sim_robot_ctrl_config, the one mapping
// the simulator, the board headers and navbridge use); fails the test on a parse error.
qnav_ctrl_config_t profile_config(const std::string &profile, std::uint16_t n_sectors = 0) {
    char err[QNAV_SIM_ERRLEN] = "";
    qnav_sim_robot_t *robot = nullptr;
    if (qnav_sim_robot_parse(profile.data(), profile.size(), "p.toml", &robot, err, sizeof err) != QNAV_SIM_OK)
        fail_with("robot", err);
    qnav_ctrl_config_t cc;
    qnav_sim_robot_ctrl_config(robot, n_sectors, &cc);
    qnav_sim_robot_free(robot);
    return cc;
}

// [map] pass_m is the controller's passing distance while a map guides it; without it, or
// without a map, or with fewer than 6 sectors, the passing distance is the safety distance
// (docs/architecture.md, "Passing distance"). A bad value is refused naming the key.
void test_a_maps_passing_distance_reaches_the_controller(void **) {
    const qnav_ctrl_config_t plain = profile_config(tekbot_with(""));
    const qnav_ctrl_config_t map = profile_config(tekbot_with("[map]\ncell_m = 0.1\n"));
    const qnav_ctrl_config_t pass = profile_config(tekbot_with("[map]\ncell_m = 0.1\npass_m = 0.01\n"));
    assert_int_equal(plain.safety_mm, 50);
    assert_int_equal(plain.pass_mm, plain.safety_mm);
    assert_int_equal(map.pass_mm, map.safety_mm);
    assert_int_equal(pass.pass_mm, 10);
    assert_int_equal(pass.safety_mm, 50);
    // wedges wider than 60 degrees keep the safety distance: 6 sectors pass nearer, 5 do not
    assert_int_equal(profile_config(tekbot_with("[map]\ncell_m = 0.1\npass_m = 0.01\n"), 6).pass_mm, 10);
    assert_int_equal(profile_config(tekbot_with("[map]\ncell_m = 0.1\npass_m = 0.01\n"), 5).pass_mm, 50);
    assert_true(refusal(tekbot_with("[map]\ncell_m = 0.1\npass_m = -0.01\n")).find("pass_m") != std::string::npos);
}

// A loaded robot spec's map configuration: 1 and cfg when its map is on, 0 when off (and
// in *bytes the board's memory for it); the test fails if the spec does not load.
int loaded_map(const char *spec, qnav_map_config_t *cfg, qnav_ctrl_config_t *cc, uint32_t *bytes = nullptr) {
    char err[QNAV_SIM_ERRLEN] = "";
    qnav_sim_robot_t *robot = nullptr;
    if (qnav_sim_robot_load(spec, &robot, err, sizeof err) != QNAV_SIM_OK) fail_with(spec, err);
    const int on = qnav_sim_robot_map_config(robot, cfg);
    if (bytes) *bytes = qnav_sim_robot_map_bytes(robot);
    qnav_sim_robot_ctrl_config(robot, 0, cc);
    qnav_sim_robot_free(robot);
    return on;
}

// The map is told the profile's typical range noise, as the board made from the profile is
// (its generated header), not the noise the run draws, which a board cannot know: a run at
// 20 % noise goes differently when the profile states 20 % than when it states 5 %, the
// sonar's samples being the same (docs/architecture.md, "The map's range noise").
void test_the_map_is_told_the_profiles_sensor_noise(void **) {
    std::string stated = tekbot_with("[map]\ncell_m = 0.1\n");
    const std::size_t at = stated.find("\nsensor = 0.05");
    assert_true(at != std::string::npos);
    stated.replace(at, 14, "\nsensor = 0.20");
    const Run typical = run(tekbot_with("[map]\ncell_m = 0.1\n"), 6, 0.2);
    const Run high = run(stated, 6, 0.2);
    print_message("at 20 %% noise, 6 episodes: %u ticks with the profile's 5 %%, %u with 20 %%\n",
                  typical.ticks, high.ticks);
    assert_true(typical.ticks != high.ticks);
    qnav_map_config_t mc;
    qnav_ctrl_config_t cc;
    assert_int_equal(loaded_map("tekbot+map", &mc, &cc), 1);
    assert_int_equal(mc.noise_pct, 10); /* the profile's [map] noise, 0.10 (its [noise] sensor is 0.05) */
    assert_int_equal(loaded_map("pioneer3dx+map", &mc, &cc), 1);
    assert_int_equal(mc.noise_pct, 1);
}

// Both robots' profiles run their maps (on = true: the compact map their ATmega128 holds,
// the TekBot's of 0.3 m cells, the Pioneer's of 0.5 m). NAME+map switches the profile's own
// map on, as written, and nothing else; NAME-map switches it off (the robot of the paper's
// experiments). A profile with no [map] has nothing to switch on: refused naming the file;
// NAME-map of it is the profile itself. 'on' takes only true or false.
void test_name_plus_map_switches_on_the_profiles_own_map(void **) {
    for (const char *robot : {"tekbot", "pioneer3dx"}) {
        const bool tekbot = std::string(robot) == "tekbot";
        qnav_map_config_t off, on, plain_map;
        qnav_ctrl_config_t plain, with, without;
        uint32_t bytes = 0, off_bytes = 1;
        assert_int_equal(loaded_map(robot, &plain_map, &plain, &bytes), 1);
        assert_int_equal(bytes, tekbot ? 768 : 512); /* placed as the board places it */
        assert_int_equal(loaded_map((std::string(robot) + "-map").c_str(), &off, &without, &off_bytes), 0);
        assert_int_equal(off_bytes, 0);
        assert_int_equal(loaded_map((std::string(robot) + "+map").c_str(), &on, &with), 1);
        /* the map their ATmega128 holds: 4 bits a cell of 0.3 m (TekBot) or 0.5 m */
        assert_int_equal(on.cell_mm, tekbot ? 300 : 500);
        assert_int_equal(on.compact, 1);
        assert_int_equal(on.grow_steps, tekbot ? 10 : 16);
        assert_int_equal(on.near_cost, 0);
        assert_int_equal(on.refuse_ticks, tekbot ? 30 : 10); /* the TekBot's 3 s, the Pioneer's 1 s (a compact map refuses only when told to) */
        assert_true(on.cell_mm == plain_map.cell_mm && on.compact == plain_map.compact);
        assert_int_equal(with.safety_mm, without.safety_mm);
        assert_int_equal(with.n_sectors, without.n_sectors);
        assert_int_equal(with.max_range_mm, without.max_range_mm);
        assert_int_equal(on.reach_mm, tekbot ? 2000 : 3000);
        assert_int_equal(with.pass_mm, tekbot ? 10 : without.safety_mm);
        assert_int_equal(plain.pass_mm, with.pass_mm);
        assert_int_equal(without.pass_mm, without.safety_mm);
    }
    char dir[] = "/tmp/qnav_map_test_XXXXXX";
    assert_non_null(mkdtemp(dir));
    const std::string file = std::string(dir) + "/nomap.toml";
    std::FILE *f = std::fopen(file.c_str(), "w");
    assert_non_null(f);
    std::fputs(tekbot_with("").c_str(), f);
    assert_int_equal(std::fclose(f), 0);
    char err[QNAV_SIM_ERRLEN] = "";
    qnav_sim_robot_t *robot = nullptr;
    assert_int_not_equal(qnav_sim_robot_load((file + "+map").c_str(), &robot, err, sizeof err), QNAV_SIM_OK);
    assert_null(robot);
    print_message("%s\n", err);
    assert_true(std::string(err).find(file + " has no [map]") != std::string::npos);
    assert_int_equal(qnav_sim_robot_load((file + "-map").c_str(), &robot, err, sizeof err), QNAV_SIM_OK);
    qnav_sim_robot_free(robot);
    assert_int_equal(std::remove(file.c_str()), 0);
    assert_int_equal(rmdir(dir), 0);
    assert_true(refusal(tekbot_with("[map]\non = 1\ncell_m = 0.1\n")).find("'on' must be true or false") !=
                std::string::npos);
    /* a compact map: cells wider than the body's reach, no near costs (refusals mark cells
     * occupied), and grow_steps only with it */
    assert_true(refusal(tekbot_with("[map]\ncompact = true\ncell_m = 0.15\n")).find("'cell_m' must exceed") !=
                std::string::npos);
    assert_true(refusal(tekbot_with("[map]\ncompact = true\ncell_m = 0.4\nnear_cost = 1\n"))
                    .find("'near_cost' must be 0 in a compact map") != std::string::npos);
    {
        const std::string ok = tekbot_with("[map]\ncompact = true\ncell_m = 0.4\nrefuse_s = 2\n");
        char why[QNAV_SIM_ERRLEN] = "";
        qnav_sim_robot_t *r = nullptr;
        assert_int_equal(qnav_sim_robot_parse(ok.data(), ok.size(), "ok.toml", &r, why, sizeof why), QNAV_SIM_OK);
        qnav_sim_robot_free(r);
    }
    assert_true(refusal(tekbot_with("[map]\ncompact = 1\ncell_m = 0.4\n")).find("'compact' must be true or false") !=
                std::string::npos);
    assert_true(refusal(tekbot_with("[map]\ncell_m = 0.4\ngrow_steps = 4\n")).find("'grow_steps' is a compact map's") !=
                std::string::npos);
}

// The map configuration a profile gives (the test fails naming the profile's error).
qnav_map_config_t map_config_of(const std::string &profile) {
    char err[QNAV_SIM_ERRLEN] = "";
    qnav_sim_robot_t *robot = nullptr;
    if (qnav_sim_robot_parse(profile.data(), profile.size(), "map.toml", &robot, err, sizeof err) != QNAV_SIM_OK)
        fail_with("robot", err);
    qnav_map_config_t cfg;
    assert_int_equal(qnav_sim_robot_map_config(robot, &cfg), 1);
    qnav_sim_robot_free(robot);
    return cfg;
}

// [map] arc_deg, the arc a reading marks, reaches the map in 0.01 deg (default 22.5 deg);
// the former share of the wedge, arc_pct, is refused naming the key, and so is an angle
// outside 0..360 (docs/architecture.md, "The arc a reading marks").
void test_the_maps_arc_is_an_angle_from_the_profile(void **) {
    assert_int_equal(map_config_of(tekbot_with("[map]\ncell_m = 0.1\n")).arc_cdeg, 2250);
    assert_int_equal(map_config_of(tekbot_with("[map]\ncell_m = 0.1\narc_deg = 11.25\n")).arc_cdeg, 1125);
    assert_true(refusal(tekbot_with("[map]\ncell_m = 0.1\narc_pct = 50\n")).find("arc_pct") != std::string::npos);
    assert_true(refusal(tekbot_with("[map]\ncell_m = 0.1\narc_deg = 361\n")).find("arc_deg") != std::string::npos);
    // arc_width_m, the arc's width across at its range, in mm (default 0: no limit)
    assert_int_equal(map_config_of(tekbot_with("[map]\ncell_m = 0.1\n")).arc_width_mm, 0);
    assert_int_equal(map_config_of(tekbot_with("[map]\ncell_m = 0.1\narc_width_m = 0.21\n")).arc_width_mm, 210);
    assert_true(refusal(tekbot_with("[map]\ncell_m = 0.1\narc_width_m = -0.1\n")).find("arc_width_m") !=
                std::string::npos);
}

// [map] opening_m reaches the map in mm (default 0: every reading marks); a negative one is
// refused naming the key (docs/architecture.md, "A reading that may be an opening").
void test_the_maps_opening_comes_from_the_profile(void **) {
    assert_int_equal(map_config_of(tekbot_with("[map]\ncell_m = 0.1\n")).opening_mm, 0);
    assert_int_equal(map_config_of(tekbot_with("[map]\ncell_m = 0.1\nopening_m = 0.27\n")).opening_mm, 270);
    assert_true(refusal(tekbot_with("[map]\ncell_m = 0.1\nopening_m = -1\n")).find("opening_m") != std::string::npos);
}

}  // namespace

int main() {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_the_map_finds_the_gap_the_policy_alone_misses),
        cmocka_unit_test(test_the_trace_carries_the_destination_the_controller_was_given),
        cmocka_unit_test(test_the_maps_grid_is_turned_against_the_walls),
        cmocka_unit_test(test_an_empty_arena_with_the_compact_map_is_no_dead_end),
        cmocka_unit_test(test_the_step_api_carries_what_the_map_did_to_the_escape),
        cmocka_unit_test(test_odometry_errors_move_the_maps_pose_only_when_drawn),
        cmocka_unit_test(test_bad_odometry_settings_are_refused_by_field),
        cmocka_unit_test(test_a_maps_passing_distance_reaches_the_controller),
        cmocka_unit_test(test_name_plus_map_switches_on_the_profiles_own_map),
        cmocka_unit_test(test_the_map_is_told_the_profiles_sensor_noise),
        cmocka_unit_test(test_the_maps_arc_is_an_angle_from_the_profile),
        cmocka_unit_test(test_the_maps_opening_comes_from_the_profile),
        cmocka_unit_test(test_a_surveyed_map_knows_the_wall_before_the_sonar_sees_it),
        cmocka_unit_test(test_a_survey_is_refused_without_a_map_or_a_sane_step),
    };
    return cmocka_run_group_tests(tests, nullptr, nullptr);
}
