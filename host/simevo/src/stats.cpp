/*
 * Statistics for experiment summaries. The incomplete beta function is evaluated by its
 * continued fraction (modified Lentz), using the symmetry I_x(a,b) = 1 - I_{1-x}(b,a)
 * where the fraction converges slowly.
 */
#include "stats.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace qnav {

double mean_of(const std::vector<double> &x)
{
    if (x.empty()) {
        return 0.0;
    }
    return std::accumulate(x.begin(), x.end(), 0.0) / static_cast<double>(x.size());
}

double sd_of(const std::vector<double> &x)
{
    if (x.size() < 2) {
        return 0.0;
    }
    const double m = mean_of(x);
    double s = 0.0;
    for (double v : x) {
        s += (v - m) * (v - m);
    }
    return std::sqrt(s / static_cast<double>(x.size() - 1));
}

namespace {
double beta_fraction(double a, double b, double x)
{
    const double tiny = 1e-300;
    double c = 1.0;
    double d = 1.0 - (a + b) * x / (a + 1.0);
    if (std::fabs(d) < tiny) {
        d = tiny;
    }
    d = 1.0 / d;
    double h = d;
    for (int m = 1; m <= 500; ++m) {
        const double m2 = 2.0 * m;
        double num = m * (b - m) * x / ((a + m2 - 1.0) * (a + m2));
        d = 1.0 + num * d;
        d = std::fabs(d) < tiny ? tiny : d;
        c = 1.0 + num / c;
        c = std::fabs(c) < tiny ? tiny : c;
        d = 1.0 / d;
        h *= d * c;
        num = -(a + m) * (a + b + m) * x / ((a + m2) * (a + m2 + 1.0));
        d = 1.0 + num * d;
        d = std::fabs(d) < tiny ? tiny : d;
        c = 1.0 + num / c;
        c = std::fabs(c) < tiny ? tiny : c;
        d = 1.0 / d;
        const double delta = d * c;
        h *= delta;
        if (std::fabs(delta - 1.0) < 1e-15) {
            break;
        }
    }
    return h;
}
} // namespace

double incomplete_beta(double a, double b, double x)
{
    if (x <= 0.0) {
        return 0.0;
    }
    if (x >= 1.0) {
        return 1.0;
    }
    const double lfront = std::lgamma(a + b) - std::lgamma(a) - std::lgamma(b) +
                          a * std::log(x) + b * std::log1p(-x);
    if (x < (a + 1.0) / (a + b + 2.0)) {
        return std::exp(lfront) * beta_fraction(a, b, x) / a;
    }
    return 1.0 - std::exp(lfront) * beta_fraction(b, a, 1.0 - x) / b;
}

double t_two_sided_p(double t, double df)
{
    if (!(df > 0.0) || !std::isfinite(t)) {
        return std::isinf(t) ? 0.0 : 1.0;
    }
    return incomplete_beta(df / 2.0, 0.5, df / (df + t * t));
}

