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

def make_meshes():
    """common/meshes/blob_attributes.ply: an icosphere of 320 triangles (binary, little-endian)
    with a float colour per vertex (`r g b`: Mitsuba's vertex_color, 0.5 + 0.5 n) and a float
    per face (`weight_0`: Mitsuba's face_weight, a smooth function of the face's centre)."""
    import numpy as np
    path = refs.DIR / "common" / "meshes" / "blob_attributes.ply"
    if path.exists():
        return
    path.parent.mkdir(parents=True, exist_ok=True)
    t = (1 + 5 ** 0.5) / 2
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
         (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    v = [np.array(p, float) / np.linalg.norm(p) for p in v]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2), (10, 7, 6),
         (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10),
         (8, 6, 7), (9, 8, 1)]
    for _ in range(2):
        mid, nf = {}, []
        def m(a, b):
            k = (min(a, b), max(a, b))
            if k not in mid:
                p = v[a] + v[b]
                v.append(p / np.linalg.norm(p))
                mid[k] = len(v) - 1
            return mid[k]
        for a, b, c in f:
            ab, bc, ca = m(a, b), m(b, c), m(c, a)
            nf += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        f = nf
    pos = np.array(v, np.float32)
    col = (0.5 + 0.5 * pos).astype(np.float32)
    centres = pos[np.array(f)].mean(axis=1)
    weight = (0.5 + 0.5 * np.sin(4 * centres[:, 0] + 2 * centres[:, 2])).astype(np.float32)
    header = (f"ply\nformat binary_little_endian 1.0\nelement vertex {len(pos)}\n"
              "property float x\nproperty float y\nproperty float z\n"
              "property float r\nproperty float g\nproperty float b\n"
              f"element face {len(f)}\nproperty list uchar int vertex_indices\nproperty float weight_0\nend_header\n")
    with open(path, "wb") as out:
        out.write(header.encode())
        out.write(np.hstack([pos, col]).astype("<f4").tobytes())
        for tri, w in zip(f, weight):
            out.write(bytes([3]) + np.array(tri, "<i4").tobytes() + np.array([w], "<f4").tobytes())


def make_volumes():
    """common/volumes/torus.vol: the signed distance to a torus (radii 0.28 and 0.12, axis z)
    sampled on a 40^3 grid over [0, 1]^3, in Mitsuba's .vol format (version 3, float32)."""
    import numpy as np
    path = refs.DIR / "common" / "volumes" / "torus.vol"
    if path.exists():
        return
    path.parent.mkdir(parents=True, exist_ok=True)
    n = 40
    x = np.linspace(0, 1, n, dtype=np.float64) - 0.5
    z, y, xx = np.meshgrid(x, x, x, indexing="ij")
    q = np.sqrt(xx ** 2 + y ** 2) - 0.28
    sdf = (np.sqrt(q ** 2 + z ** 2) - 0.12).astype("<f4")
    header = b"VOL" + bytes([3]) + np.array([1, n, n, n, 1], "<i4").tobytes() + np.array([0, 0, 0, 1, 1, 1], "<f4").tobytes()
    path.write_bytes(header + sdf.tobytes())


if __name__ == "__main__":
    make_textures()
    make_meshes()
    make_volumes()
    refs.main()
