#!/usr/bin/env bash
# caustic's Whitted integrator against POV-Ray 3.7 on the Whitted benchmark scene
# (benches/scenes/whitted.toml and scripts/povray/whitted.pov: 512 x 512, 16 samples per pixel,
# depth 6, a mirror and a Fresnel-glass sphere, two point lights). Both renderers run
# alternately, back to back, so both see the same machine load; each run's wall time is that
# of the whole process (start, parse, render, PNG written). Prints every time, the medians and
# caustic's median over POV-Ray's; exits 0 when that is at most 1/3 (issue 15's target).
#
#   scripts/povray_whitted.sh [caustic binary, default target/release/caustic] [runs, default 5]
#
# Needs POV-Ray 3.7 (`apt-get install povray`).
set -euo pipefail
shopt -s inherit_errexit
export LC_ALL=C
root=$(cd "$(dirname "$0")/.." && pwd)
caustic=$(realpath -e "${1:-$root/target/release/caustic}")
command -v povray >/dev/null || { echo "povray not found (apt-get install povray)" >&2; exit 2; }
runs=${2:-5}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cp "$root/scripts/povray/whitted.pov" "$work/"
cd "$work"

wall() { # command... -> wall seconds of the whole process; a failed run stops the script
    local t0 t1
    t0=$(date +%s.%N)
    "$@" >/dev/null 2>&1 || { echo "failed: $*" >&2; return 1; }
    t1=$(date +%s.%N)
    echo "$t1 - $t0" | bc -l
}

pov=() ours=()
for _ in $(seq "$runs"); do
    pov+=("$(wall povray +Iwhitted.pov +W512 +H512 +A0.0 +AM1 +R4 -J +FN +Opov.png -D)")
    ours+=("$(wall "$caustic" render "$root/benches/scenes/whitted.toml" -q -o caustic.png)")
done
median() { printf '%s\n' "$@" | sort -n | awk '{a[NR]=$1} END {print (NR % 2) ? a[(NR+1)/2] : (a[NR/2] + a[NR/2+1]) / 2}'; }
mp=$(median "${pov[@]}")
mc=$(median "${ours[@]}")
printf 'POV-Ray 3.7: %s s (median %.3f s)\n' "$(printf '%.3f ' "${pov[@]}")" "$mp"
printf 'caustic:     %s s (median %.3f s)\n' "$(printf '%.3f ' "${ours[@]}")" "$mc"
ratio=$(echo "$mc / $mp" | bc -l)
printf 'caustic / POV-Ray: %.3f (target: at most 1/3)\n' "$ratio"
[ "$(echo "$ratio <= 1/3" | bc -l)" = 1 ]
