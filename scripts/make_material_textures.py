#!/usr/bin/env python3
"""Writes the textures of tests/data/materials/textures: the small bitmaps that the material and
texture reference scenes (tests/data/materials/*.xml) read.

    python3 scripts/make_material_textures.py

Only numpy and the OpenEXR module are used: PNG, JPEG, BMP, TGA, PFM and Radiance HDR are written
by the small writers below, so every byte of each file is known and no codec's defaults (chroma
subsampling, gamma chunks, RLE) are involved.

Files (all at most 64 x 64):
  palette5x3.{png,bmp,tga,exr,hdr,pfm}  5 x 3 texels of distinct colours (the textured quads)
  palette5x3_16.png                    the same colours as a 16-bit PNG (value * 257)
  palette5x3.jpg                       the same colours, each texel an 8 x 8 block (40 x 24)
  tiles.png       16 x 8 RGB          diffuse_bitmap, plastic_nonlinear
  roughness.png   16 x 16 grey, raw   roughconductor_alpha_tex (alpha = value / 255)
  height.png      32 x 32 grey, raw   bumpmap
  normals.png     32 x 32 RGB, raw    normalmap (tangent space, (n + 1) / 2)
  holes.png       32 x 16 grey        mask (255 opaque, 0 holes)
  weight.png      32 x 16 grey        blendbsdf (sRGB-decoded by Mitsuba, raw is not set)
"""
import struct
import zlib
from pathlib import Path

import numpy as np
import OpenEXR

OUT = Path(__file__).resolve().parent.parent / "tests" / "data" / "materials" / "textures"

# Row by row, top row first (the file's first row is Mitsuba's v = 0). Every colour differs
# from its neighbours and from its mirror images, so a flip or transpose shows.
PALETTE_TARGETS = [
    [(220, 40, 40), (240, 140, 30), (235, 220, 60), (120, 200, 50), (30, 140, 60)],
    [(40, 180, 170), (70, 200, 240), (40, 70, 200), (140, 60, 200), (220, 70, 170)],
    [(110, 70, 30), (128, 128, 128), (240, 240, 230), (250, 170, 180), (20, 30, 80)],
]


# ---------------------------------------------------------------------------------------------
# Colours that survive JPEG exactly
# ---------------------------------------------------------------------------------------------

def ycc_to_rgb(y, cb, cr):
    """JFIF's YCbCr -> RGB, unrounded."""
    return (y + 1.402 * (cr - 128),
            y - 0.344136 * (cb - 128) - 0.714136 * (cr - 128),
            y + 1.772 * (cb - 128))


def jpeg_exact(rgb, margin=0.2):
    """The 8-bit colour near `rgb` and its integer YCbCr whose decoded RGB lies within `margin`
    of integers: every JPEG decoder (fixed-point or float) then rounds it to the same bytes."""
    r, g, b = rgb
    y0 = round(0.299 * r + 0.587 * g + 0.114 * b)
    cb0 = round(128 - 0.168736 * r - 0.331264 * g + 0.5 * b)
    cr0 = round(128 + 0.5 * r - 0.418688 * g - 0.081312 * b)
    best = None
    for dy in range(-3, 4):
        for dcb in range(-3, 4):
            for dcr in range(-3, 4):
                ycc = (y0 + dy, cb0 + dcb, cr0 + dcr)
                if not all(0 <= c <= 255 for c in ycc):
                    continue
                dec = ycc_to_rgb(*ycc)
                near = [round(c) for c in dec]
                if any(abs(c - n) > margin for c, n in zip(dec, near)) or not all(1 <= n <= 254 for n in near):
                    continue
                err = sum((n - t) ** 2 for n, t in zip(near, rgb))
                if best is None or err < best[0]:
                    best = (err, tuple(near), ycc)
    assert best is not None, rgb
    return best[1], best[2]


