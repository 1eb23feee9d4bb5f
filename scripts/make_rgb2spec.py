#!/usr/bin/env python3
"""Writes src/spectrum/data/rgb2spec_srgb.bin: the coefficient table that turns a linear sRGB
colour into a smooth reflectance spectrum (Jakob and Hanika 2019, "A Low-Dimensional Function
Space for Efficient Spectral Upsampling"), read by src/spectrum/rgb.rs.

    python3 scripts/make_rgb2spec.py                # the committed table (--res 32)
    python3 scripts/make_rgb2spec.py --res 16 --out /tmp/t.bin --check 20000

Needs numpy only: the CIE 1931 matching functions, D65, the Y normalisation and the XYZ-to-sRGB
matrix are read from src/spectrum/cie_tables.rs, so the table is fitted against exactly the data
the renderer converts with.

The model. A spectrum is s(lambda) = S(c0 t^2 + c1 t + c2) with t = (lambda - 360) / 470, the
wavelength mapped to [0, 1] over 360-830 nm (better conditioned than nanometres), and
S(x) = 1/2 + x / (2 sqrt(1 + x^2)), a sigmoid onto (0, 1). Its colour is that of a reflectance
under D65: XYZ = N * integral(s * D65 * xyz-bar), N the CIE Y normalisation, integrated with the
trapezoid rule at 1 nm over the 5 nm tables interpolated linearly (the rule the Rust tests use).

The table. A colour is indexed by which channel is largest (l), that channel's value z, and the
other two divided by it, x = rgb[(l+1)%3] / z, y = rgb[(l+2)%3] / z, each in [0, 1]. x and y
take `res` evenly spaced values; z takes `res` values bunched towards 0 and 1 by a double
smoothstep, where the coefficients change fastest. Each entry holds (c0, c1, c2).

The fit. For each entry, Gauss-Newton on the residual CIE Lab(s) - Lab(target) (Lab measures
perceptual distance, which keeps dark colours from being fitted loosely), with the 3x3 Jacobian
computed analytically (dS/dx = (1 + x^2)^(-3/2) / 2). As the paper does, the fit starts from the
flat spectrum at z index res/5 and walks up and down in z, each slice starting from the
solution of its neighbour (continuation), so that saturated colours are reached gradually. All
res x res entries of a slice are solved at once with numpy.

Cost and accuracy, measured on the project's 2-core VM while others were building: res 32
(committed, 1.18 MB) takes 91 s wall (58 s CPU, 67 MB of memory); res 64 (9.4 MB, the size
pbrt-v4 and Mitsuba use) 12 minutes. Trilinear lookups round-trip 4000 random sRGB colours to
a mean of 9e-4 and a worst of 1.2e-2 to 2.1e-2 (two draws; res 32) or 2.8e-3 (res 64), the
worst near white;
rgb.rs refines constant colours to 1e-9 from the res-32 start (`--check N` prints the lookup
figures).

File layout (little-endian): b"RGB2SPEC", u32 version 1, u32 res, f32 z nodes [res], then
f32 coefficients [3][res z][res y][res x][3]. Total 16 + 4 res + 36 res^3 bytes.
"""
import argparse
import re
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
TABLES = ROOT / "src" / "spectrum" / "cie_tables.rs"
OUT = ROOT / "src" / "spectrum" / "data" / "rgb2spec_srgb.bin"
LAMBDA_MIN, LAMBDA_MAX = 360.0, 830.0


def read_tables():
    """The arrays and constants of cie_tables.rs."""
    src = TABLES.read_text()

    def array(name):
        body = re.search(rf"pub const {name}: \[f64; \d+\] = \[(.*?)\];", src, re.S).group(1)
        return np.array([float(v) for v in body.replace("\n", "").split(",") if v.strip()])

    norm = float(re.search(r"CIE_Y_NORMALIZATION: f64 = ([0-9.e+-]+);", src).group(1))
    body = re.search(r"XYZ_TO_SRGB: \[\[f64; 3\]; 3\] = \[(.*?)\];\n", src, re.S).group(1)
    m = np.array([float(v) for v in re.findall(r"-?[0-9.]+(?:e[+-]?\d+)?", body)]).reshape(3, 3)
    return array("CIE_X"), array("CIE_Y"), array("CIE_Z"), array("D65"), norm, m


