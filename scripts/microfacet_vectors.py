#!/usr/bin/env python3
"""Writes the Mitsuba test vectors for src/material/microfacet.rs.

    python3 scripts/microfacet_vectors.py > src/material/microfacet/tests/mitsuba_vectors.rs
    python3 scripts/microfacet_vectors.py --report > /dev/null   # only the precision report

Generated with Mitsuba 3.9.1 (pip package `mitsuba`, variant scalar_rgb) and numpy; the script
refuses to run with another Mitsuba version unless given --any-version, because the vectors
pin down that version's arithmetic.

For each case it builds `mi.MicrofacetDistribution(type, alpha_u, alpha_v, sample_visible)` and
records, all as f32 values printed so that they read back exactly:
  - the inputs: distribution, alpha_u, alpha_v, wi (unit, rounded to f32), u;
  - m_visible, pdf_visible: `sample(wi, u)` with sample_visible = True (m and its density);
  - d, g1_wi, g1_wo, g at m = m_visible, with wo = reflect(wi, m) (its z may be negative, which
    exercises the back-facing rule of smith_g1): `eval(m)`, `smith_g1(wi, m)`, `smith_g1(wo, m)`,
    `G(wi, wo, m)`;
  - m_all, pdf_all: `sample(wi, u)` and `pdf(wi, m_all)` with sample_visible = False.
The cases cover both distributions, isotropic and anisotropic roughness from 0.01 to 1, normal,
oblique and grazing (89 degrees) incidence, and samples u near 0 and 1.

With --report it also prints to stderr how far Mitsuba's f32 Beckmann inversion lands from a
float64 run of the same algorithm (mpmath erf/erfinv) at grazing incidence and small u.x, the
numbers quoted in src/material/microfacet.rs.
"""
import math
import sys

import mitsuba as mi
import numpy as np

mi.set_variant("scalar_rgb")
if mi.__version__ != "3.9.1" and "--any-version" not in sys.argv:
    sys.exit(f"these vectors pin Mitsuba 3.9.1; found {mi.__version__} (pass --any-version to override)")

F32 = np.float32


def f32(x):
    return float(F32(x))


def unit(theta_deg, phi_deg):
    t, p = math.radians(theta_deg), math.radians(phi_deg)
    v = np.array([math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t)])
    return [f32(c) for c in v / np.linalg.norm(v)]


# (alpha_u, alpha_v, theta_i in degrees, phi_i in degrees, u): the same list for both
# distributions, plus random cases.
FIXED = [
    (0.1, 0.1, 0.0, 0.0, (0.5, 0.5)),
    (0.1, 0.1, 0.0, 0.0, (0.13, 0.77)),
    (0.3, 0.3, 30.0, 20.0, (0.25, 0.6)),
    (0.5, 0.5, 60.0, 135.0, (0.7, 0.1)),
    (1.0, 1.0, 45.0, -60.0, (0.9, 0.35)),
    (0.2, 0.2, 80.0, 10.0, (0.4, 0.8)),
    (0.2, 0.2, 89.0, 200.0, (0.55, 0.45)),
    (0.6, 0.6, 89.0, 90.0, (0.05, 0.95)),
    (0.01, 0.01, 40.0, 30.0, (0.6, 0.3)),
    (0.05, 0.3, 50.0, 70.0, (0.3, 0.9)),
    (0.8, 0.2, 70.0, 30.0, (0.85, 0.15)),
    (0.3, 0.05, 85.0, -100.0, (0.2, 0.5)),
    (0.4, 0.1, 0.0, 0.0, (0.66, 0.21)),
    (0.25, 0.25, 75.0, 45.0, (1e-4, 0.5)),
    (0.25, 0.25, 75.0, 45.0, (0.9999, 0.5)),
    (0.5, 0.2, 20.0, 160.0, (0.5, 1e-4)),
    (0.5, 0.2, 20.0, 160.0, (0.5, 0.9999)),
]


def cases(rng):
    out = list(FIXED)
    for _ in range(7):
        isotropic = rng.random() < 0.5
        au = float(rng.uniform(0.02, 1.0))
        av = au if isotropic else float(rng.uniform(0.02, 1.0))
        out.append((au, av, float(rng.uniform(0, 88)), float(rng.uniform(-180, 180)), tuple(rng.random(2))))
    return out


def rust_f32(x):
    """The shortest decimal that reads back as the same f32, as a Rust literal."""
    x = F32(x)
    if x == 0:
        return "0.0"
    if abs(x) >= 1e-4:
        text = np.format_float_positional(x, unique=True, trim="0")
    else:
        text = np.format_float_scientific(x, unique=True, trim="0")
    if text.endswith("."):
        text += "0"
    assert F32(text) == x, (text, x)
    return text


def vec(v):
    return "[" + ", ".join(rust_f32(c) for c in v) + "]"