def palette():
    """The palette as uint8 sRGB (3, 5, 3) and its YCbCr (3, 5, 3)."""
    rgb = np.zeros((3, 5, 3), np.uint8)
    ycc = np.zeros((3, 5, 3), np.int32)
    for j, row in enumerate(PALETTE_TARGETS):
        for i, target in enumerate(row):
            rgb[j, i], ycc[j, i] = jpeg_exact(target)
    assert len({tuple(c) for c in rgb.reshape(-1, 3)}) == 15
    return rgb, ycc


def srgb_to_linear(c):
    c = np.asarray(c, np.float64)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


# ---------------------------------------------------------------------------------------------
# Writers. `img` is (height, width, channels) with row 0 the top of the image.
# ---------------------------------------------------------------------------------------------

def write_png(path, img):
    """8- or 16-bit greyscale or RGB PNG without gamma chunks (Mitsuba assumes sRGB)."""
    h, w, c = img.shape
    depth = 16 if img.dtype == np.uint16 else 8
    color_type = {1: 0, 3: 2}[c]
    raw = img.astype(">u2" if depth == 16 else np.uint8).tobytes()
    stride = w * c * depth // 8
    rows = b"".join(b"\x00" + raw[y * stride:(y + 1) * stride] for y in range(h))

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    ihdr = struct.pack(">IIBBBBB", w, h, depth, color_type, 0, 0, 0)
    Path(path).write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(rows, 9))
                           + chunk(b"IEND", b""))


def write_bmp(path, img):
    """24-bit BI_RGB BMP: rows bottom-up, BGR, each row padded to 4 bytes."""
    h, w, _ = img.shape
    pad = (-3 * w) % 4
    rows = b"".join(img[y, :, ::-1].tobytes() + b"\x00" * pad for y in range(h - 1, -1, -1))
    header = struct.pack("<2sIHHI", b"BM", 54 + len(rows), 0, 0, 54)
    info = struct.pack("<IiiHHIIiiII", 40, w, h, 1, 24, 0, len(rows), 2835, 2835, 0, 0)
    Path(path).write_bytes(header + info + rows)


def write_tga(path, img):
    """Uncompressed 24-bit true-colour TGA with the usual bottom-left origin (descriptor 0) and
    the TGA 2.0 footer: Mitsuba recognises a TGA file only by that footer."""
    h, w, _ = img.shape
    header = struct.pack("<BBBHHBHHHHBB", 0, 0, 2, 0, 0, 0, 0, 0, w, h, 24, 0)
    rows = b"".join(img[y, :, ::-1].tobytes() for y in range(h - 1, -1, -1))
    footer = struct.pack("<II", 0, 0) + b"TRUEVISION-XFILE.\x00"
    Path(path).write_bytes(header + rows + footer)


def write_pfm(path, img):
    """Colour PFM, little endian (negative scale), rows bottom-up as the format requires."""
    h, w, _ = img.shape
    data = np.ascontiguousarray(img[::-1], dtype="<f4").tobytes()
    Path(path).write_bytes(f"PF\n{w} {h}\n-1.0\n".encode() + data)


def rgbe(img):
    """Ward's float -> RGBE: mantissas floor(c * 256 / 2^e) with 2^e just above the largest."""
    out = np.zeros(img.shape[:2] + (4,), np.uint8)
    v = img.max(axis=2)
    m, e = np.frexp(v)
    ok = v > 1e-32
    scale = np.where(ok, m * 256.0 / np.where(ok, v, 1), 0)
    out[..., :3] = np.floor(img * scale[..., None]).astype(np.uint8)
    out[..., 3] = np.where(ok, e + 128, 0)
    return out


def write_hdr(path, img):
    """Radiance RGBE without run-length encoding (5 pixels per row is below RLE's minimum of 8)."""
    h, w, _ = img.shape
    head = f"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y {h} +X {w}\n".encode()
    Path(path).write_bytes(head + rgbe(img).tobytes())


def write_exr(path, img):
    """Float32 RGB OpenEXR (half would be rounded to fp16; float keeps the exact values)."""
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    OpenEXR.File(header, {"RGB": np.ascontiguousarray(img, np.float32)}).write(str(path))


