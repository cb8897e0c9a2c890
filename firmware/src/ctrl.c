/*
 * The path-quality controller: quantizes a scan into per-path distance levels
 * (clearance.c), gives each of the 360 paths a rank key through its policy kind's
 * evaluation (policy_<kind>.c) or a compiled table, picks the best path and maps its
 * quality to a speed under the speed guard. The kind is dispatched by exhaustive switches
 * here and nowhere else; a kind left out of the build (QNAV_WITH_<KIND> 0) keeps its case
 * with an empty body under #if, never reached: qnav_policy_validate() refuses the kind, so
 * no controller holds it. Integer arithmetic only; every format and bound is in
 * docs/qformats.md.
 */
#include "qnav/ctrl.h"
#include "clearance.h"
#include "escape.h"
#include "policy_eval.h"
#include "qnav/flash.h"
#include "sigmoid_lut.h"

void qnav_ctrl_config_default(qnav_ctrl_config_t *cfg)
{
    if (cfg == 0) {
        return;
    }
    cfg->n_sectors = 16u;
    cfg->max_range_mm = 5000u;
    cfg->full_speed_quality = 29491; /* 0.9 in Q1.15 */
    cfg->body_radius_mm = 120u;
    cfg->safety_mm = 50u;
    cfg->pass_mm = 50u;
    cfg->sensor_offset_mm = 120u;
    cfg->v_max_mm_s = 500u;
    cfg->decel_mm_s2 = 2000u;
    cfg->rank = (uint8_t)QNAV_RANK_PREACT;
    cfg->wedge_pct = 100u;
    cfg->wedge_near_mm = 0u;
    cfg->escape_stall_ticks = 20u;
    cfg->escape_follow_mm = 500u;
    cfg->escape_follow_s = 20u;
    cfg->keep_pct = 0u;
    cfg->range_min_mm = 0u;
    cfg->quality_full_speed = 0;
}

void qnav_ctrl_config_literal(qnav_ctrl_config_t *cfg)
{
    if (cfg == 0) {
        return;
    }
    cfg->body_radius_mm = 0u;
    cfg->safety_mm = 0u;
    cfg->pass_mm = 0u;
    cfg->decel_mm_s2 = 0u;
    cfg->rank = (uint8_t)QNAV_RANK_QUALITY;
    cfg->wedge_pct = 100u;
    cfg->keep_pct = 0u;
}

/* The speed law for the controller's rank: full speed from cfg->quality_full_speed when
 * keys rank by quality and it is set, else from full_speed_quality. Called again once a
 * policy or a table has fixed the rank. */
static void full_speed_at(qnav_ctrl_t *ctrl, const qnav_ctrl_config_t *cfg)
{
    const qnav_q1_15_t q = ctrl->rank == (uint8_t)QNAV_RANK_QUALITY && cfg->quality_full_speed > 0
                               ? cfg->quality_full_speed
                               : cfg->full_speed_quality;
    const uint32_t q_full = (uint32_t)q;
    ctrl->full_speed_quality = q;
    ctrl->speed_scale = ((uint32_t)32768u * 32768u + q_full / 2u) / q_full;
}

static qnav_status_t init_common(qnav_ctrl_t *ctrl, const qnav_ctrl_config_t *cfg)
{
    qnav_status_t st;
    if (ctrl == 0) {
        return QNAV_E_NULL;
    }
    ctrl->magic = 0u;
    if (cfg == 0) {
        return QNAV_E_NULL;
    }
    st = qnav_clearance_setup(&ctrl->clr, cfg);
    if (st == QNAV_OK) {
        st = qnav_escape_setup(&ctrl->clr, cfg);
    }
    if (st != QNAV_OK) {
        return st;
    }
    if (cfg->full_speed_quality <= 0 || cfg->quality_full_speed < 0) {
        return QNAV_E_SPEED;
    }
    if (cfg->rank != (uint8_t)QNAV_RANK_QUALITY && cfg->rank != (uint8_t)QNAV_RANK_PREACT) {
        return QNAV_E_RANK;
    }
    if (cfg->keep_pct > 100u) {
        return QNAV_E_KEEP;
    }
    ctrl->rank = cfg->rank;
    full_speed_at(ctrl, cfg);
    ctrl->kind = QNAV_CTRL_KIND_TABLE; /* until a policy's init sets its kind */
    ctrl->p.net.table = 0;
    ctrl->hidden = 0u;
    ctrl->inputs = 0u;
    ctrl->p.net.out_bias_z = 0;
    ctrl->keep_pct = cfg->keep_pct;
    ctrl->shapes_carried = 0u;
    return QNAV_OK;
}

