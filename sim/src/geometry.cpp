// Plane geometry for the analytic sonar and environment checks (see geometry.hpp).
#include "geometry.hpp"

#include <algorithm>

namespace qnav {

Shape make_circle(double x, double y, double r) {
    Shape s;
    s.kind = Shape::kCircle;
    s.c = {x, y};
    s.r = r;
    return s;
}

Shape make_box(double x, double y, double w, double h, double angle_deg) {
    Shape s;
    s.kind = Shape::kBox;
    s.c = {x, y};
    s.n = 4;
    const double a = angle_deg * kPi / 180.0, ca = std::cos(a), sa = std::sin(a);
    s.ax = {ca, sa};
    s.hx = w / 2;
    s.hy = h / 2;
    const double hx[4] = {-w / 2, w / 2, w / 2, -w / 2};
    const double hy[4] = {-h / 2, -h / 2, h / 2, h / 2};
    for (int i = 0; i < 4; ++i) s.v[i] = {x + ca * hx[i] - sa * hy[i], y + sa * hx[i] + ca * hy[i]};
    s.r = 0.5 * std::sqrt(w * w + h * h);
    return s;
}

Shape make_segment(Vec2 a, Vec2 b) {
    Shape s;
    s.kind = Shape::kPolygon;
    s.n = 2;
    s.v[0] = a;
    s.v[1] = b;
    s.c = 0.5 * (a + b);
    s.r = 0.5 * norm(b - a);
    return s;
}

static Vec2 nearest_on_segment(Vec2 a, Vec2 b, Vec2 p) {
    const Vec2 ab = b - a;
    const double len2 = dot(ab, ab);
    double t = len2 > 0 ? dot(p - a, ab) / len2 : 0.0;
    t = std::clamp(t, 0.0, 1.0);
    return a + t * ab;
}

// p in the box frame: (along ax, along ax turned +90 deg).
static inline Vec2 box_local(const Shape &s, Vec2 p) {
    const Vec2 d = p - s.c;
    return {dot(d, s.ax), cross(s.ax, d)};
}

static bool inside_polygon(const Shape &s, Vec2 p) {
    if (s.n < 3) return false;
    for (int i = 0; i < s.n; ++i) {
        const Vec2 a = s.v[i], b = s.v[(i + 1) % s.n];
        if (cross(b - a, p - a) < 0) return false;
    }
    return true;
}

double nearest_point(const Shape &s, Vec2 p, Vec2 *out) {
    if (s.kind == Shape::kCircle) {
        const Vec2 d = p - s.c;
        const double dist = norm(d);
        if (dist <= s.r) {
            *out = p;
            return 0.0;
        }
        *out = s.c + (s.r / dist) * d;
        return dist - s.r;
    }
    if (s.kind == Shape::kBox) {
        const Vec2 l = box_local(s, p);
        const double qx = std::clamp(l.x, -s.hx, s.hx), qy = std::clamp(l.y, -s.hy, s.hy);
        const double dx = l.x - qx, dy = l.y - qy;
        if (dx == 0.0 && dy == 0.0) {
            *out = p;
            return 0.0;
        }
        *out = {s.c.x + qx * s.ax.x - qy * s.ax.y, s.c.y + qx * s.ax.y + qy * s.ax.x};
        return std::sqrt(dx * dx + dy * dy);
    }
    if (inside_polygon(s, p)) {
        *out = p;
        return 0.0;
    }
    double best = kInf;
    const int edges = s.n == 2 ? 1 : s.n;
    for (int i = 0; i < edges; ++i) {
        const Vec2 q = nearest_on_segment(s.v[i], s.v[(i + 1) % s.n], p);
        const double d = norm(q - p);
        if (d < best) {
            best = d;
            *out = q;
        }
    }
    return best;
}

double ray_hit(const Shape &s, Vec2 p, Vec2 u) {
    if (s.kind == Shape::kCircle) {
        const Vec2 m = s.c - p;
        const double b = dot(m, u);
        const double c2 = dot(m, m) - s.r * s.r;
        if (c2 <= 0) return 0.0;  // inside
        if (b <= 0) return kInf;
        const double disc = b * b - c2;
        if (disc < 0) return kInf;
        return b - std::sqrt(disc);
    }
    if (s.kind == Shape::kBox) {
        // Slabs in the box frame.
        const Vec2 o = box_local(s, p);
        const double ux = dot(u, s.ax), uy = cross(s.ax, u);
        double t0 = 0.0, t1 = kInf;
        const double oo[2] = {o.x, o.y}, uu[2] = {ux, uy}, hh[2] = {s.hx, s.hy};
        for (int k = 0; k < 2; ++k) {
            if (uu[k] == 0.0) {
                if (oo[k] < -hh[k] || oo[k] > hh[k]) return kInf;
                continue;
            }
            double ta = (-hh[k] - oo[k]) / uu[k], tb = (hh[k] - oo[k]) / uu[k];
            if (ta > tb) std::swap(ta, tb);
            t0 = std::max(t0, ta);
            t1 = std::min(t1, tb);
            if (t0 > t1) return kInf;
        }
        return t0;
    }
    double best = kInf;
    const int edges = s.n == 2 ? 1 : s.n;
    for (int i = 0; i < edges; ++i) {
        const Vec2 a = s.v[i], e = s.v[(i + 1) % s.n] - a;
        const double den = cross(u, e);
        if (den == 0.0) continue;  // parallel: a grazing ray meets the other edges
        const Vec2 ap = a - p;
        const double t = cross(ap, e) / den;
        const double k = cross(ap, u) / den;
        if (t >= 0 && k >= 0 && k <= 1 && t < best) best = t;
    }
    return best;
}

bool angular_span(const Shape &s, Vec2 p, double *lo, double *hi) {
    constexpr double kWiden = 1e-4;
    if (s.kind == Shape::kCircle) {
        const Vec2 d = s.c - p;
        const double d2 = dot(d, d), r2 = s.r * s.r;
        if (d2 <= r2) return false;
        const double mid = fast_atan2(d.y, d.x);
        const double half = fast_atan2(s.r, std::sqrt(d2 - r2)) + kWiden;
        *lo = wrap_pi(mid - half);
        *hi = *lo + 2.0 * half;
        return true;
    }
    if (inside_polygon(s, p)) return false;
    // Angles of the vertices relative to the direction of the first vertex; a convex
    // shape seen from outside spans less than pi, so the relative angles do not wrap.
    const Vec2 d0 = s.v[0] - p;
    if (dot(d0, d0) == 0.0) return false;
    double mn = 0, mx = 0;
    for (int i = 1; i < s.n; ++i) {
        const Vec2 d = s.v[i] - p;
        if (dot(d, d) == 0.0) return false;
        const double a = fast_atan2(cross(d0, d), dot(d0, d));
        mn = std::min(mn, a);
        mx = std::max(mx, a);
    }
    if (mx - mn >= kPi - 1e-9) return false;  // p on the segment's line between its ends
    *lo = wrap_pi(fast_atan2(d0.y, d0.x) + mn - kWiden);
    *hi = *lo + (mx - mn) + 2.0 * kWiden;
    return true;
}

bool angular_span_from_nearest(const Shape &s, Vec2 p, Vec2 dq, double aq, double *lo, double *hi) {
    if (s.kind == Shape::kCircle) {
        // The nearest point lies straight towards the centre.
        const Vec2 d = s.c - p;
        const double d2 = dot(d, d), r2 = s.r * s.r;
        if (d2 <= r2) return false;  // as angular_span
        const double half = fast_atan2(s.r, std::sqrt(d2 - r2));
        *lo = aq - half;
        *hi = aq + half;
        return true;
    }
    if (s.kind != Shape::kBox) {
        double a, b;
        if (!angular_span(s, p, &a, &b)) return false;
        *lo = aq + wrap_pi(a - aq);  // near aq, as the other kinds give it
        *hi = *lo + (b - a);
        return true;
    }
    // The extreme vertices by cross products (seen from outside, every direction to the
    // box lies within less than pi), then their angles from dq, which lies between them.
    Vec2 dlo = s.v[0] - p, dhi = dlo;
    for (int i = 1; i < s.n; ++i) {
        const Vec2 d = s.v[i] - p;
        if (cross(d, dlo) > 0) dlo = d;
        if (cross(dhi, d) > 0) dhi = d;
    }
    *lo = aq + fast_atan2(cross(dq, dlo), dot(dq, dlo));
    *hi = aq + fast_atan2(cross(dq, dhi), dot(dq, dhi));
    return true;
}

double shape_distance(const Shape &a, const Shape &b) {
    // (Boxes take the polygon path here through their vertices.)
    if (a.kind == Shape::kCircle && b.kind == Shape::kCircle)
        return std::max(0.0, norm(a.c - b.c) - a.r - b.r);
    if (a.kind == Shape::kCircle) {
        Vec2 q;
        return std::max(0.0, nearest_point(b, a.c, &q) - a.r);
    }
    if (b.kind == Shape::kCircle) return shape_distance(b, a);
    // Two convex polygons: 0 if a vertex of one is inside the other or edges cross;
    // otherwise the smallest vertex-to-edge distance.
    double best = kInf;
    Vec2 q;
    for (int i = 0; i < a.n; ++i) best = std::min(best, nearest_point(b, a.v[i], &q));
    for (int i = 0; i < b.n; ++i) best = std::min(best, nearest_point(a, b.v[i], &q));
    const int ea = a.n == 2 ? 1 : a.n, eb = b.n == 2 ? 1 : b.n;
    for (int i = 0; i < ea; ++i) {
        const Vec2 p = a.v[i], r = a.v[(i + 1) % a.n] - p;
        for (int j = 0; j < eb; ++j) {
            const Vec2 qq = b.v[j], s = b.v[(j + 1) % b.n] - qq;
            const double den = cross(r, s);
            if (den == 0.0) continue;
            const double t = cross(qq - p, s) / den, u = cross(qq - p, r) / den;
            if (t >= 0 && t <= 1 && u >= 0 && u <= 1) return 0.0;
        }
    }
    return best;
}

}  // namespace qnav
