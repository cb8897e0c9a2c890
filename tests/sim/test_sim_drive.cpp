/*
 * The drive model: acceleration and deceleration limits of the Pioneer profile (0.3 and
 * 0.6 m/s^2, 1 m/s), on the body (the Pioneer: braking does not wait for a turn) or on each
 * wheel, the heading controller turning to a commanded heading, and slip (a slipping robot
 * turns less at speed and skids outwards).
 */
#include "sim_test_util.hpp"

#include <algorithm>
#include <cmath>

#include "qnav/drive.h"

static const double kPiD = 3.14159265358979323846;

static qnav_sim_state_t drive(qnav_sim_t *sim, double heading_deg, double speed, int ticks) {
    qnav_sim_command_raw(sim, heading_deg, speed);
    for (int i = 0; i < ticks; ++i) qnav_sim_advance(sim);
    qnav_sim_state_t st;
    qnav_sim_state(sim, &st);
    return st;
}

static void test_pioneer_speeds_up_at_0_3_and_slows_at_0_6_mps2_to_1_mps(void **state) {
    (void)state;
    TestSim t;
    make_test_sim(t, "pioneer3dx", test_env_text(""), nullptr, 16, 0, 0);
    assert_int_equal(qnav_sim_reset(t.sim, 1), QNAV_SIM_OK);
    assert_int_equal(qnav_sim_place(t.sim, 0.8, 5.0, 0.0), QNAV_SIM_OK);
    qnav_sim_state_t st = drive(t.sim, 0.0, 1.0, 10);
    assert_true(std::fabs(st.speed_mps - 0.3) < 1e-3);  // 1 s at 0.3 m/s^2
    st = drive(t.sim, 0.0, 1.0, 30);
    assert_true(std::fabs(st.speed_mps - 1.0) < 1e-3);  // capped at v_max
    st = drive(t.sim, 0.0, 0.0, 10);
    assert_true(std::fabs(st.speed_mps - 0.4) < 1e-3);  // 1 s at 0.6 m/s^2
    st = drive(t.sim, 0.0, 0.0, 10);
    assert_true(std::fabs(st.speed_mps) < 1e-9);
    assert_true(std::fabs(st.y_m - 5.0) < 1e-6);  // straight line
}

static void test_heading_controller_turns_to_the_commanded_heading_and_stays(void **state) {
    (void)state;
    TestSim t;
    make_test_sim(t, "tekbot", test_env_text(""), nullptr, 8, 0, 0);
    assert_int_equal(qnav_sim_reset(t.sim, 1), QNAV_SIM_OK);
    assert_int_equal(qnav_sim_place(t.sim, 5.0, 5.0, 0.0), QNAV_SIM_OK);
    // Command a world heading of 90 deg, relative to the current heading every tick.
    qnav_sim_state_t st;
    qnav_sim_state(t.sim, &st);
    for (int i = 0; i < 30; ++i) {
        const double rel = std::remainder(kPiD / 2 - st.heading_rad, 2 * kPiD) * 180.0 / kPiD;
        st = drive(t.sim, rel, 0.0, 1);
    }
    assert_true(std::fabs(st.heading_rad - kPiD / 2) < 0.02);
    assert_true(std::hypot(st.x_m - 5.0, st.y_m - 5.0) < 1e-6);  // turned on the spot
}

