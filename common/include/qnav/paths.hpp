/*
 * Where an installed qnav program finds its data (robots, environments), experiments and
 * plot scripts: share/qnav beside the program's own bin/ folder (docs/install.md), so an
 * installed tree works from any folder and wherever it was installed. A program run from
 * its build tree has no such folder and falls back to the source tree it was built from.
 * Order for each: the environment variable, the installed folder, the source tree.
 */
#ifndef QNAV_PATHS_HPP
#define QNAV_PATHS_HPP

#include <cstdlib>
#include <string>
#include <sys/stat.h>
#include <unistd.h>

#ifndef QNAV_SHARE_FROM_BIN
#error "QNAV_SHARE_FROM_BIN (share/qnav relative to bin/) is set by the qnav::cli target"
#endif

namespace qnav {

/* <folder of this program>/QNAV_SHARE_FROM_BIN when that folder exists, else "". */
inline std::string installed_share_dir()
{
    char exe[4096];
    const ssize_t n = ::readlink("/proc/self/exe", exe, sizeof exe - 1);
    if (n <= 0) {
        return std::string();
    }
    exe[n] = '\0';
    std::string dir(exe);
    dir = dir.substr(0, dir.find_last_of('/')) + "/" + QNAV_SHARE_FROM_BIN;
    struct stat st;
    return ::stat(dir.c_str(), &st) == 0 && S_ISDIR(st.st_mode) ? dir : std::string();
}

/* The folder for sub (e.g. "data", "experiments", "tools"): env_var if set and non-empty,
 * else the installed share/qnav/sub, else source_fallback. */
inline std::string resource_dir(const char *env_var, const char *sub, const std::string &source_fallback)
{
    const char *v = std::getenv(env_var);
    if (v != nullptr && *v != '\0') {
        return v;
    }
    const std::string share = installed_share_dir();
    return share.empty() ? source_fallback : share + "/" + sub;
}

} // namespace qnav

#endif
