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
#include "qnav/check.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Size of an error buffer that always holds a full message. */
#define QNAV_POLICY_IO_ERRLEN 512

/* What a policyio call that can fail returns (the sim layer's shape, qnav_sim_status_t):
 * 0, or a negative status with one line for people kept in the caller's err buffer. */
typedef enum {
    QNAV_POLICY_IO_OK = 0,
    QNAV_POLICY_IO_E_NULL = -1,    /* a required argument was null */
    QNAV_POLICY_IO_E_IO = -2,      /* a file could not be opened, read or written */
    QNAV_POLICY_IO_E_PARSE = -3,   /* a policy file breaks the format (docs/policy-format.md) */
    QNAV_POLICY_IO_E_INVALID = -4, /* a policy, metadata entry or comment breaks the rules */
    QNAV_POLICY_IO_E_NAME = -5,    /* no policy kind has that name */
    QNAV_POLICY_IO_E_NOMEM = -6    /* allocation failed */
} qnav_policy_io_status_t;

/* A short text for a status ("bad policy file", ...); never null. */
const char *qnav_policy_io_status_str(qnav_policy_io_status_t status);

/*
 * Read the policy file at path into *out. Returns QNAV_POLICY_IO_OK; on failure _E_IO
 * (cannot open or read), _E_PARSE (not a good policy file), _E_NULL or _E_NOMEM, leaves
 * *out untouched and writes "PATH:LINE: what is wrong" into err (errlen bytes).
 */
QNAV_CHECK_RESULT qnav_policy_io_status_t qnav_policy_read(const char *path, qnav_policy_t *out, char *err, size_t errlen);

/* Same, from a string in memory; name is used in error messages in place of a path.
 * _OK, _E_PARSE, _E_NULL or _E_NOMEM. */
QNAV_CHECK_RESULT qnav_policy_io_status_t qnav_policy_parse(const char *text, size_t len, const char *name, qnav_policy_t *out,
                      char *err, size_t errlen);

/*
 * Write policy to path atomically (a temporary file renamed into place), so that a reader
 * never sees half a file. comment (may be null) becomes a '#' line. _OK, or with err
 * _E_INVALID (the policy, metadata or comment), _E_IO, _E_NULL or _E_NOMEM.
 */
QNAV_CHECK_RESULT qnav_policy_io_status_t qnav_policy_write(const char *path, const qnav_policy_t *policy, const char *comment,
                      char *err, size_t errlen);

/* ---- Additions: format limits, metadata, in-memory rendering, checks ---------------- */

/* The format versions this library reads (line 1: "qnav-policy 1" or "qnav-policy 2").
 * It writes the oldest version that can hold the policy: 1, or 2 for a network with the
 * previous-decision input (docs/policy-format.md). */
#define QNAV_POLICY_FORMAT_VERSION 2
#define QNAV_POLICY_FORMAT_VERSION_MIN 1
/* Longest line, in bytes, not counting the line ending. */
#define QNAV_POLICY_LINE_MAX 256
/* Largest file the reader accepts, in bytes. */
#define QNAV_POLICY_FILE_MAX (1024L * 1024L)
/* Longest comment qnav_policy_write() accepts, in bytes. */
#define QNAV_POLICY_COMMENT_MAX 4096
/* Metadata limits: entries per file, name length, value length (bytes, without NUL). */
#define QNAV_POLICY_META_MAX 16
#define QNAV_POLICY_META_NAME_MAX 31
#define QNAV_POLICY_META_VALUE_MAX 200

/* One "meta NAME TEXT" line. */
typedef struct {
    char name[QNAV_POLICY_META_NAME_MAX + 1];   /* [A-Za-z0-9_.-], 1..31 bytes */
    char value[QNAV_POLICY_META_VALUE_MAX + 1]; /* 1..200 bytes, no '#', no control
                                                   characters, no surrounding blanks */
} qnav_policy_meta_entry_t;

/* The metadata of one file, in file order. Zero it with qnav_policy_meta_clear(). */
typedef struct {
    size_t count; /* 0..QNAV_POLICY_META_MAX */
    qnav_policy_meta_entry_t entry[QNAV_POLICY_META_MAX];
} qnav_policy_meta_t;

