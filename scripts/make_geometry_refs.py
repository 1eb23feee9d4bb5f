#!/usr/bin/env python3
"""Writes the geometry test scenes of tests/data/geometry (instancing, cylinders and disks,
serialized meshes), their meshes, and renders their Mitsuba 3 reference images.

    pip install mitsuba==3.9.1 numpy
    python3 scripts/make_geometry_refs.py               # meshes, scenes and every reference
    python3 scripts/make_geometry_refs.py --scenes      # meshes and scenes only
    python3 scripts/make_geometry_refs.py instances     # meshes, scenes and the named cases

Meshes (tests/data/geometry/meshes/):
  torus.ply            a torus (R = 1, r = 0.35, 48 x 24 quads) with vertex normals, written by
                       Mitsuba's own PLY writer
  shapes.serialized    two meshes, format version 4, single precision: 0 a tetrahedron
                       (positions only), 1 the torus with normals and uv
  flat_f64_v3.serialized  an octahedron, format version 3, double precision, the face-normals
                       flag set and no normals (Mitsuba 3.9.1 ignores that flag: the octahedron
                       gets smooth normals unless the shape sets face_normals)
The serialized files are written here with struct and zlib following Mitsuba's format
description (Mitsuba's Python API has no serialized writer); each is then loaded by Mitsuba and
compared with what was written, so the files are known to be what Mitsuba reads.

Scenes: instances.xml (two shapegroups, six instances with rotations, uniform and non-uniform
scales), instances_flat.xml (the same geometry written out shape by shape, for the
instanced-against-flattened test), cylinder_disk.xml (cylinders open and textured, disks tilted,
textured and flipped), serialized.xml (the serialized meshes found through <path>).

Rotation axes are written as unit vectors: Mitsuba 3.9.1 does not normalise a <rotate> axis (a
non-unit one also scales and shears), while caustic does.

References are rendered like those of tests/data/materials (scripts/make_material_refs.py): each
<case>.exr is the mean of two renders with seeds 1 and 2 at spp/2 each (RGB half floats), and
MANIFEST.md lists per case the sample count, the time, the mean colour and luminance and
Mitsuba's own noise (rmse(a, b) / 2 of the halves). CI does not need Mitsuba: everything written
here is committed.
"""
import math
import platform
import struct
import sys
import time
import zlib
from pathlib import Path

import mitsuba as mi
import numpy as np

ROOT = Path(__file__).resolve().parent.parent
DIR = ROOT / "tests" / "data" / "geometry"
MESHES = DIR / "meshes"
SEED = 1
CASES = {"instances": 4096, "instances_flat": 4096, "cylinder_disk": 4096, "serialized": 4096}


# ---------------------------------------------------------------------------------------------
# Meshes
# ---------------------------------------------------------------------------------------------

def torus(R=1.0, r=0.35, nu=48, nv=24):
    """Positions, normals, uv (u around the main ring, v around the tube) and triangles."""
    pos, nrm, uv, tri = [], [], [], []
    for i in range(nu + 1):
        a = 2 * math.pi * i / nu
        for j in range(nv + 1):
            b = 2 * math.pi * j / nv
            n = (math.cos(a) * math.cos(b), math.sin(a) * math.cos(b), math.sin(b))
            c = (R * math.cos(a), R * math.sin(a), 0.0)
            pos.append(tuple(c[k] + r * n[k] for k in range(3)))
            nrm.append(n)
            uv.append((i / nu, j / nv))
    w = nv + 1
    for i in range(nu):
        for j in range(nv):
            a, b, c, d = i * w + j, (i + 1) * w + j, (i + 1) * w + j + 1, i * w + j + 1
            tri += [(a, b, c), (a, c, d)]
    return pos, nrm, uv, tri


def tetrahedron():
    pos = [(1, 1, 1), (1, -1, -1), (-1, 1, -1), (-1, -1, 1)]
    tri = [(0, 1, 2), (0, 3, 1), (0, 2, 3), (1, 3, 2)]
    return [tuple(0.5 * x for x in p) for p in pos], tri