/* The policy's status as the controller's. */
static qnav_status_t policy_status(qnav_policy_status_t st)
{
    switch (st) {
    case QNAV_POLICY_OK:
        return QNAV_OK;
    case QNAV_POLICY_E_NULL:
        return QNAV_E_NULL;
    case QNAV_POLICY_E_KIND:
        return QNAV_E_POLICY_KIND;
    case QNAV_POLICY_E_HIDDEN:
        return QNAV_E_HIDDEN;
    case QNAV_POLICY_E_INPUTS:
        return QNAV_E_INPUTS;
    case QNAV_POLICY_E_PROB_PARAM:
        return QNAV_E_PROB_PARAM;
    case QNAV_POLICY_E_KIND_DISABLED:
        return QNAV_E_KIND_DISABLED;
    }
    return QNAV_E_POLICY_KIND;
}

qnav_status_t qnav_ctrl_init(qnav_ctrl_t *ctrl, const qnav_ctrl_config_t *cfg,
                             const qnav_policy_t *policy)
{
    return qnav_ctrl_init_carried(ctrl, cfg, policy, 0, 0u);
}

/* qnav_ctrl_init_carried's body; with_shapes 0 leaves a 2-input network's row shapes
 * unmade (qnav_ctrl_init_compiled makes them from the table). */
static qnav_status_t init_policy(qnav_ctrl_t *ctrl, const qnav_ctrl_config_t *cfg,
                                 const qnav_policy_t *policy, const uint8_t *shapes,
                                 uint16_t len, uint8_t with_shapes)
{
    qnav_status_t st = init_common(ctrl, cfg);
    if (st != QNAV_OK) {
        return st;
    }
    st = policy_status(qnav_policy_validate(policy));
    if (st != QNAV_OK) {
        return st;
    }
    switch ((qnav_policy_kind_t)policy->kind) {
    case QNAV_POLICY_PROB:
#if QNAV_WITH_PROB
        ctrl->rank = (uint8_t)QNAV_RANK_QUALITY; /* a product of probabilities: no saturation */
        full_speed_at(ctrl, cfg);
        qnav_prob_eval_init(ctrl, &policy->u.prob);
#endif
        break;
    case QNAV_POLICY_NET:
#if QNAV_WITH_NETWORK
        qnav_net_eval_init(ctrl, &policy->u.net);
        if (policy->u.net.inputs == QNAV_NET_INPUTS_PAPER && with_shapes) {
            ctrl->shapes_carried = qnav_shapes_take(ctrl, &policy->u.net, shapes, len);
            if (!ctrl->shapes_carried) {
                qnav_net_eval_shapes(ctrl);
            }
        }
#endif
        break;
    }
    (void)shapes;
    (void)len;
    (void)with_shapes;
    ctrl->kind = policy->kind;
    ctrl->magic = QNAV_CTRL_MAGIC;
    return QNAV_OK;
}

qnav_status_t qnav_ctrl_init_carried(qnav_ctrl_t *ctrl, const qnav_ctrl_config_t *cfg,
                                     const qnav_policy_t *policy, const uint8_t *shapes,
                                     uint16_t len)
{
    return init_policy(ctrl, cfg, policy, shapes, len, 1u);
}

uint8_t qnav_ctrl_shapes_carried(const qnav_ctrl_t *ctrl)
{
    return (uint8_t)(ctrl != 0 && ctrl->magic == QNAV_CTRL_MAGIC && ctrl->shapes_carried);
}

/* The shape of every row of the table (init time: one read per entry). */
static void table_shapes(qnav_ctrl_t *ctrl)
{
    uint16_t level;
    uint16_t d;
    for (level = 0; level < QNAV_DIST_LEVELS; ++level) {
        const qnav_qkey_t *row = &ctrl->p.net.table[level * QNAV_TABLE_STRIDE];
        qnav_row_scan_t sc;
        qnav_row_shape_start(&sc, &ctrl->p.net.in.row[level], QNAV_FLASH_READ_I16(&row[0]));
        for (d = 1; d <= QNAV_DTHETA_MAX; ++d) {
            qnav_row_shape_next(&sc, (uint8_t)d, QNAV_FLASH_READ_I16(&row[d]));
        }
    }
}