// Heading change after driving 20 ticks at full speed while commanding 30 deg left.
static double turn_at_speed(const char *slip_turn, const char *slip_lateral, double *lateral) {
    std::string text;
    {
        std::FILE *f = std::fopen(QNAV_TEST_DATA_DIR "/robots/pioneer3dx.toml", "rb");
        char buf[4096];
        size_t n;
        while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) text.append(buf, n);
        std::fclose(f);
    }
    text.replace(text.find("turn = 0.15"), 11, std::string("turn = ") + slip_turn);
    text.replace(text.find("lateral_s = 0.04"), 16, std::string("lateral_s = ") + slip_lateral);
    char err[QNAV_SIM_ERRLEN];
    qnav_sim_robot_t *robot = nullptr;
    qnav_sim_env_t *env = nullptr;
    qnav_sim_t *sim = nullptr;
    const std::string et = test_env_text("");
    assert_int_equal(qnav_sim_robot_parse(text.data(), text.size(), "r.toml", &robot, err, sizeof err), QNAV_SIM_OK);
    assert_int_equal(qnav_sim_env_parse(et.data(), et.size(), "e.toml", &env, err, sizeof err), QNAV_SIM_OK);
    qnav_sim_config_t cfg;
    qnav_sim_config_default(&cfg);
    assert_int_equal(qnav_sim_create(robot, env, &cfg, &sim, err, sizeof err), QNAV_SIM_OK);
    assert_int_equal(qnav_sim_reset(sim, 1), QNAV_SIM_OK);
    assert_int_equal(qnav_sim_place(sim, 2.0, 2.0, 0.0), QNAV_SIM_OK);
    drive(sim, 0.0, 1.0, 40);  // up to 1 m/s first
    qnav_sim_state_t a, b;
    qnav_sim_state(sim, &a);
    qnav_sim_command_raw(sim, 30.0, 1.0);
    qnav_sim_advance(sim);
    qnav_sim_state(sim, &b);
    // Sideways displacement in the frame of the heading at the start of the tick.
    const double dx = b.x_m - a.x_m, dy = b.y_m - a.y_m;
    *lateral = -std::sin(a.heading_rad) * dx + std::cos(a.heading_rad) * dy;
    const double turned = b.heading_rad - a.heading_rad;
    qnav_sim_destroy(sim);
    qnav_sim_env_free(env);
    qnav_sim_robot_free(robot);
    return turned;
}

static void test_slipping_robot_turns_less_at_speed_and_skids_outwards(void **state) {
    (void)state;
    double lat_grip, lat_slip;
    const double grip = turn_at_speed("0.0", "0.0", &lat_grip);
    const double slip = turn_at_speed("0.15", "0.04", &lat_slip);
    assert_true(grip > 0.0);
    // The first tick of the turn: wheels near full speed, so the rate loss is close to 15 %.
    assert_true(slip < grip * 0.9);
    assert_true(slip > grip * 0.8);
    // Turning left: a gripping robot's chord goes left, a skidding one's less so.
    assert_true(lat_slip < lat_grip);
}

// A simulator of the robot profile `text` in the empty test arena, no noise, placed at
// (x, y) facing +x.
static void sim_of_profile(TestSim &t, const std::string &text, double x, double y) {
    char err[QNAV_SIM_ERRLEN];
    const std::string et = test_env_text("");
    assert_int_equal(qnav_sim_robot_parse(text.data(), text.size(), "r.toml", &t.robot, err, sizeof err), QNAV_SIM_OK);
    assert_int_equal(qnav_sim_env_parse(et.data(), et.size(), "e.toml", &t.env, err, sizeof err), QNAV_SIM_OK);
    qnav_sim_config_t cfg;
    qnav_sim_config_default(&cfg);
    assert_int_equal(qnav_sim_create(t.robot, t.env, &cfg, &t.sim, err, sizeof err), QNAV_SIM_OK);
    assert_int_equal(qnav_sim_reset(t.sim, 1), QNAV_SIM_OK);
    assert_int_equal(qnav_sim_place(t.sim, x, y, 0.0), QNAV_SIM_OK);
}

// The Pioneer's profile with its line `line` replaced by `by`, placed at (1, 2) facing +x and
// brought up to 1 m/s.
static void pioneer_at_full_speed(TestSim &t, const std::string &line, const std::string &by) {
    std::string text = read_text_file(QNAV_TEST_DATA_DIR "/robots/pioneer3dx.toml");
    const size_t at = text.find(line);
    assert_true(at != std::string::npos);
    text.replace(at, line.size(), by);
    sim_of_profile(t, text, 1.0, 2.0);
    const qnav_sim_state_t st = drive(t.sim, 0.0, 1.0, 40);
    assert_true(std::fabs(st.speed_mps - 1.0) < 1e-3);
}

