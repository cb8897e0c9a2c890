// Plane geometry of the world's obstacles for the analytic sonar and for checking
// environments: circles and convex polygons (boxes; arena walls are two-vertex
// "polygons", i.e. segments). Nearest point to a sensor, ray hits, angular extent.
#pragma once

#include <cmath>
#include <limits>

namespace qnav {

struct Vec2 {
    double x = 0, y = 0;
};
inline Vec2 operator+(Vec2 a, Vec2 b) { return {a.x + b.x, a.y + b.y}; }
inline Vec2 operator-(Vec2 a, Vec2 b) { return {a.x - b.x, a.y - b.y}; }
inline Vec2 operator*(double s, Vec2 a) { return {s * a.x, s * a.y}; }
inline double dot(Vec2 a, Vec2 b) { return a.x * b.x + a.y * b.y; }
inline double cross(Vec2 a, Vec2 b) { return a.x * b.y - a.y * b.x; }
inline double norm(Vec2 a) { return std::sqrt(dot(a, a)); }

constexpr double kPi = 3.14159265358979323846;
constexpr double kInf = std::numeric_limits<double>::infinity();

// Wrap an angle to (-pi, pi].
inline double wrap_pi(double a) {
    a = std::fmod(a, 2.0 * kPi);
    if (a <= -kPi) a += 2.0 * kPi;
    if (a > kPi) a -= 2.0 * kPi;
    return a;
}

struct Shape {
    enum Kind { kCircle, kPolygon } kind = kCircle;
    Vec2 c;            // circle centre, or polygon centroid, m
    double r = 0;      // circle radius, or polygon bounding radius about c, m
    int n = 0;         // polygon vertex count (2 = segment, 4 = box), counter-clockwise
    Vec2 v[4];
};

Shape make_circle(double x, double y, double r);
// Box centred at (x, y), w by h metres, rotated angle_deg counter-clockwise.
Shape make_box(double x, double y, double w, double h, double angle_deg);
Shape make_segment(Vec2 a, Vec2 b);

// Nearest point of the shape to p (p itself when inside) and its distance.
double nearest_point(const Shape &s, Vec2 p, Vec2 *out);
// Distance along the unit ray p + t*u to the shape's boundary, kInf if missed (t >= 0).
double ray_hit(const Shape &s, Vec2 p, Vec2 u);
// Angular extent [lo, hi] (rad, hi - lo < pi, lo in (-pi, pi]) of the shape seen from p,
// which must be outside it. Returns false when p is inside or on the shape.
bool angular_span(const Shape &s, Vec2 p, double *lo, double *hi);
// Smallest distance between two shapes (0 when they touch or overlap).
double shape_distance(const Shape &a, const Shape &b);

}  // namespace qnav
