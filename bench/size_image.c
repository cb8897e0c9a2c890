/*
 * A minimal firmware image for the size report (tools/size-report): the controller as a
 * board would run it, in one mode chosen at compile time (QNAV_SIZE_MODE 1 = network with
 * H = 12, 2 = probabilistic, 3 = table from flash, 4 = VFH+), a 32-sector scan read from a
 * volatile buffer (standing in for the sonar driver), and the command written to volatile
 * storage (standing in for the motor driver). Nothing else: no stdio, no semihosting.
 * Linked and measured with avr-size / arm-none-eabi-size, never run.
 */
#include <stdint.h>

#include "qnav/ctrl.h"
#include "qnav/flash.h"
#include "qnav/vfh.h"

#ifndef QNAV_SIZE_MODE
#define QNAV_SIZE_MODE 1
#endif

#if QNAV_SIZE_MODE == 3
#include "vector_table.h"
#endif

#define SECTORS 32u

#if QNAV_SIZE_MODE == 4
static qnav_vfh_t vfh;
static qnav_vfh_state_t vfh_state;
#else
static qnav_ctrl_t ctrl;
#endif
static volatile qnav_mm_t sonar[SECTORS];
static volatile qnav_cdeg_t goal;
static volatile qnav_ctrl_output_t command;

#if QNAV_SIZE_MODE == 1
/* Fixed weights in flash, as a generated policy header would give them. */
static const qnav_q8_8_t w_theta[12] QNAV_FLASH = {-1200, -800, -300, -1500, 100, -600, -900, -50, -1100, -400, -700, -200};
static const qnav_q8_8_t w_dist[12] QNAV_FLASH = {900, 300, 1400, -100, 700, 1200, 250, 800, 60, 1500, 450, 1000};
static const qnav_q8_8_t b_hidden[12] QNAV_FLASH = {-300, 200, 0, 500, -700, 100, -50, 350, -250, 600, 0, -400};
static const qnav_q8_8_t w_out[12] QNAV_FLASH = {400, -200, 700, 300, -100, 500, 250, 600, -300, 200, 450, 350};
#endif

/* The controller of this mode, initialised; its status. */
static qnav_status_t setup(void)
{
#if QNAV_SIZE_MODE == 4
    qnav_vfh_config_t vc;
    qnav_status_t st;
    qnav_vfh_config_default(&vc);
    vc.body.n_sectors = SECTORS;
    st = qnav_vfh_init(&vfh, &vc);
    qnav_vfh_state_reset(&vfh_state);
    return st;
#else
    qnav_ctrl_config_t cfg;
    qnav_ctrl_config_default(&cfg);
    cfg.n_sectors = SECTORS;
#if QNAV_SIZE_MODE == 1
    {
        qnav_policy_t policy;
        uint8_t i;
        qnav_policy_net_zero(&policy, 12u);
        for (i = 0; i < 12u; ++i) {
            policy.u.net.w_theta[i] = QNAV_FLASH_READ_I16(&w_theta[i]);
            policy.u.net.w_dist[i] = QNAV_FLASH_READ_I16(&w_dist[i]);
            policy.u.net.b_hidden[i] = QNAV_FLASH_READ_I16(&b_hidden[i]);
            policy.u.net.w_out[i] = QNAV_FLASH_READ_I16(&w_out[i]);
        }
        policy.u.net.b_out = -256;
        return qnav_ctrl_init(&ctrl, &cfg, &policy);
    }
#elif QNAV_SIZE_MODE == 2
    {
        qnav_policy_t policy;
        qnav_policy_prob_default(&policy);
        return qnav_ctrl_init(&ctrl, &cfg, &policy);
    }
#else
    return qnav_ctrl_init_table(&ctrl, &cfg, qnav_vectors_net12_table,
                                QNAV_VECTORS_NET12_TABLE_RANK);
#endif
#endif
}

static void step(const qnav_ctrl_input_t *in, qnav_ctrl_output_t *out)
{
#if QNAV_SIZE_MODE == 4
    qnav_vfh_step(&vfh, &vfh_state, in, out);
#else
    qnav_ctrl_step(&ctrl, in, out, 0);
#endif
}

int main(void)
{
    qnav_ctrl_input_t in = {0};
    qnav_ctrl_output_t out;
    qnav_mm_t ranges[SECTORS];
    uint8_t i;

    if (setup() != QNAV_OK) {
        return 1;
    }
    for (;;) {
        for (i = 0; i < SECTORS; ++i) {
            ranges[i] = sonar[i];
        }
        in.ranges_mm = ranges;
        in.goal_bearing_cdeg = goal;
        in.prev_heading_cdeg = 0; /* 2-input policies ignore it */
        step(&in, &out);
        command.heading_deg = out.heading_deg;
        command.speed = out.speed;
        command.quality = out.quality;
        command.flags = out.flags;
    }
}
