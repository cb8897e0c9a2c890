/*
 * The map in 4 bits a cell (map_compact.h; docs/architecture.md, "A map in 4 bits a cell").
 *
 * Four bit planes, a row of cells a whole number of bytes in each, cell i of a row in bit
 * i % 8 of byte i / 8:
 *   seen (2 planes): 00 unknown, 01 one arc's evidence, 10 occupied, 11 seen free. These
 *     are the full layout's evidence values as its marking uses them: a free cell takes no
 *     arc evidence whatever its count, and occupied at 2 or 3 behaves the same.
 *   plan (2 planes): 0 not reached, else the cell's step count from the destination's
 *     cell modulo 3, plus 1. A breadth-first plan (8 neighbours, a diagonal only past two
 *     passable cells, every step one) grows one step count at a time over whole rows, 8
 *     cells a byte operation; a neighbour a step nearer has the count one less modulo 3,
 *     and no other neighbour can, so the way to the destination is found from the counts
 *     modulo 3 alone. That holds for counts grown over one state of the cells: a plan is
 *     grown further only while no cell became or stopped being occupied since it began
 *     (else map.c starts it again).
 */
#include "map_compact.h"

#include <string.h>

enum { SEEN_LO, SEEN_HI, PLAN_LO, PLAN_HI, PLANES };

#define SEEN_UNKNOWN 0u
#define SEEN_ONCE 1u
#define SEEN_OCCUPIED 2u
#define SEEN_FREE 3u
#define STEP_SIDE 10u
#define STEP_DIAG 14u

size_t qnav_cmap_bytes(uint32_t nx, uint32_t ny)
{
    return (size_t)((uint32_t)PLANES * ny * ((nx + 7u) / 8u));
}

static uint8_t *plane(const qnav_map_t *m, unsigned k, int32_t j)
{
    return m->planes + ((size_t)k * m->ny + (size_t)j) * m->row_bytes;
}

/* Bit i % 8 of a byte (an AVR shifts one place a cycle: a table is quicker). */
static const uint8_t bit_of[8] = {1u, 2u, 4u, 8u, 16u, 32u, 64u, 128u};

static unsigned bit2(const qnav_map_t *m, unsigned lo, int32_t i, int32_t j)
{
    const uint8_t *p = plane(m, lo, j) + ((unsigned)i >> 3);
    const uint8_t bit = bit_of[(unsigned)i & 7u];
    const size_t stride = (size_t)m->ny * m->row_bytes; /* plane lo + 1 */
    return ((p[0] & bit) != 0u ? 1u : 0u) | ((p[stride] & bit) != 0u ? 2u : 0u);
}

static void set2(const qnav_map_t *m, unsigned lo, int32_t i, int32_t j, unsigned v)
{
    const unsigned b = (unsigned)i >> 3;
    const uint8_t bit = bit_of[(unsigned)i & 7u];
    uint8_t *p0 = &plane(m, lo, j)[b], *p1 = &plane(m, lo + 1u, j)[b];
    *p0 = (uint8_t)((v & 1u) ? (*p0 | bit) : (*p0 & (uint8_t)~bit));
    *p1 = (uint8_t)((v & 2u) ? (*p1 | bit) : (*p1 & (uint8_t)~bit));
}

/* A label, a cell's occupancy or the plan's growth changed: the cost last found near a
 * cell (qnav_cmap_cost_near) may differ now. */
static void ways_changed(qnav_map_t *m)
{
    m->way_from = UINT16_MAX;
}

void qnav_cmap_attach(qnav_map_t *m, void *buf)
{
    m->planes = (uint8_t *)buf;
    m->row_bytes = (uint16_t)((m->nx + 7u) / 8u);
}

void qnav_cmap_reset(qnav_map_t *m)
{
    memset(m->planes, 0, qnav_cmap_bytes(m->nx, m->ny));
    ways_changed(m);
}

int8_t qnav_cmap_evidence(const qnav_map_t *m, int32_t i, int32_t j)
{
    const unsigned v = bit2(m, SEEN_LO, i, j);
    return v == SEEN_FREE ? (int8_t)QNAV_MAP_FREE_FLOOR : (int8_t)v;
}

uint8_t qnav_cmap_free_bits(const qnav_map_t *m, int32_t b, int32_t j)
{
    return (uint8_t)(plane(m, SEEN_LO, j)[b] & plane(m, SEEN_HI, j)[b]);
}

void qnav_cmap_clear(qnav_map_t *m, int32_t i, int32_t j)
{
    if (bit2(m, SEEN_LO, i, j) == SEEN_OCCUPIED) {
        m->dirty = 1u;
        ways_changed(m);
    }
    set2(m, SEEN_LO, i, j, SEEN_FREE);
}

void qnav_cmap_occupy(qnav_map_t *m, int32_t i, int32_t j)
{
    set2(m, SEEN_LO, i, j, SEEN_OCCUPIED);
    m->dirty = 1u;
    ways_changed(m);
}

