/*
 * Sensing: a known obstacle at a known bearing appears in the right sector with the right
 * range (robot frame counter-clockwise, ranges from the body surface, clipped to the
 * profile's [min, max]); the destination bearing; and the analytic sonar against a
 * brute-force fan of fine rays at random poses in the dense environment; the broad phase
 * (per-cell lists, nearest first, stopped and culled by the readings) reads bit-identical
 * to testing every shape, in generated worlds of 54 to 309 obstacles, and lists every
 * shape near the robot for its contact test.
 */
#include "sim_test_util.hpp"

#include <cmath>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include "env.hpp"
#include "geometry.hpp"
#include "qnav/rng.hpp"
#include "sonar.hpp"
#include "worldgen.hpp"

static const double kPiD = 3.14159265358979323846;

// Circle of radius 0.3 m whose centre is 2 m from (5, 5) at world angle 45 deg.
static std::string env_with_circle_at_45() {
    char buf[128];
    std::snprintf(buf, sizeof buf, "[[circle]]\nx_m = %.9f\ny_m = %.9f\nr_m = 0.3\n",
                  5.0 + 2.0 * std::cos(kPiD / 4), 5.0 + 2.0 * std::sin(kPiD / 4));
    return test_env_text(buf);
}

static void test_obstacle_at_45_deg_appears_in_sector_2_of_16_at_surface_range(void **state) {
    (void)state;
    TestSim t;
    make_test_sim(t, "pioneer3dx", env_with_circle_at_45(), nullptr, 16, 0, 0);
    assert_int_equal(qnav_sim_reset(t.sim, 1), QNAV_SIM_OK);
    assert_int_equal(qnav_sim_place(t.sim, 5.0, 5.0, 0.0), QNAV_SIM_OK);
    qnav_sim_scan_t s;
    assert_int_equal(qnav_sim_scan(t.sim, &s), QNAV_SIM_OK);
    assert_int_equal(s.n_sectors, 16);
    assert_int_equal(s.max_range_mm, 5000);
    // 2.0 m to the centre - 0.3 m obstacle radius - 0.26 m robot radius.
    assert_int_equal(s.ranges_mm[2], 1440);
    // Neighbours see the walls, not the circle (it spans 45 +- 8.6 deg, inside 33.75..56.25).
    assert_true(s.ranges_mm[1] > 4000);
    assert_true(s.ranges_mm[3] > 4000);
    // Sector 0 faces the wall x = 10 square on: 5 m - 0.26 m.
    assert_int_equal(s.ranges_mm[0], 4740);
    // Sector 4 faces y = 10: same.
    assert_int_equal(s.ranges_mm[4], 4740);
}

static void test_sector_without_perpendicular_foot_reads_its_nearest_edge_ray(void **state) {
    (void)state;
    TestSim t;
    make_test_sim(t, "pioneer3dx", test_env_text(""), nullptr, 16, 0, 0);
    assert_int_equal(qnav_sim_reset(t.sim, 1), QNAV_SIM_OK);
    assert_int_equal(qnav_sim_place(t.sim, 5.0, 5.0, 0.0), QNAV_SIM_OK);
    qnav_sim_scan_t s;
    qnav_sim_scan(t.sim, &s);
    // Sector 1 spans 11.25..33.75 deg: its nearest wall point lies on the 11.25 deg edge.
    const double expect = 5.0 / std::cos(11.25 * kPiD / 180.0) - 0.26;
    assert_int_equal(s.ranges_mm[1], (int)std::lround(expect * 1000.0));
    assert_int_equal(s.ranges_mm[15], (int)std::lround(expect * 1000.0));
}

static void test_turned_robot_sees_the_obstacle_clockwise_of_ahead(void **state) {
    (void)state;
    TestSim t;
    make_test_sim(t, "pioneer3dx", env_with_circle_at_45(), nullptr, 16, 0, 0);
    assert_int_equal(qnav_sim_reset(t.sim, 1), QNAV_SIM_OK);
    // facing +y: obstacle at -45 deg
    assert_int_equal(qnav_sim_place(t.sim, 5.0, 5.0, kPiD / 2), QNAV_SIM_OK);
    qnav_sim_scan_t s;
    qnav_sim_scan(t.sim, &s);
    assert_int_equal(s.ranges_mm[14], 1440);
    assert_true(s.ranges_mm[2] > 4000);
}