qnav_status_t qnav_ctrl_init_table(qnav_ctrl_t *ctrl, const qnav_ctrl_config_t *cfg,
                                   const qnav_qkey_t *table, qnav_rank_t rank)
{
    qnav_status_t st = init_common(ctrl, cfg);
    if (st != QNAV_OK) {
        return st;
    }
    if (table == 0) {
        return QNAV_E_NULL;
    }
    if (rank != QNAV_RANK_QUALITY && rank != QNAV_RANK_PREACT) {
        return QNAV_E_RANK;
    }
    if (!QNAV_WITH_TABLE) {
        return QNAV_E_KIND_DISABLED;
    }
    ctrl->p.net.table = table;
    ctrl->rank = (uint8_t)rank;
    full_speed_at(ctrl, cfg);
    table_shapes(ctrl);
    ctrl->kind = QNAV_CTRL_KIND_TABLE;
    ctrl->magic = QNAV_CTRL_MAGIC;
    return QNAV_OK;
}

qnav_status_t qnav_ctrl_init_compiled(qnav_ctrl_t *ctrl, const qnav_ctrl_config_t *cfg,
                                      const qnav_policy_t *policy, qnav_qkey_t *table)
{
    qnav_status_t st;
    if (ctrl != 0) {
        ctrl->magic = 0u;
    }
    if (table == 0) {
        return QNAV_E_NULL;
    }
    st = init_policy(ctrl, cfg, policy, 0, 0u, 0u);
    if (st == QNAV_OK) {
        st = qnav_ctrl_build_table(ctrl, table);
    }
    if (st == QNAV_OK) {
        st = qnav_ctrl_init_table(ctrl, cfg, table, qnav_ctrl_rank(ctrl));
    }
    if (st != QNAV_OK && ctrl != 0) {
        ctrl->magic = 0u; /* never a network without its row shapes */
    }
    return st;
}

#if QNAV_WITH_PREACT_KEYS
/* A function of its own (gcc inlines a static one into the four callers of key_quality:
 * 1 KB more AVR flash). */
qnav_q1_15_t qnav_preact_key_quality(qnav_qkey_t key)
{
    int32_t z = key;
    if (z >= QNAV_KEY_KNEE) {
        z = QNAV_KEY_KNEE + (z - QNAV_KEY_KNEE) * 16;
    } else if (z < -QNAV_KEY_KNEE) {
        z = -QNAV_KEY_KNEE + (z + QNAV_KEY_KNEE) * 16;
    }
    return qnav_sigmoid_q5_11(qnav_sat16(z));
}
#endif

/* A key back to the quality under the controller's rank. Only networks and their tables
 * rank by pre-activation: a build with neither has no sigmoid table to read. */
static qnav_q1_15_t key_quality(const qnav_ctrl_t *ctrl, qnav_qkey_t key)
{
#if QNAV_WITH_PREACT_KEYS
    if (ctrl->rank == (uint8_t)QNAV_RANK_PREACT) {
        return qnav_preact_key_quality(key);
    }
#else
    (void)ctrl;
#endif
    return (qnav_q1_15_t)(key < 0 ? 0 : key);
}

static qnav_qkey_t key_at(const qnav_ctrl_t *ctrl, uint8_t level, uint8_t dtheta)
{
    const qnav_qkey_t *table = qnav_table_of(ctrl);
    if (table != 0) {
        return QNAV_FLASH_READ_I16(&table[(uint16_t)level * QNAV_TABLE_STRIDE + dtheta]);
    }
    switch ((qnav_policy_kind_t)ctrl->kind) {
    case QNAV_POLICY_PROB:
#if QNAV_WITH_PROB
        return qnav_prob_eval_key(ctrl, level, dtheta);
#endif
        break;
    case QNAV_POLICY_NET:
#if QNAV_WITH_NETWORK
        return qnav_net_eval_key(ctrl, level, dtheta);
#endif
        break;
    }
    return QNAV_KEY_NONE + 1;
}

