// The analytic sonar ring: N sectors around the robot, sector k centred on k*360/N deg
// (robot frame, counter-clockwise), each a wedge 360/N deg wide that reports the distance
// to the nearest obstacle point inside it. Computed from the obstacle geometry, not by
// casting a Box2D ray per degree: for a convex shape the nearest point inside a wedge is
// either the shape's nearest point (when that lies in the wedge) or a hit of one of the
// wedge's two boundary rays, so a tick costs one nearest-point test per shape and one ray
// test per sector boundary the shape spans. The arena walls (the inside of a rectangle)
// are treated apart: a ray's wall distance is its exit distance from the rectangle, and
// each wall's nearest point is the foot of the perpendicular.
//
// Broad phase (issue 19.5): the arena is cut into cells kCell_m wide; the first scan from a
// cell lists every shape whose bounding circle comes within reach of some point of the
// cell, ordered by that distance (a lower bound of the shape's distance from anywhere in
// the cell), and the list is kept (the world is static). A scan walks its cell's list and
// stops at the first shape whose bound is no less than every reading so far (it and all
// after it can only tie or lose); a shape before that is skipped when its bounding circle
// is no nearer than every reading in the sectors it may touch. Each reading is a minimum,
// so which shapes are skipped and in what order the rest are taken cannot change it: the
// readings are bit-identical to testing every shape (measure_plain). The bounds carry a
// slack of kSlack_m against rounding. A scan costs about the shapes near the robot,
// however many lie farther away; the robot's contact test takes its shapes from the same
// lists (for_shapes_near). A list lives as long as the ring: at most one per cell the
// robot has been in, 56 bytes per shape in reach.
//
// A profile may give a wider physical cone (cone > 360/N, at most 180 deg): then each
// sector's wedge is that cone centred on the sector, wedges overlap, and each sector has
// its own two boundary rays; the same argument applies.
#pragma once

#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include "geometry.hpp"

namespace qnav {

class SonarRing {
public:
    // Broad-phase cell side, m: small enough that a cell's bounds stay close to the true
    // distances (0.18 m at most), large enough that a robot crossing the arena meets few
    // new cells (each costs one pass over the shapes). Measured in docs/performance.md.
    // Arenas wider than kMaxCells cells get wider cells.
    static constexpr double kCell_m = 0.25;
    static constexpr int kMaxCells = 512;
    // Slack of every broad-phase bound, m: far above the rounding of the distances (about
    // 1e-13 m in a 1000 m arena), far below any obstacle's size.
    static constexpr double kSlack_m = 1e-6;
    // Worlds of fewer shapes take measure_plain (there the broad phase costs more than it
    // saves: dense, 15 shapes, +7 % instructions with it), and cells whose list holds
    // kShortList shapes or fewer test each of them without the occlusion test.
    static constexpr std::size_t kBroadPhaseMin = 32;
    static constexpr std::ptrdiff_t kShortList = 6;
    // Margin of the boundary rays tested beyond a shape's angular extent, rad: ten times
    // the extent's error (fast_atan2).
    static constexpr double kSpanMargin_rad = 3e-4;
    SonarRing(std::vector<Shape> shapes, double width_m, double height_m,
              std::uint16_t n_sectors, double reach_m, double cone_rad = 0.0);
    // True centre distances (m) of the nearest obstacle point per sector for a robot at
    // pos with heading (rad, world frame); kInf where nothing is within reach.
    void measure(Vec2 pos, double heading, double *dist_m) const;
    // The same readings, bit for bit, without the broad phase: every shape's bounding
    // circle tested (the plain body the tests hold measure() to).
    void measure_plain(Vec2 pos, double heading, double *dist_m) const;
    std::uint16_t sectors() const { return n_; }
    const std::vector<Shape> &shapes() const { return shapes_; }
    // Sector (0..N-1) whose centre is nearest the robot-frame angle a (rad): the sector
    // that contains a when cones are 2*pi/N wide.
    std::uint16_t sector_of(double a) const {
        long k = floor_long((a + 0.5 * width_) / width_);
        // a is a difference of two wrapped angles, so k is within a few turns of 0..n-1.
        while (k < 0) k += n_;
        while (k >= static_cast<long>(n_)) k -= n_;
        return static_cast<std::uint16_t>(k);
    }
    // The wedge of every sector, rad.
    double cone() const { return cone_; }

