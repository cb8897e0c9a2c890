/*
 * Policy files on the host: read, write and check the versioned text format described in
 * docs/policy-format.md. Every program that loads a policy goes through here, so a bad
 * file is refused the same way everywhere: one line naming the file, the line and the
 * problem.
 */
#ifndef QNAV_POLICY_IO_H
#define QNAV_POLICY_IO_H

#include <stddef.h>
#include "qnav/policy.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Size of an error buffer that always holds a full message. */
#define QNAV_POLICY_IO_ERRLEN 512

/*
 * Read the policy file at path into *out. Returns 0 on success; on failure returns -1,
 * leaves *out untouched and writes "PATH:LINE: what is wrong" into err (errlen bytes).
 */
int qnav_policy_read(const char *path, qnav_policy_t *out, char *err, size_t errlen);

/* Same, from a string in memory; name is used in error messages in place of a path. */
int qnav_policy_parse(const char *text, size_t len, const char *name, qnav_policy_t *out,
                      char *err, size_t errlen);

/*
 * Write policy to path atomically (a temporary file renamed into place), so that a reader
 * never sees half a file. comment (may be null) becomes a '#' line. 0 or -1 with err.
 */
int qnav_policy_write(const char *path, const qnav_policy_t *policy, const char *comment,
                      char *err, size_t errlen);

#ifdef __cplusplus
}
#endif

#endif /* QNAV_POLICY_IO_H */