void qnav_cmap_arc(qnav_map_t *m, int32_t i, int32_t j)
{
    const unsigned v = bit2(m, SEEN_LO, i, j);
    if (v == SEEN_UNKNOWN || v == SEEN_ONCE) {
        set2(m, SEEN_LO, i, j, v + 1u);
        m->dirty = (uint8_t)(m->dirty | (v == SEEN_ONCE));
        if (v == SEEN_ONCE) {
            ways_changed(m);
        }
    }
}

/* Row sj of plane k with cell i taking cell i + di, into out (unknown, 0, from outside the
 * map): a byte at a time from the two source bytes it straddles. */
static void shifted_row(const qnav_map_t *m, unsigned k, int32_t sj, int32_t di, uint8_t *out)
{
    const int32_t n = (int32_t)m->row_bytes;
    const uint8_t *src;
    int32_t b;
    if (sj < 0 || sj >= (int32_t)m->ny) {
        memset(out, 0, (size_t)n);
        return;
    }
    src = plane(m, k, sj);
    for (b = 0; b < n; ++b) {
        const int32_t first = 8 * b + di; /* the source cell of the byte's first */
        const int32_t q = first >= 0 ? first / 8 : -((7 - first) / 8);
        const unsigned off = (unsigned)(first - 8 * q);
        const unsigned lo = q >= 0 && q < n ? src[q] : 0u;
        const unsigned hi = q + 1 >= 0 && q + 1 < n ? src[q + 1] : 0u;
        out[b] = (uint8_t)((lo >> off) | (hi << (8u - off)));
    }
    if ((m->nx & 7u) != 0u) { /* the last byte's cells past the row stay unknown */
        out[n - 1] = (uint8_t)(out[n - 1] & ((1u << (m->nx & 7u)) - 1u));
    }
}

void qnav_cmap_shift(qnav_map_t *m, int32_t di, int32_t dj)
{
    /* rows in the order that reads each source row before it is written over */
    uint8_t row[QNAV_CMAP_ROW_BYTES_MAX];
    const int32_t ny = (int32_t)m->ny, step = dj > 0 ? 1 : -1;
    int32_t j, l;
    unsigned k;
    for (l = 0, j = dj > 0 ? 0 : ny - 1; l < ny; ++l, j += step) {
        for (k = SEEN_LO; k <= SEEN_HI; ++k) {
            shifted_row(m, k, j + dj, di, row);
            memcpy(plane(m, k, j), row, m->row_bytes);
        }
    }
    ways_changed(m);
}

void qnav_cmap_forget_occupied(qnav_map_t *m)
{
    /* 11 (free) stays; 01 and 10 become 00: each plane takes lo & hi */
    uint8_t *lo = plane(m, SEEN_LO, 0), *hi = plane(m, SEEN_HI, 0);
    const size_t n = (size_t)m->ny * m->row_bytes;
    size_t b;
    for (b = 0; b < n; ++b) {
        lo[b] = hi[b] = (uint8_t)(lo[b] & hi[b]);
    }
    m->dirty = 1u;
    ways_changed(m);
}

int qnav_cmap_blocked(const qnav_map_t *m, int32_t i, int32_t j)
{
    return bit2(m, SEEN_LO, i, j) == SEEN_OCCUPIED;
}

/* The plan's label of step count d: d modulo 3, plus 1. */
static unsigned label_of(uint32_t d)
{
    return (unsigned)(d % 3u) + 1u;
}

void qnav_cmap_plan_start(qnav_map_t *m, uint32_t c)
{
    memset(plane(m, PLAN_LO, 0), 0, (size_t)2u * m->ny * m->row_bytes);
    set2(m, PLAN_LO, (int32_t)(c % m->nx), (int32_t)(c / m->nx), label_of(0u));
    m->goal_cell = (uint16_t)c;
    m->layer = 0u;
    ways_changed(m);
    m->rows_from = m->rows_to = (uint16_t)(c / m->nx);
    m->q_queued = 1u; /* the last step count reached a cell: the plan may grow */
}

/* The growth reads and writes a row a word of cells at a time: elsewhere than on AVR a
 * 64-bit word (little-endian: cell i of a row in bit i % 64 of word i / 64, the planes'
 * own order), so a TekBot's 32-cell row is one word; on AVR a byte, the planes' bytes
 * themselves. The same operations either way, so both grow the same plan (the map bench
 * checks the ATmega128's against the host's). */
#if !defined(__AVR__) && defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
#define QNAV_CMAP_WIDE 1
typedef uint64_t cword_t;
#else
#define QNAV_CMAP_WIDE 0
typedef uint8_t cword_t;
#endif
#define CWORD_BYTES ((uint16_t)sizeof(cword_t))
#define CWORD_TOP (8u * sizeof(cword_t) - 1u) /* a word's last cell's bit */
#define ROW_WORDS_MAX ((QNAV_CMAP_ROW_BYTES_MAX + sizeof(cword_t) - 1u) / sizeof(cword_t))

