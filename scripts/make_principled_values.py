#!/usr/bin/env python3
"""Writes tests/data/principled/values.csv: Mitsuba 3's `principled` BSDF evaluated (f times the
cosine, radiance transport, scalar_rgb) for pairs of directions in the local frame, under
several parameter sets, so that caustic's lobes can be checked value for value
(src/material/bsdf/principled_tests.rs).

    pip install mitsuba==3.9.1 numpy
    python3 scripts/make_principled_values.py
"""
import json
from pathlib import Path

import mitsuba as mi
import numpy as np

mi.set_variant("scalar_rgb")
OUT = Path(__file__).resolve().parent.parent / "tests" / "data" / "principled" / "values.csv"

CASES = {
    "defaults": {},
    "metal_sheen_coat": {"base_color": [0.8, 0.3, 0.2], "roughness": 0.3, "metallic": 0.6, "spec_tint": 0.5,
                         "sheen": 0.7, "sheen_tint": 0.4, "clearcoat": 0.8, "clearcoat_gloss": 0.6},
    "anisotropic": {"base_color": [0.2, 0.5, 0.9], "roughness": 0.4, "anisotropic": 0.7, "metallic": 0.2},
    "glass": {"base_color": [0.9, 0.8, 0.7], "roughness": 0.2, "spec_trans": 0.8, "eta": 1.33},
    "flat_sheen": {"base_color": [0.3, 0.6, 0.3], "roughness": 0.7, "flatness": 0.6, "sheen": 0.3, "specular": 0.8},
    "polished_metal": {"base_color": [0.95, 0.64, 0.54], "roughness": 0.05, "metallic": 1.0},
    "everything": {"base_color": [0.6, 0.4, 0.7], "roughness": 0.35, "anisotropic": 0.3, "metallic": 0.3,
                   "spec_trans": 0.4, "spec_tint": 0.3, "sheen": 0.5, "sheen_tint": 0.6, "clearcoat": 0.5,
                   "clearcoat_gloss": 0.2, "specular": 0.6},
}


THIN_CASES = {
    "thin_defaults": {},
    "thin_leaf": {"base_color": [0.3, 0.7, 0.2], "roughness": 0.4, "spec_trans": 0.3, "diff_trans": 0.8,
                  "sheen": 0.4, "sheen_tint": 0.5, "flatness": 0.3, "eta": 1.4},
    "thin_glassy": {"base_color": [0.9, 0.85, 0.8], "roughness": 0.15, "spec_trans": 0.85, "spec_tint": 0.4,
                    "anisotropic": 0.5, "eta": 1.33},
}


def bsdf_of(params, kind="principled"):
    d = {"type": kind}
    for k, v in params.items():
        d[k] = {"type": "rgb", "value": v} if isinstance(v, list) else v
    return mi.load_dict(d)


def unit(v):
    return v / np.linalg.norm(v)


def main():
    rng = np.random.default_rng(5)
    rows = ["case,params,wi_x,wi_y,wi_z,wo_x,wo_y,wo_z,r,g,b"]
    ctx = mi.BSDFContext()
    all_cases = [(n, p, "principled") for n, p in CASES.items()] + [(n, p, "principledthin") for n, p in THIN_CASES.items()]
    for name, params, kind in all_cases:
        bsdf = bsdf_of(params, kind)
        transmits = params.get("spec_trans", 0) > 0 or kind == "principledthin"
        n = 0
        while n < 60:
            wi = unit(rng.normal(size=3))
            wo = unit(rng.normal(size=3))
            if not transmits:
                wi[2] = abs(wi[2])
            if abs(wi[2]) < 0.05 or abs(wo[2]) < 0.05:
                continue
            # Half the pairs near the mirror direction, where the glossy lobes live.
            if n % 2 == 0:
                wo = unit(np.array([-wi[0], -wi[1], wi[2]]) + 0.25 * rng.normal(size=3))
                if transmits and n % 4 == 0:
                    wo = unit(-wi + 0.25 * rng.normal(size=3))
            si = mi.SurfaceInteraction3f()
            si.wi = mi.Vector3f(*wi)
            si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
            value = np.array(bsdf.eval(ctx, si, mi.Vector3f(*wo)))
            rows.append(",".join([name, json.dumps(params).replace(",", ";")] + [f"{x:.9g}" for x in (*wi, *wo, *value)]))
            n += 1
    OUT.write_text("\n".join(rows) + "\n")
    print(f"wrote {OUT} ({len(rows) - 1} values)")


if __name__ == "__main__":
    main()