def octahedron():
    pos = [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1)]
    tri = [(0, 2, 4), (2, 1, 4), (1, 3, 4), (3, 0, 4), (2, 0, 5), (1, 2, 5), (3, 1, 5), (0, 3, 5)]
    return pos, tri


def serialized_mesh(version, double, positions, triangles, normals=None, uvs=None, face_normals=False, name="mesh"):
    """One mesh of a serialized file: header and zlib stream."""
    flags = (0x0001 if normals else 0) | (0x0002 if uvs else 0) | (0x0010 if face_normals else 0)
    flags |= 0x2000 if double else 0x1000
    f = "d" if double else "f"
    body = struct.pack("<I", flags)
    if version == 4:
        body += name.encode() + b"\0"
    body += struct.pack("<QQ", len(positions), len(triangles))
    for arr in (positions, normals, uvs):
        if arr:
            flat = [x for v in arr for x in v]
            body += struct.pack(f"<{len(flat)}{f}", *flat)
    flat = [i for t in triangles for i in t]
    body += struct.pack(f"<{len(flat)}I", *flat)
    return struct.pack("<HH", 0x041C, version) + zlib.compress(body)


def serialized_file(version, meshes):
    out, offsets = b"", []
    for m in meshes:
        offsets.append(len(out))
        out += m
    width = "Q" if version == 4 else "I"
    out += struct.pack(f"<{len(offsets)}{width}", *offsets) + struct.pack("<I", len(meshes))
    return out


def check_serialized(path, index, positions, uvs=None):
    """Loads mesh `index` of `path` with Mitsuba and compares it with what was written."""
    shape = mi.load_dict({"type": "serialized", "filename": str(path), "shape_index": index})
    params = mi.traverse(shape)
    got = np.array(params["vertex_positions"]).reshape(-1, 3)
    assert np.allclose(got, np.array(positions), atol=1e-6), f"{path.name}@{index}: positions differ"
    if uvs is not None:
        got = np.array(params["vertex_texcoords"]).reshape(-1, 2)
        assert np.allclose(got, np.array(uvs), atol=1e-6), f"{path.name}@{index}: uv differ"


def write_meshes():
    MESHES.mkdir(parents=True, exist_ok=True)
    pos, nrm, uv, tri = torus()
    mesh = mi.Mesh("torus", len(pos), len(tri), has_vertex_normals=True)
    params = mi.traverse(mesh)
    params["vertex_positions"] = np.array(pos, dtype=np.float32).ravel()
    params["vertex_normals"] = np.array(nrm, dtype=np.float32).ravel()
    params["faces"] = np.array(tri, dtype=np.uint32).ravel()
    params.update()
    mesh.write_ply(str(MESHES / "torus.ply"))

    tpos, ttri = tetrahedron()
    data = serialized_file(4, [
        serialized_mesh(4, False, tpos, ttri, name="tetrahedron"),
        serialized_mesh(4, False, pos, tri, normals=nrm, uvs=uv, name="torus"),
    ])
    (MESHES / "shapes.serialized").write_bytes(data)
    check_serialized(MESHES / "shapes.serialized", 0, tpos)
    check_serialized(MESHES / "shapes.serialized", 1, pos, uv)

    opos, otri = octahedron()
    data = serialized_file(3, [serialized_mesh(3, True, opos, otri, face_normals=True)])
    (MESHES / "flat_f64_v3.serialized").write_bytes(data)
    check_serialized(MESHES / "flat_f64_v3.serialized", 0, opos)


# ---------------------------------------------------------------------------------------------
# Scenes
# ---------------------------------------------------------------------------------------------

