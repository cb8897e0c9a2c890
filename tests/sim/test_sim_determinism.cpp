/*
 * Determinism: a batch of noisy episodes in the dense environment, driven through the
 * step-wise API by a small fixed rule (so that changes to libqnav do not move the hash),
 * hashes its results and trajectories to the committed value; an episode's outcome
 * depends only on (context seed, episode seed), not on earlier episodes; and whole
 * episodes with a libqnav controller repeat exactly.
 *
 * When a deliberate change to the simulator changes the hash, run
 *   build/<dir>/tests/sim/test_sim_determinism --print-hash
 * and commit the printed value as kCommittedHash with a note on why it changed.
 */
#include "sim_test_util.hpp"

#include <cinttypes>
#include <thread>
#include <cmath>
#include <cstdlib>
#include <vector>

#include "qnav/ctrl.h"
#include "qnav/policy.h"

// The committed hash (Pioneer, dense, 16 sectors, p_s = p_a = 0.05, seed 2024, episodes 0-11,
// fitness rule "paper": the value predates the progress rule, and the trajectories it
// hashes do not depend on the rule). Changed when the Pioneer's acceleration limits moved
// from its wheels to its body ([drive] limits = "body", docs/sim.md "Drive model"), and
// when its heading model began to brake before a turn in place ([drive] brake_first,
// docs/sim.md "Brake, then turn").
static const uint64_t kCommittedHash = 0xae6800362de9ba55ull;

struct Fnv {
    uint64_t h = 1469598103934665603ull;
    void bytes(const void *p, size_t n) {
        const unsigned char *c = static_cast<const unsigned char *>(p);
        for (size_t i = 0; i < n; ++i) {
            h ^= c[i];
            h *= 1099511628211ull;
        }
    }
    void f64(double x) { bytes(&x, sizeof x); }
    void u32(uint32_t x) { bytes(&x, sizeof x); }
};

// Head for the destination unless the sector ahead is closer than 0.8 m; then take the
// most open sector.
static void rule_step(const qnav_sim_scan_t &s, double *heading_deg, double *speed) {
    const unsigned n = s.n_sectors;
    if (s.ranges_mm[0] < 800) {
        unsigned best = 1;
        for (unsigned k = 1; k < n; ++k)
            if (s.ranges_mm[k] > s.ranges_mm[best]) best = k;
        *heading_deg = best * 360.0 / n;
        *speed = 0.3;
    } else {
        *heading_deg = s.goal_bearing_cdeg / 100.0;
        *speed = 0.8;
    }
}

static void hash_episode(qnav_sim_t *sim, uint64_t seed, Fnv *f, qnav_sim_result_t *out) {
    assert_int_equal(qnav_sim_reset(sim, seed), QNAV_SIM_OK);
    qnav_sim_state_t st;
    qnav_sim_state(sim, &st);
    while (!st.done) {
        qnav_sim_scan_t s;
        qnav_sim_scan(sim, &s);
        double h, v;
        rule_step(s, &h, &v);
        qnav_sim_command_raw(sim, h, v);
        qnav_sim_advance(sim);
        qnav_sim_state(sim, &st);
        if (f) {
            f->f64(st.x_m);
            f->f64(st.y_m);
            f->f64(st.heading_rad);
            f->u32(st.recovering);
            f->bytes(s.ranges_mm, s.n_sectors * sizeof(qnav_mm_t));
        }
    }
    qnav_sim_result_t r;
    qnav_sim_result(sim, &r);
    if (f) {
        f->f64(r.l);
        f->f64(r.beta_l);
        f->f64(r.tau_l);
        f->f64(r.beta_tau);
        f->f64(r.R);
        f->u32(r.tau_c);
        f->u32(r.ticks);
        f->u32(r.reached);
    }
    if (out) *out = r;
}

static uint64_t batch_hash(void) {
    TestSim t;
    make_test_sim(t, "pioneer3dx-map", "", "dense", 16, 0.05, 0.05, 2024, QNAV_SIM_FITNESS_PAPER);
    Fnv f;
    for (uint64_t e = 0; e < 12; ++e) hash_episode(t.sim, e, &f, nullptr);
    return f.h;
}

static bool g_print = false;