/* Words of a row of n bytes. */
static inline uint16_t row_words(uint16_t n)
{
    return (uint16_t)((n + CWORD_BYTES - 1u) / CWORD_BYTES);
}

/* Word w of a row of n bytes at p; the bytes past the row read 0. Elsewhere than on AVR
 * in fixed-size loads (a variable memcpy is a call): a word's last bytes short of 8 as a
 * second 4-byte load ending at the row's end, overlapping the first. */
static inline cword_t word_at(const uint8_t *p, uint16_t w, uint16_t n)
{
#if !QNAV_CMAP_WIDE
    (void)n;
    return p[w];
#else
    const uint16_t at = (uint16_t)(w * CWORD_BYTES), len = (uint16_t)(n - at);
    cword_t v = 0u;
    if (len >= CWORD_BYTES) {
        memcpy(&v, p + at, CWORD_BYTES);
    } else if (len >= 4u) {
        uint32_t a, b;
        memcpy(&a, p + at, 4u);
        v = a;
        if (len > 4u) { /* a 32-cell row (both profiles') is one such load */
            memcpy(&b, p + at + len - 4u, 4u);
            v |= (cword_t)b << (8u * (len - 4u));
        }
    } else {
        uint16_t k;
        for (k = 0; k < len; ++k) {
            v |= (cword_t)p[at + k] << (8u * k);
        }
    }
    return v;
#endif
}

/* Word w of a row of n bytes at p |= v (v holds no cell past the row). */
static inline void word_or(uint8_t *p, uint16_t w, uint16_t n, cword_t v)
{
#if !QNAV_CMAP_WIDE
    (void)n;
    p[w] = (uint8_t)(p[w] | v);
#else
    const uint16_t at = (uint16_t)(w * CWORD_BYTES), len = (uint16_t)(n - at);
    v |= word_at(p, w, n);
    if (len >= CWORD_BYTES) {
        memcpy(p + at, &v, CWORD_BYTES);
    } else if (len >= 4u) {
        const uint32_t a = (uint32_t)v, b = (uint32_t)(v >> (8u * (len - 4u)));
        memcpy(p + at, &a, 4u);
        if (len > 4u) {
            memcpy(p + at + len - 4u, &b, 4u);
        }
    } else {
        uint16_t k;
        for (k = 0; k < len; ++k) {
            p[at + k] = (uint8_t)(v >> (8u * k));
        }
    }
#endif
}

/* One row's cells as the growth reads them, a word each, with an empty word at both ends:
 * the cells labelled with the last step count, and the passable ones (not occupied, and
 * on the map). */
typedef struct {
    cword_t last[ROW_WORDS_MAX + 2u];
    cword_t pass[ROW_WORDS_MAX + 2u];
} row_t;

static void load_row(const qnav_map_t *m, int32_t j, unsigned t, row_t *r)
{
    const uint16_t n = m->row_bytes, nw = row_words(n);
    uint16_t w;
    r->last[0] = r->pass[0] = r->last[nw + 1u] = r->pass[nw + 1u] = 0u;
    if (j < 0 || j >= (int32_t)m->ny) {
        memset(r, 0, sizeof *r);
        return;
    }
    {
        const uint8_t *lo = plane(m, PLAN_LO, j), *hi = plane(m, PLAN_HI, j);
        const uint8_t *sl = plane(m, SEEN_LO, j), *sh = plane(m, SEEN_HI, j);
        const cword_t flip_lo = (t & 1u) ? 0u : (cword_t)~(cword_t)0u;
        const cword_t flip_hi = (t & 2u) ? 0u : (cword_t)~(cword_t)0u;
        for (w = 0; w < nw; ++w) {
            r->last[w + 1u] = (cword_t)((word_at(lo, w, n) ^ flip_lo) & (word_at(hi, w, n) ^ flip_hi));
            r->pass[w + 1u] = (cword_t)(word_at(sl, w, n) | (cword_t)~word_at(sh, w, n));
        }
    }
    if ((m->nx & CWORD_TOP) != 0u) { /* no cell beyond the row */
        const cword_t all = (cword_t)~(cword_t)0u;
        r->pass[nw] &= (cword_t)~(cword_t)(all << (m->nx & CWORD_TOP));
    }
}

/* Word w of a row_t array seen one cell over: cell i takes cell i - 1's bit (WEST) or
 * i + 1's (EAST). */
#define WEST(v, w) ((cword_t)((cword_t)((v)[w] << 1) | ((v)[(w) - 1u] >> CWORD_TOP)))
#define EAST(v, w) ((cword_t)(((v)[w] >> 1) | (cword_t)((v)[(w) + 1u] << CWORD_TOP)))

