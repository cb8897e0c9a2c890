/*
 * The escape memory (firmware/src/escape.c; docs/architecture.md, "Leaving dead ends"):
 * scripted scans, the memory carried from each output to the next input as a caller does.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "clearance.h"
#include "escape.h"
#include "qnav/ctrl.h"
#include "test_rng.h"

#define N 16
#define MAX_MM 2500

/* The tests' configuration: the defaults with N sectors, MAX_MM range and the stall time. */
static void test_config(qnav_ctrl_config_t *cfg, uint8_t stall_ticks)
{
    qnav_ctrl_config_default(cfg);
    cfg->n_sectors = N;
    cfg->max_range_mm = MAX_MM;
    cfg->escape_stall_ticks = stall_ticks;
}

static void init_ctrl(qnav_ctrl_t *c, const qnav_policy_t *p, uint8_t stall_ticks)
{
    qnav_ctrl_config_t cfg;
    test_config(&cfg, stall_ticks);
    assert_int_equal(qnav_ctrl_init(c, &cfg, p), QNAV_OK);
}

/* A wall across the front: sectors -1, 0 and +1 read near, the rest nothing. */
static void wall_ahead(qnav_mm_t *r, qnav_mm_t near_mm)
{
    for (unsigned k = 0; k < N; ++k) {
        r[k] = MAX_MM;
    }
    r[0] = near_mm;
    r[1] = near_mm;
    r[N - 1] = near_mm;
}

/* One scripted robot: its policy, controller, scan, input and last output. */
typedef struct {
    qnav_policy_t p;
    qnav_ctrl_t c;
    qnav_mm_t r[N];
    qnav_ctrl_input_t in;
    qnav_ctrl_output_t out;
} bot_t;

/* A controller of policy b->p with the given stall time facing a wall near_mm ahead, the
 * destination range_mm away straight behind it. */
static void facing_wall(bot_t *b, uint8_t stall_ticks, qnav_mm_t near_mm, qnav_mm_t range_mm)
{
    init_ctrl(&b->c, &b->p, stall_ticks);
    memset(&b->in, 0, sizeof b->in);
    wall_ahead(b->r, near_mm);
    b->in.ranges_mm = b->r;
    b->in.goal_range_mm = range_mm;
}

/* One tick: the previous output's memory comes back in, as every caller must do. */
static void tick(const qnav_ctrl_t *c, qnav_ctrl_input_t *in, qnav_ctrl_output_t *out)
{
    qnav_ctrl_step(c, in, out, NULL);
    in->escape = out->escape;
    in->prev_heading_cdeg = (qnav_cdeg_t)(out->heading_deg * 100);
}

/* A controller of the default probabilistic policy facing a wall near_mm ahead, the
 * destination range_mm away beyond it, ticked until it has stalled and follows the wall. */
static void following_a_wall_at(bot_t *b, qnav_mm_t near_mm, qnav_mm_t range_mm)
{
    unsigned t;
    qnav_policy_prob_default(&b->p);
    facing_wall(b, 20, near_mm, range_mm);
    for (t = 0; t < 21; ++t) {
        tick(&b->c, &b->in, &b->out);
    }
    assert_int_not_equal(b->out.escape.side, 0);
}

/* The same, the wall 300 mm ahead and the destination 3000 mm away. */
static void following_a_wall(bot_t *b)
{
    following_a_wall_at(b, 300, 3000);
}

/* How far the robot's centre can go toward a reading near_mm away (the controller's
 * default body): the reading from the centre, less body radius and safety distance. */
static qnav_mm_t free_mm(qnav_mm_t near_mm)
{
    qnav_ctrl_config_t cfg;
    qnav_ctrl_config_default(&cfg);
    return (qnav_mm_t)(near_mm + cfg.sensor_offset_mm - cfg.body_radius_mm - cfg.safety_mm);
}

/* The controller's default margin (body radius and safety distance), mm. */
static unsigned margin_mm(void)
{
    qnav_ctrl_config_t cfg;
    qnav_ctrl_config_default(&cfg);
    return (unsigned)(cfg.body_radius_mm + cfg.safety_mm);
}

/* Facing a wall with the destination behind it and no progress: the robot goes for the
 * destination until the stall time is up, then follows the wall (turns well off the
 * destination's bearing). It leaves by DistBug's rule: once the free way toward the
 * destination ends nearer to it, by a step, than it did at the hit point. */
