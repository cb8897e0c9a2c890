/*
 * Bad input: malformed robot profiles and environments, a start zone inside an obstacle
 * or outside the arena, a destination overlapping an obstacle, an obstacle wholly outside
 * the arena, a walled-in start zone, a directory or unreadable file, NaN noise on the
 * command line, impossible parameters and a
 * mismatched controller each give one "FILE:LINE: problem" (or "FIELD: problem") line and
 * an error status, never a crash; qnav-sim prints that line and exits non-zero, and its
 * good runs write complete pictures and environment files.
 */
#include "sim_test_util.hpp"

#include <cmath>
#include <string>
#include <unistd.h>
#include <sys/stat.h>
#include <sys/wait.h>

#include "env.hpp"
#include "qnav/ctrl.h"
#include "qnav/policy.h"

static qnav_sim_status_t parse_env(const std::string &text, std::string *msg) {
    char err[QNAV_SIM_ERRLEN] = "";
    qnav_sim_env_t *env = (qnav_sim_env_t *)0x1;
    const qnav_sim_status_t st = qnav_sim_env_parse(text.data(), text.size(), "bad.toml", &env, err, sizeof err);
    if (st == QNAV_SIM_OK) qnav_sim_env_free(env);
    else assert_null(env);
    *msg = err;
    return st;
}

static std::string read_data(const char *rel) {
    return read_text_file(std::string(QNAV_TEST_DATA_DIR) + "/" + rel);
}

static qnav_sim_status_t parse_robot(const std::string &text, std::string *msg) {
    char err[QNAV_SIM_ERRLEN] = "";
    qnav_sim_robot_t *r = nullptr;
    const qnav_sim_status_t st = qnav_sim_robot_parse(text.data(), text.size(), "bad.toml", &r, err, sizeof err);
    if (st == QNAV_SIM_OK) qnav_sim_robot_free(r);
    *msg = err;
    return st;
}

static bool starts_with(const std::string &s, const char *p) { return s.rfind(p, 0) == 0; }
static bool one_line(const std::string &s) { return !s.empty() && s.find('\n') == std::string::npos; }

static void test_committed_profiles_and_environments_load(void **state) {
    (void)state;
    const char *robots[] = {"robots/pioneer3dx.toml", "robots/tekbot.toml"};
    const char *envs[] = {"envs/open.toml", "envs/single.toml", "envs/dense.toml"};
    std::string msg;
    for (const char *r : robots) assert_int_equal(parse_robot(read_data(r), &msg), QNAV_SIM_OK);
    for (const char *e : envs) assert_int_equal(parse_env(read_data(e), &msg), QNAV_SIM_OK);
}

static void test_toml_syntax_error_names_file_and_line(void **state) {
    (void)state;
    std::string msg;
    assert_int_equal(parse_env("name = \"x\"\nepisode_limit_s = 3\n[arena\nwidth_m = 1\n", &msg), QNAV_SIM_E_PARSE);
    assert_true(starts_with(msg, "bad.toml:3:"));
    assert_true(one_line(msg));
}

static void test_missing_table_and_bad_values_name_their_line(void **state) {
    (void)state;
    std::string msg;
    std::string text = test_env_text("");
    std::string no_dest = text;
    no_dest.erase(no_dest.find("[destination]"), std::string("[destination]\nx_m = 9.0\ny_m = 9.0\nradius_m = 0.3\n").size());
    assert_int_equal(parse_env(no_dest, &msg), QNAV_SIM_E_PARSE);
    assert_true(msg.find("missing table [destination]") != std::string::npos);

    std::string neg = text;
    neg.replace(neg.find("radius_m = 0.3"), 14, "radius_m = -1.0");
    assert_int_equal(parse_env(neg, &msg), QNAV_SIM_E_PARSE);
    assert_true(starts_with(msg, "bad.toml:9:"));
    assert_true(msg.find("radius_m") != std::string::npos);

    std::string typo = text + "[[circle]]\nx_m = 5.0\ny_m = 5.0\nraduis_m = 1.0\n";
    assert_int_equal(parse_env(typo, &msg), QNAV_SIM_E_PARSE);
    assert_true(starts_with(msg, "bad.toml:18:"));
    assert_true(msg.find("unknown key 'raduis_m'") != std::string::npos);

    std::string word = text;
    word.replace(word.find("width_m = 10.0"), 14, "width_m = \"ten\"");
    assert_int_equal(parse_env(word, &msg), QNAV_SIM_E_PARSE);
    assert_true(starts_with(msg, "bad.toml:4:"));
    assert_true(msg.find("must be a number") != std::string::npos);
}

static void test_start_zone_inside_an_obstacle_is_refused_with_its_line(void **state) {
    (void)state;
    std::string msg;
    // The start zone (lines 10-14) is at (0.5..1, 0.5..1); a circle at (1, 1).
    assert_int_equal(parse_env(test_env_text("[[circle]]\nx_m = 1.0\ny_m = 1.0\nr_m = 0.4\n"), &msg),
                     QNAV_SIM_E_WORLD);
    assert_true(starts_with(msg, "bad.toml:10:"));
    assert_true(msg.find("overlaps the obstacle at line 15") != std::string::npos);
    std::string out = test_env_text("");
    out.replace(out.find("w_m = 0.5"), 9, "w_m = 20.0");
    assert_int_equal(parse_env(out, &msg), QNAV_SIM_E_WORLD);
    assert_true(msg.find("leaves the arena") != std::string::npos);
    assert_int_equal(parse_env(test_env_text("[[box]]\nx_m = 9.0\ny_m = 9.0\nw_m = 1\nh_m = 1\n"), &msg),
                     QNAV_SIM_E_WORLD);
    assert_true(msg.find("obstacle overlaps the destination") != std::string::npos);
}