def write_jpeg_blocks(path, ycc_texels):
    """Baseline JPEG, 4:4:4, of texels that are each one flat 8 x 8 block.

    A flat block has only a DC coefficient, 8 * (value - 128), which is an integer, so with a
    quantisation table of ones nothing is lost and every decoder's inverse DCT returns the
    texel's YCbCr exactly; with no chroma subsampling no upsampling filter is involved. The
    Huffman tables are the standard DC luminance table and an AC table holding only EOB."""
    th, tw, _ = ycc_texels.shape
    h, w = 8 * th, 8 * tw

    def segment(marker, data):
        return struct.pack(">BBH", 0xFF, marker, len(data) + 2) + data

    dc_bits = [0, 1, 5, 1, 1, 1, 1, 1, 1, 0, 0, 0, 0, 0, 0, 0]
    dc_vals = list(range(12))
    # Two codes ("0" = EOB, "10" = ZRL, never used): a code of all ones is not allowed.
    ac_bits = [1, 1] + [0] * 14
    ac_vals = [0x00, 0xF0]

    def codes(bits, vals):
        table, code, k = {}, 0, 0
        for length, count in enumerate(bits, start=1):
            for _ in range(count):
                table[vals[k]] = (code, length)
                code, k = code + 1, k + 1
            code <<= 1
        return table

    dc_codes, ac_codes = codes(dc_bits, dc_vals), codes(ac_bits, ac_vals)
    bits = []

    def put(value, length):
        bits.extend((value >> (length - 1 - i)) & 1 for i in range(length))

    pred = [0, 0, 0]
    for ty in range(th):
        for tx in range(tw):
            for comp in range(3):
                dc = 8 * (int(ycc_texels[ty, tx, comp]) - 128)
                diff, pred[comp] = dc - pred[comp], dc
                size = abs(diff).bit_length()
                put(*dc_codes[size])
                if size:
                    put(diff if diff > 0 else diff + (1 << size) - 1, size)
                put(*ac_codes[0x00])
    bits.extend([1] * (-len(bits) % 8))
    data = bytearray()
    for i in range(0, len(bits), 8):
        byte = int("".join(map(str, bits[i:i + 8])), 2)
        data.append(byte)
        if byte == 0xFF:
            data.append(0x00)  # byte stuffing

    out = b"\xFF\xD8"
    out += segment(0xE0, b"JFIF\x00\x01\x01\x00\x00\x01\x00\x01\x00\x00")
    out += segment(0xDB, b"\x00" + bytes([1] * 64))
    out += segment(0xC0, struct.pack(">BHHB", 8, h, w, 3) + b"\x01\x11\x00\x02\x11\x00\x03\x11\x00")
    out += segment(0xC4, b"\x00" + bytes(dc_bits) + bytes(dc_vals))
    out += segment(0xC4, b"\x10" + bytes(ac_bits) + bytes(ac_vals))
    out += segment(0xDA, b"\x03\x01\x00\x02\x00\x03\x00\x00\x3F\x00")
    out += bytes(data) + b"\xFF\xD9"
    Path(path).write_bytes(out)


# ---------------------------------------------------------------------------------------------
# Patterns
# ---------------------------------------------------------------------------------------------

def hsv_to_rgb(h, s, v):
    i = np.floor(h * 6).astype(int) % 6
    f = h * 6 - np.floor(h * 6)
    p, q, t = v * (1 - s), v * (1 - f * s), v * (1 - (1 - f) * s)
    choices = [(v, t, p), (q, v, p), (p, v, t), (p, q, v), (t, p, v), (v, p, q)]
    return np.stack([np.choose(i, [c[k] for c in choices]) for k in range(3)], axis=-1)


def to_u8(x):
    return np.clip(np.round(np.asarray(x) * 255), 0, 255).astype(np.uint8)


