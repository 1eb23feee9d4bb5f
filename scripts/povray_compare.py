#!/usr/bin/env python3
"""caustic's photon integrator against POV-Ray 3.7 on the point-light caustic Cornell box.

    python3 scripts/povray_compare.py [--caustic target/release/caustic] [--reps 2]
        [--spp 32] [--caustic-args "--sampler sobol --irradiance-cache 0.25"] [--pov-args "..."]

Renders, alternately and back to back (`--reps` times each, so both see the same machine load):
- POV-Ray: scripts/povray/cornell-caustics.pov at 256 x 256, photons (~200k) + radiosity,
  16 anti-aliasing samples (+AM1 +A0.0 +R4: a 4 x 4 grid in every pixel), HDR output;
- caustic: scenes/13-cornell-caustics.toml at 256 x 256 with `--integrator photon --spp 32
  --sampler sobol` (the scene's own photon counts; the irradiance cache on, --irradiance-cache 0.25);
and prints each one's wall time (the whole process: parsing, photons, radiosity or
irradiance-cache pretrace, render), its RMSE against a converged reference over all pixels and
channels (linear values) and its mean luminance relative to the reference's.

The reference is a long SPPM render (the path tracer cannot see point-light caustics), made once
and cached in /tmp/caustic-povray-ref/ (`--ref-iterations`, `--ref-photons`); its mean luminance
is cross-checked against a long photon-mapping render with final gathering at every sample (no
irradiance cache) made once as well. Both are reported with the time they took. Exit status 0
when caustic wins (no more time, lower RMSE, mean luminance within 2% of the reference).

Needs POV-Ray 3.7 (`apt-get install povray`) and Mitsuba 3's Python package (only to read the
EXR and HDR images).
"""

import argparse
import os
import shlex
import subprocess
import sys
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENE = os.path.join(ROOT, "scenes", "13-cornell-caustics.toml")
POV = os.path.join(ROOT, "scripts", "povray", "cornell-caustics.pov")
CACHE = "/tmp/caustic-povray-ref"
SIZE = 256


def read_linear(path):
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    bmp = mi.Bitmap(path).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32, srgb_gamma=False)
    return np.array(bmp, dtype=np.float64)


def luminance(img):
    return img[..., 0] * 0.2126 + img[..., 1] * 0.7152 + img[..., 2] * 0.0722


def run(cmd, what):
    t0 = time.monotonic()
    r = subprocess.run(cmd, capture_output=True, text=True)
    dt = time.monotonic() - t0
    if r.returncode != 0:
        sys.exit(f"{what} failed ({' '.join(cmd)}):\n{r.stdout}\n{r.stderr}")
    return dt


def caustic_cmd(binary, out, args):
    return [binary, "render", SCENE, "--width", str(SIZE), "--height", str(SIZE), "--quiet", "-o", out] + args


def cached(binary, name, args):
    """A reference render made once: its path and the seconds it took (from a side file)."""
    os.makedirs(CACHE, exist_ok=True)
    path = os.path.join(CACHE, name + ".exr")
    tfile = path + ".seconds"
    if not (os.path.exists(path) and os.path.exists(tfile)):
        print(f"making {path}: caustic {' '.join(args)} (once; cached)", flush=True)
        dt = run(caustic_cmd(binary, path, args), name)
        with open(tfile, "w") as f:
            f.write(f"{dt:.1f}\n")
    with open(tfile) as f:
        return path, float(f.read())


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--caustic", default=os.path.join(ROOT, "target", "release", "caustic"))
    ap.add_argument("--reps", type=int, default=2)
    ap.add_argument("--spp", type=int, default=32)
    ap.add_argument("--caustic-args", default="--sampler sobol --irradiance-cache 0.25", help="more caustic options")
    ap.add_argument("--pov-args", default="", help="more POV-Ray options")
    ap.add_argument("--ref-iterations", type=int, default=1024)
    ap.add_argument("--ref-photons", type=int, default=200_000)
    ap.add_argument("--out", default="/tmp/caustic-povray-compare")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)

    ref_args = ["--integrator", "sppm", "--spp", str(a.ref_iterations), "--photons-per-iter", str(a.ref_photons)]
    ref_path, ref_time = cached(a.caustic, f"sppm-{a.ref_iterations}x{a.ref_photons}", ref_args)
    check_args = ["--integrator", "photon", "--spp", "16", "--gather", "64", "--irradiance-cache", "0"]
    check_path, check_time = cached(a.caustic, "photon-16spp-gather64", check_args)
    ref = read_linear(ref_path)
    ref_lum = luminance(ref).mean()
    check_lum = luminance(read_linear(check_path)).mean()
    print(f"reference: SPPM {a.ref_iterations} iterations x {a.ref_photons} photons, {ref_time:.0f} s, "
          f"mean luminance {ref_lum:.5f}")
    print(f"cross-check: photon mapping 16 spp x 64 gather rays (no cache), {check_time:.0f} s, "
          f"mean luminance {check_lum:.5f} ({(check_lum / ref_lum - 1) * 100:+.2f}% of the reference)")

    pov_out = os.path.join(a.out, "povray.hdr")
    pov_cmd = ["povray", f"+I{POV}", f"+O{pov_out}", "+FH", f"+W{SIZE}", f"+H{SIZE}", "+AM1", "+A0.0", "+R4",
               "+J", "-D", "-V", "-GA"] + shlex.split(a.pov_args)
    c_out = os.path.join(a.out, "caustic.exr")
    c_cmd = caustic_cmd(a.caustic, c_out, ["--integrator", "photon", "--spp", str(a.spp)] + shlex.split(a.caustic_args))
    print(f"povray: {' '.join(pov_cmd)}")
    print(f"caustic: {' '.join(c_cmd)}")
    print(f"{'renderer':10} {'rep':>3} {'time s':>7} {'RMSE':>8} {'mean/ref':>9}")
    rows = {"povray": [], "caustic": []}
    for rep in range(a.reps):
        for name, cmd, out in (("povray", pov_cmd, pov_out), ("caustic", c_cmd, c_out)):
            dt = run(cmd, name)
            img = read_linear(out)
            rmse = float(np.sqrt(np.mean((img - ref) ** 2)))
            rel = luminance(img).mean() / ref_lum
            rows[name].append((dt, rmse, rel))
            print(f"{name:10} {rep + 1:3} {dt:7.2f} {rmse:8.5f} {rel:9.4f}", flush=True)
    p = np.mean(rows["povray"], axis=0)
    c = np.mean(rows["caustic"], axis=0)
    print(f"mean: povray {p[0]:.2f} s RMSE {p[1]:.5f} mean {p[2]:.4f}; caustic {c[0]:.2f} s RMSE {c[1]:.5f} "
          f"mean {c[2]:.4f}; time ratio caustic/povray {c[0] / p[0]:.3f}")
    ok = c[0] <= p[0] and c[1] < p[1] and abs(c[2] - 1) <= 0.02
    print("PASS" if ok else "FAIL", "(caustic: no more time, lower RMSE, mean luminance within 2%)")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