static void test_bad_robot_profiles_are_refused(void **state) {
    (void)state;
    std::string good = read_data("robots/pioneer3dx.toml"), msg;
    std::string t1 = good;
    t1.replace(t1.find("range_min_m = 0.1"), 17, "range_min_m = 6.0");
    assert_int_equal(parse_robot(t1, &msg), QNAV_SIM_E_PARSE);
    assert_true(msg.find("'range_min_m' must be below 'range_max_m'") != std::string::npos);
    std::string t2 = good;
    t2.replace(t2.find("back_ticks = 5"), 14, "back_ticks = 50");
    assert_int_equal(parse_robot(t2, &msg), QNAV_SIM_E_PARSE);
    assert_true(msg.find("'back_ticks' exceeds 'ticks'") != std::string::npos);
    std::string t3 = good;
    t3.erase(t3.find("v_max_mps"), t3.find('\n', t3.find("v_max_mps")) - t3.find("v_max_mps") + 1);
    assert_int_equal(parse_robot(t3, &msg), QNAV_SIM_E_PARSE);
    assert_true(msg.find("missing key 'v_max_mps'") != std::string::npos);
    std::string t4 = good;
    t4.replace(t4.find("default_sectors = 16"), 20, "default_sectors = 400");
    assert_int_equal(parse_robot(t4, &msg), QNAV_SIM_E_PARSE);
    assert_true(starts_with(msg, "bad.toml:"));
    assert_true(one_line(msg));
    std::string t5 = good;
    const std::size_t safe = t5.find("\nsafe_m = ") + 1;  // whatever the profile's value
    assert_true(safe != std::string::npos + 1);
    t5.replace(safe, t5.find_first_of(" \n", safe + 9) - safe, "safe_m = 0.0");
    assert_int_equal(parse_robot(t5, &msg), QNAV_SIM_E_PARSE);
    assert_true(msg.find("'safe_m' = 0 is outside") != std::string::npos);
    assert_true(one_line(msg));
    std::string t5b = good;  // the paper's k_safe and the metres both: which one is meant?
    t5b.insert(t5b.find("\nk_goal = ") + 1, "k_safe = 5.0\n");
    assert_int_equal(parse_robot(t5b, &msg), QNAV_SIM_E_PARSE);
    assert_true(msg.find("give 'k_safe' or 'safe_m', not both") != std::string::npos);
    assert_true(one_line(msg));
    std::string t5c = good;
    t5c.erase(safe, t5c.find('\n', safe) - safe + 1);
    assert_int_equal(parse_robot(t5c, &msg), QNAV_SIM_E_PARSE);
    assert_true(msg.find("missing key 'safe_m' (or the paper's 'k_safe')") != std::string::npos);
    // every quantity the board needs is in the profile: none has a silent default
    std::string t6 = good;
    t6.replace(t6.find("tick_ms = 100"), 13, "tick_ms = 50 ");
    assert_int_equal(parse_robot(t6, &msg), QNAV_SIM_E_PARSE);
    assert_true(msg.find("'tick_ms' must be 100") != std::string::npos);
    assert_true(one_line(msg));
    std::string t7 = good;
    t7.erase(t7.find("safety_m"), t7.find('\n', t7.find("safety_m")) - t7.find("safety_m") + 1);
    assert_int_equal(parse_robot(t7, &msg), QNAV_SIM_E_PARSE);
    assert_true(msg.find("missing key 'safety_m'") != std::string::npos);
    std::string t8 = good;
    t8.replace(t8.find("offset_m = 0.26"), 15, "offset_m = 0.30");
    assert_int_equal(parse_robot(t8, &msg), QNAV_SIM_E_PARSE);
    assert_true(msg.find("offset_m") != std::string::npos);
    std::string t9 = good;
    t9.erase(t9.find("full_speed_quality"),
             t9.find('\n', t9.find("full_speed_quality")) - t9.find("full_speed_quality") + 1);
    assert_int_equal(parse_robot(t9, &msg), QNAV_SIM_E_PARSE);
    assert_true(msg.find("missing key 'full_speed_quality'") != std::string::npos);
    std::string t11 = good;  // a compact plan counts steps: no cost for unknown cells
    t11.insert(t11.find("\ncompact = true") + 1, "unknown_cost = 3.0\n");
    assert_int_equal(parse_robot(t11, &msg), QNAV_SIM_E_PARSE);
    assert_true(msg.find("'unknown_cost' must be 0 in a compact map") != std::string::npos);
    assert_true(one_line(msg));
    std::string t10 = good;
    t10.replace(t10.find("full_speed_quality = 0.9"), 24, "full_speed_quality = 0.0");
    assert_int_equal(parse_robot(t10, &msg), QNAV_SIM_E_PARSE);
    assert_true(msg.find("full_speed_quality") != std::string::npos);
    assert_true(one_line(msg));
}

