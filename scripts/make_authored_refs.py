#!/usr/bin/env python3
"""Renders the Mitsuba 3 reference images of tests/data/authored: scenes written the way
Mitsuba's authors write them (wrapped integrators, <include> chains, <path> folders, spectra),
which tests/mitsuba_authored.rs compares caustic's images with. Same procedure and manifest
format as make_material_refs.py (two half-sample renders with seeds 1 and 2; their mean is the
reference, their difference Mitsuba's noise). A scene whose comment names `scalar_spectral` is
rendered with that variant (black bodies exist only there), the others with scalar_rgb.

    pip install mitsuba==3.9.1 numpy
    python3 scripts/make_authored_refs.py                  # every case
    python3 scripts/make_authored_refs.py include_chain    # only the named cases
"""
import importlib.util
import re
from pathlib import Path

import mitsuba as mi

HERE = Path(__file__).resolve().parent
spec = importlib.util.spec_from_file_location("material_refs", HERE / "make_material_refs.py")
refs = importlib.util.module_from_spec(spec)
spec.loader.exec_module(refs)

refs.DIR = HERE.parent / "tests" / "data" / "authored"
refs.MANIFEST = refs.DIR / "MANIFEST.md"
refs.HEADER = refs.HEADER.replace("material and texture tests", "tests of scenes as Mitsuba's authors write them").replace(
    "make_material_refs.py", "make_authored_refs.py").replace(
    "(`scalar_rgb`, pip package)", "(`scalar_rgb`, or `scalar_spectral` where the scene says so; pip package)").replace(
    "The scenes come from\n`scripts/make_material_scenes.py`, their textures from `scripts/make_material_textures.py`.",
    "The scenes are written\nby hand; they share include/base.xml and the folder common/.").replace(
    "every case uses `path` except `mask_*`, which uses\n`volpath` so that shadow rays pass the mask's holes; see below",
    "the first integrator element of the scene, which may wrap the one that renders").replace(
    "and the\nshare of the image's luminance in pixels whose centre sees the sphere or panels rather than the floor",
    "and (unused\nhere) the object share")
refs.spp_for = lambda case: 16384 if "glass" in case else 4096


def make_textures():
    """common/textures/stripes.png: 1920 x 1080, vertical stripes 8 texels wide, each one of
    eight colours at random (seed 7), for the textured spot light."""
    import numpy as np
    path = refs.DIR / "common" / "textures" / "stripes.png"
    if path.exists():
        return
    mi.set_variant("scalar_rgb")
    colours = np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 0], [0, 1, 1], [1, 0, 1], [1, 1, 1], [0, 0, 0]],
                       np.float32)
    seq = np.random.default_rng(7).integers(0, 8, 1920 // 8)
    img = np.repeat(colours[seq], 8, axis=0)[None, :, :].repeat(1080, axis=0)
    mi.Bitmap(img).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.UInt8, srgb_gamma=True).write(str(path))
refs.object_share = lambda scene, image: None

_render = refs.render


def render(case):
    text = (refs.DIR / f"{case}.xml").read_text()
    mi.set_variant("scalar_spectral" if "scalar_spectral" in text.split("<scene")[0] else "scalar_rgb")
    return _render(case)


refs.render = render

if __name__ == "__main__":
    make_textures()
    refs.main()
