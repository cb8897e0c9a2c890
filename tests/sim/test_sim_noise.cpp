/*
 * Noise: the generator's normal draws have the right moments and tails; sensor noise at
 * level p scales ranges by (1 + p n) and shifts the heading by p pi n (DESIGN.md §4);
 * actuation noise perturbs the motion; with both at 0 nothing random is left but the
 * start; and the streams are independent (sensor noise does not move the start).
 */
#include "sim_test_util.hpp"

#include <cmath>
#include <vector>

#include "qnav/rng.hpp"

static const double kPiD = 3.14159265358979323846;

static void test_normal_draws_have_unit_variance_and_gaussian_tails(void **state) {
    (void)state;
    qnav::Rng rng = qnav::Rng::stream(42, 0, 0);
    const int n = 200000;
    double sum = 0, sum2 = 0;
    int within1 = 0, beyond3 = 0;
    for (int i = 0; i < n; ++i) {
        const double x = rng.normal();
        sum += x;
        sum2 += x * x;
        within1 += std::fabs(x) < 1.0;
        beyond3 += std::fabs(x) > 3.0;
    }
    const double mean = sum / n, var = sum2 / n - mean * mean;
    assert_true(std::fabs(mean) < 0.01);
    assert_true(std::fabs(var - 1.0) < 0.015);
    assert_true(std::fabs(within1 / (double)n - 0.6827) < 0.005);
    assert_true(std::fabs(beyond3 / (double)n - 0.0027) < 0.0006);
}

static void test_uniform_draws_fill_the_unit_interval_evenly(void **state) {
    (void)state;
    qnav::Rng rng = qnav::Rng::stream(1, 2, 3);
    int bins[10] = {0};
    for (int i = 0; i < 100000; ++i) {
        const double u = rng.uniform01();
        assert_true(u >= 0.0 && u < 1.0);
        bins[(int)(u * 10)]++;
    }
    for (int b = 0; b < 10; ++b) assert_true(std::abs(bins[b] - 10000) < 400);
}

static void test_same_seeds_give_the_same_stream_and_different_streams_differ(void **state) {
    (void)state;
    qnav::Rng a = qnav::Rng::stream(5, 9, 1);
    qnav::Rng b = qnav::Rng::stream(5, 9, 1);
    qnav::Rng c = qnav::Rng::stream(5, 9, 2);
    int differ = 0;
    for (int i = 0; i < 100; ++i) {
        const uint64_t x = a.next_u64();
        assert_true(x == b.next_u64());
        differ += x != c.next_u64();
    }
    assert_true(differ > 95);
}

// Circle centre 2 m from (5, 5) at 45 deg, radius 0.3: sector 2 of 16 reads 1.44 m.
static std::string env_circle() {
    char buf[128];
    std::snprintf(buf, sizeof buf, "[[circle]]\nx_m = %.9f\ny_m = %.9f\nr_m = 0.3\n",
                  5.0 + 2.0 * std::cos(kPiD / 4), 5.0 + 2.0 * std::sin(kPiD / 4));
    return test_env_text(buf);
}

static void test_sensor_noise_scales_range_by_p_and_bearing_by_p_pi(void **state) {
    (void)state;
    const double p = 0.1;
    TestSim t;
    // the sonar's own bearing: without the map, whose plan would give its sub-goal's
    make_test_sim(t, "pioneer3dx-map", env_circle(), nullptr, 16, p, 0);
    assert_int_equal(qnav_sim_reset(t.sim, 3), QNAV_SIM_OK);
    const int n = 4000;
    double rs = 0, rs2 = 0, bs = 0, bs2 = 0;
    for (int i = 0; i < n; ++i) {
        // each place draws a fresh scan
        assert_int_equal(qnav_sim_place(t.sim, 5.0, 5.0, 0.0), QNAV_SIM_OK);
        qnav_sim_scan_t s;
        qnav_sim_scan(t.sim, &s);
        const double r = s.ranges_mm[2], b = s.goal_bearing_cdeg;
        rs += r;
        rs2 += r * r;
        bs += b;
        bs2 += b * b;
    }
    const double rmean = rs / n, rsd = std::sqrt(rs2 / n - rmean * rmean);
    const double bmean = bs / n, bsd = std::sqrt(bs2 / n - bmean * bmean);
    // range 1440 mm * (1 + 0.1 n): sd 144 mm
    assert_true(std::fabs(rmean - 1440.0) < 10.0);
    assert_true(std::fabs(rsd - 144.0) < 8.0);
    // bearing 45 deg + 0.1 * pi rad * n: sd 18 deg = 1800 cdeg
    assert_true(std::fabs(bmean - 4500.0) < 80.0);
    assert_true(std::fabs(bsd - 1800.0) < 80.0);
}