// Slowing to a tenth of full speed while turning 40 deg left (commanded afresh every tick,
// so the turn never ends) from 0.5 m/s, for 6 ticks, on the Pioneer's profile with its
// [drive] limits replaced: the speed at the end, the distance covered and the turn.
static void brake_while_turning(const char *limits, double *speed, double *dist, double *turned) {
    TestSim t;
    pioneer_at_full_speed(t, "limits = \"body\"", std::string("limits = \"") + limits + "\"");
    const qnav_sim_state_t a = drive(t.sim, 0.0, 0.5, 10);  // down to 0.5 m/s
    assert_true(std::fabs(a.speed_mps - 0.5) < 1e-3);
    qnav_sim_state_t b = a;
    *dist = 0;
    for (int i = 0; i < 6; ++i) {
        const qnav_sim_state_t p = b;
        b = drive(t.sim, 40.0, 0.1, 1);
        *dist += std::hypot(b.x_m - p.x_m, b.y_m - p.y_m);
    }
    *speed = b.speed_mps;
    *turned = (b.heading_rad - a.heading_rad) * 180.0 / kPiD;
}

static void test_body_limits_brake_at_decel_while_turning(void **state) {
    (void)state;
    double v_body, v_wheel, d_body, d_wheel, turn_body, turn_wheel;
    brake_while_turning("body", &v_body, &d_body, &turn_body);
    brake_while_turning("wheel", &v_wheel, &d_wheel, &turn_wheel);
    print_message("body: %.4f m/s, %.3f m, %.1f deg; wheel: %.4f m/s, %.3f m, %.1f deg\n", v_body,
                  d_body, turn_body, v_wheel, d_wheel, turn_wheel);
    // body: 0.6 s at 0.6 m/s^2, whatever the turn does: 0.5 - 0.36 = 0.14 m/s (the 0.1 m/s
    // asked for times the cosine of the heading error, 0.08-0.1, is not reached yet);
    // travelled 0.1 s x (0.44 + 0.38 + ... + 0.14) = 0.174 m
    assert_true(std::fabs(v_body - 0.14) < 0.01);
    assert_true(std::fabs(d_body - 0.174) < 0.01);
    assert_true(turn_body > 10.0);  // and it turns meanwhile
    // wheel: the outer wheel stops slowing at the turn's share (0.4 m/s), only the inner one
    // brakes, and the robot slows at half the rate: what the speed guard, which assumes
    // decel, does not see
    assert_true(v_wheel > v_body + 0.1);
    assert_true(d_wheel > d_body + 0.03);
}

// The TekBot's profile drives as its board mixes (model "mix"): a decision held each tick
// (30 deg left at full speed) gives the wheels qnav_drive_mix()'s speeds, so the robot
// circles at the forward part and turns at the wheels' difference; a turn in place at
// speed 0 turns without moving; and a decision to turn 168 deg at speed 0 from full speed
// brakes both wheels at decel first and turns only once the encoders count no travel
// forward in a tick, as the board's does (docs/sim.md, "Drive model").
static void test_the_tekbot_drives_as_its_board_mixes(void **state) {
    (void)state;
    TestSim t;
    make_test_sim(t, "tekbot", test_env_text(""), nullptr, 8, 0, 0);
    qnav_q1_15_t l = 0, r = 0;
    qnav_drive_mix(30, 32767, 32767, 90, &l, &r);
    const double v_l = l / 32767.0 * 0.5, v_r = r / 32767.0 * 0.5;  // v_max 0.5 m/s
    assert_int_equal(qnav_sim_reset(t.sim, 1), QNAV_SIM_OK);
    assert_int_equal(qnav_sim_place(t.sim, 5.0, 5.0, 0.0), QNAV_SIM_OK);
    qnav_sim_state_t a, b;
    for (int i = 0; i < 10; ++i) a = drive(t.sim, 30.0, 1.0, 1);  // the wheels at their speeds
    b = drive(t.sim, 30.0, 1.0, 1);
    const double turn = std::remainder(b.heading_rad - a.heading_rad, 2 * kPiD) / 0.1;
    const double v = 0.5 * (v_l + v_r), w = (v_r - v_l) / 0.18;  // wheel base 0.18 m
    print_message("mix: %.4f m/s, %.3f rad/s; expected %.4f, %.3f less slip\n", b.speed_mps, turn, v, w);
    assert_true(std::fabs(b.speed_mps - v) < 0.03 * v);  // the speed is read along the turned heading
    assert_true(std::fabs(turn - w * (1.0 - 0.03 * v / 0.5)) < 0.02 * w);  // slip turn 0.03
    // a turn in place: 90 deg left at speed 0, from standing
    assert_int_equal(qnav_sim_reset(t.sim, 1), QNAV_SIM_OK);
    assert_int_equal(qnav_sim_place(t.sim, 5.0, 5.0, 0.0), QNAV_SIM_OK);
    b = drive(t.sim, 90.0, 0.0, 3);
    assert_true(b.heading_rad > 0.3);
    assert_true(std::hypot(b.x_m - 5.0, b.y_m - 5.0) < 1e-6);
    // from 0.5 m/s straight, a turn of 168 deg at speed 0: both wheels brake at 2 m/s^2
    // (0.5, 0.3, 0.1, 0 m/s), then it turns in place where it stopped
    assert_int_equal(qnav_sim_reset(t.sim, 1), QNAV_SIM_OK);
    assert_int_equal(qnav_sim_place(t.sim, 5.0, 5.0, 0.0), QNAV_SIM_OK);
    b = drive(t.sim, 0.0, 1.0, 10);
    assert_true(std::fabs(b.speed_mps - 0.5) < 1e-3);
    const double h0 = b.heading_rad;
    b = drive(t.sim, 168.0, 0.0, 1);
    print_message("braking before the turn: %.4f m/s after 0.1 s\n", b.speed_mps);
    assert_true(std::fabs(b.speed_mps - (0.5 - 2.0 * 0.1)) < 0.01);
    assert_true(std::fabs(std::remainder(b.heading_rad - h0, 2 * kPiD)) < 0.01);  // not turning yet
    b = drive(t.sim, 168.0, 0.0, 2);
    assert_true(std::fabs(b.speed_mps) < 1e-9);
    assert_true(std::fabs(std::remainder(b.heading_rad - h0, 2 * kPiD)) < 0.01);
    const qnav_sim_state_t at = b;
    b = drive(t.sim, 168.0, 0.0, 5);
    assert_true(std::remainder(b.heading_rad - h0, 2 * kPiD) > 0.5);  // stopped: now it turns
    assert_true(std::hypot(b.x_m - at.x_m, b.y_m - at.y_m) < 1e-6);   // where it stopped
}

