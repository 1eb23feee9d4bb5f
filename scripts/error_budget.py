#!/usr/bin/env python3
"""Where an integrator's error is: each layer's share of the squared error against a long
reference (issue 32), so a change to SPPM (or VCM) says which layer it improved.

    python3 scripts/error_budget.py SCENE [--integrator sppm] [--time 5 | --spp N]
        [--width W --height H] [--runs 1] [-- MORE ARGUMENTS FOR THE RENDER]

The reference is rendered once per scene, size and reference settings, and cached
(--cache, default /tmp/caustic-error-budget):
- direct and indirect layers: the path tracer, `--ref-spp` samples per pixel (2048);
- caustic and specular layers: SPPM, `--ref-iters` iterations (1000) of `--ref-photons`
  photons (four per pixel): the path tracer cannot find caustics of point or sun light.
Each is rendered twice, with seeds 7919 and 7920, and the reference is their mean; the
reference's own noise (the variance of that mean per layer, a quarter of the two halves' mean
squared difference) is subtracted from every squared error printed, so the RMSEs are the
render's error against the exact image rather than against a noisy one (without this, a
2048-spp path tracer's noise in the indirect layer hid most of the difference between two
SPPM versions). The reference image is the sum of these four layers. Then the integrator renders with
`--layers` for `--time` seconds (equal time) or `--spp` samples / iterations (equal work), and
the script prints, per layer, its RMSE against the reference layer and its share of the summed
squared errors of the four layers (the cross terms between layers are left out, so the shares
add up to 100%), with the whole image's RMSE against the reference image, the wall and CPU
seconds of the render, and RMSE x sqrt(CPU seconds): the error at one CPU second if the squared
error falls as 1 / time (a path tracer's does; SPPM's a little slower), for comparisons on a
machine too busy for wall times (give `-- --threads 1`). With `--runs N` the figures are means
over N renders of different seeds (1, 2, ...; the references use another).

Columns: scene | integrator | budget | samples or iterations per run | wall | CPU | RMSE |
RMSE x sqrt(CPU) | direct, specular, caustic, indirect: share of the squared error (RMSE) |
load average after.

Needs the OpenEXR Python bindings (scripts/rmse.py).
"""

import argparse
import hashlib
import os
import re
import resource
import subprocess
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from rmse import read_rgb  # noqa: E402

LAYERS = ["direct", "specular", "caustic", "indirect"]
# The references' seed: far from the renders' (1, 2, ...), whose first samples would otherwise be
# the reference's own and their errors look far smaller than they are.
REF_SEED = 7919
# Which reference renders each layer.
REF_OF = {"direct": "path", "indirect": "path", "caustic": "sppm", "specular": "sppm"}


def cpu_seconds():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def run(cmd):
    """Runs a command; returns (wall seconds, CPU seconds, its output)."""
    t0, c0 = time.time(), cpu_seconds()
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"error_budget.py: {' '.join(cmd)} failed:\n{p.stderr}")
    return time.time() - t0, cpu_seconds() - c0, p.stderr + p.stdout


def layer_files(out):
    stem, ext = os.path.splitext(out)
    return {name: f"{stem}.{name}{ext}" for name in LAYERS}


def reference_half(args, size, seed):
    """One reference render of each kind at `seed` (cached): a dict of layer arrays."""
    with open(args.scene, "rb") as f:
        scene_hash = hashlib.sha256(f.read()).hexdigest()[:12]
    key = f"{scene_hash}-{args.width}x{args.height}-p{args.ref_spp}-s{args.ref_iters}x{args.ref_photons}-{seed}"
    name = os.path.splitext(os.path.basename(args.scene))[0]
    os.makedirs(args.cache, exist_ok=True)
    refs = {}
    for kind, extra in [
        ("path", ["--integrator", "path", "--spp", str(args.ref_spp)]),
        (
            "sppm",
            ["--integrator", "sppm", "--spp", str(args.ref_iters), "--photons-per-iter", str(args.ref_photons)],
        ),
    ]:
        out = os.path.join(args.cache, f"{name}-{key}-{kind}.exr")
        files = layer_files(out)
        if not all(os.path.exists(f) for f in files.values()):
            print(f"# rendering the {kind} reference of {args.scene} into {out}", file=sys.stderr)
            cmd = [args.bin, "render", args.scene, *size, *extra, "--seed", str(seed), "--layers", "-q", "-o", out]
            secs, _, _ = run(cmd)
            print(f"# took {secs:.0f} s", file=sys.stderr)
        for layer, img in files.items():
            if args.ref_of[layer] == kind:
                refs[layer] = read_rgb(img)
    return refs


def reference(args, size):
    """The four reference layers, each the mean of two renders of different seeds, and the
    variance of that mean per layer (its own noise, which every RMSE against it includes):
    for two independent halves a and b, the mean's squared error is E|a - b|^2 / 4."""
    a = reference_half(args, size, REF_SEED)
    b = reference_half(args, size, REF_SEED + 1)
    refs = {k: 0.5 * (a[k] + b[k]) for k in LAYERS}
    noise = {k: float(((a[k] - b[k]) ** 2).sum() / a[k].size) / 4 for k in LAYERS}
    return refs, noise


