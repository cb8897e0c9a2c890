// World families (worldgen.hpp): spec parsing, the passability grid, one builder per
// family in a canonical frame (start zones low, destination high), a random symmetry of
// the arena, and the check-and-retry loop that makes every world passable.
#include "worldgen.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>

#include "capi_internal.hpp"
#include "error.hpp"
#include "qnav/rng.hpp"
#include "tomlread.hpp"

namespace qnav {

namespace {

constexpr double kCell = 0.1;         // passability grid cell, m
constexpr int kMaxAttempts = 64;      // layouts drawn before giving up
constexpr char kPrefix[] = "gen:";

// ---- the passability grid -------------------------------------------------------------

// Cells whose centre lies closer than clearance to an obstacle or a wall are blocked (a
// count, so an obstacle can be taken out again). A disc of radius clearance - cell/2 can
// drive along any 4-connected path of free cells: every point of the path is within
// cell/2 of a free centre and distances are 1-Lipschitz.
class PassGrid {
public:
    PassGrid(double w, double h, double clearance, double cell)
        : w_(w), h_(h), clear_(clearance), cell_(cell),
          nx_(std::max(1, static_cast<int>(std::ceil(w / cell)))),
          ny_(std::max(1, static_cast<int>(std::ceil(h / cell)))),
          blocked_(cell_index(nx_ * ny_), 0),
          free_(blocked_.size(), 1) {
        for (int j = 0; j < ny_; ++j)
            for (int i = 0; i < nx_; ++i) {
                const double x = (i + 0.5) * cell_, y = (j + 0.5) * cell_;
                if (x < clear_ || y < clear_ || x > w_ - clear_ || y > h_ - clear_) change(i, j, +1);
            }
    }
    void add(const Shape &s, int delta) {
        const double reach = s.r + clear_;
        const int i0 = std::max(0, static_cast<int>(std::floor((s.c.x - reach) / cell_)));
        const int i1 = std::min(nx_ - 1, static_cast<int>(std::floor((s.c.x + reach) / cell_)));
        const int j0 = std::max(0, static_cast<int>(std::floor((s.c.y - reach) / cell_)));
        const int j1 = std::min(ny_ - 1, static_cast<int>(std::floor((s.c.y + reach) / cell_)));
        Vec2 q;
        for (int j = j0; j <= j1; ++j)
            for (int i = i0; i <= i1; ++i)
                if (nearest_point(s, {(i + 0.5) * cell_, (j + 0.5) * cell_}, &q) < clear_) change(i, j, delta);
    }
    // Add s unless it cuts a start zone off from the destination (then leave the grid as
    // it was and return false). Most obstacles are settled locally: in a window two cells
    // wider than the cells s can block, every pair of border cells (and zone centres and
    // destination cells) that were joined inside the window before must still be joined
    // after; then any path through the window can be rerouted inside it. Otherwise the
    // whole grid is flooded.
    bool add_if_passable(const Shape &s, const Environment &env) {
        const double reach = s.r + clear_;
        const int i0 = std::max(0, static_cast<int>(std::floor((s.c.x - reach) / cell_)) - 2);
        const int i1 = std::min(nx_ - 1, static_cast<int>(std::floor((s.c.x + reach) / cell_)) + 2);
        const int j0 = std::max(0, static_cast<int>(std::floor((s.c.y - reach) / cell_)) - 2);
        const int j1 = std::min(ny_ - 1, static_cast<int>(std::floor((s.c.y + reach) / cell_)) + 2);
        const std::vector<int> before = local_labels(i0, i1, j0, j1);
        add(s, +1);
        const std::vector<int> after = local_labels(i0, i1, j0, j1);
        const int w = i1 - i0 + 1;
        std::vector<int> maps(before.size(), -1);  // before-label -> after-label
        bool local_ok = true;
        const double r2 = env.dest_radius_m * env.dest_radius_m;
        std::vector<char> terminal(before.size(), 0);
        for (const StartZone &z : env.start_zones) {
            const int k = cell_of(z.x_m + z.w_m / 2, z.y_m + z.h_m / 2);
            const int i = k % nx_, j = k / nx_;
            if (i >= i0 && i <= i1 && j >= j0 && j <= j1) terminal[cell_index((j - j0) * w + (i - i0))] = 1;
        }
        for (int j = j0; j <= j1 && local_ok; ++j)
            for (int i = i0; i <= i1 && local_ok; ++i) {
                const std::size_t k = cell_index((j - j0) * w + (i - i0));
                const double dx = (i + 0.5) * cell_ - env.dest_x_m, dy = (j + 0.5) * cell_ - env.dest_y_m;
                const bool term = terminal[k] || i == i0 || i == i1 || j == j0 || j == j1 || dx * dx + dy * dy <= r2;
                if (!term || before[k] < 0) continue;
                const std::size_t label = cell_index(before[k]);  // a component number: >= 0
                if (after[k] < 0) local_ok = false;
                else if (maps[label] < 0) maps[label] = after[k];
                else if (maps[label] != after[k]) local_ok = false;
            }
        if (local_ok || path_m(env) >= 0) return true;
        add(s, -1);
        return false;
    }
    // Longest BFS distance (m) from the destination disc to a zone centre; -1 if one is cut off.
    double path_m(const Environment &env) const {
        int worst = 0;
        for (const int steps : zone_steps(env, free_, nx_, ny_, cell_, false)) {
            if (steps < 0) return -1;
            worst = std::max(worst, steps);
        }
        return worst * cell_;
    }

private:
    // A cell's count changed by delta, and whether it is free with it: the flood reads the
    // free cells as they are, without a pass over the grid to find them each time.
    void change(int i, int j, int delta) {
        const std::size_t k = cell_index(j * nx_ + i);
        blocked_[k] += delta;
        free_[k] = blocked_[k] == 0;
    }
    // Components of the free cells of the window [i0, i1] x [j0, j1] (4-connected,
    // inside the window only); -1 for blocked cells.
    std::vector<int> local_labels(int i0, int i1, int j0, int j1) const {
        const int w = i1 - i0 + 1, h = j1 - j0 + 1;
        std::vector<int> lab(cell_index(w * h), -1);
        std::vector<int> stack;
        int next = 0;
        for (int start = 0; start < w * h; ++start) {
            const int si = start % w + i0, sj = start / w + j0;
            if (lab[cell_index(start)] >= 0 || blocked_[cell_index(sj * nx_ + si)]) continue;
            lab[cell_index(start)] = next;
            stack.push_back(start);
            while (!stack.empty()) {
                const int k = stack.back();
                stack.pop_back();
                const int a = k % w, b = k / w;
                const int da[4] = {1, -1, 0, 0}, db[4] = {0, 0, 1, -1};
                for (int d = 0; d < 4; ++d) {
                    const int x = a + da[d], y = b + db[d];
                    if (x < 0 || y < 0 || x >= w || y >= h) continue;
                    const int m = y * w + x;
                    if (lab[cell_index(m)] < 0 && !blocked_[cell_index((y + j0) * nx_ + (x + i0))]) {
                        lab[cell_index(m)] = next;
                        stack.push_back(m);
                    }
                }
            }
            ++next;
        }
        return lab;
    }
    int cell_of(double x, double y) const {
        const int i = std::clamp(static_cast<int>(x / cell_), 0, nx_ - 1);
        const int j = std::clamp(static_cast<int>(y / cell_), 0, ny_ - 1);
        return j * nx_ + i;
    }
    double w_, h_, clear_, cell_;
    int nx_, ny_;
    std::vector<int> blocked_;
    std::vector<char> free_;  // blocked_ == 0, kept with it
};

// ---- what every builder shares --------------------------------------------------------

struct Ctx {
    Rng &rng;
    double radius;  // robot body radius, m
    double diam;    // robot diameter, m
    double s;       // size scale of the arena for bigger robots (1 for a TekBot)
    double d;       // difficulty in [0, 1]
    WorldNotes notes;
    double uni(double lo, double hi) { return rng.uniform(lo, hi); }
    int pick(int n) { return std::min(n - 1, static_cast<int>(rng.uniform01() * n)); }
    // A width of k robot diameters, jittered by +-0.25 diameter.
    double widths(double k) { return diam * (k + uni(-0.25, 0.25)); }
};

StartZone zone_at(double cx, double cy, double w, double h) {
    return {cx - w / 2, cy - h / 2, std::max(0.0, w), std::max(0.0, h)};
}

Vec2 zone_centre(const StartZone &z) { return {z.x_m + z.w_m / 2, z.y_m + z.h_m / 2}; }

// A wall from a to b, thick, ends extended by thick/2 so that walls meeting at a point
// close the corner.
BoxObstacle wall(Vec2 a, Vec2 b, double thick) {
    const Vec2 m = 0.5 * (a + b);
    const double len = norm(b - a);
    double ang = std::atan2(b.y - a.y, b.x - a.x) * 180.0 / kPi;
    if (ang < 0) ang += 180.0;
    if (ang >= 180.0) ang -= 180.0;
    return {m.x, m.y, len + thick, thick, ang};
}

Shape shape_of(const BoxObstacle &b) { return make_box(b.x_m, b.y_m, b.w_m, b.h_m, b.angle_deg); }
Shape shape_of(const CircleObstacle &c) { return make_circle(c.x_m, c.y_m, c.r_m); }

// Start zones spread along the bottom band: n zones in n equal slots of the width.
void bottom_zones(Ctx &c, Environment &env, int n) {
    const double margin = c.radius + 0.15;
    const double slot = env.width_m / n;
    for (int k = 0; k < n; ++k) {
        const double w = std::min(c.uni(1.0, 2.0) * c.s, slot - 2 * margin);
        const double h = c.uni(0.6, 1.0) * c.s;
        const double x = k * slot + margin + c.uni(0, std::max(0.0, slot - 2 * margin - w));
        const double y = margin + c.uni(0.0, 0.4) * c.s;
        env.start_zones.push_back({x, y, std::max(0.0, w), h});
    }
}

void top_destination(Ctx &c, Environment &env) {
    env.dest_radius_m = 0.4 * c.s;
    env.dest_x_m = c.uni(1.0 * c.s, env.width_m - 1.0 * c.s);
    env.dest_y_m = env.height_m - c.uni(0.8, 1.4) * c.s;
}

// The band of the arena between the start zones (along the bottom) and the destination
// (at the top), kept two robot radii and 0.4 m (times the size scale) from both: where
// gaps' walls and shelves' rows go.
struct Band {
    double lo, hi;
};
Band band_between(const Ctx &c, const Environment &env) {
    double ztop = 0;
    for (const StartZone &z : env.start_zones) ztop = std::max(ztop, z.y_m + z.h_m);
    return {ztop + c.radius * 2 + 0.4 * c.s, env.dest_y_m - env.dest_radius_m - c.radius * 2 - 0.4 * c.s};
}

// Scatter circles and boxes over [x0, x1] x [y0, y1] until they cover `coverage` of that
// area or `tries` draws were made. An obstacle is kept only when it overlaps no other
// obstacle, keeps 2 robot radii plus (1 - difficulty) x 0.6 m (times the size scale)
// from start zones, the destination and every keep-out shape (easy worlds leave room to
// start and to arrive), and the grid still connects every start zone to the destination.
void scatter(Ctx &c, Environment &env, PassGrid &grid, double x0, double y0, double x1, double y1,
             double coverage, int tries, const std::vector<Shape> &keepout) {
    std::vector<Shape> placed = env.obstacle_shapes();
    const double target = coverage * (x1 - x0) * (y1 - y0);
    const Shape dest = make_circle(env.dest_x_m, env.dest_y_m, env.dest_radius_m);
    double covered = 0;
    for (int t = 0; t < tries && covered < target; ++t) {
        const bool circle = c.rng.uniform01() < 0.5;
        const double x = c.uni(x0, x1), y = c.uni(y0, y1);
        Shape s;
        double area;
        CircleObstacle co{};
        BoxObstacle bo{};
        if (circle) {
            co = {x, y, c.uni(0.1, 0.45) * c.s};
            s = shape_of(co);
            area = kPi * co.r_m * co.r_m;
        } else {
            bo = {x, y, c.uni(0.2, 1.4) * c.s, c.uni(0.2, 1.0) * c.s, std::floor(c.uni(0.0, 12.0)) * 15.0};
            s = shape_of(bo);
            area = bo.w_m * bo.h_m;
        }
        const double room = 2 * c.radius + (1.0 - c.d) * 0.6 * c.s;
        bool bad = shape_distance(s, dest) < room;
        for (const StartZone &z : env.start_zones)
            if (!bad && shape_distance(s, make_box(z.x_m + z.w_m / 2, z.y_m + z.h_m / 2, z.w_m, z.h_m, 0)) < room)
                bad = true;
        for (const Shape &k : keepout)
            if (!bad && shape_distance(s, k) < room) bad = true;
        for (const Shape &o : placed)
            if (!bad && norm(o.c - s.c) < o.r + s.r && shape_distance(o, s) <= 0.0) bad = true;
        if (bad) continue;
        if (!grid.add_if_passable(s, env)) continue;
        if (circle)
            env.circles.push_back(co);
        else
            env.boxes.push_back(bo);
        placed.push_back(s);
        covered += area;
    }
}

// The builders' grid is 0.075 m stricter than the final check: the symmetry applied
// afterwards shifts the cells by up to cell/2 along each axis (< 0.071 m), and a free path
// on this grid then stays free on that one.
PassGrid grid_for(const Ctx &c, const Environment &env) {
    PassGrid g(env.width_m, env.height_m, c.radius + kCell / 2 + 0.75 * kCell, kCell);
    for (const Shape &s : env.obstacle_shapes()) g.add(s, +1);
    return g;
}

// ---- the families ---------------------------------------------------------------------

// clutter: circles and boxes anywhere in the arena; difficulty d -> covered fraction
// 0.04 + 0.36 d^1.5 (0.04, 0.085, 0.17, 0.27, 0.40 at d = 0, 0.25, 0.5, 0.75, 1;
// data/envs/dense.toml covers 0.12 of its arena).
void build_clutter(Ctx &c, Environment &env) {
    env.width_m = c.uni(8, 14) * c.s;
    env.height_m = c.uni(8, 14) * c.s;
    bottom_zones(c, env, 1 + c.pick(3));
    top_destination(c, env);
    PassGrid grid = grid_for(c, env);
    scatter(c, env, grid, 0, 0, env.width_m, env.height_m, 0.04 + 0.36 * c.d * std::sqrt(c.d), 6000, {});
}

// gaps: 1-4 walls across the arena, each with one gap of 2.75 (difficulty 1) to 7.25
// (difficulty 0) robot diameters, the gap offset from the straight line start -> goal to
// alternating sides.
void build_gaps(Ctx &c, Environment &env) {
    env.width_m = c.uni(7, 12) * c.s;
    env.height_m = c.uni(9, 14) * c.s;
    bottom_zones(c, env, 1 + c.pick(2));
    top_destination(c, env);
    double zx = 0;
    for (const StartZone &z : env.start_zones) zx += zone_centre(z).x / static_cast<double>(env.start_zones.size());
    const auto [lo, hi] = band_between(c, env);
    const int walls = std::clamp(1 + static_cast<int>(c.d * 2.5 + c.uni(0, 1.5)), 1,
                                 std::max(1, static_cast<int>((hi - lo) / (1.6 * c.s))));
    const double thick = c.uni(0.1, 0.25) * c.s;
    double side = c.rng.uniform01() < 0.5 ? -1 : 1;
    for (int k = 0; k < walls; ++k) {
        const double y = lo + (hi - lo) * (k + 0.5 + c.uni(-0.2, 0.2)) / walls;
        const double f = (y - zone_centre(env.start_zones[0]).y) / (env.dest_y_m - zone_centre(env.start_zones[0]).y);
        const double xline = zx + f * (env.dest_x_m - zx);
        const double g = c.widths(2.75 + 4.5 * (1.0 - c.d));
        const double off = std::max(g / 2 + c.diam, (0.12 + 0.25 * c.d) * env.width_m * c.uni(0.7, 1.3));
        const double edge = thick + g / 2 + c.radius;
        double gx = xline + side * off;
        if (gx < edge || gx > env.width_m - edge) gx = xline - side * off;
        gx = std::clamp(gx, edge, env.width_m - edge);
        side = -side;
        if (gx - g / 2 > 0.01) env.boxes.push_back(wall({0, y}, {gx - g / 2 - thick / 2, y}, thick));
        if (env.width_m - (gx + g / 2) > 0.01)
            env.boxes.push_back(wall({gx + g / 2 + thick / 2, y}, {env.width_m, y}, thick));
    }
}

// corridor, serpentine: baffles from alternating side walls leave a corridor of 3
// (difficulty 1) to 7 robot diameters that turns at every baffle's free end; half of
// the layouts tilt every baffle by 8-20 deg (a zig-zag).
void build_serpentine(Ctx &c, Environment &env) {
    const double cw = c.widths(3.0 + 4.0 * (1.0 - c.d));
    const int baffles = 2 + static_cast<int>(c.d * 3 + c.uni(0, 1.5));
    const double thick = 0.15 * c.s;
    const double tilt = c.rng.uniform01() < 0.5 ? 0.0 : c.uni(8, 20) * kPi / 180.0;
    env.width_m = c.uni(6, 11) * c.s;
    const double span = env.width_m - cw;                    // baffle length
    const double rise = std::tan(tilt) * span;               // height a tilted baffle climbs
    const double lane = cw / std::cos(tilt) * c.uni(1.0, 1.3) + thick;  // baffle spacing
    const double end_lane = std::max(lane, 1.2 * c.s) + rise;
    env.height_m = 2 * end_lane + (baffles - 1) * lane;
    for (int k = 0; k < baffles; ++k) {
        const double y = end_lane + k * lane;
        const bool from_left = (k % 2) == 0;
        const double xa = from_left ? 0.0 : cw, xb = from_left ? span : env.width_m;
        env.boxes.push_back(wall({xa, y - rise / 2}, {xb, y + rise / 2}, thick));
    }
    // Start under the first baffle at its wall end, destination over the last one at the
    // far end from where the corridor enters the top lane.
    const double free_lo = end_lane - rise - thick / 2;  // height of the bottom lane's low side
    const double zh = std::clamp(free_lo - 2 * (c.radius + 0.15), 0.0, 0.8 * c.s);
    const double zw = c.uni(0.8, 1.5) * c.s;
    const double zx = c.radius + 0.2 + zw / 2 + c.uni(0, 0.5) * c.s;
    env.start_zones.push_back(zone_at(zx, c.radius + 0.15 + zh / 2, zw, zh));
    const bool last_from_left = ((baffles - 1) % 2) == 0;
    env.dest_radius_m = std::min(0.4 * c.s, (end_lane - rise - thick) / 2 - 0.05);
    env.dest_x_m = last_from_left ? env.dest_radius_m + 0.3 * c.s : env.width_m - env.dest_radius_m - 0.3 * c.s;
    env.dest_y_m = env.height_m - (end_lane - rise) / 2 + thick / 4;
}

// corridor, maze: a cellular automaton (the "Maze" rule B3/S12345, 12 generations from
// 40-48 % random walls) on a grid of cells 3 (difficulty 1) to 6 robot diameters wide,
// a random walk from the start cell carved to the destination's cell so that the two
// are joined, wall cells merged into boxes row by row.
void build_maze(Ctx &c, Environment &env) {
    const double cell = c.widths(3.0 + 3.0 * (1.0 - c.d));
    const int nx = std::max(5, static_cast<int>(c.uni(8, 13) * c.s / cell));
    const int ny = std::max(5, static_cast<int>(c.uni(8, 13) * c.s / cell));
    env.width_m = nx * cell;
    env.height_m = ny * cell;
    std::vector<char> wallc(cell_index(nx * ny));
    auto at = [&](int i, int j) -> char & { return wallc[cell_index(j * nx + i)]; };
    const double p = 0.40 + 0.08 * c.d;
    for (char &w : wallc) w = c.rng.uniform01() < p;
    for (int gen = 0; gen < 12; ++gen) {
        std::vector<char> next(wallc.size());
        for (int j = 0; j < ny; ++j)
            for (int i = 0; i < nx; ++i) {
                int n = 0;
                for (int b = j - 1; b <= j + 1; ++b)
                    for (int a = i - 1; a <= i + 1; ++a)
                        if ((a != i || b != j) && a >= 0 && b >= 0 && a < nx && b < ny) n += at(a, b);
                next[cell_index(j * nx + i)] = at(i, j) ? (n >= 1 && n <= 5) : (n == 3);
            }
        wallc.swap(next);
    }
    const int si = c.pick(nx), sj = 0, gi = c.pick(nx), gj = ny - 1;
    // Carve: a walk that steps toward the goal cell with probability 0.6.
    int i = si, j = sj;
    at(i, j) = 0;
    while (i != gi || j != gj) {
        if (c.rng.uniform01() < 0.6) {
            if (i != gi && (j == gj || c.rng.uniform01() < 0.5))
                i += gi > i ? 1 : -1;
            else
                j += gj > j ? 1 : -1;
        } else {
            const int d = c.pick(4);
            i = std::clamp(i + (d == 0) - (d == 1), 0, nx - 1);
            j = std::clamp(j + (d == 2) - (d == 3), 0, ny - 1);
        }
        at(i, j) = 0;
    }
    for (int b = 0; b < ny; ++b) {
        for (int a = 0; a < nx;) {
            if (!at(a, b)) {
                ++a;
                continue;
            }
            int e = a;
            while (e < nx && at(e, b)) ++e;
            env.boxes.push_back({(a + e) * cell / 2, (b + 0.5) * cell, (e - a) * cell, cell, 0.0});
            a = e;
        }
    }
    const double zw = std::max(0.0, cell - 2 * (c.radius + 0.1));
    env.start_zones.push_back(zone_at((si + 0.5) * cell, 0.5 * cell, zw, zw));
    env.dest_radius_m = std::min(0.4 * c.s, cell / 2 - 0.02);
    env.dest_x_m = (gi + 0.5) * cell;
    env.dest_y_m = (gj + 0.5) * cell;
}

void build_corridor(Ctx &c, Environment &env) {
    if (c.rng.uniform01() < 0.5)
        build_serpentine(c, env);
    else
        build_maze(c, env);
}

// A U of three walls whose opening faces -u (towards the start): the bottom centred on
// `bottom` across u, inner width wi, arms of length depth. Indices go to the notes when
// `note`.
void add_pocket(Ctx &c, Environment &env, Vec2 bottom, Vec2 u, double wi, double depth, double thick, bool note) {
    const Vec2 n{-u.y, u.x};
    const double half = wi / 2 + thick / 2;
    const Vec2 l = bottom + half * n, r = bottom - half * n;
    if (note) c.notes.pocket_bottoms.push_back(env.boxes.size());
    env.boxes.push_back(wall(l, r, thick));
    if (note) c.notes.pocket_arms.push_back(env.boxes.size());
    env.boxes.push_back(wall(l, l - depth * u, thick));
    if (note) c.notes.pocket_arms.push_back(env.boxes.size());
    env.boxes.push_back(wall(r, r - depth * u, thick));
}

// pocket: a U-pocket straight across the line from the start zone to the destination,
// its opening toward the start (a local minimum for a robot heading straight for the
// goal), inner width 4-10 robot diameters and depth growing with difficulty; up to two
// more dead ends facing the start elsewhere; clutter of 0.02-0.10 coverage kept out of
// the straight line's approach to the pocket.
void build_pocket(Ctx &c, Environment &env) {
    env.width_m = c.uni(9, 14) * c.s;
    env.height_m = c.uni(10, 15) * c.s;
    const double thick = c.uni(0.1, 0.2) * c.s;
    const double wi = c.diam * c.uni(4.0, 6.0 + 4.0 * c.d);
    const double depth = wi * c.uni(0.5, 0.6 + 0.6 * c.d) + 0.5 * c.s;
    const double zw = wi * c.uni(0.3, 0.5), zh = c.uni(0.4, 0.8) * c.s;
    const double zx = c.uni(wi / 2 + 1.0 * c.s, env.width_m - wi / 2 - 1.0 * c.s);
    const double zy = c.radius + 0.2 + zh / 2 + c.uni(0.0, 0.5) * c.s;
    env.start_zones.push_back(zone_at(zx, zy, zw, zh));
    env.dest_radius_m = 0.4 * c.s;
    env.dest_x_m = std::clamp(zx + c.uni(-1.0, 1.0) * c.s, 1.0 * c.s, env.width_m - 1.0 * c.s);
    env.dest_y_m = env.height_m - c.uni(0.8, 1.4) * c.s;
    const Vec2 start{zx, zy}, goal{env.dest_x_m, env.dest_y_m};
    const double len = norm(goal - start);
    const Vec2 u = (1.0 / len) * (goal - start);
    // The bottom between the mouth (depth before it, clear of the zone) and the goal.
    const double lo = zh / 2 + 0.8 * c.s + depth, hi = len - env.dest_radius_m - 1.0 * c.s - thick;
    const Vec2 bottom = start + std::clamp(c.uni(lo, hi), lo, std::max(lo, hi)) * u;
    add_pocket(c, env, bottom, u, wi, depth, thick, true);
    // The straight lines from the zone's centre and corners to the goal stay free of
    // clutter up to the pocket's bottom.
    std::vector<Shape> keepout;
    for (const Vec2 p : {start, Vec2{zx - zw / 2, zy - zh / 2}, Vec2{zx + zw / 2, zy - zh / 2},
                         Vec2{zx - zw / 2, zy + zh / 2}, Vec2{zx + zw / 2, zy + zh / 2}}) {
        const Vec2 up = (1.0 / norm(goal - p)) * (goal - p);
        keepout.push_back(make_segment(p, p + (dot(bottom - p, u) / dot(up, u)) * up));
    }
    for (const BoxObstacle &b : env.boxes) keepout.push_back(shape_of(b));
    std::vector<Shape> avoid = keepout;
    avoid.push_back(make_circle(goal.x, goal.y, env.dest_radius_m));
    avoid.push_back(make_box(zx, zy, zw, zh, 0.0));
    const int dead_ends = static_cast<int>(c.d * 2 + c.uni(0, 1));
    for (int k = 0; k < dead_ends; ++k) {
        const double w2 = c.diam * c.uni(3.0, 6.0), d2 = w2 * c.uni(0.6, 1.2);
        const Vec2 b2{c.uni(w2, env.width_m - w2), c.uni(zy + d2 + 1.0 * c.s, env.height_m - 0.5 * c.s)};
        Environment trial = env;
        add_pocket(c, trial, b2, {0, 1}, w2, d2, thick, false);
        bool clear = true;
        for (std::size_t i = env.boxes.size(); i < trial.boxes.size(); ++i)
            for (const Shape &k2 : avoid)
                if (shape_distance(shape_of(trial.boxes[i]), k2) < 2 * c.diam) clear = false;
        if (clear) env = std::move(trial);
    }
    PassGrid grid = grid_for(c, env);
    scatter(c, env, grid, 0, 0, env.width_m, env.height_m, 0.02 + 0.08 * c.d, 1500, keepout);
}

// rooms: a 2-3 x 2-3 grid of rooms (3-4.5 m sides) whose shared walls have doors of 2.75
// (difficulty 1) to 6.25 robot diameters: a random spanning tree of doors joins every
// room, extra doors with probability 0.5 (1 - difficulty); furniture of 0.0-0.08
// coverage. Start in a room of the bottom row, destination in one of the top row.
void build_rooms(Ctx &c, Environment &env) {
    const int nx = 2 + c.pick(2), ny = 2 + c.pick(2);
    const double rw = c.uni(3.0, 4.5) * c.s, rh = c.uni(3.0, 4.5) * c.s;
    const double thick = 0.12 * c.s;
    env.width_m = nx * rw;
    env.height_m = ny * rh;
    // Walls between rooms a and b: index by the lower/left room and orientation.
    const int rooms = nx * ny;
    std::vector<char> door_v(static_cast<std::size_t>(rooms), 0), door_h(static_cast<std::size_t>(rooms), 0);
    std::vector<char> seen(static_cast<std::size_t>(rooms), 0);
    std::vector<int> stack{c.pick(rooms)};
    seen[cell_index(stack[0])] = 1;
    while (!stack.empty()) {  // random depth-first spanning tree
        const int r = stack.back(), i = r % nx, j = r / nx;
        int opts[4], n = 0;
        if (i + 1 < nx && !seen[cell_index(r + 1)]) opts[n++] = 0;
        if (i > 0 && !seen[cell_index(r - 1)]) opts[n++] = 1;
        if (j + 1 < ny && !seen[cell_index(r + nx)]) opts[n++] = 2;
        if (j > 0 && !seen[cell_index(r - nx)]) opts[n++] = 3;
        if (n == 0) {
            stack.pop_back();
            continue;
        }
        const int o = opts[c.pick(n)];
        const int next = o == 0 ? r + 1 : o == 1 ? r - 1 : o == 2 ? r + nx : r - nx;
        if (o == 0) door_v[cell_index(r)] = 1;
        if (o == 1) door_v[cell_index(r - 1)] = 1;
        if (o == 2) door_h[cell_index(r)] = 1;
        if (o == 3) door_h[cell_index(r - nx)] = 1;
        seen[cell_index(next)] = 1;
        stack.push_back(next);
    }
    const double extra = 0.5 * (1.0 - c.d);
    auto segment = [&](Vec2 a, Vec2 b, bool door) {
        if (!door) {
            env.boxes.push_back(wall(a, b, thick));
            return;
        }
        const double len = norm(b - a), dw = c.widths(2.75 + 3.5 * (1.0 - c.d));
        const double margin = thick + 0.3 * c.s;
        const double at = margin + c.uni(0, std::max(0.0, len - 2 * margin - dw));
        const Vec2 u = (1.0 / len) * (b - a);
        env.boxes.push_back(wall(a, a + (at - thick / 2) * u, thick));
        env.boxes.push_back(wall(a + (at + dw + thick / 2) * u, b, thick));
    };
    for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
            const std::size_t r = cell_index(j * nx + i);
            if (i + 1 < nx)
                segment({(i + 1) * rw, j * rh}, {(i + 1) * rw, (j + 1) * rh}, door_v[r] || c.rng.uniform01() < extra);
            if (j + 1 < ny)
                segment({i * rw, (j + 1) * rh}, {(i + 1) * rw, (j + 1) * rh}, door_h[r] || c.rng.uniform01() < extra);
        }
    const int si = c.pick(nx), gi = c.pick(nx);
    const double margin = c.radius + thick / 2 + 0.2;
    const double zw = std::min(c.uni(0.8, 1.6) * c.s, rw - 2 * margin), zh = std::min(c.uni(0.6, 1.0) * c.s, rh - 2 * margin);
    env.start_zones.push_back({si * rw + margin + c.uni(0, rw - 2 * margin - zw), margin + c.uni(0, rh / 2 - margin), zw, zh});
    env.dest_radius_m = 0.4 * c.s;
    const double dm = env.dest_radius_m + thick / 2 + 2 * c.radius + 0.1;
    env.dest_x_m = gi * rw + c.uni(dm, rw - dm);
    env.dest_y_m = (ny - 1) * rh + c.uni(dm, rh - dm);
    PassGrid grid = grid_for(c, env);
    scatter(c, env, grid, 0, 0, env.width_m, env.height_m, 0.08 * c.d, 800, {});
}

// shelves: rows of shelving across the arena (a store room, a warehouse), each broken by
// 1-2 openings of 4.5 (difficulty 0) to 3 (difficulty 1) robot diameters anywhere along
// it, at its ends too; aisles of 5 -> 3 diameters between rows; boxes left in
// the aisles (covered fraction 0.01 -> 0.04). The way runs along aisles to openings that
// a robot heading for its goal does not see: a search over long parallel walls, which no
// other family has.
void build_shelves(Ctx &c, Environment &env) {
    env.width_m = c.uni(9, 14) * c.s;
    env.height_m = c.uni(9, 14) * c.s;
    bottom_zones(c, env, 1 + c.pick(2));
    top_destination(c, env);
    const auto [lo, hi] = band_between(c, env);
    for (double y = lo + c.uni(0, 0.3) * c.s;;) {
        const double depth = c.uni(0.4, 0.8) * c.s;
        if (y + depth > hi) break;
        const auto piece = [&](double x0, double x1) {  // shelving from x0 to x1, if any
            if (x1 - x0 > 0.05) env.boxes.push_back({(x0 + x1) / 2, y + depth / 2, x1 - x0, depth, 0});
        };
        const int n = 1 + (c.rng.uniform01() < 0.6 * (1.0 - c.d) ? 1 : 0);
        double from = 0;  // the row's next piece begins here
        for (int k = 0; k < n; ++k) {
            const double g = c.widths(4.5 - 1.5 * c.d);
            const double slot = (env.width_m - from) / (n - k);
            const double at = from + c.uni(0, std::max(0.0, slot - g));
            piece(from, at);
            from = at + g;
        }
        piece(from, env.width_m);
        y += depth + c.widths(5.0 - 2.0 * c.d);
    }
    PassGrid grid = grid_for(c, env);
    scatter(c, env, grid, 0, 0, env.width_m, env.height_m, 0.01 + 0.03 * c.d, 800, {});
}

// ---- the family table and the symmetry ------------------------------------------------

struct Family {
    const char *name;
    void (*build)(Ctx &, Environment &);
    std::uint64_t stream;  // random stream of the family, so families do not share layouts
};
constexpr Family kFamilies[] = {
    {"clutter", build_clutter, 0x636c7574},
    {"gaps", build_gaps, 0x67617073},
    {"corridor", build_corridor, 0x636f7272},
    {"pocket", build_pocket, 0x706f636b},
    {"rooms", build_rooms, 0x726f6f6d},
    {"shelves", build_shelves, 0x7368656c},
};

const Family *find_family(std::string_view name) {
    for (const Family &f : kFamilies)
        if (name == f.name) return &f;
    return nullptr;
}

// One of the 8 symmetries of the rectangle (rotations by 90 deg, mirrors), so that the
// start is not always at the bottom.
void apply_symmetry(Environment &env, int k) {
    const bool mirror = k & 1;
    const int quarter = k >> 1;
    auto flip = [&](double &x, double &angle) {
        x = env.width_m - x;
        angle = -angle;
    };
    auto turn = [&](double &x, double &y, double &angle) {  // 90 deg counter-clockwise
        const double nx = env.height_m - y, ny = x;
        x = nx;
        y = ny;
        angle += 90.0;
    };
    auto norm_angle = [](double a) {
        a = std::fmod(a, 180.0);
        return a < 0 ? a + 180.0 : a;
    };
    double none = 0;
    if (mirror) {
        for (auto &c : env.circles) flip(c.x_m, none);
        for (auto &b : env.boxes) flip(b.x_m, b.angle_deg);
        for (auto &z : env.start_zones) {
            z.x_m = env.width_m - z.x_m - z.w_m;
        }
        flip(env.dest_x_m, none);
    }
    for (int q = 0; q < quarter; ++q) {
        for (auto &c : env.circles) turn(c.x_m, c.y_m, none);
        for (auto &b : env.boxes) turn(b.x_m, b.y_m, b.angle_deg);
        for (auto &z : env.start_zones) {
            const StartZone o = z;
            z = {env.height_m - (o.y_m + o.h_m), o.x_m, o.h_m, o.w_m};
        }
        turn(env.dest_x_m, env.dest_y_m, none);
        std::swap(env.width_m, env.height_m);
    }
    for (auto &b : env.boxes) b.angle_deg = norm_angle(b.angle_deg);
}

std::string fail_spec(std::string_view spec, const std::string &what) {
    return "world spec '" + std::string(spec) + "': " + what;
}

}  // namespace

