/*
 * The statistics an experiment summary reports, written here so that no Python package
 * beyond matplotlib/numpy is needed: mean, sample standard deviation, 95% confidence
 * half-width from Student's t, Welch's two-sample t-test, the one-sample t-test, and the
 * Mann-Whitney U test (exact for small samples without ties, else the normal approximation
 * with tie correction). p-values are two-sided. tests/simevo/test_stats_scipy.py checks
 * every one against python3-scipy.
 */
#ifndef QNAV_SIMEVO_STATS_H
#define QNAV_SIMEVO_STATS_H

#include <cstddef>
#include <vector>

namespace qnav {

double mean_of(const std::vector<double> &x);
/* Sample standard deviation (n - 1); 0 for n < 2. */
double sd_of(const std::vector<double> &x);
/* Regularised incomplete beta I_x(a, b), a, b > 0, x in [0, 1]. */
double incomplete_beta(double a, double b, double x);
/* Two-sided p-value of Student's t with df degrees of freedom. */
double t_two_sided_p(double t, double df);
/* t such that a two-sided test at level alpha is just significant (e.g. 0.05 -> 2.045
 * for df = 29). */
double t_critical(double df, double alpha);
/* Half-width of the 95% confidence interval of the mean (0 for n < 2). */
double ci95_half_width(const std::vector<double> &x);

struct TestResult {
    double statistic = 0.0; /* t, or z for Mann-Whitney */
    double df = 0.0;        /* degrees of freedom (t tests) */
    double p = 1.0;         /* two-sided p-value; 1 when undefined */
    bool valid = false;     /* enough data and variance to test */
    bool exact = false;     /* Mann-Whitney: p from the exact distribution of U */
};

/* Mann-Whitney's p is exact when the smaller sample has at most this many values and no
 * value is tied (scipy.stats.mannwhitneyu's method='auto' rule). */
constexpr std::size_t kMannWhitneyExactMax = 8;

/* Welch's t-test of mean(a) vs mean(b). */
TestResult welch_t_test(const std::vector<double> &a, const std::vector<double> &b);
/* One-sample t-test of mean(a) vs mu. */
TestResult one_sample_t_test(const std::vector<double> &a, double mu);
/* Mann-Whitney U: statistic is z of U_a (normal approximation, tie-corrected, no
 * continuity correction); p is exact (2 P(U >= max(U_a, U_b))) for small samples without
 * ties (kMannWhitneyExactMax), else from z. */
TestResult mann_whitney(const std::vector<double> &a, const std::vector<double> &b);

} // namespace qnav

#endif
