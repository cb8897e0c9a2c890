/*
 * Sweep files -> Sweep (a list of experiment files with an optional variation each), and
 * the variations themselves: a declared table of the target-situation keys a sweep may vary.
 */
#include "sweep.h"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <set>

#include <toml++/toml.h>

#include "files.h"
#include "qnav/sim.h"

namespace qnav {

namespace {

/* One key of [vary]: its range and how it sets the target situation. */
struct VaryKey {
    const char *name;
    bool integer; /* only whole numbers */
    double lo, hi;
    void (*set)(Scenario &, double);
};

const VaryKey kVaryKeys[] = {
    {"noise", false, 0.0, 1.0, [](Scenario &s, double v) { s.sensor_noise = s.actuation_noise = v; }},
    {"sectors", true, 0.0, QNAV_MAX_SECTORS, [](Scenario &s, double v) { s.sectors = static_cast<uint32_t>(v); }},
};

const VaryKey *find_vary_key(const std::string &name)
{
    for (const VaryKey &k : kVaryKeys) {
        if (name == k.name) {
            return &k;
        }
    }
    return nullptr;
}

/* The shortest decimal text that reads back as v exactly (0.05, not 0.050000000000000003);
 * a whole number as an integer (100000, not 1e+05: it names folders and fills messages). */
std::string shortest_text(double v)
{
    char buf[40];
    if (std::isfinite(v) && v == std::floor(v) && std::fabs(v) < 1e15) {
        std::snprintf(buf, sizeof buf, "%.0f", v);
        return buf;
    }
    for (int p = 1; p <= 17; ++p) {
        std::snprintf(buf, sizeof buf, "%.*g", p, v);
        if (std::strtod(buf, nullptr) == v) {
            break;
        }
    }
    return buf;
}

/* A value of key k as text, or "" with *problem set when it is out of range. */
std::string vary_value_text(const VaryKey &k, double v, std::string *problem)
{
    if (!std::isfinite(v) || v < k.lo || v > k.hi) {
        *problem = std::string(k.name) + ": " + shortest_text(v) + " is not in [" + shortest_text(k.lo) + ", " +
                   shortest_text(k.hi) + "]";
        return "";
    }
    if (k.integer && v != std::floor(v)) {
        *problem = std::string(k.name) + ": " + shortest_text(v) + " is not a whole number";
        return "";
    }
    return shortest_text(v);
}

std::string folder_of(const std::string &path)
{
    const std::size_t slash = path.find_last_of('/');
    return slash == std::string::npos ? "." : (slash == 0 ? "/" : path.substr(0, slash));
}

bool is_path(const std::string &arg)
{
    return arg.find('/') != std::string::npos || (arg.size() > 5 && arg.compare(arg.size() - 5, 5, ".toml") == 0);
}

class SweepParser {
public:
    SweepParser(std::string file, const std::function<std::string(const std::string &)> &resolve)
        : file_(std::move(file)), resolve_(resolve)
    {
    }

    [[noreturn]] void fail(const toml::node &n, const std::string &what) const
    {
        throw UserError(file_ + ":" + std::to_string(n.source().begin.line) + ": " + what);
    }

    std::string str(const toml::node &n, const std::string &key) const
    {
        if (!n.is_string()) {
            fail(n, key + ": expected a string");
        }
        return *n.value<std::string>();
    }

    /* The experiment a sweep names at node n: its path and its spec (with vary applied). */
    SweepMember member(const toml::node &n, const std::string &key, const std::string &vary) const
    {
        const std::string arg = str(n, key);
        SweepMember m;
        try {
            m.experiment_file = is_path(arg) ? (arg[0] == '/' ? arg : join_path(folder_of(file_), arg)) : resolve_(arg);
        } catch (const UserError &e) {
            fail(n, key + ": " + e.what());
        }
        if (!file_exists(m.experiment_file)) {
            fail(n, key + ": " + m.experiment_file + ": no such experiment file");
        }
        ExperimentSpec s = load_experiment(m.experiment_file); // its own FILE:LINE errors
        if (!vary.empty()) {
            try {
                apply_vary(s, vary);
            } catch (const UserError &e) {
                fail(n, e.what());
            }
        }
        m.vary = vary;
        m.name = s.name;
        return m;
    }

