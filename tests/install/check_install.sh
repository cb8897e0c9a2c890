#!/bin/sh
# The installed tree, as a user gets it (docs/install.md). Usage:
#   check_install.sh install   BUILD PREFIX            cmake --install BUILD into a fresh PREFIX
#   check_install.sh programs  PREFIX WORK             moved elsewhere, run from /, no QNAV_* set
#   check_install.sh host      PREFIX WORK SRC CMAKE   examples/host-app via find_package(qnav)
#   check_install.sh pkgconfig PREFIX WORK SRC         examples/host-app/main.c via qnav.pc
#   check_install.sh avr       PREFIX WORK SRC CMAKE   examples/avr-firmware, installed toolchain
#   check_install.sh version   PREFIX WORK SRC CMAKE   find_package(qnav X.Y) by semantic versioning
# Every check fails loudly (set -e, explicit comparisons); nothing outside WORK is written.
set -eu
mode=$1
fail() { echo "check_install.sh $mode: $*" >&2; exit 1; }
unset QNAV_DATA_DIR QNAV_EXPERIMENTS_DIR QNAV_TOOLS_DIR || true

case "$mode" in
install)
    build=$2 prefix=$3
    rm -rf "$prefix"
    cmake --install "$build" --prefix "$prefix" >/dev/null
    for f in bin/simevo bin/qnav-sim bin/qnav-policy bin/navbridge bin/qnav-sil-robot \
             include/qnav/ctrl.h include/qnav/link.h include/qnav/policy_io.h include/qnav/sim.h \
             lib/libqnav_ctrl.a lib/libqnav_sim.a lib/cmake/qnav/qnavConfig.cmake \
             lib/pkgconfig/qnav.pc share/qnav/data/envs/dense.toml \
             share/qnav/experiments/open-to-dense.toml share/qnav/tools/plot_learning.py \
             share/qnav/firmware/CMakeLists.txt share/qnav/cmake/toolchain-avr-atmega128.cmake; do
        [ -e "$prefix/$f" ] || fail "$f not installed"
    done
    for f in bin/qnav-spy share/qnav/python/qnav/goal_t.py share/qnav/java/qnav_lcmtypes.jar \
             share/qnav/sweeps/open-to-dense-noise.toml; do
        [ -e "$prefix/$f" ] || fail "$f not installed"
    done
    if [ -e "$build/firmware/boards/tekbot-avr.elf" ]; then
        [ -e "$prefix/share/qnav/boards/tekbot-avr.elf" ] || fail "tekbot-avr.elf not installed"
    fi
    ;;
programs)
    prefix=$2 work=$3
    rm -rf "$work" && mkdir -p "$work"
    # moved after installing: programs find share/qnav beside their own bin/
    cp -a "$prefix" "$work/moved"
    p=$work/moved
    sed 's/^name = "open"/name = "only-installed"/' "$p/share/qnav/data/envs/open.toml" \
        > "$p/share/qnav/data/envs/only-installed.toml"
    cd /
    "$p/bin/qnav-sim" run --env only-installed --robot tekbot --episodes 1 > "$work/sim.out"
    grep -q "env only-installed" "$work/sim.out" || fail "qnav-sim did not read the installed data"
    n=$("$p/bin/simevo" list | wc -l)
    [ "$n" -eq "$(ls "$p/share/qnav/experiments" | grep -c '\.toml$')" ] || fail "simevo list: $n experiments"
    # docs/simevo.md's sweep line from elsewhere: sweeps/ comes from the share folder
    "$p/bin/simevo" slurm sweeps/open-to-dense-noise.toml --out "$work/sweep" > "$work/sweep.out"
    grep -q "experiments; submit them all with" "$work/sweep.out" || fail "simevo did not find the installed sweep"
    "$p/bin/simevo" quality prob --out "$work/quality" > "$work/quality.out"
    head -c 8 "$work/quality/policy.png" | od -An -c | grep -q 'P   N   G' || fail "no policy.png from the installed plot script"
    v=$(cat "$p/share/qnav/VERSION")
    [ "$(/usr/bin/python3 "$p/share/qnav/tools/plot_policy.py" --version)" = "plot_policy.py (qnav) $v" ] || fail "plot script version"
    [ "$("$p/bin/qnav-policy" --version)" = "qnav-policy (qnav) $v" ] || fail "qnav-policy version"
    # the installed log tool finds the installed Python LCM types by itself
    "$p/bin/qnav-sil-robot" --version > /dev/null
    /usr/bin/python3 "$p/share/qnav/tools/qnav_log.py" --help > /dev/null
    [ -f "$p/share/qnav/python/qnav/pose_t.py" ] || fail "Python LCM types not installed"
    [ -f "$p/share/qnav/java/qnav_lcmtypes.jar" ] || fail "Java LCM types not installed"
    [ "$("$p/bin/qnav-spy" --version)" = "qnav-spy (qnav) $v" ] || fail "qnav-spy version"
    if "$p/bin/qnav-spy" --check 1 --types-jar /nonexistent.jar 2>/dev/null; then fail "qnav-spy took a missing jar"; fi
    ;;
