#!/usr/bin/env python3
"""Writes the participating-media test scenes of tests/data/media and renders their Mitsuba 3
references, which tests/media.rs compares caustic's volumetric path tracer with.

    pip install mitsuba==3.9.1 numpy
    python3 scripts/make_media_refs.py              # every case
    python3 scripts/make_media_refs.py cube_area    # only the named cases

The rendering, the noise measurement (two halves with different seeds) and MANIFEST.md are those
of scripts/make_material_refs.py, whose functions are reused with this folder and these sample
counts. Every scene uses Mitsuba's `volpath` integrator.

The heterogeneous cases read grids this script writes next to them in Mitsuba's `.vol` format
(`write_vol`): smooth blobs of density, and an RGB albedo that varies across the box. It also
writes scenes/smoke.vol, the grid of the example in docs/scene-format.md.
"""
import struct
import sys
from pathlib import Path

import numpy as np

import make_material_refs as refs

ROOT = Path(__file__).resolve().parent.parent
DIR = ROOT / "tests" / "data" / "media"

SENSOR = """    <sensor type="perspective">
        <float name="fov" value="{fov}"/>
        <transform name="to_world">
            <lookat origin="{origin}" target="{target}" up="0, 0, 1"/>
        </transform>
        <sampler type="independent">
            <integer name="sample_count" value="$spp"/>
        </sampler>
        <film type="hdrfilm">
            <integer name="width" value="$res"/>
            <integer name="height" value="$res"/>
            <string name="pixel_format" value="rgb"/>
            <rfilter type="box"/>
        </film>{medium}
    </sensor>
"""

FLOOR = """    <shape type="rectangle">
        <transform name="to_world">
            <scale value="10"/>
            <translate z="-1"/>
        </transform>
        <bsdf type="diffuse">
            <rgb name="reflectance" value="0.4"/>
        </bsdf>
    </shape>
"""

AREA_LIGHT = """    <shape type="rectangle">
        <transform name="to_world">
            <scale value="1.5"/>
            <lookat origin="-2.5, -2.5, 4" target="0, 0, 0" up="0, 0, 1"/>
        </transform>
        <bsdf type="diffuse">
            <rgb name="reflectance" value="0"/>
        </bsdf>
        <emitter type="area">
            <rgb name="radiance" value="6"/>
        </emitter>
    </shape>
"""

ENVMAP = """    <emitter type="envmap">
        <string name="filename" value="../lights/sky.exr"/>
        <transform name="to_world">
            <rotate x="1" angle="90"/>
            <rotate z="1" angle="30"/>
        </transform>
    </emitter>
"""

# A reddish fog: extinction per unit length and albedo per channel, so RGB extinction is tested.
FOG = """<medium type="homogeneous"{attrs}>
            <rgb name="sigma_t" value="{sigma_t}"/>
            <rgb name="albedo" value="{albedo}"/>
            <float name="scale" value="{scale}"/>{phase}
        </medium>"""


def fog(name=None, id=None, sigma_t="1.2, 0.8, 0.5", albedo="0.9, 0.7, 0.5", scale=1.0, g=None):
    attrs = (f' name="{name}"' if name else "") + (f' id="{id}"' if id else "")
    # Mitsuba's RGB variants read an <rgb> as a reflectance, in [0, 1]: the largest channel of
    # the extinction goes into `scale`.
    values = [float(v) for v in sigma_t.split(",")]
    top = max(values)
    scale *= top
    sigma_t = ", ".join(f"{v / top:g}" for v in values)
    phase = "" if g is None else f'\n            <phase type="hg"><float name="g" value="{g}"/></phase>'
    return FOG.format(attrs=attrs, sigma_t=sigma_t, albedo=albedo, scale=scale, phase=phase)


def scene(comment, body, fov=28, origin="0, -5.5, 1.8", target="0, 0, -0.2", sensor_medium=""):
    return f"""<?xml version="1.0" encoding="utf-8"?>
<!-- Media case: {comment}
     Reference image: rendered by scripts/make_media_refs.py with Mitsuba 3 (scalar_rgb, volpath),
     which also wrote this file. -->
<scene version="3.0.0">
    <default name="spp" value="64"/>
    <default name="res" value="64"/>

    <integrator type="volpath">
        <integer name="max_depth" value="64"/>
    </integrator>
{SENSOR.format(fov=fov, origin=origin, target=target, medium=sensor_medium)}
{body}</scene>
"""


def write_vol(path, values):
    """Writes `values` (shape nz, ny, nx, channels: x fastest, channels innermost) as a Mitsuba
    .vol file: `VOL`, version 3, encoding 1 (float32), resolutions and channels as int32, the
    bounding box [0, 1]^3, then the data, all little-endian."""
    nz, ny, nx, channels = values.shape
    header = b"VOL" + bytes([3]) + struct.pack("<5i", 1, nx, ny, nz, channels) + struct.pack("<6f", 0, 0, 0, 1, 1, 1)
    path.write_bytes(header + np.ascontiguousarray(values, dtype="<f4").tobytes())