    /* [vary]: exactly one key over a non-empty list of distinct values. */
    std::vector<std::string> variations(const toml::node &n) const
    {
        if (!n.is_table()) {
            fail(n, "vary: expected a table, e.g. [vary] noise = [0, 0.05]");
        }
        const toml::table &t = *n.as_table();
        if (t.size() != 1) {
            fail(n, "[vary]: give exactly one key (one of " + vary_key_names() + ")");
        }
        const auto first = t.begin(); // its pair is a proxy: keep the iterator alive
        const std::string key(first->first.str());
        const toml::node &v = first->second;
        const VaryKey *vk = find_vary_key(key);
        if (!vk) {
            fail(v, "[vary]: unknown key '" + key + "' (one of " + vary_key_names() + ")");
        }
        if (!v.is_array() || v.as_array()->empty()) {
            fail(v, key + ": expected a non-empty list of values, e.g. [0, 0.05]");
        }
        std::vector<std::string> out;
        std::set<std::string> seen;
        for (auto &&el : *v.as_array()) {
            double x = 0;
            if (el.is_integer()) {
                x = static_cast<double>(*el.value<int64_t>());
            } else if (el.is_floating_point() && !vk->integer) {
                x = *el.value<double>();
            } else {
                fail(el, key + ": expected " + (vk->integer ? "an integer" : "a number"));
            }
            std::string problem;
            const std::string text = vary_value_text(*vk, x, &problem);
            if (text.empty()) {
                fail(el, problem);
            }
            if (!seen.insert(text).second) {
                fail(el, key + ": " + text + " is listed twice");
            }
            out.push_back(key + "=" + text);
        }
        return out;
    }

