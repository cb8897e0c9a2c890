/*
 * Runs in libqnav built with some QNAV_WITH_* switches at 0 (tests/firmware/switches):
 * each policy kind, table mode and VFH+ that the build holds initialises and drives on an
 * open scan; each one it left out is refused by the same call with QNAV_E_KIND_DISABLED
 * (qnav_policy_validate: QNAV_POLICY_E_KIND_DISABLED), and the refused controller commands
 * a stop (QNAV_FLAG_NOT_READY). One line per check; exit 1 when one fails. Runs on the
 * host, under simavr and under qemu.
 */
#include <stdint.h>

#include "qnav/nav.h"
#include "target_io.h"
#include "vector_table.h"

#define SECTORS 16u

static uint8_t failures;
static qnav_ctrl_t ctrl;
static qnav_nav_t nav;
#if !defined(__AVR__)
static qnav_qkey_t built[QNAV_QTABLE_ENTRIES]; /* 11.6 KB: not in an ATmega128's RAM */
#endif

static void report(const char *what, const char *label, int32_t got, int32_t want)
{
    qnav_target_put(what);
    qnav_target_put(label);
    qnav_target_put_i32(got);
    if (got != want) {
        qnav_target_put(" WRONG, expected ");
        qnav_target_put_i32(want);
        ++failures;
    }
    qnav_target_put("\n");
}

/* got must be ok when the build keeps the kind, refused when it left it out. */
static void check(const char *what, uint8_t kept, int32_t got, int32_t ok, int32_t refused)
{
    report(what, kept ? " (kept in): " : " (left out): ", got, kept ? ok : refused);
}

/* The tick after an init: moving when the kind is kept in, a stop when it was refused. */
static void check_tick(const char *what, uint8_t kept, const qnav_ctrl_output_t *out)
{
    uint8_t moving = (uint8_t)((out->flags & QNAV_FLAG_NOT_READY) == 0u && out->speed > 0);
    check(what, kept, moving, 1, 0);
}

static void input(qnav_ctrl_input_t *in)
{
    static const qnav_mm_t open_scan[SECTORS] = {5000u, 5000u, 5000u, 5000u, 5000u, 5000u,
                                                 5000u, 5000u, 5000u, 5000u, 5000u, 5000u,
                                                 5000u, 5000u, 5000u, 5000u};
    qnav_ctrl_input_t zero = {0};
    *in = zero;
    in->ranges_mm = open_scan;
    in->goal_bearing_cdeg = 4500;
    in->goal_range_mm = 3000u;
}

static void policies(const qnav_ctrl_config_t *cfg, const qnav_ctrl_input_t *in)
{
    qnav_policy_t policy;
    qnav_ctrl_output_t out;

    qnav_policy_prob_default(&policy);
    check("probabilistic: qnav_policy_validate", QNAV_WITH_PROB,
          qnav_policy_validate(&policy), QNAV_POLICY_OK, QNAV_POLICY_E_KIND_DISABLED);
    check("probabilistic: qnav_ctrl_init", QNAV_WITH_PROB, qnav_ctrl_init(&ctrl, cfg, &policy),
          QNAV_OK, QNAV_E_KIND_DISABLED);
    qnav_ctrl_step(&ctrl, in, &out, 0);
    check_tick("probabilistic: qnav_ctrl_step moves", QNAV_WITH_PROB, &out);

    qnav_policy_net_zero(&policy, 2u);
    check("network: qnav_policy_validate", QNAV_WITH_NETWORK, qnav_policy_validate(&policy),
          QNAV_POLICY_OK, QNAV_POLICY_E_KIND_DISABLED);
    check("network: qnav_ctrl_init", QNAV_WITH_NETWORK, qnav_ctrl_init(&ctrl, cfg, &policy),
          QNAV_OK, QNAV_E_KIND_DISABLED);
    qnav_ctrl_step(&ctrl, in, &out, 0);
    check_tick("network: qnav_ctrl_step moves", QNAV_WITH_NETWORK, &out);
    check("network: qnav_nav_init_named body", QNAV_WITH_NETWORK,
          qnav_nav_init_named(&nav, "body", cfg, &policy), QNAV_OK, QNAV_E_KIND_DISABLED);
    qnav_nav_step(&nav, in, &out);
    check_tick("network: qnav_nav_step moves", QNAV_WITH_NETWORK, &out);
}

static void tables(const qnav_ctrl_config_t *cfg, const qnav_ctrl_input_t *in)
{
    qnav_ctrl_output_t out;
    check("table: qnav_ctrl_init_table", QNAV_WITH_TABLE,
          qnav_ctrl_init_table(&ctrl, cfg, qnav_vectors_net12_table,
                               QNAV_VECTORS_NET12_TABLE_RANK),
          QNAV_OK, QNAV_E_KIND_DISABLED);
    qnav_ctrl_step(&ctrl, in, &out, 0);
    check_tick("table: qnav_ctrl_step moves", QNAV_WITH_TABLE, &out);
#if !defined(__AVR__)
    if (QNAV_WITH_PROB) {
        qnav_policy_t policy;
        qnav_policy_prob_default(&policy);
        if (qnav_ctrl_init(&ctrl, cfg, &policy) == QNAV_OK) {
            check("table: qnav_ctrl_build_table", QNAV_WITH_TABLE,
                  qnav_ctrl_build_table(&ctrl, built), QNAV_OK, QNAV_E_KIND_DISABLED);
        }
    }
#endif
}

static void vfh(const qnav_ctrl_config_t *cfg, const qnav_ctrl_input_t *in)
{
    qnav_ctrl_output_t out;
    check("vfh: qnav_nav_init_named", QNAV_WITH_VFH, qnav_nav_init_named(&nav, "vfh", cfg, 0),
          QNAV_OK, QNAV_E_KIND_DISABLED);
    qnav_nav_step(&nav, in, &out);
    check_tick("vfh: qnav_nav_step moves", QNAV_WITH_VFH, &out);
}

/* The refusal has a text of its own, not the fallback for an unknown status. */
static void texts(void)
{
    const char *a = qnav_status_str(QNAV_E_KIND_DISABLED);
    const char *b = qnav_policy_status_str(QNAV_POLICY_E_KIND_DISABLED);
    report("qnav_status_str names the refusal: ", "", a != qnav_status_str((qnav_status_t)-100),
           1);
    report("qnav_policy_status_str names the refusal: ", "",
           b != qnav_policy_status_str((qnav_policy_status_t)-100), 1);
    qnav_target_put(a);
    qnav_target_put("\n");
}

int main(void)
{
    qnav_ctrl_config_t cfg;
    qnav_ctrl_input_t in;
    qnav_ctrl_config_default(&cfg);
    cfg.n_sectors = SECTORS;
    input(&in);
    policies(&cfg, &in);
    tables(&cfg, &in);
    vfh(&cfg, &in);
    texts();
    qnav_target_put(failures == 0u ? "all checks passed\n" : "FAILED\n");
    qnav_target_exit((uint8_t)(failures == 0u ? 0u : 1u));
    return 0;
}
