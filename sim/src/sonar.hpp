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
// Broad phase (issue 19.5): the shapes are binned once per world by centre in a uniform
// grid of cells reach/2 wide (shapes wider than a cell, such as long walls, are kept apart
// and tested every scan), so a scan visits only the cells under the square of reach + one
// cell around the robot; and the shapes found
// there are taken nearest first (by the distance to their bounding circle), a shape being
// skipped when that distance is already no less than every reading in the sectors its
// bounding circle spans. Every reading is a minimum of values no smaller than that
// distance, so skipping and reordering leave the readings bit-identical.
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
    // Fewer shapes than this: measure() tests every one, cheaper than sorting them
    // (callgrind, TekBot, 16 sectors: dense, 18 shapes, +20 % sonar instructions with the
    // broad phase; 57-shape clutter +4 %; 100 shapes -8 %; 309 shapes -28 %).
    static constexpr std::size_t kBroadPhaseMin = 48;
    // shapes: every obstacle; the arena is [0, width] x [0, height]; n_sectors 1..360;
    // reach_m: obstacles farther than this from the centre are skipped (kInf).
    // cone_rad: the wedge of each sector; 0 (or anything up to 2*pi/N) means 2*pi/N.
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
    std::uint16_t sector_of(double a) const;
    // The wedge of every sector, rad.
    double cone() const { return cone_; }

private:
    std::vector<Shape> shapes_;
    // broad phase: cells of cell_m_, nx_ x ny_ from the origin (row-major); the shapes
    // whose centre is in cell c are cell_shapes_[cell_start_[c] .. cell_start_[c + 1]),
    // so a row of cells is one run; shapes wider than a cell are in large_
    double cell_m_ = 1.0;
    int nx_ = 1, ny_ = 1;
    std::vector<std::uint32_t> cell_start_, cell_shapes_, large_;
    // per-scan scratch (a ring belongs to one context, used by one thread at a time)
    mutable std::vector<std::pair<double, std::uint32_t>> near_;
    void build_grid();
    void measure_walls(Vec2 pos, double heading, double *dist) const;
    void apply_shape(const Shape &s, Vec2 pos, double heading, double ch, double sh, double *dist) const;
    void cell_range(Vec2 c, double half, int *i0, int *i1, int *j0, int *j1) const;
    double width_m_, height_m_;
    std::uint16_t n_;
    double width_;      // sector width, rad
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

}  // namespace qnav