def render(args, size, seed, out):
    """One render of the integrator under test; returns (wall seconds, CPU seconds, samples or
    iterations)."""
    budget = ["--time", str(args.time), "--spp", "10000000"] if args.time else ["--spp", str(args.spp)]
    cmd = [args.bin, "render", args.scene, *size, "--integrator", args.integrator, *budget]
    cmd += ["--seed", str(seed), "--layers", "-o", out, *args.extra]
    secs, cpu, log = run(cmd)
    m = re.findall(r"rendered \d+x\d+ at (\d+) spp", log)
    return secs, cpu, (m[-1] if m else "?")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scene")
    ap.add_argument("--integrator", default="sppm")
    ap.add_argument("--time", type=float, help="seconds per render (equal time)")
    ap.add_argument("--spp", type=int, help="samples per pixel or iterations (equal work)")
    ap.add_argument(
        "--cpu",
        type=float,
        help="CPU seconds per render (equal CPU time, for a busy machine): a first render of "
        "--spp samples (default 16) measures the cost, and the render counted takes as many as fit",
    )
    ap.add_argument("--width", type=int, default=160)
    ap.add_argument("--height", type=int, default=120)
    ap.add_argument("--runs", type=int, default=1)
    ap.add_argument("--seed", type=int, default=1, help="the first render's seed (then seed + 1, ...)")
    ap.add_argument("--ref-spp", type=int, default=2048)
    ap.add_argument("--ref-iters", type=int, default=1000)
    ap.add_argument("--ref-photons", type=int, help="default: four per pixel")
    ap.add_argument(
        "--indirect-ref",
        choices=["path", "sppm"],
        default="path",
        help="which reference renders the indirect layer: the path tracer cannot find light that "
        "reaches a diffuse surface through a mirror or glass from a point, spot or sun light and "
        "then bounces on (L S+ D D+ E), so scenes lit by such lights need sppm here",
    )
    ap.add_argument("--cache", default="/tmp/caustic-error-budget")
    ap.add_argument("--bin", default=os.environ.get("BIN", "target/release/caustic"))
    ap.add_argument("--label", help="the table's label (default: the integrator)")
    argv = sys.argv[1:]
    extra = argv[argv.index("--") + 1 :] if "--" in argv else []
    args = ap.parse_args(argv[: len(argv) - len(extra) - (1 if "--" in argv else 0)])
    args.extra = extra
    args.ref_of = dict(REF_OF, indirect=args.indirect_ref)
    if args.cpu is not None:
        if args.time is not None:
            ap.error("give one of --time and --cpu")
        probe = args.spp or 16
        args.spp = probe
        _, cpu, _ = render(args, ["--width", str(args.width), "--height", str(args.height)], args.seed, "/tmp/eb-probe.exr")
        args.spp = max(1, round(probe * args.cpu / max(cpu, 1e-3)))
        for f in ["/tmp/eb-probe.exr", *layer_files("/tmp/eb-probe.exr").values()]:
            os.remove(f)
    if (args.time is None) == (args.spp is None):
        ap.error("give one of --time and --spp")
    if args.ref_photons is None:
        args.ref_photons = 4 * args.width * args.height
    size = ["--width", str(args.width), "--height", str(args.height)]
    refs, ref_noise = reference(args, size)
    ref_total = sum(refs[k] for k in LAYERS)
    pixels = ref_total.size
    se = {k: [] for k in LAYERS}
    total, secs, cpus, work = [], [], [], []
    tmp = os.path.join(args.cache, f"test-{os.getpid()}.exr")
    for r in range(args.runs):
        s, c, w = render(args, size, args.seed + r, tmp)
        secs.append(s)
        cpus.append(c)
        work.append(w)
        img = read_rgb(tmp)
        total.append(((img - ref_total) ** 2).sum() / pixels)
        for k, f in layer_files(tmp).items():
            se[k].append(((read_rgb(f) - refs[k]) ** 2).sum() / pixels)
    for f in [tmp, *layer_files(tmp).values()]:
        os.remove(f)
    # Each layer's error net of the reference's own noise (see `reference`): what the render's
    # error would be against the exact image.
    mse = {k: max(float(np.mean(v)) - ref_noise[k], 0.0) for k, v in se.items()}
    total_mse = max(float(np.mean(total)) - sum(ref_noise.values()), 0.0)
    summed = sum(mse.values()) or 1.0
    label = args.label or args.integrator
    budget = f"{args.time:g} s" if args.time else (f"{args.cpu:g} s CPU" if args.cpu else f"{args.spp} spp")
    load = open("/proc/loadavg").read().split()[0] if os.path.exists("/proc/loadavg") else "?"
    print(
        f"| {os.path.basename(args.scene)} | {label} | {budget} | {'/'.join(work)} | "
        f"{np.mean(secs):.1f} s | {np.mean(cpus):.1f} s | {np.sqrt(total_mse):.4f} | "
        f"{np.sqrt(total_mse * np.mean(cpus)):.4f} | "
        + " | ".join(f"{100 * mse[k] / summed:.0f}% ({np.sqrt(mse[k]):.4f})" for k in LAYERS)
        + f" | {load} |"
    )
    print(
        f"# reference noise (RMSE of the two-seed mean): total {np.sqrt(sum(ref_noise.values())):.4f}, "
        + ", ".join(f"{k} {np.sqrt(ref_noise[k]):.4f}" for k in LAYERS)
        + f"; raw RMSE against it {np.sqrt(np.mean(total)):.4f}",
        file=sys.stderr,
    )


if __name__ == "__main__":
    main()
