/*
 * The map's tick on a Cortex-M4 (QEMU mps2-an386), instructions counted by
 * tools/cm4-icount: the TekBot's episodes of bench_map_trace.h (the simulator's poses and
 * scans in generated worlds of three families) replayed through qnav_map_follow(),
 * qnav_map_observe() and qnav_map_guide() as a board does each tick, twice:
 *
 *   compact  the board's map (the profile's [map] in its [map] bytes, placed as the trace
 *            says); every tick checked against the host's (MISMATCH line, exit status 1)
 *   full     the full layout at 0.1 m in 128 KB, placed and following by the same rule:
 *            what a board with that RAM would run (docs/results.md, "A map with room");
 *            the trace's robot drove with the compact map, so there is no host answer to
 *            check, only the cost
 *
 * Each tick prints `M<TAB>map<TAB>LAYOUT<TAB>WORLD<TAB>-`, the '-' the tick's count after
 * tools/cm4-icount (docs/performance.md, "The map on a Cortex-M4").
 */
#include <stdint.h>
#include <string.h>

#include "bench_map_trace.h"
#include "qnav/map.h"
#include "cm4_markers.h"
#include "target_io.h"

#define FULL_BYTES 131072u
#define FULL_CELL_MM 100u

static const qnav_bench_map_world_t worlds[QNAV_BENCH_MAP_WORLDS] = QNAV_BENCH_MAP_WORLD_LIST;
static uint32_t map_mem[FULL_BYTES / 4u];
static qnav_map_t map;

/* One world's ticks through the map; the number that differ from the host's (check). */
static uint32_t replay(const qnav_bench_map_world_t *w, const char *layout, int check)
{
    uint32_t bad = 0u;
    uint16_t k, i;
    for (k = 0; k < w->n_ticks; ++k) {
        const qnav_bench_map_tick_t *t = &w->ticks[k];
        qnav_mm_t ranges[QNAV_BENCH_MAP_MAX_SECTORS];
        qnav_ctrl_input_t in;
        qnav_map_pose_t p;
        int got;
        for (i = 0; i < QNAV_BENCH_MAP_MAX_SECTORS; ++i) {
            ranges[i] = t->ranges_mm[i];
        }
        p.x_mm = t->x_mm;
        p.y_mm = t->y_mm;
        p.heading_cdeg = t->heading_cdeg;
        memset(&in, 0, sizeof in);
        in.ranges_mm = ranges;
        qnav_bench_begin();
        (void)qnav_map_follow(&map, &p, w->goal_x_mm, w->goal_y_mm);
        qnav_map_observe(&map, ranges, &p);
        got = qnav_map_guide(&map, &p, w->goal_x_mm, w->goal_y_mm, &in);
        qnav_bench_end();
        qnav_target_put("M\tmap\t");
        qnav_target_put(layout);
        qnav_target_put("\t");
        qnav_target_put(w->name);
        qnav_target_put("\t-\n");
        if (check && (in.goal_bearing_cdeg != t->bearing_cdeg || in.goal_range_mm != t->range_mm ||
                      got != t->flags)) {
            qnav_target_put("MISMATCH ");
            qnav_target_put(w->name);
            qnav_target_put(" tick ");
            qnav_target_put_u32(k);
            qnav_target_put("\n");
            ++bad;
        }
    }
    return bad;
}

/* The map of one layout over world w: the compact one where the trace placed it, the full
 * one where qnav_map_place puts FULL_BYTES of it. 0 when it does not start. */
static int start(const qnav_bench_map_world_t *w, const qnav_map_config_t *mc,
                 const qnav_ctrl_config_t *cc)
{
    int32_t x0 = w->x0_mm, y0 = w->y0_mm;
    uint32_t side = w->side_mm;
    const size_t len = mc->compact ? (size_t)QNAV_BENCH_MAP_BYTES : (size_t)FULL_BYTES;
    if (!mc->compact && !qnav_map_place(mc, len, w->ticks[0].x_mm, w->ticks[0].y_mm,
                                        w->goal_x_mm, w->goal_y_mm, &x0, &y0, &side)) {
        return 0;
    }
    return qnav_map_init(&map, mc, cc, x0, y0, side, side, map_mem, len) == QNAV_OK;
}

int main(void)
{
    qnav_map_config_t layouts[2] = {QNAV_BENCH_MAP_CONFIG, QNAV_BENCH_MAP_CONFIG};
    const char *names[2] = {"compact", "full"};
    qnav_ctrl_config_t cc;
    uint32_t bad = 0u;
    unsigned l, k;
    /* the full layout as the simulator makes it from the profile with [map] compact =
     * false, cell_m = 0.1: near costs and refusals at their defaults */
    qnav_map_config_default(&layouts[1]);
    layouts[1].cell_mm = FULL_CELL_MM;
    layouts[1].noise_pct = layouts[0].noise_pct;
    layouts[1].arc_cdeg = layouts[0].arc_cdeg;
    layouts[1].forget_reach_mm = layouts[0].forget_reach_mm;
    layouts[1].opening_mm = layouts[0].opening_mm;
    QNAV_BENCH_MAP_CTRL_CONFIG(&cc);
    qnav_target_put("qnav Cortex-M4 map benchmark: QEMU mps2-an386; values are instructions of "
                    "a tick's follow, observe and guide (tools/cm4-icount)\n");
    for (l = 0; l < 2u; ++l) {
        for (k = 0; k < QNAV_BENCH_MAP_WORLDS; ++k) {
            if (!start(&worlds[k], &layouts[l], &cc)) {
                qnav_target_put("the map does not start\n");
                qnav_target_exit(1u);
            }
            bad += replay(&worlds[k], names[l], l == 0u);
        }
    }
    qnav_target_exit(bad != 0u ? 1u : 0u);
    return 0;
}
