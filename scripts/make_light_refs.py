#!/usr/bin/env python3
"""Writes the environment-light scenes of tests/data/lights, the HDR sky they use, and their
Mitsuba 3 reference images, which tests/lights.rs compares caustic's renders with.

    pip install mitsuba==3.9.1 numpy
    python3 scripts/make_light_refs.py                 # sky, scenes and every reference
    python3 scripts/make_light_refs.py envmap_spheres  # only the named cases (scenes rewritten)

The sky (sky.exr, 256 x 128, RGB half float) is made here from a formula: a blue gradient above
the horizon, a brown ground below it and a small sun (4.5 degrees in radius, 35 degrees high)
about 150 times brighter than the sky, so sun and sky light the scene about equally. Its rows
follow Mitsuba's lat-long convention (+y up in the map's frame; the scenes turn it to +z up).

Each `<case>.exr` is the mean of two renders of `<case>.xml` with seeds 1 and 2 at spp/2 each
(RGB half float); their difference measures Mitsuba's own noise, which MANIFEST.md lists per case
with the sample count, the render time and the mean colour. CI does not need Mitsuba: the EXRs
are committed.
"""
import platform
import re
import sys
import textwrap
import time
from pathlib import Path

import mitsuba as mi
import numpy as np

ROOT = Path(__file__).resolve().parent.parent
DIR = ROOT / "tests" / "data" / "lights"
MANIFEST = DIR / "MANIFEST.md"
SEED = 1

# ---------------------------------------------------------------------------------------------
# The sky
# ---------------------------------------------------------------------------------------------

SKY_W, SKY_H = 256, 128
SUN_ELEVATION, SUN_AZIMUTH, SUN_RADIUS = 35.0, 285.0, 4.5  # degrees
SUN_RADIANCE = np.array([125.0, 105.0, 80.0])


def sky_radiance(d):
    """Radiance towards unit directions d (..., 3) in the map's frame, +y up."""
    y = d[..., 1]
    up = np.clip(y, 0.0, 1.0)[..., None]
    zenith, horizon = np.array([0.15, 0.3, 0.75]), np.array([0.7, 0.75, 0.85])
    sky = horizon + (zenith - horizon) * np.sqrt(up)
    down = np.clip(-y, 0.0, 1.0)[..., None]
    ground = np.array([0.22, 0.17, 0.12]) * (1.0 - 0.6 * down)
    c = np.where(y[..., None] >= 0.0, sky, ground)
    e, a = np.radians(SUN_ELEVATION), np.radians(SUN_AZIMUTH)
    sun_dir = np.array([np.sin(a) * np.cos(e), np.sin(e), -np.cos(a) * np.cos(e)])
    in_sun = (d @ sun_dir) >= np.cos(np.radians(SUN_RADIUS))
    return np.where(in_sun[..., None], SUN_RADIANCE, c)


def make_sky():
    """Each texel is the mean radiance over a 6 x 6 grid of directions around its centre (row j at
    theta = j pi / (H - 1), column i at phi = 2 pi (i + 0.5) / W, Mitsuba's texel positions)."""
    n = 6
    offs = (np.arange(n) + 0.5) / n - 0.5
    img = np.zeros((SKY_H, SKY_W, 3))
    for oy in offs:
        for ox in offs:
            theta = np.clip((np.arange(SKY_H)[:, None] + oy) * np.pi / (SKY_H - 1), 0.0, np.pi)
            phi = 2 * np.pi * (np.arange(SKY_W)[None, :] + 0.5 + ox) / SKY_W
            d = np.stack(np.broadcast_arrays(np.sin(phi) * np.sin(theta), np.cos(theta), -np.cos(phi) * np.sin(theta)),
                         axis=-1)
            img += sky_radiance(d)
    img /= n * n
    bmp = mi.Bitmap(img.astype(np.float32), pixel_format=mi.Bitmap.PixelFormat.RGB)
    bmp.convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float16, srgb_gamma=False).write(str(DIR / "sky.exr"))


# ---------------------------------------------------------------------------------------------
# The scenes
# ---------------------------------------------------------------------------------------------