/* Row j's new cells, those a step from the last count's cells in the rows up, here and
 * down, labelled next; a row with any becomes the last count's last (and, the first
 * such, its first), and *any is set. */
static inline void grow_row(qnav_map_t *m, int32_t j, const row_t *up, const row_t *here,
                            const row_t *down, unsigned next, uint8_t *any)
{
    uint8_t *lo = plane(m, PLAN_LO, j), *hi = plane(m, PLAN_HI, j);
    const cword_t *ul = up->last, *up_ = up->pass, *hl = here->last, *hp = here->pass;
    const cword_t *dl = down->last, *dp = down->pass;
    const uint16_t n = m->row_bytes, nw = row_words(n);
    uint16_t w;
    for (w = 1; w <= nw; ++w) {
        const cword_t pw = WEST(hp, w), pe = EAST(hp, w);
        const uint16_t at = (uint16_t)(w - 1u); /* the plane's word */
        cword_t r = (cword_t)(WEST(hl, w) | EAST(hl, w) | ul[w] | dl[w]);
        cword_t add;
        r |= (cword_t)(((WEST(ul, w) & pw) | (EAST(ul, w) & pe)) & up_[w]);
        r |= (cword_t)(((WEST(dl, w) & pw) | (EAST(dl, w) & pe)) & dp[w]);
        add = (cword_t)(r & hp[w] & (cword_t)~(word_at(lo, at, n) | word_at(hi, at, n)));
        if (add != 0u) {
            if (next & 1u) {
                word_or(lo, at, n, add);
            }
            if (next & 2u) {
                word_or(hi, at, n, add);
            }
            if (!*any) {
                m->rows_from = (uint16_t)j;
            }
            m->rows_to = (uint16_t)j;
            *any = 1u;
        }
    }
}

#if QNAV_CMAP_WIDE
typedef struct rows rows_t;

/* A row of n bytes, 4 <= n <= 8, at p as one word (word_at's, without its cases): two
 * 4-byte loads, the second ending at the row's end; and its store. */
static inline cword_t one_word_at(const uint8_t *p, uint16_t n)
{
    uint32_t a, b;
    memcpy(&a, p, 4u);
    memcpy(&b, p + n - 4u, 4u);
    return (cword_t)a | (cword_t)b << (8u * (n - 4u));
}

static inline void one_word_set(uint8_t *p, uint16_t n, cword_t v)
{
    const uint32_t a = (uint32_t)v, b = (uint32_t)(v >> (8u * (n - 4u)));
    memcpy(p, &a, 4u);
    memcpy(p + n - 4u, &b, 4u);
}

/* Maps of rows of 4 to 8 bytes (25 to 64 cells: both profiles' maps) and at most this many
 * rows grow from struct rows; others from the planes' bytes (load_row). */
#define WORD_ROWS_MAX 128u

/* The plan's rows, a word each, while qnav_cmap_settle() grows it: read from the planes
 * once, not once a step count, and written through to them, so the planes stay the plan.
 * Nothing but the growth changes the planes during a settle, so which cells are passable
 * (pass) holds throughout. Row j at j + 1, between two empty rows (no cell labelled, none
 * passable), so the rows beyond the map need no test. */
struct rows {
    cword_t lo[WORD_ROWS_MAX + 2u], hi[WORD_ROWS_MAX + 2u]; /* the plan's two planes */
    cword_t pass[WORD_ROWS_MAX + 2u];                       /* not occupied, and on the map */
};

/* rows with every row of the map, or NULL when the map's rows are not one word each. */
static rows_t *load_rows(const qnav_map_t *m, rows_t *rows)
{
    const uint16_t n = m->row_bytes;
    const size_t stride = (size_t)m->ny * n;
    const cword_t all = (cword_t)~(cword_t)0u;
    const cword_t on_map = (m->nx & CWORD_TOP) != 0u ? (cword_t)~(all << (m->nx & CWORD_TOP)) : all;
    const uint8_t *p = m->planes;
    uint16_t j;
    if (n < 4u || n > CWORD_BYTES || m->ny > WORD_ROWS_MAX) {
        return NULL;
    }
    rows->lo[0] = rows->hi[0] = rows->pass[0] = 0u;
    for (j = 1; j <= m->ny; ++j, p += n) {
        rows->lo[j] = one_word_at(p + PLAN_LO * stride, n);
        rows->hi[j] = one_word_at(p + PLAN_HI * stride, n);
        rows->pass[j] = (cword_t)((one_word_at(p + SEEN_LO * stride, n) | (cword_t)~one_word_at(p + SEEN_HI * stride, n)) &
                                  on_map);
    }
    rows->lo[j] = rows->hi[j] = rows->pass[j] = 0u;
    return rows;
}

