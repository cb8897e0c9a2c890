#!/bin/sh
# The README's, docs/hil.md's, docs/cluster.md's and docs/python.md's example blocks, run verbatim (docs.examples_run_verbatim):
# each block marked `<!-- doc-example: NAME ... -->` is extracted, written to WORK/NAME.sh
# and run with sh in WORK (a fresh folder) with the installed tree PREFIX/bin on PATH and
# no QNAV_* variables, inside a private network namespace (loopback up, multicast routed to
# it: LCM's default udpm:// bus cannot leave the machine; DESIGN.md section 7), then checks
# what each command should have left behind. Exit 0, 1 (a check failed, named on stderr),
# 77 (no private network namespace here: skipped).
# usage: run_examples.sh PREFIX SRC WORK   (run as: unshare -n sh run_examples.sh ...)
set -u
prefix=$(cd "$1" && pwd) src=$(cd "$2" && pwd) work=$3
ip link set lo up || exit 77
ip link set lo multicast on || exit 77
ip route add 224.0.0.0/4 dev lo || exit 77
unset QNAV_DATA_DIR QNAV_EXPERIMENTS_DIR QNAV_TOOLS_DIR LCM_DEFAULT_URL || true
export PATH="$prefix/bin:$PATH"
rm -rf "$work" && mkdir -p "$work"
extract() { # FILE NAME -> the fenced block after the marker
    awk -v name="$2" '
        index($0, "<!-- doc-example: " name " ") == 1 || $0 == "<!-- doc-example: " name " -->" { want = 1; next }
        want && /^```/ { if (inside) exit; inside = 1; next }
        inside { print }' "$1"
}
for pair in "$src/README.md readme" "$src/docs/hil.md hil-sil" "$src/docs/cluster.md cluster-parallel" \
            "$src/docs/cluster.md cluster-sweep" "$src/README.md readme-python" "$src/docs/python.md python-quick"; do
    set -- $pair
    extract "$1" "$2" > "$work/$2.sh"
    [ -s "$work/$2.sh" ] || { echo "run_examples.sh: no block '$2' in $1" >&2; exit 1; }
    echo "== $2" >> "$work/status.txt"
    (cd "$work" && sh -x "./$2.sh" > "$work/$2.out" 2> "$work/$2.err"; echo "exit $?" >> "$work/status.txt"; wait)
done

fail() { echo "run_examples.sh: $*" >&2; for f in "$work"/*.err; do echo "--- $f"; tail -n 5 "$f"; done >&2; exit 1; }
r=$work/runs
[ "$(grep -c '^exit 0$' "$work/status.txt")" -eq 6 ] || fail "a block failed: $(tr '\n' ' ' < "$work/status.txt")"
[ "$(grep -c ' Fig\. ' "$work/readme.out")" -eq "$(grep -l '^figure = ' "$src"/experiments/*.toml | wc -l)" ] || fail "simevo list"
[ -s "$r/q/open-to-dense/summary.md" ] || fail "no summary.md from simevo run"
head -c 4 "$r/q/open-to-dense/learning.png" | grep -q PNG || fail "no learning.png"
head -c 5 "$r/episode.svg" | grep -q '<?xml' && grep -q '</svg>' "$r/episode.svg" || fail "no complete episode.svg"
grep -q 'nav_table\[QNAV_QTABLE_ENTRIES\]' "$r/nav_table.h" || fail "no table header"
grep -q '^qnav-sil-robot: episode done: ' "$work/readme.out" || fail "the README's SIL trial did not run"
grep -q 'device hung up: link lost' "$work/readme.err" || fail "navbridge did not follow the trial to its end"
grep -q '^replay: \([0-9]*\) scans, \1 commands compared: \1 identical, 0 differ' "$work/hil-sil.out" \
    || fail "hil.md's replay is not identical"
[ ! -e "$r/qnav-link" ] || fail "the pty link outlived the trial"
grep -q '^open-to-dense: merged 11 tasks; summary runs/gp/open-to-dense/summary.md$' "$work/cluster-parallel.out" \
    || fail "cluster.md's GNU parallel shares were not merged"
grep -q '^complete$' "$r/gp/open-to-dense/STATUS" || fail "cluster.md's merged experiment is not complete"
grep -q '^runs/sw/noise: merged 2 experiments$' "$work/cluster-sweep.out" || fail "cluster.md's sweep was not merged"
grep -q '^identical$' "$work/cluster-sweep.out" || fail "cluster.md's sweep member differs from the experiment run directly"
grep -q '^vary = noise=0.05$' "$r/sw/open-to-dense.noise-0.05/run.txt" || fail "the sweep member's run.txt has no variation"
# qnavpy: evaluate's mean R is simevo eval's (README), the quick start's too (docs/python.md)
py_r=$(sed -n 's/^mean R \([-0-9.]*\)$/\1/p' "$work/readme-python.out")
[ -n "$py_r" ] && [ "$py_r" = "$(sed -n 's/^episodes 20  mean R \([-0-9.]*\) .*/\1/p' "$work/readme-python.out")" ] \
    || fail "the README's qnavpy.evaluate differs from simevo eval"
grep -q '^stepped: [0-9]* ticks, reached True R [-0-9.]*$' "$work/python-quick.out" || fail "python.md's stepped episode"
[ "$(sed -n 's/^evaluate: mean R \([-0-9.]*\),.*/\1/p' "$work/python-quick.out")" = \
  "$(sed -n 's/^episodes 20  mean R \([-0-9.]*\) .*/\1/p' "$work/python-quick.out")" ] \
    || fail "python.md's evaluate differs from simevo eval"
head -c 4 "$r/py/trajectory.png" | grep -q PNG || fail "python.md's example drew no trajectory.png"
[ -s "$r/py/best.policy" ] || fail "python.md's example wrote no best.policy"
echo "run_examples.sh: README, docs/hil.md, docs/cluster.md and docs/python.md examples ran verbatim"