void qnav_policy_meta_clear(qnav_policy_meta_t *meta);

/* Add or replace an entry. _OK; _E_INVALID with a message in err when the name or value
 * breaks the rules above or the table is full; _E_NULL. */
QNAV_CHECK_RESULT qnav_policy_io_status_t qnav_policy_meta_set(qnav_policy_meta_t *meta, const char *name, const char *value,
                         char *err, size_t errlen);

/* The value of an entry, or null when there is none. */
const char *qnav_policy_meta_get(const qnav_policy_meta_t *meta, const char *name);

/* qnav_policy_read / qnav_policy_parse that also keep the metadata lines (meta may be
 * null). On failure neither *out nor *meta is touched. Statuses as theirs. */
QNAV_CHECK_RESULT qnav_policy_io_status_t qnav_policy_read_meta(const char *path, qnav_policy_t *out, qnav_policy_meta_t *meta,
                          char *err, size_t errlen);
QNAV_CHECK_RESULT qnav_policy_io_status_t qnav_policy_parse_meta(const char *text, size_t len, const char *name,
                           qnav_policy_t *out, qnav_policy_meta_t *meta, char *err,
                           size_t errlen);

/* qnav_policy_write with metadata lines (meta may be null). Statuses as its. */
QNAV_CHECK_RESULT qnav_policy_io_status_t qnav_policy_write_meta(const char *path, const qnav_policy_t *policy,
                           const qnav_policy_meta_t *meta, const char *comment, char *err,
                           size_t errlen);

/*
 * Render a policy file into buf (buflen bytes, NUL-terminated when buflen > 0), like
 * snprintf: returns the length of the full text (without NUL), which is >= buflen when buf
 * was too small; or QNAV_POLICY_IO_E_INVALID (negative) with err when the policy,
 * metadata or comment is invalid. (A length, so an int: the one call here that does not
 * return a qnav_policy_io_status_t.)
 */
QNAV_CHECK_RESULT int qnav_policy_format(const qnav_policy_t *policy, const qnav_policy_meta_t *meta,
                       const char *comment, char *buf, size_t buflen, char *err,
                       size_t errlen);

/* Check a policy in memory against the rules of the format (which are those of
 * qnav_ctrl_init). _OK, or _E_INVALID with "what is wrong" (no file prefix) in err. */
QNAV_CHECK_RESULT qnav_policy_io_status_t qnav_policy_check(const qnav_policy_t *policy, char *err, size_t errlen);

/* 1 when a and b are the same policy (kind, shape and every weight in use), else 0. */
int qnav_policy_equal(const qnav_policy_t *a, const qnav_policy_t *b);

/* The file name of a policy kind ("probabilistic", "network"), or null for an unknown one. */
const char *qnav_policy_kind_name(uint8_t kind);

/* Every policy kind's file name, in the order of qnav_policy_kind_t, each between quote
 * ("" for none), sep between two and last between the last two, into buf (len bytes,
 * always NUL-terminated when len > 0, cut short if too small); returns buf. E.g. quote
 * "'", sep ", ", last " or ": "'probabilistic' or 'network'". For help and messages, so
 * that no list of kinds is kept beside the kinds' own. */
const char *qnav_policy_kind_list(char *buf, size_t len, const char *quote, const char *sep,
                                  const char *last);

/* The kind named by the len bytes at name: _OK with *kind, or _E_NAME when no kind has
 * that name. */
QNAV_CHECK_RESULT qnav_policy_io_status_t qnav_policy_kind_from_name(const char *name, size_t len, uint8_t *kind);

/* The format version qnav_policy_format() writes for policy (1 or 2). */
int qnav_policy_file_version(const qnav_policy_t *policy);

/* Write len bytes to path atomically (temporary file in the same directory, fsync,
 * rename, fsync of the directory). _OK, or _E_IO, _E_NULL or _E_NOMEM with "PATH: what
 * failed" in err. */
QNAV_CHECK_RESULT qnav_policy_io_status_t qnav_policy_io_write_atomic(const char *path, const void *data, size_t len, char *err,
                                size_t errlen);

#ifdef __cplusplus
}
#endif

#endif /* QNAV_POLICY_IO_H */
