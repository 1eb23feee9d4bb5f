#!/usr/bin/env python3
"""How long SPPM needs to reach the error of Mitsuba 3's path tracer at 256 samples per pixel on
the area-light caustic Cornell box (issue 32: at most a quarter of Mitsuba's time).

    apt-get install libllvm19            # Mitsuba's llvm variants need it (Debian)
    pip install mitsuba==3.9.1 numpy OpenEXR
    cargo build --release
    python3 scripts/sppm_vs_mitsuba.py [--res 128] [--ref-spp 16384] [--runs 3]

1. The reference: Mitsuba's path tracer (`llvm_ad_rgb`) at `--ref-spp` samples per pixel, cached
   in /tmp (a path tracer converges on this scene: its caustics are lit by an area light).
2. Mitsuba at 256 spp, warm (rendered once to compile its kernels, then timed; `--runs` times):
   its median wall time T and its RMSE against the reference.
3. caustic's SPPM (`--threads 2 --time t`, the time counted from the start of loading) at
   t = T/8, T/6, T/4, T/3, T/2: its RMSE against the same reference, each the mean of `--runs`
   seeds.
Prints the table and the fraction of T at which SPPM's RMSE falls to Mitsuba's (interpolated in
log-log between the two times around it). Run it on a quiet machine; the figures go into
BENCHMARKS.md with the load average printed at the end.
"""
import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "scripts"))
from rmse import read_rgb  # noqa: E402

SCENE = ROOT / "benches" / "scenes" / "area-caustics" / "area-caustics.xml"
CAUSTIC = Path(os.environ.get("BIN", ROOT / "target" / "release" / "caustic"))


def mitsuba_render(mi, spp, res, seed=0):
    scene = mi.load_file(str(SCENE), spp=spp, res=res)
    t0 = time.time()
    img = mi.render(scene, spp=spp, seed=seed)
    img = np.array(img)[..., :3]
    return img, time.time() - t0


def rmse(a, b):
    return float(np.sqrt(((a - b) ** 2).mean()))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--res", type=int, default=128)
    ap.add_argument("--ref-spp", type=int, default=16384)
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--fractions", default="0.125,0.1667,0.25,0.333,0.5")
    args = ap.parse_args()
    import mitsuba as mi

    mi.set_variant("llvm_ad_rgb")
    cache = Path(tempfile.gettempdir()) / f"sppm-vs-mitsuba-ref-{args.res}-{args.ref_spp}.npy"
    if cache.exists():
        ref = np.load(cache)
    else:
        print(f"# rendering Mitsuba's {args.ref_spp}-spp reference", flush=True)
        ref, t = mitsuba_render(mi, args.ref_spp, args.res, seed=7919)
        np.save(cache, ref)
        print(f"# took {t:.0f} s", flush=True)
    print(f"# load before: {os.getloadavg()[0]:.2f}", flush=True)
    mitsuba_render(mi, 256, args.res, seed=1)  # warm-up: compiles the kernels
    times, errors = [], []
    for run in range(args.runs):
        img, t = mitsuba_render(mi, 256, args.res, seed=100 + run)
        times.append(t)
        errors.append(rmse(img, ref))
    t_m, e_m = float(np.median(times)), float(np.mean(errors))
    print(f"| Mitsuba path, 256 spp | {t_m:.2f} s (runs {min(times):.2f}-{max(times):.2f}) | {e_m:.5f} |")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for frac in [float(f) for f in args.fractions.split(",")]:
            t = t_m * frac
            errs, walls = [], []
            for run in range(args.runs):
                out = Path(tmp) / f"s{run}.exr"
                cmd = [str(CAUSTIC), "render", str(SCENE), "--integrator", "sppm", "--threads", "2",
                       "--width", str(args.res), "--height", str(args.res), "--time", f"{t:.3f}",
                       "--seed", str(run + 1), "-o", str(out)]
                t0 = time.time()
                subprocess.run(cmd, check=True, capture_output=True)
                walls.append(time.time() - t0)
                errs.append(rmse(read_rgb(str(out)), ref))
            e = float(np.mean(errs))
            rows.append((frac, e))
            print(f"| caustic SPPM, {frac:.3f} x Mitsuba's time = {t:.2f} s | wall {np.median(walls):.2f} s | "
                  f"{e:.5f} ({e / e_m:.2f}x Mitsuba's) |", flush=True)
    # Where SPPM's error crosses Mitsuba's (log-log interpolation between neighbours).
    cross = None
    for (f0, e0), (f1, e1) in zip(rows, rows[1:]):
        if e0 > e_m >= e1:
            k = np.log(e_m / e0) / np.log(e1 / e0)
            cross = float(np.exp(np.log(f0) + k * (np.log(f1) - np.log(f0))))
            break
    if rows and rows[0][1] <= e_m:
        cross = rows[0][0]
        print(f"SPPM's error is below Mitsuba's already at {cross:.3f} of Mitsuba's time")
    elif cross is not None:
        print(f"SPPM reaches Mitsuba's error at {cross:.3f} of Mitsuba's time")
    else:
        print("SPPM does not reach Mitsuba's error within the times tried")
    print(f"# load after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