static void test_ranges_clip_to_profile_min_and_max(void **state) {
    (void)state;
    TestSim t;
    make_test_sim(t, "pioneer3dx", test_env_text(""), nullptr, 4, 0, 0);
    assert_int_equal(qnav_sim_reset(t.sim, 1), QNAV_SIM_OK);
    // 0.3 m from the wall x = 10: surface gap 0.04 m, below the 0.1 m minimum.
    assert_int_equal(qnav_sim_place(t.sim, 9.7, 5.0, 0.0), QNAV_SIM_OK);
    qnav_sim_scan_t s;
    qnav_sim_scan(t.sim, &s);
    assert_int_equal(s.ranges_mm[0], 100);
    // Behind: 9.7 m to x = 0, beyond the 5 m maximum.
    assert_int_equal(s.ranges_mm[2], 5000);
}

static void test_goal_bearing_is_robot_relative_in_centidegrees(void **state) {
    (void)state;
    TestSim t;
    // the sonar's own bearing: without the map, whose plan would give its sub-goal's
    make_test_sim(t, "pioneer3dx-map", test_env_text(""), nullptr, 8, 0, 0);
    assert_int_equal(qnav_sim_reset(t.sim, 1), QNAV_SIM_OK);
    // destination (9, 9): 45 deg left
    assert_int_equal(qnav_sim_place(t.sim, 5.0, 5.0, 0.0), QNAV_SIM_OK);
    qnav_sim_scan_t s;
    qnav_sim_scan(t.sim, &s);
    assert_int_equal(s.goal_bearing_cdeg, 4500);
    assert_int_equal(qnav_sim_place(t.sim, 5.0, 5.0, kPiD / 2), QNAV_SIM_OK);
    qnav_sim_scan(t.sim, &s);
    assert_int_equal(s.goal_bearing_cdeg, -4500);
    assert_int_equal(qnav_sim_place(t.sim, 5.0, 5.0, -3.0 * kPiD / 4), QNAV_SIM_OK);  // facing away
    qnav_sim_scan(t.sim, &s);
    assert_int_equal(s.goal_bearing_cdeg, -18000);
}

static void test_one_sector_reads_the_nearest_obstacle_all_round(void **state) {
    (void)state;
    TestSim t;
    make_test_sim(t, "pioneer3dx", env_with_circle_at_45(), nullptr, 1, 0, 0);
    assert_int_equal(qnav_sim_reset(t.sim, 1), QNAV_SIM_OK);
    assert_int_equal(qnav_sim_place(t.sim, 5.0, 5.0, 1.0), QNAV_SIM_OK);
    qnav_sim_scan_t s;
    qnav_sim_scan(t.sim, &s);
    assert_int_equal(s.ranges_mm[0], 1440);
}

static void test_wide_cone_sees_the_obstacle_from_every_overlapping_sector(void **state) {
    (void)state;
    char err[QNAV_SIM_ERRLEN] = "";
    std::string text;
    {
        std::FILE *f = std::fopen(QNAV_TEST_DATA_DIR "/robots/pioneer3dx.toml", "rb");
        assert_non_null(f);
        char buf[4096];
        size_t n;
        while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) text.append(buf, n);
        std::fclose(f);
    }
    text.replace(text.find("default_sectors = 16"), 20, "default_sectors = 32");
    text.replace(text.find("cone_deg = 0"), 12, "cone_deg = 30");
    qnav_sim_robot_t *robot = nullptr;
    qnav_sim_env_t *env = nullptr;
    qnav_sim_t *sim = nullptr;
    assert_int_equal(qnav_sim_robot_parse(text.data(), text.size(), "cone.toml", &robot, err, sizeof err), QNAV_SIM_OK);
    const std::string et = env_with_circle_at_45();
    assert_int_equal(qnav_sim_env_parse(et.data(), et.size(), "e.toml", &env, err, sizeof err), QNAV_SIM_OK);
    qnav_sim_config_t cfg;
    qnav_sim_config_default(&cfg);  // 0 sectors: the profile's 32
    assert_int_equal(qnav_sim_create(robot, env, &cfg, &sim, err, sizeof err), QNAV_SIM_OK);
    assert_int_equal(qnav_sim_reset(sim, 1), QNAV_SIM_OK);
    assert_int_equal(qnav_sim_place(sim, 5.0, 5.0, 0.0), QNAV_SIM_OK);
    qnav_sim_scan_t s;
    qnav_sim_scan(sim, &s);
    assert_int_equal(s.n_sectors, 32);
    // The circle spans 36.4..53.6 deg; 30 deg cones centred every 11.25 deg reach it from
    // sectors 2 (22.5) to 6 (67.5); sector 4 (45) holds its nearest point.
    assert_int_equal(s.ranges_mm[4], 1440);
    for (int k = 2; k <= 6; ++k) assert_true(s.ranges_mm[k] >= 1440 && s.ranges_mm[k] < 2000);
    assert_true(s.ranges_mm[1] > 4000);
    assert_true(s.ranges_mm[7] > 4000);
    qnav_sim_destroy(sim);
    qnav_sim_env_free(env);
    qnav_sim_robot_free(robot);
}

