// Leaving a dead end in the simulator (libqnav's escape; docs/architecture.md, "Leaving
// dead ends"): a U-pocket opens toward the start and the destination lies beyond its
// bottom, so the straight way in is a local minimum for a memoryless controller. With the
// TekBot's profile the probabilistic policy leaves the pocket and arrives; with the escape
// off most episodes end circling at the bottom of the U.
#include "sim_test_util.hpp"

#include "qnav/ctrl.h"

namespace {

const char *const kPocket =
    "name = \"pocket\"\nepisode_limit_s = 60.0\n[arena]\nwidth_m = 10.0\nheight_m = 10.0\n"
    "[destination]\nx_m = 5.0\ny_m = 9.0\nradius_m = 0.4\n"
    "[[start_zone]]\nx_m = 4.0\ny_m = 0.6\nw_m = 2.0\nh_m = 1.0\n"
    "[[box]]\nx_m = 5.0\ny_m = 6.0\nw_m = 3.2\nh_m = 0.2\n"
    "[[box]]\nx_m = 3.5\ny_m = 4.75\nw_m = 0.2\nh_m = 2.5\n"
    "[[box]]\nx_m = 6.5\ny_m = 4.75\nw_m = 0.2\nh_m = 2.5\n";

// Episodes (of 20) that arrive, and the most recovery ticks of one.
unsigned arrivals(bool escape, unsigned *worst_tau_c) {
    TestSim t;
    make_test_sim(t, "tekbot-map", kPocket, nullptr, 16, 0.0, 0.0, 11);
    qnav_ctrl_config_t cfg;
    qnav_sim_ctrl_config(t.sim, &cfg);
    assert_true(cfg.escape_stall_ticks > 0);  // the profile turns it on
    if (!escape) cfg.escape_stall_ticks = 0;
    qnav_policy_t p;
    qnav_sim_robot_prob_policy(t.robot, &p);
    qnav_ctrl_t ctrl;
    assert_int_equal(qnav_ctrl_init(&ctrl, &cfg, &p), QNAV_OK);
    unsigned reached = 0;
    *worst_tau_c = 0;
    for (uint64_t e = 0; e < 20; ++e) {
        qnav_sim_result_t res;
        assert_int_equal(qnav_sim_run_episode(t.sim, &ctrl, e, &res, nullptr, nullptr), QNAV_SIM_OK);
        reached += res.reached ? 1u : 0u;
        if (res.tau_c > *worst_tau_c) *worst_tau_c = res.tau_c;
    }
    return reached;
}

void test_escape_leaves_a_u_pocket(void **) {
    unsigned tau_on = 0, tau_off = 0;
    const unsigned on = arrivals(true, &tau_on);
    const unsigned off = arrivals(false, &tau_off);
    print_message("pocket: %u/20 arrive with the escape (worst tau_c %u), %u/20 without\n", on,
                  tau_on, off);
    assert_true(on >= 19);
    assert_true(tau_on <= 10);
    assert_true(off + 6 <= on);
}

}  // namespace

int main() {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_escape_leaves_a_u_pocket),
    };
    return cmocka_run_group_tests(tests, nullptr, nullptr);
}
