#!/usr/bin/env python3
"""Writes the small meshes of scenes/mitsuba/meshes: an icosphere (subdivided twice, with vertex
normals) as binary little-endian PLY and as OBJ with the same float32 values, and a square
pyramid as ASCII PLY with quad and triangle faces. Only the standard library is used."""
import math
import struct
from pathlib import Path

OUT = Path(__file__).resolve().parent.parent / "scenes" / "mitsuba" / "meshes"


def f32(x):
    return struct.unpack("<f", struct.pack("<f", x))[0]


def icosphere(levels):
    t = (1 + 5 ** 0.5) / 2
    verts = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
             (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    verts = [tuple(c / math.sqrt(sum(v * v for v in p)) for c in p) for p in verts]
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2),
             (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11),
             (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    for _ in range(levels):
        cache, out = {}, []

        def mid(a, b):
            key = (min(a, b), max(a, b))
            if key not in cache:
                p = [(x + y) / 2 for x, y in zip(verts[a], verts[b])]
                n = math.sqrt(sum(c * c for c in p))
                verts.append(tuple(c / n for c in p))
                cache[key] = len(verts) - 1
            return cache[key]

        for a, b, c in faces:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            out += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = out
    verts = [tuple(f32(c) for c in p) for p in verts]
    return verts, faces


def main():
    OUT.mkdir(parents=True, exist_ok=True)
    verts, faces = icosphere(2)
    header = (f"ply\nformat binary_little_endian 1.0\ncomment icosphere, 2 subdivisions\n"
              f"element vertex {len(verts)}\nproperty float x\nproperty float y\nproperty float z\n"
              f"property float nx\nproperty float ny\nproperty float nz\n"
              f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n")
    with open(OUT / "icosphere.ply", "wb") as f:
        f.write(header.encode())
        for p in verts:
            f.write(struct.pack("<6f", *p, *p))
        for face in faces:
            f.write(struct.pack("<B3i", 3, *face))
    with open(OUT / "icosphere.obj", "w") as f:
        f.write("# the same mesh as icosphere.ply\n")
        for p in verts:
            f.write("v %r %r %r\n" % p)
        for p in verts:
            f.write("vn %r %r %r\n" % p)
        for a, b, c in faces:
            f.write(f"f {a + 1}//{a + 1} {b + 1}//{b + 1} {c + 1}//{c + 1}\n")
    pyramid_v = [(-1, 0, -1), (1, 0, -1), (1, 0, 1), (-1, 0, 1), (0, 1.5, 0)]
    pyramid_f = [(0, 1, 2, 3), (0, 4, 1), (1, 4, 2), (2, 4, 3), (3, 4, 0)]
    with open(OUT / "pyramid_ascii.ply", "w") as f:
        f.write(f"ply\nformat ascii 1.0\nelement vertex {len(pyramid_v)}\nproperty float x\nproperty float y\n"
                f"property float z\nelement face {len(pyramid_f)}\nproperty list uchar int vertex_indices\nend_header\n")
        for p in pyramid_v:
            f.write("%g %g %g\n" % p)
        for face in pyramid_f:
            f.write(f"{len(face)} " + " ".join(map(str, face)) + "\n")
    with open(OUT / "pyramid.obj", "w") as f:
        f.write("# the same mesh as pyramid_ascii.ply\n")
        for p in pyramid_v:
            f.write("v %g %g %g\n" % p)
        for face in pyramid_f:
            f.write("f " + " ".join(str(i + 1) for i in face) + "\n")


main()