def tiles():
    """Hue along u, brightness along v, and a dark line every 4 texels: wrapping and seams show."""
    v, u = np.mgrid[0:8, 0:16]
    rgb = hsv_to_rgb(u / 16.0, 0.75, 0.35 + 0.6 * (1 - v / 7.0))
    rgb[(u % 4 == 0) | (v % 4 == 0)] *= 0.25
    return to_u8(rgb)


def roughness():
    """Diagonal bands of alpha 0.03, 0.1, 0.25 and 0.5 (stored raw: alpha = byte / 255)."""
    v, u = np.mgrid[0:16, 0:16]
    levels = np.array([0.03, 0.1, 0.25, 0.5])
    return to_u8(levels[((u + v) // 4) % 4])[..., None]


def height():
    """Round bumps on an 8-texel grid, offset every other row of cells (raw heights 0..1)."""
    v, u = np.mgrid[0:32, 0:32] + 0.5
    u = u + 4 * ((v // 8) % 2)
    du, dv = (u % 8) - 4, (v % 8) - 4
    r = np.sqrt(du * du + dv * dv) / 3.5
    return to_u8(np.where(r < 1, np.cos(np.minimum(r, 1) * np.pi / 2) ** 2, 0))[..., None]


def normals():
    """Tangent-space normals of h = 0.06 sin(2 pi 2x) sin(2 pi 3y) over the unit square: +x (red)
    along increasing u, +y (green) along increasing v (image rows downwards), +z (blue) out."""
    v, u = (np.mgrid[0:32, 0:32] + 0.5) / 32
    a = 0.06
    hx = a * 2 * np.pi * 2 * np.cos(2 * np.pi * 2 * u) * np.sin(2 * np.pi * 3 * v)
    hy = a * 2 * np.pi * 3 * np.sin(2 * np.pi * 2 * u) * np.cos(2 * np.pi * 3 * v)
    n = np.stack([-hx, -hy, np.ones_like(u)], axis=-1)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    return to_u8((n + 1) / 2)


def holes():
    """Opaque (255) with round holes (0) of radius 2.5 texels on an 8-texel grid."""
    v, u = np.mgrid[0:16, 0:32] + 0.5
    du, dv = (u % 8) - 4, (v % 8) - 4
    return np.where(du * du + dv * dv < 2.5 ** 2, 0, 255).astype(np.uint8)[..., None]


def weight():
    """A smooth wave along u in the top half, hard stripes in the bottom half."""
    v, u = np.mgrid[0:16, 0:32] + 0.5
    wave = 0.5 + 0.5 * np.sin(2 * np.pi * u / 16)
    stripes = ((u // 4) % 2).astype(float) * 0.9 + 0.05
    return to_u8(np.where(v < 8, wave, stripes))[..., None]


def main():
    OUT.mkdir(parents=True, exist_ok=True)
    rgb, ycc = palette()
    write_png(OUT / "palette5x3.png", rgb)
    write_png(OUT / "palette5x3_16.png", rgb.astype(np.uint16) * 257)
    write_bmp(OUT / "palette5x3.bmp", rgb)
    write_tga(OUT / "palette5x3.tga", rgb)
    # Float formats hold the linear values that an sRGB 8-bit file decodes to.
    linear = srgb_to_linear(rgb / 255.0).astype(np.float32)
    write_exr(OUT / "palette5x3.exr", linear)
    write_hdr(OUT / "palette5x3.hdr", linear)
    write_pfm(OUT / "palette5x3.pfm", linear)
    write_jpeg_blocks(OUT / "palette5x3.jpg", ycc)

    write_png(OUT / "tiles.png", tiles())
    write_png(OUT / "roughness.png", roughness())
    write_png(OUT / "height.png", height())
    write_png(OUT / "normals.png", normals())
    write_png(OUT / "holes.png", holes())
    write_png(OUT / "weight.png", weight())
    for row in rgb:
        print(" ".join("#%02x%02x%02x" % tuple(c) for c in row))
    print(f"wrote {len(list(OUT.iterdir()))} files to {OUT}")


if __name__ == "__main__":
    main()
