#!/usr/bin/env bash
# caustic's Whitted integrator against POV-Ray 3.7 on the Whitted comparison scenes: the benchmark
# scene caustic was tuned on (benches/scenes/whitted.toml: a floor plane, a mirror and a
# Fresnel-glass sphere, two point lights, depth 6) and three it was not (issue 29):
# whitted-rects (rectangles instead of the plane, depth 5), whitted-lights (four coloured lights,
# boxes, five spheres) and whitted-mesh (a 5,120-triangle mesh); each as a TOML scene in
# benches/scenes and its POV-Ray twin in scripts/povray, 512 x 512, 16 samples per pixel. Both
# renderers run alternately, back to back, so both see the same machine load; each run's wall
# time is that of the whole process (start, parse, render, PNG written). Prints every time, the
# medians and caustic's median over POV-Ray's per scene; exits 0 when every ratio is at most 1/3.
#
#   scripts/povray_whitted.sh [caustic binary, default target/release/caustic] [runs, default 5] [scene...]
#
# Needs POV-Ray 3.7 (`apt-get install povray`) and python3 (the mesh's POV-Ray include is written
# from its PLY by scripts/ply_to_pov.py).
set -euo pipefail
shopt -s inherit_errexit
export LC_ALL=C
root=$(cd "$(dirname "$0")/.." && pwd)
caustic=$(realpath -e "${1:-$root/target/release/caustic}")
command -v povray >/dev/null || { echo "povray not found (apt-get install povray)" >&2; exit 2; }
runs=${2:-5}
shift $(( $# < 2 ? $# : 2 ))
scenes=("$@")
[ ${#scenes[@]} -gt 0 ] || scenes=(whitted whitted-rects whitted-lights whitted-mesh)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cp "$root"/scripts/povray/whitted*.pov "$work/"
python3 "$root/scripts/ply_to_pov.py" "$root/scenes/meshes/blob.ply" Blob >"$work/blob.inc"
cd "$work"

wall() { # command... -> wall seconds of the whole process; a failed run stops the script
    local t0 t1
    t0=$(date +%s.%N)
    "$@" >/dev/null 2>&1 || { echo "failed: $*" >&2; return 1; }
    t1=$(date +%s.%N)
    echo "$t1 - $t0" | bc -l
}
median() { printf '%s\n' "$@" | sort -n | awk '{a[NR]=$1} END {print (NR % 2) ? a[(NR+1)/2] : (a[NR/2] + a[NR/2+1]) / 2}'; }

echo "load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
ok=1
for scene in "${scenes[@]}"; do
    pov=() ours=()
    for _ in $(seq "$runs"); do
        pov+=("$(wall povray "+I$scene.pov" +W512 +H512 +A0.0 +AM1 +R4 -J +FN +Opov.png -D)")
        ours+=("$(wall "$caustic" render "$root/benches/scenes/$scene.toml" -q -o caustic.png)")
    done
    mp=$(median "${pov[@]}")
    mc=$(median "${ours[@]}")
    ratio=$(echo "$mc / $mp" | bc -l)
    printf '%s\n  POV-Ray 3.7: %s s (median %.3f s)\n' "$scene" "$(printf '%.3f ' "${pov[@]}")" "$mp"
    printf '  caustic:     %s s (median %.3f s)\n' "$(printf '%.3f ' "${ours[@]}")" "$mc"
    printf '  caustic / POV-Ray: %.3f (target: at most 1/3)\n' "$ratio"
    [ "$(echo "$ratio <= 1/3" | bc -l)" = 1 ] || ok=0
done
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
[ "$ok" = 1 ]
