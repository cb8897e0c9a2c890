/*
 * Host program that writes tests/target/vector_table.h: the rank-key table of the shared
 * vectors' H = 12 network (vector_policy.h), compiled by qnav_ctrl_build_table() and
 * declared with QNAV_FLASH so an ATmega128 reads it from program memory. The CTest
 * vector_table_header_matches_its_generator reruns this and compares with the committed
 * file. Usage: gen_vector_table > tests/target/vector_table.h
 */
#include <stdio.h>
#include <stdlib.h>

#include "qnav/ctrl.h"
#include "vector_policy.h"

static qnav_qkey_t table[QNAV_QTABLE_ENTRIES];

int main(void)
{
    qnav_ctrl_config_t cfg;
    qnav_policy_t policy;
    qnav_ctrl_t ctrl;
    qnav_status_t st;
    unsigned i;

    qnav_ctrl_config_default(&cfg);
    qnav_vectors_net_policy(&policy, 12u, QNAV_VECTORS_NET12_SEED, 0u);
    st = qnav_ctrl_init(&ctrl, &cfg, &policy);
    if (st != QNAV_OK) {
        fprintf(stderr, "gen_vector_table: qnav_ctrl_init failed with status %d\n", (int)st);
        return 1;
    }
    st = qnav_ctrl_build_table(&ctrl, table);
    if (st != QNAV_OK) {
        fprintf(stderr, "gen_vector_table: qnav_ctrl_build_table failed with status %d\n", (int)st);
        return 1;
    }
    printf("/*\n"
           " * Rank-key table of the shared vectors' H = 12 network (seed 0x%08lX, see\n"
           " * vector_policy.h): %d distance levels x %d dtheta values, row-major by level;\n"
           " * keys of QNAV_RANK_PREACT (companded output pre-activation). Generated, do not\n"
           " * edit. Made by:\n"
           " *   build/<preset>/tests/target/gen_vector_table > tests/target/vector_table.h\n"
           " * The CTest vector_table_header_matches_its_generator fails when it is stale.\n"
           " */\n",
           (unsigned long)QNAV_VECTORS_NET12_SEED, QNAV_DIST_LEVELS, QNAV_DTHETA_MAX + 1);
    printf("#ifndef QNAV_VECTOR_TABLE_H\n#define QNAV_VECTOR_TABLE_H\n\n");
    printf("#include \"qnav/ctrl.h\"\n#include \"qnav/flash.h\"\n\n");
    printf("#if QNAV_DIST_LEVELS != %d || QNAV_DTHETA_MAX != %d\n", QNAV_DIST_LEVELS,
           QNAV_DTHETA_MAX);
    printf("#error \"vector_table.h was generated for other QNAV_DIST_LEVELS/QNAV_DTHETA_MAX\"\n");
    printf("#endif\n\n");
    if (qnav_ctrl_rank(&ctrl) != QNAV_RANK_PREACT) {
        fprintf(stderr, "gen_vector_table: the default configuration no longer ranks by pre-activation\n");
        return 1;
    }
    printf("#define QNAV_VECTORS_NET12_TABLE_RANK QNAV_RANK_PREACT\n\n");
    printf("static const qnav_qkey_t qnav_vectors_net12_table[QNAV_QTABLE_ENTRIES] QNAV_FLASH = {\n");
    for (i = 0; i < QNAV_QTABLE_ENTRIES; ++i) {
        printf("%s%6d%s", (i % 10u == 0u) ? "   " : "", (int)table[i],
               (i + 1u == QNAV_QTABLE_ENTRIES) ? "\n" : ((i % 10u == 9u) ? ",\n" : ","));
    }
    printf("};\n\n#endif /* QNAV_VECTOR_TABLE_H */\n");
    if (fflush(stdout) != 0 || ferror(stdout)) {
        fprintf(stderr, "gen_vector_table: write error on stdout\n");
        return 1;
    }
    return 0;
}