qnav_qkey_t qnav_ctrl_key(const qnav_ctrl_t *ctrl, uint8_t level, uint8_t dtheta_deg)
{
    if (ctrl == 0 || ctrl->magic != QNAV_CTRL_MAGIC) {
        return -32767;
    }
    if (level >= QNAV_DIST_LEVELS) {
        level = QNAV_DIST_LEVELS - 1u;
    }
    if (dtheta_deg > QNAV_DTHETA_MAX) {
        dtheta_deg = QNAV_DTHETA_MAX;
    }
    return key_at(ctrl, level, dtheta_deg);
}

qnav_q1_15_t qnav_ctrl_key_quality(const qnav_ctrl_t *ctrl, qnav_qkey_t key)
{
    if (ctrl == 0 || ctrl->magic != QNAV_CTRL_MAGIC) {
        return 0;
    }
    return key_quality(ctrl, key);
}

qnav_q1_15_t qnav_ctrl_quality(const qnav_ctrl_t *ctrl, uint8_t level, uint8_t dtheta_deg)
{
    if (ctrl == 0 || ctrl->magic != QNAV_CTRL_MAGIC) {
        return 0;
    }
    return key_quality(ctrl, qnav_ctrl_key(ctrl, level, dtheta_deg));
}

qnav_rank_t qnav_ctrl_rank(const qnav_ctrl_t *ctrl)
{
    if (ctrl == 0 || ctrl->magic != QNAV_CTRL_MAGIC || ctrl->rank != (uint8_t)QNAV_RANK_PREACT) {
        return QNAV_RANK_QUALITY;
    }
    return QNAV_RANK_PREACT;
}

uint8_t qnav_ctrl_level(const qnav_ctrl_t *ctrl, qnav_mm_t range_mm)
{
    if (ctrl == 0 || ctrl->magic != QNAV_CTRL_MAGIC) {
        return 0;
    }
    return qnav_clearance_level_of(&ctrl->clr, range_mm > ctrl->clr.max_range_mm
                                                   ? ctrl->clr.max_range_mm : range_mm);
}

uint16_t qnav_ctrl_sector_of_path(uint16_t n_sectors, uint16_t path_deg)
{
    uint32_t s;
    if (n_sectors == 0u) {
        return 0;
    }
    s = ((uint32_t)(path_deg % QNAV_PATHS) * n_sectors + QNAV_PATHS / 2u) / QNAV_PATHS;
    return (uint16_t)(s % n_sectors);
}


/* Table mode: read a run's row. Along the run the tie order prefers earlier paths when
 * dtheta rises and later ones when it falls, so only the run's winner is considered. */
static void eval_table_run(const qnav_ctrl_t *ctrl, const qnav_run_t *r, qnav_best_t *best,
                           qnav_qkey_t *keys)
{
    const qnav_qkey_t *p =
        &ctrl->p.net.table[(uint16_t)r->level * QNAV_TABLE_STRIDE + r->dtheta0];
    qnav_qkey_t top = QNAV_KEY_NONE;
    uint8_t top_k = 0;
    uint8_t k;
    for (k = 0; k < r->count; ++k, p += r->dir) {
        qnav_qkey_t q = QNAV_FLASH_READ_I16(p);
        if (keys != 0) {
            keys[r->first + k] = q;
        }
        if (q > top || (q == top && r->dir < 0)) {
            top = q;
            top_k = k;
        }
    }
    qnav_best_consider(best, top, (uint16_t)(r->first + top_k),
             (uint8_t)(r->dir > 0 ? r->dtheta0 + top_k : r->dtheta0 - top_k));
}

qnav_status_t qnav_ctrl_build_table(const qnav_ctrl_t *ctrl, qnav_qkey_t *table)
{
    uint16_t level;
    if (ctrl == 0 || table == 0) {
        return QNAV_E_NULL;
    }
    if (!QNAV_WITH_TABLE) {
        return QNAV_E_KIND_DISABLED;
    }
    if (ctrl->magic != QNAV_CTRL_MAGIC || qnav_table_of(ctrl) != 0) {
        return QNAV_E_POLICY_KIND;
    }
    for (level = 0; level < QNAV_DIST_LEVELS; ++level) {
        switch ((qnav_policy_kind_t)ctrl->kind) {
        case QNAV_POLICY_PROB:
#if QNAV_WITH_PROB
            qnav_prob_eval_row(ctrl, (uint8_t)level, &table[level * QNAV_TABLE_STRIDE]);
#endif
            break;
        case QNAV_POLICY_NET:
#if QNAV_WITH_NETWORK
            if (ctrl->inputs != QNAV_NET_INPUTS_PAPER) {
                return QNAV_E_NO_TABLE;
            }
            qnav_net_eval_row(ctrl, (uint8_t)level, &table[level * QNAV_TABLE_STRIDE]);
#endif
            break;
        }
    }
    return QNAV_OK;
}

