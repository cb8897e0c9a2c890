// Checked TOML getters shared by the robot-profile and environment loaders.
#include "tomlread.hpp"

#include <cmath>
#include <fstream>
#include <sstream>

#include "error.hpp"

namespace qnav {

TomlReader::TomlReader(std::string_view text, std::string name) : name_(std::move(name)) {
    try {
        root_ = toml::parse(text, name_);
    } catch (const toml::parse_error &e) {
        std::ostringstream os;
        os << name_ << ":" << e.source().begin.line << ": " << e.description();
        throw SimError(QNAV_SIM_E_PARSE, os.str());
    }
}

std::string TomlReader::read_file(const std::string &path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw SimError(QNAV_SIM_E_IO, path + ":0: cannot open file");
    std::ostringstream os;
    os << in.rdbuf();
    if (in.bad()) throw SimError(QNAV_SIM_E_IO, path + ":0: cannot read file");
    return os.str();
}

std::string TomlReader::where(const toml::node &node) const {
    std::ostringstream os;
    os << name_ << ":" << node.source().begin.line;
    return os.str();
}

void TomlReader::fail(const toml::node &node, const std::string &what) const {
    throw SimError(QNAV_SIM_E_PARSE, where(node) + ": " + what);
}

const toml::table &TomlReader::table(const toml::table &parent, const char *key) const {
    const toml::node *n = parent.get(key);
    if (!n) fail(parent, std::string("missing table [") + key + "]");
    const toml::table *t = n->as_table();
    if (!t) fail(*n, std::string("'") + key + "' must be a table");
    return *t;
}

double TomlReader::number(const toml::table &t, const char *key, double lo, double hi,
                          bool has_default, double dflt) const {
    const toml::node *n = t.get(key);
    if (!n) {
        if (has_default) return dflt;
        fail(t, std::string("missing key '") + key + "'");
    }
    double v;
    if (const auto *f = n->as_floating_point()) {
        v = f->get();
    } else if (const auto *i = n->as_integer()) {
        v = static_cast<double>(i->get());
    } else {
        fail(*n, std::string("'") + key + "' must be a number");
    }
    if (!std::isfinite(v) || v < lo || v > hi) {
        std::ostringstream os;
        os << "'" << key << "' = " << v << " is outside [" << lo << ", " << hi << "]";
        fail(*n, os.str());
    }
    return v;
}

std::int64_t TomlReader::integer(const toml::table &t, const char *key, std::int64_t lo,
                                 std::int64_t hi, bool has_default, std::int64_t dflt) const {
    const toml::node *n = t.get(key);
    if (!n) {
        if (has_default) return dflt;
        fail(t, std::string("missing key '") + key + "'");
    }
    const auto *i = n->as_integer();
    if (!i) fail(*n, std::string("'") + key + "' must be an integer");
    const std::int64_t v = i->get();
    if (v < lo || v > hi) {
        std::ostringstream os;
        os << "'" << key << "' = " << v << " is outside [" << lo << ", " << hi << "]";
        fail(*n, os.str());
    }
    return v;
}

std::string TomlReader::string(const toml::table &t, const char *key, bool has_default,
                               const std::string &dflt) const {
    const toml::node *n = t.get(key);
    if (!n) {
        if (has_default) return dflt;
        fail(t, std::string("missing key '") + key + "'");
    }
    const auto *s = n->as_string();
    if (!s) fail(*n, std::string("'") + key + "' must be a string");
    return s->get();
}

void TomlReader::only_keys(const toml::table &t,
                           std::initializer_list<const char *> allowed) const {
    for (const auto &kv : t) {
        bool ok = false;
        for (const char *a : allowed) {
            if (kv.first.str() == a) ok = true;
        }
        if (!ok) fail(kv.second, "unknown key '" + std::string(kv.first.str()) + "'");
    }
}

}  // namespace qnav
