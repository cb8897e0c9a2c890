#!/bin/sh
# One software-in-the-loop trial on a real udpm:// LCM bus, recorded by lcm-logger. Run
# only inside a private network namespace (the test does `unshare -n sh udpm_trial.sh`):
# loopback up with multicast routed to it, so no packet can leave the machine.
# The robot is paced at 20 ms per tick (not lockstep) so bursts do not overrun the
# logger's UDP socket on a busy machine.
# usage: udpm_trial.sh NAVBRIDGE SIL_ROBOT DIR [SIL_ARG... -- NAVBRIDGE_ARG...]
# Without navbridge arguments the goal is the robot's destination (--goal-at, printed by
# the robot in its odometry frame).
set -u
NB_EXE=$1; SIL_EXE=$2; DIR=$3
shift 3
SIL_ARGS=""
while [ $# -gt 0 ] && [ "$1" != "--" ]; do SIL_ARGS="$SIL_ARGS $1"; shift; done
[ $# -gt 0 ] && shift
ip link set lo up || exit 10
ip link set lo multicast on || exit 10
ip route add 224.0.0.0/4 dev lo || exit 10
export LCM_DEFAULT_URL="udpm://239.255.76.67:7667?ttl=0"
lcm-logger -q -f "$DIR/trial.lcmlog" & LOGGER=$!
# shellcheck disable=SC2086 # the robot's arguments are words
"$SIL_EXE" --tick-ms 20 --link "$DIR/link" --pose $SIL_ARGS > "$DIR/sil.out" 2> "$DIR/sil.err" & SIL=$!
i=0
while [ ! -e "$DIR/link" ] && [ $i -lt 100 ]; do sleep 0.05; i=$((i+1)); done
sleep 0.3   # lcm-logger subscribed before the trial starts
if [ $# -eq 0 ]; then
    # the robot prints its destination in the odometry frame before making the link
    GOAL=$(sed -n 's/.*--goal-at \([-0-9.:]*\)).*/\1/p' "$DIR/sil.out")
    set -- --goal-at "$GOAL"
fi
"$NB_EXE" --device "$DIR/link" "$@" > "$DIR/nb.out" 2> "$DIR/nb.err" & NB=$!
wait $SIL; SIL_RC=$?
# the robot's pty closes with it: navbridge leaves on its own (status 1); guard 5 s
( sleep 5; kill -TERM $NB 2>/dev/null ) & GUARD=$!
wait $NB; NB_RC=$?
kill $GUARD 2>/dev/null
sleep 0.3
kill -INT $LOGGER; wait $LOGGER
echo "sil=$SIL_RC navbridge=$NB_RC" > "$DIR/rc.txt"
exit $SIL_RC