/* Row j of rows as the growth reads it, -1 <= j <= ny: its cells labelled t (flips as
 * load_row's; a label is never 0, so an empty row has none), and its passable ones. */
static inline void row_word(const rows_t *rows, int32_t j, cword_t flip_lo, cword_t flip_hi,
                            cword_t *last, cword_t *pass)
{
    *last = (cword_t)((rows->lo[j + 1] ^ flip_lo) & (rows->hi[j + 1] ^ flip_hi));
    *pass = rows->pass[j + 1];
}

/* grow()'s rows first..last from rows (load_rows()), a row one word, the rows up, here
 * and down in registers: grow_row's rule without the rows' arrays; 1 when any cell took
 * the next count. */
static uint8_t grow_rows_one_word(qnav_map_t *m, rows_t *rows, int32_t first, int32_t last,
                                  unsigned t, unsigned next)
{
    const uint16_t n = m->row_bytes;
    const size_t stride = (size_t)m->ny * n;
    uint8_t *const planes = m->planes;
    const cword_t all = (cword_t)~(cword_t)0u;
    const cword_t flip_lo = (t & 1u) ? 0u : all, flip_hi = (t & 2u) ? 0u : all;
    cword_t ul, up, hl, hp, dl, dp;
    uint8_t any = 0u;
    int32_t j;
    row_word(rows, first - 1, flip_lo, flip_hi, &ul, &up);
    row_word(rows, first, flip_lo, flip_hi, &hl, &hp);
    for (j = first; j <= last; ++j) {
        const cword_t pw = (cword_t)(hp << 1), pe = hp >> 1;
        const cword_t lw = rows->lo[j + 1], hw = rows->hi[j + 1];
        cword_t r, add;
        row_word(rows, j + 1, flip_lo, flip_hi, &dl, &dp);
        r = (cword_t)((cword_t)(hl << 1) | (hl >> 1) | ul | dl);
        r |= (cword_t)((((cword_t)(ul << 1) & pw) | ((ul >> 1) & pe)) & up);
        r |= (cword_t)((((cword_t)(dl << 1) & pw) | ((dl >> 1) & pe)) & dp);
        add = (cword_t)(r & hp & (cword_t)~(lw | hw));
        if (add != 0u) {
            uint8_t *lo = planes + PLAN_LO * stride + (size_t)j * n;
            if (next & 1u) {
                rows->lo[j + 1] = lw | add;
                one_word_set(lo, n, lw | add);
            }
            if (next & 2u) {
                rows->hi[j + 1] = hw | add;
                one_word_set(lo + stride, n, hw | add);
            }
            if (!any) {
                m->rows_from = (uint16_t)j;
            }
            m->rows_to = (uint16_t)j;
            any = 1u;
        }
        ul = hl;
        up = hp;
        hl = dl;
        hp = dp;
    }
    return any;
}
#endif

#if QNAV_CMAP_FREE_ROWS
uint64_t qnav_cmap_free_row(const qnav_map_t *m, int32_t j)
{
    const uint16_t n = m->row_bytes;
    return one_word_at(plane(m, SEEN_LO, j), n) & one_word_at(plane(m, SEEN_HI, j), n);
}
#endif

/* On hosts the growth also takes the plan's rows as words (struct rows, or NULL); on AVR
 * it reads the planes' bytes and takes nothing more, as before. */
#if QNAV_CMAP_WIDE
#define WORDS_PARAM , rows_t *words
#define WORDS_ARG(w) , (w)
#else
#define WORDS_PARAM
#define WORDS_ARG(w)
#endif

/* One more step count: every passable cell not yet reached a step from the last count's
 * cells takes the next count (8 neighbours; a diagonal only past the two cells beside it,
 * both passable). 0 when none did (the plan is whole). Rows are read a row ahead, so a
 * row's new cells (label next, not t) do not change what the rows after it see. Only the
 * rows next to the last count's rows (m->rows_from..rows_to) can take new cells. */
static int grow(qnav_map_t *m WORDS_PARAM)
{
    row_t rows[3];
    row_t *up = &rows[0], *here = &rows[1], *down = &rows[2];
    const unsigned t = label_of(m->layer), next = label_of(m->layer + 1u);
    const int32_t first = m->rows_from > 0u ? (int32_t)m->rows_from - 1 : 0;
    const int32_t last = (int32_t)m->rows_to + 1 < (int32_t)m->ny ? (int32_t)m->rows_to + 1
                                                                   : (int32_t)m->ny - 1;
    uint8_t any = 0u;
    int32_t j;
    if (!m->q_queued) {
        return 0;
    }
#if QNAV_CMAP_WIDE
    if (words != NULL) {
        any = grow_rows_one_word(m, words, first, last, t, next);
    } else
#endif
    {
        load_row(m, first - 1, t, up);
        load_row(m, first, t, here);
        for (j = first; j <= last; ++j) {
            row_t *spare = up;
            load_row(m, j + 1, t, down);
            grow_row(m, j, up, here, down, next, &any);
            up = here;
            here = down;
            down = spare;
        }
    }
    m->layer++;
    m->q_queued = any;
    ways_changed(m);
    return any;
}

