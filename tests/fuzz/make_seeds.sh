#!/bin/sh
# Regenerates tests/fuzz/corpus and tests/fuzz/regress (make_seeds.c) from the source root.
set -eu
cd "$(dirname "$0")/../.."
exe=$(mktemp)
trap 'rm -f "$exe"' EXIT
cc -std=c99 -Ifirmware/include -Ifirmware/src -Ifirmware/link/include \
   -Ifirmware/boards/core/include -Ifirmware/boards/core/src -Ifirmware/boards/tekbot/include \
   -Ifirmware/boards/robots/include \
   -Itests/board tests/fuzz/make_seeds.c tests/board/sim_hal.c firmware/link/src/link.c \
   firmware/boards/core/src/*.c firmware/boards/tekbot/src/tekbot.c firmware/src/*.c -o "$exe"
mkdir -p tests/fuzz/corpus/link tests/fuzz/corpus/board tests/fuzz/corpus/board_store \
         tests/fuzz/regress/link tests/fuzz/regress/board tests/fuzz/regress/board_store
"$exe" tests/fuzz
