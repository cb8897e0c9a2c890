/*
 * The map and its plan (qnav/map.h): what a reading marks, a plan round a wall to its gap,
 * the escape memory cleared when the plan's way closes, a way the robot cannot take refused
 * for a while, and bad maps refused. Scans come from a
 * small ray marcher over rectangles written here, so each sector reports the nearest
 * obstacle point inside its wedge, as the simulator's sonar does.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "map_compact.h"
#include "map_plain.h"
#include "qnav/map.h"
#include "qnav/trig.h"

#define N 16
#define WORLD_MM 6000
#define CELLS_MAX 4000

static uint16_t mem[CELLS_MAX * 4];

typedef struct {
    int32_t x0, y0, x1, y1;
} box_t;

/* A wall across the world at y 2950..3050 with a gap at x 4500..5300. */
static const box_t wall_with_gap[] = {{0, 2950, 4500, 3050}, {5300, 2950, WORLD_MM, 3050}};

static void sensor_config(qnav_ctrl_config_t *cfg)
{
    qnav_ctrl_config_default(cfg);
    cfg->n_sectors = N;
    cfg->max_range_mm = 2500;
    cfg->sensor_offset_mm = 120;
    cfg->body_radius_mm = 120;
    cfg->safety_mm = 50;
}

/* A map of the world with configuration mc, for the sensor above. */
static void map_from(qnav_map_t *m, const qnav_map_config_t *mc)
{
    qnav_ctrl_config_t cc;
    sensor_config(&cc);
    assert_true(qnav_map_cells(WORLD_MM, WORLD_MM, mc->cell_mm) <= CELLS_MAX);
    assert_int_equal(qnav_map_init(m, mc, &cc, 0, 0, WORLD_MM, WORLD_MM, mem, sizeof mem),
                     QNAV_OK);
}

static void map_with(qnav_map_t *m, uint8_t plan_ticks, uint16_t arc_cdeg, uint8_t sight)
{
    qnav_map_config_t mc;
    qnav_map_config_default(&mc);
    mc.plan_ticks = plan_ticks;
    mc.arc_cdeg = arc_cdeg;
    mc.sight = sight;
    map_from(m, &mc);
}

static void map_of(qnav_map_t *m, uint8_t plan_ticks)
{
    map_with(m, plan_ticks, 2250, 1);
}

static int inside(const box_t *boxes, size_t n, int32_t x, int32_t y)
{
    size_t i;
    for (i = 0; i < n; ++i) {
        if (x >= boxes[i].x0 && x <= boxes[i].x1 && y >= boxes[i].y0 && y <= boxes[i].y1) {
            return 1;
        }
    }
    return 0;
}

/* Each sector's reading from pose: the nearest box point on 24 rays across its wedge,
 * marched in 5 mm steps, less the sensor offset, clipped to the range. */
static void scan_of(const box_t *boxes, size_t n, const qnav_map_pose_t *p, qnav_mm_t *ranges,
                    int sectors)
{
    int k, r;
    for (k = 0; k < sectors; ++k) {
        int32_t best = 2500 + 120;
        for (r = 0; r < 24; ++r) {
            const int32_t a = p->heading_cdeg + k * 36000 / sectors - 36000 / sectors / 2 +
                              (36000 / sectors) * r / 23;
            int16_t c, s;
            int32_t d;
            qnav_cos_sin_q14(a, &c, &s);
            for (d = 0; d < best; d += 5) {
                if (inside(boxes, n, p->x_mm + d * c / 16384, p->y_mm + d * s / 16384)) {
                    best = d;
                    break;
                }
            }
        }
        ranges[k] = (qnav_mm_t)(best - 120 > 2500 ? 2500 : (best < 120 ? 0 : best - 120));
    }
}

static void scan(const box_t *boxes, size_t n, const qnav_map_pose_t *p, qnav_mm_t *ranges)
{
    scan_of(boxes, n, p, ranges, N);
}

/* Every sector clear but the one straight ahead, which reads ahead_mm. */
static void clear_but_ahead(qnav_mm_t *ranges, qnav_mm_t ahead_mm)
{
    int k;
    for (k = 0; k < N; ++k) {
        ranges[k] = 2500;
    }
    ranges[0] = ahead_mm;
}

/* arc_cdeg: the arc is marked only near the wedge's centre line. */
static void test_arcs_are_marked_in_the_central_part_of_the_wedge(void **state)
{
    qnav_map_t m;
    qnav_mm_t ranges[N];
    const qnav_map_pose_t p = {3050, 3050, 0};
    (void)state;
    clear_but_ahead(ranges, 1000); /* 1 120 mm from the centre; the wedge is +-11.25 deg */
    map_with(&m, 10, 2250, 1);
    qnav_map_observe(&m, ranges, &p);
    assert_int_equal(qnav_map_evidence(&m, 4170, 3050), 1); /* dead ahead */
    assert_int_equal(qnav_map_evidence(&m, 4150, 3250), 1); /* 10 deg off, on the arc */
    map_with(&m, 10, 562, 1);                              /* +-2.8 deg */
    qnav_map_observe(&m, ranges, &p);
    assert_int_equal(qnav_map_evidence(&m, 4170, 3050), 1);
    assert_int_equal(qnav_map_evidence(&m, 4150, 3250), 0);
}

/* At 8 sectors a wedge is 45 deg wide, wider than the default arc (22.5 deg): its reading
 * marks occupied only the arc's central cells, and still frees the whole wedge nearer. */
static void test_a_wide_wedge_marks_only_the_default_arc(void **state)
{
    qnav_map_t m;
    qnav_map_config_t mc;
    qnav_ctrl_config_t cc;
    qnav_mm_t ranges[8];
    const qnav_map_pose_t p = {3050, 3050, 0};
    int k;
    (void)state;
    sensor_config(&cc);
    cc.n_sectors = 8;
    for (k = 0; k < 8; ++k) {
        ranges[k] = 2500;
    }
    ranges[0] = 1000; /* 1 120 mm from the centre */
    qnav_map_config_default(&mc);
    assert_int_equal(mc.arc_cdeg, 2250);
    assert_int_equal(qnav_map_init(&m, &mc, &cc, 0, 0, WORLD_MM, WORLD_MM, mem, sizeof mem),
                     QNAV_OK);
    qnav_map_observe(&m, ranges, &p);
    assert_int_equal(qnav_map_evidence(&m, 4170, 3050), 1); /* dead ahead */
    assert_int_equal(qnav_map_evidence(&m, 4150, 3250), 1); /* 10 deg off */
    assert_int_equal(qnav_map_evidence(&m, 4150, 3350), 0); /* 15 deg off: in the wedge, off the arc */
    assert_true(qnav_map_evidence(&m, 3800, 3350) < 0);     /* 20 deg off, nearer: free */
    mc.arc_cdeg = 4500;                                     /* the whole wedge, as before */
    assert_int_equal(qnav_map_init(&m, &mc, &cc, 0, 0, WORLD_MM, WORLD_MM, mem, sizeof mem),
                     QNAV_OK);
    qnav_map_observe(&m, ranges, &p);
    assert_int_equal(qnav_map_evidence(&m, 4150, 3350), 1);
}

/* arc_width_mm: a reading marks only the cells within that width of its centre line at its
 * range. 250 mm across is +-6.4 deg at 1 120 mm (10 deg off, inside the 22.5 deg arc, is
 * left unmarked) and +-11.6 deg at 620 mm (9.5 deg off is marked); 100 mm is +-4.6 deg
 * there (not marked). */
static void test_a_far_reading_marks_an_arc_no_wider_than_set(void **state)
{
    qnav_map_t m;
    qnav_map_config_t mc;
    qnav_mm_t ranges[N];
    const qnav_map_pose_t p = {3050, 3050, 0};
    (void)state;
    qnav_map_config_default(&mc);
    clear_but_ahead(ranges, 1000); /* 1 120 mm from the centre */
    mc.arc_width_mm = 250;
    map_from(&m, &mc);
    qnav_map_observe(&m, ranges, &p);
    assert_int_equal(qnav_map_evidence(&m, 4170, 3050), 1); /* dead ahead */
    assert_int_equal(qnav_map_evidence(&m, 4150, 3250), 0); /* 10 deg off: not marked */
    mc.arc_width_mm = 0;                                   /* no limit */
    map_from(&m, &mc);
    qnav_map_observe(&m, ranges, &p);
    assert_int_equal(qnav_map_evidence(&m, 4150, 3250), 1);
    clear_but_ahead(ranges, 500); /* 620 mm from the centre */
    mc.arc_width_mm = 250;
    map_from(&m, &mc);
    qnav_map_observe(&m, ranges, &p);
    assert_int_equal(qnav_map_evidence(&m, 3650, 3050), 1); /* dead ahead */
    assert_int_equal(qnav_map_evidence(&m, 3650, 3150), 1); /* 9.5 deg off: marked */
    mc.arc_width_mm = 100;
    map_from(&m, &mc);
    qnav_map_observe(&m, ranges, &p);
    assert_int_equal(qnav_map_evidence(&m, 3650, 3150), 0);
}

/* A map for a ring of n sectors, every reading clear but ahead (sector 0) and its two
 * neighbours, observed once from the centre facing +x. */
static void observe_ahead(qnav_map_t *m, uint16_t n, uint16_t opening_mm, qnav_mm_t ahead_mm,
                          qnav_mm_t left_mm, qnav_mm_t right_mm)
{
    qnav_map_config_t mc;
    qnav_ctrl_config_t cc;
    qnav_mm_t ranges[N];
    const qnav_map_pose_t p = {3050, 3050, 0};
    uint16_t k;
    sensor_config(&cc);
    cc.n_sectors = n;
    for (k = 0; k < n; ++k) {
        ranges[k] = 2500;
    }
    ranges[0] = ahead_mm;
    ranges[1] = left_mm;
    ranges[n - 1u] = right_mm;
    qnav_map_config_default(&mc);
    mc.opening_mm = opening_mm;
    assert_int_equal(qnav_map_init(m, &mc, &cc, 0, 0, WORLD_MM, WORLD_MM, mem, sizeof mem),
                     QNAV_OK);
    qnav_map_observe(m, ranges, &p);
}

/* opening_mm: in an aisle a 45 deg wedge ahead reads the side walls where its edges meet
 * them, nearer than anything ahead; the neighbouring wedges read the walls nearer still.
 * Such a range peak marks no arc where the wedge spans more than 2 opening_mm across
 * (270 mm: from 705 mm at 8 sectors, 1 384 mm at 16), so the way ahead stays open; it
 * still frees the cells short of it. A reading that is no peak, or nearer, marks. */
