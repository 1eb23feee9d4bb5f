#!/usr/bin/env python3
"""Renders the Mitsuba 3 `scalar_spectral` references of tests/data/spectral, which
tests/spectral.rs compares caustic's spectral mode with: the bundled Cornell box
(scenes/mitsuba/cornell-box.xml at 64 x 64) and two cases of the materials showcase
(tests/data/materials: gold, whose eta and k Mitsuba reads as measured spectra, and a smooth
plastic). Same procedure and manifest format as make_material_refs.py (two half-sample renders
with seeds 1 and 2; their mean is the reference, their difference Mitsuba's noise), every case
with the `scalar_spectral` variant. Unlike there, a pixel may be slightly negative in a channel:
the sRGB of a saturated spectrum (gold's) is, in Mitsuba's spectral renders as in caustic's.

    pip install mitsuba==3.9.1 numpy
    python3 scripts/make_spectral_refs.py                # every case
    python3 scripts/make_spectral_refs.py cornell_box    # only the named cases
"""
import importlib.util
import re
import time
from pathlib import Path

import mitsuba as mi
import numpy as np

HERE = Path(__file__).resolve().parent
spec = importlib.util.spec_from_file_location("material_refs", HERE / "make_material_refs.py")
refs = importlib.util.module_from_spec(spec)
spec.loader.exec_module(refs)

refs.DIR = HERE.parent / "tests" / "data" / "spectral"
refs.MANIFEST = refs.DIR / "MANIFEST.md"
refs.HEADER = refs.HEADER.replace("material and texture tests", "tests of the spectral mode").replace(
    "make_material_refs.py", "make_spectral_refs.py").replace(
    "(`scalar_rgb`, pip package)", "(`scalar_spectral`, pip package)").replace(
    "The scenes come from\n`scripts/make_material_scenes.py`, their textures from `scripts/make_material_textures.py`.",
    "`cornell_box.xml` is\nscenes/mitsuba/cornell-box.xml at 64 x 64; the others are copies of tests/data/materials cases.")
SPP = 4096


def render(case):
    mi.set_variant("scalar_spectral")
    path = refs.DIR / f"{case}.xml"
    integrator = re.search(r'<integrator type="(\w+)"', path.read_text()).group(1)
    start = time.time()
    scene = mi.load_file(str(path), spp=str(SPP // 2))
    halves = [np.array(mi.render(scene, seed=refs.SEED + k), dtype=np.float64)[..., :3] for k in range(2)]
    seconds = time.time() - start
    image = (halves[0] + halves[1]) / 2
    # Each half has twice the full image's variance: rmse(a, b)^2 = 4 sigma^2.
    noise = float(np.sqrt(np.mean((halves[0] - halves[1]) ** 2)) / 2)
    assert np.isfinite(image).all(), f"{case}: non-finite pixels"
    bmp = mi.Bitmap(image.astype(np.float32), pixel_format=mi.Bitmap.PixelFormat.RGB)
    bmp.convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float16, srgb_gamma=False).write(str(refs.DIR / f"{case}.exr"))
    row = {
        "case": case,
        "integrator": integrator,
        "size": f"{image.shape[1]}x{image.shape[0]}",
        "spp": SPP,
        "seconds": seconds,
        "mean": image.reshape(-1, 3).mean(axis=0),
        "lum": float(refs.luminance(image).mean()),
        "noise": noise,
        "share": None,
    }
    print(f"{case}: {SPP} spp, {seconds:.1f} s, mean luminance {row['lum']:.5f}, noise {noise:.5f}", flush=True)
    return row


refs.render = render

if __name__ == "__main__":
    refs.main()
