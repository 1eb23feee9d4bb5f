#!/usr/bin/env python3
"""Writes src/spectrum/cie_tables.rs: the CIE 1931 2-degree colour-matching functions and the CIE
D65 illuminant at 5 nm steps over 360-830 nm, the XYZ-to-linear-sRGB matrix and the luminance
normalisation, as Mitsuba 3's RGB variants use them to turn spectra into colours.

The values are the CIE's published tables (CIE 015:2004 and ISO/CIE 11664); they are read here
from the Mitsuba 3 Python package, so that caustic's conversion agrees with Mitsuba's to the
digit (Mitsuba interpolates the same 5 nm samples linearly, which this script checks).

    pip install mitsuba==3.9.1
    python3 scripts/make_cie_tables.py
"""
from pathlib import Path

import mitsuba as mi

mi.set_variant("scalar_rgb")
OUT = Path(__file__).resolve().parent.parent / "src" / "spectrum" / "cie_tables.rs"

lo, hi, step = int(mi.MI_CIE_MIN), int(mi.MI_CIE_MAX), 5
waves = list(range(lo, hi + 1, step))
xyz = [list(mi.cie1931_xyz(w)) for w in waves]
d65 = [float(mi.cie_d65(w)) for w in waves]
# Mitsuba interpolates between the 5 nm samples: check at the midpoints.
for a, b in zip(waves, waves[1:]):
    m = list(mi.cie1931_xyz((a + b) / 2))
    want = [(p + q) / 2 for p, q in zip(mi.cie1931_xyz(a), mi.cie1931_xyz(b))]
    assert all(abs(u - v) <= 1e-6 * max(1.0, abs(v)) for u, v in zip(m, want)), (a, m, want)
matrix = [list(mi.xyz_to_srgb(mi.Color3f(*e))) for e in ([1, 0, 0], [0, 1, 0], [0, 0, 1])]


def row(vals):
    return ", ".join(f"{v:.9e}" for v in vals)


text = f"""// Written by scripts/make_cie_tables.py from the CIE's tables as Mitsuba {mi.__version__} ships them; do not edit.

/// First wavelength of the tables, nm.
pub const CIE_MIN: f64 = {lo}.0;
/// Last wavelength of the tables, nm.
pub const CIE_MAX: f64 = {hi}.0;
/// Spacing of the tables, nm.
pub const CIE_STEP: f64 = {step}.0;
/// Mitsuba's MI_CIE_Y_NORMALIZATION: one over the integral of y-bar, so that a spectrum of ones
/// has luminance 1.
pub const CIE_Y_NORMALIZATION: f64 = {mi.MI_CIE_Y_NORMALIZATION!r};

/// CIE 1931 2-degree x-bar, y-bar, z-bar at CIE_MIN, CIE_MIN + 5, ..., CIE_MAX.
pub const CIE_X: [f64; {len(waves)}] = [{row(v[0] for v in xyz)}];
pub const CIE_Y: [f64; {len(waves)}] = [{row(v[1] for v in xyz)}];
pub const CIE_Z: [f64; {len(waves)}] = [{row(v[2] for v in xyz)}];
/// CIE D65, scaled as Mitsuba scales it (a white reflectance under it integrates to Y = 1 with
/// CIE_Y_NORMALIZATION).
pub const D65: [f64; {len(waves)}] = [{row(d65)}];

/// XYZ to linear sRGB (rows).
pub const XYZ_TO_SRGB: [[f64; 3]; 3] = [
    [{matrix[0][0]:.9}, {matrix[1][0]:.9}, {matrix[2][0]:.9}],
    [{matrix[0][1]:.9}, {matrix[1][1]:.9}, {matrix[2][1]:.9}],
    [{matrix[0][2]:.9}, {matrix[1][2]:.9}, {matrix[2][2]:.9}],
];
"""
OUT.write_text(text)
print(f"wrote {OUT}")