def comment(*paragraphs):
    lines = []
    for k, text in enumerate(paragraphs):
        lines += textwrap.wrap(" ".join(text.split()), 95, initial_indent="<!-- " if k == 0 else "     ",
                               subsequent_indent="     ")
    return "\n".join(lines) + " -->"


SPHERES = """
    <!-- Three spheres of radius 0.6 resting on the floor: diffuse, rough aluminium, glass. -->
    <shape type="sphere">
        <point name="center" x="-1.4" y="0" z="-0.4"/>
        <float name="radius" value="0.6"/>
        <bsdf type="diffuse">
            <rgb name="reflectance" value="0.7, 0.45, 0.3"/>
        </bsdf>
    </shape>
    <shape type="sphere">
        <point name="center" x="0" y="0.3" z="-0.4"/>
        <float name="radius" value="0.6"/>
        <bsdf type="roughconductor">
            <string name="material" value="Al"/>
            <string name="distribution" value="ggx"/>
            <float name="alpha" value="0.15"/>
        </bsdf>
    </shape>
    <shape type="sphere">
        <point name="center" x="1.4" y="0" z="-0.4"/>
        <float name="radius" value="0.6"/>
        <bsdf type="dielectric">
            <float name="int_ior" value="1.5"/>
        </bsdf>
    </shape>
    <!-- The floor: 20 x 20, grey diffuse, at z = -1 facing up. -->
    <shape type="rectangle">
        <transform name="to_world">
            <scale value="10"/>
            <translate z="-1"/>
        </transform>
        <bsdf type="diffuse">
            <rgb name="reflectance" value="0.4"/>
        </bsdf>
    </shape>
"""

ENVMAP = """
    <!-- The sky: its +y (up in the map) turned to +z by a rotation of 90 degrees about x, then
         turned 30 degrees about z. -->
    <emitter type="envmap">
        <string name="filename" value="sky.exr"/>
        <float name="scale" value="SCALE"/>
        <transform name="to_world">
            <rotate x="1" angle="90"/>
            <rotate z="1" angle="30"/>
        </transform>
    </emitter>
"""

CONSTANT = """
    <emitter type="constant">
        <rgb name="radiance" value="0.8, 0.9, 1.0"/>
    </emitter>
"""

CASES = {
    "envmap_spheres": ("a diffuse, a rough metal and a glass sphere on a floor under the HDR sky of sky.exr (small bright "
                       "sun), turned by to_world", ENVMAP.replace("SCALE", "1")),
    "envmap_scaled": ("the same under the sky scaled by 0.5, with max_depth 4 (caustic's 3: direct light and two more bounces)",
                      ENVMAP.replace("SCALE", "0.5")),
    "constant_spheres": ("the same spheres under a constant environment of radiance (0.8, 0.9, 1.0)", CONSTANT),
}


def scene_xml(case):
    description, emitter = CASES[case]
    depth = 4 if case == "envmap_scaled" else 12
    head = comment(f"Light case `{case}`: {description}.",
                   f"Reference image: {case}.exr, rendered by scripts/make_light_refs.py with Mitsuba 3.9.1 "
                   "(scalar_rgb), which also wrote this file.")
    return f"""<?xml version="1.0" encoding="utf-8"?>
{head}
<scene version="3.0.0">
    <default name="spp" value="64"/>
    <default name="res" value="64"/>

    <integrator type="path">
        <integer name="max_depth" value="{depth}"/>
    </integrator>
    <sensor type="perspective">
        <float name="fov" value="32"/>
        <transform name="to_world">
            <lookat origin="0, -7, 1.6" target="0, 0, -0.45" up="0, 0, 1"/>
        </transform>
        <sampler type="independent">
            <integer name="sample_count" value="$spp"/>
        </sampler>
        <film type="hdrfilm">
            <integer name="width" value="$res"/>
            <integer name="height" value="$res"/>
            <string name="pixel_format" value="rgb"/>
            <rfilter type="box"/>
        </film>
    </sensor>
{SPHERES}{emitter}</scene>
"""


SPP = {"envmap_spheres": 3072, "envmap_scaled": 2048, "constant_spheres": 2048}

# ---------------------------------------------------------------------------------------------
# Rendering and the manifest
# ---------------------------------------------------------------------------------------------


def luminance(rgb):
    return 0.2126 * rgb[..., 0] + 0.7152 * rgb[..., 1] + 0.0722 * rgb[..., 2]


