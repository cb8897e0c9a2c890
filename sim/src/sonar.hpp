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
// A profile may give a wider physical cone (cone > 360/N, at most 180 deg): then each
// sector's wedge is that cone centred on the sector, wedges overlap, and each sector has
// its own two boundary rays; the same argument applies.
#pragma once

#include <cstdint>
#include <vector>

#include "geometry.hpp"

namespace qnav {

class SonarRing {
public:
    // shapes: every obstacle; the arena is [0, width] x [0, height]; n_sectors 1..360;
    // reach_m: obstacles farther than this from the centre are skipped (kInf).
    // cone_rad: the wedge of each sector; 0 (or anything up to 2*pi/N) means 2*pi/N.
    SonarRing(std::vector<Shape> shapes, double width_m, double height_m,
              std::uint16_t n_sectors, double reach_m, double cone_rad = 0.0);
    // True centre distances (m) of the nearest obstacle point per sector for a robot at
    // pos with heading (rad, world frame); kInf where nothing is within reach.
    void measure(Vec2 pos, double heading, double *dist_m) const;
    std::uint16_t sectors() const { return n_; }
    const std::vector<Shape> &shapes() const { return shapes_; }
    // Sector (0..N-1) whose centre is nearest the robot-frame angle a (rad): the sector
    // that contains a when cones are 2*pi/N wide.
    std::uint16_t sector_of(double a) const;
    // The wedge of every sector, rad.
    double cone() const { return cone_; }

private:
    std::vector<Shape> shapes_;
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