// A TekBot whose wheels slew at 0.5 m/s^2 both ways (a robot that brakes slowly), creeping
// at 0.06 m/s, told to turn 150 deg at speed 0: it brakes to a stop and only then turns, and
// does not move while it turns. Until 0.20.1 the mixer turned at once, the robot rolling
// slower than QNAV_DRIVE_STOPPED (0.0625 m/s here), and with wheels that slew at equal rates
// a turn in place keeps the forward speed it starts from: the robot crept on into what it
// turned from (docs/sim.md, "A robot that brakes slowly").
static void test_a_slowly_braking_tekbot_stops_before_it_turns_in_place(void **state) {
    (void)state;
    std::string text = read_text_file(QNAV_TEST_DATA_DIR "/robots/tekbot.toml");
    for (const char *key : {"accel_mps2 = ", "decel_mps2 = "}) {
        const size_t at = text.find(key);
        assert_true(at != std::string::npos);
        text.replace(at, text.find('#', at) - at, std::string(key) + "0.5 ");
    }
    TestSim t;
    sim_of_profile(t, text, 5.0, 5.0);
    qnav_sim_state_t b = drive(t.sim, 0.0, 0.08, 20);  // creeping on at 0.04 m/s
    assert_true(std::fabs(b.speed_mps - 0.04) < 1e-3);
    bool turning = false;
    double x0 = 0, y0 = 0, crept = 0, turned = 0, h = b.heading_rad;
    for (int i = 0; i < 20; ++i) {
        b = drive(t.sim, 150.0, 0.0, 1);
        turned += std::remainder(b.heading_rad - h, 2 * kPiD);
        h = b.heading_rad;
        if (!turning && turned > 1.0 * kPiD / 180.0) {
            turning = true;  // its first degree: where it stood when the turn began
            x0 = b.x_m;
            y0 = b.y_m;
        }
        if (turning) crept = std::max(crept, std::hypot(b.x_m - x0, b.y_m - y0));
    }
    print_message("slow brakes: turned %.2f rad, moved %.4f m while turning\n", turned, crept);
    assert_true(turned > 1.5);
    assert_true(crept < 0.005);
}