static void test_a_far_range_peak_in_a_wide_wedge_marks_no_arc(void **state)
{
    qnav_map_t m;
    (void)state;
    observe_ahead(&m, 8, 270, 1000, 500, 500); /* 1 120 mm from the centre */
    assert_int_equal(qnav_map_evidence(&m, 4150, 3050), 0); /* unmarked: maybe an opening */
    assert_true(qnav_map_evidence(&m, 3750, 3050) < 0);     /* nearer: free */
    observe_ahead(&m, 8, 0, 1000, 500, 500);                /* every reading marks */
    assert_int_equal(qnav_map_evidence(&m, 4150, 3050), 1);
    observe_ahead(&m, 8, 270, 1000, 2500, 500);             /* no peak: a wall's end */
    assert_int_equal(qnav_map_evidence(&m, 4150, 3050), 1);
    observe_ahead(&m, 8, 270, 1000, 500, 2500);
    assert_int_equal(qnav_map_evidence(&m, 4150, 3050), 1);
    observe_ahead(&m, 8, 270, 500, 300, 300);               /* a peak 620 mm away */
    assert_int_equal(qnav_map_evidence(&m, 3650, 3050), 1);
    observe_ahead(&m, 16, 270, 1000, 500, 500);             /* a 22.5 deg wedge: 440 mm there */
    assert_int_equal(qnav_map_evidence(&m, 4150, 3050), 1);
}

/* noise_pct: a noisy sonar's reading carves free only cells nearer than its noise, but marks
 * occupied only a thin band at the reading (3/4 cell + at most 5 %), so that one
 * obstacle's spread readings do not make it thick. */
static void test_a_noisy_reading_keeps_its_arc_thin(void **state)
{
    qnav_map_t m;
    qnav_map_config_t mc;
    qnav_mm_t ranges[N];
    const qnav_map_pose_t p = {3050, 3050, 0};
    (void)state;
    clear_but_ahead(ranges, 1000); /* 1 120 mm from the centre */
    qnav_map_config_default(&mc);
    assert_int_equal(mc.noise_pct, 5);
    map_from(&m, &mc);
    qnav_map_observe(&m, ranges, &p);
    assert_true(qnav_map_evidence(&m, 3950, 3050) < 0);     /* 220 mm nearer: free */
    assert_int_equal(qnav_map_evidence(&m, 4150, 3050), 1); /* at the reading */
    mc.noise_pct = 20;                                      /* free only 299 mm nearer */
    map_from(&m, &mc);
    qnav_map_observe(&m, ranges, &p);
    assert_int_equal(qnav_map_evidence(&m, 3950, 3050), 0); /* neither free nor occupied */
    assert_int_equal(qnav_map_evidence(&m, 3750, 3050), -1);
    assert_int_equal(qnav_map_evidence(&m, 4150, 3050), 1);
}

static void test_a_reading_frees_its_wedge_and_marks_its_arc(void **state)
{
    qnav_map_t m;
    qnav_mm_t ranges[N];
    const qnav_map_pose_t p = {3000, 3000, 0};
    (void)state;
    map_of(&m, 10);
    clear_but_ahead(ranges, 1000); /* an obstacle 1 120 mm ahead of the centre */
    qnav_map_observe(&m, ranges, &p);
    assert_true(qnav_map_evidence(&m, 3550, 3050) < 0);       /* inside the wedge, nearer */
    assert_int_equal(qnav_map_evidence(&m, 4150, 3050), 1);   /* on the arc: one count */
    assert_true(qnav_map_evidence(&m, 3050, 4550) < 0);       /* a clear sector, 1.5 m */
    assert_int_equal(qnav_map_evidence(&m, 3050, 5550), 0);   /* beyond the reach: unknown */
    qnav_map_observe(&m, ranges, &p);
    assert_int_equal(qnav_map_evidence(&m, 4150, 3050), QNAV_MAP_OCCUPIED);
    /* the same cell seen through, from elsewhere: free, and it stays free */
    ranges[0] = 2500;
    qnav_map_observe(&m, ranges, &p);
    assert_true(qnav_map_evidence(&m, 4150, 3050) < 0);
    ranges[0] = 1000;
    qnav_map_observe(&m, ranges, &p);
    assert_true(qnav_map_evidence(&m, 4150, 3050) <= 0);
}

/* A sonar shorter than the map's reach (1 m against 2 m): a reading at the range says
 * nothing beyond it, so a wall marked from nearer stays marked when the robot backs off
 * out of the sonar's sight; cells the sonar does see are still cleared. */
static void test_a_reach_beyond_the_sonar_keeps_what_it_cannot_see(void **state)
{
    qnav_map_t m;
    qnav_map_config_t mc;
    qnav_ctrl_config_t cc;
    qnav_mm_t ranges[N];
    const qnav_map_pose_t near = {3000, 3000, 0}, back = {2500, 3000, 0};
    int k;
    (void)state;
    qnav_map_config_default(&mc); /* reach 2 000 mm */
    sensor_config(&cc);
    cc.max_range_mm = 1000;
    assert_int_equal(qnav_map_init(&m, &mc, &cc, 0, 0, WORLD_MM, WORLD_MM, mem, sizeof mem),
                     QNAV_OK);
    for (k = 0; k < N; ++k) {
        ranges[k] = 1000;
    }
    ranges[0] = 800; /* a wall 920 mm ahead of the centre */
    qnav_map_observe(&m, ranges, &near);
    qnav_map_observe(&m, ranges, &near);
    assert_int_equal(qnav_map_evidence(&m, 3950, 3050), QNAV_MAP_OCCUPIED);
    ranges[0] = 1000; /* 1.45 m away now: beyond the sonar's 1.12 m */
    qnav_map_observe(&m, ranges, &back);
    assert_int_equal(qnav_map_evidence(&m, 3950, 3050), QNAV_MAP_OCCUPIED);
    assert_true(qnav_map_evidence(&m, 2550, 2150) < 0);  /* 0.85 m: seen clear */
    assert_int_equal(qnav_map_evidence(&m, 2550, 1550), 0); /* 1.45 m: unknown */
}

/* unknown_cost: a cell no reading has marked costs that much more to enter, so the plan
 * prefers a way seen open; a cell seen free costs a step as before. 2 m straight along x
 * (20 cells of 100 mm) in an empty world, before and after the robot has looked along it. */
static void test_unknown_cells_cost_more_until_seen(void **state)
{
    qnav_map_t m;
    qnav_map_config_t mc;
    qnav_mm_t ranges[N];
    const qnav_map_pose_t p = {3050, 3050, 0};
    int k;
    (void)state;
    qnav_map_config_default(&mc);
    mc.unknown_cost = 30;
    map_from(&m, &mc);
    qnav_map_plan(&m, 5050, 3050);
    assert_int_equal(qnav_map_cost(&m, 3050, 3050), 20 * (10 + 30));
    for (k = 0; k < N; ++k) {
        ranges[k] = 2500; /* nothing within range: every cell within the reach seen free */
    }
    qnav_map_observe(&m, ranges, &p);
    qnav_map_plan(&m, 5050, 3050);
    assert_int_equal(qnav_map_cost(&m, 3050, 3050), 20 * 10 + 30); /* the robot's own cell
                                                                     no reading marks */
    /* without it, unknown cells cost a step like any other */
    mc.unknown_cost = 0;
    map_from(&m, &mc);
    qnav_map_plan(&m, 5050, 3050);
    assert_int_equal(qnav_map_cost(&m, 3050, 3050), 20 * 10);
    /* a compact map has no costs to add: refused */
    mc.unknown_cost = 30;
    mc.compact = 1;
    mc.near_cost = 0;
    mc.cell_mm = 200;
    {
        qnav_ctrl_config_t cc;
        sensor_config(&cc);
        assert_int_equal(qnav_map_init(&m, &mc, &cc, 0, 0, WORLD_MM, WORLD_MM, mem, sizeof mem),
                         QNAV_E_MAP);
    }
}

/* A room: the world's four sides and the wall with its gap. */
static const box_t room[] = {{0, 0, WORLD_MM, 100},         {0, WORLD_MM - 100, WORLD_MM, WORLD_MM},
                             {0, 0, 100, WORLD_MM},         {WORLD_MM - 100, 0, WORLD_MM, WORLD_MM},
                             {0, 2950, 4500, 3050},         {5300, 2950, WORLD_MM, 3050}};

/* World point (x, y) in a pose frame turned turn_cdeg against the world about its centre
 * (a heading sensor's frame lies at no particular angle to a room). */
static void turned(int32_t turn_cdeg, int32_t *x, int32_t *y)
{
    int16_t c, s;
    const int32_t dx = *x - WORLD_MM / 2, dy = *y - WORLD_MM / 2;
    qnav_cos_sin_q14(turn_cdeg, &c, &s);
    *x = WORLD_MM / 2 + (c * dx - s * dy) / 16384;
    *y = WORLD_MM / 2 + (s * dx + c * dy) / 16384;
}

/* The robot looks round at 24 points of the room (9 headings each), its map given its pose
 * in a frame turned turn_cdeg against the room; the map aligns after `samples` readings. */
static void look_round_the_room(qnav_map_t *m, int32_t turn_cdeg, uint8_t samples)
{
    qnav_map_config_t mc;
    qnav_mm_t ranges[N];
    int a, b, h;
    qnav_map_config_default(&mc);
    mc.align_samples = samples;
    map_from(m, &mc);
    for (b = 0; b < 4; ++b) {
        for (a = 0; a < 6; ++a) {
            for (h = 0; h < 9; ++h) {
                qnav_map_pose_t world = {700 + a * 900, b < 2 ? 700 + b * 900 : 3700 + (b - 2) * 900, 0};
                qnav_map_pose_t seen;
                world.heading_cdeg = h * 3917 + a * 1231 + b * 577;
                scan(room, sizeof room / sizeof room[0], &world, ranges);
                seen = world;
                turned(turn_cdeg, &seen.x_mm, &seen.y_mm);
                seen.heading_cdeg += turn_cdeg;
                qnav_map_observe(m, ranges, &seen);
            }
        }
    }
}

/* align_samples: the grid turns to the room's walls, at right angles in a frame turned 30
 * deg (or 0, or -40) against them, to within 2 deg; then a wall's cell is occupied where
 * the wall lies in the pose's frame, and the gap's is not. Without it, or in a frame along
 * the walls, the grid stays in the pose's frame. */
static void test_the_grid_turns_to_the_walls(void **state)
{
    static const int32_t turns[] = {0, 1500, -4000, 3000};
    qnav_map_t m;
    size_t t;
    (void)state;
    for (t = 0; t < sizeof turns / sizeof turns[0]; ++t) {
        int32_t x = 2000, y = 3000, gx = 4900, gy = 3000, off;
        look_round_the_room(&m, turns[t], 40);
        off = (m.grid_cdeg - turns[t]) % 9000; /* walls at right angles: modulo 90 deg */
        off += off < -4500 ? 9000 : (off >= 4500 ? -9000 : 0);
        print_message("room turned %d cdeg: the grid turned %d cdeg (%u readings, their mean %d)\n",
                      (int)turns[t], (int)m.grid_cdeg, (unsigned)m.align_n,
                      (int)qnav_atan2_cdeg(m.align_s / 1024, m.align_c / 1024, NULL) / 4);
        assert_true(off >= -200 && off <= 200);
        assert_true(turns[t] != 0 || m.grid_cdeg == 0);
        turned(turns[t], &x, &y);
        turned(turns[t], &gx, &gy);
        assert_true(qnav_map_evidence(&m, x, y) >= QNAV_MAP_OCCUPIED);
        assert_true(qnav_map_evidence(&m, gx, gy) < QNAV_MAP_OCCUPIED);
        {
            /* the grid's point a cell to the right of the map's centre, in the pose's frame:
             * as far from the centre, the grid's turn round from the pose's x axis */
            int32_t px = m.pivot_x_mm + 100, py = m.pivot_y_mm;
            int16_t c, s;
            qnav_map_grid_to_pose(&m, &px, &py);
            qnav_cos_sin_q14(m.grid_cdeg, &c, &s);
            assert_true(px - (m.pivot_x_mm + 100 * c / 16384) >= -1 && px - (m.pivot_x_mm + 100 * c / 16384) <= 1);
            assert_true(py - (m.pivot_y_mm + 100 * s / 16384) >= -1 && py - (m.pivot_y_mm + 100 * s / 16384) <= 1);
        }
    }
    look_round_the_room(&m, 3000, 0);
    assert_int_equal(m.grid_cdeg, 0);
}

