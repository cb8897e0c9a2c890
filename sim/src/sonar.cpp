// The analytic sonar ring (see sonar.hpp for the geometry argument).
#include "sonar.hpp"

#include <algorithm>
#include <cmath>

namespace qnav {

SonarRing::SonarRing(std::vector<Shape> shapes, double width_m, double height_m,
                     std::uint16_t n_sectors, double reach_m, double cone_rad)
    : shapes_(std::move(shapes)),
      width_m_(width_m),
      height_m_(height_m),
      n_(n_sectors),
      width_(2.0 * kPi / n_sectors),
      reach_(reach_m) {
    boundary_.resize(n_);
    for (std::uint16_t j = 0; j < n_; ++j) {
        const double a = (j - 0.5) * width_;
        boundary_[j] = {std::cos(a), std::sin(a)};
    }
    cone_ = cone_rad > width_ ? std::min(cone_rad, kPi) : width_;
    if (cone_ > width_) {
        right_.resize(n_);
        left_.resize(n_);
        for (std::uint16_t k = 0; k < n_; ++k) {
            right_[k] = {std::cos(k * width_ - cone_ / 2), std::sin(k * width_ - cone_ / 2)};
            left_[k] = {std::cos(k * width_ + cone_ / 2), std::sin(k * width_ + cone_ / 2)};
        }
    }
}

template <typename F>
void SonarRing::for_sectors_in(double lo, double span, double offset, F &&f) const {
    const long k0 = static_cast<long>(std::ceil((lo - offset) / width_));
    const long k1 = static_cast<long>(std::floor((lo + span - offset) / width_));
    long kk = k0;
    while (kk < 0) kk += n_;
    while (kk >= static_cast<long>(n_)) kk -= n_;
    for (long k = k0; k <= k1 && k < k0 + static_cast<long>(n_); ++k) {
        f(static_cast<std::uint16_t>(kk));
        kk = kk + 1 == static_cast<long>(n_) ? 0 : kk + 1;
    }
}

// Exit distance of the unit ray u from inside the arena, wall_d = distances to the walls
// at +x, +y, -x, -y.
static inline double exit_distance(Vec2 u, const double wall_d[4]) {
    double t = kInf;
    if (u.x > 0) t = wall_d[0] / u.x;
    else if (u.x < 0) t = -wall_d[2] / u.x;
    if (u.y > 0) t = std::min(t, wall_d[1] / u.y);
    else if (u.y < 0) t = std::min(t, -wall_d[3] / u.y);
    return std::max(0.0, t);
}

void SonarRing::measure_wide(Vec2 pos, double heading, double *dist) const {
    std::fill(dist, dist + n_, kInf);
    const double ch = std::cos(heading), sh = std::sin(heading);
    const double half = cone_ / 2;
    auto rot = [&](Vec2 b) { return rotate(b, ch, sh); };
    const double wall_d[4] = {width_m_ - pos.x, height_m_ - pos.y, pos.x, pos.y};
    for (int w = 0; w < 4; ++w) {
        const double d = std::max(0.0, wall_d[w]);
        const double a = wrap_pi(w * 0.5 * kPi - heading);
        for_sectors_in(a - half, cone_, 0.0, [&](std::uint16_t k) { dist[k] = std::min(dist[k], d); });
    }
    for (std::uint16_t k = 0; k < n_; ++k) {
        dist[k] = std::min(dist[k], exit_distance(rot(right_[k]), wall_d));
        dist[k] = std::min(dist[k], exit_distance(rot(left_[k]), wall_d));
    }
    for (const Shape &s : shapes_) {
        const Vec2 dc = s.c - pos;
        const double bound = s.r + reach_;
        if (dot(dc, dc) > bound * bound) continue;
        Vec2 q;
        const double dn = nearest_point(s, pos, &q);
        if (dn > reach_) continue;
        if (dn <= 0.0) {
            const double a = wrap_pi(fast_atan2(dc.y, dc.x) - heading);
            for_sectors_in(a - half, cone_, 0.0, [&](std::uint16_t k) { dist[k] = 0.0; });
            continue;
        }
        const Vec2 dq = q - pos;
        const double aq = wrap_pi(fast_atan2(dq.y, dq.x) - heading);
        for_sectors_in(aq - half, cone_, 0.0, [&](std::uint16_t k) { dist[k] = std::min(dist[k], dn); });
        double lo, hi;
        if (!angular_span(s, pos, &lo, &hi)) continue;
        const double lo_r = wrap_pi(lo - heading), span = hi - lo;
        for_sectors_in(lo_r, span, -half, [&](std::uint16_t k) {
            dist[k] = std::min(dist[k], ray_hit(s, pos, rot(right_[k])));
        });
        for_sectors_in(lo_r, span, half, [&](std::uint16_t k) {
            dist[k] = std::min(dist[k], ray_hit(s, pos, rot(left_[k])));
        });
    }
}

std::uint16_t SonarRing::sector_of(double a) const {
    long k = static_cast<long>(std::floor((a + 0.5 * width_) / width_));
    // a is a difference of two wrapped angles, so k is within a few turns of 0..n-1.
    while (k < 0) k += n_;
    while (k >= static_cast<long>(n_)) k -= n_;
    return static_cast<std::uint16_t>(k);
}

void SonarRing::measure(Vec2 pos, double heading, double *dist) const {
    if (cone_ > width_) {
        measure_wide(pos, heading, dist);
        return;
    }
    std::fill(dist, dist + n_, kInf);
    const double ch = std::cos(heading), sh = std::sin(heading);
    // Arena walls: perpendicular feet (walls at angles 0, pi/2, pi, -pi/2 from the robot)...
    const double wall_d[4] = {width_m_ - pos.x, height_m_ - pos.y, pos.x, pos.y};
    for (int w = 0; w < 4; ++w) {
        const double d = std::max(0.0, wall_d[w]);
        const std::uint16_t k = sector_of(w * 0.5 * kPi - heading);
        if (d < dist[k]) dist[k] = d;
    }
    // ... and every boundary ray's exit distance from the rectangle.
    if (n_ > 1) {
        for (std::uint16_t j = 0; j < n_; ++j) {
            const Vec2 u = rotate(boundary_[j], ch, sh);
            const double t = exit_distance(u, wall_d);
            const std::uint16_t left = j == 0 ? static_cast<std::uint16_t>(n_ - 1) : static_cast<std::uint16_t>(j - 1);
            if (t < dist[j]) dist[j] = t;
            if (t < dist[left]) dist[left] = t;
        }
    }
    for (const Shape &s : shapes_) {
        // Cheap cull on the bounding circle before any exact test.
        const Vec2 dc = s.c - pos;
        const double bound = s.r + reach_;
        if (dot(dc, dc) > bound * bound) continue;
        Vec2 q;
        const double dn = nearest_point(s, pos, &q);
        if (dn > reach_) continue;
        if (dn <= 0.0) {
            // Inside or touching: the sector facing the shape reads zero.
            const double a = fast_atan2(dc.y, dc.x) - heading;
            dist[sector_of(a)] = 0.0;
            continue;
        }
        const Vec2 dq = q - pos;
        const std::uint16_t ks = sector_of(fast_atan2(dq.y, dq.x) - heading);
        if (dn < dist[ks]) dist[ks] = dn;
        if (n_ == 1) continue;
        double lo, hi;
        if (!angular_span(s, pos, &lo, &hi)) continue;
        // Boundary j sits at (j - 0.5) * width in the robot frame.
        const double lo_r = wrap_pi(lo - heading);
        const double span = hi - lo;
        const long j0 = static_cast<long>(std::ceil(lo_r / width_ + 0.5));
        const long j1 = static_cast<long>(std::floor((lo_r + span) / width_ + 0.5));
        long jj = j0;
        while (jj < 0) jj += n_;
        while (jj >= static_cast<long>(n_)) jj -= n_;
        for (long j = j0; j <= j1; ++j, jj = jj + 1 == static_cast<long>(n_) ? 0 : jj + 1) {
            const Vec2 u = rotate(boundary_[static_cast<std::size_t>(jj)], ch, sh);
            const double t = ray_hit(s, pos, u);
            if (t == kInf) continue;
            const std::size_t right = static_cast<std::size_t>(jj);
            const std::size_t left = static_cast<std::size_t>(jj == 0 ? n_ - 1 : jj - 1);
            if (t < dist[right]) dist[right] = t;
            if (t < dist[left]) dist[left] = t;
        }
    }
}

}  // namespace qnav
