/*
 * File helpers (POSIX): atomic writes by rename from an exclusively created temporary
 * file, reads, mkdir -p.
 */
#include "files.h"

#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include "spec.h"

namespace qnav {

namespace {
std::string errno_text() { return std::strerror(errno); }
} // namespace

std::string join_path(const std::string &a, const std::string &b)
{
    if (a.empty()) {
        return b;
    }
    return a.back() == '/' ? a + b : a + "/" + b;
}

void write_all(int fd, const std::string &s, const std::string &path)
{
    std::size_t off = 0;
    while (off < s.size()) {
        const ssize_t n = ::write(fd, s.data() + off, s.size() - off);
        if (n < 0) {
            if (errno == EINTR) {
                continue;
            }
            throw UserError(path + ": write failed (" + errno_text() + ")");
        }
        off += static_cast<std::size_t>(n);
    }
}

void write_file_atomic(const std::string &path, const std::string &content)
{
    // The temporary file is made exclusively (mkstemp: O_CREAT | O_EXCL, a random name) in
    // the target's folder, so a symlink planted beside the target is never followed and two
    // writers (a resumed run and a leftover process) never share one.
    const std::size_t slash = path.find_last_of('/');
    std::string tmp = (slash == std::string::npos ? std::string() : path.substr(0, slash + 1)) + "." +
                      path.substr(slash == std::string::npos ? 0 : slash + 1) + ".tmp.XXXXXX";
    const int fd = ::mkostemp(tmp.data(), O_CLOEXEC);
    if (fd < 0) {
        throw UserError(path + ": cannot write (" + errno_text() + ")");
    }
    try {
        if (::fchmod(fd, 0644) != 0) {
            throw UserError(path + ": cannot write (" + errno_text() + ")");
        }
        write_all(fd, content, path);
    } catch (...) {
        ::close(fd);
        ::unlink(tmp.c_str());
        throw;
    }
    if (::close(fd) != 0 || ::rename(tmp.c_str(), path.c_str()) != 0) {
        const std::string e = errno_text();
        ::unlink(tmp.c_str());
        throw UserError(path + ": cannot write (" + e + ")");
    }
}

bool read_file(const std::string &path, std::string &out)
{
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) {
        if (errno == ENOENT) {
            return false;
        }
        throw UserError(path + ": cannot read (" + errno_text() + ")");
    }
    struct stat st;
    if (::fstat(fd, &st) == 0 && S_ISDIR(st.st_mode)) {
        ::close(fd);
        throw UserError(path + ": is a directory, not a file");
    }
    out.clear();
    char buf[65536];
    for (;;) {
        const ssize_t n = ::read(fd, buf, sizeof buf);
        if (n < 0) {
            if (errno == EINTR) {
                continue;
            }
            const std::string e = errno_text();
            ::close(fd);
            throw UserError(path + ": read failed (" + e + ")");
        }
        if (n == 0) {
            break;
        }
        out.append(buf, static_cast<std::size_t>(n));
    }
    ::close(fd);
    return true;
}

bool file_exists(const std::string &path)
{
    struct stat st;
    return ::stat(path.c_str(), &st) == 0;
}

void make_dirs(const std::string &path)
{
    if (path.empty()) {
        return;
    }
    std::string cur;
    std::size_t pos = 0;
    while (pos != std::string::npos) {
        pos = path.find('/', pos + 1);
        cur = path.substr(0, pos);
        if (cur.empty() || cur == "/") {
            continue;
        }
        if (::mkdir(cur.c_str(), 0755) != 0 && errno != EEXIST) {
            throw UserError(cur + ": cannot create directory (" + errno_text() + ")");
        }
    }
    struct stat st;
    if (::stat(path.c_str(), &st) != 0 || !S_ISDIR(st.st_mode)) {
        throw UserError(path + ": not a directory");
    }
}

} // namespace qnav
