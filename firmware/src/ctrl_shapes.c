/*
 * Carried row shapes (qnav/ctrl.h, docs/architecture.md "Carried row shapes"): a 2-input
 * network's row shapes written where the policy is made, with a check that binds them to
 * the weights, and taken back at init instead of evaluating all 181 x QNAV_DIST_LEVELS
 * paths. What is taken must be this policy's: right format and rank, a CRC-32 over the
 * weights and the shapes, every field in the range the step relies on, and each row's top
 * equal to the network's own key there (QNAV_DIST_LEVELS evaluations, about 0.5 % of
 * computing them). Anything else is ignored and init computes the shapes as before.
 */
#include "policy_eval.h"

/* CRC-32 (IEEE 802.3, reflected, polynomial 0xEDB88320) of n bytes, continuing crc (start
 * with 0xFFFFFFFF, finish with ~). Bitwise: no table in flash, about 100 cycles a byte on
 * the ATmega128, 0.2 ms for a whole record. */
static uint32_t crc32_add(uint32_t crc, const uint8_t *p, uint16_t n)
{
    uint16_t i;
    uint8_t b;
    for (i = 0; i < n; ++i) {
        crc ^= p[i];
        for (b = 0; b < 8u; ++b) {
            crc = (crc >> 1) ^ (0xEDB88320ul & (uint32_t)(-(int32_t)(crc & 1u)));
        }
    }
    return crc;
}

static uint32_t crc32_i16(uint32_t crc, int16_t v)
{
    uint8_t le[2];
    le[0] = (uint8_t)((uint16_t)v & 0xFFu);
    le[1] = (uint8_t)((uint16_t)v >> 8);
    return crc32_add(crc, le, 2u);
}

/* The check of a record: the network (H and its weights in qnav_net_weight() order of a
 * 2-input network), then the record's bytes before the check. */
static uint32_t shapes_check(const qnav_net_t *net, const uint8_t *rec)
{
    uint32_t crc = 0xFFFFFFFFul;
    uint16_t n = qnav_net_weight_count(net);
    uint16_t k;
    crc = crc32_add(crc, &net->hidden, 1u);
    for (k = 0; k < n; ++k) {
        /* read only: qnav_net_weight is the one home of the weights' order */
        crc = crc32_i16(crc, *qnav_net_weight((qnav_net_t *)net, k));
    }
    crc = crc32_add(crc, rec, (uint16_t)(QNAV_SHAPES_BYTES - 4u));
    return ~crc;
}

qnav_status_t qnav_ctrl_shapes_save(const qnav_ctrl_t *ctrl, const qnav_policy_t *policy,
                                    uint8_t *out)
{
    uint16_t l;
    uint32_t check;
    if (ctrl == 0 || policy == 0 || out == 0) {
        return QNAV_E_NULL;
    }
    if (ctrl->magic != QNAV_CTRL_MAGIC || ctrl->kind != (uint8_t)QNAV_POLICY_NET ||
        ctrl->inputs != QNAV_NET_INPUTS_PAPER ||
        policy->kind != (uint8_t)QNAV_POLICY_NET ||
        policy->u.net.inputs != QNAV_NET_INPUTS_PAPER || policy->u.net.hidden != ctrl->hidden) {
        return QNAV_E_NO_TABLE;
    }
    out[0] = QNAV_SHAPES_FORMAT;
    out[1] = ctrl->rank;
    for (l = 0; l < QNAV_DIST_LEVELS; ++l) {
        const qnav_row_shape_t *s = &ctrl->p.net.in.row[l];
        uint8_t *o = &out[2u + 6u * l];
        o[0] = (uint8_t)((uint16_t)s->top & 0xFFu);
        o[1] = (uint8_t)((uint16_t)s->top >> 8);
        o[2] = s->top_d;
        o[3] = s->fall_d;
        o[4] = s->peak_lo;
        o[5] = s->peak_hi;
    }
    check = shapes_check(&policy->u.net, out);
    for (l = 0; l < 4u; ++l) {
        out[QNAV_SHAPES_BYTES - 4u + l] = (uint8_t)(check >> (8u * l));
    }
    return QNAV_OK;
}

#if QNAV_WITH_NETWORK
static uint32_t get_u32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) |
           ((uint32_t)p[3] << 24);
}

/* One row read from its 6 bytes, 1 when every field is in the range the step relies on:
 * dthetas 0..180, the top's dtheta not past the last rise (the top is reached by a rise,
 * or at 0), an interior peak 1 <= peak_lo <= peak_hi <= 179 unless none or several. */
static uint8_t row_read(const uint8_t *o, qnav_row_shape_t *s)
{
    s->top = (qnav_qkey_t)(uint16_t)((uint16_t)o[0] | ((uint16_t)o[1] << 8));
    s->top_d = o[2];
    s->fall_d = o[3];
    s->peak_lo = o[4];
    s->peak_hi = o[5];
    if (s->fall_d > QNAV_DTHETA_MAX || s->top_d > s->fall_d) {
        return 0;
    }
    if (s->peak_lo == QNAV_PEAK_NONE || s->peak_lo == QNAV_PEAK_MANY) {
        return (uint8_t)(s->peak_hi < QNAV_DTHETA_MAX);
    }
    return (uint8_t)(s->peak_lo >= 1u && s->peak_lo <= s->peak_hi &&
                     s->peak_hi < QNAV_DTHETA_MAX);
}

uint8_t qnav_shapes_take(qnav_ctrl_t *ctrl, const qnav_net_t *net, const uint8_t *shapes,
                         uint16_t len)
{
    uint16_t l;
    if (shapes == 0 || len != QNAV_SHAPES_BYTES || shapes[0] != QNAV_SHAPES_FORMAT ||
        shapes[1] != ctrl->rank ||
        get_u32(&shapes[QNAV_SHAPES_BYTES - 4u]) != shapes_check(net, shapes)) {
        return 0;
    }
    for (l = 0; l < QNAV_DIST_LEVELS; ++l) {
        qnav_row_shape_t *s = &ctrl->p.net.in.row[l];
        if (!row_read(&shapes[2u + 6u * l], s) ||
            qnav_net_eval_key(ctrl, (uint8_t)l, s->top_d) != s->top) {
            return 0; /* the caller computes every row over what was read */
        }
    }
    return 1;
}
#endif
