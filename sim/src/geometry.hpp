// Plane geometry of the world's obstacles for the analytic sonar and for checking
// environments: circles and convex polygons (boxes; arena walls are two-vertex
// "polygons", i.e. segments). Nearest point to a sensor, ray hits, angular extent.
#pragma once

#include <cmath>
#include <cstddef>
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
// a rotated by the angle whose cosine and sine are c and s.
inline Vec2 rotate(Vec2 a, double c, double s) { return {c * a.x - s * a.y, s * a.x + c * a.y}; }

// Grids (passability, sonar cells, maze and room layouts) number their cells
// k = j * nx + i with int coordinates, so that a neighbour one step outside the grid is a
// plain comparison; a cell inside its grid (k >= 0) indexes the grid's vectors through this.
inline std::size_t cell_index(int k) { return static_cast<std::size_t>(k); }

constexpr double kPi = 3.14159265358979323846;
constexpr double kInf = std::numeric_limits<double>::infinity();

// Wrap an angle to (-pi, pi].
inline double wrap_pi(double a) {
    if (a > 8.0 * kPi || a < -8.0 * kPi) a = std::fmod(a, 2.0 * kPi);
    while (a <= -kPi) a += 2.0 * kPi;
    while (a > kPi) a -= 2.0 * kPi;
    return a;
}

// floor(x) for |x| < 2^63, as std::floor, without a call into libm (x86-64 without
// SSE4.1 has no rounding instruction).
inline long floor_long(double x) {
    const long k = static_cast<long>(x);
    return k - (static_cast<double>(k) > x);
}

// atan2 to within 1e-5 rad (Abramowitz & Stegun 4.4.49 polynomial after reduction to
// [-1, 1]); used where the sonar only needs to know which sectors an angle falls in.
inline double fast_atan2(double y, double x) {
    const double ax = std::fabs(x), ay = std::fabs(y);
    if (ax == 0.0 && ay == 0.0) return 0.0;
    const bool swap = ay > ax;
    const double t = swap ? ax / ay : ay / ax;
    const double t2 = t * t;
    double r = t * (0.99997726 + t2 * (-0.33262347 + t2 * (0.19354346 + t2 * (-0.11643287 +
                   t2 * (0.05265332 + t2 * -0.01172120)))));
    if (swap) r = 0.5 * kPi - r;
    if (x < 0) r = kPi - r;
    return y < 0 ? -r : r;
}

struct Shape {
    // A box is also a 4-vertex polygon; its own kind lets nearest-point and ray tests
    // work in the box frame (clamp and slabs) instead of edge by edge.
    enum Kind { kCircle, kPolygon, kBox } kind = kCircle;
    Vec2 c;            // circle centre, or polygon centroid, m
    double r = 0;      // circle radius, or polygon bounding radius about c, m
    int n = 0;         // polygon vertex count (2 = segment, 4 = box), counter-clockwise
    Vec2 v[4];
    Vec2 ax{1, 0};     // box: unit vector of its local x axis
    double hx = 0, hy = 0;  // box: half width and half height, m
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
// Computed with fast_atan2 and widened by 1e-4 rad on each side (a superset is harmless:
// callers only use it to decide which rays to test).
bool angular_span(const Shape &s, Vec2 p, double *lo, double *hi);
// The same extent, cheaper, for p outside the shape, from the direction dq of p's nearest
// point of the shape and its angle aq = fast_atan2(dq.y, dq.x): [lo, hi] (rad, not
// wrapped, not widened) within 3e-5 rad of the true extent. False where angular_span is
// false for a circle or a segment.
bool angular_span_from_nearest(const Shape &s, Vec2 p, Vec2 dq, double aq, double *lo, double *hi);
// Smallest distance between two shapes (0 when they touch or overlap).
double shape_distance(const Shape &a, const Shape &b);

}  // namespace qnav
