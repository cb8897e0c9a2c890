/*
 * A host program on an installed qnav: every library of the package once. The controller
 * (qnav::ctrl) decides on one fixed scan, the same scan the ATmega128 example decides on
 * (examples/avr-firmware: identical output expected); the policy goes through a policy
 * file (qnav::policyio) and a link frame (qnav::link); the simulator (qnav::sim) drives the
 * TekBot through the open arena with it.
 * Usage: qnav-example [SHARE_DIR]   (default: the installation's share/qnav)
 */
#define _POSIX_C_SOURCE 200809L /* mkstemp */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "qnav/ctrl.h"
#include "qnav/link.h"
#include "qnav/policy_io.h"
#include "qnav/sim.h"

#ifndef QNAV_EXAMPLE_SHARE_DIR
#define QNAV_EXAMPLE_SHARE_DIR "."
#endif

/* the fixed scan of both examples: 16 sectors, open at 3 m but sectors 0 and 1 at 0.4 m,
 * the destination 30 degrees to the left */
static void fixed_decision(const qnav_policy_t *policy)
{
    qnav_mm_t ranges[16];
    qnav_ctrl_config_t cfg;
    qnav_ctrl_t ctrl;
    qnav_ctrl_output_t out;
    qnav_ctrl_input_t in = {0};
    int k;
    for (k = 0; k < 16; ++k) {
        ranges[k] = (qnav_mm_t)(k < 2 ? 400 : 3000);
    }
    qnav_ctrl_config_default(&cfg);
    cfg.n_sectors = 16;
    cfg.max_range_mm = 3000;
    if (qnav_ctrl_init(&ctrl, &cfg, policy) != QNAV_OK) {
        fprintf(stderr, "qnav-example: qnav_ctrl_init failed\n");
        exit(1);
    }
    in.ranges_mm = ranges;
    in.goal_bearing_cdeg = 3000;
    in.prev_heading_cdeg = 0; /* 2-input policies ignore it */
    qnav_ctrl_step(&ctrl, &in, &out, NULL);
    printf("fixed scan: heading %d speed %d\n", (int)out.heading_deg, (int)out.speed);
}

int main(int argc, char **argv)
{
    const char *share = argc > 1 ? argv[1] : QNAV_EXAMPLE_SHARE_DIR;
    char robot_path[1024], env_path[1024], err[512];
    char policy_path[] = "/tmp/qnav-example-XXXXXX";
    qnav_policy_t policy, back;
    qnav_sim_robot_t *robot = NULL;
    qnav_sim_env_t *env = NULL;
    qnav_sim_t *sim = NULL;
    qnav_sim_config_t scfg;
    qnav_sim_result_t res;
    qnav_ctrl_config_t ccfg;
    qnav_ctrl_t ctrl;
    uint8_t blob[QNAV_LINK_POLICY_MAX_BYTES];
    int32_t blob_len;
    int fd;

    qnav_policy_prob_default(&policy);
    fixed_decision(&policy);

    /* through a policy file and back */
    fd = mkstemp(policy_path);
    if (fd < 0) {
        perror("qnav-example: mkstemp");
        return 1;
    }
    close(fd);
    if (qnav_policy_write(policy_path, &policy, "qnav example", err, sizeof err) != 0 ||
        qnav_policy_read(policy_path, &back, err, sizeof err) != 0) {
        fprintf(stderr, "qnav-example: %s\n", err);
        unlink(policy_path);
        return 1;
    }
    unlink(policy_path);
    blob_len = qnav_link_policy_to_blob(&back, blob, sizeof blob);
    printf("policy blob: %ld bytes, crc 0x%04x\n", (long)blob_len,
           blob_len > 0 ? (unsigned)qnav_link_crc16(QNAV_LINK_CRC16_INIT, blob, (uint16_t)blob_len)
                        : 0u);

    snprintf(robot_path, sizeof robot_path, "%s/data/robots/tekbot.toml", share);
    snprintf(env_path, sizeof env_path, "%s/data/envs/open.toml", share);
    if (qnav_sim_robot_load(robot_path, &robot, err, sizeof err) != QNAV_SIM_OK ||
        qnav_sim_env_load(env_path, &env, err, sizeof err) != QNAV_SIM_OK) {
        fprintf(stderr, "%s\n", err);
        qnav_sim_robot_free(robot);
        return 2;
    }
    qnav_sim_config_default(&scfg);
    if (qnav_sim_create(robot, env, &scfg, &sim, err, sizeof err) != QNAV_SIM_OK) {
        fprintf(stderr, "%s\n", err);
        return 1;
    }
    qnav_sim_robot_prob_policy(robot, &back);
    qnav_sim_ctrl_config(sim, &ccfg);
    if (qnav_ctrl_init(&ctrl, &ccfg, &back) != QNAV_OK ||
        qnav_sim_run_episode(sim, &ctrl, 1, &res, NULL, NULL) != QNAV_SIM_OK) {
        fprintf(stderr, "qnav-example: the episode did not run\n");
        return 1;
    }
    printf("episode: reached %s, %u collisions, R %.3f\n", res.reached ? "yes" : "no",
           (unsigned)res.collisions, res.R);
    qnav_sim_destroy(sim);
    qnav_sim_env_free(env);
    qnav_sim_robot_free(robot);
    return res.reached ? 0 : 1;
}
