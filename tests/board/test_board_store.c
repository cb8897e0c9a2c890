/*
 * The board core's policy store in non-volatile storage, on the host with the scripted
 * robot's EEPROM: a committed upload is loaded at the next start-up, a store with a
 * flipped bit or a wrong format is not, the slots alternate so that a power cut at any
 * byte of a commit leaves either the old or the new policy (never another), and a board
 * without storage keeps uploads in RAM.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "qnav/tekbot.h"
#include "sim_hal.h"

static sim_hal_t g_sim;
static qnav_board_hal_t g_hal;
static qnav_board_t g_bot;
static qnav_link_tx_t g_tx;

static qnav_board_status_t boot(void)
{
    qnav_board_config_t cfg;
    qnav_tekbot_config_default(&cfg);
    qnav_link_tx_init(&g_tx);
    return qnav_board_init(&g_bot, &cfg, &g_hal);
}

/* Upload and commit pol; the board acts on it at its next receive. */
static void commit(const qnav_policy_t *pol)
{
    assert_int_equal(sim_hal_upload(&g_sim, &g_tx, pol, 0), 0);
    qnav_board_receive(&g_bot);
    qnav_board_receive(&g_bot);
    qnav_board_receive(&g_bot);
}

static void net_policy(qnav_policy_t *p, uint16_t mult)
{
    uint16_t k;
    qnav_policy_net_zero(p, 6);
    for (k = 0; k < QNAV_NET_WEIGHTS(6); ++k) {
        *qnav_net_weight(&p->u.net, k) = (qnav_q8_8_t)((int)((k * mult) % 1536u) - 768);
    }
}

static int setup(void **state)
{
    (void)state;
    sim_hal_init(&g_sim, &g_hal);
    return 0;
}

static void test_new_board_runs_the_built_in_policy(void **state)
{
    qnav_policy_t builtin;
    (void)state;
    assert_int_equal(boot(), QNAV_BOARD_OK);
    qnav_policy_prob_default(&builtin);
    assert_int_equal(qnav_board_policy_source(&g_bot), QNAV_BOARD_POLICY_BUILTIN);
    assert_int_equal(g_bot.policy_crc, qnav_link_policy_crc(&builtin));
}

static void test_committed_policy_is_loaded_at_the_next_start(void **state)
{
    qnav_policy_t a;
    (void)state;
    net_policy(&a, 613u);
    assert_int_equal(boot(), QNAV_BOARD_OK);
    commit(&a);
    assert_int_equal(qnav_board_policy_source(&g_bot), QNAV_BOARD_POLICY_UPLOADED);
    assert_int_equal(g_bot.stats.store_writes_failed, 0);
    assert_int_equal(boot(), QNAV_BOARD_OK); /* a reset: RAM gone, EEPROM kept */
    assert_int_equal(qnav_board_policy_source(&g_bot), QNAV_BOARD_POLICY_STORED);
    assert_int_equal(g_bot.policy_crc, qnav_link_policy_crc(&a));
    assert_int_equal(g_bot.policy.u.net.w_out[5], a.u.net.w_out[5]);
}

static void test_newest_of_two_commits_is_loaded(void **state)
{
    qnav_policy_t a, b, c;
    (void)state;
    net_policy(&a, 613u);
    net_policy(&b, 977u);
    net_policy(&c, 331u);
    assert_int_equal(boot(), QNAV_BOARD_OK);
    commit(&a);
    commit(&b);
    assert_int_equal(boot(), QNAV_BOARD_OK);
    assert_int_equal(g_bot.policy_crc, qnav_link_policy_crc(&b));
    commit(&c); /* overwrites a's slot, not b's */
    assert_int_equal(boot(), QNAV_BOARD_OK);
    assert_int_equal(g_bot.policy_crc, qnav_link_policy_crc(&c));
}

static void test_store_with_a_flipped_bit_falls_back_to_the_built_in_policy(void **state)
{
    qnav_policy_t a;
    uint16_t k;
    (void)state;
    net_policy(&a, 613u);
    /* every byte of the one written slot, one at a time */
    for (k = 0; k < QNAV_BOARD_STORE_HEADER_BYTES + 2u + 2u * QNAV_NET_WEIGHTS(6); ++k) {
        sim_hal_init(&g_sim, &g_hal);
        assert_int_equal(boot(), QNAV_BOARD_OK);
        commit(&a);
        g_sim.nvm[k] ^= 0x10u;
        assert_int_equal(boot(), QNAV_BOARD_OK);
        assert_int_equal(qnav_board_policy_source(&g_bot), QNAV_BOARD_POLICY_BUILTIN);
    }
}

static void test_power_cut_at_any_byte_of_a_commit_leaves_old_or_new_policy(void **state)
{
    qnav_policy_t a, b;
    uint32_t cut, full;
    uint32_t saw_old = 0, saw_new = 0;
    (void)state;
    net_policy(&a, 613u);
    net_policy(&b, 977u);
    /* how many bytes a commit of b writes */
    sim_hal_init(&g_sim, &g_hal);
    assert_int_equal(boot(), QNAV_BOARD_OK);
    commit(&a);
    full = g_sim.nvm_written;
    commit(&b);
    full = g_sim.nvm_written - full;
    assert_true(full > 50u); /* 8 header bytes and a 52-byte blob */
    for (cut = 0; cut <= full; ++cut) {
        uint16_t crc;
        sim_hal_init(&g_sim, &g_hal);
        assert_int_equal(boot(), QNAV_BOARD_OK);
        commit(&a);
        g_sim.nvm_cut_after = g_sim.nvm_written + cut; /* the first `cut` bytes of b */
        commit(&b);
        g_sim.nvm_cut_after = 0;
        assert_int_equal(boot(), QNAV_BOARD_OK);
        crc = g_bot.policy_crc;
        assert_true(crc == qnav_link_policy_crc(&a) || crc == qnav_link_policy_crc(&b));
        assert_int_equal(qnav_board_policy_source(&g_bot), QNAV_BOARD_POLICY_STORED);
        saw_old += crc == qnav_link_policy_crc(&a);
        saw_new += crc == qnav_link_policy_crc(&b);
    }
    assert_int_equal(saw_old, full); /* any cut before the last byte: the old one */
    assert_int_equal(saw_new, 1u);  /* only the whole write gives the new one */
}

static void test_board_without_storage_keeps_uploads_in_ram(void **state)
{
    qnav_policy_t a;
    (void)state;
    net_policy(&a, 613u);
    g_hal.nvm_read = NULL;
    g_hal.nvm_write = NULL;
    assert_int_equal(boot(), QNAV_BOARD_OK);
    commit(&a);
    assert_int_equal(qnav_board_policy_source(&g_bot), QNAV_BOARD_POLICY_UPLOADED);
    assert_int_equal(g_bot.stats.store_writes_failed, 1);
    assert_int_equal(boot(), QNAV_BOARD_OK);
    assert_int_equal(qnav_board_policy_source(&g_bot), QNAV_BOARD_POLICY_BUILTIN);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_new_board_runs_the_built_in_policy, setup),
        cmocka_unit_test_setup(test_committed_policy_is_loaded_at_the_next_start, setup),
        cmocka_unit_test_setup(test_newest_of_two_commits_is_loaded, setup),
        cmocka_unit_test_setup(test_store_with_a_flipped_bit_falls_back_to_the_built_in_policy,
                               setup),
        cmocka_unit_test_setup(test_power_cut_at_any_byte_of_a_commit_leaves_old_or_new_policy,
                               setup),
        cmocka_unit_test_setup(test_board_without_storage_keeps_uploads_in_ram, setup),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