// The heading model brakes before a turn in place as the mixer does ([drive] brake_first,
// qnav_drive_brakes_first): the Pioneer at 1 m/s told to turn 170 deg at speed 0 holds its
// heading and brakes at 0.6 m/s^2 in a straight line while it rolls faster than 1/8 of
// v_max (15 ticks: 1.0 - 15 x 0.06 = 0.1 m/s), and turns after; brake_first = false turns
// at once while it brakes, and its momentum carries it off the line toward the turn.
static void test_the_pioneer_brakes_before_a_turn_in_place(void **state) {
    (void)state;
    TestSim on, off;
    pioneer_at_full_speed(on, "brake_first = true", "brake_first = true");
    pioneer_at_full_speed(off, "brake_first = true", "brake_first = false");
    qnav_sim_state_t a = drive(on.sim, 170.0, 0.0, 14);
    print_message("brake first: %.3f m/s, heading %.4f rad, y %.4f m after 1.4 s\n", a.speed_mps,
                  a.heading_rad, a.y_m);
    assert_true(std::fabs(a.speed_mps - (1.0 - 14 * 0.06)) < 1e-3);
    assert_true(std::fabs(a.heading_rad) < 1e-9);  // not a degree turned yet
    assert_true(std::fabs(a.y_m - 2.0) < 1e-6);    // a straight line
    a = drive(on.sim, 170.0, 0.0, 1);
    assert_true(a.speed_mps < 0.125 && std::fabs(a.heading_rad) < 1e-9);
    a = drive(on.sim, 170.0, 0.0, 10);
    assert_true(a.heading_rad > 0.5);  // stopped: now it turns
    const qnav_sim_state_t b = drive(off.sim, 170.0, 0.0, 3);
    print_message("turning at once: heading %.3f rad after 0.3 s\n", b.heading_rad);
    assert_true(b.heading_rad > 0.05);  // the turn gets what the wheels have left
    const qnav_sim_state_t c = drive(off.sim, 170.0, 0.0, 7);
    print_message("and off the line: y %.3f m after 1 s\n", c.y_m);
    assert_true(c.y_m > 2.05);
}

// A stop the speed guard asks with the way on 30 deg to one side is no turn back: the
// Pioneer's servo brakes at 0.6 m/s^2 and turns toward it at once (separate translational
// and rotational profiles, qnav_drive_servo_brakes_first), curving away from the line it
// braked along before (0.19.0; docs/sim.md, "Brake, then turn").
static void test_the_pioneer_brakes_and_turns_at_once_for_a_small_turn(void **state) {
    (void)state;
    TestSim t;
    pioneer_at_full_speed(t, "brake_first = true", "brake_first = true");
    const qnav_sim_state_t a = drive(t.sim, 30.0, 0.0, 3);
    print_message("a stop with the way 30 deg left: %.3f m/s, heading %.3f rad after 0.3 s\n", a.speed_mps,
                  a.heading_rad);
    assert_true(std::fabs(a.speed_mps - (1.0 - 3 * 0.06)) < 0.02);  // braking at its deceleration
    assert_true(a.heading_rad > 0.05);                              // and turning already
}

// The mixer's full turn comes from the profile (qnav_sim_robot_info().turn_full_deg): the
// TekBot's 90 deg; twice its v_max on the same track, 180 (the same turn rate for a degree
// of heading); a slower one keeps 90 (never a full turn short of it); the Pioneer 116.
static unsigned turn_full_with(const char *v_max) {
    std::string text = read_text_file(QNAV_TEST_DATA_DIR "/robots/tekbot.toml");
    const std::string key = "v_max_mps = 0.5";
    text.replace(text.find(key), key.size(), std::string("v_max_mps = ") + v_max);
    char err[QNAV_SIM_ERRLEN];
    qnav_sim_robot_t *robot = nullptr;
    assert_int_equal(qnav_sim_robot_parse(text.data(), text.size(), "r.toml", &robot, err, sizeof err), QNAV_SIM_OK);
    qnav_sim_robot_info_t ri;
    qnav_sim_robot_info(robot, &ri);
    qnav_sim_robot_free(robot);
    return ri.turn_full_deg;
}

