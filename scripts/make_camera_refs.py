#!/usr/bin/env python3
"""Writes the camera and film test scenes of tests/data/camera and renders their Mitsuba 3
reference images, which tests/camera.rs compares caustic's renders with.

    pip install mitsuba==3.9.1 numpy
    python3 scripts/make_camera_refs.py            # every case
    python3 scripts/make_camera_refs.py crop ppo   # only the named cases

Every case is one scene (a checkered floor, a cube and a sphere under a sun and a blue sky, with
sharp edges everywhere: checks, silhouettes and shadows) seen through a different sensor or film:
an orthographic view with a non-uniformly scaled to_world, Mitsuba's default (Gaussian) filter and
the other filters, a crop window with and without sample_border, and a principal-point offset.
Each is rendered with the scalar_rgb variant as two halves with seeds 1 and 2: the EXR
(<case>.exr, RGB half float) is their mean, and their difference measures Mitsuba's own noise,
which MANIFEST.md lists with the sample count, the render time and the mean colour. CI does not
need Mitsuba: the scenes and EXRs are committed.
"""
import platform
import sys
import time
from pathlib import Path

import mitsuba as mi
import numpy as np

ROOT = Path(__file__).resolve().parent.parent
DIR = ROOT / "tests" / "data" / "camera"
MANIFEST = DIR / "MANIFEST.md"
SEED = 1
SPP = 2048

PERSPECTIVE = """<sensor type="perspective">
        <float name="fov" value="{fov}"/>{extra}
        <transform name="to_world">
            <lookat origin="2.2, 3.0, 4.5" target="0, 0.35, 0" up="0, 1, 0"/>
        </transform>
        <sampler type="independent">
            <integer name="sample_count" value="$spp"/>
        </sampler>
        <film type="hdrfilm">
            <integer name="width" value="{width}"/>
            <integer name="height" value="{height}"/>{film}
        </film>
    </sensor>"""

ORTHOGRAPHIC = """<sensor type="orthographic">
        <!-- The scale sets the view: 2 x 2.6 = 5.2 units across the film's width and
             2 x 1.8 / aspect = 2.4 units up its height (non-square pixels of the scene). -->
        <transform name="to_world">
            <scale x="2.6" y="1.8"/>
            <lookat origin="3, 4, 5" target="0, 0.35, 0" up="0, 1, 0"/>
        </transform>
        <sampler type="independent">
            <integer name="sample_count" value="$spp"/>
        </sampler>
        <film type="hdrfilm">
            <integer name="width" value="96"/>
            <integer name="height" value="64"/>
            <rfilter type="box"/>
        </film>
    </sensor>"""


def perspective(fov=32, width=64, height=64, extra="", film=""):
    return PERSPECTIVE.format(fov=fov, width=width, height=height, extra=extra, film=film)


CROP = """
            <integer name="crop_offset_x" value="44"/>
            <integer name="crop_offset_y" value="30"/>
            <integer name="crop_width" value="64"/>
            <integer name="crop_height" value="48"/>"""

# case: (what it shows, sensor)
CASES = {
    "ortho": ("orthographic sensor, scaled to_world, 96 x 64, box filter", ORTHOGRAPHIC),
    "gaussian": ("no rfilter: Mitsuba's default Gaussian (stddev 0.5, radius 2)", perspective()),
    "mitchell": ("Mitchell-Netravali filter, B = C = 1/3 (negative lobes)",
                 perspective(film='\n            <rfilter type="mitchell"/>')),
    "lanczos": ("Lanczos sinc filter, 3 lobes (negative lobes)", perspective(film='\n            <rfilter type="lanczos"/>')),
    "tent": ("tent filter, radius 1.5",
             perspective(film='\n            <rfilter type="tent"><float name="radius" value="1.5"/></rfilter>')),
    "crop": ("crop window 64 x 48 at (44, 30) of a 160 x 112 film, default Gaussian",
             perspective(fov=52, width=160, height=112, film=CROP)),
    "crop_border": ("the same crop with sample_border",
                    perspective(fov=52, width=160, height=112,
                                film=CROP + '\n            <boolean name="sample_border" value="true"/>')),
    "ppo": ("principal point offset (0.2, -0.15), box filter",
            perspective(extra='\n        <float name="principal_point_offset_x" value="0.2"/>'
                              '\n        <float name="principal_point_offset_y" value="-0.15"/>',
                        film='\n            <rfilter type="box"/>')),
}