/* `[clearance] wedge_near_m = "stopping"` (the TekBot's profile) is the robot's stopping
 * distance from v_max, v T + v^2 / (2 decel), and follows the profile's drive: 0.1125 m at
 * the TekBot's 0.5 m/s and 2 m/s^2, 0.30 m at 0.5 m/s^2; any other string is refused by
 * name on one line. */
static void test_whole_wedges_within_the_stopping_distance(void **state) {
    (void)state;
    char err[QNAV_SIM_ERRLEN] = "";
    std::string t = read_data("robots/tekbot.toml");
    assert_true(t.find("wedge_near_m = \"stopping\"") != std::string::npos);
    const std::size_t at = t.find("decel_mps2 = ");
    static const struct {
        const char *decel;
        qnav_mm_t near_mm;
    } want[] = {{"2.0", 112}, {"0.5", 300}, {"0.25", 550}};
    for (const auto &w : want) {
        std::string u = t;
        u.replace(at, u.find('#', at) - at, std::string("decel_mps2 = ") + w.decel + " ");
        qnav_sim_robot_t *robot = nullptr;
        qnav_ctrl_config_t cfg;
        assert_int_equal(qnav_sim_robot_parse(u.data(), u.size(), "d.toml", &robot, err, sizeof err), QNAV_SIM_OK);
        qnav_sim_robot_ctrl_config(robot, 0, &cfg);
        assert_true(std::abs(static_cast<int>(cfg.wedge_near_mm) - static_cast<int>(w.near_mm)) <= 1);
        qnav_sim_robot_free(robot);
    }
    std::string bad = t;
    bad.replace(bad.find("\"stopping\""), 10, "\"braking\"");
    std::string msg;
    assert_int_equal(parse_robot(bad, &msg), QNAV_SIM_E_PARSE);
    assert_true(msg.find("'wedge_near_m' must be a distance in m or \"stopping\"") != std::string::npos);
    assert_true(one_line(msg));
}

/* `[clearance] wedge_deg` places a reading over that angle of its wedge at every sector
 * count: the TekBot's 5.625 deg is libqnav's wedge_pct 25 at its 16 sectors, 13 at 8 (12.5
 * rounded), 50 at 32 and all of a wedge from 64 on; `wedge_pct` stays a share of each wedge
 * whatever the count; a profile giving both is refused on one line naming both. */
static void test_a_wedge_placement_in_degrees_follows_the_sector_count(void **state) {
    (void)state;
    char err[QNAV_SIM_ERRLEN] = "";
    const std::string t = read_data("robots/tekbot.toml");
    const std::size_t at = t.find("wedge_deg = 5.625");
    assert_true(at != std::string::npos);
    static const struct {
        std::uint16_t n;
        std::uint8_t pct;
    } want[] = {{0, 25}, {16, 25}, {8, 13}, {12, 19}, {32, 50}, {64, 100}, {180, 100}, {1, 2}};
    qnav_sim_robot_t *robot = nullptr;
    qnav_ctrl_config_t cfg;
    assert_int_equal(qnav_sim_robot_parse(t.data(), t.size(), "d.toml", &robot, err, sizeof err), QNAV_SIM_OK);
    for (const auto &w : want) {
        qnav_sim_robot_ctrl_config(robot, w.n, &cfg);
        assert_int_equal(cfg.wedge_pct, w.pct);
    }
    qnav_sim_robot_free(robot);
    std::string pct = t;
    pct.replace(at, 17, "wedge_pct = 25   ");
    assert_int_equal(qnav_sim_robot_parse(pct.data(), pct.size(), "p.toml", &robot, err, sizeof err), QNAV_SIM_OK);
    for (std::uint16_t n : {8, 16, 32}) {
        qnav_sim_robot_ctrl_config(robot, n, &cfg);
        assert_int_equal(cfg.wedge_pct, 25);
    }
    qnav_sim_robot_free(robot);
    std::string both = t;
    both.insert(at, "wedge_pct = 25\n");
    std::string msg;
    assert_int_equal(parse_robot(both, &msg), QNAV_SIM_E_PARSE);
    assert_true(msg.find("'wedge_deg' and 'wedge_pct'") != std::string::npos);
    assert_true(one_line(msg));
}

/* The quality commanded at v_max is the profile's (both robots: the paper's 0.9), not a
 * default of libqnav's: a copy of the TekBot's profile with another value gives it. The
 * probabilistic policy's own value ([probabilistic] full_speed_quality: the TekBot's 0.7,
 * the Pioneer's 0.8) reaches libqnav as quality_full_speed, 0 when absent; a value
 * outside (0, 1] is refused on one line naming the key. */
