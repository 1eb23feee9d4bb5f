#!/usr/bin/env bash
# Equal-time comparison of the path tracer, photon mapping, SPPM, bidirectional path tracing and
# VCM on four scenes (a caustic, a glossy, a sky-lit one, and glossy caustics: a caustic seen in
# a metal floor and light through glass onto a rough plastic table): each integrator renders for
# the same wall time, and the RMSE against a long reference says which to pick for which kind of
# scene (BENCHMARKS.md). Run it on a quiet machine (nothing else building, testing or
# rendering; record the load average), or the figures measure the load.
#
#   scripts/equal_time.sh [SECONDS] [OUT_DIR]
#   INTEGRATORS="bdpt vcm" scripts/equal_time.sh 10     (a subset; INTEGRATORS= only makes the references)
#   CPU=1 scripts/equal_time.sh 10     (equal CPU time on one thread each: for a machine that is
#                                       not quiet, where wall time measures the load)
#   SEEDS="1 2 3" scripts/equal_time.sh 10   (wall time only: one render per seed, and the RMSE
#                                       column the root mean square of theirs; default seed 0)
#
# References are long renders made once into OUT_DIR, with another seed than the renders:
# - SPPM for the point-light caustics, which the path tracer cannot find, at 20,000 iterations
#   (about 9 minutes; at 1,000 its noise and bias were as large as the 10-s errors it scored);
# - bidirectional path tracing, unbiased, for the glossy caustics of a small area light, at most
#   REF_TIME seconds, default 3600;
# - the path tracer elsewhere.
# Needs the OpenEXR Python bindings.
set -euo pipefail
T=${1:-10}
OUT=${2:-/tmp/caustic-equal-time}
BIN=${BIN:-target/release/caustic}
mkdir -p "$OUT"
# name | scene | size | reference integrator and options
scenes=(
  "caustic|scenes/13-cornell-caustics.toml|--width 128 --height 128|--integrator sppm --spp 20000 --photons-per-iter 100000"
  "glossy|scenes/15-materials.toml|--width 160 --height 120|--integrator path --spp 4096"
  "sky|benches/scenes/sky-lit.toml|--width 160 --height 120|--integrator path --spp 8192"
  "glossy-caustics|scenes/16-glossy-caustics.toml|--width 160 --height 120|--integrator bdpt --spp 16384 --time ${REF_TIME:-3600}"
)
INTEGRATORS=${INTEGRATORS-path photon sppm bdpt vcm}
# User + system CPU seconds of a command (its output discarded).
cpu_seconds() { /usr/bin/time -f '%U %S' "$@" 2>&1 >/dev/null | tail -1 | awk '{print $1 + $2}'; }
printf 'load average before: %s\n\n' "$(cut -d' ' -f1-3 /proc/loadavg)"
printf '| scene | integrator | samples in %s s%s | RMSE | mean / reference |\n|---|---|---|---|---|\n' "$T" "${CPU:+ of CPU, one thread}"
for entry in "${scenes[@]}"; do
  IFS='|' read -r name scene size ref <<<"$entry"
  if [[ ! -f "$OUT/$name-ref.exr" ]]; then
    # Another seed than the renders compared (seed 0): an SPPM or bdpt render must not share its
    # first samples with its reference.
    # shellcheck disable=SC2086
    "$BIN" render "$scene" $size $ref --seed 7 -q -o "$OUT/$name-ref.exr"
  fi
  for integrator in $INTEGRATORS; do
    if [[ -n "${CPU:-}" ]]; then
      # Equal CPU time: one thread, as many samples as fit T CPU-seconds by two probes (the cost
      # is a fixed part, such as photon maps, plus a part per sample).
      # shellcheck disable=SC2086
      p1=$(cpu_seconds "$BIN" render "$scene" $size --integrator "$integrator" --threads 1 --spp 4 -q -o "$OUT/probe.exr")
      # shellcheck disable=SC2086
      p2=$(cpu_seconds "$BIN" render "$scene" $size --integrator "$integrator" --threads 1 --spp 12 -q -o "$OUT/probe.exr")
      n=$(python3 -c "a, b = $p1, $p2; per = max((b - a) / 8, 1e-4); print(max(1, int(($T - max(a - 4 * per, 0)) / per)))")
      # shellcheck disable=SC2086
      used=$(cpu_seconds "$BIN" render "$scene" $size --integrator "$integrator" --threads 1 --spp "$n" -q \
        -o "$OUT/$name-$integrator.exr")
      samples="$n in $used CPU-s"
      images=("$OUT/$name-$integrator.exr")
    else
      images=()
      samples=""
      for seed in ${SEEDS:-0}; do
        image="$OUT/$name-$integrator-$seed.exr"
        # shellcheck disable=SC2086
        "$BIN" render "$scene" $size --integrator "$integrator" --spp 100000 --time "$T" --seed "$seed" -o "$image" \
          2>"$OUT/$name-$integrator.log" >/dev/null
        samples+="$(grep -oE '([0-9]+ samples per pixel|took [0-9]+ iterations)' "$OUT/$name-$integrator.log" | tail -1 | grep -oE '[0-9]+' || true) "
        images+=("$image")
      done
      samples="$samples(${SEEDS:+seeds $SEEDS; }samples per pixel or iterations)"
    fi
    python3 - "$OUT/$name-ref.exr" "$name" "$integrator" "$samples" "${images[@]:-$OUT/$name-$integrator.exr}" <<'PY'
import sys
sys.path.insert(0, "scripts")
from rmse import read_rgb
import numpy as np
r = read_rgb(sys.argv[1])
lum = lambda x: (x * [0.2126, 0.7152, 0.0722]).sum(-1).mean()
mse = [((read_rgb(f) - r) ** 2).mean() for f in sys.argv[5:]]
means = [lum(read_rgb(f)) / lum(r) for f in sys.argv[5:]]
each = " (" + ", ".join(f"{np.sqrt(m):.4f}" for m in mse) + ")" if len(mse) > 1 else ""
print(f"| {sys.argv[2]} | {sys.argv[3]} | {sys.argv[4]} | {np.sqrt(np.mean(mse)):.4f}{each} | {np.mean(means):.3f} |")
PY
  done
done
printf '\nload average after: %s\n' "$(cut -d' ' -f1-3 /proc/loadavg)"
