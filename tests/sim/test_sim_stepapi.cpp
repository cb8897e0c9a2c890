/*
 * The step-wise API against whole episodes: qnav_sim_scan() writes every field of the
 * scan, and for every controller in libqnav's table (qnav_nav_count / qnav_nav_method_at,
 * so a new row is covered without editing this file), an episode driven tick by tick
 * through qnav_sim_reset / scan / command / advance equals the one qnav_sim_run_episode_nav
 * runs: every tick's pose and command, and the result.
 */
#include "sim_test_util.hpp"

#include <cmath>
#include <vector>

#include "qnav/fixed_host.h"
#include "qnav/nav.h"
#include "qnav/policy.h"

// One tick as both drivers see it: the pose after the tick and the command applied in it.
struct Tick {
    double x_m, y_m, heading_rad, speed_mps;
    int cmd_heading_deg;
    double cmd_speed;
    bool recovering;
};

static void collect(void *user, const qnav_sim_sample_t *s) {
    auto *ticks = static_cast<std::vector<Tick> *>(user);
    if (s->tick == 0) return;  // the start pose carries no command
    ticks->push_back({s->x_m, s->y_m, s->heading_rad, s->speed_mps, s->cmd_heading_deg,
                      s->cmd_speed, s->recovering});
}

// The same episode through the step API, with the controller in the caller's loop.
static qnav_sim_result_t step_episode(qnav_sim_t *sim, qnav_nav_t *nav, uint64_t seed,
                                      std::vector<Tick> *ticks) {
    assert_int_equal(qnav_sim_reset(sim, seed), QNAV_SIM_OK);
    qnav_nav_reset(nav);
    qnav_sim_state_t st;
    assert_int_equal(qnav_sim_state(sim, &st), QNAV_SIM_OK);
    qnav_ctrl_output_t out{};
    while (!st.done) {
        qnav_sim_scan_t s;
        std::memset(&s, 0xA5, sizeof s);  // a field the call leaves alone shows as garbage
        assert_int_equal(qnav_sim_scan(sim, &s), QNAV_SIM_OK);
        // the caller carries the escape memory, cleared or grown when the map says so
        const qnav_ctrl_input_t in = step_input(s, out);
        qnav_nav_step(nav, &in, &out);
        assert_int_equal(qnav_sim_command(sim, &out), QNAV_SIM_OK);
        assert_int_equal(qnav_sim_advance(sim), QNAV_SIM_OK);
        assert_int_equal(qnav_sim_state(sim, &st), QNAV_SIM_OK);
        const double speed = QNAV_Q1_15_TO_REAL(out.speed);
        ticks->push_back({st.x_m, st.y_m, st.heading_rad, st.speed_mps,
                          static_cast<int>(out.heading_deg), speed, st.recovering});
    }
    qnav_sim_result_t r;
    assert_int_equal(qnav_sim_result(sim, &r), QNAV_SIM_OK);
    return r;
}

static void assert_same_episode(const char *what, const std::vector<Tick> &a,
                                const std::vector<Tick> &b, const qnav_sim_result_t &ra,
                                const qnav_sim_result_t &rb) {
    if (a.size() != b.size()) {
        print_error("%s: %zu ticks through the step API, %zu in run_episode_nav\n", what, a.size(),
                    b.size());
        fail();
    }
    for (size_t i = 0; i < a.size(); ++i) {
        const Tick &p = a[i], &q = b[i];
        if (p.x_m != q.x_m || p.y_m != q.y_m || p.heading_rad != q.heading_rad ||
            p.speed_mps != q.speed_mps || p.cmd_heading_deg != q.cmd_heading_deg ||
            p.cmd_speed != q.cmd_speed || p.recovering != q.recovering) {
            print_error("%s: tick %zu differs: step API (%.6f, %.6f) cmd %d deg %.4f, "
                        "run_episode_nav (%.6f, %.6f) cmd %d deg %.4f\n",
                        what, i + 1, p.x_m, p.y_m, p.cmd_heading_deg, p.cmd_speed, q.x_m, q.y_m,
                        q.cmd_heading_deg, q.cmd_speed);
            fail();
        }
    }
    assert_true(ra.reached == rb.reached);
    assert_int_equal(ra.ticks, rb.ticks);
    assert_int_equal(ra.collisions, rb.collisions);
    assert_int_equal(ra.tau_c, rb.tau_c);
    assert_true(ra.l == rb.l);
    assert_true(ra.R == rb.R);
}

