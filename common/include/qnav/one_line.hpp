/*
 * Error messages are one line (STYLE.md, "Errors for people"), but they quote what the
 * user wrote: a TOML key or string may hold a newline or another control character, and
 * toml++'s descriptions quote the input. one_line() escapes those (\n, \r, \t, \xHH), so a
 * message never spans two lines and never carries raw control bytes to a terminal.
 */
#ifndef QNAV_ONE_LINE_HPP
#define QNAV_ONE_LINE_HPP

#include <cstdio>
#include <string>

namespace qnav {

inline std::string one_line(const std::string &s)
{
    std::string out;
    out.reserve(s.size());
    for (const char c : s) {
        const unsigned char u = static_cast<unsigned char>(c);
        if (c == '\n') {
            out += "\\n";
        } else if (c == '\r') {
            out += "\\r";
        } else if (c == '\t') {
            out += "\\t";
        } else if (u < 0x20 || u == 0x7f) {
            char hex[8];
            std::snprintf(hex, sizeof hex, "\\x%02x", u);
            out += hex;
        } else {
            out += c;
        }
    }
    return out;
}

} // namespace qnav

#endif
