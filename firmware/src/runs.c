/*
 * The run machinery of the step (runs.h): the iterator that cuts the 360 path levels into
 * runs outward from the goal, the row shapes learnt at init, and the rule that settles a
 * run from its row's shape before any evaluation; and the whole degree of an angle, the
 * paths' unit. Calls nothing above it: the step and the policy kinds call in.
 */
#include "runs.h"

#include <stddef.h>
#include <string.h>

/* Elsewhere than on AVR the level walks below compare a machine word of levels at a time
 * when the compiler can find a word's first differing byte (GCC, Clang; little-endian
 * words: x86-64, Cortex-M), and a byte at a time otherwise. */
#if !defined(__AVR__) && defined(__GNUC__) && defined(__BYTE_ORDER__) &&                  \
    __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
#define QNAV_WORD_WALK 1
typedef unsigned long walk_word_t;
#define WALK_BYTES ((uint8_t)sizeof(walk_word_t))

/* The word of WALK_BYTES levels at q, each byte xor level: 0 where a byte is level. */
static inline walk_word_t walk_diff(const uint8_t *q, uint8_t level)
{
    walk_word_t w;
    memcpy(&w, q, sizeof w);
    return w ^ ((~(walk_word_t)0 / 0xFFu) * level);
}
#else
#define QNAV_WORD_WALK 0
#endif

uint16_t qnav_whole_deg(qnav_cdeg_t cdeg)
{
    int16_t d = (int16_t)(cdeg / 100);
    int16_t rest = (int16_t)(cdeg - d * 100);
    if (rest >= 50) {
        ++d;
    } else if (rest <= -50) {
        --d;
    }
    while (d < 0) {
        d = (int16_t)(d + QNAV_PATHS);
    }
    while (d >= (int16_t)QNAV_PATHS) {
        d = (int16_t)(d - QNAV_PATHS);
    }
    return (uint16_t)d;
}

/* The first of the n bytes from q on that differs from level (q + n when none does). The
 * walk over the 360 levels is the step's longest loop: on AVR two bytes per iteration by
 * hand, 5.5 cycles a byte against 11 from avr-gcc (checked by the shared vectors under
 * simavr). */
static inline const uint8_t *same_up(const uint8_t *q, uint8_t n, uint8_t level)
{
#if defined(__AVR__)
    uint8_t pairs = (uint8_t)(n >> 1);
    if ((n & 1u) != 0u) {
        if (*q != level) {
            return q;
        }
        ++q;
    }
    if (pairs != 0u) {
        __asm__ volatile("1: ld __tmp_reg__, %a0+\n\t"
                         "cp __tmp_reg__, %2\n\t"
                         "brne 2f\n\t"
                         "ld __tmp_reg__, %a0+\n\t"
                         "cp __tmp_reg__, %2\n\t"
                         "brne 2f\n\t"
                         "dec %1\n\t"
                         "brne 1b\n\t"
                         "rjmp 3f\n\t"
                         "2: sbiw %0, 1\n\t"
                         "3:\n\t"
                         : "+z"(q), "+r"(pairs)
                         : "r"(level)
                         : "memory");
    }
    return q;
#else
    const uint8_t *end = q + n;
#if QNAV_WORD_WALK
    for (; end - q >= (ptrdiff_t)WALK_BYTES; q += WALK_BYTES) {
        const walk_word_t d = walk_diff(q, level);
        if (d != 0u) {
            return q + (__builtin_ctzl(d) >> 3); /* the lowest address differs first */
        }
    }
#endif
    while (q != end && *q == level) {
        ++q;
    }
    return q;
#endif
}

/* Walking down from q (whose byte is level), the lowest of q - n .. q such that every byte
 * from it to q is level. */