static void test_batch_of_episodes_hashes_to_the_committed_value(void **state) {
    (void)state;
    const uint64_t h = batch_hash();
    if (g_print) std::printf("determinism hash: 0x%016" PRIx64 "ull\n", h);
    if (h != kCommittedHash)
        print_error("hash 0x%016" PRIx64 " != committed 0x%016" PRIx64
                    " (see the comment at the top of this file)\n", h, kCommittedHash);
    assert_true(h == kCommittedHash);
    assert_true(h == batch_hash());  // and again in the same process
}

static void test_contexts_in_parallel_threads_give_the_committed_hash(void **state) {
    (void)state;
    uint64_t h[2] = {0, 0};
    std::thread a([&] { h[0] = batch_hash(); });
    std::thread b([&] { h[1] = batch_hash(); });
    a.join();
    b.join();
    assert_true(h[0] == kCommittedHash);
    assert_true(h[1] == kCommittedHash);
}

static void test_episode_does_not_depend_on_earlier_episodes(void **state) {
    (void)state;
    TestSim a, b;
    make_test_sim(a, "tekbot", "", "dense", 8, 0.05, 0.05, 77);
    make_test_sim(b, "tekbot", "", "dense", 8, 0.05, 0.05, 77);
    qnav_sim_result_t ra, rb;
    hash_episode(a.sim, 1, nullptr, nullptr);
    hash_episode(a.sim, 2, nullptr, nullptr);
    hash_episode(a.sim, 3, nullptr, &ra);
    hash_episode(b.sim, 3, nullptr, &rb);
    assert_true(ra.l == rb.l);
    assert_true(ra.R == rb.R);
    assert_int_equal(ra.ticks, rb.ticks);
    // and another context seed gives another episode
    TestSim c;
    make_test_sim(c, "tekbot", "", "dense", 8, 0.05, 0.05, 78);
    qnav_sim_result_t rc;
    hash_episode(c.sim, 3, nullptr, &rc);
    assert_true(rc.start_x_m != ra.start_x_m);
}

static void collect(void *user, const qnav_sim_sample_t *s) {
    Fnv *f = static_cast<Fnv *>(user);
    f->f64(s->x_m);
    f->f64(s->y_m);
    f->u32(s->tick);
}

static void test_whole_episodes_with_libqnav_repeat_exactly_in_table_and_network_mode(void **state) {
    (void)state;
    TestSim t;
    make_test_sim(t, "pioneer3dx", "", "dense", 32, 0.05, 0.05, 5);
    qnav_policy_t pol;
    qnav_policy_net_zero(&pol, 12);
    for (uint16_t k = 0; k < QNAV_NET_WEIGHTS(12); ++k)
        *qnav_net_weight(&pol.u.net, k) = (qnav_q8_8_t)(((k * 7919) % 2048) - 1024);
    qnav_ctrl_config_t cc;
    qnav_sim_ctrl_config(t.sim, &cc);
    qnav_ctrl_t net, tab;
    assert_int_equal(qnav_ctrl_init(&net, &cc, &pol), QNAV_OK);
    std::vector<qnav_qkey_t> table(QNAV_QTABLE_ENTRIES);
    assert_int_equal(qnav_ctrl_build_table(&net, table.data()), QNAV_OK);
    assert_int_equal(qnav_ctrl_init_table(&tab, &cc, table.data(), qnav_ctrl_rank(&net)), QNAV_OK);
    for (uint64_t e = 0; e < 3; ++e) {
        Fnv f1, f2;
        qnav_sim_result_t r1, r2;
        assert_int_equal(qnav_sim_run_episode(t.sim, &net, e, &r1, collect, &f1), QNAV_SIM_OK);
        assert_int_equal(qnav_sim_run_episode(t.sim, &tab, e, &r2, collect, &f2), QNAV_SIM_OK);
        assert_true(f1.h == f2.h);
        assert_true(r1.R == r2.R);
        assert_int_equal(r1.ticks, r2.ticks);
    }
}

int main(int argc, char **argv) {
    if (argc > 1 && std::strcmp(argv[1], "--print-hash") == 0) g_print = true;
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_batch_of_episodes_hashes_to_the_committed_value),
        cmocka_unit_test(test_contexts_in_parallel_threads_give_the_committed_hash),
        cmocka_unit_test(test_episode_does_not_depend_on_earlier_episodes),
        cmocka_unit_test(test_whole_episodes_with_libqnav_repeat_exactly_in_table_and_network_mode),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
