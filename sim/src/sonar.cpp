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
      inv_width_(n_sectors / (2.0 * kPi)),
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

void SonarRing::build_grid() {
    cell_m_ = std::max(kCell_m, std::max(width_m_, height_m_) / kMaxCells);
    nx_ = std::max(1, static_cast<int>(std::ceil(width_m_ / cell_m_)));
    ny_ = std::max(1, static_cast<int>(std::ceil(height_m_ / cell_m_)));
    first_.assign(cell_index(nx_) * cell_index(ny_), -1);
    count_.assign(first_.size(), 0);
}

// Every shape whose bounding circle comes within reach of cell (i, j) grown by kSlack_m,
// nearest first: a superset of the shapes that pass measure_plain's bounding test from
// any position in the cell. Seen from a point p within rho of the cell's centre o, a
// circle B(c, r) spans no more directions than B(c, r + rho) seen from o (the directions
// from p to B(c, r) are those from o to B(c - (p - o), r), inside B(c, r + rho)).
void SonarRing::build_cell(std::size_t cell, int i, int j) const {
    const double x0 = i * cell_m_ - kSlack_m, x1 = (i + 1) * cell_m_ + kSlack_m;
    const double y0 = j * cell_m_ - kSlack_m, y1 = (j + 1) * cell_m_ + kSlack_m;
    const Vec2 o{0.5 * (x0 + x1), 0.5 * (y0 + y1)};
    const double rho = 0.5 * std::hypot(x1 - x0, y1 - y0) + kSlack_m;
    const std::size_t begin = candidates_.size();
    for (std::uint32_t k = 0; k < shapes_.size(); ++k) {
        const Shape &s = shapes_[k];
        const double dx = std::max({x0 - s.c.x, s.c.x - x1, 0.0});
        const double dy = std::max({y0 - s.c.y, s.c.y - y1, 0.0});
        const double lower = std::sqrt(dx * dx + dy * dy) - s.r;
        if (!(lower <= reach_ + kSlack_m)) continue;
        const Vec2 d = s.c - o;
        const double dist = norm(d);
        const double half = dist > s.r + rho ? std::asin((s.r + rho) / dist) * inv_width_ : static_cast<double>(n_);
        candidates_.push_back({lower, s.c, s.r, std::atan2(d.y, d.x) * inv_width_, half, k});
    }
    std::sort(candidates_.begin() + static_cast<std::ptrdiff_t>(begin), candidates_.end(),
              [](const Candidate &a, const Candidate &b) { return a.lower < b.lower || (a.lower == b.lower && a.k < b.k); });
    first_[cell] = static_cast<std::int32_t>(begin);
    count_[cell] = static_cast<std::uint32_t>(candidates_.size() - begin);
}