static void test_profile_sets_the_speed_at_full_quality(void **state) {
    (void)state;
    char err[QNAV_SIM_ERRLEN] = "";
    static const struct {
        const char *robot;
        qnav_q1_15_t q;
        qnav_q1_15_t prob_q;
    } want[] = {{"tekbot", 29491, 22938}, {"pioneer3dx", 29491, 26214}};
    for (const auto &w : want) {
        qnav_sim_robot_t *robot = nullptr;
        qnav_ctrl_config_t cfg;
        assert_int_equal(qnav_sim_robot_load(w.robot, &robot, err, sizeof err), QNAV_SIM_OK);
        qnav_sim_robot_ctrl_config(robot, 0, &cfg);
        assert_int_equal(cfg.full_speed_quality, w.q);
        assert_int_equal(cfg.quality_full_speed, w.prob_q);
        qnav_sim_robot_free(robot);
    }
    {
        std::string u = read_data("robots/tekbot.toml");
        const std::size_t at = u.find("full_speed_quality = 0.7");
        assert_true(at != std::string::npos);
        std::string bad = u;
        bad.replace(at, 24, "full_speed_quality = 1.5");
        std::string msg;
        assert_int_equal(parse_robot(bad, &msg), QNAV_SIM_E_PARSE);
        assert_true(msg.find("full_speed_quality") != std::string::npos);
        assert_true(one_line(msg));
        u.erase(at, u.find('\n', at) - at + 1);
        qnav_sim_robot_t *robot = nullptr;
        qnav_ctrl_config_t cfg;
        assert_int_equal(qnav_sim_robot_parse(u.data(), u.size(), "p.toml", &robot, err, sizeof err), QNAV_SIM_OK);
        qnav_sim_robot_ctrl_config(robot, 0, &cfg);
        assert_int_equal(cfg.quality_full_speed, 0);
        qnav_sim_robot_free(robot);
    }
    std::string t = read_data("robots/tekbot.toml");
    t.replace(t.find("full_speed_quality = 0.9"), 24, "full_speed_quality = 0.5");
    qnav_sim_robot_t *robot = nullptr;
    qnav_ctrl_config_t cfg;
    assert_int_equal(qnav_sim_robot_parse(t.data(), t.size(), "fsq.toml", &robot, err, sizeof err),
                     QNAV_SIM_OK);
    qnav_sim_robot_ctrl_config(robot, 0, &cfg);
    assert_int_equal(cfg.full_speed_quality, 16384);
    qnav_sim_robot_free(robot);
}

static void test_profile_carries_its_tuned_probabilistic_policy(void **state) {
    (void)state;
    char err[QNAV_SIM_ERRLEN] = "";
    qnav_sim_robot_t *robot = nullptr;
    qnav_policy_t p;
    assert_int_equal(qnav_sim_robot_load("tekbot", &robot, err, sizeof err), QNAV_SIM_OK);
    qnav_sim_robot_prob_policy(robot, &p);
    assert_int_equal(p.kind, QNAV_POLICY_PROB);
    assert_int_equal(p.u.prob.k_goal, 256);
    assert_int_equal(p.u.prob.k_safe, 1024);
    qnav_sim_robot_free(robot);
    /* no robot: libqnav's defaults */
    qnav_policy_t d;
    qnav_policy_prob_default(&d);
    qnav_sim_robot_prob_policy(nullptr, &p);
    assert_int_equal(p.u.prob.k_safe, d.u.prob.k_safe);
}

/* P_safe's scale is in metres (safe_m): a sonar of twice the range doubles the paper's
 * k_safe, so a reading 1 m away is as safe as before, and a shorter one keeps k_safe 4 at
 * least; a profile giving the paper's k_safe keeps it whatever the range
 * (docs/architecture.md, "The safety scale in metres"). */
static qnav_q8_8_t profile_k_safe(const std::string &text) {
    char err[QNAV_SIM_ERRLEN] = "";
    qnav_sim_robot_t *robot = nullptr;
    qnav_policy_t p;
    assert_int_equal(qnav_sim_robot_parse(text.data(), text.size(), "ks.toml", &robot, err, sizeof err),
                     QNAV_SIM_OK);
    qnav_sim_robot_prob_policy(robot, &p);
    qnav_sim_robot_free(robot);
    return p.u.prob.k_safe;
}

static void test_the_safety_scale_follows_the_sonar_range(void **state) {
    (void)state;
    std::string t = read_data("robots/tekbot.toml");
    assert_int_equal(profile_k_safe(t), 1024);  // 2.5 m / 0.625 m = 4
    std::string shorter = t;
    t.replace(t.find("range_max_m = 2.5"), 17, "range_max_m = 5.0");
    assert_int_equal(profile_k_safe(t), 2048);
    /* a 1.5 m sonar: 2.4 by the metres, but a path open to the range stays safe (k >= 4) */
    shorter.replace(shorter.find("range_max_m = 2.5"), 17, "range_max_m = 1.5");
    assert_int_equal(profile_k_safe(shorter), 1024);
    std::string paper = t;
    paper.replace(paper.find("\nsafe_m = 0.625") + 1, 14, "k_safe = 4.0");
    assert_int_equal(profile_k_safe(paper), 1024);
    std::string p = read_data("robots/pioneer3dx.toml");
    assert_int_equal(profile_k_safe(p), 1280);  // 5 m / 1 m = 5
}

static void test_missing_file_is_an_io_error_naming_it(void **state) {
    (void)state;
    char err[QNAV_SIM_ERRLEN] = "";
    qnav_sim_env_t *env = nullptr;
    assert_int_equal(qnav_sim_env_load("/nonexistent/x.toml", &env, err, sizeof err), QNAV_SIM_E_IO);
    assert_null(env);
    assert_string_equal(err, "/nonexistent/x.toml: cannot open (No such file or directory)");
}

