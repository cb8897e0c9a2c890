/*
 * The map's grid turned to the walls (map_align.h).
 *
 * A sonar's nearest reading of a wall lies along the wall's normal, give or take half a
 * wedge: a sector whose reading is nearer than both neighbours' points, from the robot's
 * heading, along a wall's normal. Walls at right angles have normals whose directions agree
 * modulo 90 deg, so the mean of four times those directions (as unit vectors: sums of their
 * cosines and sines) points four times the walls' direction, and its length against the
 * count says how much they agree (1: all alike; about 1 / sqrt(count) for directions at
 * random, as in a field of circles). Half a wedge of error a reading averages out as the
 * robot turns. The grid turns when enough readings agree well enough and it lies 5 deg or
 * more off them, about the map's centre (so a whole-arena map still covers its arena).
 */
#include "map_align.h"

#include "qnav/trig.h"

/* Readings nearer than this count: a far reading's wedge is wide and often an opening's edge. */
#define NEAR_MM 2000u
/* Every reading since the map began counts (halved at this count, so the sums stay below
 * 2^31): an estimate of the last few seconds' readings only wandered by 7 deg and turned
 * the grid again and again, each time forgetting the map. */
#define COUNT_MAX 65000u
/* qnav_atan2_cdeg takes |x|, |y| < 2^21 unclamped. */
#define ATAN2_MAX (INT32_C(1) << 21)
/* The grid turns when the readings agree to 40 % of the count (a field of circles: about
 * 1 / sqrt(count), 13 % at 60) and it lies this far off them, 0.01 deg (measured:
 * docs/architecture.md, "A grid turned to the walls"). */
#define AGREE_PCT 40u
#define OFF_CDEG 500

void qnav_align_start(qnav_map_t *m, int32_t x_mm, int32_t y_mm)
{
    m->pivot_x_mm = x_mm;
    m->pivot_y_mm = y_mm;
    m->grid_cdeg = 0;
    m->grid_cos = 16384;
    m->grid_sin = 0;
    m->align_n = 0u;
    m->align_c = 0;
    m->align_s = 0;
}

/* (x, y) turned about the pivot by the angle whose cosine is the grid's and sine s, Q2.14.
 * Within 2^16 mm of the pivot (every pose a map of at most 192 cells of 1 m can hold) each
 * product is below 2^30 and 32 bits do (an AVR's 64-bit product costs a thousand cycles);
 * farther, 64. */
static void turn(const qnav_map_t *m, int32_t *x_mm, int32_t *y_mm, int32_t s)
{
    const int32_t c = m->grid_cos, dx = *x_mm - m->pivot_x_mm, dy = *y_mm - m->pivot_y_mm;
    if (dx > -65536 && dx < 65536 && dy > -65536 && dy < 65536) {
        *x_mm = m->pivot_x_mm + (c * dx - s * dy) / 16384;
        *y_mm = m->pivot_y_mm + (s * dx + c * dy) / 16384;
    } else {
        *x_mm = (int32_t)(m->pivot_x_mm + ((int64_t)c * dx - (int64_t)s * dy) / 16384);
        *y_mm = (int32_t)(m->pivot_y_mm + ((int64_t)s * dx + (int64_t)c * dy) / 16384);
    }
}

void qnav_align_point(const qnav_map_t *m, int32_t *x_mm, int32_t *y_mm)
{
    if (m->grid_cdeg != 0) {
        turn(m, x_mm, y_mm, -(int32_t)m->grid_sin);
    }
}

void qnav_map_grid_to_pose(const qnav_map_t *m, int32_t *x_mm, int32_t *y_mm)
{
    if (m != NULL && x_mm != NULL && y_mm != NULL && m->grid_cdeg != 0) {
        turn(m, x_mm, y_mm, m->grid_sin);
    }
}

qnav_map_pose_t qnav_align_pose(const qnav_map_t *m, const qnav_map_pose_t *pose)
{
    qnav_map_pose_t p = *pose;
    qnav_align_point(m, &p.x_mm, &p.y_mm);
    p.heading_cdeg -= m->grid_cdeg;
    return p;
}

/* 1 with the agreed walls' direction modulo 90 deg in *dir (-4500..4499, 0.01 deg) when
 * enough readings agree well enough; else 0. */
static int agreed(const qnav_map_t *m, int32_t *dir)
{
    uint32_t len;
    int32_t c = m->align_c, s = m->align_s;
    unsigned shift = 0u;
    while (c >= ATAN2_MAX || c <= -ATAN2_MAX || s >= ATAN2_MAX || s <= -ATAN2_MAX) {
        c /= 2;
        s /= 2;
        ++shift;
    }
    *dir = qnav_atan2_cdeg(s, c, &len) / 4;
    /* len << shift is at most the sums' length, below 2^31 (x sqrt 2); AGREE_PCT % of a
     * reading's 16384 times the count below 2^29 */
    return m->align_n >= m->cfg.align_samples &&
           (len << shift) >= (uint32_t)AGREE_PCT * 16384u / 100u * m->align_n;
}

int qnav_align_observe(qnav_map_t *m, const qnav_mm_t *ranges_mm, const qnav_map_pose_t *pose)
{
    const uint16_t n = m->n_sectors;
    uint16_t k, counted = 0u;
    int32_t est, off;
    if (m->cfg.align_samples == 0u || n < 3u) {
        return 0;
    }
    for (k = 0; k < n; ++k) {
        const qnav_mm_t r = ranges_mm[k], right = ranges_mm[k + 1u == n ? 0u : k + 1u];
        uint32_t at = (uint32_t)k * 2u; /* half sectors */
        int16_t c, s;
        if (r >= m->max_range_mm || r >= NEAR_MM || r >= ranges_mm[k == 0u ? n - 1u : k - 1u] ||
            r > right) {
            continue;
        }
        if (r == right) { /* two alike: the wall's nearest point lies between them */
            if (r >= ranges_mm[(k + 2u) % n]) {
                continue;
            }
            ++at;
        }
        /* four times the reading's direction, wrapped: sector k's centre is k 36000 / n */
        qnav_cos_sin_q14(4 * (qnav_wrap_cdeg(pose->heading_cdeg) + (int32_t)(at * 18000u / n)) % 36000,
                         &c, &s);
        m->align_c += c;
        m->align_s += s;
        ++counted;
        if (++m->align_n >= COUNT_MAX) {
            m->align_c /= 2;
            m->align_s /= 2;
            m->align_n /= 2u;
        }
    }
    if (counted == 0u || !agreed(m, &est)) {
        return 0;
    }
    off = est - m->grid_cdeg; /* both in -4500..4499: off in -8999..8999, modulo 9000 */
    off += off < -4500 ? 9000 : (off >= 4500 ? -9000 : 0);
    if (off > -OFF_CDEG && off < OFF_CDEG) {
        return 0;
    }
    m->grid_cdeg = (int16_t)est;
    qnav_cos_sin_q14(est, &m->grid_cos, &m->grid_sin);
    return 1;
}
