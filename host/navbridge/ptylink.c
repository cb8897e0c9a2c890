/*
 * Pty links that are made exclusively and removed only while they are still ours (see
 * ptylink.h). A new link is made under a unique temporary name beside link_path (symlink()
 * never follows or replaces anything) and renamed over a stale pty link only after lstat()
 * has shown that link_path is one.
 */
#define _XOPEN_SOURCE 700
#define _DEFAULT_SOURCE
#include "ptylink.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* The target of the symlink at path into buf (NUL-terminated); 0, or -1 if path is not a
 * symlink or its target does not fit. */
static int link_target(const char *path, char *buf, size_t len)
{
    ssize_t n = readlink(path, buf, len - 1);
    if (n < 0 || (size_t)n >= len - 1) {
        return -1;
    }
    buf[n] = '\0';
    return 0;
}

/* A symlink into /dev/pts/ whose pty is gone: what an earlier run that was killed leaves. */
static int is_stale_pty_link(const char *path)
{
    char target[256];
    struct stat st;
    return lstat(path, &st) == 0 && S_ISLNK(st.st_mode) &&
           link_target(path, target, sizeof target) == 0 &&
           strncmp(target, "/dev/pts/", 9) == 0 && stat(path, &st) != 0 && errno == ENOENT;
}

int qnav_ptylink_make(const char *link_path, const char *pty, char *err, size_t errlen)
{
    char tmp[4096];
    int k;
    if (symlink(pty, link_path) == 0) {
        return 0;
    }
    if (errno != EEXIST) {
        snprintf(err, errlen, "--link %s: %s", link_path, strerror(errno));
        return -1;
    }
    if (!is_stale_pty_link(link_path)) {
        snprintf(err, errlen,
                 "--link %s: exists and is not a stale pty link; refusing to replace it "
                 "(remove it or choose another path)",
                 link_path);
        return -1;
    }
    for (k = 0; k < 100; ++k) {
        if (snprintf(tmp, sizeof tmp, "%s.%ld.%d", link_path, (long)getpid(), k) >=
            (int)sizeof tmp) {
            snprintf(err, errlen, "--link %s: path too long", link_path);
            return -1;
        }
        if (symlink(pty, tmp) == 0) {
            break;
        }
        if (errno != EEXIST) {
            snprintf(err, errlen, "--link %s: %s", tmp, strerror(errno));
            return -1;
        }
    }
    if (k == 100 || !is_stale_pty_link(link_path) || rename(tmp, link_path) != 0) {
        snprintf(err, errlen, "--link %s: cannot replace the stale pty link", link_path);
        if (k < 100) {
            unlink(tmp);
        }
        return -1;
    }
    return 0;
}

void qnav_ptylink_remove(const char *link_path, const char *pty)
{
    char target[256];
    struct stat st;
    if (link_path != NULL && lstat(link_path, &st) == 0 && S_ISLNK(st.st_mode) &&
        link_target(link_path, target, sizeof target) == 0 && strcmp(target, pty) == 0) {
        unlink(link_path);
    }
}
