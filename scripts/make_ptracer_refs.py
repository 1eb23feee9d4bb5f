#!/usr/bin/env python3
"""Renders the Mitsuba 3 reference images of tests/data/ptracer, which caustic's light tracer
(`--integrator light`) is compared with: scenes whose integrator is Mitsuba's particle tracer
`ptracer`. Same procedure and manifest format as make_material_refs.py (two half-sample renders
with seeds 1 and 2; their mean is the reference, their difference Mitsuba's noise).

    python3 scripts/make_ptracer_refs.py                # every case
    python3 scripts/make_ptracer_refs.py all_emitters   # only the named cases
"""
import importlib.util
from pathlib import Path

HERE = Path(__file__).resolve().parent
spec = importlib.util.spec_from_file_location("material_refs", HERE / "make_material_refs.py")
refs = importlib.util.module_from_spec(spec)
spec.loader.exec_module(refs)

refs.DIR = HERE.parent / "tests" / "data" / "ptracer"
refs.MANIFEST = refs.DIR / "MANIFEST.md"
refs.HEADER = refs.HEADER.replace("material and texture tests", "light-tracer tests").replace(
    "make_material_refs.py", "make_ptracer_refs.py").replace(
    "The scenes come from\n`scripts/make_material_scenes.py`, their textures from `scripts/make_material_textures.py`.",
    "The scenes are written\nby hand; their textures are those of tests/data/materials and tests/data/lights.").replace(
    "every case uses `path` except `mask_*`, which uses\n`volpath` so that shadow rays pass the mask's holes; see below",
    "every case uses `ptracer`").replace(
    "and the\nshare of the image's luminance in pixels whose centre sees the sphere or panels rather than the floor",
    "and (unused\nhere) the object share")
refs.spp_for = lambda case: 8192
refs.object_share = lambda scene, image: None

if __name__ == "__main__":
    refs.main()
