#!/usr/bin/env python3
"""Writes the Mitsuba 3 scenes of tests/data/materials: one file per material case and lighting,
and the textured quads. Each file is self-contained and readable on its own; this script only
keeps the 53 of them consistent (same camera, floor and lights in every material scene).

    python3 scripts/make_material_scenes.py

Then scripts/make_material_refs.py renders them with Mitsuba. The textures come from
scripts/make_material_textures.py.

Material scenes (<case>_point.xml, <case>_area.xml): a unit sphere at the origin on a 20 x 20 grey
floor at z = -1, +z up, seen from the front and above; lit by one point light or one 2 x 2
rectangular area light above and to the left. The twosided/onesided cases replace the sphere by
two open panels. Quad scenes (quad_*.xml): a textured rectangle filling a 128 x 128 view, lit by
a constant environment only.
"""
import textwrap
from pathlib import Path

OUT = Path(__file__).resolve().parent.parent / "tests" / "data" / "materials"

I1, I2, I3 = " " * 4, " " * 8, " " * 12


def comment(*paragraphs):
    """An XML comment of wrapped paragraphs, the first after `<!-- `, the rest indented to match."""
    lines = []
    for k, text in enumerate(paragraphs):
        lines += textwrap.wrap(" ".join(text.split()), 95, initial_indent="<!-- " if k == 0 else "     ",
                               subsequent_indent="     ")
    return "\n".join(lines) + " -->"


def indent(text, pad):
    return "\n".join(pad + line if line else line for line in text.strip("\n").split("\n"))


def bitmap(name, filename, to_uv=None, raw=False, filter_type=None, wrap_mode=None):
    """A nested bitmap texture (name may be None, as bumpmap's height texture needs none)."""
    attr = f' name="{name}"' if name else ""
    lines = [f'<texture type="bitmap"{attr}>', f'    <string name="filename" value="textures/{filename}"/>']
    if raw:
        lines.append('    <boolean name="raw" value="true"/>')
    if filter_type:
        lines.append(f'    <string name="filter_type" value="{filter_type}"/>')
    if wrap_mode:
        lines.append(f'    <string name="wrap_mode" value="{wrap_mode}"/>')
    if to_uv:
        lines.append(f'    <transform name="to_uv">{to_uv}</transform>')
    lines.append("</texture>")
    return "\n".join(lines)


# ---------------------------------------------------------------------------------------------
# Material cases: (name, one-line description, the sphere's BSDF)
# ---------------------------------------------------------------------------------------------