/* The robot drives along y = 1500 facing the wall and observes it, then plans. */
static void observe_the_wall(qnav_map_t *m)
{
    qnav_mm_t ranges[N];
    int32_t x;
    for (x = 500; x <= 5500; x += 250) {
        const qnav_map_pose_t p = {x, 1500, 9000};
        scan(wall_with_gap, 2, &p, ranges);
        qnav_map_observe(m, ranges, &p);
    }
}

/* The compact layout at cell_mm (wider than the sensor's body, 170 mm), planning every
 * plan_ticks, growing its plan by grow_steps a tick (0: as far as it needs). */
/* mc made compact: cells of cell_mm, no near cost or refusal (a compact map has no bits
 * for them). */
static void make_compact(qnav_map_config_t *mc, uint16_t cell_mm, uint8_t plan_ticks,
                         uint8_t grow_steps)
{
    mc->compact = 1;
    mc->cell_mm = cell_mm;
    mc->plan_ticks = plan_ticks;
    mc->grow_steps = grow_steps;
    mc->near_cost = 0;
    mc->refuse_ticks = 0;
}

static void compact_map(qnav_map_t *m, uint16_t cell_mm, uint8_t plan_ticks, uint8_t grow_steps)
{
    qnav_map_config_t mc;
    qnav_map_config_default(&mc);
    make_compact(&mc, cell_mm, plan_ticks, grow_steps);
    map_from(m, &mc);
}

/* m, empty, leads round the wall to its gap once it has seen the wall. */
static void plan_round_the_wall(qnav_map_t *m)
{
    qnav_map_t *const mp = m;
    qnav_ctrl_input_t in;
    const qnav_map_pose_t p = {1500, 1500, 9000}; /* facing the wall (+y) */
#define m (*mp)
    /* nothing seen yet: the plan is the straight line */
    memset(&in, 0, sizeof in);
    assert_int_equal(qnav_map_guide(&m, &p, 1500, 5000, &in), QNAV_MAP_GUIDED);
    assert_true(in.goal_bearing_cdeg > -1000 && in.goal_bearing_cdeg < 1000);
    assert_true(in.goal_range_mm > 3300 && in.goal_range_mm < 3700);
    assert_int_equal(qnav_map_cost(&m, 1550, 5050), 0);
    observe_the_wall(&m);
    assert_true(qnav_map_evidence(&m, 2050, 2950) >= QNAV_MAP_OCCUPIED ||
                qnav_map_evidence(&m, 2050, 3050) >= QNAV_MAP_OCCUPIED);
    in.escape.side = 1;
    in.escape.ticks = 42;
    /* the way is through the gap, to the right: the plan grew by metres, so the escape
     * memory of the closed way is cleared */
    assert_int_equal(qnav_map_guide(&m, &p, 1500, 5000, &in),
                     QNAV_MAP_GUIDED | QNAV_MAP_ESCAPE_CLEARED);
    assert_true(in.goal_bearing_cdeg < -2000);
    assert_true(in.goal_range_mm > 3500 + 4000);
    assert_int_equal(in.escape.side, 0);
    assert_int_equal(in.escape.ticks, 0);
    /* no wall cell is on the way: the cost under the wall's middle is unreached or more
     * than the way round */
    assert_true(qnav_map_cost(&m, 1550, 3000) == QNAV_MAP_UNREACHED);
    /* the heading taken modulo a turn: a pose that has turned three times decides alike */
    {
        const qnav_map_pose_t turned = {1500, 1500, 9000 + 3 * 36000};
        qnav_ctrl_input_t again = in;
        assert_int_equal(qnav_map_guide(&m, &turned, 1500, 5000, &again) & QNAV_MAP_GUIDED,
                         QNAV_MAP_GUIDED);
        assert_int_equal(again.goal_bearing_cdeg, in.goal_bearing_cdeg);
    }
    /* next tick, the same plan: nothing cleared */
    in.escape.side = 1;
    assert_int_equal(qnav_map_guide(&m, &p, 1500, 5000, &in), QNAV_MAP_GUIDED);
    assert_int_equal(in.escape.side, 1);
#undef m
}

static void test_the_plan_leads_round_the_wall_to_its_gap(void **state)
{
    qnav_map_t m;
    (void)state;
    map_of(&m, 1);
    plan_round_the_wall(&m);
}

/* The compact layout (4 bits a cell) plans the same way round at 400 mm cells. */
static void test_the_compact_plan_leads_round_the_wall_to_its_gap(void **state)
{
    qnav_map_t m;
    (void)state;
    compact_map(&m, 400, 1, 0);
    assert_int_equal(qnav_map_size(&m.cfg, WORLD_MM, WORLD_MM), 4u * 15u * 2u);
    plan_round_the_wall(&m);
}

/* A plan that grows by at most grow_steps a tick (the board's bound on a tick's cost)
 * holds the last sub-goal while it has not reached the robot, then gives what a plan
 * grown at once gives. */
static void test_a_compact_plan_grown_a_few_steps_a_tick_holds_its_last_sub_goal(void **state)
{
    static qnav_map_t bounded, whole;
    static uint16_t whole_mem[64];
    qnav_ctrl_config_t cc;
    qnav_ctrl_input_t a, b;
    const qnav_map_pose_t p = {1500, 1500, 9000};
    int t, held = 0, got;
    (void)state;
    compact_map(&bounded, 400, 1, 3);
    /* the same map in memory of its own */
    sensor_config(&cc);
    whole.cfg = bounded.cfg;
    whole.cfg.grow_steps = 0;
    assert_int_equal(qnav_map_init(&whole, &whole.cfg, &cc, 0, 0, WORLD_MM, WORLD_MM, whole_mem,
                                   sizeof whole_mem),
                     QNAV_OK);
    memset(&a, 0, sizeof a);
    /* 9 steps away: no sub-goal yet for two ticks, then the straight way */
    assert_int_equal(qnav_map_guide(&bounded, &p, 1500, 5000, &a), 0);
    assert_int_equal(qnav_map_guide(&bounded, &p, 1500, 5000, &a), 0);
    assert_int_equal(qnav_map_guide(&bounded, &p, 1500, 5000, &a), QNAV_MAP_GUIDED);
    observe_the_wall(&bounded);
    observe_the_wall(&whole);
    memset(&b, 0, sizeof b);
    assert_int_equal(qnav_map_guide(&whole, &p, 1500, 5000, &b) & QNAV_MAP_GUIDED, QNAV_MAP_GUIDED);
    /* the new plan, round the wall, is some 20 steps long: the old sub-goal stands for
     * ticks, then the two agree */
    a.goal_bearing_cdeg = 0;
    a.goal_range_mm = 0;
    got = qnav_map_guide(&bounded, &p, 1500, 5000, &a);
    assert_int_equal(got, QNAV_MAP_GUIDED);
    assert_true(a.goal_bearing_cdeg > -1000 && a.goal_bearing_cdeg < 1000);
    assert_true(a.goal_range_mm > 3300 && a.goal_range_mm < 3700);
    for (t = 0; t < 20 && a.goal_range_mm < 7000; ++t) {
        got = qnav_map_guide(&bounded, &p, 1500, 5000, &a);
        ++held;
    }
    print_message("the new plan reached the robot after %d ticks\n", held);
    assert_true(held >= 4);
    assert_int_equal(a.goal_bearing_cdeg, b.goal_bearing_cdeg);
    assert_int_equal(a.goal_range_mm, b.goal_range_mm);
}

/* Boxes to drive among: the wall with its gap, a pillar, a U open to the south. */
static const box_t among[] = {{0, 2950, 4500, 3050},    {5300, 2950, WORLD_MM, 3050},
                              {2600, 1200, 3000, 1600}, {600, 4000, 700, 5400},
                              {600, 5300, 2200, 5400},  {2100, 4000, 2200, 5400}};

/* A robot driven among the boxes, both layouts marking its scans: the compact layout
 * holds what the full one says of every cell (occupied, seen free, neither), and its
 * plan is a breadth-first search over its occupied cells (8 neighbours, no corner cut):
 * a cell is reached exactly when such a search reaches it, and its way to the destination
 * is that search's step count long (each step 10 or 14). */
static void test_the_compact_layout_marks_as_the_full_one_and_plans_breadth_first(void **state)
{
    static qnav_map_t full, small;
    static int32_t steps[(WORLD_MM / 300) * (WORLD_MM / 300)];
    static int32_t queue[(WORLD_MM / 300) * (WORLD_MM / 300)];
    static uint16_t mem_small[2000];
    qnav_map_config_t mc;
    qnav_ctrl_config_t cc;
    qnav_mm_t ranges[N];
    const int32_t cell = 300, n = WORLD_MM / cell;
    int32_t t, i, j, head = 0, tail = 0, reached = 0;
    (void)state;
    qnav_map_config_default(&mc);
    mc.cell_mm = (uint16_t)cell;
    mc.near_cost = 0;
    mc.refuse_ticks = 0;
    map_from(&full, &mc);
    mc.compact = 1;
    sensor_config(&cc);
    assert_true(qnav_map_size(&mc, WORLD_MM, WORLD_MM) <= sizeof mem_small);
    assert_int_equal(qnav_map_init(&small, &mc, &cc, 0, 0, WORLD_MM, WORLD_MM, mem_small,
                                   sizeof mem_small),
                     QNAV_OK);
    /* a loop round the pillar and along the wall, turning as it goes */
    for (t = 0; t < 120; ++t) {
        const qnav_map_pose_t p = {900 + (t % 40) * 110, 700 + (t / 40) * 600, t * 1700};
        scan(among, sizeof among / sizeof among[0], &p, ranges);
        qnav_map_observe(&full, ranges, &p);
        qnav_map_observe(&small, ranges, &p);
    }
    for (j = 0; j < n; ++j) {
        for (i = 0; i < n; ++i) {
            const int32_t x = i * cell + cell / 2, y = j * cell + cell / 2;
            const int8_t a = qnav_map_evidence(&full, x, y), b = qnav_map_evidence(&small, x, y);
            assert_int_equal(a >= QNAV_MAP_OCCUPIED, b >= QNAV_MAP_OCCUPIED);
            assert_int_equal(a < 0, b < 0);
            steps[j * n + i] = -1;
        }
    }
    /* the search, from the destination's cell (3, 17) */
    qnav_map_plan(&small, 3 * cell + 100, 17 * cell + 100);
    steps[17 * n + 3] = 0;
    queue[tail++] = 17 * n + 3;
    while (head < tail) {
        const int32_t c = queue[head++], ci = c % n, cj = c / n;
        int32_t a, b;
        for (b = -1; b <= 1; ++b) {
            for (a = -1; a <= 1; ++a) {
                const int32_t ti = ci + a, tj = cj + b;
                if (ti < 0 || tj < 0 || ti >= n || tj >= n || steps[tj * n + ti] >= 0 ||
                    qnav_map_evidence(&small, ti * cell, tj * cell) >= QNAV_MAP_OCCUPIED) {
                    continue;
                }
                if (a != 0 && b != 0 &&
                    (qnav_map_evidence(&small, ti * cell, cj * cell) >= QNAV_MAP_OCCUPIED ||
                     qnav_map_evidence(&small, ci * cell, tj * cell) >= QNAV_MAP_OCCUPIED)) {
                    continue;
                }
                steps[tj * n + ti] = steps[c] + 1;
                queue[tail++] = tj * n + ti;
            }
        }
    }
    for (j = 0; j < n; ++j) {
        for (i = 0; i < n; ++i) {
            const int32_t s = steps[j * n + i];
            const uint16_t cost = qnav_map_cost(&small, i * cell, j * cell);
            if (s < 0) {
                assert_int_equal(cost, QNAV_MAP_UNREACHED);
                continue;
            }
            reached++;
            assert_true(cost >= 10 * s && cost <= 14 * s);
        }
    }
    print_message("%d of %d cells reached, %d not (occupied, or walled in)\n", reached, n * n,
                  n * n - reached);
    assert_true(reached > n * n / 2 && reached < n * n);
}

