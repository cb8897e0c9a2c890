/*
 * The --link PATH of the programs that play a board on a pseudo-terminal (qnav-sil-robot,
 * qnav-simavr-board): PATH becomes a symlink to the pty so that navbridge --device PATH
 * finds it. Neither program ever deletes or overwrites a file it did not create: an
 * existing PATH is refused unless it is a dangling symlink into /dev/pts/ (the link of a
 * killed earlier run), and at exit PATH is removed only while it is still the link this
 * program made.
 */
#ifndef QNAV_PTYLINK_H
#define QNAV_PTYLINK_H

#include <stddef.h>

/* Make link_path a symlink to pty (a /dev/pts/N name). A stale pty link left by a killed
 * earlier run (a symlink to a /dev/pts/ name that no longer exists) is replaced; anything
 * else at link_path, a live pty link included, is left alone and refused. 0, or -1 with
 * the reason in err. */
int qnav_ptylink_make(const char *link_path, const char *pty, char *err, size_t errlen);

/* Remove link_path if it is still a symlink to pty; otherwise leave it. */
void qnav_ptylink_remove(const char *link_path, const char *pty);

#endif
