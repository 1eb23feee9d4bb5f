#!/usr/bin/env python3
"""Writes a binary little-endian PLY mesh (float x, y, z vertices; faces as a uchar count and int
indices) as a POV-Ray mesh2 named by the second argument, for the POV-Ray comparison scenes.

    python3 scripts/ply_to_pov.py scenes/meshes/blob.ply Blob > blob.inc
"""
import struct
import sys


def read_ply(path):
    with open(path, "rb") as f:
        data = f.read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii").splitlines()
    counts = {l.split()[1]: int(l.split()[2]) for l in header if l.startswith("element")}
    if "format binary_little_endian 1.0" not in header:
        sys.exit(f"{path}: only binary little-endian PLY is read")
    nv, nf = counts["vertex"], counts["face"]
    vertices = [struct.unpack_from("<3f", data, end + 12 * i) for i in range(nv)]
    at, faces = end + 12 * nv, []
    for _ in range(nf):
        (n,) = struct.unpack_from("<B", data, at)
        idx = struct.unpack_from(f"<{n}i", data, at + 1)
        at += 1 + 4 * n
        faces.extend((idx[0], idx[k], idx[k + 1]) for k in range(1, n - 1))
    return vertices, faces


def main():
    vertices, faces = read_ply(sys.argv[1])
    out = [f"#declare {sys.argv[2]} = mesh2 {{", f"  vertex_vectors {{ {len(vertices)},"]
    out += [f"    <{x!r}, {y!r}, {z!r}>," for x, y, z in vertices]
    out[-1] = out[-1].rstrip(",")
    out += ["  }", f"  face_indices {{ {len(faces)},"]
    out += [f"    <{a}, {b}, {c}>," for a, b, c in faces]
    out[-1] = out[-1].rstrip(",")
    out += ["  }", "}"]
    print("\n".join(out))


if __name__ == "__main__":
    main()
