#!/bin/sh
# Who may move the robot (docs/hil.md, "Who may move the robot"), shown on a real udpm://
# bus. Run only inside a private network namespace (the test does `unshare -n sh
# goal_trust.sh ...`): loopback up with multicast routed to it, nothing leaves the machine.
#  1. default (goal from the command line, no --lcm-goals): navbridge has no socket on
#     LCM's port; a stray clear-goal and a stray route on QNAV_GOAL / QNAV_WAYPOINTS change
#     nothing (the board keeps reporting goal 1 in every scan) and the robot reaches its
#     destination as before;
#  2. opt-in (--lcm-goals, no goal on the command line): stray goals and routes on the plain
#     channels and on another run's token channel are ignored (20 scans later the board
#     still reports no goal), then the route published on the channel navbridge printed is
#     obeyed and the robot reaches its destination.
# Every wait is on an event (a line printed, a number of scans on the bus, a process's
# exit); the counts only end a broken run. Prints "goal_trust: ok" and exits 0, or one
# "goal_trust: FAIL: ..." line and 1; 77 when loopback multicast cannot be set up.
# usage: goal_trust.sh NAVBRIDGE SIL_ROBOT LCM_POKE DIR
set -u
NB_EXE=$1; SIL_EXE=$2; POKE=$3; DIR=$4
ip link set lo up 2>/dev/null && ip link set lo multicast on && \
    ip route add 224.0.0.0/4 dev lo || exit 77
rm -rf "$DIR" && mkdir -p "$DIR" || exit 1
URL="udpm://239.255.76.67:7667?ttl=0"
export LCM_DEFAULT_URL="$URL"
OTHER_RUN=0123456789abcdef0123456789abcdef

fail() {
    echo "goal_trust: FAIL: $*"
    for f in "$DIR"/*.out "$DIR"/*.err; do echo "--- $f"; cat "$f"; done
    kill ${SIL:-} ${NB:-} 2>/dev/null   # ours, started below
    exit 1
}

# Wait until file $1 holds text $2, while process $3 lives.
wait_text() {
    i=0
    while ! grep -q "$2" "$1" 2>/dev/null; do
        kill -0 "$3" 2>/dev/null || grep -q "$2" "$1" 2>/dev/null || return 1
        i=$((i + 1))
        [ $i -lt 15000 ] || return 1
        sleep 0.02
    done
}

# The SIL robot for case $1, paced at 50 ms per tick (the opt-in case idles for about 25
# of the episode's 300 ticks; the route takes about 170); sets SIL and DEST (its
# destination in the odometry frame, printed before its link exists).
start_robot() {
    "$SIL_EXE" --tick-ms 50 --link "$DIR/$1.link" > "$DIR/$1.sil.out" 2> "$DIR/$1.sil.err" &
    SIL=$!
    wait_text "$DIR/$1.sil.out" "link on" $SIL || fail "$1: the robot did not come up"
    DEST=$(sed -n 's/.*--goal-at \([-0-9.:]*\)).*/\1/p' "$DIR/$1.sil.out")
    [ -n "$DEST" ] || fail "$1: the robot printed no destination"
}

# "scans N with_goal W max_goal_id G" for the next $2 scans, into $DIR/$1.
scans() {
    "$POKE" "$URL" scans "$2" > "$DIR/$1" 2>&1 || fail "$1: fewer than $2 scans on the bus"
}

# The robot's and navbridge's ends: the robot must have reached its destination.
finish() {
    wait $SIL; src=$?
    wait $NB; nrc=$?   # the robot's pty closes with it: navbridge leaves with 1
    [ $src -eq 0 ] && grep -q "reached yes" "$DIR/$1.sil.out" ||
        fail "$1: the robot did not reach its destination (status $src)"
    [ $nrc -eq 1 ] || fail "$1: navbridge ended with $nrc, not 1 (link lost)"
}

# 1. default: goals from the command line only
start_robot default
"$NB_EXE" --device "$DIR/default.link" --goal-at "$DEST" \
    > "$DIR/default.nb.out" 2> "$DIR/default.nb.err" & NB=$!
scans default.before 3
ss -Huanp 'sport = :7667' > "$DIR/default.ss"
grep -q "pid=$NB," "$DIR/default.ss" && fail "default: navbridge listens on LCM's port"
# a clear-goal would stop the robot, a route to its start would turn it back
"$POKE" "$URL" goal QNAV_GOAL 0 0 route QNAV_WAYPOINTS 0:0 0.3 scans 20 \
    > "$DIR/default.after" 2>&1 || fail "default: cannot publish, or fewer than 20 scans"
grep -q "^scans 20 with_goal 20 max_goal_id 1$" "$DIR/default.after" ||
    fail "default: a stray goal reached the board: $(cat "$DIR/default.after")"
finish default

# 2. opt-in: goals from LCM on this run's token channels only
start_robot optin
"$NB_EXE" --device "$DIR/optin.link" --lcm-goals \
    > "$DIR/optin.nb.out" 2> "$DIR/optin.nb.err" & NB=$!
wait_text "$DIR/optin.nb.out" "goals from LCM" $NB || fail "optin: navbridge printed no token"
ROUTE_CH=$(sed -n 's/.* on \(QNAV_WAYPOINTS_[0-9a-f]*\)$/\1/p' "$DIR/optin.nb.out")
[ ${#ROUTE_CH} -eq 47 ] || fail "optin: no 32-digit token channel in: $(cat "$DIR/optin.nb.out")"
scans optin.before 3
"$POKE" "$URL" route QNAV_WAYPOINTS "$DEST" 0.3 goal QNAV_GOAL 9 0 \
    route "QNAV_WAYPOINTS_$OTHER_RUN" "$DEST" 0.3 goal "QNAV_GOAL_$OTHER_RUN" 9 0 scans 20 \
    > "$DIR/optin.after" 2>&1 || fail "optin: cannot publish, or fewer than 20 scans"
grep -q "^scans 20 with_goal 0 max_goal_id 0$" "$DIR/optin.after" ||
    fail "optin: a stray goal reached the board: $(cat "$DIR/optin.after")"
"$POKE" "$URL" route "$ROUTE_CH" "$DEST" 0.3 || fail "cannot publish"
finish optin
grep -q "route 7 of 1 waypoints" "$DIR/optin.nb.err" || fail "optin: navbridge did not log the route"
echo "goal_trust: ok (default: $(cat "$DIR/default.after"); opt-in: $(cat "$DIR/optin.after"))"