class Fit:
    def __init__(self):
        x, y, z, d65, norm, m = read_tables()
        grid5 = np.linspace(LAMBDA_MIN, LAMBDA_MAX, len(x))
        lam = np.arange(LAMBDA_MIN, LAMBDA_MAX + 0.5, 1.0)
        weight = np.ones_like(lam)
        weight[0] = weight[-1] = 0.5
        cmf = np.stack([np.interp(lam, grid5, t) for t in (x, y, z)])
        # XYZ of a spectrum sampled at `lam`: this matrix times the samples.
        self.w_xyz = cmf * np.interp(lam, grid5, d65) * weight * norm
        self.t = (lam - LAMBDA_MIN) / (LAMBDA_MAX - LAMBDA_MIN)
        self.powers = np.stack([self.t**2, self.t, np.ones_like(self.t)])  # (3, L)
        self.white = self.w_xyz.sum(axis=1)
        self.xyz_to_rgb = m
        self.rgb_to_xyz = np.linalg.inv(m)

    def lab(self, xyz):
        """CIE Lab of XYZ (..., 3) relative to the D65 white, and d Lab / d XYZ (..., 3, 3)."""
        d = 6.0 / 29.0
        v = xyz / self.white
        f = np.where(v > d**3, np.cbrt(np.maximum(v, d**3)), v / (3 * d * d) + 4.0 / 29.0)
        df = np.where(v > d**3, 1.0 / (3 * np.cbrt(np.maximum(v, d**3)) ** 2), 1.0 / (3 * d * d)) / self.white
        lab = np.stack([116 * f[..., 1] - 16, 500 * (f[..., 0] - f[..., 1]), 200 * (f[..., 1] - f[..., 2])], -1)
        jac = np.zeros(xyz.shape + (3,))
        jac[..., 0, 1] = 116 * df[..., 1]
        jac[..., 1, 0] = 500 * df[..., 0]
        jac[..., 1, 1] = -500 * df[..., 1]
        jac[..., 2, 1] = 200 * df[..., 1]
        jac[..., 2, 2] = -200 * df[..., 2]
        return lab, jac

    def spectra(self, c):
        """The spectra of coefficients c (N, 3) at the 1 nm samples, and dS/dx there."""
        x = c @ self.powers  # (N, L)
        root = np.sqrt(1 + x * x)
        return 0.5 + 0.5 * x / root, 0.5 / root**3

    def rgb(self, c):
        s, _ = self.spectra(c)
        return (s @ self.w_xyz.T) @ self.xyz_to_rgb.T

    def solve(self, c, target_rgb, iterations):
        """Gauss-Newton from c towards the Lab of target_rgb; returns c and the Lab residual."""
        target, _ = self.lab(target_rgb @ self.rgb_to_xyz.T)
        for _ in range(iterations):
            s, ds = self.spectra(c)
            lab, dlab = self.lab(s @ self.w_xyz.T)
            r = lab - target
            # d XYZ / d c_k = integral of dS/dx * t^(2-k) against the weighted matching functions.
            dxyz = np.einsum("jl,nl,kl->njk", self.w_xyz, ds, self.powers)
            jac = dlab @ dxyz
            norm = np.linalg.norm(r, axis=1)
            if norm.max() < 1e-7:
                break
            # A whisker of damping keeps the few singular Jacobians (flat spectra at 0 or 1)
            # from stopping the batch; it changes converged steps by nothing measurable.
            jt = np.swapaxes(jac, 1, 2)
            step = np.linalg.solve(jt @ jac + 1e-12 * np.eye(3), (jt @ r[..., None]))[..., 0]
            # Long steps overshoot where the sigmoid saturates: cap them.
            big = np.linalg.norm(step, axis=1)
            step *= np.minimum(1.0, 50.0 / np.maximum(big, 1e-30))[:, None]
            c = c - step
        s, _ = self.spectra(c)
        lab, _ = self.lab(s @ self.w_xyz.T)
        return c, np.linalg.norm(lab - target, axis=1)