CASES = [
    ("diffuse_bitmap", "diffuse with an 8-bit sRGB PNG reflectance (16 x 8 texels) repeated 3 x 2 times", f"""
<bsdf type="diffuse">
{indent(bitmap("reflectance", "tiles.png", '<scale x="3" y="2"/>'), I1)}
</bsdf>"""),
    ("diffuse_checker", "diffuse with a checkerboard reflectance, 16 checks around and 8 from pole to pole", """
<bsdf type="diffuse">
    <texture type="checkerboard" name="reflectance">
        <rgb name="color0" value="0.8, 0.75, 0.2"/>
        <rgb name="color1" value="0.1, 0.25, 0.6"/>
        <transform name="to_uv"><scale x="8" y="4"/></transform>
    </texture>
</bsdf>"""),
    ("conductor_au", "smooth gold (Mitsuba's tabulated Au, converted to RGB)", """
<bsdf type="conductor">
    <string name="material" value="Au"/>
</bsdf>"""),
    ("conductor_etak", "smooth conductor with explicit complex IOR and a tinted specular_reflectance", """
<bsdf type="conductor">
    <rgb name="eta" value="1.2, 0.6, 0.4"/>
    <rgb name="k" value="3.5, 3.0, 2.6"/>
    <rgb name="specular_reflectance" value="1.0, 0.85, 0.7"/>
</bsdf>"""),
    ("conductor_none", "the default conductor: material none, a perfect 100% mirror", """
<bsdf type="conductor"/>"""),
    ("roughconductor_ggx", "rough copper, GGX, alpha 0.2", """
<bsdf type="roughconductor">
    <string name="material" value="Cu"/>
    <string name="distribution" value="ggx"/>
    <float name="alpha" value="0.2"/>
</bsdf>"""),
    ("roughconductor_beckmann_aniso",
     "anisotropic rough aluminium, Beckmann, alpha_u 0.05 (along dp/du, around the sphere), alpha_v 0.35", """
<bsdf type="roughconductor">
    <string name="material" value="Al"/>
    <string name="distribution" value="beckmann"/>
    <float name="alpha_u" value="0.05"/>
    <float name="alpha_v" value="0.35"/>
</bsdf>"""),
    ("roughconductor_alpha_tex",
     "GGX rough mirror (material none) whose alpha comes from a raw greyscale PNG: bands of 0.03, 0.1, 0.25, 0.5",
     f"""
<bsdf type="roughconductor">
    <string name="distribution" value="ggx"/>
{indent(bitmap("alpha", "roughness.png", '<scale x="4" y="2"/>', raw=True), I1)}
</bsdf>"""),
    ("dielectric", "smooth glass with the defaults (int_ior bk7 = 1.5046, ext_ior air = 1.000277)", """
<bsdf type="dielectric"/>"""),
    ("roughdielectric_ggx", "rough glass, GGX, alpha 0.15, default IORs (bk7 in air)", """
<bsdf type="roughdielectric">
    <string name="distribution" value="ggx"/>
    <float name="alpha" value="0.15"/>
</bsdf>"""),
    ("roughdielectric_beckmann", "rough water, Beckmann, alpha 0.3, int_ior \"water\" (1.333) in air", """
<bsdf type="roughdielectric">
    <string name="distribution" value="beckmann"/>
    <float name="alpha" value="0.3"/>
    <string name="int_ior" value="water"/>
</bsdf>"""),
    ("plastic", "smooth plastic, rgb diffuse_reflectance, default IORs (polypropylene in air)", """
<bsdf type="plastic">
    <rgb name="diffuse_reflectance" value="0.1, 0.27, 0.36"/>
</bsdf>"""),
    ("plastic_nonlinear", "smooth plastic with a bitmap diffuse_reflectance and nonlinear = true", f"""
<bsdf type="plastic">
{indent(bitmap("diffuse_reflectance", "tiles.png", '<scale x="3" y="2"/>'), I1)}
    <boolean name="nonlinear" value="true"/>
</bsdf>"""),
    ("roughplastic_ggx", "rough plastic, GGX, alpha 0.2, rgb diffuse_reflectance", """
<bsdf type="roughplastic">
    <string name="distribution" value="ggx"/>
    <float name="alpha" value="0.2"/>
    <rgb name="diffuse_reflectance" value="0.6, 0.12, 0.1"/>
</bsdf>"""),
    ("roughplastic_beckmann", "rough plastic with every default: Beckmann, alpha 0.1, diffuse 0.5", """
<bsdf type="roughplastic"/>"""),
    ("bumpmap", "bump map (raw greyscale height PNG, scale 0.06) over a GGX rough plastic", f"""
<bsdf type="bumpmap">
{indent(bitmap(None, "height.png", '<scale x="4" y="2"/>', raw=True), I1)}
    <float name="scale" value="0.06"/>
    <bsdf type="roughplastic">
        <string name="distribution" value="ggx"/>
        <float name="alpha" value="0.15"/>
        <rgb name="diffuse_reflectance" value="0.7, 0.55, 0.3"/>
    </bsdf>
</bsdf>"""),
    ("normalmap", "tangent-space normal map (RGB PNG, raw) over GGX rough copper, alpha 0.15", f"""
<bsdf type="normalmap">
{indent(bitmap("normalmap", "normals.png", '<scale x="4" y="2"/>', raw=True), I1)}
    <bsdf type="roughconductor">
        <string name="material" value="Cu"/>
        <string name="distribution" value="ggx"/>
        <float name="alpha" value="0.15"/>
    </bsdf>
</bsdf>"""),
    ("mask", "diffuse behind a mask whose opacity is a greyscale PNG with round holes (0 = hole)", f"""
<bsdf type="mask">
{indent(bitmap("opacity", "holes.png", '<scale x="3" y="3"/>'), I1)}
    <bsdf type="diffuse">
        <rgb name="reflectance" value="0.8, 0.45, 0.2"/>
    </bsdf>
</bsdf>"""),
    ("blendbsdf",
     "blend of a diffuse (first) and GGX rough gold (second); weight = the second's share, from a greyscale PNG",
     f"""
<bsdf type="blendbsdf">
{indent(bitmap("weight", "weight.png", '<scale x="2" y="1"/>'), I1)}
    <bsdf type="diffuse">
        <rgb name="reflectance" value="0.2, 0.45, 0.7"/>
    </bsdf>
    <bsdf type="roughconductor">
        <string name="material" value="Au"/>
        <string name="distribution" value="ggx"/>
        <float name="alpha" value="0.1"/>
    </bsdf>
</bsdf>"""),
    ("twosided", "two open panels with a twosided diffuse: the left one shows its front, the right one its back", """
<bsdf type="twosided">
    <bsdf type="diffuse">
        <rgb name="reflectance" value="0.75, 0.55, 0.25"/>
    </bsdf>
</bsdf>"""),
    ("onesided", "the twosided case without the wrapper: the right panel shows its back, which must be black", """
<bsdf type="diffuse">
    <rgb name="reflectance" value="0.75, 0.55, 0.25"/>
</bsdf>"""),
]

