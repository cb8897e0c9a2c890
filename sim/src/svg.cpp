// SVG pictures of environments and episodes (see svg.hpp).
#include "svg.hpp"

#include <cmath>
#include <cstdio>
#include <sstream>


#include "error.hpp"

namespace qnav {

namespace {

constexpr double kScale = 60.0;  // pixels per metre
constexpr double kMargin = 20.0; // pixels

struct Mapper {
    double h_m;
    double x(double xm) const { return kMargin + xm * kScale; }
    double y(double ym) const { return kMargin + (h_m - ym) * kScale; }
};

// Header, background and arena; the start zones (yellow).
void draw_arena(std::ostream &o, const Mapper &m, const Environment &env, double wpx, double hpx) {
    o << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << wpx << "\" height=\"" << hpx
      << "\" viewBox=\"0 0 " << wpx << " " << hpx << "\">\n"
      << "<title>" << env.name << "</title>\n"
      << "<rect x=\"0\" y=\"0\" width=\"" << wpx << "\" height=\"" << hpx << "\" fill=\"white\"/>\n"
      << "<rect x=\"" << m.x(0) << "\" y=\"" << m.y(env.height_m) << "\" width=\""
      << env.width_m * kScale << "\" height=\"" << env.height_m * kScale
      << "\" fill=\"#f4f4f4\" stroke=\"black\" stroke-width=\"3\"/>\n";
    for (const auto &z : env.start_zones)
        o << "<rect x=\"" << m.x(z.x_m) << "\" y=\"" << m.y(z.y_m + z.h_m) << "\" width=\""
          << std::max(2.0, z.w_m * kScale) << "\" height=\"" << std::max(2.0, z.h_m * kScale)
          << "\" fill=\"#ffe24a\" stroke=\"#c9a800\"/>\n";
}

// Direct lines (orange): from a grid of start points, straight to the destination
// with the robot's clearance from every obstacle.
void draw_direct_lines(std::ostream &o, const Mapper &m, const Environment &env,
                       const std::vector<Shape> &obs, double robot_r) {
    const Vec2 dest{env.dest_x_m, env.dest_y_m};
    o << "<g stroke=\"#ff8c00\" stroke-width=\"1.2\" stroke-opacity=\"0.7\">\n";
    for (const auto &z : env.start_zones) {
        for (int i = 0; i < 5; ++i)
            for (int j = 0; j < 3; ++j) {
                const Vec2 p{z.x_m + z.w_m * (i + 0.5) / 5, z.y_m + z.h_m * (j + 0.5) / 3};
                const Shape seg = make_segment(p, dest);
                bool clear = true;
                for (const Shape &s : obs)
                    if (shape_distance(seg, s) < robot_r) clear = false;
                if (clear)
                    o << "<line x1=\"" << m.x(p.x) << "\" y1=\"" << m.y(p.y) << "\" x2=\""
                      << m.x(dest.x) << "\" y2=\"" << m.y(dest.y) << "\"/>\n";
            }
    }
    o << "</g>\n";
}

// Obstacles (grey) and the destination.
void draw_obstacles_and_destination(std::ostream &o, const Mapper &m, const Environment &env) {
    o << "<g fill=\"#5a5a5a\" stroke=\"black\">\n";
    for (const auto &c : env.circles)
        o << "<circle cx=\"" << m.x(c.x_m) << "\" cy=\"" << m.y(c.y_m) << "\" r=\"" << c.r_m * kScale
          << "\"/>\n";
    for (const auto &b : env.boxes) {
        const Shape s = make_box(b.x_m, b.y_m, b.w_m, b.h_m, b.angle_deg);
        o << "<polygon points=\"";
        for (int i = 0; i < 4; ++i) o << m.x(s.v[i].x) << "," << m.y(s.v[i].y) << " ";
        o << "\"/>\n";
    }
    o << "</g>\n";
    o << "<circle cx=\"" << m.x(env.dest_x_m) << "\" cy=\"" << m.y(env.dest_y_m) << "\" r=\""
      << env.dest_radius_m * kScale << "\" fill=\"#ff8c00\" fill-opacity=\"0.5\" stroke=\"#d35400\" stroke-width=\"2\"/>\n";
}

// The map's occupied cells (translucent red squares, turned as its grid is) at the sonar's tick.
void draw_map(std::ostream &o, const Mapper &m, const EpisodePicture &ep) {
    o << "<g fill=\"#d62728\" fill-opacity=\"0.35\">\n";
    for (const std::array<Vec2, 4> &c : ep.map_occupied) {
        o << "<polygon points=\"";
        for (std::size_t k = 0; k < c.size(); ++k) o << (k ? " " : "") << m.x(c[k].x) << "," << m.y(c[k].y);
        o << "\"/>\n";
    }
    o << "</g>\n";
}

// Each sonar sector as a wedge out to its reported range (from the body surface), then
// the robot's outline and heading at that tick.
void draw_sonar(std::ostream &o, const Mapper &m, const EpisodePicture &ep, double robot_r) {
    const std::size_t n = ep.sonar_ranges_m.size();
    const double step = 2 * kPi / static_cast<double>(n);
    const double w = ep.cone_rad > step ? ep.cone_rad : step;
    const Vec2 c = ep.sonar_pos;
    o << "<g fill=\"#3fa9f5\" fill-opacity=\"0.25\" stroke=\"#1f6fb2\" stroke-width=\"0.8\">\n";
    for (std::size_t k = 0; k < n; ++k) {
        const double rr = robot_r + ep.sonar_ranges_m[k];
        const double a0 = ep.sonar_heading + static_cast<double>(k) * step - 0.5 * w;
        const double a1 = a0 + w;
        if (n == 1) {
            o << "<circle cx=\"" << m.x(c.x) << "\" cy=\"" << m.y(c.y) << "\" r=\"" << rr * kScale << "\"/>\n";
            continue;
        }
        o << "<path d=\"M " << m.x(c.x) << " " << m.y(c.y) << " L "
          << m.x(c.x + rr * std::cos(a0)) << " " << m.y(c.y + rr * std::sin(a0)) << " A "
          << rr * kScale << " " << rr * kScale << " 0 " << (w > kPi ? 1 : 0) << " 0 "
          << m.x(c.x + rr * std::cos(a1)) << " " << m.y(c.y + rr * std::sin(a1)) << " Z\"/>\n";
    }
    o << "</g>\n";
    o << "<circle cx=\"" << m.x(c.x) << "\" cy=\"" << m.y(c.y) << "\" r=\"" << robot_r * kScale
      << "\" fill=\"none\" stroke=\"#1f6fb2\" stroke-width=\"2\"/>\n"
      << "<line x1=\"" << m.x(c.x) << "\" y1=\"" << m.y(c.y) << "\" x2=\""
      << m.x(c.x + robot_r * std::cos(ep.sonar_heading)) << "\" y2=\""
      << m.y(c.y + robot_r * std::sin(ep.sonar_heading)) << "\" stroke=\"#1f6fb2\" stroke-width=\"2\"/>\n";
}

// The path with the robot at its start (green) and end (blue), the collision marks (red
// crosses) and the caption.
void draw_episode(std::ostream &o, const Mapper &m, const EpisodePicture &ep, double robot_r,
                  double hpx) {
    if (!ep.path.empty()) {
        o << "<polyline fill=\"none\" stroke=\"#0b3d91\" stroke-width=\"2\" points=\"";
        for (const Vec2 &p : ep.path) o << m.x(p.x) << "," << m.y(p.y) << " ";
        o << "\"/>\n";
        const Vec2 s = ep.path.front(), e = ep.path.back();
        o << "<circle cx=\"" << m.x(s.x) << "\" cy=\"" << m.y(s.y) << "\" r=\"" << robot_r * kScale
          << "\" fill=\"none\" stroke=\"#2e8b57\" stroke-width=\"2\"/>\n";
        o << "<circle cx=\"" << m.x(e.x) << "\" cy=\"" << m.y(e.y) << "\" r=\"" << robot_r * kScale
          << "\" fill=\"none\" stroke=\"#0b3d91\" stroke-width=\"2\"/>\n";
    }
    o << "<g stroke=\"red\" stroke-width=\"2.5\">\n";
    for (const auto &c : ep.collisions) {
        const double x = m.x(c.contact.x), y = m.y(c.contact.y), d = 6;
        o << "<line x1=\"" << x - d << "\" y1=\"" << y - d << "\" x2=\"" << x + d << "\" y2=\"" << y + d << "\"/>"
          << "<line x1=\"" << x - d << "\" y1=\"" << y + d << "\" x2=\"" << x + d << "\" y2=\"" << y - d << "\"/>\n";
    }
    o << "</g>\n";
    if (!ep.caption.empty())
        o << "<text x=\"" << kMargin << "\" y=\"" << hpx - 8
          << "\" font-family=\"sans-serif\" font-size=\"14\">" << ep.caption << "</text>\n";
}

}  // namespace

std::string render_svg(const Environment &env, double robot_r, const EpisodePicture *ep) {
    const Mapper m{env.height_m};
    const double wpx = env.width_m * kScale + 2 * kMargin;
    const double hpx = env.height_m * kScale + 2 * kMargin + (ep && !ep->caption.empty() ? 24 : 0);
    std::ostringstream o;
    o.setf(std::ios::fixed);
    o.precision(2);
    draw_arena(o, m, env, wpx, hpx);
    draw_direct_lines(o, m, env, env.obstacle_shapes(), robot_r);
    draw_obstacles_and_destination(o, m, env);
    if (ep) {
        if (ep->map_drawn) draw_map(o, m, *ep);
        if (!ep->sonar_ranges_m.empty()) draw_sonar(o, m, *ep, robot_r);
        draw_episode(o, m, *ep, robot_r, hpx);
    }
    o << "</svg>\n";
    return o.str();
}

}  // namespace qnav