static inline const uint8_t *same_down(const uint8_t *q, uint8_t n, uint8_t level)
{
#if defined(__AVR__)
    uint8_t pairs = (uint8_t)(n >> 1);
    if ((n & 1u) != 0u) {
        if (q[-1] != level) {
            return q;
        }
        --q;
    }
    if (pairs != 0u) {
        __asm__ volatile("1: ld __tmp_reg__, -%a0\n\t"
                         "cp __tmp_reg__, %2\n\t"
                         "brne 2f\n\t"
                         "ld __tmp_reg__, -%a0\n\t"
                         "cp __tmp_reg__, %2\n\t"
                         "brne 2f\n\t"
                         "dec %1\n\t"
                         "brne 1b\n\t"
                         "rjmp 3f\n\t"
                         "2: adiw %0, 1\n\t"
                         "3:\n\t"
                         : "+z"(q), "+r"(pairs)
                         : "r"(level)
                         : "memory");
    }
    return q;
#else
    uint8_t i = 0;
#if QNAV_WORD_WALK
    for (; (uint8_t)(n - i) >= WALK_BYTES; i = (uint8_t)(i + WALK_BYTES)) {
        const walk_word_t d = walk_diff(q - WALK_BYTES, level);
        if (d != 0u) {
            /* the highest address below q that differs is the word's top differing byte */
            return q - (__builtin_clzl(d) >> 3);
        }
        q -= WALK_BYTES;
    }
#endif
    for (; i < n && q[-1] == level; ++i) {
        --q;
    }
    return q;
#endif
}

/*
 * The next run into *r; 0 when all 360 paths have been handed out. Runs come outward
 * from the goal: of the two sides (counter-clockwise: paths goal + 0..180, dtheta rising
 * with the path; clockwise: goal - 1..179, dtheta falling with the path), the one whose
 * next path is nearer the goal gives the next run, so runs arrive by their smallest
 * dtheta. A run ends where the level changes, at the side's end and at the wrap from path
 * 359 to 0 (a run's paths are first..first + count - 1).
 */
uint8_t qnav_run_next(qnav_run_iter_t *it, qnav_run_t *r)
{
    uint16_t p;
    uint16_t limit;
    uint8_t level;
    uint8_t k;
    if (it->up <= QNAV_DTHETA_MAX && (it->down >= QNAV_DTHETA_MAX || it->up <= it->down)) {
        p = (uint16_t)(it->goal + it->up);
        if (p >= QNAV_PATHS) {
            p = (uint16_t)(p - QNAV_PATHS);
        }
        limit = (uint16_t)(QNAV_DTHETA_MAX + 1u - it->up);
        if (limit > QNAV_PATHS - p) {
            limit = (uint16_t)(QNAV_PATHS - p);
        }
        level = it->lvl[p];
        k = (uint8_t)(same_up(it->lvl + p + 1, (uint8_t)(limit - 1u), level) - (it->lvl + p));
        r->first = p;
        r->dtheta0 = (uint8_t)it->up;
        r->dir = 1;
        it->up = (uint8_t)(it->up + k);
    } else if (it->down < QNAV_DTHETA_MAX) {
        p = (uint16_t)(it->goal >= it->down ? it->goal - it->down
                                            : it->goal + QNAV_PATHS - it->down);
        limit = (uint16_t)(QNAV_DTHETA_MAX - it->down);
        if (limit > p + 1u) {
            limit = (uint16_t)(p + 1u);
        }
        level = it->lvl[p];
        k = (uint8_t)((it->lvl + p) - same_down(it->lvl + p, (uint8_t)(limit - 1u), level) + 1);
        r->first = (uint16_t)(p + 1u - k);
        r->dtheta0 = (uint8_t)((uint8_t)(it->down + k) - 1u);
        r->dir = -1;
        it->down = (uint8_t)(it->down + k);
    } else {
        return 0;
    }
    r->count = k;
    r->level = level;
    return 1;
}

void qnav_row_shape_start(qnav_row_scan_t *sc, qnav_row_shape_t *s, qnav_qkey_t key0)
{
    sc->shape = s;
    sc->prev = key0;
    sc->last_rise = 0;
    sc->rising = 0;
    s->top = key0;
    s->top_d = 0;
    s->fall_d = 0;
    s->peak_lo = QNAV_PEAK_NONE;
    s->peak_hi = 0;
}

