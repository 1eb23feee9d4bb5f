#!/usr/bin/env python3
"""Renders the Mitsuba 3 `scalar_spectral` references of tests/data/spectral_media, which
tests/spectral_media.rs compares caustic's spectral volumetric path tracer with: three cases of
tests/data/media (a homogeneous chromatic fog under an area light, the heterogeneous RGB grids of
`hetero_rgb`, and a fog around an emitter), copied here with their grids. The procedure and the
manifest are those of make_spectral_refs.py (itself make_material_refs.py's): two half-sample
renders with seeds 1 and 2, their mean the reference and their difference Mitsuba's noise.

    pip install mitsuba==3.9.1 numpy
    python3 scripts/make_spectral_media_refs.py              # every case
    python3 scripts/make_spectral_media_refs.py cube_area    # only the named cases
"""
import importlib.util
import shutil
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
spec = importlib.util.spec_from_file_location("spectral_refs", HERE / "make_spectral_refs.py")
spectral = importlib.util.module_from_spec(spec)
spec.loader.exec_module(spectral)
refs = spectral.refs

MEDIA = HERE.parent / "tests" / "data" / "media"
CASES = {"cube_area": [], "hetero_rgb": ["hetero_rgb_sigma_t.vol", "hetero_rgb_albedo.vol"], "emitter_inside": []}

refs.DIR = HERE.parent / "tests" / "data" / "spectral_media"
refs.MANIFEST = refs.DIR / "MANIFEST.md"
refs.HEADER = refs.HEADER.replace("tests of the spectral mode", "tests of the spectral mode in media").replace(
    "make_spectral_refs.py", "make_spectral_media_refs.py").replace(
    "`cornell_box.xml` is\nscenes/mitsuba/cornell-box.xml at 64 x 64; the others are copies of tests/data/materials cases.",
    "The scenes (and the\ngrids of `hetero_rgb`) are copies of tests/data/media cases.").replace(
    "(every case uses `path` except `mask_*`, which uses\n`volpath` so that shadow rays pass the mask's holes; see below)",
    "(`volpath` in every case)")


def copy_scenes():
    refs.DIR.mkdir(parents=True, exist_ok=True)
    for case, grids in CASES.items():
        text = (MEDIA / f"{case}.xml").read_text().replace(
            "Mitsuba 3 (scalar_rgb, volpath),\n     which also wrote this file",
            "Mitsuba 3 (scalar_spectral, volpath):\n     scripts/make_spectral_media_refs.py, which copied this file from tests/data/media")
        (refs.DIR / f"{case}.xml").write_text(text)
        for g in grids:
            shutil.copyfile(MEDIA / g, refs.DIR / g)


if __name__ == "__main__":
    copy_scenes()
    if len(sys.argv) == 1:
        sys.argv += sorted(CASES)
    refs.main()
