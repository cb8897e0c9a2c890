// The analytic sonar ring: N sectors around the robot, sector k centred on k*360/N deg
// (robot frame, counter-clockwise), each a wedge 360/N deg wide that reports the distance
// to the nearest obstacle point inside it. Computed from the obstacle geometry, not by
// casting a Box2D ray per degree: for a convex shape the nearest point inside a wedge is
// either the shape's nearest point (when that lies in the wedge) or a hit of one of the
// wedge's two boundary rays, so a tick costs one nearest-point test per shape and one ray
// test per sector boundary the shape spans. The arena walls (the inside of a rectangle)
// are treated apart: a ray's wall distance is its exit distance from the rectangle, and
// each wall's nearest point is the foot of the perpendicular.
#pragma once

#include <cstdint>
#include <vector>

#include "geometry.hpp"

namespace qnav {

class SonarRing {
public:
    // shapes: every obstacle; the arena is [0, width] x [0, height]; n_sectors 1..360;
    // reach_m: obstacles farther than this from the centre are skipped (kInf).
    SonarRing(std::vector<Shape> shapes, double width_m, double height_m,
              std::uint16_t n_sectors, double reach_m);
    // True centre distances (m) of the nearest obstacle point per sector for a robot at
    // pos with heading (rad, world frame); kInf where nothing is within reach.
    void measure(Vec2 pos, double heading, double *dist_m) const;
    std::uint16_t sectors() const { return n_; }
    const std::vector<Shape> &shapes() const { return shapes_; }
    // Sector (0..N-1) that contains the robot-frame angle a (rad).
    std::uint16_t sector_of(double a) const;

private:
    std::vector<Shape> shapes_;
    double width_m_, height_m_;
    std::uint16_t n_;
    double width_;      // sector width, rad
    double reach_;      // m
    std::vector<Vec2> boundary_;  // unit vector of boundary j (between sectors j-1 and j),
                                  // robot frame, at angle (j - 0.5) * width
};

}  // namespace qnav
