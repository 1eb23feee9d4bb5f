#!/usr/bin/env python3
"""Renders the Mitsuba 3 `scalar_spectral` references of tests/data/spectral, which
tests/spectral.rs compares caustic's spectral mode with: the bundled Cornell box
(scenes/mitsuba/cornell-box.xml at 64 x 64) and two cases of the materials showcase
(tests/data/materials: gold, whose eta and k Mitsuba reads as measured spectra, and a smooth
plastic). Same procedure and manifest format as make_material_refs.py (two half-sample renders
with seeds 1 and 2; their mean is the reference, their difference Mitsuba's noise), every case
with the `scalar_spectral` variant.

    pip install mitsuba==3.9.1 numpy
    python3 scripts/make_spectral_refs.py                # every case
    python3 scripts/make_spectral_refs.py cornell_box    # only the named cases
"""
import importlib.util
from pathlib import Path

import mitsuba as mi

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
refs.spp_for = lambda case: 4096
refs.object_share = lambda scene, image: None

_render = refs.render


def render(case):
    mi.set_variant("scalar_spectral")
    return _render(case)


refs.render = render

if __name__ == "__main__":
    refs.main()
