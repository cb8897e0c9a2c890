// Checked TOML getters shared by the robot-profile and environment loaders.
#include "tomlread.hpp"

#include <cerrno>
#include <cmath>
#include <cstring>
#include <fcntl.h>
#include <sstream>
#include <sys/stat.h>
#include <unistd.h>

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
    // POSIX rather than ifstream: ifstream opens a directory and reads it as empty (then
    // "missing key 'name'"), and says nothing of why an open failed.
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) throw SimError(QNAV_SIM_E_IO, path + ": cannot open (" + std::strerror(errno) + ")");
    struct stat st;
    if (::fstat(fd, &st) == 0 && S_ISDIR(st.st_mode)) {
        ::close(fd);
        throw SimError(QNAV_SIM_E_IO, path + ": is a directory, not a file");
    }
    std::string text;
    char buf[65536];
    for (;;) {
        const ssize_t n = ::read(fd, buf, sizeof buf);
        if (n < 0 && errno == EINTR) continue;
        if (n < 0) {
            const std::string e = std::strerror(errno);
            ::close(fd);
            throw SimError(QNAV_SIM_E_IO, path + ": cannot read (" + e + ")");
        }
        if (n == 0) break;
        text.append(buf, static_cast<std::size_t>(n));
    }
    ::close(fd);
    return text;
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
