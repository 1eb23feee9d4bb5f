#!/usr/bin/env python3
"""Checks that a change keeps the images: every bundled scene with every integrator, rendered by
two builds of caustic, compared bit for bit, by mean luminance and by RMSE against a reference.

    # 1. Before the change: keep the old binary and render with it.
    cp target/release/caustic /tmp/caustic-old
    python3 scripts/image_regression.py render --bin /tmp/caustic-old --out /tmp/old
    # Optional: high-sample references (8x the samples, another seed) with the old binary.
    python3 scripts/image_regression.py render --bin /tmp/caustic-old --out /tmp/ref --reference
    # 2. After the change:
    python3 scripts/image_regression.py render --bin target/release/caustic --out /tmp/new
    python3 scripts/image_regression.py compare /tmp/old /tmp/new --ref /tmp/ref

`compare` prints one row per (scene, integrator): whether the two images are bit-identical, the
ratio of their mean luminances (new / old), and, with --ref, the RMSE of each against the
reference and their ratio. With `render --seeds K` every image is rendered with K seeds and the
comparison averages over them (means of the K images, RMSE averaged over the K renders), which
takes the noise of a single render out of the figures. It exits with status 1 when a pair that is not bit-identical has a
mean luminance more than 0.5% apart or an RMSE more than 5% worse than the old one (the
acceptance rule of the architecture issue); `--allow SCENE:INTEGRATOR` exempts a pair whose
image changed on purpose (a fixed bug), which the table still shows.

Images are small (128 x 96) with few samples so the whole set renders in a few minutes on two
cores; the same fixed seed is used for every render. Needs the OpenEXR Python bindings
(`pip install OpenEXR`).
"""

import argparse
import glob
import json
import os
import re
import subprocess
import sys
import time

try:
    import numpy as np
    import OpenEXR
except ImportError as e:
    sys.exit(f"image_regression.py: {e}; install the bindings with `pip install OpenEXR`")

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SIZE = ["--width", "128", "--height", "96"]
# Settings per integrator: small but not trivial, so every code path runs.
SETTINGS = {
    "whitted": ["--spp", "16"],
    "path": ["--spp", "64"],
    "photon": ["--spp", "16", "--photons", "200000", "--caustic-photons", "50000", "--gather", "8"],
    "sppm": ["--iterations", "64"],
    "light": ["--spp", "16"],
    "bdpt": ["--spp", "16"],
    "vcm": ["--spp", "16"],
}
# A reference takes this many times the samples (photon counts included), with another seed.
REFERENCE_FACTOR = 8


def scenes():
    found = sorted(glob.glob(os.path.join(ROOT, "scenes", "*.toml")))
    found += sorted(glob.glob(os.path.join(ROOT, "scenes", "mitsuba", "*.xml")))
    return found


def scaled(args, factor):
    out = list(args)
    for i, a in enumerate(out[:-1]):
        if a in ("--spp", "--iterations", "--photons", "--caustic-photons"):
            out[i + 1] = str(int(out[i + 1]) * factor)
    return out


def key(scene):
    rel = os.path.relpath(scene, os.path.join(ROOT, "scenes"))
    return rel.replace(os.sep, "_").rsplit(".", 1)[0]


def render(args):
    os.makedirs(args.out, exist_ok=True)
    times = {}
    for scene in scenes():
        for integrator, settings in SETTINGS.items():
            if args.integrators and integrator not in args.integrators.split(","):
                continue
            extra = scaled(settings, REFERENCE_FACTOR) if args.reference else settings
            seeds = ["7"] if args.reference else [str(s) for s in range(1, args.seeds + 1)]
            for seed in seeds:
                suffix = "" if len(seeds) == 1 else f".s{seed}"
                out = os.path.join(args.out, f"{key(scene)}.{integrator}{suffix}.exr")
                cmd = [args.bin, "render", scene, "-o", out, "-q", "--seed", seed, "--integrator", integrator]
                cmd += SIZE + extra
                t0 = time.time()
                r = subprocess.run(cmd, capture_output=True, text=True)
                took = time.time() - t0
                if r.returncode != 0:
                    print(f"FAILED {key(scene)} {integrator}: {r.stderr.strip()}", file=sys.stderr)
                    continue
                times[f"{key(scene)}.{integrator}{suffix}"] = took
                print(f"{key(scene):32} {integrator:8} {seed:>3} {took:6.2f} s", flush=True)
    with open(os.path.join(args.out, "times.json"), "w") as f:
        json.dump(times, f, indent=1)