/* The compact map keeps the cost it found near the robot's cell (qnav_map_t.way_from) until
 * a label, a cell's occupancy or the plan's growth changes. Two maps see the same drive
 * among the boxes (walls appearing, plans growing 2 steps a tick, the robot crossing
 * cells); one forgets the kept cost before every guide. Every tick's guidance is the same,
 * and the kept cost was used on some ticks. Fails when a change that the walk depends on
 * leaves the kept cost standing (a ways_changed() call left out). */
static void test_a_compact_map_keeps_the_cost_near_the_robot_only_while_it_holds(void **state)
{
    static qnav_map_t kept, fresh;
    static uint16_t mem_kept[2000], mem_fresh[2000];
    qnav_map_config_t mc;
    qnav_ctrl_config_t cc;
    qnav_mm_t ranges[N];
    int32_t t, used = 0;
    (void)state;
    qnav_map_config_default(&mc);
    make_compact(&mc, 300, 3, 2);
    sensor_config(&cc);
    assert_int_equal(qnav_map_init(&kept, &mc, &cc, 0, 0, WORLD_MM, WORLD_MM, mem_kept,
                                   sizeof mem_kept),
                     QNAV_OK);
    assert_int_equal(qnav_map_init(&fresh, &mc, &cc, 0, 0, WORLD_MM, WORLD_MM, mem_fresh,
                                   sizeof mem_fresh),
                     QNAV_OK);
    for (t = 0; t < 240; ++t) {
        /* slowly round the pillar and along the wall: several ticks in each cell */
        const qnav_map_pose_t p = {900 + (t % 80) * 50, 700 + (t / 80) * 500, t * 900};
        qnav_ctrl_input_t a, b;
        int ga, gb;
        memset(&a, 0, sizeof a);
        memset(&b, 0, sizeof b);
        scan(among, sizeof among / sizeof among[0], &p, ranges);
        qnav_map_observe(&kept, ranges, &p);
        qnav_map_observe(&fresh, ranges, &p);
        used += kept.way_from != UINT16_MAX;
        fresh.way_from = UINT16_MAX;
        ga = qnav_map_guide(&kept, &p, 3 * 300 + 100, 17 * 300 + 100, &a);
        gb = qnav_map_guide(&fresh, &p, 3 * 300 + 100, 17 * 300 + 100, &b);
        assert_int_equal(ga, gb);
        assert_int_equal(a.goal_bearing_cdeg, b.goal_bearing_cdeg);
        assert_int_equal(a.goal_range_mm, b.goal_range_mm);
    }
    print_message("a kept cost stood at %d of 240 guides\n", used);
    assert_true(used > 20);
}

/* The same, change by change: each change a way depends on (a cell becoming occupied by
 * a second arc or a refusal, an occupied cell seen free, a forget, the map moving, a new
 * plan, a plan's growth, a reset) drops the kept cost, a new map keeps none, and a first arc (not yet occupied) keeps it;
 * the cost then found is the fresh walk's, and a new plan's, not the old one's. */
static void test_every_change_a_way_depends_on_drops_the_kept_cost(void **state)
{
    qnav_map_t m;
    int32_t bi, bj;
    uint32_t before, after;
    (void)state;
    memset(&m, 0, sizeof m); /* a caller's zeroed map: cell 0 must not look kept */
    compact_map(&m, 300, 1, 0);
    assert_int_equal(m.way_from, UINT16_MAX);
    qnav_map_plan(&m, 15 * 300 + 150, 15 * 300 + 150); /* the diagonal from (2, 2) on */
#define KEPT_THEN(change)                                                                    \
    do {                                                                                     \
        (void)qnav_cmap_cost_near(&m, 2, 2, &bi, &bj);                                       \
        assert_int_equal(m.way_from, qnav_map_at(&m, 2, 2));                                 \
        change;                                                                              \
        assert_int_equal(m.way_from, UINT16_MAX);                                            \
    } while (0)
    before = qnav_cmap_cost_near(&m, 2, 2, &bi, &bj);
    assert_int_equal(before, 13u * 14u); /* 13 diagonal steps */
    qnav_cmap_arc(&m, 3, 2); /* one arc: not occupied, the way and the kept cost stand */
    assert_int_equal(m.way_from, qnav_map_at(&m, 2, 2));
    KEPT_THEN(qnav_cmap_arc(&m, 3, 2)); /* occupied beside the first diagonal step */
    after = qnav_cmap_cost_near(&m, 2, 2, &bi, &bj);
    m.way_from = UINT16_MAX;
    assert_int_equal(qnav_cmap_cost_near(&m, 2, 2, &bi, &bj), after);
    KEPT_THEN(qnav_cmap_clear(&m, 3, 2));
    KEPT_THEN(qnav_cmap_occupy(&m, 2, 3));
    KEPT_THEN(qnav_cmap_forget_occupied(&m));
    KEPT_THEN(qnav_cmap_shift(&m, 0, 0));
    KEPT_THEN(qnav_cmap_plan_start(&m, qnav_map_at(&m, 15, 15)));
    /* a new plan has settled only its destination: no cost near (2, 2) yet, not the old */
    assert_int_equal(qnav_cmap_cost_near(&m, 2, 2, &bi, &bj), QNAV_MAP_UNREACHED);
    qnav_cmap_settle(&m, -1, -1);
    assert_int_equal(m.way_from, UINT16_MAX);
    assert_int_equal(qnav_cmap_cost_near(&m, 2, 2, &bi, &bj), before);
    KEPT_THEN(qnav_map_reset(&m));
#undef KEPT_THEN
}

/* A compact map reads a scan of twice QNAV_MAP_WEDGES_MAX sectors or more as that many
 * wedges, each the least reading of the sectors whose centres lie within it (a sector on
 * the boundary in both): fed 64 sectors along a drive among the boxes, it holds what the
 * map of a 32-sector sonar fed those wedges holds, cell for cell. 63 sectors, and a
 * full-layout map, are read sector by sector. Fails when a boundary sector is left to one
 * wedge, or the wedges are centred off the map's sectors. */
static void test_a_compact_map_reads_a_finer_scan_as_its_wedges(void **state)
{
    static qnav_map_t fine, wedges, full;
    static uint16_t mem_fine[2000], mem_wedges[2000];
    qnav_map_config_t mc;
    qnav_ctrl_config_t cc;
    qnav_mm_t r64[64], r32[32];
    int32_t t, w, i, j, marked = 0;
    (void)state;
    qnav_map_config_default(&mc);
    make_compact(&mc, 300, 1, 0);
    sensor_config(&cc);
    cc.n_sectors = 64;
    assert_int_equal(qnav_map_init(&fine, &mc, &cc, 0, 0, WORLD_MM, WORLD_MM, mem_fine,
                                   sizeof mem_fine),
                     QNAV_OK);
    assert_int_equal(fine.n_sectors, QNAV_MAP_WEDGES_MAX);
    cc.n_sectors = 32;
    assert_int_equal(qnav_map_init(&wedges, &mc, &cc, 0, 0, WORLD_MM, WORLD_MM, mem_wedges,
                                   sizeof mem_wedges),
                     QNAV_OK);
    for (t = 0; t < 120; ++t) {
        const qnav_map_pose_t p = {900 + (t % 40) * 110, 700 + (t / 40) * 600, t * 1700};
        scan_of(among, sizeof among / sizeof among[0], &p, r64, 64);
        for (w = 0; w < 32; ++w) { /* sectors 2w - 1, 2w and 2w + 1: centres within 5.625 deg */
            const qnav_mm_t a = r64[(2 * w + 63) % 64], b = r64[2 * w], c = r64[2 * w + 1];
            r32[w] = a < b ? (a < c ? a : c) : (b < c ? b : c);
        }
        qnav_map_observe(&fine, r64, &p);
        qnav_map_observe(&wedges, r32, &p);
    }
    for (j = 0; j < WORLD_MM / 300; ++j) {
        for (i = 0; i < WORLD_MM / 300; ++i) {
            const int8_t a = qnav_map_evidence(&fine, i * 300 + 150, j * 300 + 150);
            assert_int_equal(a, qnav_map_evidence(&wedges, i * 300 + 150, j * 300 + 150));
            marked += a >= QNAV_MAP_OCCUPIED;
        }
    }
    print_message("%d cells occupied, the same in both\n", marked);
    assert_true(marked > 10);
    cc.n_sectors = 63;
    assert_int_equal(qnav_map_init(&wedges, &mc, &cc, 0, 0, WORLD_MM, WORLD_MM, mem_wedges,
                                   sizeof mem_wedges),
                     QNAV_OK);
    assert_int_equal(wedges.n_sectors, 63);
    mc.compact = 0;
    cc.n_sectors = 64;
    assert_int_equal(qnav_map_init(&full, &mc, &cc, 0, 0, WORLD_MM, WORLD_MM, mem, sizeof mem),
                     QNAV_OK);
    assert_int_equal(full.n_sectors, 64);
}

/* Left of the gap, the destination straight beyond the wall: once the wall is seen the way
 * bends through the gap, a few decimetres longer (less than a jump). The escape memory's
 * distances grow by what the plan grew, so its stall timer measures progress along the new
 * plan; 0 stays "none"; with escape_grow 0 they stay. */
