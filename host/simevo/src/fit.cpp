/*
 * A network fitted to a robot's probabilistic policy (fit.h). The target is libqnav's own
 * quality of the policy over every (level, dtheta); the network is the paper's 2-input
 * sigmoid network, x_theta = dtheta / 180 and x_d = level / (QNAV_DIST_LEVELS - 1) as
 * libqnav feeds it, fitted in double precision and rounded to Q8.8 as evolution rounds.
 */
#include "fit.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

#include "evolution.h"
#include "qnav/policy_io.h"
#include "qnav/rng.hpp"
#include "spec.h"

namespace qnav {
namespace {

constexpr std::size_t kDthetas = QNAV_DTHETA_MAX + 1;
constexpr std::size_t kPoints = QNAV_DIST_LEVELS * kDthetas;
constexpr double kWeightMax = 127.99; /* a Q8.8 weight lies in [-128, 128) */

/* libqnav's quality of policy under cfg at every (level, dtheta), in [0, 1], level-major. */
std::vector<double> quality_grid(const qnav_ctrl_config_t &cfg, const qnav_policy_t &policy)
{
    auto ctrl = std::make_unique<qnav_ctrl_t>();
    const qnav_status_t st = qnav_ctrl_init(ctrl.get(), &cfg, &policy);
    if (st != QNAV_OK) {
        throw UserError(std::string("fit: the policy does not run: ") + qnav_status_str(st));
    }
    std::vector<double> q(kPoints);
    for (std::size_t l = 0; l < QNAV_DIST_LEVELS; ++l) {
        for (std::size_t d = 0; d < kDthetas; ++d) {
            q[l * kDthetas + d] =
                qnav_ctrl_quality(ctrl.get(), static_cast<uint8_t>(l), static_cast<uint8_t>(d)) / 32768.0;
        }
    }
    return q;
}

double sigmoid(double z) { return 1.0 / (1.0 + std::exp(-z)); }

/* One start's weights: per hidden unit theta, dist, bias, out; then the output bias. */
struct Net {
    std::vector<std::array<double, 4>> w;
    double b = 0.0;
};

/* Adam's moments for every weight, in Net's order. */
struct Moments {
    std::vector<double> m, v;
};

/* One full-batch gradient g of the mean squared quality error over the grid; returns the
 * root mean square error. A hidden unit's activation at (level l, dtheta d) is
 * 1 / (1 + e^-(w_theta x_d) e^-(w_dist x_l + b)): two exponentials per row and column
 * instead of one per point. h, gz and z are the caller's scratch (hidden x points, points,
 * points), kept across steps so that a step allocates nothing. */
double gradient(const Net &n, const std::vector<double> &target, std::vector<double> &g, std::vector<double> &h,
                std::vector<double> &gz, std::vector<double> &z)
{
    const std::size_t hidden = n.w.size();
    std::fill(z.begin(), z.end(), n.b);
    std::array<double, kDthetas> et{};
    std::array<double, QNAV_DIST_LEVELS> ed{};
    double sse = 0.0;
    std::fill(g.begin(), g.end(), 0.0);
    for (std::size_t j = 0; j < hidden; ++j) {
        for (std::size_t d = 0; d < kDthetas; ++d) {
            et[d] = std::exp(-n.w[j][0] * static_cast<double>(d) / (kDthetas - 1));
        }
        for (std::size_t l = 0; l < QNAV_DIST_LEVELS; ++l) {
            ed[l] = std::exp(-(n.w[j][1] * static_cast<double>(l) / (QNAV_DIST_LEVELS - 1) + n.w[j][2]));
        }
        for (std::size_t p = 0; p < kPoints; ++p) {
            const double a = 1.0 / (1.0 + et[p % kDthetas] * ed[p / kDthetas]);
            h[j * kPoints + p] = a;
            z[p] += n.w[j][3] * a;
        }
    }
    for (std::size_t p = 0; p < kPoints; ++p) {
        const double y = sigmoid(z[p]), e = y - target[p];
        sse += e * e;
        gz[p] = 2.0 * e * y * (1.0 - y) / kPoints;
        g[4 * hidden] += gz[p];
    }
    for (std::size_t j = 0; j < hidden; ++j) {
        for (std::size_t p = 0; p < kPoints; ++p) {
            const double xt = static_cast<double>(p % kDthetas) / (kDthetas - 1);
            const double xd = static_cast<double>(p / kDthetas) / (QNAV_DIST_LEVELS - 1);
            const double a = h[j * kPoints + p];
            const double gh = gz[p] * n.w[j][3] * a * (1.0 - a);
            g[4 * j + 0] += xt * gh;
            g[4 * j + 1] += xd * gh;
            g[4 * j + 2] += gh;
            g[4 * j + 3] += a * gz[p];
        }
    }
    return std::sqrt(sse / kPoints);
}

/* One Adam step (rate 0.05, betas 0.9 / 0.999) of every weight, kept within Q8.8's range. */
void adam_step(Net &n, Moments &mo, const std::vector<double> &g, int t)
{
    const double c1 = 1.0 - std::pow(0.9, t), c2 = 1.0 - std::pow(0.999, t);
    for (std::size_t k = 0; k < g.size(); ++k) {
        double &w = k / 4 < n.w.size() ? n.w[k / 4][k % 4] : n.b;
        mo.m[k] = 0.9 * mo.m[k] + 0.1 * g[k];
        mo.v[k] = 0.999 * mo.v[k] + 0.001 * g[k] * g[k];
        w -= 0.05 * (mo.m[k] / c1) / (std::sqrt(mo.v[k] / c2) + 1e-8);
        w = std::clamp(w, -kWeightMax, kWeightMax);
    }
}

/* The policy of net n, rounded to Q8.8. */
qnav_policy_t rounded(const Net &n)
{
    qnav_policy_t p;
    qnav_policy_net_zero(&p, static_cast<uint8_t>(n.w.size()));
    uint16_t k = 0;
    for (const auto &u : n.w) {
        for (double x : u) {
            *qnav_net_weight(&p.u.net, k++) = weight_to_q8_8(x);
        }
    }
    *qnav_net_weight(&p.u.net, k) = weight_to_q8_8(n.b);
    return p;
}

} // namespace

void write_fit(const std::string &path, const std::string &robot, const FitResult &r, const char *by)
{
    char comment[200];
    std::snprintf(comment, sizeof comment, "%d hidden units fitted to %s's probabilistic policy by %s: quality error rms %.4f, max %.4f",
                  static_cast<int>(r.policy.u.net.hidden), robot.c_str(), by, r.rms, r.max);
    char err[QNAV_POLICY_IO_ERRLEN] = {0};
    if (qnav_policy_write(path.c_str(), &r.policy, comment, err, sizeof err) != 0) {
        throw UserError(err);
    }
}

FitResult fit_network(const qnav_ctrl_config_t &cfg, const qnav_policy_t &target, const FitSettings &s)
{
    if (s.hidden < 1 || s.hidden > QNAV_MAX_HIDDEN || s.starts < 1 || s.iterations < 1) {
        throw UserError("fit: hidden units 1.." + std::to_string(QNAV_MAX_HIDDEN) +
                        ", at least one start and one iteration");
    }
    const std::vector<double> q = quality_grid(cfg, target);
    Rng rng(s.seed);
    Net best;
    double best_rms = INFINITY;
    std::vector<double> g(4 * static_cast<std::size_t>(s.hidden) + 1);
    std::vector<double> h(static_cast<std::size_t>(s.hidden) * kPoints), gz(kPoints), z(kPoints);
    for (int start = 0; start < s.starts; ++start) {
        Net n;
        n.w.resize(static_cast<std::size_t>(s.hidden));
        for (auto &u : n.w) {
            for (double &x : u) {
                x = 2.0 * rng.normal();
            }
        }
        Moments mo{std::vector<double>(g.size()), std::vector<double>(g.size())};
        double rms = 0.0;
        for (int t = 1; t <= s.iterations; ++t) {
            rms = gradient(n, q, g, h, gz, z);
            adam_step(n, mo, g, t);
        }
        if (rms < best_rms) {
            best_rms = rms;
            best = n;
        }
    }
    FitResult r;
    r.policy = rounded(best);
    const std::vector<double> got = quality_grid(cfg, r.policy);
    double sse = 0.0;
    for (std::size_t i = 0; i < got.size(); ++i) {
        const double e = got[i] - q[i];
        sse += e * e;
        r.max = std::max(r.max, std::fabs(e));
    }
    r.rms = std::sqrt(sse / static_cast<double>(got.size()));
    return r;
}

} // namespace qnav