def read_rgb(path):
    with OpenEXR.File(path) as f:
        channels = f.channels()
        if "RGB" in channels:
            rgb = channels["RGB"].pixels
        else:
            rgb = np.stack([channels[c].pixels for c in "RGB"], axis=-1)
    return np.asarray(rgb, dtype=np.float64)


def luminance(img):
    return float((img @ np.array([0.2126, 0.7152, 0.0722])).mean())


def rmse(a, b):
    return float(np.sqrt(((a - b) ** 2).mean()))


def compare(args):
    allowed = set(args.allow or [])
    failures = 0
    header = f"| scene | integrator | identical | mean new/old |"
    if args.ref:
        header += " RMSE old | RMSE new | new/old |"
    print(header)
    print("|" + "---|" * (header.count("|") - 1))
    # Group the files of one (scene, integrator) over their seeds.
    groups = {}
    for old_path in sorted(glob.glob(os.path.join(args.old, "*.exr"))):
        name = os.path.basename(old_path)[: -len(".exr")]
        base = re.sub(r"\.s\d+$", "", name)
        groups.setdefault(base, []).append(os.path.basename(old_path))
    for base, names in groups.items():
        scene, integrator = base.rsplit(".", 1)
        missing = [n for n in names if not os.path.exists(os.path.join(args.new, n))]
        if missing:
            print(f"| {scene} | {integrator} | missing | |")
            failures += 1
            continue
        olds = [read_rgb(os.path.join(args.old, n)) for n in names]
        news = [read_rgb(os.path.join(args.new, n)) for n in names]
        identical = all(a.shape == b.shape and np.array_equal(a, b) for a, b in zip(olds, news))
        lo, ln = luminance(np.mean(olds, axis=0)), luminance(np.mean(news, axis=0))
        ratio = ln / lo if lo > 0 else (1.0 if ln == 0 else float("inf"))
        row = f"| {scene} | {integrator} | {'yes' if identical else 'no'} | {ratio:.4f} |"
        bad = not identical and abs(ratio - 1) > 0.005
        ref_path = os.path.join(args.ref, base + ".exr") if args.ref else None
        if ref_path and os.path.exists(ref_path):
            ref = read_rgb(ref_path)
            eo = float(np.mean([rmse(a, ref) for a in olds]))
            en = float(np.mean([rmse(b, ref) for b in news]))
            r = en / eo if eo > 0 else 1.0
            row += f" {eo:.5f} | {en:.5f} | {r:.3f} |"
            bad = bad or (not identical and r > 1.05)
        exempt = f"{scene}:{integrator}" in allowed
        if bad:
            row += " allowed" if exempt else " **CHANGED**"
            failures += 0 if exempt else 1
        print(row)
    if failures:
        print(f"\n{failures} image(s) changed beyond the tolerances", file=sys.stderr)
        sys.exit(1)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("render")
    r.add_argument("--bin", required=True)
    r.add_argument("--out", required=True)
    r.add_argument("--reference", action="store_true", help="8x the samples, another seed")
    r.add_argument("--seeds", type=int, default=1, help="render each image with seeds 1..K")
    r.add_argument("--integrators", help="only these integrators, e.g. photon,sppm (default: all)")
    c = sub.add_parser("compare")
    c.add_argument("old")
    c.add_argument("new")
    c.add_argument("--ref")
    c.add_argument("--allow", action="append", metavar="SCENE:INTEGRATOR")
    args = p.parse_args()
    render(args) if args.cmd == "render" else compare(args)


if __name__ == "__main__":
    main()
