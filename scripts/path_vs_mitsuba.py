#!/usr/bin/env python3
"""caustic's path tracer against Mitsuba 3's in time per sample (issue 29): the same Cornell box
in Mitsuba XML (`scenes/mitsuba/cornell-box.xml` unless given), the same image size and samples
per pixel, two threads each, alternating. Mitsuba runs `llvm_ad_rgb` warm: one render first to
compile its kernels, then each timed `mi.render` call. caustic's time is the whole process (load,
render, EXR written).

    apt-get install libllvm19 && pip install mitsuba==3.9.1
    python3 scripts/path_vs_mitsuba.py [--bin target/release/caustic [--bin target/pgo/caustic]] [--spp 256] [--res 256] [--runs 3]

With several --bin, each round runs Mitsuba and then every binary in turn. Prints every time,
the medians with their ranges, each binary's median over Mitsuba's, and the load average before
and after. Run it on a quiet machine.
"""
import argparse
import os
import statistics
import subprocess
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bin", action="append", help="caustic binaries (default target/release/caustic)")
    ap.add_argument("--scene", default=str(ROOT / "scenes/mitsuba/cornell-box.xml"))
    ap.add_argument("--spp", type=int, default=256)
    ap.add_argument("--res", type=int, default=256)
    ap.add_argument("--runs", type=int, default=3)
    a = ap.parse_args()
    bins = a.bin or [str(ROOT / "target/release/caustic")]
    import drjit as dr
    import mitsuba as mi

    mi.set_variant("llvm_ad_rgb")
    dr.set_thread_count(2)
    # The bundled scene takes its size and sample count as parameters ($res, $spp).
    scene = mi.load_file(a.scene, res=a.res, spp=a.spp)
    load_before = os.getloadavg()[0]
    t0 = time.perf_counter()
    dr.eval(mi.render(scene, spp=a.spp))
    print(f"Mitsuba first render (kernels compiled): {time.perf_counter() - t0:.2f} s")
    ours, theirs = {b: [] for b in bins}, []
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "c.exr"
        for k in range(a.runs):
            t0 = time.perf_counter()
            img = mi.render(scene, spp=a.spp, seed=k + 1)
            dr.eval(img)
            dr.sync_thread()
            theirs.append(time.perf_counter() - t0)
            for b in bins:
                cmd = [b, "render", a.scene, "--integrator", "path", "--spp", str(a.spp), "--width", str(a.res),
                       "--height", str(a.res), "--threads", "2", "-q", "-o", str(out)]
                t0 = time.perf_counter()
                subprocess.run(cmd, check=True, capture_output=True)
                ours[b].append(time.perf_counter() - t0)
    load_after = os.getloadavg()[0]
    fmt = lambda xs: " ".join(f"{x:.2f}" for x in xs) + f" s, median {statistics.median(xs):.2f} ({min(xs):.2f}-{max(xs):.2f})"
    print(f"Mitsuba llvm_ad_rgb: {fmt(theirs)}")
    for b in bins:
        print(f"caustic {b}: {fmt(ours[b])}")
        print(f"  caustic / Mitsuba time per sample: {statistics.median(ours[b]) / statistics.median(theirs):.3f}")
    print(f"load average before {load_before:.2f}, after {load_after:.2f}")


if __name__ == "__main__":
    main()
