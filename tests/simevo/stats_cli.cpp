/*
 * stats.cpp on the command line, for tests/simevo/test_stats_scipy.py (which compares it
 * with python3-scipy). Reads lines from stdin, answers one line each on stdout:
 *   welch A B    -> t df p valid           (A, B: comma-separated samples)
 *   one A MU     -> t df p valid
 *   mw A B       -> z p valid exact
 */
#include <cstdio>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "stats.h"

static std::vector<double> parse(const std::string &csv)
{
    std::vector<double> v;
    std::stringstream ss(csv);
    std::string item;
    while (std::getline(ss, item, ',')) {
        v.push_back(std::stod(item));
    }
    return v;
}

int main()
{
    std::string line;
    while (std::getline(std::cin, line)) {
        std::istringstream in(line);
        std::string op, a, b;
        in >> op >> a >> b;
        qnav::TestResult r;
        if (op == "welch") {
            r = qnav::welch_t_test(parse(a), parse(b));
        } else if (op == "one") {
            r = qnav::one_sample_t_test(parse(a), std::stod(b));
        } else if (op == "mw") {
            r = qnav::mann_whitney(parse(a), parse(b));
            std::printf("%.17g %.17g %d %d\n", r.statistic, r.p, r.valid ? 1 : 0, r.exact ? 1 : 0);
            continue;
        } else {
            std::fprintf(stderr, "stats_cli: unknown operation '%s'\n", op.c_str());
            return 2;
        }
        std::printf("%.17g %.17g %.17g %d\n", r.statistic, r.df, r.p, r.valid ? 1 : 0);
    }
    return 0;
}
