#!/usr/bin/env python3
"""Writes the big-mesh benchmark files into a folder (default /tmp/caustic-knot): the (2, 3)
torus knot of scenes/07-torus-knot.toml with `segments` = 80000 (2 x 80000 x 32 = 5.12 M
triangles, 2.56 M vertices), the same geometry as caustic's `torus_knot` generator, as

    knot.ply        binary little-endian PLY, positions and faces only (about 97 MB; the
                    renderer computes smooth normals, as Mitsuba does)
    knot.obj        OBJ with `v` and `f` lines (about 211 MB)
    knot-vn.obj     with --vn: OBJ with vertex normals numbered apart from the positions
                    (listed in reverse, faces `v//vn`), so a reader must pair them up
    knot-ply.xml    a Mitsuba scene rendering knot.ply at 64 x 48, 1 spp
    knot-obj.xml    the same scene with knot.obj
    empty.xml       the same scene without the knot (the memory baseline)

Peak memory is then measured as in BENCHMARKS.md ("Big meshes"):

    /usr/bin/time -v caustic render /tmp/caustic-knot/knot-ply.xml -o /tmp/k.png

    python3 scripts/make_big_knot.py [--segments 80000] [--out /tmp/caustic-knot]
"""

import argparse
import os

import numpy as np


def knot(p, q, radius, tube, segments, sides):
    """Vertices (float32, segments*sides x 3) and faces (uint32, 2*segments*sides x 3) laid out
    as TriangleMesh::torus_knot lays them out."""

    def curve(s):
        phi = s * 2 * np.pi
        r = radius * (0.6 + 0.4 * np.cos(q * phi))
        return np.stack([r * np.cos(p * phi), radius * 0.4 * np.sin(q * phi), r * np.sin(p * phi)], axis=-1)

    s = np.arange(segments, dtype=np.float64) / segments
    c = curve(s)
    tangent = curve(s + 1e-4) - curve(s - 1e-4)
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    side = np.cross(tangent, c + tangent)
    side -= tangent * np.sum(side * tangent, axis=1, keepdims=True)
    side /= np.linalg.norm(side, axis=1, keepdims=True)
    up = np.cross(tangent, side)
    a = np.arange(sides, dtype=np.float64) / sides * 2 * np.pi
    n = side[:, None, :] * np.cos(a)[None, :, None] + up[:, None, :] * np.sin(a)[None, :, None]
    verts = (c[:, None, :] + n * tube).reshape(-1, 3).astype(np.float32)

    i = np.arange(segments, dtype=np.uint32)[:, None]
    j = np.arange(sides, dtype=np.uint32)[None, :]
    i1, j1 = (i + 1) % segments, (j + 1) % sides
    v = lambda a, b: (a * sides + b).ravel()
    t0 = np.stack([v(i, j), v(i1, j), v(i1, j1)], axis=-1)
    t1 = np.stack([v(i, j), v(i1, j1), v(i, j1)], axis=-1)
    faces = np.stack([t0, t1], axis=1).reshape(-1, 3)
    return verts, faces


def write_ply(path, verts, faces):
    header = (
        "ply\nformat binary_little_endian 1.0\ncomment caustic scripts/make_big_knot.py\n"
        f"element vertex {len(verts)}\nproperty float x\nproperty float y\nproperty float z\n"
        f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n"
    )
    rec = np.zeros(len(faces), dtype=[("n", "u1"), ("i", "<i4", 3)])
    rec["n"] = 3
    rec["i"] = faces
    with open(path, "wb") as f:
        f.write(header.encode())
        f.write(verts.astype("<f4").tobytes())
        f.write(rec.tobytes())


def write_obj(path, verts, faces, normals=None, chunk=200_000):
    with open(path, "w") as f:
        f.write("# caustic scripts/make_big_knot.py\no knot\n")
        for k in range(0, len(verts), chunk):
            np.savetxt(f, verts[k : k + chunk], fmt="v %.7g %.7g %.7g")
        if normals is not None:
            rev = normals[::-1]
            for k in range(0, len(rev), chunk):
                np.savetxt(f, rev[k : k + chunk], fmt="vn %.6f %.6f %.6f")
        n = len(verts)
        for k in range(0, len(faces), chunk):
            fk = faces[k : k + chunk].astype(np.int64)
            if normals is None:
                np.savetxt(f, fk + 1, fmt="f %d %d %d")
            else:
                pairs = np.stack([fk + 1, n - fk], axis=-1).reshape(-1, 6)
                np.savetxt(f, pairs, fmt="f %d//%d %d//%d %d//%d")


SCENE = """<?xml version="1.0"?>
<!-- Big-mesh benchmark (scripts/make_big_knot.py): the 5 M-triangle torus knot. -->
<scene version="3.0.0">
    <integrator type="path"><integer name="max_depth" value="2"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0, 0, 8" target="0, 0, 0" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="1"/></sampler>
        <film type="hdrfilm"><integer name="width" value="64"/><integer name="height" value="48"/></film>
    </sensor>
    <emitter type="point"><point name="position" x="-4" y="8" z="7"/><rgb name="intensity" value="80"/></emitter>
    <shape type="sphere"><float name="radius" value="0.1"/><point name="center" x="3" y="0" z="0"/></shape>
{shape}</scene>
"""


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--segments", type=int, default=80000)
    ap.add_argument("--out", default="/tmp/caustic-knot")
    ap.add_argument("--no-obj", action="store_true")
    ap.add_argument("--vn", action="store_true", help="also write knot-vn.obj (normals numbered apart)")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    verts, faces = knot(2, 3, 1.5, 0.28, args.segments, 32)
    write_ply(os.path.join(args.out, "knot.ply"), verts, faces)
    if not args.no_obj:
        write_obj(os.path.join(args.out, "knot.obj"), verts, faces)
    if args.vn:
        # Smooth normals: the average of the adjacent faces' (enough for a reader's test).
        fn = np.cross(verts[faces[:, 1]] - verts[faces[:, 0]], verts[faces[:, 2]] - verts[faces[:, 0]])
        vn = np.zeros_like(verts)
        for c in range(3):
            np.add.at(vn, faces[:, c], fn)
        vn /= np.maximum(np.linalg.norm(vn, axis=1, keepdims=True), 1e-30)
        write_obj(os.path.join(args.out, "knot-vn.obj"), verts, faces, vn)
    for kind in ["ply", "obj"]:
        shape = f'    <shape type="{kind}"><string name="filename" value="knot.{kind}"/></shape>\n'
        with open(os.path.join(args.out, f"knot-{kind}.xml"), "w") as f:
            f.write(SCENE.replace("{shape}", shape))
    with open(os.path.join(args.out, "empty.xml"), "w") as f:
        f.write(SCENE.replace("{shape}", ""))
    print(f"{len(faces)} triangles, {len(verts)} vertices in {args.out}")


if __name__ == "__main__":
    main()