static uint16_t grow_after_the_wall(uint8_t escape_grow, qnav_ctrl_input_t *in, int *got)
{
    qnav_map_t m;
    qnav_map_config_t mc;
    const qnav_map_pose_t p = {4300, 1500, 9000};
    uint16_t before;
    qnav_map_config_default(&mc);
    mc.plan_ticks = 1;
    mc.escape_grow = escape_grow;
    map_from(&m, &mc);
    memset(in, 0, sizeof *in);
    assert_int_equal(qnav_map_guide(&m, &p, 4300, 5000, in), QNAV_MAP_GUIDED);
    before = in->goal_range_mm;
    observe_the_wall(&m);
    in->escape.best_mm = 3000;
    in->escape.stall_mm = 3200;
    in->escape.ticks = 7;
    *got = qnav_map_guide(&m, &p, 4300, 5000, in);
    print_message("plan %u -> %u mm, flags %d\n", before, in->goal_range_mm, *got);
    assert_true(in->goal_range_mm > before + 100 && in->goal_range_mm < before + 1000);
    assert_int_equal(qnav_map_grown_mm(&m), escape_grow ? in->goal_range_mm - before : 0);
    return (uint16_t)(in->goal_range_mm - before);
}

static void test_a_longer_plan_grows_the_escape_memory(void **state)
{
    qnav_ctrl_input_t in;
    int got;
    uint16_t d;
    (void)state;
    d = grow_after_the_wall(1, &in, &got);
    assert_int_equal(got, QNAV_MAP_GUIDED | QNAV_MAP_ESCAPE_GROWN);
    assert_int_equal(in.escape.best_mm, 3000 + d);
    assert_int_equal(in.escape.stall_mm, 3200 + d);
    assert_int_equal(in.escape.hit_mm, 0);  /* none stays none */
    assert_int_equal(in.escape.ticks, 7);   /* the stall's time goes on */
    d = grow_after_the_wall(0, &in, &got);
    assert_int_equal(got, QNAV_MAP_GUIDED);
    assert_int_equal(in.escape.best_mm, 3000);
    assert_int_equal(in.escape.stall_mm, 3200);
}

/* The same with the compact layout growing its plan 2 steps a tick: the longer plan reaches
 * the robot ticks after it began, and the escape memory grows on the tick it first guides
 * from, by what the plan grew (before 0.15.1 the tick that began the plan was the only one
 * that counted, so a late plan looked like a step back and set off a follow). */
static void test_a_longer_plan_that_reaches_the_robot_late_grows_the_escape_memory(void **state)
{
    qnav_map_t m;
    qnav_ctrl_input_t in;
    const qnav_map_pose_t p = {4300, 1500, 9000};
    uint16_t before;
    int t, got = 0, late = 0;
    (void)state;
    compact_map(&m, 400, 1, 2);
    memset(&in, 0, sizeof in);
    for (t = 0; t < 10 && got == 0; ++t) {
        got = qnav_map_guide(&m, &p, 4300, 5000, &in);
    }
    assert_int_equal(got & QNAV_MAP_GUIDED, QNAV_MAP_GUIDED);
    before = in.goal_range_mm;
    observe_the_wall(&m);
    in.escape.best_mm = 3000;
    in.escape.ticks = 7;
    for (t = 0; t < 20 && in.goal_range_mm <= before; ++t) {
        got = qnav_map_guide(&m, &p, 4300, 5000, &in);
        late += in.goal_range_mm <= before;
    }
    print_message("plan %u -> %u mm after %d ticks, flags %d\n", before, in.goal_range_mm, late, got);
    assert_true(late >= 1); /* the plan did reach the robot late */
    assert_true(in.goal_range_mm > before + 100 && in.goal_range_mm < before + 1000);
    assert_int_equal(got, QNAV_MAP_GUIDED | QNAV_MAP_ESCAPE_GROWN);
    assert_int_equal(in.escape.best_mm, 3000 + in.goal_range_mm - before);
    assert_int_equal(in.escape.ticks, 7);
    /* the next tick, the same plan: nothing grows */
    before = in.goal_range_mm;
    got = qnav_map_guide(&m, &p, 4300, 5000, &in);
    assert_int_equal(got & QNAV_MAP_ESCAPE_GROWN, 0);
}

/* Below the wall, left of its gap, with the destination beyond the wall to the left: the
 * plan turns round the gap's edge within the look-ahead. With sight the sub-goal stays
 * where the robot sees it past the edge (further right); without, it lies behind it. */
static void test_the_sub_goal_is_not_behind_a_corner(void **state)
{
    qnav_map_t m;
    qnav_ctrl_input_t with, without;
    const qnav_map_pose_t p = {4200, 2650, 9000};
    (void)state;
    memset(&with, 0, sizeof with);
    memset(&without, 0, sizeof without);
    map_with(&m, 1, 2250, 0);
    observe_the_wall(&m);
    assert_int_equal(qnav_map_guide(&m, &p, 1500, 5000, &without) & QNAV_MAP_GUIDED,
                     QNAV_MAP_GUIDED);
    map_with(&m, 1, 2250, 1);
    observe_the_wall(&m);
    assert_int_equal(qnav_map_guide(&m, &p, 1500, 5000, &with) & QNAV_MAP_GUIDED,
                     QNAV_MAP_GUIDED);
    assert_true(with.goal_bearing_cdeg < without.goal_bearing_cdeg - 1000); /* -90 / -54 deg */
}

/* The sub-goal is the destination itself once the plan reaches it within the look-ahead
 * (QNAV_MAP_DIRECT: a caller with a beacon may keep the sensed bearing), not before. */
static void test_the_destination_in_reach_is_flagged_direct(void **state)
{
    qnav_map_t m;
    qnav_ctrl_input_t in;
    const qnav_map_pose_t far = {1500, 1500, 9000}, near = {1500, 4300, 9000};
    (void)state;
    map_of(&m, 1);
    memset(&in, 0, sizeof in);
    assert_int_equal(qnav_map_guide(&m, &far, 1500, 5000, &in), QNAV_MAP_GUIDED);
    assert_int_equal(qnav_map_guide(&m, &near, 1500, 5000, &in),
                     QNAV_MAP_GUIDED | QNAV_MAP_DIRECT);
    assert_true(in.goal_bearing_cdeg > -300 && in.goal_bearing_cdeg < 300);
    assert_true(in.goal_range_mm >= 600 && in.goal_range_mm <= 800);
}

/* A wall the robot saw closed, seen from below with the destination beyond it: the plan
 * finds no way and leaves the input alone, and the map forgets what the arcs marked (the
 * robot was placed where the destination can be reached), so the next plan leads through
 * the wall's cells again; cells seen free stay free. Both layouts. */
static void walled_in_forgets(qnav_map_t *m)
{
    static const box_t closed[] = {{0, 2950, WORLD_MM, 3050}};
    qnav_ctrl_input_t in;
    qnav_mm_t ranges[N];
    const qnav_map_pose_t p = {1500, 1500, 9000};
    int32_t x;
    int t, got = 0;
    for (x = 300; x <= 5700; x += 200) {
        const qnav_map_pose_t q = {x, 1500, 9000};
        scan(closed, 1, &q, ranges);
        qnav_map_observe(m, ranges, &q);
    }
    assert_true(qnav_map_evidence(m, 1500, 2960) >= QNAV_MAP_OCCUPIED);
    assert_true(qnav_map_evidence(m, 1500, 2200) < 0);
    memset(&in, 0, sizeof in);
    in.goal_bearing_cdeg = 1234;
    in.goal_range_mm = 3500;
    for (t = 0; t < 40 && got == 0 && qnav_map_evidence(m, 1500, 2960) != 0; ++t) {
        got = qnav_map_guide(m, &p, 1500, 5000, &in);
    }
    assert_int_equal(got, 0);
    assert_int_equal(in.goal_bearing_cdeg, 1234);
    assert_int_equal(in.goal_range_mm, 3500);
    for (x = 300; x <= 5700; x += 200) {
        assert_int_equal(qnav_map_evidence(m, x, 2960), 0);
    }
    assert_true(qnav_map_evidence(m, 1500, 2200) < 0);
    for (t = 0; t < 40 && got == 0; ++t) {
        got = qnav_map_guide(m, &p, 1500, 5000, &in);
    }
    assert_int_equal(got & QNAV_MAP_GUIDED, QNAV_MAP_GUIDED);
    assert_true(in.goal_bearing_cdeg > -1500 && in.goal_bearing_cdeg < 1500);
}

static void test_a_map_that_closed_every_way_forgets_what_it_marked(void **state)
{
    qnav_map_t m;
    (void)state;
    map_of(&m, 1);
    walled_in_forgets(&m);
    compact_map(&m, 400, 1, 16);
    walled_in_forgets(&m);
}

/* The map of walled_in_forgets with forget_reach_mm 1200, after the forget: the wall seen
 * again from 1.45 m (farther than 1 200 mm) is not marked, from 0.75 m it is; a new
 * destination marks from afar again. */
static void near_marks_after_a_forget(qnav_map_t *m)
{
    static const box_t closed[] = {{0, 2950, WORLD_MM, 3050}};
    qnav_ctrl_input_t in;
    qnav_mm_t ranges[N];
    int32_t x, y;
    walled_in_forgets(m);
    for (y = 1500; y <= 2200; y += 700) {
        for (x = 300; x <= 5700; x += 200) {
            const qnav_map_pose_t q = {x, y, 9000};
            scan(closed, 1, &q, ranges);
            qnav_map_observe(m, ranges, &q);
        }
        for (x = 500; x <= 5500; x += 500) {
            if (y == 1500) {
                assert_int_equal(qnav_map_evidence(m, x, 2960), 0);
            } else {
                assert_true(qnav_map_evidence(m, x, 2960) >= QNAV_MAP_OCCUPIED);
            }
        }
    }
    /* forgotten again (the wall is marked from near); then a new destination: a reading
     * from afar marks again */
    walled_in_forgets(m);
    memset(&in, 0, sizeof in);
    {
        const qnav_map_pose_t p = {1500, 1500, 9000};
        scan(closed, 1, &p, ranges);
        qnav_map_observe(m, ranges, &p);
        assert_int_equal(qnav_map_evidence(m, 1500, 2960), 0);
        (void)qnav_map_guide(m, &p, 1600, 5000, &in);
        qnav_map_observe(m, ranges, &p);
        qnav_map_observe(m, ranges, &p);
        assert_true(qnav_map_evidence(m, 1500, 2960) >= QNAV_MAP_OCCUPIED);
    }
}

static void test_after_a_forget_only_near_readings_mark(void **state)
{
    qnav_map_config_t mc;
    qnav_map_t m;
    (void)state;
    qnav_map_config_default(&mc);
    mc.plan_ticks = 1;
    mc.forget_reach_mm = 1200;
    map_from(&m, &mc);
    near_marks_after_a_forget(&m);
    make_compact(&mc, 400, 1, 16);
    map_from(&m, &mc);
    near_marks_after_a_forget(&m);
}

/* The wall with its gap at x 4500..5300, and a second gap at x 200..1800. */
static const box_t wall_with_two_gaps[] = {
    {0, 2950, 200, 3050}, {1800, 2950, 4500, 3050}, {5300, 2950, WORLD_MM, 3050}};

/* Below the near gap, the destination beyond it, the robot makes no progress (a controller
 * that will not pass where the plan leads): after refuse_ticks guided ticks the plan's
 * cells ahead are refused, so the plan seeks another way. Returns the guided tick whose
 * sub-goal no longer lies ahead through the near gap (-1: none in 100), with the last
 * tick's input in *in. With refuse_ticks 0, never. */