def record(kind, name, au, av, wi, u):
    visible = mi.MicrofacetDistribution(kind, au, av, True)
    all_normals = mi.MicrofacetDistribution(kind, au, av, False)
    wi_v = mi.Vector3f(*wi)
    m, pdf_visible = visible.sample(wi_v, mi.Point2f(*u))
    m = [f32(c) for c in m]
    m_v = mi.Vector3f(*m)
    # reflect(wi, m) = 2 (wi.m) m - wi, in f32 as Mitsuba would
    wi32, m32 = np.array(wi, dtype=F32), np.array(m, dtype=F32)
    wo = (F32(2) * np.dot(wi32, m32) * m32 - wi32).astype(F32)
    wo_v = mi.Vector3f(*[float(c) for c in wo])
    m_all, _ = all_normals.sample(wi_v, mi.Point2f(*u))
    m_all = [f32(c) for c in m_all]
    pdf_all = all_normals.pdf(wi_v, mi.Vector3f(*m_all))
    fields = [
        ("distribution", f"Distribution::{name}"),
        ("alpha_u", rust_f32(au)),
        ("alpha_v", rust_f32(av)),
        ("wi", vec(wi)),
        ("u", vec(u)),
        ("m_visible", vec(m)),
        ("pdf_visible", rust_f32(pdf_visible)),
        ("wo", vec(wo)),
        ("d", rust_f32(visible.eval(m_v))),
        ("g1_wi", rust_f32(visible.smith_g1(wi_v, m_v))),
        ("g1_wo", rust_f32(visible.smith_g1(wo_v, m_v))),
        ("g", rust_f32(visible.G(wi_v, wo_v, m_v))),
        ("m_all", vec(m_all)),
        ("pdf_all", rust_f32(pdf_all)),
    ]
    return "    Vector { " + ", ".join(f"{k}: {v}" for k, v in fields) + " },"


def beckmann_f64(cos_theta, u):
    """Mitsuba's Beckmann slope inversion (sample_visible_11) in float64, for the stderr report."""
    import mpmath as mp

    u = [min(max(c, 1e-6), 1 - 1e-6) for c in u]
    sin_theta = math.sqrt(max(0.0, 1 - cos_theta * cos_theta))
    tan_theta, cot_theta = sin_theta / cos_theta, cos_theta / sin_theta
    max_x = float(mp.erf(cot_theta))
    x = max_x - (max_x + 1) * float(mp.erf(math.sqrt(-math.log(u[0]))))
    target = u[0] * (1 + max_x + tan_theta / math.sqrt(math.pi) * math.exp(-cot_theta * cot_theta))
    for _ in range(3):
        slope = float(mp.erfinv(x))
        value = 1 + x + tan_theta / math.sqrt(math.pi) * math.exp(-slope * slope) - target
        x -= value / (1 - slope * tan_theta)
    return float(mp.erfinv(x)), float(mp.erfinv(2 * u[1] - 1))


def report_beckmann_precision():
    distr = mi.MicrofacetDistribution(mi.MicrofacetType.Beckmann, 1.0, 1.0, True)
    worst = {}
    for theta in (60.0, 80.0, 85.0, 89.0):
        for ux in (1e-2, 1e-3, 1e-4, 1e-5):
            slope = beckmann_f64(math.cos(math.radians(theta)), (ux, 0.5))
            m_ref = np.array([-slope[0], -slope[1], 1.0])
            m_ref /= np.linalg.norm(m_ref)
            m = np.array(distr.sample(mi.Vector3f(*unit(theta, 0.0)), mi.Point2f(ux, 0.5))[0])
            worst[(theta, ux)] = float(np.linalg.norm(m - m_ref))
    print("Mitsuba f32 Beckmann sample vs float64 (alpha 1, u.y 0.5): |m - m_f64|", file=sys.stderr)
    for (theta, ux), e in worst.items():
        print(f"  theta {theta:4.0f} deg, u.x {ux:.0e}: {e:.1e}", file=sys.stderr)


def main():
    rng = np.random.default_rng(20240917)
    all_cases = cases(rng)
    print(f"// Generated by scripts/microfacet_vectors.py with Mitsuba {mi.__version__} (scalar_rgb); do not edit.")
    print("use super::Vector;")
    print("use crate::material::microfacet::Distribution;")
    print()
    print("#[rustfmt::skip]")
    print(f"pub const VECTORS: [Vector; {2 * len(all_cases)}] = [")
    for kind, name in ((mi.MicrofacetType.Beckmann, "Beckmann"), (mi.MicrofacetType.GGX, "Ggx")):
        for au, av, theta, phi, u in all_cases:
            print(record(kind, name, f32(au), f32(av), unit(theta, phi), [f32(c) for c in u]))
    print("];")
    if "--report" in sys.argv:
        report_beckmann_precision()


if __name__ == "__main__":
    main()