static void test_follows_after_a_stall_and_leaves_when_nearer(void **state)
{
    (void)state;
    bot_t b;
    qnav_policy_prob_default(&b.p);
    facing_wall(&b, 20, 300, 3000);
    for (unsigned t = 0; t < 20; ++t) {
        tick(&b.c, &b.in, &b.out);
        assert_int_equal(b.out.escape.side, 0);
    }
    tick(&b.c, &b.in, &b.out);
    assert_int_not_equal(b.out.escape.side, 0);
    /* the hit point: the free way toward the destination ended 3000 - free_mm(300) from it */
    assert_int_equal(b.out.escape.hit_mm, 3000 - free_mm(300));
    for (unsigned t = 0; t < 10; ++t) {
        tick(&b.c, &b.in, &b.out);
        assert_int_not_equal(b.out.escape.side, 0);
        /* along the wall, never into it: well away from straight ahead */
        assert_true(b.out.heading_deg >= 30 || b.out.heading_deg <= -30);
        assert_true(b.out.speed > 0);
    }
    /* nearer by less than the progress step, the wall as near: still following */
    b.in.goal_range_mm = 2950;
    tick(&b.c, &b.in, &b.out);
    assert_int_not_equal(b.out.escape.side, 0);
    /* much nearer, but the wall still blocks the way: still following */
    b.in.goal_range_mm = 2000;
    tick(&b.c, &b.in, &b.out);
    assert_int_not_equal(b.out.escape.side, 0);
    /* as far as at the hit, but the way toward the destination open to the sonar's range:
     * it ends far nearer than at the hit point, so the robot goes back to the destination */
    b.in.goal_range_mm = 3000;
    wall_ahead(b.r, MAX_MM);
    tick(&b.c, &b.in, &b.out);
    assert_int_equal(b.out.escape.side, 0);
    assert_int_equal(b.out.escape.best_mm, 3000);
    assert_true(b.out.heading_deg <= 5 && b.out.heading_deg >= -5);
}

/* The leave rule reads the clear way toward the destination from every sector within 11
 * degrees of its bearing, not only the one under it: a bearing 22 degrees off (sector 1's,
 * half a degree from sector 0's) does not see past a wall that sector 0 still reads as
 * near as at the hit point, however open sector 1 is. A compass whose noise carries the
 * bearing across a sector boundary must not make the robot leave on one tick and drive back
 * into the pocket it is leaving (docs/architecture.md, "Leaving"). */
static void test_the_leave_rule_reads_the_sectors_near_the_bearing(void **state)
{
    (void)state;
    bot_t b;
    following_a_wall_at(&b, 2000, 5000);
    assert_int_equal(b.out.escape.hit_mm, 5000 - free_mm(2000));
    /* sector 1 open to the sonar's range: on its own it would end the clear way 500 mm
     * nearer than at the hit; sector 0, 11 degrees off the bearing, still reads the wall */
    b.in.goal_bearing_cdeg = 2200;
    b.r[1] = MAX_MM;
    for (unsigned t = 0; t < 5; ++t) {
        tick(&b.c, &b.in, &b.out);
        assert_int_not_equal(b.out.escape.side, 0);
    }
    /* the wall gone from sector 0 too: the way is clear, the robot leaves */
    b.r[0] = MAX_MM;
    tick(&b.c, &b.in, &b.out);
    assert_int_equal(b.out.escape.side, 0);
}

/* The one sector under the bearing still leaves when it sees far past the hit point, by
 * four margins (r + d_s), more than a neighbour's wall can fake, though a neighbour within
 * 11 degrees reads nearer: the way past the end of a bar, seen beside its corner. */
static void test_the_sector_under_the_bearing_leaves_when_it_sees_far(void **state)
{
    (void)state;
    bot_t b;
    const unsigned margin = margin_mm();
    const unsigned hit = 5000 - free_mm(2000);
    following_a_wall_at(&b, 2000, 5000);
    b.in.goal_bearing_cdeg = 2200;
    b.r[0] = 1500; /* the bar's corner, 11 degrees off the bearing: the near way is shut */
    b.r[1] = MAX_MM;
    /* sector 1 sees the clear way end 4 margins less 1 mm short of the hit's: following */
    b.in.goal_range_mm = (qnav_mm_t)(hit - 4u * margin + free_mm(MAX_MM) + 1u);
    tick(&b.c, &b.in, &b.out);
    assert_int_not_equal(b.out.escape.side, 0);
    /* 4 margins: it leaves */
    b.in.goal_range_mm = (qnav_mm_t)(b.in.goal_range_mm - 1u);
    tick(&b.c, &b.in, &b.out);
    assert_int_equal(b.out.escape.side, 0);
}

/* Progress resets the stall count: a robot that keeps getting nearer never follows. */
static void test_progress_never_follows(void **state)
{
    (void)state;
    bot_t b;
    qnav_policy_prob_default(&b.p);
    facing_wall(&b, 20, 300, 9000);
    for (unsigned t = 0; t < 200; ++t) {
        tick(&b.c, &b.in, &b.out);
        assert_int_equal(b.out.escape.side, 0);
        b.in.goal_range_mm = (qnav_mm_t)(b.in.goal_range_mm - 40u); /* 0.4 m/s */
    }
}

