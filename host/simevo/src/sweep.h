/*
 * Sweeps: several experiments, or one experiment over a list of values of one setting of
 * its target situation, run through the same path as a single experiment (docs/cluster.md,
 * "Sweeps"). A sweep member is an experiment file plus an optional "KEY=VALUE" variation
 * (`simevo run FILE --vary KEY=VALUE`); a variation renames the experiment to
 * NAME.KEY-VALUE, so every member has its own folder and run.txt.
 */
#ifndef QNAV_SIMEVO_SWEEP_H
#define QNAV_SIMEVO_SWEEP_H

#include <functional>
#include <string>
#include <vector>

#include "spec.h"

namespace qnav {

/* The keys a variation may set, comma-separated ("noise, sectors"). */
std::string vary_key_names();
/* Applies "KEY=VALUE" to spec's target situation and renames spec to NAME.KEY-VALUE
 * (VALUE in its shortest exact form). Throws UserError naming --vary. */
void apply_vary(ExperimentSpec &spec, const std::string &vary);

struct SweepMember {
    std::string experiment_file; /* as resolved: a path */
    std::string vary;            /* "" or "KEY=VALUE" */
    std::string name;            /* the member's experiment name (its folder) */
};

struct Sweep {
    std::string file; /* where it was read from */
    std::string name; /* [a-z0-9-_], the sweep folder OUT/<name> */
    std::vector<SweepMember> members;
};

/* True when the TOML file at path is a sweep (it has `experiments`, `experiment` or
 * `vary`, keys no experiment file has). False for anything else, unreadable included. */
bool is_sweep_file(const std::string &path);
/* Reads and checks a sweep file (every member's experiment file parsed too). A member
 * given by name goes through resolve (name -> path; throws UserError); one given as a
 * path (with '/' or ending in .toml) is relative to the sweep file's folder. Throws
 * UserError "FILE:LINE: problem". */
Sweep load_sweep(const std::string &path, const std::function<std::string(const std::string &)> &resolve);

/* OUT/<sweep>/sweep.txt: the members' names, one "member = NAME" per line. */
std::string sweep_record_text(const Sweep &sweep);
/* Makes out_dir/<sweep> and writes its sweep.txt; a sweep.txt there with other members, or
 * an experiment folder (run.txt) of that name, is refused. Returns the folder. Throws
 * UserError. */
std::string write_sweep_record(const std::string &out_dir, const Sweep &sweep);
/* The member names of sweep.txt text (path names it in errors). Throws UserError. */
std::vector<std::string> parse_sweep_record(const std::string &text, const std::string &path);

} // namespace qnav

#endif
