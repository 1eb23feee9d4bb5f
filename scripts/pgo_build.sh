#!/usr/bin/env bash
# Builds caustic with profile-guided optimisation (PGO): an instrumented build renders a training
# set of the bundled scenes with every integrator, and the counts it records tell the compiler
# which branches are taken and which calls are hot when it builds the binary again. The images
# are bit for bit those of `cargo build --release` (PGO changes code layout and inlining, not
# arithmetic); renders are 1.05-1.25x as fast (BENCHMARKS.md, issue 29).
#
#     rustup component add llvm-tools     # once: llvm-profdata, matching the compiler
#     scripts/pgo_build.sh                # about 4 minutes on two cores
#     target/pgo/caustic render scenes/11-cornell-area.toml -o box.png
#
# The two builds use target directories of their own under target/pgo, so the plain build in
# target/release is left as it was. The profile is made from the source being built, so it is
# never stale; run the script again after changing the code.
set -euo pipefail

root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
out=${CARGO_TARGET_DIR:-$root/target}/pgo
profdata=$(ls "$(rustc --print sysroot)"/lib/rustlib/*/bin/llvm-profdata 2>/dev/null | head -n 1 || true)
if [ -z "$profdata" ]; then
    echo "pgo_build.sh: llvm-profdata not found; install it with: rustup component add llvm-tools" >&2
    exit 1
fi

rm -rf "$out/profiles"
mkdir -p "$out/profiles" "$out/train"
echo "1/3: instrumented build" >&2
RUSTFLAGS="-Cprofile-generate=$out/profiles" cargo build --release --target-dir "$out/instrumented" --bin caustic

echo "2/3: training renders" >&2
bin=$out/instrumented/release/caustic
img=$out/train/image.exr
render() { "$bin" render "$@" -q -o "$img"; }
# Each integrator on the scenes it is meant for, small images: the branch counts matter, not
# the pixels.
render scenes/mitsuba/cornell-box.xml --integrator path --spp 16 --width 128 --height 128
render scenes/11-cornell-area.toml --integrator path --spp 16 --width 128 --height 128
render scenes/13-cornell-caustics.toml --integrator path --spp 16 --width 128 --height 128
render scenes/15-materials.toml --integrator path --spp 8 --width 128 --height 96
render scenes/16-glossy-caustics.toml --integrator path --spp 8 --width 128 --height 96
render scenes/13-cornell-caustics.toml --integrator sppm --iterations 8 --width 128 --height 128
render benches/scenes/sky-lit.toml --integrator sppm --iterations 4 --width 96 --height 72
render scenes/12-cornell-point.toml --integrator photon --spp 2 --width 96 --height 96
render scenes/13-cornell-caustics.toml --integrator vcm --iterations 8 --width 128 --height 128
render scenes/16-glossy-caustics.toml --integrator vcm --iterations 4 --width 128 --height 96
render scenes/13-cornell-caustics.toml --integrator bdpt --spp 4 --width 96 --height 96
render scenes/13-cornell-caustics.toml --integrator light --spp 4 --width 96 --height 96
render scenes/17-volumetric-caustic.toml --spp 4 --width 96 --height 72
render scenes/18-light-shaft.toml --spp 4 --width 96 --height 72
render scenes/19-prism.toml --spp 4 --width 96 --height 72
render scenes/14-first-scene.toml --spp 2 --width 128 --height 96
render scenes/05-transparent-ior1.5.toml --spp 4 --width 128 --height 96
render scenes/08-dof-red-focus.toml --spp 4 --width 128 --height 96
for s in whitted whitted-rects whitted-lights whitted-mesh; do
    render benches/scenes/$s.toml --width 128 --height 128
done
"$bin" bench --repeats 1 >/dev/null

echo "3/3: optimised build" >&2
"$profdata" merge -o "$out/caustic.profdata" "$out/profiles"
RUSTFLAGS="-Cprofile-use=$out/caustic.profdata" cargo build --release --target-dir "$out/optimized" --bin caustic
cp "$out/optimized/release/caustic" "$out/caustic"
echo "PGO build: $out/caustic" >&2