/* A follow that does not get nearer is given up for the other side after escape_follow_s
 * and one stall time more (the window in which it could still have got nearer): the
 * default robot following a wall until then. Returns the side given up. */
static int8_t first_side_given_up(bot_t *b)
{
    int8_t first;
    unsigned t;
    following_a_wall(b);
    first = b->out.escape.side;
    for (t = 0; t < 219; ++t) {
        tick(&b->c, &b->in, &b->out);
        assert_int_equal(b->out.escape.side, first);
    }
    tick(&b->c, &b->in, &b->out);
    assert_int_equal(b->out.escape.side, -first);
    assert_int_equal(b->out.escape.tries, 1);
    return first;
}

/* ... and the next try lasts twice as long. */
static void test_a_long_follow_tries_the_other_side(void **state)
{
    (void)state;
    bot_t b;
    int8_t first = first_side_given_up(&b);
    unsigned t;
    for (t = 0; t < 419; ++t) {
        tick(&b.c, &b.in, &b.out);
        assert_int_equal(b.out.escape.side, -first);
    }
    tick(&b.c, &b.in, &b.out);
    assert_int_equal(b.out.escape.side, first);
}

/* A side given up stays given up: after the first side's try, the other side is left
 * early (a way seen open for a tick) and the robot stalls again no nearer; it goes on
 * round the other side, with that try's length, instead of going back the side it gave
 * up (the rule for a follow that led back to its wall). */
static void test_a_side_given_up_is_not_taken_again(void **state)
{
    (void)state;
    bot_t b;
    int8_t first = first_side_given_up(&b);
    unsigned t;
    wall_ahead(b.r, MAX_MM); /* the way opens for a tick */
    tick(&b.c, &b.in, &b.out);
    assert_int_equal(b.out.escape.side, 0);
    wall_ahead(b.r, 300); /* and closes: the same wall, no nearer */
    for (t = 0; t < 21; ++t) {
        tick(&b.c, &b.in, &b.out);
    }
    assert_int_equal(b.out.escape.side, -first);
    assert_int_equal(b.out.escape.tries, 1);
}

/* Past its time, a follow that still gets nearer to the destination (round the far end of
 * a long wall) goes on; once it stops getting nearer, it is given up a stall time later. */
static void test_a_follow_getting_nearer_outlasts_its_time(void **state)
{
    (void)state;
    bot_t b;
    int8_t first;
    unsigned t;
    qnav_policy_prob_default(&b.p);
    facing_wall(&b, 20, 300, 9000); /* room to get nearer for 45 s */
    for (t = 0; t < 21; ++t) {
        tick(&b.c, &b.in, &b.out);
    }
    first = b.out.escape.side;
    assert_int_not_equal(first, 0);
    for (t = 0; t < 600; ++t) {
        if (t >= 150u && t % 10u == 0u) { /* half a margin nearer a second */
            b.in.goal_range_mm = (qnav_mm_t)(b.in.goal_range_mm - (margin_mm() / 2u + 1u));
        }
        tick(&b.c, &b.in, &b.out);
        assert_int_equal(b.out.escape.side, first);
    }
    for (t = 0; t < 19; ++t) {
        tick(&b.c, &b.in, &b.out);
        assert_int_equal(b.out.escape.side, first);
    }
    for (t = 0; t < 21 && b.out.escape.side == first; ++t) {
        tick(&b.c, &b.in, &b.out);
    }
    assert_int_equal(b.out.escape.side, -first);
}

/* Following a wall with open space on the other hand, a side that leads 14 margins
 * farther from the destination than where it began is given up before its time (the
 * wrong way along a long wall); the next try may lead twice as far. In a corridor (the
 * other hand closed) the same side is kept: there the way out leads away first, and when
 * the corridor turns (the other hand opens) only what the side loses from there on counts. */
/* n ticks, each half a margin farther from the destination, the side followed kept; then
 * one more half margin, after which the side is `then`. */
static void walk_away(bot_t *b, unsigned n, int8_t side, int8_t then)
{
    const unsigned step = margin_mm() / 2u;
    unsigned t;
    for (t = 0; t <= n; ++t) {
        if (t == n) {
            side = then;
        }
        b->in.goal_range_mm = (qnav_mm_t)(b->in.goal_range_mm + step);
        tick(&b->c, &b->in, &b->out);
        assert_int_equal(b->out.escape.side, side);
    }
}