// ---- public ---------------------------------------------------------------------------

bool is_world_spec(std::string_view spec) { return spec.substr(0, sizeof kPrefix - 1) == kPrefix; }

const char *world_family_names() {
    static const std::string names = [] {
        std::string s;
        for (const Family &f : kFamilies) s += (s.empty() ? "" : ", ") + std::string(f.name);
        return s;
    }();
    return names.c_str();
}

WorldSpec parse_world_spec(std::string_view spec) {
    const char *grammar = "expected gen:FAMILY:SEED[:DIFFICULTY[:ROBOT]]";
    if (!is_world_spec(spec)) throw SimError(QNAV_SIM_E_PARAM, fail_spec(spec, grammar));
    // Split into at most four fields after "gen:"; the robot (last) may hold ':' (a path).
    std::vector<std::string_view> f;
    std::string_view rest = spec.substr(sizeof kPrefix - 1);
    while (f.size() < 3) {
        const std::size_t colon = rest.find(':');
        if (colon == std::string_view::npos) break;
        f.push_back(rest.substr(0, colon));
        rest = rest.substr(colon + 1);
    }
    f.push_back(rest);
    if (f.size() < 2) throw SimError(QNAV_SIM_E_PARAM, fail_spec(spec, std::string(grammar) + " (no seed)"));
    for (std::size_t k = 0; k < f.size(); ++k)
        if (f[k].empty())
            throw SimError(QNAV_SIM_E_PARAM, fail_spec(spec, std::string(k == 0 ? "family" : k == 1 ? "seed" : k == 2 ? "difficulty" : "robot") + " is empty (" + grammar + ")"));
    WorldSpec w;
    if (!find_family(f[0]))
        throw SimError(QNAV_SIM_E_PARAM, fail_spec(spec, "unknown family '" + std::string(f[0]) + "' (families: " + world_family_names() + ")"));
    w.family = std::string(f[0]);
    // Seed: decimal digits only, no sign, no overflow.
    const std::string seed_msg = "seed '" + std::string(f[1]) + "' is not a whole number in [0, 18446744073709551615]";
    if (f[1].size() > 20) throw SimError(QNAV_SIM_E_PARAM, fail_spec(spec, seed_msg));
    std::uint64_t seed = 0;
    for (char ch : f[1]) {
        if (ch < '0' || ch > '9') throw SimError(QNAV_SIM_E_PARAM, fail_spec(spec, seed_msg));
        const std::uint64_t digit = static_cast<std::uint64_t>(ch - '0');
        if (seed > (UINT64_MAX - digit) / 10) throw SimError(QNAV_SIM_E_PARAM, fail_spec(spec, seed_msg));
        seed = seed * 10 + digit;
    }
    w.seed = seed;
    if (f.size() >= 3) {
        // Difficulty: "0", "1", "1.0", "0.5", ".25", "0.125": at most three decimals, in [0, 1].
        const std::string_view d = f[2];
        const std::string msg = "difficulty '" + std::string(d) + "' is not a number in [0, 1] with at most 3 decimals";
        const std::size_t dot = d.find('.');
        const std::string_view ip = d.substr(0, dot), fp = dot == std::string_view::npos ? std::string_view() : d.substr(dot + 1);
        auto digits = [](std::string_view s) {
            return std::all_of(s.begin(), s.end(), [](char ch) { return ch >= '0' && ch <= '9'; });
        };
        if (!digits(ip) || !digits(fp) || fp.size() > 3 || (ip.empty() && fp.empty()) ||
            (dot != std::string_view::npos && fp.empty()) || ip.size() > 6)
            throw SimError(QNAV_SIM_E_PARAM, fail_spec(spec, msg));
        int whole = 0;
        for (char ch : ip) whole = whole * 10 + (ch - '0');
        int milli = 0, scale = 100;
        for (char ch : fp) {
            milli += (ch - '0') * scale;
            scale /= 10;
        }
        if (whole > 1 || (whole == 1 && milli > 0)) throw SimError(QNAV_SIM_E_PARAM, fail_spec(spec, msg));
        w.difficulty_milli = whole * 1000 + milli;
    }
    if (f.size() == 4) w.robot = std::string(f[3]);
    return w;
}