static void test_box_ray_hits_and_nearest_points_match_hand_geometry(void **state) {
    (void)state;
    const qnav::Shape b = qnav::make_box(5.0, 5.0, 2.0, 1.0, 0.0);
    assert_true(std::fabs(qnav::ray_hit(b, {0.0, 5.0}, {1.0, 0.0}) - 4.0) < 1e-12);  // left face x = 4
    assert_true(std::fabs(qnav::ray_hit(b, {5.0, 0.0}, {0.0, 1.0}) - 4.5) < 1e-12);
    assert_true(qnav::ray_hit(b, {0.0, 5.0}, {-1.0, 0.0}) == qnav::kInf);
    assert_true(qnav::ray_hit(b, {0.0, 6.0}, {1.0, 0.0}) == qnav::kInf);  // passes above
    const qnav::Shape r = qnav::make_box(5.0, 5.0, 2.0, 1.0, 90.0);
    assert_true(std::fabs(qnav::ray_hit(r, {0.0, 5.0}, {1.0, 0.0}) - 4.5) < 1e-12);
    const double h = std::sqrt(0.5);
    const qnav::Shape d = qnav::make_box(0.0, 0.0, 1.0, 1.0, 45.0);  // a diamond
    assert_true(std::fabs(qnav::ray_hit(d, {3.0, 0.0}, {-1.0, 0.0}) - (3.0 - h)) < 1e-12);
    qnav::Vec2 q;
    assert_true(std::fabs(qnav::nearest_point(b, {5.0, 8.0}, &q) - 2.5) < 1e-12);
    assert_true(std::fabs(q.x - 5.0) < 1e-12 && std::fabs(q.y - 5.5) < 1e-12);
    assert_true(std::fabs(qnav::nearest_point(b, {7.0, 7.5}, &q) - std::sqrt(5.0)) < 1e-12);  // corner
    assert_true(std::fabs(qnav::nearest_point(d, {3.0, 0.0}, &q) - (3.0 - h)) < 1e-12);
    assert_true(qnav::nearest_point(b, {5.5, 5.2}, &q) == 0.0);  // inside
}