static unsigned plan_label(const qnav_map_t *m, int32_t i, int32_t j)
{
    return bit2(m, PLAN_LO, i, j);
}

/* A cell of the 5 x 5 about (ri, rj) is settled. */
static int window_settled(const qnav_map_t *m, int32_t ri, int32_t rj)
{
    int32_t a, b;
    for (b = -2; b <= 2; ++b) {
        for (a = -2; a <= 2; ++a) {
            if (qnav_map_in(m, ri + a, rj + b) && plan_label(m, ri + a, rj + b) != 0u) {
                return 1;
            }
        }
    }
    return 0;
}

int qnav_cmap_needs_growth(const qnav_map_t *m, int32_t ri, int32_t rj)
{
    return m->q_queued && (ri < 0 || plan_label(m, ri, rj) == 0u);
}

/* grow(), while *budget lasts (0: none left; a budget of 0 from the start: no bound). */
static int grow_within(qnav_map_t *m WORDS_PARAM, uint16_t *budget, int bounded)
{
    if (bounded) {
        if (*budget == 0u) {
            return 0;
        }
        --*budget;
    }
    return grow(m WORDS_ARG(words));
}

void qnav_cmap_settle(qnav_map_t *m, int32_t ri, int32_t rj)
{
    uint16_t budget = m->cfg.grow_steps;
    const int bounded = ri >= 0 && budget != 0u;
    int k;
#if QNAV_CMAP_WIDE
    rows_t buf, *rows = NULL;
    if (ri < 0 || plan_label(m, ri, rj) == 0u) {
        rows = m->q_queued ? load_rows(m, &buf) : NULL; /* no growth: nothing to read */
    }
#endif
    if (ri < 0) {
        while (grow(m WORDS_ARG(rows))) {
        }
        return;
    }
    if (plan_label(m, ri, rj) != 0u) {
        return;
    }
    if (!qnav_cmap_blocked(m, ri, rj)) {
        while (plan_label(m, ri, rj) == 0u && grow_within(m WORDS_ARG(rows), &budget, bounded)) {
        }
        return;
    }
    /* the robot stands on a blocked cell: settle the window's nearest cells, and two
     * step counts more (a cell two further is never chosen: qnav_cmap_cost_near) in the
     * tick that reaches the window */
    if (window_settled(m, ri, rj)) {
        return;
    }
    while (!window_settled(m, ri, rj) && grow_within(m WORDS_ARG(rows), &budget, bounded)) {
    }
    for (k = 0; k < 2 && grow_within(m WORDS_ARG(rows), &budget, bounded); ++k) {
    }
}

/* Cell i's 2-bit value in the row whose two planes' bytes are lo and hi. */
static inline unsigned bits_in(const uint8_t *lo, const uint8_t *hi, int32_t i)
{
    const unsigned b = (unsigned)i >> 3;
    const uint8_t bit = bit_of[(unsigned)i & 7u];
    return ((lo[b] & bit) != 0u ? 1u : 0u) | ((hi[b] & bit) != 0u ? 2u : 0u);
}

/* The walk by words (descend_words) on hosts only: the Cortex-M4 keeps the byte walk its
 * map bench measured. */
#if QNAV_CMAP_WIDE && !(defined(__ARM_ARCH_PROFILE) && __ARM_ARCH_PROFILE == 'M')
#define DESCEND_WORDS 1
#else
#define DESCEND_WORDS 0
#endif

#if DESCEND_WORDS
/* qnav_cmap_descend() for rows of 4 to 8 bytes (both profiles' maps), on hosts: the three
 * rows' cells a step nearer as words, so only those cells are looked at, in the same order
 * (row by row, then along the row) and with the same tests. */
