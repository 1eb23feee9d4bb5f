#!/usr/bin/env python3
"""Writes the textures of the materials showcase, scenes/15-materials.toml, into scenes/textures/.

    python3 scripts/make_showcase_textures.py

Everything is procedural (numpy only) and written by the small PNG writer below, so the files are
reproducible byte for byte. Colour images are 8-bit sRGB; the files the scene reads with
`raw = true` (heights, normals, roughness) hold their values directly (value / 255).

Files:
  tiles.png          256 x 256 RGB    floor colour: 4 x 4 stone tiles with grout
  tiles_height.png   256 x 256 grey   floor bump map (raw): tiles 1 with bevelled edges, grout 0
  planet.png         256 x 128 RGB    an invented planet, equirectangular (row 0 = north, v = 0)
  dimples.png        128 x 64 grey    bump map of a golf ball's dimples (raw), tiles in u and v
  hammered.png       128 x 128 RGB    tangent-space normal map of hammered metal (raw), tiles
  bands.png          4 x 64 grey      roughness in bands along v (raw): alpha = value / 255
  dots.png           64 x 64 grey     a round hole or dot in each texel block: opacity / weight
"""
import struct
import zlib
from pathlib import Path

import numpy as np

OUT = Path(__file__).resolve().parent.parent / "scenes" / "textures"


def write_png(path, img):
    """Writes uint8 `img` (h, w) grey or (h, w, 3) RGB as a PNG, every row with the Paeth filter
    (small files for smooth images)."""
    img = np.ascontiguousarray(img, dtype=np.uint8)
    h, w = img.shape[:2]
    channels = 1 if img.ndim == 2 else img.shape[2]
    color_type = {1: 0, 3: 2}[channels]
    px = img.reshape(h, w * channels).astype(np.int32)
    out = bytearray()
    prev = np.zeros(w * channels, np.int32)
    for y in range(h):
        row = px[y]
        a = np.concatenate([np.zeros(channels, np.int32), row[:-channels]])  # left
        b = prev  # up
        c = np.concatenate([np.zeros(channels, np.int32), prev[:-channels]])  # up-left
        p = a + b - c
        pa, pb, pc = np.abs(p - a), np.abs(p - b), np.abs(p - c)
        pred = np.where((pa <= pb) & (pa <= pc), a, np.where(pb <= pc, b, c))
        out.append(4)
        out += ((row - pred) % 256).astype(np.uint8).tobytes()
        prev = row

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    ihdr = struct.pack(">IIBBBBB", w, h, 8, color_type, 0, 0, 0)
    path.write_bytes(
        b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(bytes(out), 9)) + chunk(b"IEND", b"")
    )
    print(f"{path.name}: {w} x {h}, {path.stat().st_size} bytes")


def linear_to_srgb(c):
    c = np.clip(c, 0.0, 1.0)
    return np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1 / 2.4) - 0.055)


def to_u8(x):
    return np.clip(np.round(x * 255.0), 0, 255).astype(np.uint8)


def srgb_u8(linear):
    return to_u8(linear_to_srgb(linear))


def value_noise(h, w, cells_y, cells_x, rng):
    """Smooth noise in [0, 1] that tiles: a random lattice of cells_y x cells_x values,
    interpolated with a smoothstep."""
    lattice = rng.random((cells_y, cells_x))
    y = np.arange(h) * cells_y / h
    x = np.arange(w) * cells_x / w
    y0, x0 = np.floor(y).astype(int), np.floor(x).astype(int)
    fy, fx = y - y0, x - x0
    sy, sx = fy * fy * (3 - 2 * fy), fx * fx * (3 - 2 * fx)
    y1, x1 = (y0 + 1) % cells_y, (x0 + 1) % cells_x
    v00 = lattice[y0][:, x0]
    v01 = lattice[y0][:, x1]
    v10 = lattice[y1][:, x0]
    v11 = lattice[y1][:, x1]
    top = v00 * (1 - sx) + v01 * sx
    bottom = v10 * (1 - sx) + v11 * sx
    return top * (1 - sy[:, None]) + bottom * sy[:, None]


def fractal(h, w, base_y, base_x, octaves, rng):
    total, amp, norm = np.zeros((h, w)), 1.0, 0.0
    for o in range(octaves):
        total += amp * value_noise(h, w, base_y * 2**o, base_x * 2**o, rng)
        norm += amp
        amp *= 0.5
    return total / norm


def tiles(rng):
    """4 x 4 tiles of 64 texels: two stone colours in a chequer, each tile's shade varied, a
    soft mottling, and grout 3 texels wide (centred on the tile borders, so the texture tiles)."""
    n, size = 256, 64
    y, x = np.mgrid[0:n, 0:n]
    ty, tx = y // size, x // size
    # Distance (in texels) from the tile's border; the grout is where it is below 1.5.
    fy, fx = (y % size) + 0.5, (x % size) + 0.5
    edge = np.minimum(np.minimum(fy, size - fy), np.minimum(fx, size - fx))
    warm = np.array([0.52, 0.40, 0.30])
    cool = np.array([0.36, 0.34, 0.32])
    base = np.where(((tx + ty) % 2 == 0)[..., None], warm, cool)
    shade = 0.85 + 0.3 * rng.random((4, 4))
    base = base * shade[ty, tx][..., None]
    mottle = fractal(n, n, 4, 4, 5, rng)
    colour = base * (0.75 + 0.5 * mottle)[..., None]
    grout = np.array([0.09, 0.085, 0.08])
    g = np.clip((edge - 1.5) / 1.0, 0.0, 1.0)[..., None]
    colour = grout * (1 - g) + colour * g
    # Heights: 0 in the grout, rising to 1 over a bevel of 5 texels.
    t = np.clip((edge - 1.5) / 5.0, 0.0, 1.0)
    height = t * t * (3 - 2 * t)
    return srgb_u8(colour), to_u8(height)