void qnav_ctrl_stop(qnav_ctrl_output_t *out, uint8_t flags, qnav_q1_15_t *qualities)
{
    uint16_t i;
    out->heading_deg = 0;
    out->speed = 0;
    out->quality = 0;
    out->flags = flags;
    qnav_escape_clear(&out->escape);
    if (qualities != 0) {
        for (i = 0; i < QNAV_PATHS; ++i) {
            qualities[i] = 0;
        }
    }
}

/* Table mode: every run, read where its row's shape leaves anything to read. Out of line
 * on AVR: inlined, its run and registers sit in the step's frame under the network's
 * evaluation too, the deepest call path (11 bytes). */
QNAV_AVR_NOINLINE static void table_paths_best(const qnav_ctrl_t *ctrl, qnav_run_iter_t *it,
                                               qnav_best_t *best, qnav_qkey_t *keys)
{
    qnav_run_t r;
    while (qnav_run_next(it, &r)) {
        if (keys != 0 || qnav_run_reduce(ctrl->p.net.in.row, &r, best, it) != QNAV_RUN_DONE) {
            eval_table_run(ctrl, &r, best, keys);
        }
    }
}

/* Every path: table mode through its runs, a policy through its kind's evaluation. */
static void paths_best(const qnav_ctrl_t *ctrl, qnav_run_iter_t *it, qnav_best_t *best,
                       qnav_qkey_t *keys)
{
    if (qnav_table_of(ctrl) != 0) {
        table_paths_best(ctrl, it, best, keys);
        return;
    }
    switch ((qnav_policy_kind_t)ctrl->kind) {
    case QNAV_POLICY_PROB:
#if QNAV_WITH_PROB
        qnav_prob_eval_paths(ctrl, it, best, keys);
#endif
        break;
    case QNAV_POLICY_NET:
#if QNAV_WITH_NETWORK
        qnav_net_eval_paths(ctrl, it, best, keys);
#endif
        break;
    }
}

uint8_t qnav_ctrl_path_levels(const qnav_ctrl_t *ctrl, const qnav_mm_t *ranges_mm, uint8_t *lvl)
{
    if (ctrl == 0 || ctrl->magic != QNAV_CTRL_MAGIC || ranges_mm == 0 || lvl == 0) {
        return QNAV_FLAG_NOT_READY;
    }
    return qnav_clearance_levels(&ctrl->clr, ranges_mm, ctrl->clr.n_sectors, lvl);
}

/*
 * Holding the heading (keep_pct): the path on the previous tick's heading replaces the best
 * while its key is near the best's. Quality keys (QNAV_RANK_QUALITY): at least
 * (100 - keep_pct) % of the best's quality. Pre-activation keys (QNAV_RANK_PREACT, a
 * 2-input network): at most keep_pct hundredths of z below the best's (keep_pct * 2048 / 100
 * key steps, written 512 / 25 so that the ATmega128 divides 16-bit: Q5.11 below |z| 8), and z above 0 (quality above one half). A network's quality
 * is flat near 1 over much of its grid, so a margin in quality would hold nearly any
 * heading; one in z holds between near equals (docs/architecture.md, "Holding the
 * heading"). The step calls it only while going to the destination (a follow's skirt
 * bearing comes from the boundary).
 */
static inline void keep_heading(const qnav_ctrl_t *ctrl, const uint8_t *lvl, uint16_t goal,
                         uint16_t prev, qnav_best_t *best)
{
    uint8_t dtheta = qnav_angle_dist_deg(prev, goal);
    qnav_qkey_t key = key_at(ctrl, lvl[prev], dtheta);
    if (key <= 0) {
        return; /* no way that way */
    }
    if (ctrl->rank == (uint8_t)QNAV_RANK_PREACT
            ? (int32_t)key >= (int32_t)best->key - (int32_t)(uint16_t)(ctrl->keep_pct * 512u / 25u)
            : (uint32_t)key * 100u >= (uint32_t)best->key * (uint32_t)(100u - ctrl->keep_pct)) {
        best->key = key;
        best->dtheta = dtheta;
        best->heading = qnav_signed_deg(prev);
    }
}