HEAD = """<?xml version="1.0" encoding="utf-8"?>
<!-- {comment}
     Reference image: {case}.exr, rendered by scripts/make_geometry_refs.py with Mitsuba 3.9.1
     (scalar_rgb); the same script wrote this file. -->
<scene version="3.0.0">
    <default name="spp" value="64"/>
    <default name="res" value="64"/>

    <integrator type="path">
        <integer name="max_depth" value="6"/>
    </integrator>
    <sensor type="perspective">
        <float name="fov" value="{fov}"/>
        <transform name="to_world">
            <lookat origin="{origin}" target="{target}" up="0, 0, 1"/>
        </transform>
        <sampler type="independent">
            <integer name="sample_count" value="$spp"/>
        </sampler>
        <film type="hdrfilm">
            <integer name="width" value="$res"/>
            <integer name="height" value="$res"/>
            <string name="pixel_format" value="rgb"/>
            <rfilter type="box"/>
        </film>
    </sensor>

    <!-- A grey floor at z = 0, a point light and a rectangular area light. -->
    <shape type="rectangle">
        <transform name="to_world"><scale value="10"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.45"/></bsdf>
    </shape>
    <emitter type="point">
        <point name="position" x="-3" y="-2.5" z="6"/>
        <rgb name="intensity" value="60"/>
    </emitter>
    <shape type="rectangle">
        <transform name="to_world">
            <scale value="0.6"/>
            <rotate x="1" angle="180"/>
            <translate x="2" y="1" z="4"/>
        </transform>
        <emitter type="area"><rgb name="radiance" value="12"/></emitter>
    </shape>
"""


def diffuse(rgb):
    return f'<bsdf type="diffuse"><rgb name="reflectance" value="{rgb}"/></bsdf>'


# The two groups: a torus with a sphere in its hole, and the torus alone (for the instance
# scaled unevenly, which a sphere could not follow in the flattened scene).
GROUPS = {
    "thing": [
        ("ply", '<string name="filename" value="meshes/torus.ply"/>', diffuse("0.7, 0.35, 0.15"), ""),
        ("sphere", '<float name="radius" value="0.5"/>', diffuse("0.15, 0.3, 0.7"), ""),
    ],
    "ring": [
        ("ply", '<string name="filename" value="meshes/torus.ply"/>', diffuse("0.25, 0.6, 0.3"), ""),
    ],
}
# (group, transform operations in order)
INSTANCES = [
    ("thing", '<scale value="0.5"/><rotate x="1" angle="90"/><translate x="-1.3" y="0.2" z="0.68"/>'),
    ("thing", '<scale value="0.45"/><translate x="0" y="-0.7" z="0.23"/>'),
    ("thing", '<scale value="0.35"/><rotate x="0.70710678" y="0.70710678" angle="50"/><translate x="0.3" y="1.3" z="0.55"/>'),
    ("thing", '<scale value="0.3"/><rotate y="1" angle="-60"/><rotate z="1" angle="20"/>'
              '<translate x="-0.6" y="1.0" z="1.5"/>'),
    ("ring", '<scale x="0.7" y="0.35" z="0.45"/><rotate z="1" angle="30"/><translate x="1.3" y="0.1" z="0.16"/>'),
    ("ring", '<scale x="0.3" y="0.3" z="0.8"/><rotate y="1" angle="70"/><translate x="1.4" y="-1.2" z="0.45"/>'),
]
CAMERA = {"fov": "40", "origin": "0.5, -6, 4", "target": "0, 0.2, 0.4"}


def instances_scene():
    out = HEAD.format(case="instances", comment="Instancing: two shapegroups (a PLY torus with a sphere in "
                      "its hole, and the torus alone) placed six times with rotations, uniform and "
                      "non-uniform scales; each shape keeps its own BSDF.", **CAMERA)
    for gid, shapes in GROUPS.items():
        out += f'\n    <shape type="shapegroup" id="{gid}">\n'
        for kind, props, bsdf, _ in shapes:
            out += f'        <shape type="{kind}">\n            {props}\n            {bsdf}\n        </shape>\n'
        out += "    </shape>\n"
    for gid, ops in INSTANCES:
        out += (f'    <shape type="instance">\n        <ref id="{gid}"/>\n'
                f'        <transform name="to_world">{ops}</transform>\n    </shape>\n')
    return out + "</scene>\n"