def render(case):
    path = DIR / f"{case}.xml"
    spp = SPP[case]
    start = time.time()
    scene = mi.load_file(str(path), spp=str(spp // 2))
    halves = [np.array(mi.render(scene, seed=SEED + k), dtype=np.float64) for k in range(2)]
    seconds = time.time() - start
    image = (halves[0] + halves[1]) / 2
    # Each half has twice the full image's variance: rmse(a, b)^2 = 4 sigma^2.
    noise = float(np.sqrt(np.mean((halves[0] - halves[1]) ** 2)) / 2)
    assert np.isfinite(image).all() and image.min() >= 0, f"{case}: bad pixels"
    bmp = mi.Bitmap(image.astype(np.float32), pixel_format=mi.Bitmap.PixelFormat.RGB)
    bmp.convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float16, srgb_gamma=False).write(str(DIR / f"{case}.exr"))
    row = {"case": case, "size": f"{image.shape[1]}x{image.shape[0]}", "spp": spp, "seconds": seconds,
           "mean": image.reshape(-1, 3).mean(axis=0), "lum": float(luminance(image).mean()), "noise": noise}
    print(f"{case}: {spp} spp, {seconds:.1f} s, mean luminance {row['lum']:.5f}, noise {noise:.5f}", flush=True)
    return row


def format_row(r):
    mean = ", ".join(f"{c:.4f}" for c in r["mean"])
    return f"| `{r['case']}` | {r['size']} | {r['spp']} | {r['seconds']:.0f} | {mean} | {r['lum']:.5f} | {r['noise']:.5f} |"


HEADER = """# Mitsuba 3 references for the environment-light tests

Written and rendered by `scripts/make_light_refs.py` with Mitsuba {version} (`scalar_rgb`, pip
package) on {machine}, as

    python3 scripts/make_light_refs.py

(case names as arguments render only those). `sky.exr` is the HDR sky the `envmap_*` scenes use,
made by the same script from a formula (a 256 x 128 lat-long map, RGB half float: a blue
gradient, a brown ground, a sun 4.5 degrees in radius at 35 degrees elevation). Each `<case>.exr`
is the mean of two renders of `<case>.xml` with seeds 1 and 2 at spp/2 each, stored as RGB half
floats.

Columns: image size, samples per pixel, wall-clock seconds on 2 cores, the image's mean R, G, B,
its mean Rec. 709 luminance, and Mitsuba's own noise (the RMS over pixels and channels of each
pixel's standard deviation, from the two halves: rmse(a, b) / 2).

| case | size | spp | s | mean R, G, B | mean lum. | noise |
|---|---|---|---|---|---|---|
"""


def read_manifest():
    rows, notes = {}, ""
    if not MANIFEST.exists():
        return rows, notes
    text = MANIFEST.read_text()
    end = 0
    for m in re.finditer(r"^\| `(\w+)` \| (\d+x\d+) \| (\d+) \| (\d+) \| ([\d., ]+) \| ([\d.]+) \| ([\d.]+) \|$", text,
                         re.M):
        g = m.groups()
        rows[g[0]] = {"case": g[0], "size": g[1], "spp": int(g[2]), "seconds": float(g[3]),
                      "mean": [float(x) for x in g[4].split(",")], "lum": float(g[5]), "noise": float(g[6])}
        end = m.end()
    return rows, (text[end + 1:] if end else "")


def write_manifest(rows, notes):
    machine = f"{platform.machine()} Linux, Python {platform.python_version()}"
    body = "\n".join(format_row(rows[k]) for k in sorted(rows))
    MANIFEST.write_text(HEADER.format(version=mi.__version__, machine=machine) + body + "\n" + notes)


def main():
    mi.set_variant("scalar_rgb")
    DIR.mkdir(parents=True, exist_ok=True)
    cases = sys.argv[1:] or sorted(CASES)
    if not sys.argv[1:] or not (DIR / "sky.exr").exists():
        make_sky()
    rows, notes = read_manifest()
    for case in cases:
        (DIR / f"{case}.xml").write_text(scene_xml(case))
        rows[case] = render(case)
        write_manifest(rows, notes)


if __name__ == "__main__":
    main()