static void test_a_follow_leading_away_is_given_up_early(void **state)
{
    (void)state;
    bot_t b;
    int8_t first;
    following_a_wall(&b);
    first = b.out.escape.side;
    walk_away(&b, 28, first, (int8_t)-first); /* 14 margins in half-margin steps, then beyond */
    assert_int_equal(b.out.escape.from_mm, b.in.goal_range_mm);
    walk_away(&b, 56, (int8_t)-first, first); /* the second try: 28 margins */

    following_a_wall(&b);
    first = b.out.escape.side;
    b.r[N / 4] = 400; /* a corridor: walls on both hands */
    b.r[3 * N / 4] = 400;
    walk_away(&b, 150, first, first);
    /* the corridor turns: the away hand opens. What the range grew by between the walls
     * does not count; 14 margins more through the open does. */
    b.r[first > 0 ? N / 4 : 3 * N / 4] = MAX_MM;
    walk_away(&b, 28, first, (int8_t)-first);
}

/* At 32 sectors the open hand is read over +-11 degrees of the path 90 degrees off the
 * boundary (three sectors), as one sector does at 16: a corridor whose 90-degree sector
 * alone sees through (a turn, a doorway) is still closed, and the side is kept. */
static void test_the_open_hand_is_read_alike_at_32_sectors(void **state)
{
    enum { N32 = 32 };
    qnav_policy_t p;
    qnav_ctrl_t c;
    qnav_ctrl_config_t cfg;
    qnav_mm_t r[N32];
    qnav_ctrl_input_t in;
    qnav_ctrl_output_t out;
    const unsigned step = margin_mm() / 2u;
    unsigned t;
    int8_t first;
    unsigned away;
    (void)state;
    qnav_policy_prob_default(&p);
    test_config(&cfg, 20);
    cfg.n_sectors = N32;
    assert_int_equal(qnav_ctrl_init(&c, &cfg, &p), QNAV_OK);
    memset(&in, 0, sizeof in);
    for (t = 0; t < N32; ++t) {
        r[t] = MAX_MM;
    }
    r[N32 - 1] = r[0] = r[1] = 300; /* a wall ahead, the destination behind it */
    in.ranges_mm = r;
    in.goal_range_mm = 3000;
    for (t = 0; t < 21; ++t) {
        tick(&c, &in, &out);
    }
    first = out.escape.side;
    assert_int_not_equal(first, 0);
    away = first > 0 ? N32 / 4 : 3 * N32 / 4;
    r[away - 1] = 400; /* the open hand's sectors at 78.75 and 101.25 degrees read a wall; */
    r[away + 1] = 400; /* the one at 90 degrees sees through */
    for (t = 0; t < 60; ++t) { /* 30 margins farther: more than the 14 of the budget */
        in.goal_range_mm = (qnav_mm_t)(in.goal_range_mm + step);
        tick(&c, &in, &out);
        assert_int_equal(out.escape.side, first);
    }
}

/* Following a wall on the right (side +1), the destination behind it: the bearing it
 * skirts by is found from the wall itself, so the decision is the same whatever the
 * previous command was (a search from 90 degrees off the previous command swung with the
 * policy's own choice and dithered at doorways), and it runs along the wall: past its
 * readings, not back. */
static void test_the_follow_bearing_comes_from_the_boundary(void **state)
{
    static const qnav_cdeg_t prev[] = {0, 9000, -4000, 17000, -13000};
    bot_t b;
    qnav_escape_t following;
    qnav_deg_t first = 0;
    unsigned t;
    (void)state;
    following_a_wall(&b);
    assert_int_equal(b.out.escape.side, 1); /* a symmetric wall: obstacle on the right */
    following = b.out.escape;
    for (t = 0; t < N; ++t) {
        b.r[t] = MAX_MM;
    }
    b.r[N / 4 * 3 - 1] = 300; /* sectors at -112.5, -90 and -67.5 degrees: a wall 300 mm */
    b.r[N / 4 * 3] = 300;     /* to the right, the destination behind it */
    b.r[N / 4 * 3 + 1] = 300;
    b.in.goal_bearing_cdeg = -9000;
    for (t = 0; t < sizeof prev / sizeof prev[0]; ++t) {
        b.in.escape = following;
        b.in.prev_heading_cdeg = prev[t];
        qnav_ctrl_step(&b.c, &b.in, &b.out, NULL);
        assert_int_equal(b.out.escape.side, 1);
        if (t == 0) {
            first = b.out.heading_deg;
        }
        assert_int_equal(b.out.heading_deg, first);
    }
    /* the wall's readings block the paths to about -41 degrees (-67.5 plus its part of the
     * wedge and the enlargement asin((r + d_s) / 420 mm)): past them, not back */
    assert_true(first >= -40 && first <= 60);
    assert_true(b.out.speed > 0);
}

