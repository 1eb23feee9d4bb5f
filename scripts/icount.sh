#!/usr/bin/env bash
# Instructions of one render, for speed work on a machine that is not quiet (BENCHMARKS.md): the
# whole process under callgrind on one thread, in millions. The image goes to /tmp/ic-NAME.exr,
# to compare two binaries' images bit for bit.
#
#   scripts/icount.sh BIN NAME SCENE [RENDER ARGS...]
#   scripts/icount.sh target/release/caustic vcm13 scenes/13-cornell-caustics.toml --integrator vcm \
#       --iterations 4 --width 128 --height 128
set -euo pipefail
bin=$1 name=$2
shift 2
valgrind --tool=callgrind --callgrind-out-file=/dev/null "$bin" render "$@" --threads 1 -q -o "/tmp/ic-$name.exr" 2>&1 \
  | awk '/refs:/ { gsub(",", "", $4); printf "%.1f\n", $4 / 1e6 }'