def texel_centres(n):
    """The texel centres of an n[0] x n[1] x n[2] grid in its unit cube, as arrays z, y, x."""
    axes = [(np.arange(k) + 0.5) / k for k in (n[2], n[1], n[0])]
    return np.meshgrid(*axes, indexing="ij")


def blob_density(n):
    """A smooth density: two Gaussian blobs over a floor of 0.15, so the grid's edges are not
    empty (outside the grid there is no medium, inside its edge texels hold 0.15)."""
    z, y, x = texel_centres(n)
    d = 0.15 + np.exp(-((x - 0.4) ** 2 + (y - 0.45) ** 2 + (z - 0.45) ** 2) / (2 * 0.16**2))
    d += 0.6 * np.exp(-((x - 0.7) ** 2 + (y - 0.6) ** 2 + (z - 0.7) ** 2) / (2 * 0.1**2))
    return d[..., None].astype(np.float32)


def write_grids():
    write_vol(DIR / "hetero_blob.vol", blob_density((24, 24, 20)))
    # RGB extinction: the blob, redder where it is dense.
    d = blob_density((12, 12, 12))[..., 0]
    write_vol(DIR / "hetero_rgb_sigma_t.vol", np.stack([d, 0.8 * d + 0.05, 0.5 * d + 0.1], axis=-1))
    # RGB albedo varying along each axis, within [0.1, 0.95].
    z, y, x = texel_centres((12, 12, 12))
    albedo = np.stack([0.95 - 0.6 * x, 0.3 + 0.6 * y, 0.1 + 0.8 * z * (1 - 0.5 * x)], axis=-1)
    write_vol(DIR / "hetero_rgb_albedo.vol", albedo.astype(np.float32))
    write_vol(ROOT / "scenes" / "smoke.vol", blob_density((16, 16, 16)))