static inline int descend_words(const qnav_map_t *m, int32_t *i, int32_t *j)
{
    const int32_t gi = (int32_t)(m->goal_cell % m->nx), gj = (int32_t)(m->goal_cell / m->nx);
    const uint16_t n = m->row_bytes;
    const unsigned here = plan_label(m, *i, *j);
    const unsigned want = here == 1u ? 3u : here - 1u;
    const cword_t flip_lo = (want & 1u) ? 0u : ~(cword_t)0u, flip_hi = (want & 2u) ? 0u : ~(cword_t)0u;
    /* the window's three cells *i - 1 .. *i + 1 of a row, within the row (bits past the
     * row's end are 0 in a word, and no label there is wanted: want is 1 to 3) */
    const cword_t window = *i > 0 ? (cword_t)7u << (*i - 1) : (cword_t)3u;
    int32_t best = INT32_MAX;
    int32_t b, ni = *i, nj = *j;
    const uint8_t *seen_lo = plane(m, SEEN_LO, *j), *seen_hi = plane(m, SEEN_HI, *j);
    if (here == 0u || qnav_map_at(m, *i, *j) == m->goal_cell) {
        return 0;
    }
    for (b = -1; b <= 1; ++b) {
        const int32_t tj = *j + b;
        cword_t near;
        if (tj < 0 || tj >= (int32_t)m->ny) {
            continue;
        }
        near = (one_word_at(plane(m, PLAN_LO, tj), n) ^ flip_lo) &
               (one_word_at(plane(m, PLAN_HI, tj), n) ^ flip_hi) & window;
        if (b == 0) {
            near &= ~((cword_t)1u << *i);
        }
        while (near != 0u) {
            const int32_t ti = (int32_t)__builtin_ctzll((unsigned long long)near);
            const int32_t a = ti - *i;
            int32_t d2;
            near &= near - 1u;
            if (ti >= (int32_t)m->nx) {
                continue;
            }
            if (a != 0 && b != 0 &&
                (bits_in(seen_lo, seen_hi, ti) == SEEN_OCCUPIED ||
                 bits_in(plane(m, SEEN_LO, tj), plane(m, SEEN_HI, tj), *i) == SEEN_OCCUPIED)) {
                continue; /* no corner cutting, as the plan grew */
            }
            d2 = (gi - ti) * (gi - ti) + (gj - tj) * (gj - tj);
            if (d2 < best) {
                best = d2;
                ni = ti;
                nj = tj;
            }
        }
    }
    if (best == INT32_MAX) {
        return 0;
    }
    *i = ni;
    *j = nj;
    return 1;
}
#endif

int qnav_cmap_descend(const qnav_map_t *m, int32_t *i, int32_t *j)
{
#if DESCEND_WORDS
    if (m->row_bytes >= 4u && m->row_bytes <= CWORD_BYTES) {
        return descend_words(m, i, j);
    }
#endif
    { /* the plain way, a cell at a time */
        const int32_t gi = (int32_t)(m->goal_cell % m->nx), gj = (int32_t)(m->goal_cell / m->nx);
        const unsigned here = plan_label(m, *i, *j);
        const unsigned want = here == 1u ? 3u : here - 1u;
        int32_t best = INT32_MAX; /* squared cells: at most 2 x 192^2 */
        int32_t a, b, ni = *i, nj = *j;
        const uint8_t *seen_lo = plane(m, SEEN_LO, *j), *seen_hi = plane(m, SEEN_HI, *j);
        if (here == 0u || qnav_map_at(m, *i, *j) == m->goal_cell) {
            return 0;
        }
        /* a row's plane pointers once (not a cell's each time): the walk of every tick's way */
        for (b = -1; b <= 1; ++b) {
            const int32_t tj = *j + b;
            const uint8_t *lo, *hi;
            if (tj < 0 || tj >= (int32_t)m->ny) {
                continue;
            }
            lo = plane(m, PLAN_LO, tj);
            hi = plane(m, PLAN_HI, tj);
            for (a = -1; a <= 1; ++a) {
                const int32_t ti = *i + a;
                int32_t d2;
                if ((a == 0 && b == 0) || ti < 0 || ti >= (int32_t)m->nx || bits_in(lo, hi, ti) != want) {
                    continue;
                }
                if (a != 0 && b != 0 &&
                    (bits_in(seen_lo, seen_hi, ti) == SEEN_OCCUPIED ||
                     bits_in(plane(m, SEEN_LO, tj), plane(m, SEEN_HI, tj), *i) == SEEN_OCCUPIED)) {
                    continue; /* no corner cutting, as the plan grew */
                }
                /* of the cells a step nearer, the one nearest the destination: a straight way */
                d2 = (gi - ti) * (gi - ti) + (gj - tj) * (gj - tj);
                if (d2 < best) {
                    best = d2;
                    ni = ti;
                    nj = tj;
                }
            }
        }
        if (best == INT32_MAX) {
            return 0;
        }
        *i = ni;
        *j = nj;
        return 1;
    }
}

/* The plan's cost from settled cell (i, j): its way to the destination, 10 a side and 14 a
 * diagonal. A way cut by a cell that became occupied since the plan (the next plan mends
 * it) counts the rest as the straight octile distance. */
#if DESCEND_WORDS
/* A way's step on hosts: the walk by words inlined into the walk of the way (up to the
 * plan's step count of them), so that what does not change between steps (the
 * destination's cell, the rows' size) is worked out once a way, not once a step. */
#define WAY_STEP(m, i, j)                                                                    \
    ((m)->row_bytes >= 4u && (m)->row_bytes <= CWORD_BYTES ? descend_words(m, i, j)         \
                                                           : qnav_cmap_descend(m, i, j))