/* qnav_ctrl_decide's body, inline in the fast step (a call there costs 40 cycles a tick on
 * the ATmega128); the plain step calls it through qnav_ctrl_decide. */
static inline void decide(const qnav_ctrl_t *ctrl, const uint8_t *lvl, uint16_t goal,
                          uint16_t prev, uint8_t flags, qnav_best_t *best,
                          qnav_ctrl_output_t *out)
{
    uint16_t path;
    uint32_t speed;
    qnav_q1_15_t quality;
    qnav_q1_15_t cap;
    if (ctrl->keep_pct != 0u && out->escape.side == 0 && ctrl->inputs != QNAV_NET_INPUTS_PREV) {
        keep_heading(ctrl, lvl, goal, prev, best);
    }
    quality = key_quality(ctrl, best->key);
    if (quality <= 0) {
        out->heading_deg = 0;
        out->speed = 0;
        out->quality = 0;
        out->flags = (uint8_t)(flags | QNAV_FLAG_NO_PATH);
        qnav_escape_keep_moving(&ctrl->clr, lvl, &out->escape, goal, out);
        qnav_escape_unstand(&ctrl->clr, lvl, prev, out);
        qnav_escape_hold_turn(prev, out);
        return;
    }
    speed = ((uint32_t)quality * ctrl->speed_scale) >> 15;
    if (quality >= ctrl->full_speed_quality || speed > QNAV_Q1_15_MAX) {
        speed = QNAV_Q1_15_MAX;
        flags |= QNAV_FLAG_FULL_SPEED;
    }
    path = (uint16_t)(best->heading < 0 ? best->heading + QNAV_PATHS : best->heading);
    cap = qnav_clearance_turn_cap(&ctrl->clr, lvl, path);
    if (speed > (uint32_t)cap) {
        speed = (uint32_t)cap;
        flags |= QNAV_FLAG_SPEED_GUARD;
    }
    out->heading_deg = best->heading;
    out->speed = (qnav_q1_15_t)speed;
    out->quality = quality;
    out->flags = flags;
    qnav_escape_keep_moving(&ctrl->clr, lvl, &out->escape, goal, out);
    qnav_escape_unstand(&ctrl->clr, lvl, prev, out);
    qnav_escape_hold_turn(prev, out);
}

void qnav_ctrl_decide(const qnav_ctrl_t *ctrl, const uint8_t *lvl, uint16_t goal,
                      uint16_t prev, uint8_t flags, qnav_best_t *best,
                      qnav_ctrl_output_t *out)
{
    decide(ctrl, lvl, goal, prev, flags, best, out);
}

/* The fast step: the runs settle most paths from their rows' shapes, the rest are searched
 * (policy_<kind>.c); qnav_ctrl_step_plain (ctrl_plain.c) evaluates every path instead and
 * must decide the same, bit for bit. */
void qnav_ctrl_step(const qnav_ctrl_t *ctrl, const qnav_ctrl_input_t *in,
                    qnav_ctrl_output_t *out, qnav_q1_15_t *qualities)
{
    uint8_t lvl[QNAV_PATHS];
    qnav_run_iter_t it;
    qnav_best_t best;
    uint8_t flags;
    uint16_t path;
    uint16_t goal;
    uint16_t prev;

    if (out == 0) {
        return;
    }
    if (ctrl == 0 || ctrl->magic != QNAV_CTRL_MAGIC || in == 0 || in->ranges_mm == 0) {
        qnav_ctrl_stop(out, QNAV_FLAG_NOT_READY, qualities);
        return;
    }
    best.key = QNAV_KEY_NONE;
    best.dtheta = 0;
    best.heading = 0;
    flags = qnav_clearance_input_levels(&ctrl->clr, in, lvl);
    /* the memory goes straight to the output (no copy on the stack: the ATmega128's RAM) */
    goal = qnav_escape_goal(&ctrl->clr, lvl, in, &out->escape);
    prev = qnav_whole_deg(in->prev_heading_cdeg);
    qnav_run_start(&it, lvl, goal, prev);
    /* the keys land in qualities[] and are turned into qualities below */
    paths_best(ctrl, &it, &best, qualities);
    if (qualities != 0) {
        for (path = 0; path < QNAV_PATHS; ++path) {
            qualities[path] = key_quality(ctrl, qualities[path]);
        }
    }
    decide(ctrl, lvl, goal, prev, flags, &best, out);
}

