/*
 * libFuzzer target: the policy file reader (host/policyio), format versions 1 and 2. The
 * input is a file's text. Properties beyond "no crash, no sanitizer report": a refused
 * file gets a one-line message that names the file ("fuzz.policy:"); an accepted one is
 * written back with qnav_policy_format and read again to the same policy and metadata
 * (whatever the reader takes, the writer can say, and means the same).
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "qnav/policy_io.h"

static char g_text[256 * 1024];

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    qnav_policy_t p, back;
    qnav_policy_meta_t meta, meta_back;
    char err[512];
    int n;
    memset(&p, 0, sizeof p);
    memset(&back, 0, sizeof back);
    qnav_policy_meta_clear(&meta);
    qnav_policy_meta_clear(&meta_back);
    if (qnav_policy_parse_meta((const char *)data, size, "fuzz.policy", &p, &meta, err,
                               sizeof err) != 0) {
        if (strncmp(err, "fuzz.policy", 11) != 0 || strchr(err, '\n') != NULL) {
            abort(); /* errors name the file, on one line */
        }
        return 0;
    }
    n = qnav_policy_format(&p, &meta, NULL, g_text, sizeof g_text, err, sizeof err);
    if (n < 0 || (size_t)n >= sizeof g_text) {
        abort(); /* the reader took a policy the writer refuses */
    }
    if (qnav_policy_parse_meta(g_text, (size_t)n, "again.policy", &back, &meta_back, err,
                               sizeof err) != 0) {
        abort(); /* the writer wrote a file the reader refuses */
    }
    if (memcmp(&p, &back, sizeof p) != 0 || meta.count != meta_back.count ||
        memcmp(meta.entry, meta_back.entry, sizeof meta.entry[0] * meta.count) != 0) {
        abort();
    }
    return 0;
}