    // Call f(k) for every shape k whose bounding circle may come within d_m of pos (a
    // superset of them, in no particular order; every shape in small worlds, when d_m
    // exceeds the reach or when pos lies outside the arena).
    template <typename F>
    void for_shapes_near(Vec2 pos, double d_m, F &&f) const;

private:
    std::vector<Shape> shapes_;
    // A shape in a cell's list: its bounding circle, its distance from the cell and the
    // directions in which a robot in the cell may see it.
    struct Candidate {
        double lower;  // distance from the cell (grown by kSlack_m) to the bounding circle, m;
                       // negative when they overlap
        Vec2 c;        // bounding circle: centre, m
        double r;      // and radius, m
        double mid;    // world angle of c from the cell's centre, in sectors (rad / width)
        double half;   // half the angle the circle spans from anywhere in the cell, in
                       // sectors (a bound; n_ or more when the cell may overlap it)
        std::uint32_t k;  // index in shapes_
    };
    double cell_m_ = kCell_m;
    int nx_ = 0, ny_ = 0;  // cells of cell_m_ from the origin (row-major), covering the arena
    // Cell c's list is candidates_[first_[c] .. first_[c] + count_[c]); first_ is -1 until
    // the cell is first scanned from (mutable: a ring belongs to one context, used by one
    // thread at a time, and the lists change no reading).
    mutable std::vector<std::int32_t> first_;
    mutable std::vector<std::uint32_t> count_;
    mutable std::vector<Candidate> candidates_;
    // The list of the cell holding pos (made on first use); false when pos is outside the
    // arena (the caller then tests every shape).
    bool candidates_at(Vec2 pos, const Candidate **begin, const Candidate **end) const;
    void build_grid();
    void build_cell(std::size_t cell, int i, int j) const;
    bool hidden(const Candidate &c, double heading_sectors, double lower, const double *dist) const;
    // ch, sh: cos and sin of heading (the caller turns the boundary rays with them too)
    void measure_walls(Vec2 pos, double heading, double ch, double sh, double *dist) const;
    double apply_shape(const Shape &s, Vec2 pos, double heading, double ch, double sh, double *dist) const;
    double width_m_, height_m_;
    std::uint16_t n_;
    double width_;      // sector width, rad
    double inv_width_;  // 1 / width_ (only where a sector of margin absorbs its rounding)
    double reach_;      // m
    std::vector<Vec2> boundary_;  // unit vector of boundary j (between sectors j-1 and j),
                                  // robot frame, at angle (j - 0.5) * width
    double cone_;                 // wedge, rad
    std::vector<Vec2> right_, left_;  // wide cones: sector k's edges at k*width -/+ cone/2
    void measure_wide(Vec2 pos, double heading, double *dist) const;
    // Call f(k) for every sector k (mod N) whose angle k*width + offset lies in [lo, lo+span].
    template <typename F>
    void for_sectors_in(double lo, double span, double offset, F &&f) const;
};

template <typename F>
void SonarRing::for_shapes_near(Vec2 pos, double d_m, F &&f) const {
    const Candidate *c, *end;
    if (shapes_.size() < kBroadPhaseMin || !(d_m <= reach_) || !candidates_at(pos, &c, &end)) {
        for (std::uint32_t k = 0; k < shapes_.size(); ++k) f(k);
        return;
    }
    // The list is ordered by the bound: past d_m, every shape's bounding circle is
    // farther than d_m from pos.
    for (; c != end && c->lower - kSlack_m <= d_m; ++c) f(c->k);
}

}  // namespace qnav
