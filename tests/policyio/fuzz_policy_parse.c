/*
 * libFuzzer harness for the policy reader: any byte string must give either a policy the
 * controller accepts or a one-line "NAME:LINE: problem" message, without crashing or
 * reading out of bounds. Not part of CTest (it needs clang); run it by hand, e.g.
 *   clang -g -O1 -fsanitize=fuzzer,address,undefined -Ifirmware/include
 *     -Ihost/policyio/include tests/policyio/fuzz_policy_parse.c host/policyio/src/policy_io.c
 *     firmware/src/ctrl.c firmware/src/policy.c firmware/src/sigmoid_lut.c -o /tmp/fuzz_policy
 *   /tmp/fuzz_policy -max_total_time=60 tests/policyio/good tests/policyio/bad
 */
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "qnav/ctrl.h"
#include "qnav/policy_io.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    qnav_policy_t p;
    qnav_policy_meta_t meta;
    char err[QNAV_POLICY_IO_ERRLEN];
    if (qnav_policy_parse_meta((const char *)data, size, "f", &p, &meta, err, sizeof err) == 0) {
        qnav_ctrl_t ctrl;
        qnav_ctrl_config_t cfg;
        qnav_ctrl_config_default(&cfg);
        if (qnav_policy_check(&p, err, sizeof err) != 0 ||
            qnav_ctrl_init(&ctrl, &cfg, &p) != QNAV_OK) {
            abort();
        }
        {
            /* what was accepted must render and read back to the same policy */
            char buf[16384];
            qnav_policy_t q;
            int n = qnav_policy_format(&p, &meta, NULL, buf, sizeof buf, err, sizeof err);
            if (n < 0 || (size_t)n >= sizeof buf ||
                qnav_policy_parse(buf, (size_t)n, "r", &q, err, sizeof err) != 0 ||
                !qnav_policy_equal(&p, &q)) {
                abort();
            }
        }
    } else if (strncmp(err, "f:", 2) != 0 || strchr(err, '\n') != NULL) {
        abort();
    }
    return 0;
}
