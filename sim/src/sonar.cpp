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
    build_grid();
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

void SonarRing::cell_range(Vec2 c, double half, int *i0, int *i1, int *j0, int *j1) const {
    auto idx = [&](double v, int n) {
        const double k = std::floor(v / cell_m_);
        return k < 0 ? 0 : k >= n ? n - 1 : static_cast<int>(k);
    };
    *i0 = idx(c.x - half, nx_);
    *i1 = idx(c.x + half, nx_);
    *j0 = idx(c.y - half, ny_);
    *j1 = idx(c.y + half, ny_);
}

void SonarRing::build_grid() {
    // Cells of half the reach. A shape no wider than a cell (bounding radius <= cell) is
    // binned by its centre: it can matter only when its centre is within reach + cell of
    // the robot, so a scan visits the cells under that square (at most 7 x 7). Wider
    // shapes (long walls) are few and tested every scan.
    cell_m_ = std::isfinite(reach_) && reach_ > 0 ? std::max(0.25, reach_ / 2) : 1e9;
    nx_ = std::max(1, std::min(4096, static_cast<int>(std::ceil(width_m_ / cell_m_))));
    ny_ = std::max(1, std::min(4096, static_cast<int>(std::ceil(height_m_ / cell_m_))));
    std::vector<std::uint32_t> count(cell_index(nx_ * ny_) + 1, 0);
    std::vector<std::uint32_t> cell_of(shapes_.size());
    large_.clear();
    for (std::uint32_t k = 0; k < shapes_.size(); ++k) {
        if (!(shapes_[k].r <= cell_m_)) {
            large_.push_back(k);
            continue;
        }
        int i0, i1, j0, j1;
        cell_range(shapes_[k].c, 0.0, &i0, &i1, &j0, &j1);
        cell_of[k] = static_cast<std::uint32_t>(j0 * nx_ + i0);
        ++count[cell_of[k] + 1];
    }
    for (std::size_t c = 1; c < count.size(); ++c) count[c] += count[c - 1];
    cell_start_ = count;
    cell_shapes_.resize(count.back());
    for (std::uint32_t k = 0; k < shapes_.size(); ++k)
        if (shapes_[k].r <= cell_m_) cell_shapes_[count[cell_of[k]]++] = k;
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

// The arena walls' readings (every sector starts from them).
void SonarRing::measure_walls(Vec2 pos, double heading, double *dist) const {
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
}

void SonarRing::measure(Vec2 pos, double heading, double *dist) const {
    if (cone_ > width_) {
        measure_wide(pos, heading, dist);
        return;
    }
    if (shapes_.size() < kBroadPhaseMin) {
        measure_plain(pos, heading, dist);
        return;
    }
    measure_walls(pos, heading, dist);
    const double ch = std::cos(heading), sh = std::sin(heading);
    // Broad phase: the shapes whose bounding circle comes within reach, nearest first.
    near_.clear();
    auto consider = [&](std::uint32_t k) {
        const Shape &s = shapes_[k];
        const Vec2 dc = s.c - pos;
        const double bound = s.r + reach_;
        const double d2 = dot(dc, dc);
        if (d2 <= bound * bound) near_.push_back({std::max(0.0, std::sqrt(d2) - s.r), k});
    };
    int gi0, gi1, gj0, gj1;
    cell_range(pos, reach_ + cell_m_, &gi0, &gi1, &gj0, &gj1);
    for (int j = gj0; j <= gj1; ++j) {
        const int row = j * nx_;
        for (std::uint32_t e = cell_start_[cell_index(row + gi0)]; e < cell_start_[cell_index(row + gi1 + 1)]; ++e)
            consider(cell_shapes_[e]);
    }
    for (const std::uint32_t k : large_) consider(k);
    std::sort(near_.begin(), near_.end());
    for (const auto &[lower, k] : near_) {
        const Shape &s = shapes_[k];
        const Vec2 dc = s.c - pos;
        if (lower > 0.0 && n_ > 1) {
            // Occlusion: every value this shape can give is >= lower; skip it when every
            // sector its bounding circle may touch already reads no more. The circle spans
            // +-asin(r / |dc|) <= +-(pi/2) r / |dc| about its centre; one more sector of
            // margin on each side covers fast_atan2's error and the boundary rays.
            const double dist_c = lower + s.r;
            const double half = 0.5 * kPi * s.r / dist_c;
            const double a = fast_atan2(dc.y, dc.x) - heading;
            const long k0 = static_cast<long>(std::floor((a - half) / width_ + 0.5)) - 1;
            const long k1 = static_cast<long>(std::floor((a + half) / width_ + 0.5)) + 1;
            bool hidden = true;
            if (k1 - k0 + 1 >= static_cast<long>(n_)) {
                for (std::uint16_t kk = 0; kk < n_ && hidden; ++kk) hidden = lower >= dist[kk];
            } else {
                long kk = k0 % static_cast<long>(n_);
                if (kk < 0) kk += n_;
                for (long m = k0; m <= k1 && hidden; ++m) {
                    hidden = lower >= dist[kk];
                    kk = kk + 1 == static_cast<long>(n_) ? 0 : kk + 1;
                }
            }
            if (hidden) continue;
        }
        apply_shape(s, pos, heading, ch, sh, dist);
    }
}

// One shape's readings: its nearest point's sector and its hits on the sector boundaries
// it spans (narrow cones).
void SonarRing::apply_shape(const Shape &s, Vec2 pos, double heading, double ch, double sh, double *dist) const {
    const Vec2 dc = s.c - pos;
    Vec2 q;
    const double dn = nearest_point(s, pos, &q);
    if (dn > reach_) return;
    if (dn <= 0.0) {
        // Inside or touching: the sector facing the shape reads zero.
        const double a = fast_atan2(dc.y, dc.x) - heading;
        dist[sector_of(a)] = 0.0;
        return;
    }
    const Vec2 dq = q - pos;
    const std::uint16_t ks = sector_of(fast_atan2(dq.y, dq.x) - heading);
    if (dn < dist[ks]) dist[ks] = dn;
    if (n_ == 1) return;
    double lo, hi;
    if (!angular_span(s, pos, &lo, &hi)) return;
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

void SonarRing::measure_plain(Vec2 pos, double heading, double *dist) const {
    if (cone_ > width_) {
        measure_wide(pos, heading, dist);
        return;
    }
    measure_walls(pos, heading, dist);
    const double ch = std::cos(heading), sh = std::sin(heading);
    for (const Shape &s : shapes_) {
        const Vec2 dc = s.c - pos;
        const double bound = s.r + reach_;
        if (dot(dc, dc) > bound * bound) continue;
        apply_shape(s, pos, heading, ch, sh, dist);
    }
}

}  // namespace qnav
