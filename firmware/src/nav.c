/*
 * The controller table (qnav/nav.h): one row per controller, each a thin adapter from
 * the shared step signature to that controller's own init, step and sensor settings.
 * Adding a controller is one row here, one union member in qnav_nav_t, and its own
 * header and source (docs/architecture.md, "Adding a controller").
 */
#include "qnav/nav.h"

static qnav_status_t body_init(qnav_nav_t *nav, const qnav_ctrl_config_t *cfg,
                               const qnav_policy_t *policy, const uint8_t *shapes,
                               uint16_t shapes_len)
{
    return qnav_ctrl_init_carried(&nav->u.paths, cfg, policy, shapes, shapes_len);
}


static void paths_reset(qnav_nav_t *nav)
{
    (void)nav; /* the path-quality controller keeps nothing between ticks */
}

static void paths_step(qnav_nav_t *nav, const qnav_ctrl_input_t *in, qnav_ctrl_output_t *out)
{
    qnav_ctrl_step(&nav->u.paths, in, out, 0);
}

static const qnav_clearance_t *paths_sensors(const qnav_nav_t *nav)
{
    return &nav->u.paths.clr;
}

static const qnav_clearance_t *vfh_sensors(const qnav_nav_t *nav)
{
    return &nav->u.vfh.vfh.clr;
}

/* What a controller that is not ready commands. */
static void stop(qnav_ctrl_output_t *out)
{
    out->heading_deg = 0;
    out->speed = 0;
    out->quality = 0;
    out->flags = QNAV_FLAG_NOT_READY;
}

#if QNAV_WITH_VFH
static qnav_status_t vfh_init(qnav_nav_t *nav, const qnav_ctrl_config_t *cfg,
                              const qnav_policy_t *policy, const uint8_t *shapes,
                              uint16_t shapes_len)
{
    qnav_vfh_config_t vc;
    (void)policy;
    (void)shapes;
    (void)shapes_len;
    qnav_vfh_config_default(&vc);
    vc.body = *cfg;
    return qnav_vfh_init(&nav->u.vfh.vfh, &vc);
}

static void vfh_reset(qnav_nav_t *nav)
{
    qnav_vfh_state_reset(&nav->u.vfh.state);
}

static void vfh_step(qnav_nav_t *nav, const qnav_ctrl_input_t *in, qnav_ctrl_output_t *out)
{
    qnav_vfh_step(&nav->u.vfh.vfh, &nav->u.vfh.state, in, out);
}
#else
/* VFH+ left out of this build (QNAV_WITH_VFH 0): the row keeps its name, so that a board
 * configured for it learns why it has no controller, and its init refuses. */
static qnav_status_t vfh_init(qnav_nav_t *nav, const qnav_ctrl_config_t *cfg,
                              const qnav_policy_t *policy, const uint8_t *shapes,
                              uint16_t shapes_len)
{
    (void)nav;
    (void)cfg;
    (void)policy;
    (void)shapes;
    (void)shapes_len;
    return QNAV_E_KIND_DISABLED;
}

static void vfh_reset(qnav_nav_t *nav)
{
    (void)nav;
}

static void vfh_step(qnav_nav_t *nav, const qnav_ctrl_input_t *in, qnav_ctrl_output_t *out)
{
    (void)nav;
    (void)in;
    if (out != 0) {
        stop(out);
    }
}
#endif

static const qnav_nav_method_t methods[] = {
    {"body", 1u, 0, body_init, paths_reset, paths_step, paths_sensors},
    {"literal", 1u, qnav_ctrl_config_literal, body_init, paths_reset, paths_step, paths_sensors},
    {"vfh", 0u, 0, vfh_init, vfh_reset, vfh_step, vfh_sensors},
};

#define N_METHODS ((uint8_t)(sizeof methods / sizeof methods[0]))

uint8_t qnav_nav_count(void)
{
    return N_METHODS;
}