def flat_scene():
    out = HEAD.format(case="instances_flat", comment="The geometry of instances.xml written out shape by "
                      "shape: each shape of a group with the instance's transform as its to_world.", **CAMERA)
    for gid, ops in INSTANCES:
        for kind, props, bsdf, _ in GROUPS[gid]:
            out += (f'    <shape type="{kind}">\n        {props}\n        {bsdf}\n'
                    f'        <transform name="to_world">{ops}</transform>\n    </shape>\n')
    return out + "</scene>\n"


CHECKER = """<bsdf type="{wrap}">
            <bsdf type="diffuse">
                <texture type="checkerboard" name="reflectance">
                    <rgb name="color0" value="{c0}"/>
                    <rgb name="color1" value="{c1}"/>
                    <transform name="to_uv"><scale x="{su}" y="{sv}"/></transform>
                </texture>
            </bsdf>
        </bsdf>"""


def cylinder_disk_scene():
    out = HEAD.format(case="cylinder_disk", comment="Analytic cylinders and disks: an open upright tube "
                      "with a two-sided checkerboard (its inside seen through the top), a tube lying on "
                      "the floor from p0 to p1, a tilted checkered disk (uv = (r, phi / 2 pi)), and a disk "
                      "on the floor with flip_normals (its one-sided diffuse back is black).",
                      fov="38", origin="0.3, -5.5, 4.5", target="0, 0.2, 0.3")
    tube = CHECKER.format(wrap="twosided", c0="0.8, 0.7, 0.2", c1="0.1, 0.2, 0.6", su="8", sv="4")
    disk = CHECKER.format(wrap="twosided", c0="0.75, 0.2, 0.2", c1="0.9, 0.9, 0.85", su="4", sv="8")
    out += f"""
    <shape type="cylinder">
        <transform name="to_world"><scale x="0.55" y="0.55" z="1.3"/><translate x="-1.1" y="0.3"/></transform>
        {tube}
    </shape>
    <shape type="cylinder">
        <point name="p0" x="0.2" y="-0.9" z="0.3"/>
        <point name="p1" x="1.6" y="-0.4" z="0.3"/>
        <float name="radius" value="0.3"/>
        {diffuse("0.3, 0.55, 0.6")}
    </shape>
    <shape type="disk">
        <transform name="to_world"><scale value="0.7"/><rotate x="1" angle="-55"/><rotate z="1" angle="20"/>
            <translate x="0.9" y="1.0" z="0.9"/></transform>
        {disk}
    </shape>
    <shape type="disk">
        <boolean name="flip_normals" value="true"/>
        <transform name="to_world"><scale value="0.5"/><translate x="-0.3" y="-1.6" z="0.002"/></transform>
        {diffuse("0.8, 0.8, 0.8")}
    </shape>
</scene>
"""
    return out


def serialized_scene():
    out = HEAD.format(case="serialized", comment="Serialized meshes found through <path value=\"meshes\"/>: "
                      "mesh 1 of shapes.serialized (a torus with normals and uv, under a checkerboard), mesh "
                      "0 (a tetrahedron) with face_normals, and a double-precision version-3 octahedron "
                      "whose file asks for face normals, which Mitsuba 3.9.1 ignores (it is shaded smooth).", fov="38", origin="0.3, -5.5, 4.5",
                      target="0, 0.2, 0.4")
    torus_bsdf = CHECKER.format(wrap="twosided", c0="0.8, 0.6, 0.2", c1="0.15, 0.25, 0.55", su="12", sv="4")
    out += f"""
    <path value="meshes"/>
    <shape type="serialized">
        <string name="filename" value="shapes.serialized"/>
        <integer name="shape_index" value="1"/>
        <transform name="to_world"><scale value="0.75"/><rotate x="1" angle="35"/><translate x="-0.5" y="0.4" z="0.8"/></transform>
        {torus_bsdf}
    </shape>
    <shape type="serialized">
        <string name="filename" value="shapes.serialized"/>
        <boolean name="face_normals" value="true"/>
        <transform name="to_world"><scale value="0.8"/><rotate z="1" angle="25"/><translate x="1.2" y="-0.6" z="0.45"/></transform>
        {diffuse("0.7, 0.7, 0.3")}
    </shape>
    <shape type="serialized">
        <string name="filename" value="flat_f64_v3.serialized"/>
        <transform name="to_world"><scale value="0.55"/><rotate z="1" angle="30"/><translate x="1.0" y="1.1" z="0.55"/></transform>
        {diffuse("0.6, 0.3, 0.6")}
    </shape>
</scene>
"""
    return out


