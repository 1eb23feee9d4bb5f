#!/usr/bin/env python3
"""Writes src/material/conductor_spectra.rs: the measured complex indices of refraction (eta and
k over wavelength) of the conductors that Mitsuba 3 knows by name, which spectral mode evaluates
at each path's wavelengths (RGB mode keeps the colours of src/material/conductors.rs).

The data are measured optical constants from the luxpop.com database, as the files' headers
say (the `_palik` ones from Palik's Handbook of Optical Constants of Solids), as Mitsuba ships
them in its `data/ior/<name>.eta.spd` and `.k.spd` files. They are read from those files and
checked against what Mitsuba's own `conductor` plugin (`scalar_spectral`) holds, for every
material the plugin loads (it refuses the few whose k is zero at every wavelength), so the table
has exactly the wavelengths and values Mitsuba interpolates, in single precision.
Materials whose eta and k files hold the same samples share one entry.

    pip install mitsuba==3.9.1
    python3 scripts/make_conductor_spectra.py
"""
from pathlib import Path

import mitsuba as mi
import numpy as np

mi.set_variant("scalar_spectral")
ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "src" / "material" / "conductor_spectra.rs"
DATA = Path(mi.__file__).parent / "data" / "ior"

names = sorted({p.name.split(".")[0] for p in DATA.glob("*.eta.spd")})
entries = []  # (wavelengths, eta, k)
index = {}  # name -> entry


def read_spd(path):
    """The (wavelength, value) columns of an .spd file, rounded to single precision."""
    rows = [line.split() for line in path.read_text().splitlines() if line.strip() and not line.startswith("#")]
    return [float(np.float32(r[0])) for r in rows], [float(np.float32(r[1])) for r in rows]


for name in names:
    lam, eta = read_spd(DATA / f"{name}.eta.spd")
    lam_k, k = read_spd(DATA / f"{name}.k.spd")
    assert lam_k == lam, f"{name}: eta and k on different wavelengths"
    # Where Mitsuba's plugin loads the material (it refuses a k that is zero everywhere), it
    # holds these same numbers.
    try:
        params = mi.traverse(mi.load_dict({"type": "conductor", "material": name}))
    except RuntimeError:
        params = None
    if params is not None:
        for key, want in (("eta.wavelengths", lam), ("eta.values", eta), ("k.values", k)):
            assert [float(x) for x in params[key]] == want, f"{name}: {key} differs from Mitsuba's"
    assert all(b > a for a, b in zip(lam, lam[1:])), f"{name}: wavelengths not increasing"
    entry = (tuple(lam), tuple(eta), tuple(k))
    if entry not in entries:
        entries.append(entry)
    index[name] = entries.index(entry)


def floats(vals):
    # The shortest decimals that give back each single-precision value.
    return ", ".join(str(np.float32(v)) for v in vals)


lines = [
    f"// Written by scripts/make_conductor_spectra.py from the measured optical constants (luxpop.com;",
    f"// the _palik ones from Palik's handbook) that Mitsuba {mi.__version__} ships in data/ior; do not edit.",
    "// Measured values, not constants: 3.14 is a k, not pi.",
    "#![allow(clippy::approx_constant)]",
    "",
    "/// Measured eta and k of a conductor at increasing wavelengths (nm).",
    "pub(super) struct MeasuredIor {",
    "    pub lambda: &'static [f32],",
    "    pub eta: &'static [f32],",
    "    pub k: &'static [f32],",
    "}",
    "",
    "/// The measured spectra, shared by the names of `NAMES`.",
    "pub(super) const MEASURED: &[MeasuredIor] = &[",
]
for lam, eta, k in entries:
    lines.append("    MeasuredIor {")
    lines.append(f"        lambda: &[{floats(lam)}],")
    lines.append(f"        eta: &[{floats(eta)}],")
    lines.append(f"        k: &[{floats(k)}],")
    lines.append("    },")
lines.append("];")
lines.append("")
lines.append("/// Each name Mitsuba knows and the index of its spectra in `MEASURED`.")
lines.append("pub(super) const NAMES: &[(&str, u8)] = &[")
for name in names:
    lines.append(f'    ("{name}", {index[name]}),')
lines.append("];")
OUT.write_text("\n".join(lines) + "\n")
print(f"{len(names)} names, {len(entries)} distinct spectra -> {OUT}")