const qnav_nav_method_t *qnav_nav_method_at(uint8_t i)
{
    return i < N_METHODS ? &methods[i] : 0;
}

static uint8_t same_name(const char *a, const char *b)
{
    while (*a != '\0' && *a == *b) {
        ++a;
        ++b;
    }
    return (uint8_t)(*a == *b);
}

const qnav_nav_method_t *qnav_nav_find(const char *name)
{
    uint8_t i;
    if (name == 0) {
        return 0;
    }
    for (i = 0; i < N_METHODS; ++i) {
        if (same_name(methods[i].name, name)) {
            return &methods[i];
        }
    }
    return 0;
}

void qnav_nav_config(const qnav_nav_method_t *method, const qnav_ctrl_config_t *cfg,
                     qnav_ctrl_config_t *out)
{
    if (method == 0 || cfg == 0 || out == 0) {
        return;
    }
    *out = *cfg;
    if (method->adjust != 0) {
        method->adjust(out);
    }
}

qnav_status_t qnav_nav_init(qnav_nav_t *nav, const qnav_nav_method_t *method,
                            const qnav_ctrl_config_t *cfg, const qnav_policy_t *policy)
{
    return qnav_nav_init_carried(nav, method, cfg, policy, 0, 0u);
}

qnav_status_t qnav_nav_init_carried(qnav_nav_t *nav, const qnav_nav_method_t *method,
                                    const qnav_ctrl_config_t *cfg, const qnav_policy_t *policy,
                                    const uint8_t *shapes, uint16_t shapes_len)
{
    qnav_ctrl_config_t own;
    qnav_status_t st;
    if (nav == 0) {
        return QNAV_E_NULL;
    }
    nav->method = 0;
    if (method == 0 || cfg == 0 || (method->uses_policy && policy == 0)) {
        return QNAV_E_NULL;
    }
    qnav_nav_config(method, cfg, &own);
    st = method->init(nav, &own, policy, shapes, shapes_len);
    if (st != QNAV_OK) {
        return st;
    }
    nav->method = method;
    method->reset(nav);
    return QNAV_OK;
}

qnav_status_t qnav_nav_init_named(qnav_nav_t *nav, const char *name,
                                  const qnav_ctrl_config_t *cfg, const qnav_policy_t *policy)
{
    const qnav_nav_method_t *m = qnav_nav_find(name);
    if (nav != 0) {
        nav->method = 0;
    }
    if (m == 0) {
        return QNAV_E_NAME;
    }
    return qnav_nav_init(nav, m, cfg, policy);
}

void qnav_nav_reset(qnav_nav_t *nav)
{
    if (nav != 0 && nav->method != 0) {
        nav->method->reset(nav);
    }
}

void qnav_nav_step(qnav_nav_t *nav, const qnav_ctrl_input_t *in, qnav_ctrl_output_t *out)
{
    if (out == 0) {
        return;
    }
    if (nav == 0 || nav->method == 0) {
        stop(out);
        return;
    }
    nav->method->step(nav, in, out);
}

const qnav_nav_method_t *qnav_nav_method(const qnav_nav_t *nav)
{
    return nav != 0 ? nav->method : 0;
}

void qnav_nav_sensors(const qnav_nav_t *nav, uint16_t *n_sectors, qnav_mm_t *max_range_mm)
{
    const qnav_clearance_t *c = 0;
    if (nav != 0 && nav->method != 0) {
        c = nav->method->sensors(nav);
    }
    if (n_sectors != 0) {
        *n_sectors = c != 0 ? c->n_sectors : 0u;
    }
    if (max_range_mm != 0) {
        *max_range_mm = c != 0 ? c->max_range_mm : 0u;
    }
}

qnav_ctrl_t *qnav_nav_paths(qnav_nav_t *nav)
{
    if (nav == 0 || nav->method == 0 || nav->method->step != paths_step) {
        return 0;
    }
    return &nav->u.paths;
}