def write_scenes():
    DIR.mkdir(parents=True, exist_ok=True)
    for name, text in [("instances", instances_scene()), ("instances_flat", flat_scene()),
                       ("cylinder_disk", cylinder_disk_scene()), ("serialized", serialized_scene())]:
        (DIR / f"{name}.xml").write_text(text)


# ---------------------------------------------------------------------------------------------
# References
# ---------------------------------------------------------------------------------------------

def luminance(rgb):
    return 0.2126 * rgb[..., 0] + 0.7152 * rgb[..., 1] + 0.0722 * rgb[..., 2]


def render(case):
    spp = CASES[case]
    start = time.time()
    scene = mi.load_file(str(DIR / f"{case}.xml"), spp=str(spp // 2))
    halves = [np.array(mi.render(scene, seed=SEED + k), dtype=np.float64) for k in range(2)]
    seconds = time.time() - start
    image = (halves[0] + halves[1]) / 2
    noise = float(np.sqrt(np.mean((halves[0] - halves[1]) ** 2)) / 2)
    assert np.isfinite(image).all() and image.min() >= 0, case
    bmp = mi.Bitmap(image.astype(np.float32), pixel_format=mi.Bitmap.PixelFormat.RGB)
    bmp.convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float16, srgb_gamma=False).write(str(DIR / f"{case}.exr"))
    mean = image.reshape(-1, 3).mean(axis=0)
    row = {"case": case, "size": f"{image.shape[1]}x{image.shape[0]}", "spp": spp, "seconds": seconds,
           "mean": mean, "lum": float(luminance(image).mean()), "noise": noise}
    print(f"{case}: {spp} spp, {seconds:.1f} s, mean luminance {row['lum']:.5f}, noise {noise:.5f}", flush=True)
    return row


HEADER = """# Mitsuba 3 references for the geometry tests

Rendered by `scripts/make_geometry_refs.py` with Mitsuba {version} (`scalar_rgb`, pip package) on
{machine}, as

    python3 scripts/make_geometry_refs.py

which also writes the scenes and the meshes in `meshes/` (see its docstring). Each `<case>.exr` is
the mean of two renders of `<case>.xml` with seeds 1 and 2 at spp/2 each, stored as RGB half
floats; `tests/geometry.rs` compares caustic's path tracer with them (mean luminance within 1%,
RMSE within 1.25 times the noise both images predict).

Columns: image size, samples per pixel, wall-clock seconds on 2 cores, the image's mean R, G, B,
its mean Rec. 709 luminance and Mitsuba's own noise (the RMS over pixels and channels of each
pixel's standard deviation, from the two halves: rmse(a, b) / 2).

| case | size | spp | s | mean R, G, B | mean lum. | noise |
|---|---|---|---|---|---|---|
"""


def main():
    mi.set_variant("scalar_rgb")
    args = sys.argv[1:]
    write_meshes()
    write_scenes()
    if args == ["--scenes"]:
        return
    rows = [render(case) for case in (args or CASES)]
    if args:
        return
    body = "\n".join(
        f"| `{r['case']}` | {r['size']} | {r['spp']} | {r['seconds']:.0f} | "
        f"{', '.join(f'{c:.4f}' for c in r['mean'])} | {r['lum']:.5f} | {r['noise']:.5f} |" for r in rows)
    machine = f"{platform.machine()} Linux, Python {platform.python_version()}"
    (DIR / "MANIFEST.md").write_text(HEADER.format(version=mi.__version__, machine=machine) + body + "\n")


if __name__ == "__main__":
    main()
