/*
 * Unit tests of simevo's core without the simulator: the clipped Cauchy sampler, mutation
 * rounding and saturation, ε-greedy selection frequencies, replace-worst, transfer
 * seeding, determinism, the statistics, and experiment-file errors.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

extern "C" {
#include <cmocka.h>
}

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "evolution.h"
#include "fake_runner.h"
#include "rng.h"
#include "spec.h"
#include "stats.h"

using namespace qnav;

static void test_cauchy_samples_stay_inside_clip_and_tail_matches_theory(void **state)
{
    (void)state;
    Rng rng(42);
    const int n = 200000;
    int at_clip = 0;
    for (int i = 0; i < n; ++i) {
        const double x = rng.cauchy_clipped(1.0, 10.0);
        assert_true(x >= -10.0 && x <= 10.0);
        at_clip += (std::fabs(x) == 10.0);
    }
    // P(|X| > 10) for a standard Cauchy = 1 - (2/pi) atan(10) = 0.06345.
    const double expected = 1.0 - 2.0 / M_PI * std::atan(10.0);
    const double sd = std::sqrt(expected * (1 - expected) / n);
    assert_true(std::fabs(static_cast<double>(at_clip) / n - expected) < 5 * sd);
}

static void test_cauchy_median_is_zero_and_median_abs_is_scale(void **state)
{
    (void)state;
    Rng rng(7);
    std::vector<double> x, ax;
    for (int i = 0; i < 40001; ++i) {
        const double v = rng.cauchy_clipped(0.5, 10.0);
        x.push_back(v);
        ax.push_back(std::fabs(v));
    }
    std::nth_element(x.begin(), x.begin() + 20000, x.end());
    std::nth_element(ax.begin(), ax.begin() + 20000, ax.end());
    assert_true(std::fabs(x[20000]) < 0.02);          // median 0
    assert_true(std::fabs(ax[20000] - 0.5) < 0.02);   // median |X| = scale
}

static void test_uniform_below_is_unbiased_over_small_range(void **state)
{
    (void)state;
    Rng rng(3);
    int count[5] = {0};
    for (int i = 0; i < 50000; ++i) {
        count[rng.below(5)]++;
    }
    for (int c : count) {
        assert_true(std::abs(c - 10000) < 500); // ~5 sd
    }
}

static void test_mutation_rounds_to_q8_8_and_saturates(void **state)
{
    (void)state;
    qnav_policy_t p;
    qnav_policy_net_zero(&p, 4);
    p.u.net.w_theta[0] = QNAV_Q8_8_MAX - 10;
    p.u.net.w_dist[0] = QNAV_Q8_8_MIN + 10;
    // A huge clip-limited scale: almost every sample is +-clip = +-100 weight units.
    int saturated_hi = 0, saturated_lo = 0;
    for (uint64_t s = 0; s < 50; ++s) {
        qnav_policy_t q = p;
        Rng rng(s);
        mutate_network(q.u.net, rng, 1e6, 100.0);
        saturated_hi += q.u.net.w_theta[0] == QNAV_Q8_8_MAX;
        saturated_lo += q.u.net.w_dist[0] == QNAV_Q8_8_MIN;
        // Everything stays a valid Q8.8 value (type guarantees range); the untouched
        // units beyond hidden stay zero.
        assert_int_equal(q.u.net.w_theta[5], 0);
    }
    assert_true(saturated_hi > 15 && saturated_lo > 15);
    // Small scale: the change is the sample rounded to 1/256.
    qnav_policy_t q = p;
    Rng a(9), b(9);
    mutate_network(q.u.net, a, 0.01, 10.0);
    const double first = b.cauchy_clipped(0.01, 10.0);
    assert_int_equal(q.u.net.w_theta[0] - p.u.net.w_theta[0], static_cast<int>(std::round(first * 256.0)));
}

static EvolutionParams small_params()
{
    EvolutionParams p;
    p.population = 10;
    p.hidden = 3;
    p.epsilon = 0.25;
    p.mutation_scale = 0.3;
    return p;
}

static void test_initial_episodes_score_every_member_once_in_random_order(void **state)
{
    (void)state;
    Evolution evo(small_params(), 11);
    FakeRunner runner;
    std::vector<int> seen;
    for (int i = 0; i < 10; ++i) {
        const Candidate c = evo.propose();
        assert_int_equal(c.parent, -1);
        seen.push_back(c.slot);
        evo.accept(c, runner.run(c.policy, static_cast<uint64_t>(i)));
    }
    std::vector<int> sorted = seen;
    std::sort(sorted.begin(), sorted.end());
    for (int i = 0; i < 10; ++i) {
        assert_int_equal(sorted[static_cast<size_t>(i)], i);
    }
    assert_false(std::is_sorted(seen.begin(), seen.end()));
    for (const Member &m : evo.members()) {
        assert_true(m.evaluated);
    }
}

static void test_epsilon_greedy_picks_random_member_with_probability_epsilon(void **state)
{
    (void)state;
    EvolutionParams p = small_params();
    p.epsilon = 0.1;
    Evolution evo(p, 5);
    FakeRunner runner;
    int explored = 0, greedy_from_best = 0, steps = 0;
    for (uint64_t i = 0; i < 10000; ++i) {
        const int32_t best_before = evo.best_index();
        const Candidate c = evo.propose();
        if (c.parent >= 0) {
            ++steps;
            if (c.explored) {
                ++explored;
            } else {
                greedy_from_best += (c.parent == best_before);
            }
        }
        evo.accept(c, runner.run(c.policy, i));
    }
    assert_int_equal(greedy_from_best, steps - explored); // every greedy pick is the best
    const double f = static_cast<double>(explored) / steps;
    const double sd = std::sqrt(0.1 * 0.9 / steps);
    assert_true(std::fabs(f - 0.1) < 5 * sd);
}

static void test_mutant_replaces_the_worst_member(void **state)
{
    (void)state;
    Evolution evo(small_params(), 21);
    // Score the initial members with known fitness: member i gets R = i.
    for (int i = 0; i < 10; ++i) {
        const Candidate c = evo.propose();
        EpisodeOutcome o;
        o.R = c.slot;
        evo.accept(c, o);
    }
    assert_int_equal(evo.worst_index(), 0);
    assert_int_equal(evo.best_index(), 9);
    const Candidate c = evo.propose();
    EpisodeOutcome o;
    o.R = -5.0; // even a bad mutant replaces the worst (Fig. 4 step 5)
    evo.accept(c, o);
    assert_true(std::memcmp(&evo.members()[0].policy, &c.policy, sizeof c.policy) == 0);
    assert_true(evo.members()[0].fitness == -5.0);
    assert_int_equal(evo.worst_index(), 0);
    const Candidate d = evo.propose();
    EpisodeOutcome good;
    good.R = 100.0;
    evo.accept(d, good);
    assert_int_equal(evo.best_index(), 0);
    assert_int_equal(evo.worst_index(), 1); // fitness 1 is now the lowest
}

static void test_transfer_population_is_source_plus_mutants_first_episode_random(void **state)
{
    (void)state;
    qnav_policy_t src;
    qnav_policy_net_zero(&src, 5);
    src.u.net.w_out[2] = 300;
    src.u.net.b_out = -77;
    EvolutionParams p = small_params();
    int first_slot_zero = 0;
    for (uint64_t seed = 0; seed < 40; ++seed) {
        Evolution evo(p, seed, src);
        const auto &m = evo.members();
        assert_true(std::memcmp(&m[0].policy, &src, sizeof src) == 0);
        for (size_t i = 1; i < m.size(); ++i) {
            assert_int_equal(m[i].policy.u.net.hidden, 5); // the source's shape
            assert_false(std::memcmp(&m[i].policy, &src, sizeof src) == 0);
        }
        first_slot_zero += evo.propose().slot == 0;
    }
    assert_true(first_slot_zero < 15); // random first member, not always the source
}

static void test_same_seed_gives_identical_evolution(void **state)
{
    (void)state;
    auto trace = [](uint64_t seed) {
        Evolution evo(small_params(), seed);
        FakeRunner runner;
        std::vector<uint32_t> fps;
        for (uint64_t i = 0; i < 500; ++i) {
            const Candidate c = evo.propose();
            fps.push_back(policy_fingerprint(c.policy));
            evo.accept(c, runner.run(c.policy, mix_seed(99, i)));
        }
        return fps;
    };
    assert_true(trace(1234) == trace(1234));
    assert_false(trace(1234) == trace(1235));
}

static void test_evolution_improves_fitness_on_fake_task(void **state)
{
    (void)state;
    Evolution evo(small_params(), 77);
    FakeRunner runner;
    double first_best = 0;
    for (uint64_t i = 0; i < 3000; ++i) {
        const Candidate c = evo.propose();
        evo.accept(c, runner.run(c.policy, i));
        if (i == 9) {
            first_best = evo.members()[static_cast<size_t>(evo.best_index())].fitness;
        }
    }
    const double last = evo.members()[static_cast<size_t>(evo.best_index())].fitness;
    assert_true(last > first_best + 1.0);
}

static void test_t_critical_and_welch_match_tables(void **state)
{
    (void)state;
    assert_true(std::fabs(t_critical(29, 0.05) - 2.0452) < 1e-3);
    assert_true(std::fabs(t_critical(1e6, 0.05) - 1.95996) < 1e-3);
    assert_true(std::fabs(t_two_sided_p(2.0, 10) - 0.07339) < 1e-4);
    // Welch: a = 1..5, b = 3..7 -> t = -2, df = 8, p = 0.0805.
    const TestResult w = welch_t_test({1, 2, 3, 4, 5}, {3, 4, 5, 6, 7});
    assert_true(w.valid);
    assert_true(std::fabs(w.statistic + 2.0) < 1e-12);
    assert_true(std::fabs(w.df - 8.0) < 1e-9);
    assert_true(std::fabs(w.p - 0.080516) < 1e-4);
    const double ci = ci95_half_width({1, 2, 3, 4, 5});
    assert_true(std::fabs(ci - 2.776445 * std::sqrt(2.5) / std::sqrt(5.0)) < 1e-3);
}

static void test_mann_whitney_separated_samples_are_significant(void **state)
{
    (void)state;
    std::vector<double> a, b;
    for (int i = 0; i < 10; ++i) {
        a.push_back(i);
        b.push_back(100 + i);
    }
    const TestResult m = mann_whitney(a, b);
    assert_true(m.valid);
    // U = 0, mu = 50, sd = sqrt(10*10*21/12) = 13.229 -> z = -3.7796, p = 1.57e-4.
    assert_true(std::fabs(m.statistic + 3.7796) < 1e-3);
    assert_true(std::fabs(m.p - 1.571e-4) < 1e-5);
    const TestResult same = mann_whitney({1, 2, 3}, {1, 2, 3});
    assert_true(same.valid && std::fabs(same.p - 1.0) < 1e-12);
}

static const char *kGoodSpec = R"(name = "t"
runs = 3
[evolution]
population = 12
epsilon = 0.2
[target]
environment = "dense"
sectors = 32
episodes = 100
[[source]]
label = "open"
environment = "open"
sectors = 8
[preset.quick]
runs = 2
episodes = 10
)";

static std::string parse_error(const std::string &text)
{
    try {
        parse_experiment(text, "x.toml");
    } catch (const UserError &e) {
        return e.what();
    }
    return "";
}

static void test_spec_parses_inheritance_and_presets(void **state)
{
    (void)state;
    ExperimentSpec s = parse_experiment(kGoodSpec, "x.toml");
    assert_int_equal(s.runs, 3);
    assert_int_equal(s.evolution.population, 12);
    assert_int_equal(s.sources.size(), 1);
    assert_string_equal(s.sources[0].scenario.environment.c_str(), "open");
    assert_int_equal(s.sources[0].scenario.sectors, 8);
    assert_string_equal(s.sources[0].scenario.robot.c_str(), "tekbot"); // inherited default
    assert_int_equal(s.sources[0].episodes, 100);                      // inherits target's
    apply_preset(s, "quick");
    assert_int_equal(s.runs, 2);
    assert_int_equal(s.target_episodes, 10);
}

static void test_spec_fitness_rule_reaches_every_scenario(void **state)
{
    (void)state;
    ExperimentSpec d = parse_experiment(kGoodSpec, "x.toml");
    assert_int_equal(d.target.fitness, QNAV_SIM_FITNESS_PROGRESS); // the default
    ExperimentSpec s = parse_experiment(
        "name = \"t\"\n[evolution]\nfitness = \"paper\"\n[target]\nepisodes = 9\n[[source]]\nlabel = \"a\"\n", "x.toml");
    assert_int_equal(s.target.fitness, QNAV_SIM_FITNESS_PAPER);
    assert_int_equal(s.sources[0].scenario.fitness, QNAV_SIM_FITNESS_PAPER);
    assert_true(s.target.describe().find("fitness=paper") != std::string::npos);
}

static void test_spec_controller_reading_reaches_every_scenario_and_bad_names_fail(void **state)
{
    (void)state;
    ExperimentSpec d = parse_experiment(kGoodSpec, "x.toml");
    assert_true(d.target.controller == ControllerReading::Body); // the default
    ExperimentSpec s = parse_experiment(
        "name = \"t\"\n[evolution]\ncontroller = \"literal\"\n[target]\nepisodes = 9\n[[source]]\nlabel = \"a\"\n", "x.toml");
    assert_true(s.target.controller == ControllerReading::Literal);
    assert_true(s.sources[0].scenario.controller == ControllerReading::Literal);
    assert_true(s.target.describe().find("controller=literal") != std::string::npos);
    try {
        (void)parse_experiment("name = \"t\"\n[evolution]\ncontroller = \"wide\"\n[target]\nepisodes = 9\n", "x.toml");
        fail_msg("a bad controller name was accepted");
    } catch (const UserError &e) {
        assert_true(std::string(e.what()).find("x.toml:3: controller: 'wide' is not one of body, literal") !=
                    std::string::npos);
    }
}

static void test_spec_checkpoints_parse_and_presets_shrink_their_evaluation(void **state)
{
    (void)state;
    ExperimentSpec s = parse_experiment(std::string(kGoodSpec) + "checkpoint_episodes = 5\n[evaluation]\n"
                                        "checkpoints = [10, 40]\ncheckpoint_every = 0\narrival_threshold = 90\n",
                                        "x.toml");
    assert_int_equal(s.checkpoints.size(), 2);
    assert_int_equal(s.checkpoints[1], 40);
    assert_int_equal(s.checkpoint_every, 0);
    assert_true(std::fabs(s.arrival_threshold - 0.9) < 1e-12);
    assert_int_equal(s.checkpoint_episodes, 20);
    apply_preset(s, "quick");
    assert_int_equal(s.checkpoint_episodes, 5);
}

static void test_spec_errors_name_file_line_and_problem(void **state)
{
    (void)state;
    std::string t = kGoodSpec;
    assert_string_equal(parse_error(t + "bogus = 1\n").c_str(), "x.toml:17: unknown key 'bogus' in [preset.quick]");
    assert_string_equal(parse_error("name = \"t\"\nruns = \"many\"\n").c_str(), "x.toml:2: runs: expected an integer");
    assert_string_equal(parse_error("name = \"t\"\n[target]\nsectors = 400\n").c_str(),
                        "x.toml:3: sectors: 400 is outside 0..360");
    assert_string_equal(parse_error("name = \"t\"\n[target]\nepisodes = 5\n").c_str(),
                        "x.toml:1: [[source]]: at least one source situation is needed for a transfer");
    assert_string_equal(parse_error("name = \"t\"\n").c_str(),
                        "x.toml:1: [target]: missing (the situation transfer and direct evolution share)");
    assert_true(parse_error("name = \"t\"\n[target\n").rfind("x.toml:2: ", 0) == 0);
    assert_string_equal(parse_error("name = \"t\"\n[evolution]\nepsilon = 1.5\n").c_str(),
                        "x.toml:3: epsilon: 1.5 is outside [0, 1]");
    assert_string_equal(parse_error("name = \"t\"\n[evolution]\nfitness = \"survival\"\n").c_str(),
                        "x.toml:3: fitness: 'survival' is not one of progress, paper");
    assert_string_equal(parse_error("name = \"t\"\n[evolution]\nfitness = 1\n").c_str(),
                        "x.toml:3: fitness: expected a string");
    assert_string_equal(parse_error("name = \"t\"\n[target]\n[[source]]\nlabel = \"a\"\n[evaluation]\ncheckpoints = [100, 50]\n").c_str(),
                        "x.toml:6: checkpoints: must be increasing (50 after 100)");
    assert_string_equal(parse_error("name = \"t\"\n[target]\n[[source]]\nlabel = \"a\"\n[evaluation]\ncheckpoints = 100\n").c_str(),
                        "x.toml:6: checkpoints: expected an array of episode counts, e.g. [100, 250, 500]");
    assert_string_equal(parse_error("name = \"t\"\n[target]\n[[source]]\nlabel = \"a\"\n[evaluation]\narrival_threshold = 120\n").c_str(),
                        "x.toml:6: arrival_threshold: 120 is outside [0, 100]");
    ExperimentSpec s = parse_experiment(kGoodSpec, "x.toml");
    try {
        apply_preset(s, "slow");
        fail();
    } catch (const UserError &e) {
        assert_string_equal(e.what(), "x.toml: no preset 'slow' (known: full, quick)");
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cauchy_samples_stay_inside_clip_and_tail_matches_theory),
        cmocka_unit_test(test_cauchy_median_is_zero_and_median_abs_is_scale),
        cmocka_unit_test(test_uniform_below_is_unbiased_over_small_range),
        cmocka_unit_test(test_mutation_rounds_to_q8_8_and_saturates),
        cmocka_unit_test(test_initial_episodes_score_every_member_once_in_random_order),
        cmocka_unit_test(test_epsilon_greedy_picks_random_member_with_probability_epsilon),
        cmocka_unit_test(test_mutant_replaces_the_worst_member),
        cmocka_unit_test(test_transfer_population_is_source_plus_mutants_first_episode_random),
        cmocka_unit_test(test_same_seed_gives_identical_evolution),
        cmocka_unit_test(test_evolution_improves_fitness_on_fake_task),
        cmocka_unit_test(test_t_critical_and_welch_match_tables),
        cmocka_unit_test(test_mann_whitney_separated_samples_are_significant),
        cmocka_unit_test(test_spec_parses_inheritance_and_presets),
        cmocka_unit_test(test_spec_fitness_rule_reaches_every_scenario),
        cmocka_unit_test(test_spec_controller_reading_reaches_every_scenario_and_bad_names_fail),
        cmocka_unit_test(test_spec_checkpoints_parse_and_presets_shrink_their_evaluation),
        cmocka_unit_test(test_spec_errors_name_file_line_and_problem),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