static void test_impossible_parameters_are_refused_by_field(void **state) {
    (void)state;
    TestSim t;
    make_test_sim(t, "pioneer3dx", test_env_text(""), nullptr, 16, 0, 0);
    char err[QNAV_SIM_ERRLEN] = "";
    qnav_sim_config_t cfg;
    qnav_sim_t *sim = nullptr;
    qnav_sim_config_default(&cfg);
    cfg.n_sectors = 361;
    assert_int_equal(qnav_sim_create(t.robot, t.env, &cfg, &sim, err, sizeof err), QNAV_SIM_E_PARAM);
    assert_true(starts_with(err, "n_sectors:"));
    qnav_sim_config_default(&cfg);
    cfg.sensor_noise = -0.1;
    assert_int_equal(qnav_sim_create(t.robot, t.env, &cfg, &sim, err, sizeof err), QNAV_SIM_E_PARAM);
    assert_true(starts_with(err, "sensor_noise:"));
    qnav_sim_config_default(&cfg);
    cfg.actuation_noise = NAN;
    assert_int_equal(qnav_sim_create(t.robot, t.env, &cfg, &sim, err, sizeof err), QNAV_SIM_E_PARAM);
    assert_true(starts_with(err, "actuation_noise:"));
    assert_null(sim);
    // A start zone that a small robot fits but the Pioneer does not.
    qnav_sim_env_t *tight = nullptr;
    const std::string text = test_env_text("[[circle]]\nx_m = 1.25\ny_m = 1.3\nr_m = 0.2\n");
    assert_int_equal(qnav_sim_env_parse(text.data(), text.size(), "tight.toml", &tight, err, sizeof err), QNAV_SIM_OK);
    qnav_sim_config_default(&cfg);
    assert_int_equal(qnav_sim_create(t.robot, tight, &cfg, &sim, err, sizeof err), QNAV_SIM_E_WORLD);
    assert_true(starts_with(err, "tight.toml:10: start zone is closer than the robot radius"));
    qnav_sim_env_free(tight);
}

static void test_mismatched_controller_is_refused(void **state) {
    (void)state;
    TestSim t;
    make_test_sim(t, "pioneer3dx", test_env_text(""), nullptr, 16, 0, 0);
    qnav_policy_t pol;
    qnav_policy_prob_default(&pol);
    qnav_ctrl_config_t cc;
    qnav_ctrl_config_default(&cc);
    cc.n_sectors = 8;
    cc.max_range_mm = 5000;
    qnav_ctrl_t ctrl;
    assert_int_equal(qnav_ctrl_init(&ctrl, &cc, &pol), QNAV_OK);
    qnav_sim_result_t r;
    assert_int_equal(qnav_sim_run_episode(t.sim, &ctrl, 0, &r, NULL, NULL), QNAV_SIM_E_PARAM);
    assert_string_equal(qnav_sim_last_error(t.sim),
                        "controller: n_sectors 8 does not match the simulation's 16");
    assert_int_equal(qnav_sim_place(t.sim, 11.0, 5.0, 0.0), QNAV_SIM_E_PARAM);
    assert_string_equal(qnav_sim_last_error(t.sim), "place: pose outside the arena");
}

static void test_generator_is_seeded_connected_and_writes_what_it_reads(void **state) {
    (void)state;
    const qnav::Environment a = qnav::generate_environment(0.2, 5, 0.26);
    const qnav::Environment b = qnav::generate_environment(0.2, 5, 0.26);
    const qnav::Environment c = qnav::generate_environment(0.2, 6, 0.26);
    const std::string ta = qnav::environment_to_toml(a);
    assert_true(ta == qnav::environment_to_toml(b));
    assert_true(ta != qnav::environment_to_toml(c));
    assert_true(a.circles.size() + a.boxes.size() >= 5);
    assert_true(qnav::environment_connected(a, 0.26));
    const qnav::Environment back = qnav::parse_environment(ta, "gen.toml");
    assert_int_equal(back.circles.size(), a.circles.size());
    assert_int_equal(back.boxes.size(), a.boxes.size());
    // A wall of boxes across the arena is not connected.
    qnav::Environment blocked = a;
    blocked.circles.clear();
    blocked.boxes = {{5.0, 5.0, 10.0, 0.5, 0.0}};
    assert_false(qnav::environment_connected(blocked, 0.26));
}