#else
#define WAY_STEP(m, i, j) qnav_cmap_descend(m, i, j)
#endif

static uint32_t way_cost(const qnav_map_t *m, int32_t i, int32_t j)
{
    const int32_t gi = (int32_t)(m->goal_cell % m->nx), gj = (int32_t)(m->goal_cell / m->nx);
    uint32_t cost = 0u, di, dj, steps;
    /* a way is at most the plan's step count long; a corner that opened since the plan
     * can show a cell two steps further as one nearer, so the walk is bounded */
    for (steps = 0u; steps <= m->layer; ++steps) {
        const int32_t pi = i, pj = j;
        if (!WAY_STEP(m, &i, &j)) {
            break;
        }
        cost += (pi != i && pj != j) ? STEP_DIAG : STEP_SIDE;
    }
    di = (uint32_t)(gi > i ? gi - i : i - gi);
    dj = (uint32_t)(gj > j ? gj - j : j - gj);
    cost += di > dj ? STEP_DIAG * dj + STEP_SIDE * (di - dj) : STEP_DIAG * di + STEP_SIDE * (dj - di);
    return cost >= QNAV_MAP_UNREACHED ? QNAV_MAP_UNREACHED - 1u : cost;
}

uint32_t qnav_cmap_cost(const qnav_map_t *m, int32_t i, int32_t j)
{
    return plan_label(m, i, j) != 0u ? way_cost(m, i, j) : QNAV_MAP_UNREACHED;
}

/* Steps from cell (i, j) to the destination's on an empty map (8 neighbours). */
static uint32_t chebyshev(const qnav_map_t *m, int32_t i, int32_t j)
{
    const int32_t di = (int32_t)(m->goal_cell % m->nx) - i, dj = (int32_t)(m->goal_cell / m->nx) - j;
    const uint32_t ai = (uint32_t)(di < 0 ? -di : di), aj = (uint32_t)(dj < 0 ? -dj : dj);
    return ai > aj ? ai : aj;
}

static uint32_t cost_near_walked(const qnav_map_t *m, int32_t i, int32_t j, int32_t *bi,
                                 int32_t *bj)
{
    uint32_t best = QNAV_MAP_UNREACHED, visited = 0u;
    int32_t a, b;
    *bi = i;
    *bj = j;
    if (plan_label(m, i, j) != 0u) {
        return way_cost(m, i, j);
    }
    if (m->q_queued && !qnav_cmap_blocked(m, i, j)) {
        return QNAV_MAP_UNREACHED; /* the plan has not grown as far as the cell yet */
    }
    /* to a cell: 10 a side, as the full layout; its way from there is at least 10 a step
     * of its Chebyshev distance to the destination, so a cell whose bound is no better
     * than the best found is not walked (each walk is up to the plan's length) */
    for (;;) {
        uint32_t lower = QNAV_MAP_UNREACHED, c;
        int32_t ni = 0, nj = 0;
        for (b = -2; b <= 2; ++b) {
            for (a = -2; a <= 2; ++a) {
                if (!qnav_map_in(m, i + a, j + b) || plan_label(m, i + a, j + b) == 0u ||
                    (visited & ((uint32_t)1u << (unsigned)((b + 2) * 5 + a + 2))) != 0u) {
                    continue;
                }
                c = ((uint32_t)((a < 0 ? -a : a) + (b < 0 ? -b : b)) + chebyshev(m, i + a, j + b)) *
                    STEP_SIDE;
                if (c < lower) {
                    lower = c;
                    ni = a;
                    nj = b;
                }
            }
        }
        if (lower >= best) {
            return best;
        }
        visited |= (uint32_t)1u << (unsigned)((nj + 2) * 5 + ni + 2);
        c = way_cost(m, i + ni, j + nj) +
            (uint32_t)((ni < 0 ? -ni : ni) + (nj < 0 ? -nj : nj)) * STEP_SIDE;
        if (c < best) {
            best = c;
            *bi = i + ni;
            *bj = j + nj;
        }
    }
}

/* The guide asks every tick from the robot's cell, and the walk is the plan's way: kept
 * until something it depends on changes (ways_changed), so a robot that stays in its cell
 * between plans walks it once (a TekBot crosses a 0.35 m cell in about 7 ticks). */
uint32_t qnav_cmap_cost_near(qnav_map_t *m, int32_t i, int32_t j, int32_t *bi, int32_t *bj)
{
    const uint16_t c = (uint16_t)qnav_map_at(m, i, j);
    uint32_t cost;
    if (m->way_from == c) {
        *bi = m->way_i;
        *bj = m->way_j;
        return m->way_cost;
    }
    cost = cost_near_walked(m, i, j, bi, bj);
    m->way_from = c;
    m->way_cost = (uint16_t)cost;
    m->way_i = (uint8_t)*bi;
    m->way_j = (uint8_t)*bj;
    return cost;
}