static int ticks_until_refused_in(uint16_t compact_cell_mm, uint8_t refuse_ticks, const box_t *wall,
                                  size_t n, qnav_map_t *m, qnav_ctrl_input_t *in, int *got)
{
    qnav_map_config_t mc;
    qnav_mm_t ranges[N];
    const qnav_map_pose_t p = {4900, 2300, 9000};
    int32_t x;
    int t;
    qnav_map_config_default(&mc);
    mc.plan_ticks = 1;
    if (compact_cell_mm != 0u) {
        make_compact(&mc, compact_cell_mm, 1, 0);
    }
    mc.refuse_ticks = refuse_ticks;
    mc.refuse_life_ticks = 20;
    map_from(m, &mc);
    for (x = 500; x <= 5500; x += 250) {
        const qnav_map_pose_t q = {x, 1500, 9000};
        scan(wall, n, &q, ranges);
        qnav_map_observe(m, ranges, &q);
    }
    assert_true(qnav_map_evidence(m, 4950, 3050) < QNAV_MAP_OCCUPIED); /* the gap is open */
    for (t = 0; t < 100; ++t) {
        memset(in, 0, sizeof *in);
        *got = qnav_map_guide(m, &p, 4900, 5000, in);
        if (*got == 0 || in->goal_bearing_cdeg < -1500 || in->goal_bearing_cdeg > 1500) {
            return t;
        }
    }
    return -1;
}

/* The same in the full layout (8 bytes a cell). */
static int ticks_until_refused(uint8_t refuse_ticks, const box_t *wall, size_t n,
                               qnav_map_t *m, qnav_ctrl_input_t *in, int *got)
{
    return ticks_until_refused_in(0u, refuse_ticks, wall, n, m, in, got);
}

/* The compact layout has no bits for a refusal: the refused cells are marked occupied and
 * stay so (no lapse) until a forget. */
static void test_a_compact_map_refuses_a_way_by_marking_it_occupied(void **state)
{
    qnav_map_t m;
    qnav_ctrl_input_t in;
    const qnav_map_pose_t p = {4900, 2300, 9000};
    int t, got;
    (void)state;
    assert_int_equal(ticks_until_refused_in(400, 30, wall_with_two_gaps, 3, &m, &in, &got), 31);
    assert_int_equal(got & QNAV_MAP_GUIDED, QNAV_MAP_GUIDED);
    print_message("refused: bearing %d cdeg, flags %d\n", in.goal_bearing_cdeg, got);
    assert_true(in.goal_bearing_cdeg > 1500); /* toward the far gap, to the robot's left */
    assert_true(qnav_map_evidence(&m, 4950, 3050) >= QNAV_MAP_OCCUPIED);
    assert_true(qnav_map_evidence(&m, 4950, 2550) < QNAV_MAP_OCCUPIED); /* not at the robot */
    for (t = 0; t < 40; ++t) { /* twice the full layout's life: still refused */
        memset(&in, 0, sizeof in);
        got = qnav_map_guide(&m, &p, 4900, 5000, &in);
        assert_int_equal(got & QNAV_MAP_GUIDED, QNAV_MAP_GUIDED);
        assert_true(in.goal_bearing_cdeg > 1500);
    }
    assert_true(qnav_map_evidence(&m, 4950, 3050) >= QNAV_MAP_OCCUPIED);
    /* never with refuse_ticks 0 (a forget clears refused cells with every other occupied
     * one: test_a_map_that_closed_every_way_forgets_what_it_marked) */
    assert_int_equal(ticks_until_refused_in(400, 0, wall_with_two_gaps, 3, &m, &in, &got), -1);
}

/* A lane up to the wall, shut at its far end: the way to (1500, 5000) from inside it is
 * back down the lane and round through the gap. */
static const box_t lane_to_the_wall[] = {{0, 2950, 4500, 3050},   {5300, 2950, WORLD_MM, 3050},
                                         {1000, 1800, 1100, 2950}, {1900, 1800, 2000, 2950}};

/* The guided bearing and flags at (1500, 2500) facing the wall (+y), toward (1500, 5000), one
 * tick after another: the map sees nothing, then the lane shut ahead. */
static void guide_into_the_lane(uint8_t turn_back_ticks, int32_t *bearing, int *got, int ticks)
{
    qnav_map_t m;
    qnav_map_config_t mc;
    qnav_ctrl_input_t in;
    qnav_mm_t ranges[N];
    const qnav_map_pose_t p = {1500, 2500, 9000};
    int32_t y;
    int t;
    qnav_map_config_default(&mc);
    mc.plan_ticks = 1;
    mc.turn_back_ticks = turn_back_ticks;
    map_from(&m, &mc);
    memset(&in, 0, sizeof in);
    assert_int_equal(qnav_map_guide(&m, &p, 1500, 5000, &in), QNAV_MAP_GUIDED);
    assert_true(in.goal_bearing_cdeg > -500 && in.goal_bearing_cdeg < 500); /* straight on */
    for (y = 1900; y <= 2700; y += 200) {
        const qnav_map_pose_t at = {1500, y, 9000};
        scan(lane_to_the_wall, 4, &at, ranges);
        qnav_map_observe(&m, ranges, &at);
    }
    for (t = 0; t < ticks; ++t) {
        in.escape.side = 1;
        got[t] = qnav_map_guide(&m, &p, 1500, 5000, &in);
        bearing[t] = in.goal_bearing_cdeg;
        print_message("tick %d: bearing %d, %u mm, flags %d\n", t, (int)bearing[t],
                      in.goal_range_mm, got[t]);
    }
}

/* turn_back_ticks: a new plan that turns the robot back (its lane shut ahead in the map) is
 * followed only after that many ticks, the last sub-goal standing until then and the escape
 * memory kept; once only; 0 turns back at once, as before. */
static void test_a_turn_back_waits_its_ticks_once(void **state)
{
    int32_t bearing[6];
    int got[6];
    int t;
    (void)state;
    guide_into_the_lane(0, bearing, got, 2);
    assert_true(bearing[0] > 9000 || bearing[0] < -9000); /* back down the lane at once */
    assert_int_equal(got[0], QNAV_MAP_GUIDED | QNAV_MAP_ESCAPE_CLEARED);
    guide_into_the_lane(3, bearing, got, 6);
    for (t = 0; t < 3; ++t) {
        assert_true(bearing[t] > -500 && bearing[t] < 500); /* the last sub-goal stands */
        assert_int_equal(got[t], QNAV_MAP_GUIDED);
    }
    assert_true(bearing[3] > 9000 || bearing[3] < -9000);
    assert_int_equal(got[3], QNAV_MAP_GUIDED | QNAV_MAP_ESCAPE_CLEARED);
    for (t = 4; t < 6; ++t) { /* no second wait while the way lies behind */
        assert_true(bearing[t] > 9000 || bearing[t] < -9000);
        assert_int_equal(got[t], QNAV_MAP_GUIDED);
    }
}

static void test_a_way_the_robot_cannot_take_is_refused_for_a_while(void **state)
{
    qnav_map_t m;
    qnav_ctrl_input_t in;
    const qnav_map_pose_t p = {4900, 2300, 9000};
    int t, got;
    (void)state;
    /* the first tick plans and starts the count; refused on the 31st; planned again on the
     * 32nd, toward the far gap (to the robot's left) */
    assert_int_equal(ticks_until_refused(30, wall_with_two_gaps, 3, &m, &in, &got), 31);
    assert_int_equal(got & QNAV_MAP_GUIDED, QNAV_MAP_GUIDED);
    assert_true(in.goal_bearing_cdeg > 3000);
    assert_true(qnav_map_evidence(&m, 4950, 3050) >= QNAV_MAP_OCCUPIED);
    assert_true(qnav_map_evidence(&m, 4950, 2550) < QNAV_MAP_OCCUPIED); /* not at the robot */
    for (t = 0; t < 18; ++t) {
        memset(&in, 0, sizeof in);
        got = qnav_map_guide(&m, &p, 4900, 5000, &in);
        assert_int_equal(got & QNAV_MAP_GUIDED, QNAV_MAP_GUIDED);
        assert_true(in.goal_bearing_cdeg > 3000);
    }
    /* the refusal lapses after refuse_life_ticks (20): through the near gap again */
    for (t = 0; t < 5; ++t) {
        memset(&in, 0, sizeof in);
        got = qnav_map_guide(&m, &p, 4900, 5000, &in);
        if ((got & QNAV_MAP_GUIDED) && in.goal_bearing_cdeg > -1500 &&
            in.goal_bearing_cdeg < 1500) {
            break;
        }
    }
    assert_true(t < 5);
    assert_true(qnav_map_evidence(&m, 4950, 3050) < QNAV_MAP_OCCUPIED);
    assert_int_equal(ticks_until_refused(0, wall_with_two_gaps, 3, &m, &in, &got), -1);
    /* the only way refused: no way, so the map forgets the refusal with every arc, and the
     * plan leads through the gap again */
    assert_int_equal(ticks_until_refused(30, wall_with_gap, 2, &m, &in, &got), 31);
    assert_int_equal(got, 0);
    assert_int_equal(qnav_map_evidence(&m, 4950, 3050), 0);
    memset(&in, 0, sizeof in);
    assert_int_equal(qnav_map_guide(&m, &p, 4900, 5000, &in) & QNAV_MAP_GUIDED, QNAV_MAP_GUIDED);
    assert_true(in.goal_bearing_cdeg > -1500 && in.goal_bearing_cdeg < 1500);
}

/* A copy of full-layout map src in buf: the same state, its own cells (its memory starts
 * at the queue's heads). */
static void copy_map(qnav_map_t *dst, const qnav_map_t *src, uint16_t *buf)
{
    const size_t bytes = qnav_map_size(&src->cfg, (uint32_t)src->nx * src->cfg.cell_mm,
                                       (uint32_t)src->ny * src->cfg.cell_mm);
    const uint8_t *base = (const uint8_t *)src->q_head;
    uint8_t *to = (uint8_t *)buf;
    *dst = *src;
    memcpy(to, base, bytes);
    dst->q_head = (uint16_t *)(void *)(to + ((const uint8_t *)src->q_head - base));
    dst->cost = (uint16_t *)(void *)(to + ((const uint8_t *)src->cost - base));
    dst->next = (uint16_t *)(void *)(to + ((const uint8_t *)src->next - base));
    dst->prev = (uint16_t *)(void *)(to + ((const uint8_t *)src->prev - base));
    dst->evidence = (int8_t *)(void *)(to + ((const uint8_t *)src->evidence - base));
    dst->blocked = to + (src->blocked - base);
}

static uint16_t mem_full[CELLS_MAX * 4];

/* A robot driven along a path that brushes past boxes (its own cell blocked, within the
 * body's reach of what it has seen) decides every tick as it would from a whole plan:
 * qnav_map_guide() settles the plan only as far as the robot's cell needs, and goes on
 * from there on later ticks. The reference is a copy of the map taken each tick before
 * the guide, its plan finished first (qnav_map_cost finishes it). */