def smoothstep(x):
    return x * x * (3 - 2 * x)


def build(fit, res):
    z_nodes = smoothstep(smoothstep(np.linspace(0, 1, res)))
    xy = np.linspace(0, 1, res)
    ys, xs = np.meshgrid(xy, xy, indexing="ij")  # [y][x]
    table = np.zeros((3, res, res, res, 3))
    worst = 0.0
    start = res // 5
    for l in range(3):
        for order in (range(start, res), range(start, -1, -1)):
            c = np.zeros((res * res, 3))
            for k in order:
                z = z_nodes[k]
                rgb = np.zeros((res * res, 3))
                rgb[:, l] = z
                rgb[:, (l + 1) % 3] = xs.ravel() * z
                rgb[:, (l + 2) % 3] = ys.ravel() * z
                c, err = fit.solve(c, rgb, 200 if k == start else 100)
                table[l, k] = c.reshape(res, res, 3)
                # Black (z = 0) has no solution: the walk leaves ever more negative coefficients
                # there, which only colours below z = 3e-5 (res 32) interpolate towards, and the
                # evaluation refines or treats black exactly.
                if z > 0:
                    worst = max(worst, float(err.max()))
    return z_nodes, table, worst


def write(path, z_nodes, table):
    res = len(z_nodes)
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "wb") as f:
        f.write(b"RGB2SPEC")
        f.write(np.array([1, res], dtype="<u4").tobytes())
        f.write(z_nodes.astype("<f4").tobytes())
        f.write(table.astype("<f4").tobytes())


def lookup(z_nodes, table, rgb):
    """Trilinear interpolation as rgb.rs does it (for --check)."""
    res = len(z_nodes)
    l = int(np.argmax(rgb))
    z = rgb[l]
    if z <= 0:
        return None
    x, y = rgb[(l + 1) % 3] / z * (res - 1), rgb[(l + 2) % 3] / z * (res - 1)
    zi = min(max(int(np.searchsorted(z_nodes, z, side="right")) - 1, 0), res - 2)
    xi, yi = min(int(x), res - 2), min(int(y), res - 2)
    dz = (z - z_nodes[zi]) / (z_nodes[zi + 1] - z_nodes[zi])
    dx, dy = x - xi, y - yi
    c = 0
    for a, wz in ((0, 1 - dz), (1, dz)):
        for b, wy in ((0, 1 - dy), (1, dy)):
            for e, wx in ((0, 1 - dx), (1, dx)):
                c = c + wz * wy * wx * table[l, zi + a, yi + b, xi + e]
    return c


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--res", type=int, default=32)
    ap.add_argument("--out", type=Path, default=OUT)
    ap.add_argument("--check", type=int, default=0, help="round-trip this many random colours")
    args = ap.parse_args()
    fit = Fit()
    t0 = time.time()
    z_nodes, table, worst = build(fit, args.res)
    took = time.time() - t0
    write(args.out, z_nodes, table)
    size = args.out.stat().st_size
    print(f"res {args.res}: fitted in {took:.1f} s, worst Lab residual at the nodes {worst:.2e}, "
          f"wrote {args.out} ({size} bytes)")
    if args.check:
        rng = np.random.default_rng(1)
        rgbs = rng.random((args.check, 3))
        errs = []
        for rgb in rgbs:
            c = lookup(z_nodes, table.astype(np.float32).astype(np.float64), rgb)
            errs.append(np.abs(fit.rgb(c[None])[0] - rgb).max())
        errs = np.array(errs)
        print(f"round trip of {args.check} random colours: max {errs.max():.2e}, "
              f"99.9% {np.quantile(errs, 0.999):.2e}, mean {errs.mean():.2e}")


if __name__ == "__main__":
    main()
