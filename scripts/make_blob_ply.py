#!/usr/bin/env python3
"""Writes scenes/meshes/blob.ply: a lumpy, bunny-sized blob (a subdivided icosahedron pushed in
and out by a few sine waves), as a binary little-endian PLY with positions and faces only, so
caustic computes its smooth normals. About 5,120 triangles, 8 cm across like the Stanford bunny
scanned in metres, standing on y = 0. Used by the walkthrough in docs/walkthrough.md.

    python3 scripts/make_blob_ply.py
"""

import math
import os
import struct


def icosphere(levels):
    t = (1 + 5 ** 0.5) / 2
    verts = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
             (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    verts = [tuple(c / math.sqrt(sum(x * x for x in v)) for c in v) for v in verts]
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2),
             (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5),
             (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    for _ in range(levels):
        cache = {}

        def mid(a, b):
            key = (min(a, b), max(a, b))
            if key not in cache:
                m = [(verts[a][i] + verts[b][i]) / 2 for i in range(3)]
                n = math.sqrt(sum(x * x for x in m))
                verts.append(tuple(x / n for x in m))
                cache[key] = len(verts) - 1
            return cache[key]

        new = []
        for a, b, c in faces:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            new += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = new
    return verts, faces


def main():
    verts, faces = icosphere(4)
    out = []
    for x, y, z in verts:
        r = 1 + 0.18 * math.sin(3 * x + 1) * math.sin(2 * y) + 0.12 * math.sin(5 * z + 2 * x) + 0.25 * max(y, 0) ** 3
        out.append((x * r * 0.04, (y * r + 1.1) * 0.04, z * r * 0.035))
    ymin = min(v[1] for v in out)
    out = [(x, y - ymin, z) for x, y, z in out]
    path = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "scenes", "meshes", "blob.ply")
    with open(path, "wb") as f:
        f.write(b"ply\nformat binary_little_endian 1.0\ncomment made by scripts/make_blob_ply.py\n")
        f.write(f"element vertex {len(out)}\nproperty float x\nproperty float y\nproperty float z\n".encode())
        f.write(f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n".encode())
        for v in out:
            f.write(struct.pack("<3f", *v))
        for a, b, c in faces:
            f.write(struct.pack("<B3i", 3, a, b, c))
    print(f"wrote {path}: {len(out)} vertices, {len(faces)} triangles")


if __name__ == "__main__":
    main()