MASK_NOTE = (
    "Integrator: volpath, not path. Mitsuba's path integrator tests shadow rays with scene.ray_test, "
    "which any surface blocks, the mask's holes included: light reaches the floor through the holes only "
    "by BSDF sampling, so a point light casts a solid shadow. volpath multiplies a shadow ray's "
    "throughput by each crossed surface's eval_null_transmission (1 - opacity), so light passes the "
    "holes, as in caustic. volpath also does not count a pass through a hole as a bounce for max_depth.")

LIGHTS = {
    "point": ("one point light of intensity 60 W/sr at (-3, -3, 4.5)", """
<emitter type="point">
    <point name="position" x="-3" y="-3" z="4.5"/>
    <rgb name="intensity" value="60"/>
</emitter>"""),
    "area": ("one 3 x 3 one-sided rectangular area light of radiance 6 centred at (-2.5, -2.5, 4),\n"
             "     facing the origin", """
<shape type="rectangle">
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
</shape>"""),
}

SENSOR = """
<sensor type="perspective">
    <float name="fov" value="{fov}"/>
    <transform name="to_world">
        <lookat origin="{origin}" target="{target}" up="{up}"/>
    </transform>
    <sampler type="independent">
        <integer name="sample_count" value="$spp"/>
    </sampler>
    <film type="hdrfilm">
        <integer name="width" value="$res"/>
        <integer name="height" value="$res"/>
        <string name="pixel_format" value="rgb"/>
        <rfilter type="box"/>
    </film>
</sensor>"""

FLOOR = """
<!-- The floor: 20 x 20, grey diffuse, at z = -1 facing up. -->
<shape type="rectangle">
    <transform name="to_world">
        <scale value="10"/>
        <translate z="-1"/>
    </transform>
    <bsdf type="diffuse">
        <rgb name="reflectance" value="0.4"/>
    </bsdf>
</shape>"""

