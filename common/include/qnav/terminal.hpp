/*
 * A progress line redrawn in place with "\r" must fit the terminal, or every redraw wraps
 * and scrolls (docs/cli.md). Shared by the programs that show one (simevo).
 */
#ifndef QNAV_TERMINAL_HPP
#define QNAV_TERMINAL_HPP

#include <cstdlib>
#include <string>
#include <sys/ioctl.h>
#include <unistd.h>

namespace qnav::cli {

/* Columns of the terminal on fd; COLUMNS when fd is not a terminal or does not say; 80. */
inline int terminal_columns(int fd)
{
    struct winsize ws {};
    if (::ioctl(fd, TIOCGWINSZ, &ws) == 0 && ws.ws_col > 0) {
        return ws.ws_col;
    }
    const char *c = std::getenv("COLUMNS");
    const int n = c != nullptr ? std::atoi(c) : 0;
    return n > 0 ? n : 80;
}

/* line cut to at most columns - 1 characters (UTF-8 sequences counted as one and never
 * split), so that a progress line redrawn with "\r" never wraps and scrolls. */
inline std::string fit_line(const std::string &line, int columns)
{
    const int room = columns > 1 ? columns - 1 : 1;
    int shown = 0;
    for (std::size_t i = 0; i < line.size(); ++i) {
        if ((static_cast<unsigned char>(line[i]) & 0xC0) != 0x80) { // a character starts
            if (shown == room) {
                return line.substr(0, i);
            }
            ++shown;
        }
    }
    return line;
}

} // namespace qnav::cli

#endif