std::string world_spec_name(const WorldSpec &w) {
    char d[16];
    if (w.difficulty_milli % 1000 == 0)
        std::snprintf(d, sizeof d, "%d", w.difficulty_milli / 1000);
    else {
        std::snprintf(d, sizeof d, "0.%03d", w.difficulty_milli);
        std::size_t n = std::char_traits<char>::length(d);
        while (n > 0 && d[n - 1] == '0') d[--n] = '\0';
    }
    return std::string(kPrefix) + w.family + ":" + std::to_string(w.seed) + ":" + d + ":" + w.robot;
}

double passable_path_m(const Environment &env, double clearance_m, double cell_m) {
    PassGrid g(env.width_m, env.height_m, clearance_m, cell_m);
    for (const Shape &s : env.obstacle_shapes()) g.add(s, +1);
    return g.path_m(env);
}

Environment generate_world(const WorldSpec &w, const RobotProfile &robot, WorldNotes *notes) {
    const Family *fam = find_family(w.family);
    const std::string name = world_spec_name(w);
    if (!fam)
        throw SimError(QNAV_SIM_E_PARAM, fail_spec(name, "unknown family '" + w.family + "' (families: " + world_family_names() + ")"));
    if (w.difficulty_milli < 0 || w.difficulty_milli > 1000)
        throw SimError(QNAV_SIM_E_PARAM, fail_spec(name, "difficulty outside [0, 1]"));
    const double diam = 2 * robot.radius_m;
    for (int attempt = 0; attempt < kMaxAttempts; ++attempt) {
        Rng rng = Rng::stream(w.seed, fam->stream, static_cast<std::uint64_t>(attempt));
        Ctx c{rng, robot.radius_m, diam, std::max(1.0, std::sqrt(diam / 0.24)), w.difficulty_milli / 1000.0, {}};
        Environment env;
        env.name = name;
        fam->build(c, env);
        apply_symmetry(env, c.pick(8));
        env.episode_limit_s = 30;
        Environment parsed;
        try {
            parsed = parse_environment(environment_to_toml(env), name);
            check_zone_clearance(parsed, robot.radius_m);
        } catch (const SimError &) {
            continue;  // a layout whose zone or destination came out blocked: draw again
        }
        // A path for a disc wider than the robot: check_clearance's walled-in test (the
        // robot's own radius blocks no more cells and floods from no fewer) passes too.
        const double path = passable_path_m(parsed, robot.radius_m + kCell / 2, kCell);
        if (path < 0) continue;
        parsed.clearance_checked_m = robot.radius_m;
        // Time limit: twice the grid path at full speed plus 10 s, to 5 s, at least 30 s.
        parsed.episode_limit_s = std::max(30.0, 5.0 * std::ceil((2.0 * path / robot.v_max_mps + 10.0) / 5.0));
        if (notes) {
            *notes = c.notes;
            notes->attempt = attempt;
            notes->path_m = path;
        }
        return parsed;
    }
    throw SimError(QNAV_SIM_E_WORLD, fail_spec(name, "no passable layout in " + std::to_string(kMaxAttempts) + " attempts"));
}

// The profile in the robot file at path: parsed again only when the file's text differs
// from the last one this thread parsed. A distribution makes a world per episode, each
// for the same profile, and parsing it was 2 % of `simevo run generalist`'s instructions.
static const RobotProfile &robot_profile_at(const std::string &path) {
    thread_local std::string last_path, last_text;
    thread_local RobotProfile last;
    std::string text = TomlReader::read_file(path);
    if (text != last_text || path != last_path) {
        last = parse_robot_profile(text, path);
        last_text = std::move(text);
        last_path = path;
    }
    return last;
}

Environment load_world(std::string_view spec, WorldNotes *notes) {
    const WorldSpec w = parse_world_spec(spec);
    std::string base = w.robot;  // worlds are sized for the body: NAME+map and NAME-map as NAME
    robot_spec_map(w.robot, &base);
    const std::string path = resolve_data_spec(base.c_str(), "robots");
    RobotProfile robot;
    try {
        robot = robot_profile_at(path);
    } catch (const SimError &e) {
        throw SimError(e.status(), fail_spec(spec, std::string("robot: ") + e.what()));
    }
    return generate_world(w, robot, notes);
}

}  // namespace qnav