# Two 1.2 x 1.8 panels standing on the floor, leaning back 20 degrees. The left one's front
# (+z of the rectangle) faces the camera; the right one is turned over first (rotate y 180), so
# the camera and the lights see its back.
PANELS = """
<!-- Left panel: its front faces the camera and the light. -->
<shape type="rectangle">
    <transform name="to_world">
        <scale x="0.6" y="0.9"/>
        <rotate x="1" angle="90"/>
        <rotate x="1" angle="-20"/>
        <translate x="-0.75" y="0.3078" z="-0.1543"/>
    </transform>
    <ref id="material"/>
</shape>
<!-- Right panel: the same, turned over, so its back faces the camera and the light. -->
<shape type="rectangle">
    <transform name="to_world">
        <scale x="0.6" y="0.9"/>
        <rotate y="1" angle="180"/>
        <rotate x="1" angle="90"/>
        <rotate x="1" angle="-20"/>
        <translate x="0.75" y="0.3078" z="-0.1543"/>
    </transform>
    <ref id="material"/>
</shape>"""

SPHERE = """
<!-- The sphere: radius 1 at the origin, resting on the floor; its poles are on the z axis, so
     u runs around it (u = 0 at +x) and v from the top (v = 0) to the bottom. -->
<shape type="sphere">
    <ref id="material"/>
</shape>"""

CAMERA = dict(fov=26, origin="0, -5.5, 1.8", target="0, 0, -0.2", up="0, 0, 1")
# The panels are wider than the sphere.
PANEL_CAMERA = dict(CAMERA, fov=30)


def with_id(bsdf):
    """The BSDF element with id="material" on its opening tag."""
    bsdf = bsdf.strip("\n")
    first, _, rest = bsdf.partition("\n")
    if first.endswith("/>"):
        first = first[:-2].rstrip() + ' id="material"/>'
    else:
        first = first[:-1] + ' id="material">'
    return first + ("\n" + rest if rest else "")


def material_scene(case, description, bsdf, light):
    light_text, light_xml = LIGHTS[light]
    panels = case in ("twosided", "onesided")
    integrator = "volpath" if case == "mask" else "path"
    subject = ("Two open panels (rectangles) standing on" if panels else "A unit sphere resting on")
    header = '<?xml version="1.0" encoding="utf-8"?>\n' + comment(
        f"Material case `{case}`, {light} light: {description}.",
        f"{subject} a grey floor, lit by {light_text}.",
        f"Reference image: {case}_{light}.exr, rendered by scripts/make_material_refs.py with Mitsuba 3.9.1 "
        "(scalar_rgb); scripts/make_material_scenes.py wrote this file.",
        *([MASK_NOTE] if case == "mask" else []))
    body = [
        '<default name="spp" value="64"/>',
        '<default name="res" value="64"/>',
        "",
        "<!-- max_depth counts path segments: 12 lets light through a glass sphere and back. -->",
        f'<integrator type="{integrator}">\n    <integer name="max_depth" value="12"/>\n</integrator>',
        SENSOR.format(**(PANEL_CAMERA if panels else CAMERA)).strip("\n"),
        "",
        with_id(bsdf),
        (PANELS if panels else SPHERE).strip("\n"),
        FLOOR.strip("\n"),
        "",
        f"<!-- The light. -->\n{light_xml.strip()}",
    ]
    return header + '\n<scene version="3.0.0">\n' + "\n".join(indent(b, I1) if b else "" for b in body) + "\n</scene>\n"


# ---------------------------------------------------------------------------------------------
# Textured quads
# ---------------------------------------------------------------------------------------------

# to_uv: uv' = 3 uv + (-1.15, -0.9), so the view shows u' in [-1.15, 1.85] and v' in [-0.9, 2.1]:
# three repetitions with the borders in the middle of texels, and both sides of [0, 1]^2.
QUAD_TO_UV = '<scale x="3" y="3"/><translate x="-1.15" y="-0.9"/>'