/* The follow's bearing with the wall of the test above (300 mm on the right, the
 * destination behind it) when readings block wedge_pct % of their wedge; *clear: the first
 * path counter-clockwise from the wall's middle (-90 degrees) whose level clears the
 * follow level, as signed degrees. */
static int16_t follow_bearing(uint8_t wedge_pct, int16_t *clear, uint8_t *shaved)
{
    bot_t b;
    qnav_ctrl_config_t cfg;
    qnav_ctrl_t c;
    qnav_escape_t e;
    uint8_t lvl[QNAV_PATHS];
    int16_t k;
    uint16_t goal;
    following_a_wall(&b);
    e = b.out.escape;
    assert_int_equal(e.side, 1);
    test_config(&cfg, 20);
    cfg.wedge_pct = wedge_pct;
    assert_int_equal(qnav_ctrl_init(&c, &cfg, &b.p), QNAV_OK);
    for (k = 0; k < N; ++k) {
        b.r[k] = MAX_MM;
    }
    b.r[N / 4 * 3 - 1] = 300;
    b.r[N / 4 * 3] = 300;
    b.r[N / 4 * 3 + 1] = 300;
    b.in.goal_bearing_cdeg = -9000;
    b.in.escape = e;
    (void)qnav_clearance_input_levels(&c.clr, &b.in, lvl);
    for (k = -90; k < 90 && lvl[(k + QNAV_PATHS) % QNAV_PATHS] < c.clr.esc_free_level; ++k) {
    }
    *clear = k;
    *shaved = c.clr.wedge_shrink;
    goal = qnav_escape_goal(&c.clr, lvl, &b.in, &e);
    assert_int_equal(e.side, 1);
    return (int16_t)(goal >= QNAV_PATHS / 2u ? (int16_t)goal - (int16_t)QNAV_PATHS : (int16_t)goal);
}

/* The follow's bearing from hand-made levels lvl in follow state e (side s), the
 * destination on that side. */
static uint16_t skirt_of(const bot_t *b, const qnav_escape_t *e, int8_t s, const uint8_t *lvl)
{
    qnav_ctrl_input_t in = b->in;
    qnav_escape_t m = *e;
    m.side = s;
    in.escape = m;
    in.goal_bearing_cdeg = (qnav_cdeg_t)(-9000 * s);
    return qnav_escape_goal(&b->c.clr, lvl, &in, &m);
}

/* The follow skirts from the first path, walking its side's half outward from straight
 * ahead, that has the half's lowest level: where several share it, the later ones do not
 * matter. On random levels (few values, so that lowest levels repeat, often within
 * sixteen paths) raising every later path of the lowest level by one leaves the bearing as
 * it was, on either side; a walk that took another of them (the x86 windows' last hit
 * instead of their first) turns from there and does not. */
static void test_the_follow_skirts_from_the_first_nearest_path(void **state)
{
    static const uint8_t values[] = {4, 9, 14, 31};
    bot_t b;
    uint8_t lvl[QNAV_PATHS], raised[QNAV_PATHS];
    unsigned t, moved = 0;
    (void)state;
    following_a_wall(&b);
    for (t = 0; t < 4000; ++t) {
        const int8_t s = (t & 1u) ? 1 : -1;
        uint8_t lw = 255u;
        int16_t k, first = -1;
        for (k = 0; k < (int16_t)QNAV_PATHS; ++k) {
            lvl[k] = values[rng_range(0, 3)];
        }
        for (k = 1; k < (int16_t)QNAV_DTHETA_MAX; ++k) { /* the half, walked outward */
            uint16_t p = (uint16_t)(s < 0 ? k : (int16_t)QNAV_PATHS - k);
            if (lvl[p] < lw) {
                lw = lvl[p];
                first = (int16_t)p;
            }
        }
        memcpy(raised, lvl, sizeof raised);
        for (k = 1; k < (int16_t)QNAV_DTHETA_MAX; ++k) {
            uint16_t p = (uint16_t)(s < 0 ? k : (int16_t)QNAV_PATHS - k);
            if (lvl[p] == lw && (int16_t)p != first) {
                raised[p] = (uint8_t)(lw + 1u);
                ++moved;
            }
        }
        assert_int_equal(skirt_of(&b, &b.out.escape, s, lvl),
                         skirt_of(&b, &b.out.escape, s, raised));
    }
    assert_true(moved > 4000u); /* the lowest level repeated in most cases */
}

/* A reading placed on the central part of its wedge (wedge_pct) may lie anywhere in the
 * edge the placement left free, and a follow drives tangent to what it sees: its bearing
 * keeps half that edge beyond the first path that clears the follow level (the Pioneer's
 * touches at the ends of walls; docs/architecture.md, "The follow keeps half the shaved
 * edge away"). Whole wedges leave no edge, and the bearing is that path. */