static void test_zero_noise_gives_identical_scans(void **state) {
    (void)state;
    TestSim t;
    make_test_sim(t, "pioneer3dx", env_circle(), nullptr, 16, 0, 0);
    assert_int_equal(qnav_sim_reset(t.sim, 3), QNAV_SIM_OK);
    assert_int_equal(qnav_sim_place(t.sim, 5.0, 5.0, 0.0), QNAV_SIM_OK);
    qnav_sim_scan_t a, b;
    qnav_sim_scan(t.sim, &a);
    assert_int_equal(qnav_sim_place(t.sim, 5.0, 5.0, 0.0), QNAV_SIM_OK);
    qnav_sim_scan(t.sim, &b);
    assert_memory_equal(a.ranges_mm, b.ranges_mm, 16 * sizeof(qnav_mm_t));
    assert_int_equal(a.goal_bearing_cdeg, b.goal_bearing_cdeg);
}

// Final pose after driving straight ahead for 20 ticks from a fixed pose.
static void drive_straight(qnav_sim_t *sim, uint64_t seed, double *y, double *heading) {
    assert_int_equal(qnav_sim_reset(sim, seed), QNAV_SIM_OK);
    assert_int_equal(qnav_sim_place(sim, 2.0, 5.0, 0.0), QNAV_SIM_OK);
    qnav_sim_command_raw(sim, 0.0, 0.6);
    for (int i = 0; i < 20; ++i) qnav_sim_advance(sim);
    qnav_sim_state_t st;
    qnav_sim_state(sim, &st);
    *y = st.y_m;
    *heading = st.heading_rad;
}

static void test_actuation_noise_spreads_the_path_and_none_keeps_it_straight(void **state) {
    (void)state;
    TestSim quiet, noisy;
    make_test_sim(quiet, "tekbot", test_env_text(""), nullptr, 8, 0, 0);
    make_test_sim(noisy, "tekbot", test_env_text(""), nullptr, 8, 0, 0.05);
    double s2 = 0;
    for (uint64_t e = 0; e < 50; ++e) {
        double y, h;
        drive_straight(quiet.sim, e, &y, &h);
        assert_true(std::fabs(y - 5.0) < 1e-9);
        assert_true(std::fabs(h) < 1e-9);
        drive_straight(noisy.sim, e, &y, &h);
        s2 += h * h;
    }
    // Heading noise 0.05 * pi rad per tick, corrected by the heading controller: the
    // final heading wanders by several degrees.
    const double sd = std::sqrt(s2 / 50);
    assert_true(sd > 0.02);
    assert_true(sd < 0.5);
}

static void test_sensor_noise_does_not_move_the_start(void **state) {
    (void)state;
    TestSim a, b;
    make_test_sim(a, "pioneer3dx", "", "dense", 16, 0, 0, 9);
    make_test_sim(b, "pioneer3dx", "", "dense", 16, 0.1, 0.1, 9);
    for (uint64_t e = 0; e < 5; ++e) {
        assert_int_equal(qnav_sim_reset(a.sim, e), QNAV_SIM_OK);
        assert_int_equal(qnav_sim_reset(b.sim, e), QNAV_SIM_OK);
        qnav_sim_result_t ra, rb;
        qnav_sim_result(a.sim, &ra);
        qnav_sim_result(b.sim, &rb);
        assert_true(ra.start_x_m == rb.start_x_m);
        assert_true(ra.start_y_m == rb.start_y_m);
        assert_true(ra.start_heading_rad == rb.start_heading_rad);
    }
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_normal_draws_have_unit_variance_and_gaussian_tails),
        cmocka_unit_test(test_uniform_draws_fill_the_unit_interval_evenly),
        cmocka_unit_test(test_same_seeds_give_the_same_stream_and_different_streams_differ),
        cmocka_unit_test(test_sensor_noise_scales_range_by_p_and_bearing_by_p_pi),
        cmocka_unit_test(test_zero_noise_gives_identical_scans),
        cmocka_unit_test(test_actuation_noise_spreads_the_path_and_none_keeps_it_straight),
        cmocka_unit_test(test_sensor_noise_does_not_move_the_start),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
