// The analytic sonar ring (see sonar.hpp for the geometry argument).
#include "sonar.hpp"

#include <algorithm>
#include <cmath>

namespace qnav {

SonarRing::SonarRing(std::vector<Shape> shapes, double width_m, double height_m,
                     std::uint16_t n_sectors, double reach_m)
    : shapes_(std::move(shapes)), width_m_(width_m), height_m_(height_m), n_(n_sectors), width_(2.0 * kPi / n_sectors), reach_(reach_m) {
    boundary_.resize(n_);
    for (std::uint16_t j = 0; j < n_; ++j) {
        const double a = (j - 0.5) * width_;
        boundary_[j] = {std::cos(a), std::sin(a)};
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
            const Vec2 b = boundary_[j];
            const Vec2 u{ch * b.x - sh * b.y, sh * b.x + ch * b.y};
            double t = kInf;
            if (u.x > 0) t = wall_d[0] / u.x;
            else if (u.x < 0) t = -wall_d[2] / u.x;
            if (u.y > 0) t = std::min(t, wall_d[1] / u.y);
            else if (u.y < 0) t = std::min(t, -wall_d[3] / u.y);
            t = std::max(0.0, t);
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
            const Vec2 b = boundary_[static_cast<std::size_t>(jj)];
            const Vec2 u{ch * b.x - sh * b.y, sh * b.x + ch * b.y};
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