static void test_a_follow_keeps_half_the_shaved_edge_away(void **state)
{
    int16_t clear;
    uint8_t shaved;
    int16_t bearing;
    (void)state;
    bearing = follow_bearing(100, &clear, &shaved);
    assert_int_equal(shaved, 0);
    assert_int_equal(bearing, clear);
    bearing = follow_bearing(20, &clear, &shaved);
    assert_true(shaved / 2 >= 4); /* 80 % of half a 22.5 degree wedge */
    assert_int_equal(bearing, clear + shaved / 2);
}

/* Following round an island (a box in a room, the way to the destination beyond it never
 * opening): back at the place marked early in the follow (the destination's range and
 * bearing as they were), the robot has gone round, and it leaves once it is again as
 * near the destination as it came on the way round (Bug1), choosing the next side afresh.
 * Passing the mark's range with a bearing 30 degrees or more off is not being back. Returns the side at
 * the end; back_cdeg: the bearing when the range returns to the mark's. */
static int8_t round_an_island(qnav_cdeg_t back_cdeg)
{
    bot_t b;
    unsigned t;
    following_a_wall(&b);
    assert_int_not_equal(b.out.escape.side, 0);
    b.in.goal_range_mm = 3200; /* the mark, 20 ticks into the follow */
    for (t = 0; t < 21; ++t) {
        tick(&b.c, &b.in, &b.out);
    }
    b.in.goal_range_mm = 3600; /* away from it */
    tick(&b.c, &b.in, &b.out);
    b.in.goal_range_mm = 2960; /* the nearest the way round comes (the wall still ahead:
                                  DistBug's rule does not leave) */
    tick(&b.c, &b.in, &b.out);
    assert_int_not_equal(b.out.escape.side, 0);
    b.in.goal_range_mm = 3200; /* back at the mark's range */
    b.in.goal_bearing_cdeg = back_cdeg;
    tick(&b.c, &b.in, &b.out);
    b.in.goal_bearing_cdeg = 0;
    b.in.goal_range_mm = 3400; /* on round, away from the mark again */
    tick(&b.c, &b.in, &b.out);
    assert_int_not_equal(b.out.escape.side, 0);
    b.in.goal_range_mm = 3000; /* within (r + d_s) / 2 of the nearest */
    tick(&b.c, &b.in, &b.out);
    if (b.out.escape.side == 0) {
        assert_int_equal(b.out.escape.last_side, 0); /* the next stall chooses afresh */
    }
    return b.out.escape.side;
}

static void test_round_an_island_leaves_at_its_nearest_place(void **state)
{
    (void)state;
    assert_int_equal(round_an_island(0), 0);
    /* 32 degrees off the mark's bearing (still into the wall): not back at the mark */
    assert_int_not_equal(round_an_island(3200), 0);
}

/* A wall ahead and to the left (sectors 0, 1 and 2): the nearest free way round is on the
 * right, so a fresh choice follows it on the left (side -1). */
static void wall_ahead_left(qnav_mm_t *r, qnav_mm_t near_mm)
{
    wall_ahead(r, near_mm);
    r[N - 1] = MAX_MM;
    r[2] = near_mm;
}

/* A follow on side +1 that began 3000 mm from the destination and ended end_mm from it,
 * then the ticks of a new stall range_mm away at a wall ahead and to the left. Returns the
 * side the robot then follows. */
static int8_t side_of_next_stall(qnav_mm_t end_mm, qnav_mm_t range_mm)
{
    bot_t b;
    unsigned t;
    following_a_wall(&b);
    assert_int_equal(b.out.escape.side, 1); /* a symmetric wall: counter-clockwise */
    wall_ahead(b.r, MAX_MM);                /* the way opens: the follow ends at end_mm */
    b.in.goal_range_mm = end_mm;
    tick(&b.c, &b.in, &b.out);
    assert_int_equal(b.out.escape.side, 0);
    wall_ahead_left(b.r, 300);
    b.in.goal_range_mm = range_mm;
    for (t = 0; t < 21; ++t) {
        tick(&b.c, &b.in, &b.out);
    }
    assert_int_not_equal(b.out.escape.side, 0);
    return b.out.escape.side;
}

/* A new stall near where the last follow ended, and nearer than where it began, keeps its
 * side (no shuttling between two sides of one obstacle); one more than 4 (r + d_s) nearer
 * than where it ended is at another obstacle and chooses afresh (an S-corridor's next
 * wall); one no nearer than where the last follow began means that follow led back to it
 * (round a room, back to the same wall): the other way round. */