void qnav_row_shape_next(qnav_row_scan_t *sc, uint8_t d, qnav_qkey_t key)
{
    qnav_row_shape_t *s = sc->shape;
    if (key > s->top) {
        s->top = key;
        s->top_d = d;
    }
    if (key > sc->prev) {
        s->fall_d = d; /* the last rise so far ends here */
        sc->last_rise = d;
        sc->rising = 1;
    } else if (key < sc->prev && sc->rising) {
        /* a rise, equal keys, a fall: an interior peak last_rise..d - 1 */
        if (s->peak_lo == QNAV_PEAK_NONE) {
            s->peak_lo = sc->last_rise;
            s->peak_hi = (uint8_t)(d - 1u);
        } else {
            s->peak_lo = QNAV_PEAK_MANY;
        }
        sc->rising = 0;
    }
    sc->prev = key;
}

/* Narrow r (its dtheta a..b) to dtheta a..e. */
static void keep_dtheta(qnav_run_t *r, uint8_t a, uint8_t b, uint8_t e)
{
    if (r->dir < 0) {
        r->first = (uint16_t)(r->first + (uint8_t)(b - e));
        r->dtheta0 = e;
    }
    r->count = (uint8_t)((uint8_t)(e - a) + 1u);
}

/*
 * Every key of the run is at most the row's top, so a top below the best (or equal, with
 * every dtheta of the run larger than the best's: the tie is lost) rules the run out. A run
 * that holds the top's dtheta has its best there: the top is the largest key and top_d the
 * smallest dtheta with it. From fall_d on the keys never rise, so of the paths at or
 * beyond fall_d only the one nearest the goal can win (ties prefer the smaller dtheta).
 * Runs arrive by their smallest dtheta (qnav_run_next), so once a run of a level that lies
 * wholly beyond fall_d has had its first path offered, a later such run of that level
 * cannot win either: its keys are at most that path's, its dtheta larger. The one
 * exception is the run straight after it on the other side starting at the same dtheta
 * (equal keys, equal dtheta: the turn decides), which "fresh" recognises.
 */
uint8_t qnav_run_reduce(const qnav_row_shape_t *row, qnav_run_t *r, qnav_best_t *best,
                        qnav_run_iter_t *it)
{
    const qnav_row_shape_t *s = &row[r->level];
    uint8_t a = qnav_run_dmin(r);
    uint8_t b = (uint8_t)(a + (uint8_t)(r->count - 1u));
    uint8_t byte = (uint8_t)(r->level >> 3);
    uint8_t bit = (uint8_t)(1u << (r->level & 7u));
    uint8_t mirror = (uint8_t)(it->fresh && it->fresh_level == r->level && it->fresh_a == a);
    uint8_t e;
    it->fresh = 0;
    if (s->top < best->key || (s->top == best->key && a > best->dtheta)) {
        return QNAV_RUN_DONE;
    }
    if (s->top_d >= a && s->top_d <= b) {
        qnav_best_consider(best, s->top, qnav_run_path_at(r, s->top_d), s->top_d);
        return QNAV_RUN_DONE;
    }
    if (a >= s->fall_d) {
        if ((it->settled[byte] & bit) != 0u) {
            if (!mirror) {
                return QNAV_RUN_DONE;
            }
        } else {
            it->settled[byte] = (uint8_t)(it->settled[byte] | bit);
            it->fresh = 1;
            it->fresh_level = r->level;
            it->fresh_a = a;
        }
        keep_dtheta(r, a, b, a);
        return QNAV_RUN_ALL;
    }
    e = b < s->fall_d ? b : s->fall_d;
    keep_dtheta(r, a, b, e);
    if (s->peak_lo == QNAV_PEAK_MANY) {
        return QNAV_RUN_ALL; /* peaks somewhere: search */
    }
    if (s->peak_lo == QNAV_PEAK_NONE || !(a < s->peak_lo && s->peak_hi < e)) {
        return QNAV_RUN_VALLEY; /* no interior peak inside a..e */
    }
    return QNAV_RUN_PEAK;
}