qnav_cdeg_t qnav_ctrl_prev_heading(qnav_deg_t last_heading_deg, qnav_cdeg_t last_yaw_cdeg,
                                   qnav_cdeg_t yaw_cdeg)
{
    int32_t a = (int32_t)last_heading_deg * 100 - ((int32_t)yaw_cdeg - last_yaw_cdeg);
    a %= 36000;
    if (a < -18000) {
        a += 36000;
    } else if (a >= 18000) {
        a -= 36000;
    }
    return (qnav_cdeg_t)a;
}

void qnav_ctrl_carry_reset(qnav_ctrl_carry_t *c)
{
    qnav_escape_clear(&c->escape);
    c->goal_id = 0u;
    c->last_heading_deg = 0;
    c->last_yaw_cdeg = 0;
    c->yaw_cdeg = 0;
    c->have_last = 0u;
}

void qnav_ctrl_carry_input(qnav_ctrl_carry_t *c, uint16_t goal_id, uint32_t range_mm,
                           qnav_cdeg_t yaw_cdeg, qnav_ctrl_input_t *in)
{
    if (goal_id != c->goal_id) {
        qnav_escape_clear(&c->escape); /* a new destination: nothing learnt holds */
        c->goal_id = goal_id;
    }
    c->yaw_cdeg = yaw_cdeg;
    in->prev_heading_cdeg = c->have_last ? qnav_ctrl_prev_heading(c->last_heading_deg,
                                                                  c->last_yaw_cdeg, yaw_cdeg)
                                         : 0;
    in->goal_range_mm = (qnav_mm_t)(range_mm > 65535u ? 65535u : range_mm);
    in->escape = c->escape;
}

void qnav_ctrl_carry_output(qnav_ctrl_carry_t *c, const qnav_ctrl_output_t *out)
{
    c->escape = out->escape;
    if (!(out->flags & QNAV_FLAG_NOT_READY)) {
        c->last_heading_deg = out->heading_deg;
        c->last_yaw_cdeg = c->yaw_cdeg;
        c->have_last = 1u;
    }
}

const char *qnav_status_str(qnav_status_t status)
{
    switch (status) {
    case QNAV_OK:
        return "ok";
    case QNAV_E_NULL:
        return "a required pointer was null";
    case QNAV_E_SECTORS:
        return "n_sectors outside 1..QNAV_MAX_SECTORS";
    case QNAV_E_RANGE:
        return "max_range_mm is 0, or range_min_mm not below it";
    case QNAV_E_SPEED:
        return "full_speed_quality outside (0, 1), or quality_full_speed negative";
    case QNAV_E_POLICY_KIND:
        return "unknown policy kind (or no policy to compile)";
    case QNAV_E_HIDDEN:
        return "hidden units outside 1..QNAV_MAX_HIDDEN";
    case QNAV_E_PROB_PARAM:
        return "probabilistic k_goal or k_safe outside (0, 64]";
    case QNAV_E_RANK:
        return "rank is not a qnav_rank_t";
    case QNAV_E_INPUTS:
        return "network inputs neither 2 nor 3";
    case QNAV_E_NO_TABLE:
        return "a 3-input network has no 2-D quality table";
    case QNAV_E_VFH_PARAM:
        return "a VFH+ parameter out of range";
    case QNAV_E_NAME:
        return "no controller of that name";
    case QNAV_E_WEDGE:
        return "wedge_pct above 100";
    case QNAV_E_KIND_DISABLED:
        return "policy kind, table mode or controller left out of this build (a QNAV_WITH_* "
               "switch is 0)";
    case QNAV_E_KEEP:
        return "keep_pct above 100";
    case QNAV_E_MAP:
        return "map cell_mm outside 20..1000, plan_ticks 0, arc_cdeg above 36000, more than 65 000 "
               "cells, or too little memory for them";
    }
    return "unknown status";
}
