#!/bin/sh
# One software-in-the-loop trial on a real udpm:// LCM bus, recorded by lcm-logger. Run
# only inside a private network namespace (the test does `unshare -n sh udpm_trial.sh`):
# loopback up with multicast routed to it, so no packet can leave the machine.
# The robot is paced at 20 ms per tick (not lockstep) so bursts do not overrun the
# logger's UDP socket on a busy machine.
# With QNAV_SPY, qnav-spy --check also watches the trial, on a private Xvfb display
# (Xvfb's abstract socket is private to the namespace; -displayfd picks a free number),
# and its report and window go to DIR/spy.out and DIR/spy.png; the robot is then paced at
# 50 ms so that the trial outlasts the JVM's start. QNAV_SPY "-" (or none) is no spy.
# Further arguments go to the robot, and those after "--" to navbridge; without navbridge
# arguments its goal is the robot's destination (--goal-at, printed by the robot in its
# odometry frame).
# Every wait is on an event (a file written, a line printed, a socket bound or drained, a
# process's exit); the counts in the loops only end a broken run (WAIT_LIMIT, 120 s).
# usage: udpm_trial.sh NAVBRIDGE SIL_ROBOT DIR [QNAV_SPY|- [SIL_ARG... [-- NAVBRIDGE_ARG...]]]
set -u
NB_EXE=$1; SIL_EXE=$2; DIR=$3; SPY=${4:-}
[ "$SPY" = "-" ] && SPY=
[ $# -ge 4 ] && shift 4 || shift $#
SIL_ARGS=""
while [ $# -gt 0 ] && [ "$1" != "--" ]; do SIL_ARGS="$SIL_ARGS $1"; shift; done
[ $# -gt 0 ] && shift
ip link set lo up || exit 10
ip link set lo multicast on || exit 10
ip route add 224.0.0.0/4 dev lo || exit 10
export LCM_DEFAULT_URL="udpm://239.255.76.67:7667?ttl=0"
TICK_MS=20
WAIT_LIMIT=6000   # 20 ms steps
# Wait until command $1 (a string to eval) succeeds.
wait_for() {
    i=0
    until eval "$1"; do
        i=$((i+1)); [ $i -lt $WAIT_LIMIT ] || return 1
        sleep 0.02
    done
}
# lcm-logger's socket on LCM's port: udpm opens it when the logger subscribes
logger_bound() { ss -Huanp 'sport = :7667' | grep -q "pid=$LOGGER,"; }
# its receive queue is empty: everything sent so far is in the logger's hands
logger_drained() { ss -Huanp 'sport = :7667' | grep "pid=$LOGGER," | awk '$2 != 0 {x=1} END {exit x}'; }
if [ -n "$SPY" ]; then
    TICK_MS=50
    Xvfb -displayfd 3 -screen 0 1024x768x24 -nolisten tcp 3> "$DIR/display" 2> "$DIR/xvfb.err" & XVFB=$!
    wait_for '[ -s "$DIR/display" ]' || exit 11
    DISPLAY=:$(cat "$DIR/display") "$SPY" --lcm-url "$LCM_DEFAULT_URL" --check 20 \
        --screenshot "$DIR/spy.png" > "$DIR/spy.out" 2> "$DIR/spy.err" & SPY_PID=$!
fi
lcm-logger -q -f "$DIR/trial.lcmlog" & LOGGER=$!
wait_for logger_bound || exit 12   # subscribed before the trial starts
: > "$DIR/sil.out"   # emptied now: an earlier trial's "link on" must not count
# shellcheck disable=SC2086 # the robot's arguments are words
"$SIL_EXE" --tick-ms $TICK_MS --link "$DIR/link" --pose $SIL_ARGS > "$DIR/sil.out" 2> "$DIR/sil.err" & SIL=$!
# "link on" comes after the link is made and after the destination line
wait_for 'grep -q "link on" "$DIR/sil.out"' || exit 13
if [ $# -eq 0 ]; then
    GOAL=$(sed -n 's/.*--goal-at \([-0-9.:]*\)).*/\1/p' "$DIR/sil.out")
    set -- --goal-at "$GOAL"
fi
"$NB_EXE" --device "$DIR/link" "$@" > "$DIR/nb.out" 2> "$DIR/nb.err" & NB=$!
wait $SIL; SIL_RC=$?
# the robot's pty closes with it: navbridge leaves on its own (status 1)
wait $NB; NB_RC=$?
wait_for logger_drained   # navbridge's last messages are in the logger's socket
kill -INT $LOGGER; wait $LOGGER
SPY_RC=-
if [ -n "$SPY" ]; then
    wait $SPY_PID; SPY_RC=$?
    kill $XVFB 2>/dev/null; wait $XVFB 2>/dev/null
fi
echo "sil=$SIL_RC navbridge=$NB_RC spy=$SPY_RC" > "$DIR/rc.txt"
exit $SIL_RC