// The policies a controller that takes one is driven with: the profile's probabilistic
// policy, and a 3-input network (it reads prev_heading_cdeg) with fixed weights.
static std::vector<qnav_policy_t> policies(const qnav_sim_robot_t *robot) {
    std::vector<qnav_policy_t> out(2);
    qnav_sim_robot_prob_policy(robot, &out[0]);
    qnav_policy_net_zero_inputs(&out[1], 6, 3);
    const uint16_t n = qnav_net_weight_count(&out[1].u.net);
    for (uint16_t k = 0; k < n; ++k)
        *qnav_net_weight(&out[1].u.net, k) = (qnav_q8_8_t)(((k * 7919) % 2048) - 1024);
    return out;
}

static void test_scan_writes_every_field(void **state) {
    (void)state;
    TestSim t;
    make_test_sim(t, "tekbot", "", "dense", 16, 0.0, 0.0, 3);
    assert_int_equal(qnav_sim_reset(t.sim, 0), QNAV_SIM_OK);
    assert_int_equal(qnav_sim_command_raw(t.sim, 30.0, 0.5), QNAV_SIM_OK);
    assert_int_equal(qnav_sim_advance(t.sim), QNAV_SIM_OK);
    qnav_sim_scan_t a, b;
    std::memset(&a, 0x00, sizeof a);
    std::memset(&b, 0xFF, sizeof b);
    assert_int_equal(qnav_sim_scan(t.sim, &a), QNAV_SIM_OK);
    assert_int_equal(qnav_sim_scan(t.sim, &b), QNAV_SIM_OK);
    assert_int_equal(a.prev_heading_cdeg, b.prev_heading_cdeg);
    assert_memory_equal(&a, &b, sizeof a);
    // 30 deg commanded from the sensed heading, read back one tick later in the new
    // robot frame: the robot turned towards it, so it lies between 0 and 30 deg.
    assert_true(a.prev_heading_cdeg > 0 && a.prev_heading_cdeg < 3000);
}

static void test_every_controller_gives_the_same_episode_stepwise_and_whole(void **state) {
    (void)state;
    const uint8_t n_methods = qnav_nav_count();
    assert_true(n_methods >= 3);
    TestSim t;
    make_test_sim(t, "tekbot", "", "dense", 16, 0.05, 0.05, 11);
    qnav_ctrl_config_t cc;
    qnav_sim_ctrl_config(t.sim, &cc);
    const std::vector<qnav_policy_t> pols = policies(t.robot);
    unsigned compared = 0;
    for (uint8_t i = 0; i < n_methods; ++i) {
        const qnav_nav_method_t *m = qnav_nav_method_at(i);
        assert_non_null(m);
        const size_t n_pol = m->uses_policy ? pols.size() : 1;
        for (size_t p = 0; p < n_pol; ++p) {
            qnav_nav_t *nav = new qnav_nav_t;  // large with QNAV_MAX_SECTORS = 360: keep off the stack
            assert_int_equal(qnav_nav_init(nav, m, &cc, &pols[p]), QNAV_OK);
            for (uint64_t e = 0; e < 3; ++e) {
                std::vector<Tick> whole, stepped;
                qnav_sim_result_t rw, rs;
                assert_int_equal(qnav_sim_run_episode_nav(t.sim, nav, e, &rw, collect, &whole),
                                 QNAV_SIM_OK);
                rs = step_episode(t.sim, nav, e, &stepped);
                char what[96];
                std::snprintf(what, sizeof what, "controller %s, policy %zu, episode %u", m->name,
                              p, (unsigned)e);
                assert_same_episode(what, stepped, whole, rs, rw);
                ++compared;
            }
            delete nav;
        }
    }
    assert_true(compared >= 3u * n_methods);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_scan_writes_every_field),
        cmocka_unit_test(test_every_controller_gives_the_same_episode_stepwise_and_whole),
    };
    return cmocka_run_group_tests(tests, nullptr, nullptr);
}