static void test_the_mixers_full_turn_keeps_the_turn_rate_per_degree(void **state) {
    (void)state;
    assert_int_equal(turn_full_with("0.5"), 90);
    assert_int_equal(turn_full_with("1.0"), 180);
    assert_int_equal(turn_full_with("1.5"), 270);
    assert_int_equal(turn_full_with("0.3"), 90);
    qnav_sim_robot_t *robot = nullptr;
    char err[QNAV_SIM_ERRLEN];
    assert_int_equal(qnav_sim_robot_load(QNAV_TEST_DATA_DIR "/robots/pioneer3dx.toml", &robot, err, sizeof err), QNAV_SIM_OK);
    qnav_sim_robot_info_t ri;
    qnav_sim_robot_info(robot, &ri);
    qnav_sim_robot_free(robot);
    assert_int_equal(ri.turn_full_deg, 116);  // 2 x 1.0 / (0.33 x 3.0) rad
}

static void test_limits_key_is_checked(void **state) {
    (void)state;
    std::string text = read_text_file(QNAV_TEST_DATA_DIR "/robots/pioneer3dx.toml");
    const std::string key = "limits = \"body\"";
    text.replace(text.find(key), key.size(), "limits = \"wheels\"");
    char err[QNAV_SIM_ERRLEN] = "";
    qnav_sim_robot_t *robot = nullptr;
    assert_int_equal(qnav_sim_robot_parse(text.data(), text.size(), "r.toml", &robot, err, sizeof err),
                     QNAV_SIM_E_PARSE);
    assert_non_null(std::strstr(err, "'limits' must be \"wheel\" or \"body\""));
    // the drive model: one of two, and a mix drives each wheel
    std::string tek = read_text_file(QNAV_TEST_DATA_DIR "/robots/tekbot.toml");
    const std::string mix = "model = \"mix\"";
    assert_true(tek.find(mix) != std::string::npos);
    std::string bad = tek;
    bad.replace(bad.find(mix), mix.size(), "model = \"mixer\"");
    assert_int_equal(qnav_sim_robot_parse(bad.data(), bad.size(), "r.toml", &robot, err, sizeof err),
                     QNAV_SIM_E_PARSE);
    assert_non_null(std::strstr(err, "'model' must be \"heading\" or \"mix\""));
    bad = tek;
    bad.replace(bad.find(mix), mix.size(), mix + "\nlimits = \"body\"");
    assert_int_equal(qnav_sim_robot_parse(bad.data(), bad.size(), "r.toml", &robot, err, sizeof err),
                     QNAV_SIM_E_PARSE);
    assert_non_null(std::strstr(err, "not with limits = \"body\""));
    // brake_first: a boolean, and the mix always brakes first
    bad = tek;
    bad.replace(bad.find(mix), mix.size(), mix + "\nbrake_first = false");
    assert_int_equal(qnav_sim_robot_parse(bad.data(), bad.size(), "r.toml", &robot, err, sizeof err),
                     QNAV_SIM_E_PARSE);
    assert_non_null(std::strstr(err, "the mix always brakes first"));
    text = read_text_file(QNAV_TEST_DATA_DIR "/robots/pioneer3dx.toml");
    const std::string bf = "brake_first = true";
    text.replace(text.find(bf), bf.size(), "brake_first = 1");
    assert_int_equal(qnav_sim_robot_parse(text.data(), text.size(), "r.toml", &robot, err, sizeof err),
                     QNAV_SIM_E_PARSE);
    assert_non_null(std::strstr(err, "'brake_first' must be true or false"));
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_pioneer_speeds_up_at_0_3_and_slows_at_0_6_mps2_to_1_mps),
        cmocka_unit_test(test_heading_controller_turns_to_the_commanded_heading_and_stays),
        cmocka_unit_test(test_slipping_robot_turns_less_at_speed_and_skids_outwards),
        cmocka_unit_test(test_body_limits_brake_at_decel_while_turning),
        cmocka_unit_test(test_the_tekbot_drives_as_its_board_mixes),
        cmocka_unit_test(test_a_slowly_braking_tekbot_stops_before_it_turns_in_place),
        cmocka_unit_test(test_the_pioneer_brakes_before_a_turn_in_place),
        cmocka_unit_test(test_the_pioneer_brakes_and_turns_at_once_for_a_small_turn),
        cmocka_unit_test(test_the_mixers_full_turn_keeps_the_turn_rate_per_degree),
        cmocka_unit_test(test_limits_key_is_checked),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