static void test_a_new_obstacle_chooses_its_side_afresh(void **state)
{
    const qnav_mm_t margin = (qnav_mm_t)margin_mm();
    (void)state;
    assert_int_equal(side_of_next_stall(2500, 2450), 1);
    assert_int_equal(side_of_next_stall(2500, (qnav_mm_t)(2500 - 4 * margin + 10)), 1);
    assert_int_equal(side_of_next_stall(2500, (qnav_mm_t)(2500 - 4 * margin - 10)), -1);
    /* the follow left farther away (3400) and the robot stalls where it stalled before */
    assert_int_equal(side_of_next_stall(3400, 3000), -1);
    assert_int_equal(side_of_next_stall(3400, (qnav_mm_t)(3000 - margin / 2u + 1u)), -1);
    assert_int_equal(side_of_next_stall(3400, (qnav_mm_t)(3000 - margin / 2u - 1u)), 1);
}

/* No policy freezes: a network whose quality is 0 on every path stands still (NO_PATH)
 * until the stall time is up, then crawls along the boundary. Without an escape it stands
 * still for ever. */
static void test_a_policy_of_zeros_does_not_freeze(void **state)
{
    (void)state;
    bot_t b;
    qnav_ctrl_t off;
    qnav_ctrl_input_t in_off;
    unsigned moving = 0;
    qnav_policy_net_zero(&b.p, 4);
    b.p.u.net.b_out = (qnav_q8_8_t)-32768;
    init_ctrl(&off, &b.p, 0);
    facing_wall(&b, 20, 400, 3000);
    in_off = b.in;
    for (unsigned t = 0; t < 60; ++t) {
        tick(&b.c, &b.in, &b.out);
        if (b.out.speed > 0) {
            ++moving;
            assert_int_equal(b.out.flags & QNAV_FLAG_NO_PATH, 0);
        }
        tick(&off, &in_off, &b.out);
        assert_int_equal(b.out.speed, 0);
        assert_int_not_equal(b.out.flags & QNAV_FLAG_NO_PATH, 0);
    }
    assert_true(moving >= 30);
}

/* While following, a decision that moves goes as fast as the robot can stop within the
 * clearance of its path, of straight ahead and of the boundary's half (the speed guard's
 * cap at the lowest of them): the probabilistic policy's speed is its quality, its
 * confidence in a way toward the destination, and along a boundary that is a crawl. The
 * boundary's half counts because a follow that turns back turns into it. */
static void test_a_follow_goes_at_its_speed_cap(void **state)
{
    static const qnav_cdeg_t prev[] = {0, 9000, -4000, 17000};
    bot_t b;
    qnav_escape_t following;
    qnav_ctrl_config_t cfg;
    uint8_t lvl[QNAV_PATHS];
    uint8_t low = 255u;
    unsigned t;
    (void)state;
    following_a_wall(&b);
    following = b.out.escape;
    test_config(&cfg, 20); /* the same controller, braking slowly */
    cfg.decel_mm_s2 = 250;
    assert_int_equal(qnav_ctrl_init(&b.c, &cfg, &b.p), QNAV_OK);
    for (t = 0; t < N; ++t) {
        b.r[t] = MAX_MM;
    }
    b.r[N / 4 * 3 - 1] = 600; /* a wall 600 mm to the right, the destination behind it */
    b.r[N / 4 * 3] = 600;     /* as far beyond it as the first wall left it (no leave), */
    b.r[N / 4 * 3 + 1] = 600;
    b.r[N - 1] = 800;         /* and a post 800 mm away 22.5 degrees right of ahead: the */
    b.in.goal_bearing_cdeg = -9000; /* policy's own speed past it is 0.86 */
    b.in.goal_range_mm = 3300;
    (void)qnav_ctrl_path_levels(&b.c, b.r, lvl);
    for (t = 1; t < QNAV_PATHS / 2u; ++t) {
        low = lvl[QNAV_PATHS - t] < low ? lvl[QNAV_PATHS - t] : low; /* the boundary's half */
    }
    for (t = 0; t < sizeof prev / sizeof prev[0]; ++t) {
        int16_t h;
        uint16_t path;
        uint8_t level = low < lvl[0] ? low : lvl[0];
        b.in.escape = following;
        b.in.prev_heading_cdeg = prev[t];
        qnav_ctrl_step(&b.c, &b.in, &b.out, NULL);
        assert_int_equal(b.out.escape.side, 1);
        h = b.out.heading_deg;
        path = (uint16_t)(h < 0 ? h + QNAV_PATHS : h);
        level = lvl[path] < level ? lvl[path] : level;
        assert_int_equal(b.out.speed, qnav_clearance_speed_cap(&b.c.clr, level));
        assert_true(b.out.speed < qnav_clearance_turn_cap(&b.c.clr, lvl, path));
    }
}

