/*
 * Instruction-count benchmark of qnav_ctrl_step() on a Cortex-M4 (QEMU mps2-an386), over
 * the benchmark set (bench_grid.h). The program does not count: it calls
 * qnav_bench_begin() right before and qnav_bench_end() right after each measured step and
 * prints that step's M line, with '-' as its value, after the end marker. The counter
 * (tools/cm4-icount) runs the ELF under QEMU, counts the instructions executed between the
 * k-th begin and end, and replaces the k-th '-' with the count. Tables are compiled into
 * RAM for every 2-input network (no flash limit here). Exit status 1 on a heading mismatch.
 */
#include <stdint.h>

#include "bench_grid.h"
#include "cm4_markers.h"
#include "target_io.h"

static uint32_t measure(const qnav_ctrl_t *ctrl, const qnav_ctrl_input_t *in,
                        qnav_ctrl_output_t *out, uint8_t mode)
{
    (void)mode;
    qnav_bench_begin();
    qnav_ctrl_step(ctrl, in, out, 0);
    qnav_bench_end();
    return 0;
}

int main(void)
{
    qnav_bench_hooks_t hooks;
    uint16_t bad;
    hooks.target = "cm4";
    hooks.sep = '\t';
    hooks.modes = (uint8_t)(QNAV_BENCH_MODE_BIT(QNAV_BENCH_NETWORK) | QNAV_BENCH_MODE_BIT(QNAV_BENCH_PROB) |
                            QNAV_BENCH_MODE_BIT(QNAV_BENCH_TABLE) |
                            QNAV_BENCH_MODE_BIT(QNAV_BENCH_NETWORK3));
    hooks.measure = measure;
    hooks.has_value = 0;
    hooks.table = qnav_bench_ram_table;
    qnav_target_put("qnav Cortex-M4 benchmark: QEMU mps2-an386; values are instructions between "
                    "qnav_bench_begin() and qnav_bench_end() (tools/cm4-icount)\n");
    qnav_target_put("sizeof(qnav_ctrl_t) ");
    qnav_target_put_u32(sizeof(qnav_ctrl_t));
    qnav_target_put(" bytes\n");
    bad = qnav_bench_grid(&hooks);
    if (bad != 0u) {
        qnav_target_put("MISMATCH count ");
        qnav_target_put_u32(bad);
        qnav_target_put("\n");
    }
    qnav_target_exit(bad ? 1u : 0u);
    return 0;
}
