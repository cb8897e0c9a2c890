/*
 * The controller seam (after the Crazyflie firmware's controllerFunctions[]): a small
 * table of controllers that share one step signature over qnav_ctrl_input_t /
 * qnav_ctrl_output_t, selected by name, so that the simulator's tools, simevo, navbridge
 * and the board drive any of them the same way. Each controller keeps its own
 * config/init/step (qnav/ctrl.h, qnav/vfh.h); a qnav_nav_t is the caller-owned instance
 * that holds whichever one was chosen and its state between ticks. No heap, no writable
 * file-scope state (the table is const).
 *
 *   "body"    the path-quality controller (paper §3, body-aware clearance), with a policy
 *   "literal" the same with qnav_ctrl_config_literal() (the paper read literally)
 *   "vfh"     VFH+ (Ulrich & Borenstein 1998), no policy
 * Every row is there in every build; a controller or policy kind that the build's
 * QNAV_WITH_* switches left out is refused at init with QNAV_E_KIND_DISABLED.
 */
#ifndef QNAV_NAV_H
#define QNAV_NAV_H

#include "qnav/check.h"
#include "qnav/ctrl.h"
#include "qnav/vfh.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct qnav_nav qnav_nav_t;

/* One row of the controller table. */
typedef struct {
    const char *name;    /* selects it: "body", "literal", "vfh" */
    uint8_t uses_policy; /* 1: init needs a policy; 0: policy ignored (may be null) */
    /* Edit the shared configuration before init (null: use it as given); callers that
     * build a path-quality table apply it too (qnav_nav_config). */
    void (*adjust)(qnav_ctrl_config_t *cfg);
    /* Configure nav from the shared sensor/body configuration and a policy, with the
     * policy's carried row shapes (null: none; qnav_ctrl_init_carried). */
    qnav_status_t (*init)(qnav_nav_t *nav, const qnav_ctrl_config_t *cfg,
                          const qnav_policy_t *policy, const uint8_t *shapes,
                          uint16_t shapes_len);
    /* Forget everything kept between ticks (start of an episode). */
    void (*reset)(qnav_nav_t *nav);
    /* One tick: the signature every controller shares. Never fails. */
    void (*step)(qnav_nav_t *nav, const qnav_ctrl_input_t *in, qnav_ctrl_output_t *out);
    /* Where this controller keeps the sensor settings it was initialised with (sectors N,
     * maximum range): its own member of nav's union, so that no caller guesses which
     * member holds them (qnav_nav_sensors). A row without it does not compile
     * (-Wmissing-field-initializers under -Werror). */
    const qnav_clearance_t *(*sensors)(const qnav_nav_t *nav);
} qnav_nav_method_t;

/* A controller instance: the chosen method and its storage. Caller-owned; private fields. */
struct qnav_nav {
    const qnav_nav_method_t *method; /* null until a successful qnav_nav_init() */
    union {
        qnav_ctrl_t paths;           /* "body", "literal" */
        struct {
            qnav_vfh_t vfh;
            qnav_vfh_state_t state;
        } vfh;                       /* "vfh" */
    } u;
};

/* Number of controllers in the table, and row i (null when i is past the end). */
uint8_t qnav_nav_count(void);
const qnav_nav_method_t *qnav_nav_method_at(uint8_t i);

/* The controller called name (NUL-terminated), or null. */
const qnav_nav_method_t *qnav_nav_find(const char *name);

/* Initialise nav as method from cfg (and policy when the method uses one), then reset it.
 * Returns the method's status (QNAV_E_NULL for a null nav, cfg or method; QNAV_E_NULL for
 * a null policy when the method uses one; QNAV_E_KIND_DISABLED for a controller or policy
 * kind left out of this build); on error nav is not ready and steps stop. */
QNAV_CHECK_RESULT qnav_status_t qnav_nav_init(qnav_nav_t *nav, const qnav_nav_method_t *method,
                                              const qnav_ctrl_config_t *cfg,
                                              const qnav_policy_t *policy);

/* qnav_nav_init() with the policy's carried row shapes (shapes_len bytes; null: none), which
 * the path-quality controller takes when they are the policy's (qnav_ctrl_init_carried). */
QNAV_CHECK_RESULT qnav_status_t qnav_nav_init_carried(qnav_nav_t *nav,
                                                      const qnav_nav_method_t *method,
                                                      const qnav_ctrl_config_t *cfg,
                                                      const qnav_policy_t *policy,
                                                      const uint8_t *shapes,
                                                      uint16_t shapes_len);

/* qnav_nav_find(name) then qnav_nav_init(); QNAV_E_NAME when there is no such controller. */
QNAV_CHECK_RESULT qnav_status_t qnav_nav_init_named(qnav_nav_t *nav, const char *name,
                                                    const qnav_ctrl_config_t *cfg,
                                                    const qnav_policy_t *policy);

/* The configuration method's init sees: *cfg after the method's adjust hook. */
void qnav_nav_config(const qnav_nav_method_t *method, const qnav_ctrl_config_t *cfg,
                     qnav_ctrl_config_t *out);

/* Start of an episode: clear what the controller keeps between ticks. */
void qnav_nav_reset(qnav_nav_t *nav);

/* One tick of whichever controller nav holds; not ready: stop and QNAV_FLAG_NOT_READY. */
void qnav_nav_step(qnav_nav_t *nav, const qnav_ctrl_input_t *in, qnav_ctrl_output_t *out);

/* The method nav holds (null when not ready), and the path-quality controller inside it
 * (null unless the method is "body" or "literal"), e.g. to compile its table. */
const qnav_nav_method_t *qnav_nav_method(const qnav_nav_t *nav);
qnav_ctrl_t *qnav_nav_paths(qnav_nav_t *nav);

/* The sensor configuration nav was initialised with (sectors N and maximum range), for a
 * caller that checks it against its sensors; 0 and 0 when not ready. */
void qnav_nav_sensors(const qnav_nav_t *nav, uint16_t *n_sectors, qnav_mm_t *max_range_mm);

#ifdef __cplusplus
}
#endif

#endif /* QNAV_NAV_H */
