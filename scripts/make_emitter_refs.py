#!/usr/bin/env python3
"""Renders the Mitsuba 3 reference images of tests/data/emitters (see make_emitter_scenes.py)
with the same procedure and manifest format as make_material_refs.py: two half-sample renders
with seeds 1 and 2, their mean as tests/data/emitters/<case>.exr, their difference as Mitsuba's
noise in tests/data/emitters/MANIFEST.md.

    python3 scripts/make_emitter_refs.py            # every case
    python3 scripts/make_emitter_refs.py projector  # only the named cases
"""
import importlib.util
from pathlib import Path

HERE = Path(__file__).resolve().parent
spec = importlib.util.spec_from_file_location("material_refs", HERE / "make_material_refs.py")
refs = importlib.util.module_from_spec(spec)
spec.loader.exec_module(refs)

refs.DIR = HERE.parent / "tests" / "data" / "emitters"
refs.MANIFEST = refs.DIR / "MANIFEST.md"
refs.HEADER = refs.HEADER.replace("material and texture tests", "emitter tests").replace(
    "make_material_refs.py", "make_emitter_refs.py").replace(
    "make_material_scenes.py`, their textures from `scripts/make_material_textures.py",
    "make_emitter_scenes.py`; the textures are those of tests/data/materials").replace(
    "every case uses `path` except `mask_*`, which uses\n`volpath` so that shadow rays pass the mask's holes; see below",
    "every case uses `path`").replace(
    "and the\nshare of the image's luminance in pixels whose centre sees the sphere or panels rather than the floor",
    "and (unused\nhere) the object share")
refs.spp_for = lambda case: 4096
refs.object_share = lambda scene, image: None

if __name__ == "__main__":
    refs.main()