host)
    prefix=$2 work=$3 src=$4 cmake=$5
    rm -rf "$work"
    "$cmake" -S "$src/examples/host-app" -B "$work" -G Ninja -DCMAKE_PREFIX_PATH="$prefix" >/dev/null
    "$cmake" --build "$work" >/dev/null
    "$work/qnav-example" > "$work/out.txt"
    cat "$work/out.txt"
    grep -q '^fixed scan: heading -\{0,1\}[0-9]* speed [0-9]*$' "$work/out.txt" || fail "no decision"
    grep -q '^episode: reached yes' "$work/out.txt" || fail "the episode did not reach"
    grep '^fixed scan:' "$work/out.txt" > "$work/../host-decision.txt"
    ;;
pkgconfig)
    prefix=$2 work=$3 src=$4
    rm -rf "$work" && mkdir -p "$work"
    export PKG_CONFIG_PATH="$prefix/lib/pkgconfig"
    [ "$(pkg-config --modversion qnav)" = "$(cat "$prefix/share/qnav/VERSION")" ] || fail "version"
    # shellcheck disable=SC2046
    cc -std=c99 -Wall -Wextra -Werror -o "$work/qnav-example" "$src/examples/host-app/main.c" \
        $(pkg-config --cflags qnav) $(pkg-config --static --libs qnav)
    "$work/qnav-example" "$prefix/share/qnav" > "$work/out.txt"
    grep -q '^episode: reached yes' "$work/out.txt" || fail "the episode did not reach"
    ;;
avr)
    prefix=$2 work=$3 src=$4 cmake=$5
    rm -rf "$work"
    "$cmake" -S "$src/examples/avr-firmware" -B "$work" -G Ninja -DCMAKE_BUILD_TYPE=Release \
        -DQNAV_PREFIX="$prefix" \
        -DCMAKE_TOOLCHAIN_FILE="$prefix/share/qnav/cmake/toolchain-avr-atmega128.cmake" >/dev/null
    "$cmake" --build "$work" >/dev/null
    # add_subdirectory(firmware) builds the libraries, not qnav's own TekBot image
    if find "$work" -name 'tekbot*.elf' | grep -q .; then fail "the TekBot image was built unasked"; fi
    grep -q 'static QNAV_FLASH const qnav_qkey_t nav_table' "$work/nav_table.h" || fail "no table header"
    "$prefix/share/qnav/cmake/run-simavr" "$work/nav-example.elf" > "$work/out.txt"
    cat "$work/out.txt"
    # the ATmega128 decides exactly as the host did on the same scan
    cmp "$work/out.txt" "$work/../host-decision.txt" || fail "AVR and host decisions differ"
    ;;
version)
    prefix=$2 work=$3 src=$4 cmake=$5
    rm -rf "$work" && mkdir -p "$work"
    v=$(cat "$prefix/share/qnav/VERSION")
    major=${v%%.*} rest=${v#*.}
    minor=${rest%%.*}
    # find_package(qnav REQUEST CONFIG REQUIRED) in a fresh project: 0 when it accepts
    accepts() {
        d="$work/request-$1"
        mkdir -p "$d"
        printf 'cmake_minimum_required(VERSION 3.25)\nproject(version_check LANGUAGES C CXX)\nfind_package(qnav %s CONFIG REQUIRED)\n' \
            "$1" > "$d/CMakeLists.txt"
        "$cmake" -S "$d" -B "$d/build" -G Ninja -DCMAKE_PREFIX_PATH="$prefix" > "$d/cmake.out" 2>&1
    }
    accepts "$v" || fail "find_package(qnav $v) refused the installed $v: $(tail -n 3 "$work/request-$v/cmake.out")"
    accepts "$major.$minor" || fail "find_package(qnav $major.$minor) refused the installed $v"
    if accepts "$major.$((minor + 1))"; then fail "find_package(qnav $major.$((minor + 1))) took the older $v"; fi
    if accepts "$((major + 1)).0"; then fail "find_package(qnav $((major + 1)).0) took $v"; fi
    if [ "$major" -eq 0 ]; then
        # before 1.0 a minor release may break the API: 0.(Y-1) is not 0.Y
        if [ "$minor" -gt 0 ] && accepts "0.$((minor - 1))"; then fail "find_package(qnav 0.$((minor - 1))) took $v"; fi
    elif [ "$minor" -gt 0 ]; then
        accepts "$major.0" || fail "find_package(qnav $major.0) refused $v (same major version)"
    fi
    # a project written for 0.1 calls qnav_ctrl_init_table() without its rank (CHANGELOG.md)
    if accepts 0.1; then fail "find_package(qnav 0.1) took $v, whose API differs"; fi
    # the newest version CHANGELOG.md describes is this one
    newest=$(sed -n 's/^## \([0-9][0-9.]*\) .*/\1/p' "$src/CHANGELOG.md" | head -n 1)
    [ "$newest" = "$v" ] || fail "CHANGELOG.md's newest entry is '$newest', VERSION says $v"
    echo "find_package(qnav ...) against $v: $v and $major.$minor accepted; $major.$((minor + 1)), $((major + 1)).0 and 0.1 refused"
    ;;
*)
    fail "unknown mode"
    ;;
esac