    const std::string &file() const { return file_; }

private:
    std::string file_;
    const std::function<std::string(const std::string &)> &resolve_;
};

} // namespace

std::string vary_key_names()
{
    std::string s;
    for (const VaryKey &k : kVaryKeys) {
        s += (s.empty() ? "" : ", ") + std::string(k.name);
    }
    return s;
}

void apply_vary(ExperimentSpec &spec, const std::string &vary)
{
    const std::size_t eq = vary.find('=');
    const VaryKey *k = eq == std::string::npos ? nullptr : find_vary_key(vary.substr(0, eq));
    if (!k) {
        throw UserError("--vary: '" + vary + "' is not KEY=VALUE with KEY one of " + vary_key_names());
    }
    const std::string value = vary.substr(eq + 1);
    // only number characters: the text goes into Slurm scripts unquoted and into a folder name
    const bool plain = !value.empty() && value.find_first_not_of("0123456789.eE+-") == std::string::npos;
    char *end = nullptr;
    errno = 0;
    const double v = std::strtod(value.c_str(), &end);
    std::string problem;
    const std::string text = !plain || *end || errno ? "" : vary_value_text(*k, v, &problem);
    if (text.empty()) {
        throw UserError("--vary: " + (problem.empty() ? "'" + value + "' is not a number" : problem));
    }
    k->set(spec.target, v);
    spec.name += "." + std::string(k->name) + "-" + text;
}

bool is_sweep_file(const std::string &path)
{
    std::string text;
    try {
        if (!read_file(path, text)) {
            return false;
        }
        const toml::table root = toml::parse(text, path);
        return root.contains("experiments") || root.contains("experiment") || root.contains("vary");
    } catch (const std::exception &) {
        return false; // not a readable TOML file: the experiment loader names the problem
    }
}

Sweep load_sweep(const std::string &path, const std::function<std::string(const std::string &)> &resolve)
{
    std::string text;
    if (!read_file(path, text)) {
        throw UserError(path + ": cannot open sweep file (No such file or directory)");
    }
    toml::table root;
    try {
        root = toml::parse(text, path);
    } catch (const toml::parse_error &e) {
        throw UserError(path + ":" + std::to_string(e.source().begin.line) + ": " + std::string(e.description()));
    }
    const SweepParser p(path, resolve);
    Sweep sw;
    sw.file = path;
    for (auto &&[k, v] : root) {
        const std::string key(k.str());
        if (key != "name" && key != "experiments" && key != "experiment" && key != "vary") {
            p.fail(v, "unknown key '" + key + "' in a sweep file (name, experiments, or experiment and [vary])");
        }
    }
    if (!root.contains("name")) {
        throw UserError(path + ":1: name: missing (the sweep's identifier)");
    }
    sw.name = p.str(*root.get("name"), "name");
    if (!valid_name(sw.name)) {
        p.fail(*root.get("name"), "name: use 1-64 characters a-z, 0-9, '-', '_'");
    }
    const toml::node *list = root.get("experiments"), *one = root.get("experiment"), *vary = root.get("vary");
    if (list && (one || vary)) {
        p.fail(*list, "experiments: give either 'experiments' or 'experiment' with [vary], not both");
    }
    if (list) {
        if (!list->is_array() || list->as_array()->empty()) {
            p.fail(*list, "experiments: expected a non-empty list of experiment names or paths");
        }
        for (auto &&el : *list->as_array()) {
            sw.members.push_back(p.member(el, "experiments", ""));
        }
    } else if (one && vary) {
        for (const std::string &v : p.variations(*vary)) {
            sw.members.push_back(p.member(*one, "experiment", v));
        }
    } else {
        throw UserError(path + ":1: a sweep needs 'experiments = [...]', or 'experiment' with one [vary] key");
    }
    std::set<std::string> names;
    for (std::size_t i = 0; i < sw.members.size(); ++i) {
        const toml::node &at = list ? *list->as_array()->get(i) : *one;
        if (!names.insert(sw.members[i].name).second) {
            p.fail(at, "experiment '" + sw.members[i].name + "' is in the sweep twice (one folder each)");
        }
        if (sw.members[i].name == sw.name) {
            p.fail(at, "experiment '" + sw.name + "' has the sweep's name (both need their own folder)");
        }
    }
    return sw;
}

std::string sweep_record_text(const Sweep &sweep)
{
    std::string s = "# simevo sweep record: the experiments `simevo summarize` merges for this sweep\n";
    for (const SweepMember &m : sweep.members) {
        s += "member = " + m.name + "\n";
    }
    return s;
}

std::string write_sweep_record(const std::string &out_dir, const Sweep &sweep)
{
    const std::string dir = join_path(out_dir, sweep.name), path = join_path(dir, "sweep.txt");
    if (file_exists(join_path(dir, "run.txt"))) {
        throw UserError(dir + ": is the folder of an experiment named '" + sweep.name + "', not of sweep " + sweep.file +
                        "; use another --out or sweep name");
    }
    const std::string text = sweep_record_text(sweep);
    std::string existing;
    if (read_file(path, existing) && existing != text) {
        throw UserError(path + ": this output folder holds sweep " + sweep.name +
                        " with other members; use another --out");
    }
    make_dirs(dir);
    write_file_atomic(path, text);
    return dir;
}

std::vector<std::string> parse_sweep_record(const std::string &text, const std::string &path)
{
    std::vector<std::string> names;
    std::size_t from = 0;
    for (int n = 1; from < text.size(); ++n) {
        std::size_t to = text.find('\n', from);
        to = to == std::string::npos ? text.size() : to;
        const std::string line = text.substr(from, to - from);
        from = to + 1;
        if (line.empty() || line[0] == '#') {
            continue;
        }
        if (line.compare(0, 9, "member = ") != 0 || line.size() == 9 || line.find('/') != std::string::npos) {
            throw UserError(path + ":" + std::to_string(n) + ": expected 'member = NAME'");
        }
        names.push_back(line.substr(9));
    }
    if (names.empty()) {
        throw UserError(path + ": no 'member = NAME' line");
    }
    return names;
}

} // namespace qnav
