// Reading checked values out of a TOML document for robot profiles and environments: each
// getter names the file and the line of the offending key (or of its table when the key
// is missing) in the one-line error it throws.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include <toml++/toml.h>

namespace qnav {

class TomlReader {
public:
    // Parse text; a syntax error throws SimError(QNAV_SIM_E_PARSE, "NAME:LINE: ...").
    TomlReader(std::string_view text, std::string name);
    // Read a whole file; an unreadable file throws SimError(QNAV_SIM_E_IO).
    static std::string read_file(const std::string &path);

    const toml::table &root() const { return root_; }
    const std::string &name() const { return name_; }

    // A required table (or the root when key is empty).
    const toml::table &table(const toml::table &parent, const char *key) const;
    // A number in [lo, hi]; required unless a default is given (has_default).
    double number(const toml::table &t, const char *key, double lo, double hi,
                  bool has_default = false, double dflt = 0.0) const;
    // An integer in [lo, hi].
    std::int64_t integer(const toml::table &t, const char *key, std::int64_t lo,
                         std::int64_t hi, bool has_default = false,
                         std::int64_t dflt = 0) const;
    std::string string(const toml::table &t, const char *key, bool has_default = false,
                       const std::string &dflt = "") const;
    // Refuse keys not in the allowed list (catches typos such as "raduis_m").
    void only_keys(const toml::table &t, std::initializer_list<const char *> allowed) const;

    // "NAME:LINE: what" for a node (line 0 when the node has no source).
    std::string where(const toml::node &node) const;
    [[noreturn]] void fail(const toml::node &node, const std::string &what) const;

private:
    std::string name_;
    toml::table root_;
};

}  // namespace qnav
