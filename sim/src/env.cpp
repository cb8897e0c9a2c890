// Environment files: parsing and checking, the random generator and the TOML writer.
#include "env.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "error.hpp"
#include "qnav/rng.hpp"
#include "tomlread.hpp"

namespace qnav {

std::vector<Shape> Environment::obstacle_shapes() const {
    std::vector<Shape> out;
    out.reserve(circles.size() + boxes.size());
    for (const auto &c : circles) out.push_back(make_circle(c.x_m, c.y_m, c.r_m));
    for (const auto &b : boxes) out.push_back(make_box(b.x_m, b.y_m, b.w_m, b.h_m, b.angle_deg));
    return out;
}

std::vector<Shape> Environment::wall_shapes() const {
    const Vec2 a{0, 0}, b{width_m, 0}, c{width_m, height_m}, d{0, height_m};
    return {make_segment(a, b), make_segment(b, c), make_segment(c, d), make_segment(d, a)};
}

static Shape zone_shape(const StartZone &z) {
    return make_box(z.x_m + z.w_m / 2, z.y_m + z.h_m / 2, z.w_m, z.h_m, 0.0);
}

static std::string line_prefix(const std::string &name, int line) {
    return name + ":" + std::to_string(line) + ": ";
}

// The [[key]] tables of the root, or null when there are none (an error when required).
static const toml::array *array_of_tables(const TomlReader &r, const char *key, bool required) {
    const toml::table &root = r.root();
    const toml::node *n = root.get(key);
    if (!n) {
        if (required) r.fail(root, std::string("missing [[") + key + "]] (at least one)");
        return nullptr;
    }
    const toml::array *a = n->as_array();
    if (!a || !a->is_array_of_tables())
        r.fail(*n, std::string("'") + key + "' must be written as [[" + key + "]] tables");
    return a;
}

static int source_line(const toml::table &t) { return static_cast<int>(t.source().begin.line); }

// name, episode limit, [arena] and [destination].
static void parse_environment_frame(const TomlReader &r, Environment &env) {
    const toml::table &root = r.root();
    r.only_keys(root, {"name", "episode_limit_s", "arena", "destination", "start_zone",
                       "circle", "box"});
    env.name = r.string(root, "name");
    if (env.name.empty()) r.fail(root, "'name' must not be empty");
    env.episode_limit_s = r.number(root, "episode_limit_s", 0.1, 36000.0);

    const toml::table &arena = r.table(root, "arena");
    r.only_keys(arena, {"width_m", "height_m"});
    env.width_m = r.number(arena, "width_m", 0.5, 1000.0);
    env.height_m = r.number(arena, "height_m", 0.5, 1000.0);

    const toml::table &dest = r.table(root, "destination");
    r.only_keys(dest, {"x_m", "y_m", "radius_m"});
    env.dest_x_m = r.number(dest, "x_m", 0.0, env.width_m);
    env.dest_y_m = r.number(dest, "y_m", 0.0, env.height_m);
    env.dest_radius_m = r.number(dest, "radius_m", 0.01, 100.0);
}

// [[start_zone]]: each inside the arena; their lines go to env.zone_lines.
static void parse_start_zones(const TomlReader &r, Environment &env) {
    const toml::array *zones = array_of_tables(r, "start_zone", true);
    if (!zones) return;
    for (const toml::node &n : *zones) {
        const toml::table &t = *n.as_table();
        r.only_keys(t, {"x_m", "y_m", "w_m", "h_m"});
        StartZone z;
        z.x_m = r.number(t, "x_m", -1e6, 1e6);
        z.y_m = r.number(t, "y_m", -1e6, 1e6);
        z.w_m = r.number(t, "w_m", 0.0, 1e6);
        z.h_m = r.number(t, "h_m", 0.0, 1e6);
        const int line = source_line(t);
        if (z.x_m < 0 || z.y_m < 0 || z.x_m + z.w_m > env.width_m ||
            z.y_m + z.h_m > env.height_m)
            throw SimError(QNAV_SIM_E_WORLD, line_prefix(r.name(), line) + "start zone leaves the arena");
        env.start_zones.push_back(z);
        env.zone_lines.push_back(line);
    }
}

// [[circle]] then [[box]]; returns each obstacle's line in obstacle_shapes() order.
static std::vector<int> parse_obstacles(const TomlReader &r, Environment &env) {
    std::vector<int> circle_lines, box_lines;
    if (const toml::array *cs = array_of_tables(r, "circle", false)) {
        for (const toml::node &n : *cs) {
            const toml::table &t = *n.as_table();
            r.only_keys(t, {"x_m", "y_m", "r_m"});
            CircleObstacle c;
            c.x_m = r.number(t, "x_m", -1e6, 1e6);
            c.y_m = r.number(t, "y_m", -1e6, 1e6);
            c.r_m = r.number(t, "r_m", 0.001, 1e6);
            env.circles.push_back(c);
            circle_lines.push_back(source_line(t));
        }
    }
    if (const toml::array *bs = array_of_tables(r, "box", false)) {
        for (const toml::node &n : *bs) {
            const toml::table &t = *n.as_table();
            r.only_keys(t, {"x_m", "y_m", "w_m", "h_m", "angle_deg"});
            BoxObstacle b;
            b.x_m = r.number(t, "x_m", -1e6, 1e6);
            b.y_m = r.number(t, "y_m", -1e6, 1e6);
            b.w_m = r.number(t, "w_m", 0.001, 1e6);
            b.h_m = r.number(t, "h_m", 0.001, 1e6);
            b.angle_deg = r.number(t, "angle_deg", -360.0, 360.0, true, 0.0);
            env.boxes.push_back(b);
            box_lines.push_back(source_line(t));
        }
    }
    circle_lines.insert(circle_lines.end(), box_lines.begin(), box_lines.end());
    return circle_lines;
}

// World consistency: start zones and the destination must be free. An obstacle wholly
// outside the walls is a typo that would silently do nothing; one that touches the
// destination's disc makes "reached" partly unreachable.
static void check_environment_world(const TomlReader &r, const Environment &env,
                                    const std::vector<int> &obs_lines) {
    const std::string &name = r.name();
    const std::vector<Shape> obs = env.obstacle_shapes();
    const Shape dest_shape = make_circle(env.dest_x_m, env.dest_y_m, env.dest_radius_m);
    for (std::size_t z = 0; z < env.start_zones.size(); ++z) {
        const Shape zs = zone_shape(env.start_zones[z]);
        for (std::size_t k = 0; k < obs.size(); ++k) {
            if (shape_distance(zs, obs[k]) <= 0.0)
                throw SimError(QNAV_SIM_E_WORLD,
                               line_prefix(name, env.zone_lines[z]) +
                                   "start zone overlaps the obstacle at line " +
                                   std::to_string(obs_lines[k]));
        }
        if (shape_distance(zs, dest_shape) <= 0.0)
            throw SimError(QNAV_SIM_E_WORLD, line_prefix(name, env.zone_lines[z]) +
                                                 "start zone overlaps the destination");
    }
    const Shape arena_shape = make_box(env.width_m / 2, env.height_m / 2, env.width_m, env.height_m, 0.0);
    for (std::size_t k = 0; k < obs.size(); ++k) {
        if (shape_distance(obs[k], arena_shape) > 0.0)
            throw SimError(QNAV_SIM_E_WORLD, line_prefix(name, obs_lines[k]) +
                                                 "obstacle lies wholly outside the arena");
        if (shape_distance(obs[k], dest_shape) <= 0.0)
            throw SimError(QNAV_SIM_E_WORLD, line_prefix(name, obs_lines[k]) +
                                                 "obstacle overlaps the destination (" +
                                                 r.where(r.table(r.root(), "destination")) + ")");
    }
}

Environment parse_environment(std::string_view text, const std::string &name) {
    TomlReader r(text, name);
    Environment env;
    env.source = name;
    parse_environment_frame(r, env);
    parse_start_zones(r, env);
    const std::vector<int> obs_lines = parse_obstacles(r, env);
    check_environment_world(r, env, obs_lines);
    return env;
}

void check_zone_clearance(const Environment &env, double clearance_m) {
    const std::vector<Shape> obs = env.obstacle_shapes();
    const std::vector<Shape> walls = env.wall_shapes();
    for (std::size_t z = 0; z < env.start_zones.size(); ++z) {
        const Shape zs = zone_shape(env.start_zones[z]);
        const int line = z < env.zone_lines.size() ? env.zone_lines[z] : 0;
        auto refuse = [&](const char *what) {
            char buf[64];
            std::snprintf(buf, sizeof buf, "%.3f", clearance_m);
            throw SimError(QNAV_SIM_E_WORLD, line_prefix(env.source.empty() ? env.name : env.source, line) + "start zone is closer than the robot radius (" + buf + " m) to " + what);
        };
        for (const Shape &s : obs)
            if (shape_distance(zs, s) < clearance_m) refuse("an obstacle");
        for (const Shape &s : walls)
            if (shape_distance(zs, s) < clearance_m) refuse("an arena wall");
    }
}

void check_clearance(const Environment &env, double clearance_m) {
    if (clearance_m == env.clearance_checked_m) return;
    check_zone_clearance(env, clearance_m);
    const int walled = first_walled_in_zone(env, clearance_m);
    if (walled >= 0) {
        char buf[64];
        std::snprintf(buf, sizeof buf, "%.3f", clearance_m);
        const int line = static_cast<std::size_t>(walled) < env.zone_lines.size() ? env.zone_lines[cell_index(walled)] : 0;
        throw SimError(QNAV_SIM_E_WORLD, line_prefix(env.source.empty() ? env.name : env.source, line) +
                                             "start zone is walled in: no path to the destination for a "
                                             "robot of radius " + buf + " m");
    }
}

bool environment_connected(const Environment &env, double clearance_m, double cell_m) {
    return first_walled_in_zone(env, clearance_m, cell_m) < 0;
}

std::vector<int> zone_steps(const Environment &env, const std::vector<char> &free, int nx, int ny,
                            double cell_m, bool from_goal_cell) {
    // The grid framed by a border of blocked cells (no bounds to test while flooding);
    // each cell holds its step count once reached, else what it is.
    constexpr int kBlocked = -2, kFree = -1, kZone = -3;  // kZone: free and a zone's cell
    const std::size_t w = cell_index(nx + 2);
    auto at = [&](int i, int j) { return cell_index(j + 1) * w + cell_index(i + 1); };  // i, j >= 0
    std::vector<int> steps(w * cell_index(ny + 2), kBlocked);
    for (int j = 0; j < ny; ++j) {  // a row at a time, without a branch: the compiler's vectors
        const char *f = free.data() + cell_index(j) * cell_index(nx);
        int *row = steps.data() + at(0, j);
        for (int i = 0; i < nx; ++i) row[i] = f[i] ? kFree : kBlocked;
    }
    auto cell = [&](double x, double y) {
        return at(std::clamp(static_cast<int>(x / cell_m), 0, nx - 1), std::clamp(static_cast<int>(y / cell_m), 0, ny - 1));
    };
    std::vector<std::size_t> zones;
    int unreached = 0;  // zone cells not reached yet
    for (const StartZone &z : env.start_zones) {
        zones.push_back(cell(z.x_m + z.w_m / 2, z.y_m + z.h_m / 2));
        if (steps[zones.back()] == kFree) {
            steps[zones.back()] = kZone;
            ++unreached;
        }
    }
    std::vector<std::size_t> queue;  // breadth first: every cell once, in the order reached
    queue.reserve(steps.size());
    auto reach = [&](std::size_t k, int count) {
        unreached -= steps[k] == kZone;
        steps[k] = count;
        queue.push_back(k);
    };
    auto open = [&](std::size_t k) { return steps[k] == kFree || steps[k] == kZone; };
    // Sources: the free cells whose centre lies in the destination disc (only the cells
    // of its bounding square, one more on each side, can).
    const double r2 = env.dest_radius_m * env.dest_radius_m, around = env.dest_radius_m + cell_m;
    const int i0 = std::max(0, static_cast<int>(std::floor((env.dest_x_m - around) / cell_m)));
    const int i1 = std::min(nx - 1, static_cast<int>(std::floor((env.dest_x_m + around) / cell_m)));
    const int j0 = std::max(0, static_cast<int>(std::floor((env.dest_y_m - around) / cell_m)));
    const int j1 = std::min(ny - 1, static_cast<int>(std::floor((env.dest_y_m + around) / cell_m)));
    for (int j = j0; j <= j1; ++j)
        for (int i = i0; i <= i1; ++i) {
            const double dx = (i + 0.5) * cell_m - env.dest_x_m, dy = (j + 0.5) * cell_m - env.dest_y_m;
            if (open(at(i, j)) && dx * dx + dy * dy <= r2) reach(at(i, j), 0);
        }
    const std::size_t goal = cell(env.dest_x_m, env.dest_y_m);
    if (queue.empty() && from_goal_cell && steps[goal] != kBlocked) reach(goal, 0);
    // A cell's count is final when it is first reached: the flood stops once every
    // zone's cell is. The border keeps k - 1 and k - w inside the grid.
    for (std::size_t head = 0; head < queue.size() && unreached > 0; ++head) {
        const std::size_t k = queue[head];
        for (const std::size_t m : {k + 1, k - 1, k + w, k - w})
            if (open(m)) reach(m, steps[k] + 1);
    }
    std::vector<int> out;
    for (const std::size_t z : zones) out.push_back(steps[z] >= 0 ? steps[z] : -1);
    return out;
}

std::vector<char> free_cells(const Environment &env, double clearance_m, double cell_m, int *nx_out, int *ny_out) {
    const int nx = *nx_out = static_cast<int>(std::ceil(env.width_m / cell_m));
    const int ny = *ny_out = static_cast<int>(std::ceil(env.height_m / cell_m));
    const std::vector<Shape> obs = env.obstacle_shapes();
    std::vector<char> free(cell_index(nx * ny), 0);
    for (int j = 0; j < ny; ++j) {
        for (int i = 0; i < nx; ++i) {
            const Vec2 p{(i + 0.5) * cell_m, (j + 0.5) * cell_m};
            free[cell_index(j * nx + i)] = p.x >= clearance_m && p.y >= clearance_m &&
                                                         p.x <= env.width_m - clearance_m &&
                                                         p.y <= env.height_m - clearance_m;
        }
    }
    // An obstacle can only block cells within its bounding circle + clearance (one more
    // cell of margin): worlds of hundreds of obstacles cost their area, not cells x obstacles.
    for (const Shape &s : obs) {
        const double reach = s.r + clearance_m + cell_m;
        const int i0 = std::max(0, static_cast<int>(std::floor((s.c.x - reach) / cell_m)));
        const int i1 = std::min(nx - 1, static_cast<int>(std::floor((s.c.x + reach) / cell_m)));
        const int j0 = std::max(0, static_cast<int>(std::floor((s.c.y - reach) / cell_m)));
        const int j1 = std::min(ny - 1, static_cast<int>(std::floor((s.c.y + reach) / cell_m)));
        Vec2 q;
        for (int j = j0; j <= j1; ++j)
            for (int i = i0; i <= i1; ++i) {
                char &f = free[cell_index(j * nx + i)];
                if (f && nearest_point(s, {(i + 0.5) * cell_m, (j + 0.5) * cell_m}, &q) < clearance_m) f = 0;
            }
    }
    return free;
}

int first_walled_in_zone(const Environment &env, double clearance_m, double cell_m) {
    int nx = 0, ny = 0;
    const std::vector<char> free = free_cells(env, clearance_m, cell_m, &nx, &ny);
    const std::vector<int> steps = zone_steps(env, free, nx, ny, cell_m, true);
    for (std::size_t z = 0; z < steps.size(); ++z)
        if (steps[z] < 0) return static_cast<int>(z);
    return -1;
}

Environment generate_environment(double density, std::uint64_t seed, double clearance_m) {
    Environment env;
    char nm[64];
    std::snprintf(nm, sizeof nm, "generated-d%.2f-s%llu", density,
                  static_cast<unsigned long long>(seed));
    env.name = nm;
    env.width_m = 10;
    env.height_m = 10;
    env.dest_x_m = 5;
    env.dest_y_m = 9;
    env.dest_radius_m = 0.4;
    env.episode_limit_s = 40;
    env.start_zones = {{0.6, 0.6, 2.0, 1.0}, {4.0, 0.6, 2.0, 1.0}, {7.4, 0.6, 2.0, 1.0}};
    env.zone_lines = {0, 0, 0};
    Rng rng = Rng::stream(seed, 0x67656e, 0);
    // Obstacles live in the band y in [2.2, 8.2]; keep the destination area free.
    const double band_lo = 2.2, band_hi = 8.2;
    const double band_area = env.width_m * (band_hi - band_lo);
    double covered = 0;
    std::vector<Shape> placed;  // env's obstacles so far
    const double target = std::clamp(density, 0.0, 0.5) * band_area;
    for (int attempt = 0; attempt < 4000 && covered < target; ++attempt) {
        const bool circle = rng.uniform01() < 0.5;
        const double x = rng.uniform(0.3, env.width_m - 0.3);
        const double y = rng.uniform(band_lo, band_hi);
        Environment trial = env;
        double area;
        Shape s;
        if (circle) {
            const double r = rng.uniform(0.2, 0.7);
            trial.circles.push_back({x, y, r});
            s = make_circle(x, y, r);
            area = kPi * r * r;
        } else {
            const double w = rng.uniform(0.3, 1.8), h = rng.uniform(0.3, 1.8);
            const double a = std::floor(rng.uniform(0.0, 4.0)) * 15.0;  // 0, 15, 30, 45
            trial.boxes.push_back({x, y, w, h, a});
            s = make_box(x, y, w, h, a);
            area = w * h;
        }
        Vec2 q;
        if (nearest_point(s, {env.dest_x_m, env.dest_y_m}, &q) < env.dest_radius_m + 2 * clearance_m)
            continue;
        bool bad = false;
        for (const auto &z : env.start_zones)
            if (shape_distance(zone_shape(z), s) < 2 * clearance_m) bad = true;
        // Obstacles do not overlap: spread out, they make more distinct gaps.
        for (const Shape &o : placed)
            if (!bad && shape_distance(o, s) < 0.1) bad = true;
        if (bad || !environment_connected(trial, clearance_m, 0.1)) continue;
        env = std::move(trial);
        placed.push_back(s);
        covered += area;
    }
    return env;
}

std::string environment_to_toml(const Environment &env) {
    std::ostringstream os;
    os.precision(6);
    os << "# qnav environment (format: docs/sim.md). Units: metres, degrees, seconds.\n";
    os << "name = \"";
    for (const char c : env.name) {  // a TOML basic string: escape what ends it
        const auto ch = static_cast<unsigned char>(c);
        if (ch == '"' || ch == '\\') {
            os << '\\' << ch;
        } else if (ch < 0x20 || ch == 0x7f) {
            char u[8];
            std::snprintf(u, sizeof u, "\\u%04x", ch);
            os << u;
        } else {
            os << ch;
        }
    }
    os << "\"\n";
    os << "episode_limit_s = " << env.episode_limit_s << "\n\n";
    os << "[arena]\nwidth_m = " << env.width_m << "\nheight_m = " << env.height_m << "\n\n";
    os << "[destination]\nx_m = " << env.dest_x_m << "\ny_m = " << env.dest_y_m
       << "\nradius_m = " << env.dest_radius_m << "\n";
    for (const auto &z : env.start_zones)
        os << "\n[[start_zone]]\nx_m = " << z.x_m << "\ny_m = " << z.y_m << "\nw_m = " << z.w_m
           << "\nh_m = " << z.h_m << "\n";
    for (const auto &c : env.circles)
        os << "\n[[circle]]\nx_m = " << c.x_m << "\ny_m = " << c.y_m << "\nr_m = " << c.r_m << "\n";
    for (const auto &b : env.boxes)
        os << "\n[[box]]\nx_m = " << b.x_m << "\ny_m = " << b.y_m << "\nw_m = " << b.w_m
           << "\nh_m = " << b.h_m << "\nangle_deg = " << b.angle_deg << "\n";
    return os.str();
}

}  // namespace qnav