QUADS = [
    ("quad_repeat_bilinear", "palette5x3.png", "bilinear", "repeat", "the 8-bit PNG, bilinear, repeat"),
    ("quad_mirror_nearest", "palette5x3.png", "nearest", "mirror", "the 8-bit PNG, nearest, mirror"),
    ("quad_clamp_bilinear", "palette5x3.png", "bilinear", "clamp", "the 8-bit PNG, bilinear, clamp"),
    ("quad_png8", "palette5x3.png", "nearest", "repeat", "8-bit RGB PNG (sRGB-decoded)"),
    ("quad_png16", "palette5x3_16.png", "nearest", "repeat", "16-bit RGB PNG (sRGB-decoded too, values x 257)"),
    ("quad_jpeg", "palette5x3.jpg", "nearest", "repeat",
     "baseline JPEG, 4:4:4, 40 x 24: each texel a flat 8 x 8 block, so decoding is exact"),
    ("quad_bmp", "palette5x3.bmp", "nearest", "repeat", "24-bit BMP, bottom-up rows (sRGB-decoded)"),
    ("quad_tga", "palette5x3.tga", "nearest", "repeat",
     "uncompressed 24-bit TGA, bottom-left origin, with the TGA 2.0 footer Mitsuba needs to recognise it"),
    ("quad_exr", "palette5x3.exr", "nearest", "repeat", "float32 OpenEXR of the linear values (not decoded)"),
    ("quad_hdr", "palette5x3.hdr", "nearest", "repeat",
     "Radiance RGBE of the linear values, flat (no RLE); decoded as mantissa * 2^(e - 136)"),
    ("quad_pfm", "palette5x3.pfm", "nearest", "repeat", "little-endian colour PFM of the linear values, bottom-up rows"),
]


def quad_scene(case, filename, filter_type, wrap_mode, description):
    tex = bitmap("reflectance", filename, QUAD_TO_UV, filter_type=filter_type, wrap_mode=wrap_mode)
    header = '<?xml version="1.0" encoding="utf-8"?>\n' + comment(
        f"Textured quad `{case}`: {description}; filter {filter_type}, wrap {wrap_mode}.",
        "The default rectangle ([-1, 1]^2 at z = 0, facing +z, uv = ((x + 1) / 2, (y + 1) / 2)) fills a "
        "90 degree view from (0, 0, 1) exactly, so pixel (i, j) of the 128 x 128 image covers u in "
        "[i, i + 1] / 128 and v in [127 - j, 128 - j] / 128: v grows upwards in the image while the "
        "bitmap's v = 0 is its top row, so the texture shows upside down.",
        "A diffuse surface under a constant environment of radiance 1, with max_depth 2 (direct light "
        "only) and nothing to occlude it, has radiance equal to its reflectance: each pixel is the "
        "texture averaged over the pixel.",
        f"Reference image: {case}.exr, rendered by scripts/make_material_refs.py with Mitsuba 3.9.1 "
        "(scalar_rgb); scripts/make_material_scenes.py wrote this file.")
    body = [
        '<default name="spp" value="64"/>',
        '<default name="res" value="128"/>',
        "",
        '<integrator type="path">\n    <integer name="max_depth" value="2"/>\n</integrator>',
        SENSOR.format(fov=90, origin="0, 0, 1", target="0, 0, 0", up="0, 1, 0").strip("\n"),
        "",
        "<!-- uv' = 3 uv + (-1.15, -0.9): three repeats, borders inside texels, both sides of [0, 1]. -->",
        f'<shape type="rectangle">\n    <bsdf type="diffuse">\n{indent(tex, I2)}\n    </bsdf>\n</shape>',
        "",
        '<emitter type="constant">\n    <rgb name="radiance" value="1"/>\n</emitter>',
    ]
    return header + '\n<scene version="3.0.0">\n' + "\n".join(indent(b, I1) if b else "" for b in body) + "\n</scene>\n"


def main():
    OUT.mkdir(parents=True, exist_ok=True)
    n = 0
    for case, description, bsdf in CASES:
        for light in LIGHTS:
            (OUT / f"{case}_{light}.xml").write_text(material_scene(case, description, bsdf, light))
            n += 1
    for args in QUADS:
        (OUT / f"{args[0]}.xml").write_text(quad_scene(*args))
        n += 1
    print(f"wrote {n} scenes to {OUT}")


if __name__ == "__main__":
    main()
