#!/usr/bin/env python3
"""Renders the Mitsuba 3 reference images of tests/data/materials, which caustic's material and
texture tests compare with.

    pip install mitsuba==3.9.1 numpy
    python3 scripts/make_material_refs.py              # every tests/data/materials/*.xml
    python3 scripts/make_material_refs.py mask_area    # only the named cases

Each scene is rendered with Mitsuba's scalar_rgb variant at the sample count of `spp_for` (its
own resolution: 64 x 64, or 128 x 128 for the quads) and written as tests/data/materials/<case>.exr
(RGB, half float). The render is done as two halves with different seeds: the image is their
mean, and their difference measures Mitsuba's own noise, which MANIFEST.md lists per case next
to the sample count, the render time and a few statistics. CI does not need Mitsuba: the EXRs are
committed.
"""
import platform
import re
import sys
import time
from pathlib import Path

import mitsuba as mi
import numpy as np

ROOT = Path(__file__).resolve().parent.parent
DIR = ROOT / "tests" / "data" / "materials"
MANIFEST = DIR / "MANIFEST.md"
SEED = 1


def spp_for(case):
    """Sample counts: glass (caustics through it, fireflies) gets four times the sphere scenes,
    the textured quads (direct light from a constant environment, no noise but the pixel's
    footprint) a quarter. The rows of MANIFEST.md say what each committed image used: the first
    fifteen cases were rendered at four times these counts."""
    if case.startswith("quad_"):
        return 1024
    if case.startswith(("dielectric", "roughdielectric")):
        return 16384
    return 4096


def luminance(rgb):
    return 0.2126 * rgb[..., 0] + 0.7152 * rgb[..., 1] + 0.0722 * rgb[..., 2]


def object_share(scene, image):
    """The share of the image's luminance that comes from pixels whose centre sees the sphere
    (or the panels) rather than the floor, which sits at z = -1; None for the quads."""
    sensor = scene.sensors()[0]
    h, w = image.shape[:2]
    on_object = np.zeros((h, w), bool)
    for y in range(h):
        for x in range(w):
            ray, _ = sensor.sample_ray(0.0, 0.5, mi.Point2f((x + 0.5) / w, (y + 0.5) / h), mi.Point2f(0.5))
            si = scene.ray_intersect(ray)
            on_object[y, x] = bool(si.is_valid()) and abs(si.p.z + 1.0) > 1e-3
    lum = luminance(image)
    return float(lum[on_object].sum() / lum.sum())


def render(case):
    path = DIR / f"{case}.xml"
    spp = spp_for(case)
    integrator = re.search(r'<integrator type="(\w+)"', path.read_text()).group(1)
    start = time.time()
    scene = mi.load_file(str(path), spp=str(spp // 2))
    # Wrapping integrators (moment, aov) add channels after the image's R, G, B.
    halves = [np.array(mi.render(scene, seed=SEED + k), dtype=np.float64)[..., :3] for k in range(2)]
    seconds = time.time() - start
    image = (halves[0] + halves[1]) / 2
    # Each half has twice the full image's variance: rmse(a, b)^2 = 4 sigma^2.
    noise = float(np.sqrt(np.mean((halves[0] - halves[1]) ** 2)) / 2)

    assert np.isfinite(image).all(), f"{case}: non-finite pixels"
    assert image.min() >= 0, f"{case}: negative pixels"
    bmp = mi.Bitmap(image.astype(np.float32), pixel_format=mi.Bitmap.PixelFormat.RGB)
    bmp.convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float16, srgb_gamma=False).write(str(DIR / f"{case}.exr"))

    mean = image.reshape(-1, 3).mean(axis=0)
    share = None if case.startswith("quad_") else object_share(scene, image)
    row = {
        "case": case,
        "integrator": integrator,
        "size": f"{image.shape[1]}x{image.shape[0]}",
        "spp": spp,
        "seconds": seconds,
        "mean": mean,
        "lum": float(luminance(image).mean()),
        "noise": noise,
        "share": share,
    }
    print(f"{case}: {spp} spp, {seconds:.1f} s, mean luminance {row['lum']:.5f}, noise {noise:.5f}"
          + ("" if share is None else f", object share {share:.2f}"), flush=True)
    return row


def format_row(r):
    share = "-" if r["share"] is None else f"{r['share']:.2f}"
    mean = ", ".join(f"{c:.4f}" for c in r["mean"])
    return (f"| `{r['case']}` | {r['integrator']} | {r['size']} | {r['spp']} | {r['seconds']:.0f} | {mean} "
            f"| {r['lum']:.5f} | {r['noise']:.5f} | {share} |")


HEADER = """# Mitsuba 3 references for the material and texture tests

Rendered by `scripts/make_material_refs.py` with Mitsuba {version} (`scalar_rgb`, pip package) on
{machine}, as

    python3 scripts/make_material_refs.py

(a case name as argument renders only that case). Each `<case>.exr` is the mean of two renders of
`<case>.xml` with seeds 1 and 2 at spp/2 each, stored as RGB half floats. The scenes come from
`scripts/make_material_scenes.py`, their textures from `scripts/make_material_textures.py`.

Columns: the integrator named in the scene (every case uses `path` except `mask_*`, which uses
`volpath` so that shadow rays pass the mask's holes; see below), image size, samples per pixel,
wall-clock seconds on 2 cores, the image's mean R, G, B, its mean Rec. 709 luminance, Mitsuba's
own noise (the RMS over pixels and channels of each pixel's standard deviation, from the two
halves: rmse(a, b) / 2, in the units of `rmse` in tests/mitsuba.rs) and the share of the image's
luminance in pixels whose centre sees the sphere or panels rather than the floor.

| case | integrator | size | spp | s | mean R, G, B | mean lum. | noise | object share |
|---|---|---|---|---|---|---|---|---|
"""


def write_manifest(rows, notes):
    version = mi.__version__
    machine = f"{platform.machine()} Linux, Python {platform.python_version()}"
    body = "\n".join(format_row(rows[k]) for k in sorted(rows))
    MANIFEST.write_text(HEADER.format(version=version, machine=machine) + body + "\n" + notes)


def read_manifest():
    """The rows and the notes after the table of an existing manifest, so a partial run keeps
    the other cases."""
    rows, notes = {}, ""
    if not MANIFEST.exists():
        return rows, notes
    text = MANIFEST.read_text()
    table_end = 0
    for m in re.finditer(r"^\| `(\w+)` \| (\w+) \| (\d+)x(\d+) \| (\d+) \| (\d+) \| ([\d., ]+) \| ([\d.]+) "
                         r"\| ([\d.]+) \| ([\d.-]+) \|$", text, re.M):
        g = m.groups()
        rows[g[0]] = {
            "case": g[0], "integrator": g[1], "size": f"{g[2]}x{g[3]}", "spp": int(g[4]), "seconds": float(g[5]),
            "mean": [float(x) for x in g[6].split(",")], "lum": float(g[7]), "noise": float(g[8]),
            "share": None if g[9] == "-" else float(g[9]),
        }
        table_end = m.end()
    notes = text[table_end + 1:] if table_end else ""
    return rows, notes


def main():
    mi.set_variant("scalar_rgb")
    cases = sys.argv[1:] or sorted(p.stem for p in DIR.glob("*.xml"))
    rows, notes = read_manifest()
    for case in cases:
        rows[case] = render(case)
        write_manifest(rows, notes)


if __name__ == "__main__":
    main()
