/*
 * The compact map on an ATmega128 at 16 MHz, under simavr (docs/performance.md, "The map
 * on the ATmega128"): the TekBot's episodes of bench_map_trace.h (the simulator's poses and
 * scans in generated worlds of three families) replayed through qnav_map_follow(),
 * qnav_map_observe() and qnav_map_guide() as a board does each tick, over the map the board
 * places in its [map] bytes. Prints, per world, the cycles of each call
 * and of the tick (min / median / max), the peak stack below the caller and the map's
 * bytes; a tick whose sub-goal, planned distance or flags differ from the host's prints a
 * MISMATCH line, and the program exits 1.
 */
#include <stdint.h>
#include <string.h>

#include "avr_clock.h"
#include "bench_map_trace.h"
#include "qnav/map.h"
#include "target_io.h"

static const qnav_bench_map_world_t worlds[QNAV_BENCH_MAP_WORLDS] = QNAV_BENCH_MAP_WORLD_LIST;
static uint16_t map_mem[(QNAV_BENCH_MAP_BYTES + 1u) / 2u];
static qnav_map_t map;
/* a tick's cycles / 16 in each call for the medians (at most 300 ticks a world); the
 * tick's are their sums (a third array would leave the stack too little of the 4 KB beside
 * the board's map, the profile's [map] bytes) */
static uint16_t obs_c[300], guide_c[300];
static uint32_t overhead;

static void sort16(uint16_t *v, uint16_t n)
{
    uint16_t i, j;
    for (i = 1; i < n; ++i) {
        const uint16_t x = v[i];
        for (j = i; j > 0u && v[j - 1u] > x; --j) {
            v[j] = v[j - 1u];
        }
        v[j] = x;
    }
}

/* The median of a[k] + b[k] over k < n (the lower one, as sorting gives), found by rank
 * without a third array. */
static uint32_t median_of_sums(const uint16_t *a, const uint16_t *b, uint16_t n)
{
    const uint16_t want = (uint16_t)((n - 1u) / 2u);
    uint16_t i, j;
    for (i = 0; i < n; ++i) {
        const uint32_t s = (uint32_t)a[i] + b[i];
        uint16_t less = 0u, same = 0u;
        for (j = 0; j < n; ++j) {
            const uint32_t t = (uint32_t)a[j] + b[j];
            less = (uint16_t)(less + (t < s));
            same = (uint16_t)(same + (t == s));
        }
        if (less <= want && want < less + same) {
            return s;
        }
    }
    return 0u;
}

/* "name min / median / max cycles": the exact min and max, the median of values kept / 16 */
static void put_spread(const char *name_flash, uint32_t median16, uint32_t lo, uint32_t hi)
{
    qnav_avr_put_flash(name_flash);
    qnav_target_put_u32(lo);
    PUT(" / ");
    qnav_target_put_u32(median16 * 16u);
    PUT(" / ");
    qnav_avr_put_cycles(hi);
    PUT("\n");
}

static uint32_t sorted_median(uint16_t *v, uint16_t n)
{
    sort16(v, n);
    return v[(n - 1u) / 2u];
}

static uint32_t timed_end(void)
{
    return qnav_avr_timer_stop() - overhead;
}

/* A replayed world's spreads, then the follow's move timed with the robot at the map's
 * corner cell (every cell moves: the most a tick can add). */
static void put_world(const qnav_bench_map_world_t *w, const qnav_map_config_t *mc,
                      const uint32_t *lo, const uint32_t *hi, uint16_t *peak)
{
    const qnav_map_pose_t corner = {map.x0_mm + (int32_t)mc->cell_mm / 2,
                                    map.y0_mm + (int32_t)mc->cell_mm / 2, 0};
    const uint32_t tick16 = median_of_sums(obs_c, guide_c, w->n_ticks);
    uint32_t c;
    uint16_t sp, used;
    int moved;
    put_spread(PSTR("  follow + observe min / median / max: "), sorted_median(obs_c, w->n_ticks),
               lo[0], hi[0]);
    put_spread(PSTR("  guide            min / median / max: "),
               sorted_median(guide_c, w->n_ticks), lo[1], hi[1]);
    put_spread(PSTR("  tick             min / median / max: "), tick16, lo[2], hi[2]);
    sp = qnav_avr_paint();
    qnav_avr_timer_start();
    moved = qnav_map_follow(&map, &corner, w->goal_x_mm, w->goal_y_mm);
    c = timed_end();
    used = qnav_avr_stack_used(sp);
    *peak = used > *peak ? used : *peak;
    PUT("  the map moved by the follow (the robot at its corner): ");
    qnav_avr_put_cycles(moved ? c : 0u);
    PUT("\n");
}