// Run qnav-sim with args; returns its exit status and its stderr+stdout.
static int run_tool(const std::string &args, std::string *out) {
    const std::string cmd = std::string(QNAV_SIM_TOOL) + " " + args + " 2>&1";
    FILE *p = popen(cmd.c_str(), "r");
    assert_non_null(p);
    char buf[1024];
    out->clear();
    while (fgets(buf, sizeof buf, p)) out->append(buf);
    const int st = pclose(p);
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

static void test_cli_prints_one_line_and_fails_on_bad_input(void **state) {
    (void)state;
    std::string out;
    assert_int_equal(run_tool("run --env /nonexistent/env.toml", &out), 2); /* bad input */
    assert_string_equal(out.c_str(), "/nonexistent/env.toml: cannot open (No such file or directory)\n");
    assert_int_not_equal(run_tool("run --sectors 400", &out), 0);
    assert_true(one_line(out.substr(0, out.size() - 1)));
    assert_true(out.find("--sectors") != std::string::npos);
    assert_int_not_equal(run_tool("run --sensor-noise -1", &out), 0);
    assert_int_not_equal(run_tool(std::string("run --robot ") + QNAV_TEST_DATA_DIR + "/robots/tekbot.toml --env " +
                                      QNAV_TEST_DATA_DIR + "/envs/open.toml --fitness survival",
                                  &out),
                         0);
    assert_string_equal(out.c_str(), "--fitness: 'survival' is not one of progress, paper\n");
    assert_int_not_equal(run_tool("gen-env --density 0.9 --out /tmp/never.toml", &out), 0);
    /* an output that cannot be written is a failure at run time: 1 */
    assert_int_equal(run_tool("draw-env --env " + std::string(QNAV_TEST_DATA_DIR) + "/envs/open.toml --out /nonexistent/x.svg", &out), 1);
    assert_string_equal(out.c_str(), "qnav-sim: /nonexistent/x.svg: cannot write (No such file or directory)\n");
    assert_int_not_equal(access("/tmp/never.toml", F_OK), 0);
}

static void test_cli_runs_an_episode_and_writes_a_complete_picture(void **state) {
    (void)state;
    char dir[] = "/tmp/qnav_sim_test_XXXXXX";
    assert_non_null(mkdtemp(dir));
    const std::string svg = std::string(dir) + "/ep.svg", envf = std::string(dir) + "/gen.toml";
    std::string out;
    const std::string data = std::string("--robot ") + QNAV_TEST_DATA_DIR + "/robots/tekbot.toml --env " +
                             QNAV_TEST_DATA_DIR + "/envs/dense.toml";
    assert_int_equal(run_tool("run " + data + " --sectors 16 --sensor-noise 0 --actuation-noise 0 --svg " + svg + " --svg-tick 5", &out), 0);
    assert_true(out.find("episode 0:") != std::string::npos);
    assert_true(out.find(" R ") != std::string::npos);
    const std::string text = read_text_file(svg);
    assert_true(starts_with(text, "<?xml"));
    assert_true(text.find("</svg>") != std::string::npos);
    assert_true(text.find("<polyline") != std::string::npos);  // the path
    assert_int_equal(run_tool("gen-env --density 0.15 --seed 3 --robot " + std::string(QNAV_TEST_DATA_DIR) +
                              "/robots/pioneer3dx.toml --out " + envf, &out), 0);
    char err[QNAV_SIM_ERRLEN];
    qnav_sim_env_t *env = nullptr;
    assert_int_equal(qnav_sim_env_load(envf.c_str(), &env, err, sizeof err), QNAV_SIM_OK);
    qnav_sim_env_info_t info;
    qnav_sim_env_info(env, &info);
    assert_true(info.n_obstacles >= 5);
    qnav_sim_env_free(env);
    std::remove(svg.c_str());
    std::remove(envf.c_str());
    rmdir(dir);
}

// The first map cell drawn in picture text: its first edge's length and direction in the
// picture (pixels; degrees, the picture's y downward).
static void first_cell_edge(const std::string &svg_text, double *len, double *deg) {
    const std::string tag = "<polygon points=\"";
    const std::size_t at = svg_text.find(tag, svg_text.find("fill=\"#d62728\" fill-opacity=\"0.35\""));
    assert_true(at != std::string::npos);
    double x0, y0, x1, y1;
    assert_int_equal(std::sscanf(svg_text.c_str() + at + tag.size(), "%lf,%lf %lf,%lf", &x0, &y0, &x1, &y1), 4);
    *len = std::hypot(x1 - x0, y1 - y0);
    *deg = std::atan2(y1 - y0, x1 - x0) * 180.0 / std::acos(-1.0);
}

// With a profile's [map], the picture also draws the map's occupied cells at its tick (one
// translucent red square each, turned as the map's grid is against the arena: --map-frame);
// without one, none.
static void test_the_picture_draws_the_maps_cells(void **state) {
    (void)state;
    char dir[] = "/tmp/qnav_sim_test_XXXXXX";
    assert_non_null(mkdtemp(dir));
    const std::string svg = std::string(dir) + "/ep.svg", robot = std::string(dir) + "/tekbot-map.toml";
    const std::string profile = read_text_file(std::string(QNAV_TEST_DATA_DIR) + "/robots/tekbot.toml");
    const std::size_t off = profile.find("\n[map]");  // the profile's own [map] (off, last) replaced
    assert_true(off != std::string::npos);
    std::FILE *f = std::fopen(robot.c_str(), "w");
    assert_non_null(f);
    std::fputs((profile.substr(0, off + 1) + "\n[map]\ncell_m = 0.1\n").c_str(), f);
    std::fclose(f);
    const std::string rest = " --env " + std::string(QNAV_TEST_DATA_DIR) +
                             "/envs/dense.toml --sectors 16 --sensor-noise 0 --actuation-noise 0 --svg " + svg +
                             " --svg-tick 40";
    std::string out;
    double len = 0, deg = 0;
    assert_int_equal(run_tool("run --robot " + robot + rest + " --map-frame 0", &out), 0);
    first_cell_edge(read_text_file(svg), &len, &deg);
    assert_true(std::fabs(len - 6.0) < 0.05 && std::fabs(deg) < 0.5);  // 0.1 m at 60 px/m, along x
    assert_int_equal(run_tool("run --robot " + robot + rest + " --map-frame 30", &out), 0);
    first_cell_edge(read_text_file(svg), &len, &deg);
    assert_true(std::fabs(len - 6.0) < 0.05 && std::fabs(deg - 30.0) < 0.5);  // turned back: -30 deg, y down
    assert_int_equal(run_tool("run --robot " + robot + rest, &out), 0);  // a turn drawn per episode
    first_cell_edge(read_text_file(svg), &len, &deg);
    assert_true(std::fabs(len - 6.0) < 0.05);
    // ... and per world: episode 0 of another world, another turn
    double other = 0;
    std::string in_cluttered = rest;
    in_cluttered.replace(in_cluttered.find("dense.toml"), 10, "cluttered.toml");
    assert_int_equal(run_tool("run --robot " + robot + in_cluttered, &out), 0);
    first_cell_edge(read_text_file(svg), &len, &other);
    assert_true(std::fabs(std::fmod(deg - other + 360.0, 90.0)) > 0.5);
    assert_int_equal(run_tool("run --robot tekbot-map" + rest, &out), 0);
    assert_true(read_text_file(svg).find("#d62728") == std::string::npos);
    std::remove(svg.c_str());
    std::remove(robot.c_str());
    rmdir(dir);
}

static void test_obstacle_wholly_outside_the_arena_is_refused(void **state) {
    (void)state;
    std::string msg;
    assert_int_equal(parse_env(test_env_text("[[circle]]\nx_m = 15\ny_m = 5\nr_m = 1\n"), &msg), QNAV_SIM_E_WORLD);
    assert_string_equal(msg.c_str(), "bad.toml:15: obstacle lies wholly outside the arena");
    assert_int_equal(parse_env(test_env_text("[[box]]\nx_m = 5\ny_m = -3\nw_m = 2\nh_m = 2\n"), &msg), QNAV_SIM_E_WORLD);
    assert_string_equal(msg.c_str(), "bad.toml:15: obstacle lies wholly outside the arena");
    // half in, half out is a legitimate obstacle against the wall
    assert_int_equal(parse_env(test_env_text("[[circle]]\nx_m = 10\ny_m = 5\nr_m = 1\n"), &msg), QNAV_SIM_OK);
}

static void test_obstacle_overlapping_the_destination_is_refused(void **state) {
    (void)state;
    std::string msg;
    // the destination (9, 9) is outside the circle, but its 0.3 m disc overlaps it
    assert_int_equal(parse_env(test_env_text("[[circle]]\nx_m = 9\ny_m = 8.2\nr_m = 0.6\n"), &msg), QNAV_SIM_E_WORLD);
    assert_string_equal(msg.c_str(), "bad.toml:15: obstacle overlaps the destination (bad.toml:6)");
    assert_int_equal(parse_env(test_env_text("[[circle]]\nx_m = 9\ny_m = 7.9\nr_m = 0.6\n"), &msg), QNAV_SIM_OK);
}

static void test_walled_in_start_zone_is_refused_when_the_world_is_made(void **state) {
    (void)state;
    char err[QNAV_SIM_ERRLEN] = "";
    qnav_sim_env_t *env = nullptr;
    qnav_sim_robot_t *robot = nullptr;
    qnav_sim_t *sim = nullptr;
    qnav_sim_config_t cfg;
    // a wall of boxes across the arena between the start zone and the destination
    const std::string text = test_env_text("[[box]]\nx_m = 5\ny_m = 4\nw_m = 10\nh_m = 0.5\n");
    assert_int_equal(qnav_sim_env_parse(text.data(), text.size(), "walled.toml", &env, err, sizeof err), QNAV_SIM_OK);
    assert_int_equal(qnav_sim_robot_load((std::string(QNAV_TEST_DATA_DIR) + "/robots/tekbot.toml").c_str(), &robot, err, sizeof err), QNAV_SIM_OK);
    qnav_sim_config_default(&cfg);
    assert_int_equal(qnav_sim_create(robot, env, &cfg, &sim, err, sizeof err), QNAV_SIM_E_WORLD);
    assert_null(sim);
    assert_string_equal(err, "walled.toml:10: start zone is walled in: no path to the destination for a robot of radius 0.120 m");
    qnav_sim_env_free(env);
    qnav_sim_robot_free(robot);
}

static void test_directory_and_unreadable_files_say_why(void **state) {
    (void)state;
    char dir[] = "/tmp/qnav_sim_dir_XXXXXX";
    assert_non_null(mkdtemp(dir));
    char err[QNAV_SIM_ERRLEN] = "";
    qnav_sim_env_t *env = nullptr;
    qnav_sim_robot_t *robot = nullptr;
    assert_int_equal(qnav_sim_env_load(dir, &env, err, sizeof err), QNAV_SIM_E_IO);
    assert_string_equal(err, (std::string(dir) + ": is a directory, not a file").c_str());
    assert_int_equal(qnav_sim_robot_load(dir, &robot, err, sizeof err), QNAV_SIM_E_IO);
    assert_string_equal(err, (std::string(dir) + ": is a directory, not a file").c_str());
    const std::string locked = std::string(dir) + "/locked.toml";
    FILE *f = fopen(locked.c_str(), "w");
    assert_non_null(f);
    fputs("name = \"x\"\n", f);
    fclose(f);
    chmod(locked.c_str(), 0);
    if (access(locked.c_str(), R_OK) == 0) {
        print_message("(running as root: the unreadable-file half cannot be shown here)\n");
    } else {
        assert_int_equal(qnav_sim_env_load(locked.c_str(), &env, err, sizeof err), QNAV_SIM_E_IO);
        assert_string_equal(err, (locked + ": cannot open (Permission denied)").c_str());
    }
    // a reason root sees too: a symlink that points at itself
    const std::string loop = std::string(dir) + "/loop.toml";
    assert_int_equal(symlink(loop.c_str(), loop.c_str()), 0);
    assert_int_equal(qnav_sim_env_load(loop.c_str(), &env, err, sizeof err), QNAV_SIM_E_IO);
    assert_string_equal(err, (loop + ": cannot open (Too many levels of symbolic links)").c_str());
    std::remove(loop.c_str());
    std::remove(locked.c_str());
    rmdir(dir);
}

static void test_messages_quoting_newlines_stay_one_line(void **state) {
    (void)state;
    std::string msg;
    // a quoted key holding an escaped newline: the key is quoted back in the message
    assert_int_equal(parse_env("name = \"x\"\n\"long\\nname\" = 3\n", &msg), QNAV_SIM_E_PARSE);
    assert_string_equal(msg.c_str(), "bad.toml:2: unknown key 'long\\nname'");
    // toml++'s own description of a control character in a string
    assert_int_equal(parse_env("name = \"a\x01b\"\n", &msg), QNAV_SIM_E_PARSE);
    assert_true(starts_with(msg, "bad.toml:1: "));
    assert_true(one_line(msg));
    for (char c : msg) assert_true(static_cast<unsigned char>(c) >= 0x20);
}

static void test_cli_refuses_nan_noise_instead_of_using_the_profiles(void **state) {
    (void)state;
    std::string out;
    assert_int_equal(run_tool("run --sensor-noise nan", &out), 2);
    assert_true(one_line(out.substr(0, out.size() - 1)));
    assert_true(out.find("--sensor-noise") != std::string::npos);
    assert_true(out.find("expected a number in [0, 1], got 'nan'") != std::string::npos);
    assert_int_equal(run_tool("run --actuation-noise nan", &out), 2);
    assert_true(out.find("--actuation-noise") != std::string::npos);
    assert_int_equal(run_tool("run --actuation-noise inf", &out), 2);
    assert_int_equal(run_tool("bench --sensor-noise nan", &out), 2);
}

static void test_cli_names_unknown_options_and_subcommands_and_prints_its_version(void **state) {
    (void)state;
    std::string out;
    assert_int_equal(run_tool("--bogus", &out), 2);
    assert_string_equal(out.c_str(), "qnav-sim: --bogus: unknown option (see qnav-sim --help)\n");
    assert_int_equal(run_tool("bogus", &out), 2);
    assert_string_equal(out.c_str(), "qnav-sim: bogus: unknown subcommand (known: run, draw-env, gen-env, bench, robot-header) "
                                     "(see qnav-sim --help)\n");
    assert_int_equal(run_tool("--version", &out), 0);
    assert_string_equal(out.c_str(), "qnav-sim (qnav) " QNAV_VERSION "\n");
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_committed_profiles_and_environments_load),
        cmocka_unit_test(test_toml_syntax_error_names_file_and_line),
        cmocka_unit_test(test_missing_table_and_bad_values_name_their_line),
        cmocka_unit_test(test_start_zone_inside_an_obstacle_is_refused_with_its_line),
        cmocka_unit_test(test_bad_robot_profiles_are_refused),
        cmocka_unit_test(test_profile_carries_its_tuned_probabilistic_policy),
        cmocka_unit_test(test_the_safety_scale_follows_the_sonar_range),
        cmocka_unit_test(test_profile_sets_the_speed_at_full_quality),
        cmocka_unit_test(test_whole_wedges_within_the_stopping_distance),
        cmocka_unit_test(test_a_wedge_placement_in_degrees_follows_the_sector_count),
        cmocka_unit_test(test_missing_file_is_an_io_error_naming_it),
        cmocka_unit_test(test_impossible_parameters_are_refused_by_field),
        cmocka_unit_test(test_mismatched_controller_is_refused),
        cmocka_unit_test(test_generator_is_seeded_connected_and_writes_what_it_reads),
        cmocka_unit_test(test_cli_prints_one_line_and_fails_on_bad_input),
        cmocka_unit_test(test_cli_runs_an_episode_and_writes_a_complete_picture),
        cmocka_unit_test(test_the_picture_draws_the_maps_cells),
        cmocka_unit_test(test_obstacle_wholly_outside_the_arena_is_refused),
        cmocka_unit_test(test_obstacle_overlapping_the_destination_is_refused),
        cmocka_unit_test(test_walled_in_start_zone_is_refused_when_the_world_is_made),
        cmocka_unit_test(test_directory_and_unreadable_files_say_why),
        cmocka_unit_test(test_messages_quoting_newlines_stay_one_line),
        cmocka_unit_test(test_cli_refuses_nan_noise_instead_of_using_the_profiles),
        cmocka_unit_test(test_cli_names_unknown_options_and_subcommands_and_prints_its_version),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