/* A robot that stands does not stand for ever, whatever a map's plans do. A wall so near
 * ahead that no decision may move (the speed cap of straight ahead is 0), and a plan that
 * jumps every 5 ticks (qnav_escape_follow_plan clears the memory: no stall ever builds up,
 * no follow starts): the decisions count the ticks they stand, and past twice the stall
 * time the decision is the middle of a free window (every path within 5 degrees either side free)
 * and stays there while the robot turns toward it. A decision that moves halves the count. */
static void test_a_robot_that_stands_turns_to_a_free_window(void **state)
{
    bot_t b;
    qnav_ctrl_input_t fresh;
    qnav_ctrl_output_t decided;
    uint8_t lvl[QNAV_PATHS];
    int16_t first = 0;
    unsigned t;
    (void)state;
    qnav_policy_prob_default(&b.p);
    facing_wall(&b, 20, 120, 3000);
    (void)qnav_ctrl_path_levels(&b.c, b.r, lvl);
    assert_int_equal(qnav_clearance_turn_cap(&b.c.clr, lvl, 90), 0);
    for (t = 1; t <= 60; ++t) {
        if (t % 5 == 0) {
            qnav_escape_follow_plan(&b.in.escape, 1, 0);
        }
        fresh = b.in; /* the same tick by a robot that has not stood */
        fresh.escape.stood = 0u;
        qnav_ctrl_step(&b.c, &fresh, &decided, NULL);
        tick(&b.c, &b.in, &b.out);
        assert_int_equal(b.out.escape.side, 0);
        assert_int_equal(b.out.speed, 0);
        assert_int_equal(b.out.escape.stood, t);
        if (t <= 40u) {
            assert_int_equal(b.out.heading_deg, decided.heading_deg); /* as decided */
        } else {
            const int16_t h = b.out.heading_deg;
            const uint16_t p = (uint16_t)(h < 0 ? h + QNAV_PATHS : h);
            int k;
            for (k = -5; k <= 5; ++k) {
                assert_true(lvl[(p + QNAV_PATHS + (uint16_t)(k + 5) - 5u) % QNAV_PATHS] >=
                            b.c.clr.esc_free_level);
            }
            if (t == 41u) {
                first = h;
            }
            assert_int_equal(h, first); /* one way, not a new one each tick */
        }
    }
    for (t = 0; t < N; ++t) {
        b.r[t] = MAX_MM; /* it has turned and faces open space: it drives */
    }
    tick(&b.c, &b.in, &b.out);
    assert_true(b.out.speed > 0);
    assert_int_equal(b.out.escape.stood, 30);
    tick(&b.c, &b.in, &b.out);
    assert_int_equal(b.out.escape.stood, 15);
    /* the memory's own clear (a new destination) forgets it */
    qnav_escape_clear(&b.out.escape);
    assert_int_equal(b.out.escape.stood, 0);
}

/* Without a distance to the destination (0) there is no escape, and the memory stays 0. */
static void test_no_range_no_escape(void **state)
{
    (void)state;
    bot_t b;
    qnav_policy_prob_default(&b.p);
    facing_wall(&b, 20, 300, 0);
    for (unsigned t = 0; t < 100; ++t) {
        tick(&b.c, &b.in, &b.out);
        assert_int_equal(b.out.escape.side, 0);
        assert_int_equal(b.out.escape.best_mm, 0);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_follows_after_a_stall_and_leaves_when_nearer),
        cmocka_unit_test(test_the_leave_rule_reads_the_sectors_near_the_bearing),
        cmocka_unit_test(test_the_sector_under_the_bearing_leaves_when_it_sees_far),
        cmocka_unit_test(test_progress_never_follows),
        cmocka_unit_test(test_a_long_follow_tries_the_other_side),
        cmocka_unit_test(test_a_side_given_up_is_not_taken_again),
        cmocka_unit_test(test_a_follow_getting_nearer_outlasts_its_time),
        cmocka_unit_test(test_a_follow_leading_away_is_given_up_early),
        cmocka_unit_test(test_the_open_hand_is_read_alike_at_32_sectors),
        cmocka_unit_test(test_the_follow_bearing_comes_from_the_boundary),
        cmocka_unit_test(test_a_follow_keeps_half_the_shaved_edge_away),
        cmocka_unit_test(test_the_follow_skirts_from_the_first_nearest_path),
        cmocka_unit_test(test_round_an_island_leaves_at_its_nearest_place),
        cmocka_unit_test(test_a_new_obstacle_chooses_its_side_afresh),
        cmocka_unit_test(test_a_policy_of_zeros_does_not_freeze),
        cmocka_unit_test(test_a_follow_goes_at_its_speed_cap),
        cmocka_unit_test(test_a_robot_that_stands_turns_to_a_free_window),
        cmocka_unit_test(test_no_range_no_escape),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