static void drive_against_a_whole_plan(uint8_t plan_ticks)
{
    static const box_t boxes[] = {{1000, 1000, 1800, 1600}, {2500, 2200, 3200, 2600},
                                  {3800, 1000, 4400, 3200}, {1200, 3600, 2600, 4200},
                                  {4000, 4200, 5200, 4700}};
    static const int32_t path[][2] = {{500, 500},   {880, 1700},  {2400, 2080},
                                      {3690, 2400}, {3690, 4000}, {2700, 4320},
                                      {1100, 4300}, {3000, 5300}, {5400, 5400}};
    qnav_map_t m, full;
    qnav_ctrl_input_t in, in_full;
    qnav_map_config_t mc;
    size_t w, c, settled = 0;
    int ticks = 0, guided = 0;
    qnav_map_config_default(&mc);
    mc.plan_ticks = plan_ticks;
    map_from(&m, &mc);
    memset(&in, 0, sizeof in);
    in_full = in;
    for (w = 0; w + 1 < sizeof path / sizeof path[0]; ++w) {
        const int32_t dx = path[w + 1][0] - path[w][0], dy = path[w + 1][1] - path[w][1];
        uint32_t length;
        const int32_t heading = qnav_atan2_cdeg(dy, dx, &length);
        const int32_t steps = ((int32_t)length + 79) / 80; /* 80 mm a tick */
        int32_t s;
        for (s = 0; s < steps; ++s) {
            const qnav_map_pose_t p = {path[w][0] + dx * s / steps, path[w][1] + dy * s / steps,
                                       heading};
            qnav_mm_t ranges[N];
            int got, got_full;
            scan(boxes, sizeof boxes / sizeof boxes[0], &p, ranges);
            qnav_map_observe(&m, ranges, &p);
            copy_map(&full, &m, mem_full);
            (void)qnav_map_cost(&full, 0, 0);
            got = qnav_map_guide(&m, &p, 5600, 5600, &in);
            got_full = qnav_map_guide(&full, &p, 5600, 5600, &in_full);
            assert_int_equal(got, got_full);
            assert_int_equal(in.goal_bearing_cdeg, in_full.goal_bearing_cdeg);
            assert_int_equal(in.goal_range_mm, in_full.goal_range_mm);
            assert_memory_equal(&in.escape, &in_full.escape, sizeof in.escape);
            /* every cost the guide settled is the whole plan's (a white-box look: a
             * settled cell has a cost and is out of the queue) */
            copy_map(&full, &m, mem_full);
            (void)qnav_map_cost(&full, 0, 0);
            for (c = 0; c < (size_t)m.nx * m.ny; ++c) {
                if (m.cost[c] != QNAV_MAP_UNREACHED && m.prev[c] == UINT16_C(0xFFFF)) {
                    assert_int_equal(m.cost[c], full.cost[c]);
                    settled++;
                }
            }
            ticks++;
            guided += (got & QNAV_MAP_GUIDED) != 0;
        }
    }
    print_message("plan every %u ticks: %d ticks, %d guided, %.0f of %u cells settled a tick\n",
                  plan_ticks, ticks, guided, (double)settled / ticks, (unsigned)m.nx * m.ny);
    assert_true(guided > ticks / 2);
    assert_true(settled < (size_t)ticks * m.nx * m.ny); /* the guide did not plan it all */
}

static void test_the_plan_is_settled_as_far_as_the_robot_needs(void **state)
{
    (void)state;
    drive_against_a_whole_plan(1);
    drive_against_a_whole_plan(10);
}

/* A map of 1 000 mm square with configuration mc. */
static qnav_status_t square_metre(qnav_map_t *m, const qnav_map_config_t *mc,
                                  const qnav_ctrl_config_t *cc)
{
    return qnav_map_init(m, mc, cc, 0, 0, 1000, 1000, mem, sizeof mem);
}

/* The evidence of every 100 mm point of [x0, x1) x [y0, y1) into e (at most 64 x 64). */
static void evidence_grid(const qnav_map_t *m, int32_t x0, int32_t y0, int32_t x1, int32_t y1,
                          int8_t *e)
{
    int32_t x, y, k = 0;
    for (y = y0; y < y1; y += 100) {
        for (x = x0; x < x1; x += 100) {
            e[k++] = qnav_map_evidence(m, x, y);
        }
    }
}

/* The placement tests' map: compact, 0.4 m cells (32 x 32 of them in 512 bytes). */
static void placing_config(qnav_map_config_t *mc)
{
    qnav_map_config_default(mc);
    mc->cell_mm = 400;
    mc->compact = 1;
}

/* A goal too far for the square: the robot the readings' reach and a cell (6 cells of
 * 400 mm) inside it, the rest toward the goal; too few bytes, or a square too small to keep
 * the robot that far in: no map. */
static void test_a_map_reaches_toward_a_goal_too_far_for_it(void **state)
{
    qnav_map_config_t mc;
    int32_t x0, y0;
    uint32_t side;
    const size_t len = 512u;
    (void)state;
    placing_config(&mc);
    assert_int_equal(qnav_map_place(&mc, len, 0, 0, 12001, 0, &x0, &y0, &side), 1);
    assert_int_equal(side, 12800);
    assert_int_equal(x0, -2400);
    assert_int_equal(y0, -6400);
    assert_int_equal(qnav_map_place(&mc, len, 0, 0, 0, -12001, &x0, &y0, &side), 1);
    assert_int_equal(x0, -6400);
    assert_int_equal(y0, 2400 - 12800);
    assert_int_equal(qnav_map_place(&mc, 3, 0, 0, 100, 100, &x0, &y0, &side), 0);
    mc.reach_mm = 6001; /* 16 cells: 2 x 17 do not fit in 32 */
    assert_int_equal(qnav_map_place(&mc, len, 0, 0, 12001, 0, &x0, &y0, &side), 0);
    assert_int_equal(qnav_map_place(&mc, len, 0, 0, 1000, 0, &x0, &y0, &side), 1);
}

/* A goal nearly a square away along an axis: midway would leave the robot a cell inside
 * the map, where a way on past the edge is no way at all; the map keeps it 0.9 m inside in
 * whole cells (three of 0.4 m, two of 0.5 m), the goal in its edge cell or past it. */
static void test_a_map_keeps_the_robot_a_metre_inside(void **state)
{
    qnav_map_config_t mc;
    int32_t x0, y0;
    uint32_t side;
    const size_t len = 512u;
    (void)state;
    placing_config(&mc);
    /* 12 m apart in a 12.8 m square: midway is a corner at -400, the robot a cell in */
    assert_int_equal(qnav_map_place(&mc, len, 0, 0, 12000, 0, &x0, &y0, &side), 1);
    assert_int_equal(side, 12800);
    assert_int_equal(x0, -3 * 400);
    assert_int_equal(y0, -6400); /* the other axis midway, as before */
    assert_int_equal(qnav_map_place(&mc, len, 0, 0, -12000, 0, &x0, &y0, &side), 1);
    assert_int_equal(x0, 3 * 400 - 12800);
    assert_int_equal(qnav_map_place(&mc, len, 0, 0, 0, 12000, &x0, &y0, &side), 1);
    assert_int_equal(y0, -3 * 400);
    /* nearer goals: midway, the robot farther in than three cells */
    assert_int_equal(qnav_map_place(&mc, len, 0, 0, 8000, 0, &x0, &y0, &side), 1);
    assert_int_equal(x0, 4000 - 6400);
    /* 0.5 m cells (16 m): two of them, 15 m apart */
    mc.cell_mm = 500;
    assert_int_equal(qnav_map_place(&mc, len, 0, 0, 15000, 0, &x0, &y0, &side), 1);
    assert_int_equal(side, 16000);
    assert_int_equal(x0, -2 * 500);
}

/* Where a board places its map, and the map following the robot: what it saw stays where
 * it was in the world, and what moved in is unknown, in either layout. */
static void placed_map_follows(uint8_t compact)
{
    static int8_t before[64 * 64], after[64 * 64];
    qnav_map_config_t mc;
    qnav_ctrl_config_t cc;
    qnav_map_t m;
    qnav_ctrl_input_t in;
    int32_t x0, y0;
    uint32_t side;
    const size_t len = compact ? 512u : 32u * 32u * 8u + 540u;
    qnav_map_pose_t p = {1500, 1500, 9000};
    qnav_map_config_default(&mc);
    mc.cell_mm = 400;
    mc.compact = compact;
    mc.near_cost = 0;
    mc.refuse_ticks = 0;
    sensor_config(&cc);
    /* the largest square the bytes hold (32 cells), midway between robot and goal */
    assert_int_equal(qnav_map_place(&mc, len, 1500, 1500, 1500, 5000, &x0, &y0, &side), 1);
    assert_int_equal(side, 12800);
    assert_int_equal(x0, 750 + 750 - 6400);
    assert_int_equal(y0, 750 + 2500 - 6400);
    assert_int_equal(qnav_map_init(&m, &mc, &cc, x0, y0, side, side, mem, len), QNAV_OK);
    observe_the_wall(&m);
    /* the readings (2 m) stay 5 cells inside: the map stays put */
    assert_int_equal(qnav_map_follow(&m, &p, 1500, 5000), 0);
    evidence_grid(&m, -2000, 100, 4400, 6500, before);
    /* near the east edge (x 7 900): the map moves east by whole cells, 2.4 m */
    p.x_mm = 6000;
    assert_int_equal(qnav_map_follow(&m, &p, 1500, 5000), 1);
    assert_int_equal(m.x0_mm, -4900 + 2400);
    assert_int_equal(m.y0_mm, -3150);
    assert_int_equal(qnav_map_follow(&m, &p, 1500, 5000), 0);
    evidence_grid(&m, -2000, 100, 4400, 6500, after);
    assert_memory_equal(before, after, 64 * 64);
    assert_true(qnav_map_evidence(&m, 2050, 2950) >= QNAV_MAP_OCCUPIED ||
                qnav_map_evidence(&m, 2050, 3050) >= QNAV_MAP_OCCUPIED);
    assert_int_equal(qnav_map_evidence(&m, 10000, 3000), 0); /* moved in: unknown */
    assert_int_equal(qnav_map_evidence(&m, -4800, 3000), 0); /* moved out: no cell */
    /* and back west past its other edge: what both squares hold is kept again */
    p.x_mm = -600;
    assert_int_equal(qnav_map_follow(&m, &p, 1500, 5000), 1);
    assert_int_equal(m.x0_mm, -2500 - 9 * 400);
    evidence_grid(&m, -2000, 100, 4400, 6500, after);
    assert_memory_equal(before, after, 64 * 64);
    /* north and east at once, then south */
    p.x_mm = 1500;
    p.y_mm = 8000;
    assert_int_equal(qnav_map_follow(&m, &p, 1500, 5000), 1);
    assert_int_equal(m.x0_mm, -4900);
    assert_int_equal(m.y0_mm, -3150 + 8 * 400);
    evidence_grid(&m, -2000, 100, 4400, 6500, after);
    assert_memory_equal(before, after, 64 * 64);
    p.y_mm = 1000;
    assert_int_equal(qnav_map_follow(&m, &p, 1500, 5000), 1);
    assert_int_equal(m.x0_mm, -4900);
    assert_int_equal(m.y0_mm, 50 - 9 * 400);
    evidence_grid(&m, -2000, 100, 4400, 6500, after);
    assert_memory_equal(before, after, 64 * 64);
    /* the plan made again over the moved map still goes round the wall (by its gap, or
     * past its west end, which the moved map now holds) */
    p.x_mm = 1500;
    memset(&in, 0, sizeof in);
    assert_true(qnav_map_guide(&m, &p, 1500, 5000, &in) & QNAV_MAP_GUIDED);
    assert_true(in.goal_range_mm > 3500 + 1000);
}

