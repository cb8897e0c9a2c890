/*
 * The map's benchmark trace (bench/map_trace.c): written by qnav_bench_fixtures beside the
 * other fixtures.
 */
#ifndef QNAV_BENCH_MAP_TRACE_GEN_H
#define QNAV_BENCH_MAP_TRACE_GEN_H

/* Write out_dir/bench_map_trace.h from the simulator in source tree root; note names the
 * generator (fails with exit 1 or 2, as the other fixtures). */
void qnav_fx_write_map_trace(const char *root, const char *out_dir, const char *note);

#endif
