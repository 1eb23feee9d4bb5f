#!/usr/bin/env python3
"""Renders the Mitsuba 3 `scalar_spectral` references of tests/data/spectral, which
tests/spectral.rs compares caustic's spectral mode with: the bundled Cornell box
(scenes/mitsuba/cornell-box.xml at 64 x 64), the materials showcase (scenes/15-materials.toml
as Mitsuba XML, at 96 x 72), two scenes lit by emitted spectra (black bodies; narrow lines),
one whose reflectances and conductor eta and k are wavelength:value lists (reflectance_lists)
and two cases of the materials showcase
(tests/data/materials: gold, whose eta and k Mitsuba reads as measured spectra, and a smooth
plastic). Same procedure and manifest format as make_material_refs.py (two half-sample renders
with seeds 1 and 2; their mean is the reference, their difference Mitsuba's noise), every case
with the `scalar_spectral` variant. Unlike there, a pixel may be slightly negative in a channel:
the sRGB of a saturated spectrum (gold's) is, in Mitsuba's spectral renders as in caustic's.

    pip install mitsuba==3.9.1 numpy
    python3 scripts/make_spectral_refs.py                # every case
    python3 scripts/make_spectral_refs.py cornell_box    # only the named cases
    python3 scripts/make_spectral_refs.py --unbounded 0.444,0.527,1.094

The last form prints the smooth spectrum of an RGB colour whose channels may exceed 1, as a
wavelength:value list every 10 nm: how materials_showcase.xml gives the brass's eta and k. In
Mitsuba 3.9.1's spectral variants an `<rgb>` eta or k is a reflectance spectrum, clamped to
[0, 1] (k = 1 for the brass), while its RGB variants take the colour as it is; a list means the
same in both. The spectrum is the colour's Jakob-Hanika uplift at half its largest channel times
twice that channel (Mitsuba's own model, the lift caustic's spectral mode gives an unbounded
colour), and turns back into the colour within 0.2% (checked here).
"""
import sys
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
    "`cornell_box.xml` is\nscenes/mitsuba/cornell-box.xml at 64 x 64; `materials_showcase.xml` is scenes/15-materials.toml\n"
    "written for Mitsuba (its comment says how) at 96 x 72; `emitter_*.xml` light the scene of the material\n"
    "cases with emitted spectra; `reflectance_lists.xml` gives reflectances and a conductor's eta and k\n"
    "as wavelength:value lists; the others are copies of tests/data/materials cases.")
SPP = 4096
# The showcase's glass and small light sources are noisier: more samples.
SPP_OF = {"materials_showcase": 8192}


def render(case):
    mi.set_variant("scalar_spectral")
    path = refs.DIR / f"{case}.xml"
    integrator = re.search(r'<integrator type="(\w+)"', path.read_text()).group(1)
    start = time.time()
    spp = SPP_OF.get(case, SPP)
    scene = mi.load_file(str(path), spp=str(spp // 2))
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
        "spp": spp,
        "seconds": seconds,
        "mean": image.reshape(-1, 3).mean(axis=0),
        "lum": float(refs.luminance(image).mean()),
        "noise": noise,
        "share": None,
    }
    print(f"{case}: {spp} spp, {seconds:.1f} s, mean luminance {row['lum']:.5f}, noise {noise:.5f}", flush=True)
    return row


refs.render = render


def unbounded_spectrum(rgb):
    """The wavelength:value list (360-830 nm, every 10 nm) of the smooth spectrum of `rgb`."""
    mi.set_variant("scalar_spectral")
    scale = 2 * max(rgb)
    coeff = mi.srgb_model_fetch(mi.Color3f(*(c / scale for c in rgb)))
    waves = range(360, 831, 10)
    values = [scale * mi.srgb_model_eval(coeff, mi.UnpolarizedSpectrum(float(w)))[0] for w in waves]
    mi.set_variant("scalar_rgb")
    back = mi.spectrum_list_to_srgb(list(map(float, waves)), values, bounded=False, d65=True)
    assert all(abs(b / c - 1) < 2e-3 for b, c in zip(back, rgb)), (rgb, back)
    return ", ".join(f"{w}:{v:.4f}" for w, v in zip(waves, values))


if __name__ == "__main__":
    if sys.argv[1:2] == ["--unbounded"]:
        print(unbounded_spectrum([float(c) for c in sys.argv[2].split(",")]))
    else:
        refs.main()
