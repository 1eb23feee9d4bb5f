#!/usr/bin/env python3
"""Renders the Mitsuba 3 reference image that tests/mitsuba.rs compares our path tracer with.

    python3 -m venv /tmp/mi-venv && /tmp/mi-venv/bin/pip install mitsuba numpy
    /tmp/mi-venv/bin/python scripts/mitsuba_reference.py

It renders scenes/mitsuba/cornell-box.xml with Mitsuba's own path tracer (scalar_rgb variant) at
64 x 64 and writes tests/data/mitsuba/cornell_ref.exr (linear RGB, float32). CI does not need
Mitsuba: the EXR is committed.
"""
import sys
from pathlib import Path

import mitsuba as mi

ROOT = Path(__file__).resolve().parent.parent
SCENE = ROOT / "scenes" / "mitsuba" / "cornell-box.xml"
OUT = ROOT / "tests" / "data" / "mitsuba" / "cornell_ref.exr"
RES = 64
SPP = int(sys.argv[1]) if len(sys.argv) > 1 else 8192

mi.set_variant("scalar_rgb")
scene = mi.load_file(str(SCENE), spp=str(SPP), res=str(RES))
image = mi.render(scene, seed=1)
bmp = mi.Bitmap(image, pixel_format=mi.Bitmap.PixelFormat.RGB)
OUT.parent.mkdir(parents=True, exist_ok=True)
bmp.convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32, srgb_gamma=False).write(str(OUT))
print(f"mitsuba {mi.__version__}: wrote {OUT} ({RES}x{RES}, {SPP} spp)")