double t_critical(double df, double alpha)
{
    double lo = 0.0;
    double hi = 1000.0;
    for (int i = 0; i < 200; ++i) {
        const double mid = 0.5 * (lo + hi);
        if (t_two_sided_p(mid, df) > alpha) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    return 0.5 * (lo + hi);
}

double ci95_half_width(const std::vector<double> &x)
{
    if (x.size() < 2) {
        return 0.0;
    }
    const double n = static_cast<double>(x.size());
    return t_critical(n - 1.0, 0.05) * sd_of(x) / std::sqrt(n);
}

TestResult welch_t_test(const std::vector<double> &a, const std::vector<double> &b)
{
    TestResult r;
    if (a.size() < 2 || b.size() < 2) {
        return r;
    }
    const double na = static_cast<double>(a.size());
    const double nb = static_cast<double>(b.size());
    const double va = sd_of(a) * sd_of(a) / na;
    const double vb = sd_of(b) * sd_of(b) / nb;
    if (va + vb <= 0.0) {
        return r;
    }
    r.statistic = (mean_of(a) - mean_of(b)) / std::sqrt(va + vb);
    r.df = (va + vb) * (va + vb) / (va * va / (na - 1.0) + vb * vb / (nb - 1.0));
    r.p = t_two_sided_p(r.statistic, r.df);
    r.valid = true;
    return r;
}

TestResult one_sample_t_test(const std::vector<double> &a, double mu)
{
    TestResult r;
    const double s = sd_of(a);
    if (a.size() < 2 || s <= 0.0) {
        return r;
    }
    const double n = static_cast<double>(a.size());
    r.statistic = (mean_of(a) - mu) / (s / std::sqrt(n));
    r.df = n - 1.0;
    r.p = t_two_sided_p(r.statistic, r.df);
    r.valid = true;
    return r;
}

namespace {

/* Two-sided exact p of the Mann-Whitney U for sample sizes na, nb without ties:
 * 2 P(U >= u_max), u_max = max(U_a, U_b), capped at 1. The count of orderings with a given
 * U follows f(i, j, u) = f(i - 1, j, u - j) + f(i, j - 1, u) over i a's and j b's. */
double mann_whitney_exact_p(std::size_t na, std::size_t nb, double u_max)
{
    const std::size_t umax = na * nb;
    // ways[j][u] for the current i, j = 0..nb
    std::vector<std::vector<double>> prev(nb + 1, std::vector<double>(umax + 1, 0.0)), cur = prev;
    for (std::size_t j = 0; j <= nb; ++j) {
        prev[j][0] = 1.0; // i = 0: one ordering, U = 0
    }
    for (std::size_t i = 1; i <= na; ++i) {
        for (std::size_t j = 0; j <= nb; ++j) {
            for (std::size_t v = 0; v <= umax; ++v) {
                double w = v >= j ? prev[j][v - j] : 0.0;
                if (j > 0) {
                    w += cur[j - 1][v];
                }
                cur[j][v] = w;
            }
        }
        std::swap(prev, cur);
    }
    double total = 0.0, tail = 0.0;
    for (std::size_t v = 0; v <= umax; ++v) {
        total += prev[nb][v];
        if (static_cast<double>(v) >= u_max - 1e-9) {
            tail += prev[nb][v];
        }
    }
    return std::min(1.0, 2.0 * tail / total);
}

} // namespace

TestResult mann_whitney(const std::vector<double> &a, const std::vector<double> &b)
{
    TestResult r;
    const std::size_t na = a.size();
    const std::size_t nb = b.size();
    if (na < 1 || nb < 1) {
        return r;
    }
    std::vector<std::pair<double, int>> all;
    for (double v : a) {
        all.emplace_back(v, 0);
    }
    for (double v : b) {
        all.emplace_back(v, 1);
    }
    std::sort(all.begin(), all.end(),
              [](const auto &x, const auto &y) { return x.first < y.first; });
    const double n = static_cast<double>(all.size());
    double rank_sum_a = 0.0;
    double tie_term = 0.0;
    for (std::size_t i = 0; i < all.size();) {
        std::size_t j = i;
        while (j < all.size() && all[j].first == all[i].first) {
            ++j;
        }
        const double avg_rank = (static_cast<double>(i + 1) + static_cast<double>(j)) / 2.0;
        const double t = static_cast<double>(j - i);
        tie_term += t * t * t - t;
        for (std::size_t k = i; k < j; ++k) {
            if (all[k].second == 0) {
                rank_sum_a += avg_rank;
            }
        }
        i = j;
    }
    const double dna = static_cast<double>(na);
    const double dnb = static_cast<double>(nb);
    const double u = rank_sum_a - dna * (dna + 1.0) / 2.0;
    const double mu = dna * dnb / 2.0;
    const double var = dna * dnb / 12.0 * ((n + 1.0) - tie_term / (n * (n - 1.0)));
    if (var <= 0.0) {
        return r;
    }
    r.statistic = (u - mu) / std::sqrt(var);
    r.p = std::erfc(std::fabs(r.statistic) / std::sqrt(2.0));
    r.valid = true;
    if (tie_term == 0.0 && std::min(na, nb) <= kMannWhitneyExactMax) {
        // small samples without ties: the exact distribution of U (as scipy's 'auto')
        r.p = mann_whitney_exact_p(na, nb, std::max(u, dna * dnb - u));
        r.exact = true;
    }
    return r;
}

} // namespace qnav
