#!/bin/sh
# simevo on a real one-node Slurm cluster (tests/cluster/one_node_slurm.sh, localhost
# only): tiny.toml as a two-stage job array (5 stage-1 tasks, 2 transfers after them with
# afterok) plus a summarize job, waited for with a bounded timeout, then every merged file
# compared (cmp) with a local `simevo run` of the same experiment. Exit 77 (CTest skip) with
# the reason when the cluster cannot be tried (not root, packages missing); a daemon that
# does not come up although it could is a failure (exit 1). Then a sweep (tiny at noise 0.05)
# through its submit.sh: the member's files equal a local `simevo run tiny --vary noise=0.05`.
#   test_slurm.sh SIMEVO SOURCE_DIR
set -u
simevo=$1
src=$2
d=$(mktemp -d /tmp/qnav-slurm-XXXXXX)
. "$src/tests/cluster/one_node_slurm.sh"
trap 'cluster_down; rm -rf "$d"' EXIT
fail() { echo "FAIL: $*" >&2; for f in "$d"/c/*.log "$d"/out/tiny/slurm/*.out; do [ -f "$f" ] && { echo "== $f"; tail -n 5 "$f"; }; done >&2; exit 1; }

cluster_up "$d/c"
rc=$?
[ $rc = 0 ] || exit $rc
echo "cluster up: daemons $CLUSTER_PIDS, $(sinfo -h -o '%P %t %c cpus')"
# slurmd's port follows slurmctld's (it once read an unset variable and got port 1)
ctld_port=$(scontrol show config | sed -n 's/^SlurmctldPort *= *//p')
slurmd_port=$(scontrol show config | sed -n 's/^SlurmdPort *= *//p')
echo "ports: slurmctld $ctld_port, slurmd $slurmd_port"
[ "$slurmd_port" -gt "$ctld_port" ] || fail "slurmd port $slurmd_port is not above slurmctld's $ctld_port"
ss -ltn | awk '{print $4}' | grep -qx "127.0.0.1:$slurmd_port" || fail "nothing listens on 127.0.0.1:$slurmd_port"

export QNAV_DATA_DIR="$src/data"
exp="$src/tests/simevo/tiny.toml"
"$simevo" run "$exp" --out "$d/local" --no-progress -j 2 --tools-dir "$src/tools" >/dev/null || fail "local run"

"$simevo" slurm "$exp" --out "$d/out" --array-limit 2 --time 10 --tools-dir "$src/tools" --submit >"$d/submit.txt" ||
    fail "simevo slurm --submit: $(cat "$d/submit.txt")"
cat "$d/submit.txt"
set -- $(cat "$d/out/tiny/slurm/jobs.txt")   # "STAGE1:STAGE2 SUMMARIZE"
stage1=${1%%:*}; stage2=${1#*:}; summ=$2
[ "$stage1" != "$stage2" ] || fail "no stage-2 array in $d/out/tiny/slurm/jobs.txt"
dep=$(scontrol show job "$stage2" | grep -o 'Dependency=[^ ]*' | head -n 1)
echo "stage 2 job $stage2: $dep"
case $dep in *afterok:$stage1*) ;; *) fail "stage 2 does not depend on stage 1 ($dep)";; esac
n1=$(squeue -h -r -j "$stage1" -o %i | wc -l)
n2=$(squeue -h -r -j "$stage2" -o %i | wc -l)
echo "array tasks: stage 1 $n1, stage 2 $n2"
[ $((n1 + n2)) -ge 4 ] || fail "fewer than 4 array tasks"

cluster_wait_for 300 sh -c "[ -z \"\$(squeue -h -j $stage1,$stage2,$summ 2>/dev/null)\" ]" || fail "jobs not done within 300 s"
grep -q "merged 7 tasks" "$d"/out/tiny/slurm/simevo-summarize-"$summ".out || fail "the summarize job did not merge"
for f in $(cd "$d/local" && find . -type f | sort); do
    cmp -s "$d/local/$f" "$d/out/$f" || fail "differs from the local run: $f"
done
extra=$(cd "$d/out" && find . -type f ! -path './tiny/slurm/*' | sort | while read -r f; do [ -f "$d/local/$f" ] || echo "$f"; done)
[ -z "$extra" ] || fail "files only in the Slurm run: $extra"
echo "PASS: all $(cd "$d/local" && find . -type f | wc -l) files of the Slurm run equal the local run's (cmp); STATUS $(cat "$d/out/tiny/STATUS")"

printf 'name = "sw"\nexperiment = "%s"\n[vary]\nnoise = [0.05]\n' "$exp" > "$d/sw.toml"
"$simevo" run "$exp" --vary noise=0.05 --out "$d/local-sw" --no-progress -j 2 --tools-dir "$src/tools" >/dev/null || fail "local --vary run"
"$simevo" slurm "$d/sw.toml" --out "$d/sw" --array-limit 2 --time 10 --tools-dir "$src/tools" --submit >"$d/submit-sw.txt" ||
    fail "simevo slurm SWEEP --submit: $(cat "$d/submit-sw.txt")"
cat "$d/submit-sw.txt"
cluster_wait_for 300 sh -c '[ -z "$(squeue -h 2>/dev/null)" ]' || fail "sweep jobs not done within 300 s"
"$simevo" summarize "$d/sw/sw" >"$d/summarize-sw.txt" || fail "sweep summarize: $(cat "$d/summarize-sw.txt")"
grep -q "^$d/sw/sw: merged 1 experiment$" "$d/summarize-sw.txt" || fail "sweep summarize: $(cat "$d/summarize-sw.txt")"
m=tiny.noise-0.05
for f in $(cd "$d/local-sw" && find . -type f | sort); do
    cmp -s "$d/local-sw/$f" "$d/sw/$f" || fail "sweep member differs from the local --vary run: $f"
done
echo "PASS: sweep member $m: all $(cd "$d/local-sw" && find . -type f | wc -l) files equal the local --vary run's (cmp)"