// Brute force: nearest hit over a fan of rays 0.01 deg apart inside each sector.
static void test_analytic_sonar_matches_a_fine_ray_fan_in_the_dense_environment(void **state) {
    (void)state;
    char err[QNAV_SIM_ERRLEN];
    qnav_sim_env_t *env = nullptr;
    const std::string path = std::string(QNAV_TEST_DATA_DIR) + "/envs/dense.toml";
    assert_int_equal(qnav_sim_env_load(path.c_str(), &env, err, sizeof err), QNAV_SIM_OK);
    qnav_sim_env_info_t info;
    qnav_sim_env_info(env, &info);
    // Re-read through the C++ loader to get the shapes.
    const qnav::Environment e = qnav::parse_environment(read_text_file(path), path);
    std::vector<qnav::Shape> shapes = e.obstacle_shapes();
    std::vector<qnav::Shape> all = shapes;
    for (const auto &w : e.wall_shapes()) all.push_back(w);
    qnav::Rng rng = qnav::Rng::stream(7, 7, 7);
    // (sectors, cone deg): cone 0 = 360/N; wider cones overlap.
    const struct { unsigned n; double cone_deg; } cases[] = {
        {3, 0}, {8, 0}, {16, 0}, {32, 0}, {180, 0}, {8, 60}, {32, 30}, {180, 15}};
    int compared = 0;
    for (const auto &cs : cases) {
        const unsigned n = cs.n;
        qnav::SonarRing ring(shapes, e.width_m, e.height_m, static_cast<uint16_t>(n), 100.0,
                             cs.cone_deg * kPiD / 180.0);
        const double cone = ring.cone();
        std::vector<double> dist(n);
        for (int trial = 0; trial < 4; ++trial) {
            qnav::Vec2 p;
            qnav::Vec2 q;
            bool free;
            do {
                p = {rng.uniform(0.3, 9.7), rng.uniform(0.3, 9.7)};
                free = true;
                for (const auto &s : shapes)
                    if (qnav::nearest_point(s, p, &q) < 0.3) free = false;
            } while (!free);
            const double h = rng.uniform(-kPiD, kPiD);
            ring.measure(p, h, dist.data());
            const double w = 2 * kPiD / n;
            for (unsigned k = 0; k < n; ++k) {
                double best = qnav::kInf;
                const int steps = static_cast<int>(std::ceil(cone * 180 / kPiD * 30));
                for (int i = 0; i <= steps; ++i) {
                    const double a = h + k * w - cone / 2 + cone * i / steps;
                    const qnav::Vec2 u{std::cos(a), std::sin(a)};
                    for (const auto &s : all) best = std::min(best, qnav::ray_hit(s, p, u));
                }
                // The fan can only overestimate the true minimum, and by very little.
                assert_true(dist[k] <= best + 1e-9);
                if (best - dist[k] >= 0.003)
                    print_error("n %u cone %g sector %u: analytic %.4f m, fan %.4f m\n", n,
                                cs.cone_deg, k, dist[k], best);
                assert_true(best - dist[k] < 0.003);
                ++compared;
            }
        }
    }
    assert_true(compared > 1500);  // 4 poses x (3+8+16+32+180+8+32+180) sectors
    qnav_sim_env_free(env);
}

// Generated worlds of every family that the broad phase serves (at least kBroadPhaseMin
// shapes), for both robots: 54 to 309 shapes, arenas of 7 to 20 m.
struct BroadPhaseWorld {
    std::string spec;
    double reach_m;  // range_max + offset of the profile
    qnav::Environment env;
    std::vector<qnav::Shape> shapes;
};
static std::vector<BroadPhaseWorld> broad_phase_worlds() {
    const char *specs[] = {"gen:clutter:4:1:tekbot", "gen:clutter:5:1:pioneer3dx", "gen:clutter:9:0.6:pioneer3dx",
                           "gen:clutter:7:0.5:tekbot", "gen:rooms:3:1:pioneer3dx", "gen:rooms:5:1:tekbot",
                           "gen:corridor:7:1:tekbot", "gen:pocket:7:1:tekbot", "gen:pocket:4:1:pioneer3dx"};
    std::vector<BroadPhaseWorld> out;
    for (const char *spec : specs) {
        BroadPhaseWorld w{spec, std::strstr(spec, "pioneer3dx") ? 5.26 : 2.62, qnav::load_world(spec), {}};
        w.shapes = w.env.obstacle_shapes();
        assert_true(w.shapes.size() >= qnav::SonarRing::kBroadPhaseMin);  // the broad phase runs
        out.push_back(std::move(w));
    }
    return out;
}

// A pose anywhere in (or just outside) the arena, inside obstacles too (a robot pressed
// into one), or close around a random shape, where tangents and ties are likeliest.
static qnav::Vec2 random_pose(qnav::Rng &rng, const qnav::Environment &e, const std::vector<qnav::Shape> &shapes) {
    if (rng.uniform01() < 0.5) return {rng.uniform(-0.1, e.width_m + 0.1), rng.uniform(-0.1, e.height_m + 0.1)};
    const qnav::Shape &s = shapes[static_cast<std::size_t>(rng.uniform01() * shapes.size()) % shapes.size()];
    const double a = rng.uniform(-kPiD, kPiD), d = s.r * rng.uniform(0.3, 1.6);
    return {s.c.x + d * std::cos(a), s.c.y + d * std::sin(a)};
}

