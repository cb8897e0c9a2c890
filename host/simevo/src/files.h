/*
 * Small file helpers for simevo's outputs: atomic whole-file writes (temporary file in the
 * same folder, then rename, so a reader or a resumed run never sees half a file), whole
 * file reads, and recursive directory creation. Errors throw UserError naming the path.
 */
#ifndef QNAV_SIMEVO_FILES_H
#define QNAV_SIMEVO_FILES_H

#include <string>

namespace qnav {

void write_file_atomic(const std::string &path, const std::string &content);
/* Write all of s to fd (retrying short writes); path names the file in the error. */
void write_all(int fd, const std::string &s, const std::string &path);
/* Returns false if the file does not exist; throws on other read errors. */
bool read_file(const std::string &path, std::string &out);
bool file_exists(const std::string &path);
void make_dirs(const std::string &path);
std::string join_path(const std::string &a, const std::string &b);

} // namespace qnav

#endif