SCENES = {
    "cube_area": scene(
        "a null-bounded cube of fog (side 1.96, just above the floor: a face on the floor would make the\n     boundary and the floor coplanar) under a rectangular area light.",
        f"""    <shape type="cube">
        <transform name="to_world"><scale value="0.98"/></transform>
        <bsdf type="null"/>
        {fog("interior")}
    </shape>
{FLOOR}{AREA_LIGHT}""",
    ),
    "dielectric_envmap": scene(
        "a glass sphere (ior 1.5) filled with forward-scattering fog, on a floor under the sky.",
        f"""    <shape type="sphere">
        <bsdf type="dielectric"><float name="int_ior" value="1.5"/><float name="ext_ior" value="1"/></bsdf>
        {fog("interior", sigma_t="2, 1.5, 0.8", albedo="0.95, 0.9, 0.8", g=0.6)}
    </shape>
{FLOOR}{ENVMAP}""",
    ),
    "emitter_inside": scene(
        "a small glowing sphere inside a null-bounded cube of fog, on a floor, nothing else lit.",
        f"""    {fog(id="fog", sigma_t="0.8, 0.6, 0.4", albedo="0.8, 0.8, 0.8")}
    <shape type="cube">
        <transform name="to_world"><scale value="0.98"/></transform>
        <bsdf type="null"/>
        <ref name="interior" id="fog"/>
    </shape>
    <shape type="sphere">
        <float name="radius" value="0.25"/>
        <point name="center" x="0.2" y="0" z="0"/>
        <bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf>
        <emitter type="area"><rgb name="radiance" value="20, 16, 10"/></emitter>
        <ref name="exterior" id="fog"/>
    </shape>
{FLOOR}""",
    ),
    "null_envmap": scene(
        "a null-bounded sphere of back-scattering fog (hg g = -0.3) under the sky, no floor.",
        f"""    <shape type="sphere">
        <bsdf type="null"/>
        {fog("interior", sigma_t="1.5, 1.5, 1.5", albedo="0.95, 0.85, 0.7", g=-0.3)}
    </shape>
{ENVMAP}""",
    ),
    "opaque_inside": scene(
        "an orange diffuse sphere (radius 0.6) inside a null-bounded cube of fog, under an area light.",
        f"""    {fog(id="fog", sigma_t="0.6, 0.6, 0.6", albedo="0.9, 0.9, 0.9")}
    <shape type="cube">
        <transform name="to_world"><scale value="0.98"/></transform>
        <bsdf type="null"/>
        <ref name="interior" id="fog"/>
    </shape>
    <shape type="sphere">
        <float name="radius" value="0.6"/>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.8, 0.45, 0.2"/></bsdf>
        <ref name="exterior" id="fog"/>
    </shape>
{FLOOR}{AREA_LIGHT}""",
    ),
    "camera_in_fog": scene(
        "the camera inside a large null-bounded box of thin fog, looking at a rectangular area "
        "light and a diffuse floor: the light seen through the medium, the sensor in the medium.",
        f"""    {fog(id="air", sigma_t="0.25, 0.2, 0.15", albedo="0.8, 0.8, 0.8")}
    <shape type="cube">
        <transform name="to_world"><scale value="8"/></transform>
        <bsdf type="null"/>
        <ref name="interior" id="air"/>
    </shape>
{FLOOR}{AREA_LIGHT}""",
        origin="2, -5.5, 1.8",
        target="-1, 0, 1",
        fov=45,
        sensor_medium='\n        <ref id="air"/>',
    ),
    "rough_box_spot": scene(
        "a box of fog behind a rough dielectric boundary (GGX, alpha 0.3, index 1.33) under a spot\n"
        "     light: the light reaches the fog through the rough surface only after the floor (volpath's\n"
        "     light samples stop at glass, and a delta light is never hit), as Mitsuba's volpath renders it.",
        f"""    <shape type="cube">
        <transform name="to_world"><scale value="0.98"/></transform>
        <bsdf type="roughdielectric">
            <string name="distribution" value="ggx"/>
            <float name="alpha" value="0.3"/>
            <float name="int_ior" value="1.33"/>
            <float name="ext_ior" value="1"/>
        </bsdf>
        {fog("interior", sigma_t="0.9, 0.7, 0.5", albedo="0.9, 0.85, 0.8")}
    </shape>
    <emitter type="spot">
        <transform name="to_world">
            <lookat origin="2, -3, 6" target="0, 0, -1" up="0, 0, 1"/>
        </transform>
        <rgb name="intensity" value="150"/>
        <float name="cutoff_angle" value="50"/>
        <float name="beam_width" value="40"/>
    </emitter>
{FLOOR}""",
    ),
    "hetero_blob": scene(
        "a heterogeneous medium: a grid of density (two smooth blobs on a floor of 0.15, 24 x 24 x 20\n"
        "     texels) filling part of a null-bounded cube (the grid's box is smaller than the cube: no\n"
        "     medium outside it), grey albedo, under a rectangular area light.",
        """    <shape type="cube">
        <transform name="to_world"><scale value="0.98"/></transform>
        <bsdf type="null"/>
        <medium type="heterogeneous" name="interior">
            <volume name="sigma_t" type="gridvolume">
                <string name="filename" value="hetero_blob.vol"/>
                <transform name="to_world">
                    <scale x="1.6" y="1.6" z="1.4"/>
                    <translate x="-0.8" y="-0.8" z="-0.9"/>
                </transform>
            </volume>
            <float name="albedo" value="0.85"/>
            <float name="scale" value="4"/>
        </medium>
    </shape>
""" + FLOOR + AREA_LIGHT,
    ),
    "hetero_rgb": scene(
        "a heterogeneous medium with RGB extinction (a 3-channel grid, 12^3) and an RGB albedo grid\n"
        "     (3 channels, 12^3) placed by a to_world of its own (the whole cube), forward scattering,\n"
        "     under a rectangular area light.",
        """    <shape type="cube">
        <transform name="to_world"><scale value="0.98"/></transform>
        <bsdf type="null"/>
        <medium type="heterogeneous" name="interior">
            <volume name="sigma_t" type="gridvolume">
                <string name="filename" value="hetero_rgb_sigma_t.vol"/>
                <transform name="to_world">
                    <scale x="1.8" y="1.5" z="1.6"/>
                    <translate x="-0.9" y="-0.7" z="-0.95"/>
                </transform>
            </volume>
            <volume name="albedo" type="gridvolume">
                <string name="filename" value="hetero_rgb_albedo.vol"/>
                <transform name="to_world">
                    <scale value="1.96"/>
                    <translate x="-0.98" y="-0.98" z="-0.98"/>
                </transform>
            </volume>
            <float name="scale" value="3"/>
            <phase type="hg"><float name="g" value="0.5"/></phase>
        </medium>
    </shape>
""" + FLOOR + AREA_LIGHT,
    ),
}


def spp_for(case):
    # The box behind rough glass is lit only by paths that leave it and find the spot-lit floor:
    # noisy, so more samples keep the reference's mean within a quarter of the test's tolerance.
    return 16384 if case == "rough_box_spot" else 4096


HEADER = refs.HEADER.replace("material and texture tests", "participating-media tests").replace(
    "scripts/make_material_refs.py", "scripts/make_media_refs.py"
)


def main():
    refs.mi.set_variant("scalar_rgb")
    refs.DIR = DIR
    refs.MANIFEST = DIR / "MANIFEST.md"
    refs.spp_for = spp_for
    refs.HEADER = HEADER
    refs.object_share = lambda scene, image: None
    DIR.mkdir(parents=True, exist_ok=True)
    write_grids()
    cases = sys.argv[1:] or sorted(SCENES)
    for case in cases:
        (DIR / f"{case}.xml").write_text(SCENES[case])
    rows, notes = refs.read_manifest()
    for case in cases:
        rows[case] = refs.render(case)
        refs.write_manifest(rows, notes)


if __name__ == "__main__":
    main()
