#!/usr/bin/env python3
"""Equal-time RMSE of caustic's volumetric path tracer against Mitsuba 3's `volpath` (llvm_ad_rgb,
warm) on the participating-media scenes of tests/data/media (issue 27).

    apt-get install libllvm19            # Mitsuba's llvm variants need it (Debian)
    pip install mitsuba==3.9.1 numpy OpenEXR
    cargo build --release
    python3 scripts/media_equal_time.py [SECONDS] [CASE ...]

For each case, Mitsuba renders at 64 x 64 on two threads with as many samples per pixel as fit
in SECONDS (default 2; measured from a warm render, then rendered twice at that count and the
second one timed, so its kernels are compiled before the clock starts); caustic then renders the
same file with `--integrator volpath --threads 2 --time T`, T being Mitsuba's measured time
(caustic's budget includes loading the scene). Both are compared with the committed 4096-spp
reference of the case; its own noise (MANIFEST.md's column, independent of either render) is
taken out of the squared error, so the figures are each render's own RMSE. Run it on a quiet
machine: the table goes into BENCHMARKS.md with the load average.
"""
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
DIR = ROOT / "tests" / "data" / "media"
CAUSTIC = ROOT / "target" / "release" / "caustic"
CASES = [
    "cube_area",
    "dielectric_envmap",
    "emitter_inside",
    "null_envmap",
    "opaque_inside",
    "camera_in_fog",
    "rough_box_spot",
    "hetero_blob",
    "hetero_rgb",
]
RES = 64

sys.path.insert(0, str(ROOT / "scripts"))
from rmse import read_rgb  # noqa: E402


def reference_noise():
    """Each case's reference noise (RMS per-pixel standard deviation) from MANIFEST.md."""
    noise = {}
    for line in (DIR / "MANIFEST.md").read_text().splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) >= 8 and re.fullmatch(r"[0-9.]+(e-?[0-9]+)?", cells[6] or "x"):
            noise[cells[0]] = float(cells[6])
    return noise


def own_rmse(image, ref, ref_noise):
    mse = float(np.mean((image - ref) ** 2)) - ref_noise**2
    return max(mse, 0.0) ** 0.5


def main():
    args = sys.argv[1:]
    seconds = float(args.pop(0)) if args and re.fullmatch(r"[0-9.]+", args[0]) else 2.0
    cases = args or CASES
    if "DRJIT_LIBLLVM_PATH" not in os.environ and Path("/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1").exists():
        os.environ["DRJIT_LIBLLVM_PATH"] = "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1"
    import drjit as dr
    import mitsuba as mi

    mi.set_variant("llvm_ad_rgb")
    dr.set_thread_count(2)
    noise = reference_noise()
    print(f"load average before: {os.getloadavg()[0]:.2f}")
    print(f"| case | Mitsuba spp | seconds | Mitsuba RMSE | caustic spp | caustic RMSE | ratio |")
    print("|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for case in cases:
            xml = DIR / f"{case}.xml"
            ref = read_rgb(str(DIR / f"{case}.exr"))
            scene = mi.load_file(str(xml), res=RES, spp=16)

            def timed(spp, seed):
                mi.render(scene, spp=spp, seed=seed)
                start = time.perf_counter()
                img = mi.render(scene, spp=spp, seed=seed + 1)
                dr.eval(img)
                return np.array(img, dtype=np.float64)[..., :3], time.perf_counter() - start

            _, t16 = timed(16, 10)
            spp = max(16, int(16 * seconds / max(t16, 1e-6)))
            theirs, t = timed(spp, 20)
            out = Path(tmp) / f"{case}.exr"
            cmd = [str(CAUSTIC), "render", str(xml), "-D", f"res={RES}", "--integrator", "volpath",
                   "--threads", "2", "--seed", "3", "--time", f"{t:.3f}", "-o", str(out)]
            log = subprocess.run(cmd, capture_output=True, text=True, check=True).stderr
            m = re.search(r"at (\d+) spp", log)
            ours = read_rgb(str(out))
            a = own_rmse(theirs, ref, noise.get(case, 0.0))
            b = own_rmse(ours, ref, noise.get(case, 0.0))
            print(f"| {case} | {spp} | {t:.2f} | {a:.5f} | {m.group(1) if m else '?'} | {b:.5f} | {b / a:.2f} |",
                  flush=True)
    print(f"load average after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