static void test_a_placed_map_follows_the_robot(void **state)
{
    (void)state;
    placed_map_follows(1);
    placed_map_follows(0);
}

static void test_bad_maps_are_refused(void **state)
{
    qnav_map_t m;
    qnav_map_config_t mc;
    qnav_ctrl_config_t cc;
    (void)state;
    sensor_config(&cc);
    qnav_map_config_default(&mc);
    assert_int_equal(qnav_map_init(NULL, &mc, &cc, 0, 0, 1000, 1000, mem, sizeof mem),
                     QNAV_E_NULL);
    assert_int_equal(qnav_map_init(&m, &mc, &cc, 0, 0, 1000, 1000, NULL, sizeof mem),
                     QNAV_E_NULL);
    /* too little memory for 6 000 mm square at 100 mm: 3 600 cells, 8 bytes each, and the
     * plan's queue */
    assert_int_equal(qnav_map_size(&mc, WORLD_MM, WORLD_MM), 3600u * 8u + 540u);
    assert_int_equal(qnav_map_init(&m, &mc, &cc, 0, 0, WORLD_MM, WORLD_MM, mem,
                                   qnav_map_size(&mc, WORLD_MM, WORLD_MM) - 1),
                     QNAV_E_MAP);
    assert_int_equal(qnav_map_init(&m, &mc, &cc, 0, 0, WORLD_MM, WORLD_MM, mem,
                                   qnav_map_size(&mc, WORLD_MM, WORLD_MM)),
                     QNAV_OK);
    mc.cell_mm = 10;
    assert_int_equal(square_metre(&m, &mc, &cc), QNAV_E_MAP);
    mc.cell_mm = 100;
    mc.plan_ticks = 0;
    assert_int_equal(square_metre(&m, &mc, &cc), QNAV_E_MAP);
    mc.plan_ticks = 10;
    mc.arc_cdeg = 36001;
    assert_int_equal(square_metre(&m, &mc, &cc), QNAV_E_MAP);
    mc.arc_cdeg = 36000;
    mc.reach_mm = 40001; /* distances are squared in 32 bits */
    assert_int_equal(square_metre(&m, &mc, &cc), QNAV_E_MAP);
    mc.reach_mm = 40000;
    mc.refuse_life_ticks = 0; /* a refusal that would never lapse */
    assert_int_equal(square_metre(&m, &mc, &cc), QNAV_E_MAP);
    mc.refuse_ticks = 0;
    assert_int_equal(square_metre(&m, &mc, &cc), QNAV_OK);
    /* the compact layout: half a byte a cell, rows of whole bytes; no bits for near costs
     * and refusals, and a cell must be wider than the body's reach (170 mm) */
    mc.compact = 1;
    mc.near_cost = 0;
    mc.cell_mm = 400;
    assert_int_equal(qnav_map_size(&mc, 3300, 1000), 4u * 3u * 2u); /* 9 x 3 cells */
    assert_int_equal(qnav_map_init(&m, &mc, &cc, 0, 0, 3300, 1000, mem, 23), QNAV_E_MAP);
    assert_int_equal(qnav_map_init(&m, &mc, &cc, 0, 0, 3300, 1000, mem, 24), QNAV_OK);
    mc.cell_mm = 170;
    assert_int_equal(square_metre(&m, &mc, &cc), QNAV_E_MAP);
    mc.cell_mm = 171;
    assert_int_equal(square_metre(&m, &mc, &cc), QNAV_OK);
    mc.near_cost = 1;
    assert_int_equal(square_metre(&m, &mc, &cc), QNAV_E_MAP);
    mc.near_cost = 0;
    mc.refuse_ticks = 1;
    assert_int_equal(square_metre(&m, &mc, &cc), QNAV_E_MAP);
    mc.refuse_ticks = 0;
    assert_int_equal(qnav_map_init(&m, &mc, &cc, 0, 0, 192u * 171u, 1000, mem, sizeof mem), QNAV_OK);
    assert_int_equal(qnav_map_init(&m, &mc, &cc, 0, 0, 193u * 171u, 1000, mem, sizeof mem),
                     QNAV_E_MAP); /* more than 192 cells across */
    mc.compact = 2;
    assert_int_equal(square_metre(&m, &mc, &cc), QNAV_E_MAP);
    assert_int_equal(qnav_map_cells(100000000u, 100000000u, 100), 0);
    assert_string_not_equal(qnav_status_str(QNAV_E_MAP), "unknown status");
}

static uint16_t mem_plain[CELLS_MAX * 4];

/* lo..hi (inclusive) from a fixed-seed linear congruential stream: the same draws every run. */
static int32_t draw(int32_t lo, int32_t hi)
{
    static uint32_t state = 12345u;
    state = state * 1664525u + 1013904223u;
    return lo + (int32_t)((state >> 8) % (uint32_t)(hi - lo + 1));
}

/* Maps marked by qnav_map_observe() (on hosts its shortcuts: observe_fast) and by the plain
 * marking, from the same random scans and poses (some off the map, headings all round),
 * hold the same cells after every scan: compact and full layouts, 8 to 72 sectors (a
 * compact map groups 72 into 32 wedges), an arc's width bound, range peaks, a grid turned
 * to the walls; compact rows of 3 bytes (20 cells, marked a byte at a time), 4 and 5 (30
 * and 36 cells, a word at a time on hosts). */
static void test_the_fast_marking_marks_as_the_plain_one(void **state)
{
    static const struct {
        uint8_t compact;
        uint16_t cell_mm, sectors, arc_width_mm, opening_mm, align_samples;
        uint8_t noise_pct;
    } cases[] = {
        {1, 300, 16, 0, 270, 40, 10}, {1, 200, 16, 0, 0, 0, 5},   {1, 300, 8, 200, 0, 0, 5},
        {1, 300, 72, 0, 270, 0, 10},  {0, 100, 16, 0, 270, 40, 10}, {0, 100, 32, 200, 0, 0, 5},
        {0, 200, 72, 0, 0, 0, 5},     {1, 171, 32, 0, 270, 0, 10},
    };
    size_t c;
    (void)state;
    for (c = 0; c < sizeof cases / sizeof cases[0]; ++c) {
        qnav_map_t fast, plain;
        qnav_map_config_t mc;
        qnav_ctrl_config_t cc;
        qnav_mm_t ranges[72];
        size_t bytes;
        int t, k;
        qnav_map_config_default(&mc);
        mc.compact = cases[c].compact;
        mc.near_cost = cases[c].compact ? 0u : mc.near_cost; /* a compact map has no near cost */
        mc.cell_mm = cases[c].cell_mm;
        mc.arc_width_mm = cases[c].arc_width_mm;
        mc.opening_mm = cases[c].opening_mm;
        mc.align_samples = cases[c].align_samples;
        mc.noise_pct = cases[c].noise_pct;
        sensor_config(&cc);
        cc.n_sectors = cases[c].sectors;
        bytes = qnav_map_size(&mc, WORLD_MM, WORLD_MM);
        assert_true(bytes > 0u && bytes <= sizeof mem);
        memset(mem, 0, sizeof mem); /* what the maps leave unwritten alike in both */
        memset(mem_plain, 0, sizeof mem_plain);
        assert_int_equal(qnav_map_init(&fast, &mc, &cc, 0, 0, WORLD_MM, WORLD_MM, mem, sizeof mem),
                         QNAV_OK);
        assert_int_equal(qnav_map_init(&plain, &mc, &cc, 0, 0, WORLD_MM, WORLD_MM, mem_plain,
                                       sizeof mem_plain),
                         QNAV_OK);
        for (t = 0; t < 300; ++t) {
            const qnav_map_pose_t p = {draw(-600, WORLD_MM + 600), draw(-600, WORLD_MM + 600),
                                       draw(-36000, 36000)};
            for (k = 0; k < cases[c].sectors; ++k) {
                ranges[k] = (qnav_mm_t)(draw(0, 2) == 0 ? 2500 : draw(0, 2499));
            }
            qnav_map_observe(&fast, ranges, &p);
            qnav_map_observe_plain(&plain, ranges, &p);
            assert_memory_equal(mem, mem_plain, bytes);
            assert_int_equal(fast.dirty, plain.dirty);
            fast.dirty = plain.dirty = 0u;
        }
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_a_reading_frees_its_wedge_and_marks_its_arc),
        cmocka_unit_test(test_a_reach_beyond_the_sonar_keeps_what_it_cannot_see),
        cmocka_unit_test(test_unknown_cells_cost_more_until_seen),
        cmocka_unit_test(test_the_grid_turns_to_the_walls),
        cmocka_unit_test(test_arcs_are_marked_in_the_central_part_of_the_wedge),
        cmocka_unit_test(test_a_wide_wedge_marks_only_the_default_arc),
        cmocka_unit_test(test_a_far_reading_marks_an_arc_no_wider_than_set),
        cmocka_unit_test(test_a_far_range_peak_in_a_wide_wedge_marks_no_arc),
        cmocka_unit_test(test_a_noisy_reading_keeps_its_arc_thin),
        cmocka_unit_test(test_the_plan_leads_round_the_wall_to_its_gap),
        cmocka_unit_test(test_the_compact_plan_leads_round_the_wall_to_its_gap),
        cmocka_unit_test(test_a_compact_plan_grown_a_few_steps_a_tick_holds_its_last_sub_goal),
        cmocka_unit_test(test_the_compact_layout_marks_as_the_full_one_and_plans_breadth_first),
        cmocka_unit_test(test_a_compact_map_keeps_the_cost_near_the_robot_only_while_it_holds),
        cmocka_unit_test(test_every_change_a_way_depends_on_drops_the_kept_cost),
        cmocka_unit_test(test_a_compact_map_reads_a_finer_scan_as_its_wedges),
        cmocka_unit_test(test_the_sub_goal_is_not_behind_a_corner),
        cmocka_unit_test(test_a_longer_plan_grows_the_escape_memory),
        cmocka_unit_test(test_a_longer_plan_that_reaches_the_robot_late_grows_the_escape_memory),
        cmocka_unit_test(test_a_compact_map_refuses_a_way_by_marking_it_occupied),
        cmocka_unit_test(test_the_destination_in_reach_is_flagged_direct),
        cmocka_unit_test(test_a_map_that_closed_every_way_forgets_what_it_marked),
        cmocka_unit_test(test_after_a_forget_only_near_readings_mark),
        cmocka_unit_test(test_a_way_the_robot_cannot_take_is_refused_for_a_while),
        cmocka_unit_test(test_a_turn_back_waits_its_ticks_once),
        cmocka_unit_test(test_the_plan_is_settled_as_far_as_the_robot_needs),
        cmocka_unit_test(test_a_map_reaches_toward_a_goal_too_far_for_it),
        cmocka_unit_test(test_a_map_keeps_the_robot_a_metre_inside),
        cmocka_unit_test(test_a_placed_map_follows_the_robot),
        cmocka_unit_test(test_bad_maps_are_refused),
        cmocka_unit_test(test_the_fast_marking_marks_as_the_plain_one),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