bool SonarRing::candidates_at(Vec2 pos, const Candidate **begin, const Candidate **end) const {
    const double fx = pos.x / cell_m_, fy = pos.y / cell_m_;
    if (!(fx >= 0.0 && fy >= 0.0 && fx < nx_ && fy < ny_)) return false;  // NaN too
    const int i = static_cast<int>(fx), j = static_cast<int>(fy);
    const std::size_t cell = cell_index(j) * cell_index(nx_) + cell_index(i);
    if (first_[cell] < 0) build_cell(cell, i, j);
    *begin = candidates_.data() + first_[cell];
    *end = *begin + count_[cell];
    return true;
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


// The arena walls' readings (every sector starts from them).
void SonarRing::measure_walls(Vec2 pos, double heading, double ch, double sh, double *dist) const {
    std::fill(dist, dist + n_, kInf);
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
    const Candidate *c, *end;
    if (shapes_.size() < kBroadPhaseMin || !candidates_at(pos, &c, &end)) {
        measure_plain(pos, heading, dist);
        return;
    }
    const double ch = std::cos(heading), sh = std::sin(heading);
    measure_walls(pos, heading, ch, sh, dist);
    if (end - c <= kShortList) {
        // Few shapes: testing each is cheaper than deciding which to skip.
        for (; c != end; ++c) {
            const Vec2 dc = c->c - pos;
            const double bound = c->r + reach_;
            if (dot(dc, dc) <= bound * bound) apply_shape(shapes_[c->k], pos, heading, ch, sh, dist);
        }
        return;
    }
    // The largest reading (kept exact: rescanned when the sector that held it falls), and
    // about the smallest (the least nearest distance applied): a shape nearer than that
    // cannot be hidden.
    std::uint16_t top = 0;
    double smallest = dist[0];
    for (std::uint16_t k = 1; k < n_; ++k) {
        if (dist[k] > dist[top]) top = k;
        smallest = std::min(smallest, dist[k]);
    }
    double largest = dist[top];
    const double heading_sectors = heading * inv_width_;
    for (; c != end; ++c) {
        if (c->lower - kSlack_m >= largest) break;  // this shape and every later one
        // measure_plain's bounding test, on the same numbers
        const Vec2 dc = c->c - pos;
        const double bound = c->r + reach_;
        const double d2 = dot(dc, dc);
        if (d2 > bound * bound) continue;
        const double lower = std::sqrt(d2) - c->r - kSlack_m;
        if (lower > 0.0 && lower >= smallest && hidden(*c, heading_sectors, lower, dist)) continue;
        smallest = std::min(smallest, apply_shape(shapes_[c->k], pos, heading, ch, sh, dist));
        if (dist[top] < largest) {
            top = static_cast<std::uint16_t>(std::max_element(dist, dist + n_) - dist);
            largest = dist[top];
        }
    }
}

// Occlusion: every value a shape can give from outside its bounding circle (its nearest
// point, its boundary-ray hits) is at least lower; it changes nothing when every sector
// its bounding circle may touch already reads no more. One more sector of margin on each
// side of the circle's span covers the sector of its nearest point (found with
// fast_atan2, 1e-5 rad), the boundary rays (each touches the sectors on both sides) and
// the rounding here.
bool SonarRing::hidden(const Candidate &c, double heading_sectors, double lower, const double *dist) const {
    const double a = c.mid - heading_sectors + 0.5;
    long k = floor_long(a - c.half) - 1;
    const long count = floor_long(a + c.half) + 1 - k + 1;
    if (count >= static_cast<long>(n_)) {
        for (std::uint16_t kk = 0; kk < n_; ++kk)
            if (lower < dist[kk]) return false;
        return true;
    }
    while (k < 0) k += n_;
    while (k >= static_cast<long>(n_)) k -= n_;
    for (long m = 0; m < count; ++m) {
        if (lower < dist[k]) return false;
        k = k + 1 == static_cast<long>(n_) ? 0 : k + 1;
    }
    return true;
}

// One shape's readings: its nearest point's sector and its hits on the sector boundaries
// it spans (narrow cones). Returns its nearest distance (kInf beyond reach).
double SonarRing::apply_shape(const Shape &s, Vec2 pos, double heading, double ch, double sh, double *dist) const {
    const Vec2 dc = s.c - pos;
    Vec2 q;
    const double dn = nearest_point(s, pos, &q);
    if (dn > reach_) return kInf;
    if (dn <= 0.0) {
        // Inside or touching: the sector facing the shape reads zero.
        const double a = fast_atan2(dc.y, dc.x) - heading;
        dist[sector_of(a)] = 0.0;
        return 0.0;
    }
    const Vec2 dq = q - pos;
    const double aq = fast_atan2(dq.y, dq.x);
    const std::uint16_t ks = sector_of(aq - heading);
    if (dn < dist[ks]) dist[ks] = dn;
    if (n_ == 1) return dn;
    double lo, hi;
    if (!angular_span_from_nearest(s, pos, dq, aq, &lo, &hi)) return dn;
    // Boundary j sits at (j - 0.5) * width in the robot frame. A ray outside the shape's
    // extent misses it (ray_hit gives kInf), so testing boundaries up to kSpanMargin_rad
    // beyond it changes nothing; the margin covers the errors of the extent.
    const double lo_r = lo - heading - kSpanMargin_rad, hi_r = hi - heading + kSpanMargin_rad;
    const long j0 = -floor_long(-(lo_r / width_ + 0.5));  // ceil
    const long j1 = std::min(floor_long(hi_r / width_ + 0.5), j0 + n_ - 1);
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
    return dn;
}

void SonarRing::measure_plain(Vec2 pos, double heading, double *dist) const {
    if (cone_ > width_) {
        measure_wide(pos, heading, dist);
        return;
    }
    const double ch = std::cos(heading), sh = std::sin(heading);
    measure_walls(pos, heading, ch, sh, dist);
    for (const Shape &s : shapes_) {
        const Vec2 dc = s.c - pos;
        const double bound = s.r + reach_;
        if (dot(dc, dc) > bound * bound) continue;
        apply_shape(s, pos, heading, ch, sh, dist);
    }
}

}  // namespace qnav