static void test_broad_phase_reads_bit_identical_to_testing_every_shape(void **state) {
    (void)state;
    // Few sectors most often read the largest value, where the walk stops: many poses there.
    const struct { unsigned n; int poses; } sectors[] = {{1, 800}, {2, 300}, {3, 300}, {8, 600}, {16, 300}, {32, 200}, {180, 40}, {360, 40}};
    qnav::Rng rng = qnav::Rng::stream(19, 5, 0);
    long compared = 0, hits = 0;
    for (const BroadPhaseWorld &w : broad_phase_worlds()) {
        const qnav::Environment &e = w.env;
        const double reach = w.reach_m;
        for (const auto &[n, poses] : sectors) {
            qnav::SonarRing ring(w.shapes, e.width_m, e.height_m, static_cast<uint16_t>(n), reach);
            std::vector<double> fast(n), again(n), plain(n);
            for (int trial = 0; trial < poses; ++trial) {
                const qnav::Vec2 p = random_pose(rng, e, w.shapes);
                const double h = rng.uniform(-3 * kPiD, 3 * kPiD);
                ring.measure(p, h, fast.data());   // the cell's list made here...
                ring.measure(p, h, again.data());  // ...and kept
                ring.measure_plain(p, h, plain.data());
                if (std::memcmp(fast.data(), plain.data(), n * sizeof(double)) != 0 ||
                    std::memcmp(again.data(), plain.data(), n * sizeof(double)) != 0)
                    fail_msg("%s, %u sectors, pose (%.17g, %.17g, %.17g): broad phase differs", w.spec.c_str(), n, p.x, p.y, h);
                for (unsigned k = 0; k < n; ++k) hits += plain[k] < reach;
                compared += n;
            }
        }
    }
    assert_true(compared > 300000);
    assert_true(hits > compared / 3);  // most readings are within reach (obstacle or wall)
}

// The robot's contact test takes its shapes from the same lists: every shape whose
// bounding circle comes within d of the pose must be among them.
static void test_shapes_near_include_every_shape_within_the_distance(void **state) {
    (void)state;
    qnav::Rng rng = qnav::Rng::stream(19, 5, 1);
    long listed = 0, needed = 0;
    for (const BroadPhaseWorld &w : broad_phase_worlds()) {
        const std::vector<qnav::Shape> &shapes = w.shapes;
        const double reach = w.reach_m;
        qnav::SonarRing ring(shapes, w.env.width_m, w.env.height_m, 16, reach);
        std::vector<char> seen(shapes.size());
        for (int trial = 0; trial < 400; ++trial) {
            const qnav::Vec2 p = random_pose(rng, w.env, shapes);
            const double d = trial % 3 == 0 ? reach : rng.uniform(0.0, 1.2);
            std::fill(seen.begin(), seen.end(), 0);
            ring.for_shapes_near(p, d, [&](std::uint32_t k) {
                seen[k] = 1;
                ++listed;
            });
            for (std::size_t k = 0; k < shapes.size(); ++k) {
                const qnav::Vec2 dc = shapes[k].c - p;
                const double bound = shapes[k].r + d;
                if (qnav::dot(dc, dc) > bound * bound) continue;
                ++needed;
                if (!seen[k]) fail_msg("%s: shape %zu within %.3f m of (%.17g, %.17g) not listed", w.spec.c_str(), k, d, p.x, p.y);
            }
        }
    }
    assert_true(needed > 10000);
    assert_true(listed < 3 * needed);  // and the lists leave the far shapes out
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_obstacle_at_45_deg_appears_in_sector_2_of_16_at_surface_range),
        cmocka_unit_test(test_sector_without_perpendicular_foot_reads_its_nearest_edge_ray),
        cmocka_unit_test(test_turned_robot_sees_the_obstacle_clockwise_of_ahead),
        cmocka_unit_test(test_ranges_clip_to_profile_min_and_max),
        cmocka_unit_test(test_goal_bearing_is_robot_relative_in_centidegrees),
        cmocka_unit_test(test_one_sector_reads_the_nearest_obstacle_all_round),
        cmocka_unit_test(test_wide_cone_sees_the_obstacle_from_every_overlapping_sector),
        cmocka_unit_test(test_box_ray_hits_and_nearest_points_match_hand_geometry),
        cmocka_unit_test(test_analytic_sonar_matches_a_fine_ray_fan_in_the_dense_environment),
        cmocka_unit_test(test_broad_phase_reads_bit_identical_to_testing_every_shape),
        cmocka_unit_test(test_shapes_near_include_every_shape_within_the_distance),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
