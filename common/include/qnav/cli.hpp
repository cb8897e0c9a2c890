/*
 * The command-line conventions shared by qnav's C++ programs (simevo, qnav-sim), on CLI11;
 * docs/cli.md. `--version`; an unknown option or subcommand named as such (CLI11 alone
 * says "A subcommand is required"); every parse error one line on stderr ending in
 * "(see PROG --help)", exit status 2; numbers checked finite as well as in range.
 */
#ifndef QNAV_CLI_HPP
#define QNAV_CLI_HPP

#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdio>
#include <string>

#include "qnav/cli.h"

namespace qnav::cli {

/* A number in [lo, hi]. CLI::Range lets NaN through (every comparison with it is false),
 * and a NaN default then stands for "not given": this refuses NaN and infinities. */
inline CLI::Validator finite_range(double lo, double hi)
{
    return CLI::Validator(
        [lo, hi](std::string &s) -> std::string {
            double v = 0.0;
            if (!CLI::detail::lexical_cast(s, v) || !std::isfinite(v) || v < lo || v > hi) {
                return "expected a number in [" + CLI::detail::to_string(lo) + ", " +
                       CLI::detail::to_string(hi) + "], got '" + s + "'";
            }
            return std::string();
        },
        "NUMBER in [" + CLI::detail::to_string(lo) + " - " + CLI::detail::to_string(hi) + "]");
}

/* --version on app: "PROG (qnav) VERSION". */
inline void add_version(CLI::App &app, const std::string &prog)
{
    app.set_version_flag("--version", prog + " (qnav) " QNAV_VERSION, "print the version and exit");
}

/* Parse argv. Returns -1 to go on, or the status to exit with (0 after --help/--version,
 * 2 after one line on stderr for a bad command line). */
inline int parse(CLI::App &app, int argc, char **argv, const std::string &prog)
{
    try {
        app.parse(argc, argv);
        return -1;
    } catch (const CLI::ParseError &e) {
        if (e.get_exit_code() == 0) {
            return app.exit(e);
        }
        std::string msg = e.what();
        const auto extra = app.remaining();
        const auto all = app.get_subcommands([](CLI::App *) { return true; });
        if (!extra.empty() && app.get_subcommands().empty() && !all.empty()) {
            // nothing recognised as a subcommand: name what was given instead
            const std::string &a = extra.front();
            if (!a.empty() && a[0] == '-') {
                msg = a + ": unknown option";
            } else {
                std::string known;
                for (const CLI::App *s : all) {
                    known += (known.empty() ? "" : ", ") + s->get_name();
                }
                msg = a + ": unknown subcommand (known: " + known + ")";
            }
        }
        std::fprintf(stderr, "%s: %s (see %s --help)\n", prog.c_str(), msg.c_str(), prog.c_str());
        return QNAV_EXIT_USAGE;
    }
}

} // namespace qnav::cli

#endif
