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
 * Within 2^16 mm of the pivot (any pose on a board's map: 11.2 m for the TekBot's) each
 * product is below 2^30 and 32 bits do (an AVR's 64-bit product costs a thousand cycles);
 * farther (a map of 1 m cells spans up to 192 m), 64. */
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

/* Cosine and sine (Q2.14) of a, 0.01 deg, 0..35999: a multiple of 45 deg exactly (four
 * times a sector's direction at 4, 8, 16 or 32 sectors), else by the CORDIC. */
static void of_angle(int32_t a, int16_t *c, int16_t *s)
{
    static const int16_t eighths[8] = {16384, 11585, 0, -11585, -16384, -11585, 0, 11585};
    if (a % 4500 == 0) {
        *c = eighths[a / 4500];
        *s = eighths[(a / 4500 + 6) % 8];
        return;
    }
    qnav_cos_sin_q14(a, c, s);
}

int qnav_align_observe(qnav_map_t *m, const qnav_mm_t *ranges_mm, const qnav_map_pose_t *pose)
{
    const uint16_t n = m->n_sectors;
    const uint16_t before = m->align_n;
    uint16_t k, counted = 0u;
    int32_t est, off, tc = 0, ts = 0;
    int16_t hc, hs;
    if (m->cfg.align_samples == 0u || n < 3u) {
        return 0;
    }
    /* this tick's readings in the robot's frame (four times their directions), then turned
     * by four times the heading once: a CORDIC is thousands of an AVR's cycles */
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
        of_angle((int32_t)(4u * (at * 18000u / n) % 36000u), &c, &s); /* sector k: k 36000 / n */
        tc += c;
        ts += s;
        ++counted;
    }
    if (counted == 0u) {
        return 0;
    }
    qnav_cos_sin_q14(4 * (int32_t)qnav_wrap_cdeg(pose->heading_cdeg) % 36000, &hc, &hs);
    if (tc > -65536 && tc < 65536 && ts > -65536 && ts < 65536) { /* products below 2^30 */
        m->align_c += ((int32_t)hc * tc - (int32_t)hs * ts) / 16384;
        m->align_s += ((int32_t)hs * tc + (int32_t)hc * ts) / 16384;
    } else { /* more than 4 readings a tick (more than 8 sectors): 64 bits */
        m->align_c += (int32_t)(((int64_t)hc * tc - (int64_t)hs * ts) / 16384);
        m->align_s += (int32_t)(((int64_t)hs * tc + (int64_t)hc * ts) / 16384);
    }
    m->align_n = (uint16_t)(m->align_n + counted);
    if (m->align_n >= COUNT_MAX) {
        m->align_c /= 2;
        m->align_s /= 2;
        m->align_n /= 2u;
    }
    /* whether the readings agree, every 8 counted (an arctangent a tick is most of the cost) */
    if (m->align_n / 8u == before / 8u || !agreed(m, &est)) {
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