def planet(rng):
    """Oceans, land with a few climate zones and ice caps, on a 2:1 equirectangular map whose top
    row is the north pole (v = 0) and which tiles in u."""
    h, w = 128, 256
    elevation = fractal(h, w, 4, 8, 6, rng)
    lat = (np.arange(h) + 0.5) / h  # 0 at the north pole
    polar = np.abs(lat - 0.5) * 2  # 0 at the equator, 1 at the poles
    sea = elevation < 0.52
    deep = np.array([0.01, 0.04, 0.16])
    shallow = np.array([0.03, 0.16, 0.35])
    d = np.clip((elevation - 0.3) / 0.22, 0, 1)[..., None]
    ocean = deep * (1 - d) + shallow * d
    green = np.array([0.09, 0.22, 0.05])
    desert = np.array([0.45, 0.33, 0.16])
    mountain = np.array([0.28, 0.24, 0.20])
    dry = np.clip(1 - np.abs(polar - 0.35) / 0.2, 0, 1)[:, None]  # deserts around 30 degrees
    dry = dry * fractal(h, w, 8, 16, 3, rng)
    land = green * (1 - dry[..., None]) + desert * dry[..., None]
    m = np.clip((elevation - 0.62) / 0.12, 0, 1)[..., None]
    land = land * (1 - m) + mountain * m
    colour = np.where(sea[..., None], ocean, land)
    ice = np.clip((polar[:, None] + 0.15 * fractal(h, w, 4, 8, 3, rng) - 0.85) / 0.05, 0, 1)[..., None]
    colour = colour * (1 - ice) + np.array([0.8, 0.82, 0.85]) * ice
    return srgb_u8(colour)


def dimples():
    """Round dimples in a staggered grid, 16 across and 8 down (cells square on a sphere's
    equator, where u spans twice the length v does)."""
    h, w = 64, 128
    y, x = np.mgrid[0:h, 0:w] + 0.5
    cell = 8.0
    best = np.full((h, w), 1e9)
    for row in range(-1, 9):
        cy = (row + 0.5) * cell
        shift = cell / 2 if row % 2 else 0.0
        for col in range(-1, 17):
            cx = (col + 0.5) * cell + shift
            dx = np.abs(x - cx)
            dx = np.minimum(dx, w - dx)  # tile in u
            best = np.minimum(best, np.hypot(dx, y - cy))
    r = 3.4
    depth = np.where(best < r, np.sqrt(np.clip(1 - (best / r) ** 2, 0, 1)), 0.0)
    return to_u8(1.0 - 0.8 * depth)


def hammered(rng):
    """A tangent-space normal map of overlapping shallow hammer blows: the slopes of a height field
    made of random spherical caps (tiling), stored as (n + 1) / 2."""
    n = 128
    y, x = np.mgrid[0:n, 0:n] + 0.5
    height = np.zeros((n, n))
    for _ in range(90):
        cx, cy, r = rng.random() * n, rng.random() * n, 7 + 6 * rng.random()
        dx = np.abs(x - cx)
        dx = np.minimum(dx, n - dx)
        dy = np.abs(y - cy)
        dy = np.minimum(dy, n - dy)
        d2 = (dx * dx + dy * dy) / (r * r)
        cap = np.where(d2 < 1, -(1 - d2) ** 2 * r * 0.35, 0.0)
        height = np.minimum(height, cap)
    # Slopes by central differences, wrapping.
    gx = (np.roll(height, -1, axis=1) - np.roll(height, 1, axis=1)) / 2
    gy = (np.roll(height, -1, axis=0) - np.roll(height, 1, axis=0)) / 2
    # Rows run down the image, which is +v; the normal is (-dh/du, -dh/dv, 1).
    nrm = np.stack([-gx, -gy, np.ones_like(gx)], axis=-1)
    nrm /= np.linalg.norm(nrm, axis=-1, keepdims=True)
    return to_u8((nrm + 1) / 2)


def bands():
    """Roughness (alpha) in 8 bands down the image: polished 0.03 and matte 0.35, with soft
    edges."""
    h, w = 64, 4
    v = (np.arange(h) + 0.5) / h
    s = 0.5 + 0.5 * np.cos(v * 2 * np.pi * 4)
    s = np.clip((s - 0.5) * 4 + 0.5, 0, 1)
    alpha = 0.03 + 0.32 * s
    return to_u8(np.tile(alpha[:, None], (1, w)))


def dots():
    """A disc of 0 (radius 11 texels, soft 1-texel rim) in a 64 x 64 block of 1."""
    n = 64
    y, x = np.mgrid[0:n, 0:n] + 0.5
    d = np.hypot(x - n / 2, y - n / 2)
    return to_u8(np.clip(d - 20, 0, 1))


def main():
    OUT.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(15)
    colour, height = tiles(rng)
    write_png(OUT / "tiles.png", colour)
    write_png(OUT / "tiles_height.png", height)
    write_png(OUT / "planet.png", planet(rng))
    write_png(OUT / "dimples.png", dimples())
    write_png(OUT / "hammered.png", hammered(rng))
    write_png(OUT / "bands.png", bands())
    write_png(OUT / "dots.png", dots())


if __name__ == "__main__":
    main()