/* One world's episode; the number of ticks that differ from the host's. */
static uint16_t replay(const qnav_bench_map_world_t *w, const qnav_map_config_t *mc,
                       const qnav_ctrl_config_t *cc, uint16_t *peak)
{
    qnav_bench_map_tick_t t;
    qnav_mm_t ranges[QNAV_BENCH_MAP_MAX_SECTORS];
    uint32_t lo[3] = {UINT32_MAX, UINT32_MAX, UINT32_MAX}, hi[3] = {0, 0, 0};
    uint16_t k, bad = 0;
    const qnav_status_t st =
        qnav_map_init(&map, mc, cc, w->x0_mm, w->y0_mm, w->side_mm, w->side_mm, map_mem,
                      QNAV_BENCH_MAP_BYTES);
    if (st != QNAV_OK) {
        PUT("the map does not start: ");
        qnav_target_put(qnav_status_str(st));
        PUT("\n");
        return 1;
    }
    for (k = 0; k < w->n_ticks; ++k) {
        qnav_ctrl_input_t in;
        qnav_map_pose_t p;
        uint32_t c[3];
        uint16_t sp, i;
        int got;
        memcpy_P(&t, &w->ticks[k], sizeof t);
        for (i = 0; i < QNAV_BENCH_MAP_MAX_SECTORS; ++i) {
            ranges[i] = t.ranges_mm[i];
        }
        p.x_mm = t.x_mm;
        p.y_mm = t.y_mm;
        p.heading_cdeg = t.heading_cdeg;
        memset(&in, 0, sizeof in);
        in.ranges_mm = ranges;
        sp = qnav_avr_paint();
        qnav_avr_timer_start();
        (void)qnav_map_follow(&map, &p, w->goal_x_mm, w->goal_y_mm); /* as the board */
        qnav_map_observe(&map, ranges, &p);
        c[0] = timed_end();
        qnav_avr_timer_start();
        got = qnav_map_guide(&map, &p, w->goal_x_mm, w->goal_y_mm, &in);
        c[1] = timed_end();
        i = qnav_avr_stack_used(sp);
        *peak = i > *peak ? i : *peak;
        c[2] = c[0] + c[1];
        for (i = 0; i < 3u; ++i) {
            lo[i] = c[i] < lo[i] ? c[i] : lo[i];
            hi[i] = c[i] > hi[i] ? c[i] : hi[i];
        }
        obs_c[k] = (uint16_t)(c[0] / 16u > 0xFFFFu ? 0xFFFFu : c[0] / 16u);
        guide_c[k] = (uint16_t)(c[1] / 16u > 0xFFFFu ? 0xFFFFu : c[1] / 16u);
        if (in.goal_bearing_cdeg != t.bearing_cdeg || in.goal_range_mm != t.range_mm ||
            got != t.flags) {
            PUT("MISMATCH tick ");
            qnav_target_put_u32(k);
            PUT(": bearing ");
            qnav_target_put_i32(in.goal_bearing_cdeg);
            PUT(" (host ");
            qnav_target_put_i32(t.bearing_cdeg);
            PUT("), distance ");
            qnav_target_put_u32(in.goal_range_mm);
            PUT(" (host ");
            qnav_target_put_u32(t.range_mm);
            PUT(")\n");
            ++bad;
        }
    }
    put_world(w, mc, lo, hi, peak);
    return bad;
}

int main(void)
{
    qnav_map_config_t mc = QNAV_BENCH_MAP_CONFIG;
    qnav_ctrl_config_t cc;
    uint16_t bad = 0, peak = 0;
    uint8_t k;
    if (qnav_avr_flash_data_too_far()) {
        qnav_target_exit(1u);
    }
    qnav_avr_timer_start();
    overhead = qnav_avr_timer_stop();
    QNAV_BENCH_MAP_CTRL_CONFIG(&cc);
    PUT("qnav AVR map benchmark: ATmega128, 16 MHz, simavr; compact map, cells of ");
    qnav_target_put_u32(mc.cell_mm);
    PUT(" mm\n");
    for (k = 0; k < QNAV_BENCH_MAP_WORLDS; ++k) {
        PUT("map ");
        qnav_target_put(worlds[k].name);
        PUT(": ");
        qnav_target_put_u32(worlds[k].n_ticks);
        PUT(" ticks, ");
        qnav_target_put_u32(qnav_map_size(&mc, worlds[k].side_mm, worlds[k].side_mm));
        PUT(" bytes of map\n");
        bad = (uint16_t)(bad + replay(&worlds[k], &mc, &cc, &peak));
    }
    PUT("map peak stack (follow, observe, guide): ");
    qnav_target_put_u32(peak);
    PUT(" bytes; sizeof(qnav_map_t) ");
    qnav_target_put_u32(sizeof(qnav_map_t));
    PUT(" bytes\n");
    if (bad != 0u) {
        PUT("map ticks that differ from the host's: ");
        qnav_target_put_u32(bad);
        PUT("\n");
    }
    qnav_target_exit(bad != 0u ? 1u : 0u);
    return 0;
}