SCENE = """<?xml version="1.0" encoding="utf-8"?>
<!-- Camera case `{case}`: {what}.
     A checkered floor, a red cube and a white sphere under a sun (directional emitter) and a
     blue sky (constant emitter); every edge is sharp, so the filter and the projection show.
     Reference image: {case}.exr, rendered by scripts/make_camera_refs.py with Mitsuba 3.9.1
     (scalar_rgb); the same script wrote this file. -->
<scene version="3.0.0">
    <default name="spp" value="64"/>

    <!-- Direct light and one bounce. -->
    <integrator type="path">
        <integer name="max_depth" value="3"/>
    </integrator>
    {sensor}

    <emitter type="constant">
        <rgb name="radiance" value="0.25, 0.3, 0.4"/>
    </emitter>
    <emitter type="directional">
        <vector name="direction" x="-0.6" y="-1" z="-0.35"/>
        <rgb name="irradiance" value="3.0, 2.8, 2.5"/>
    </emitter>

    <!-- The floor: 8 x 8 at y = 0 facing up, 8 x 8 checks. -->
    <shape type="rectangle">
        <transform name="to_world">
            <scale value="4"/>
            <rotate x="1" angle="-90"/>
        </transform>
        <bsdf type="diffuse">
            <texture type="checkerboard" name="reflectance">
                <rgb name="color0" value="0.75, 0.75, 0.7"/>
                <rgb name="color1" value="0.08, 0.1, 0.12"/>
                <transform name="to_uv"><scale x="4" y="4"/></transform>
            </texture>
        </bsdf>
    </shape>
    <!-- A cube of side 1 resting on the floor, turned 30 degrees. -->
    <shape type="cube">
        <transform name="to_world">
            <scale value="0.5"/>
            <rotate y="1" angle="30"/>
            <translate x="0.7" y="0.5" z="-0.4"/>
        </transform>
        <bsdf type="diffuse">
            <rgb name="reflectance" value="0.7, 0.15, 0.1"/>
        </bsdf>
    </shape>
    <shape type="sphere">
        <point name="center" x="-0.8" y="0.6" z="0.5"/>
        <float name="radius" value="0.6"/>
        <bsdf type="diffuse">
            <rgb name="reflectance" value="0.8"/>
        </bsdf>
    </shape>
</scene>
"""


def luminance(rgb):
    return 0.2126 * rgb[..., 0] + 0.7152 * rgb[..., 1] + 0.0722 * rgb[..., 2]


def write_scene(case):
    what, sensor = CASES[case]
    (DIR / f"{case}.xml").write_text(SCENE.format(case=case, what=what, sensor=sensor))


def render(case):
    start = time.time()
    scene = mi.load_file(str(DIR / f"{case}.xml"), spp=str(SPP // 2))
    halves = [np.array(mi.render(scene, seed=SEED + k), dtype=np.float64) for k in range(2)]
    seconds = time.time() - start
    image = (halves[0] + halves[1]) / 2
    # Each half has twice the full image's variance: rmse(a, b)^2 = 4 sigma^2.
    noise = float(np.sqrt(np.mean((halves[0] - halves[1]) ** 2)) / 2)
    assert np.isfinite(image).all(), f"{case}: non-finite pixels"
    bmp = mi.Bitmap(image.astype(np.float32), pixel_format=mi.Bitmap.PixelFormat.RGB)
    bmp.convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float16, srgb_gamma=False).write(str(DIR / f"{case}.exr"))
    mean = image.reshape(-1, 3).mean(axis=0)
    row = {"case": case, "size": f"{image.shape[1]}x{image.shape[0]}", "spp": SPP, "seconds": seconds,
           "mean": mean, "lum": float(luminance(image).mean()), "noise": noise}
    print(f"{case}: {row['size']}, {SPP} spp, {seconds:.1f} s, mean luminance {row['lum']:.5f}, noise {noise:.5f}",
          flush=True)
    return row


def format_row(r):
    mean = ", ".join(f"{c:.4f}" for c in r["mean"])
    return f"| `{r['case']}` | {r['size']} | {r['spp']} | {r['seconds']:.0f} | {mean} | {r['lum']:.5f} | {r['noise']:.5f} |"


HEADER = """# Mitsuba 3 references for the camera and film tests

Written and rendered by `scripts/make_camera_refs.py` with Mitsuba {version} (`scalar_rgb`, pip
package) on {machine}, as

    python3 scripts/make_camera_refs.py

(case names as arguments render only those cases). Each `<case>.exr` is the mean of two renders
of `<case>.xml` with seeds 1 and 2 at spp/2 each, stored as RGB half floats. tests/camera.rs
compares caustic's path tracer with them (mean luminance within 1%, RMSE within 1.25 times what
the two images' noise predicts).

Columns: image size (the crop's for the cropped cases), samples per pixel, wall-clock seconds on
2 cores, the image's mean R, G, B, its mean Rec. 709 luminance and Mitsuba's own noise (the RMS
over pixels and channels of each pixel's standard deviation, from the two halves: rmse(a, b) / 2).

| case | size | spp | s | mean R, G, B | mean lum. | noise |
|---|---|---|---|---|---|---|
"""


def main():
    mi.set_variant("scalar_rgb")
    cases = sys.argv[1:] or list(CASES)
    unknown = [c for c in cases if c not in CASES]
    if unknown:
        sys.exit(f"unknown cases: {', '.join(unknown)}; known: {', '.join(CASES)}")
    DIR.mkdir(parents=True, exist_ok=True)
    rows = {}
    if MANIFEST.exists():
        for line in MANIFEST.read_text().splitlines():
            if line.startswith("| `"):
                rows[line.split("`")[1]] = line
    for case in cases:
        write_scene(case)
        rows[case] = format_row(render(case))
    machine = f"{platform.machine()} {platform.system()}, Python {platform.python_version()}"
    text = HEADER.format(version=mi.__version__, machine=machine)
    text += "\n".join(rows[c] for c in CASES if c in rows) + "\n"
    MANIFEST.write_text(text)


if __name__ == "__main__":
    main()
