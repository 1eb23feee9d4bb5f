#!/usr/bin/env python3
"""Writes the Mitsuba 3 scenes of tests/data/emitters (emitting meshes, spot lights with and
without a projected texture, a projector, a reflecting emitter), which tests/emitters.rs renders
and compares with Mitsuba's own images (scripts/make_emitter_refs.py renders those).

    python3 scripts/make_emitter_scenes.py
"""
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DIR = ROOT / "tests" / "data" / "emitters"

HEADER = """<?xml version="1.0" encoding="utf-8"?>
<!-- Emitter case `{case}`: {what}
     Reference image: {case}.exr, rendered by scripts/make_emitter_refs.py with Mitsuba 3.9.1
     (scalar_rgb); scripts/make_emitter_scenes.py wrote this file. -->
"""

# A unit sphere on a 20 x 20 grey floor seen from the front, as in tests/data/materials.
STAGE = """<scene version="3.0.0">
    <default name="spp" value="64"/>
    <default name="res" value="64"/>

    <integrator type="path">
        <integer name="max_depth" value="12"/>
    </integrator>
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="to_world">
            <lookat origin="0, -7, 3" target="0, 0, -0.5" up="0, 0, 1"/>
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
    </sensor>
    <shape type="sphere">
        <bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.55, 0.5"/></bsdf>
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><scale value="10"/><translate z="-1"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf>
    </shape>
{lights}</scene>
"""

SPOT = """    <emitter type="spot">
        <transform name="to_world"><lookat origin="0.5, -3, 4" target="0, 0, -1" up="0, 0, 1"/></transform>
        <rgb name="intensity" value="60"/>
        <float name="cutoff_angle" value="{cutoff}"/>
        <float name="beam_width" value="{beam}"/>
{texture}    </emitter>
"""

def checker_sphere(transform):
    """The stage with its sphere emitting a checkerboard radiance, placed by `transform`."""
    return STAGE.replace("""    <shape type="sphere">
        <bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.55, 0.5"/></bsdf>
    </shape>""", """    <shape type="sphere">""" + transform + """
        <bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf>
        <emitter type="area">
            <texture type="checkerboard" name="radiance">
                <rgb name="color0" value="1, 0.8, 0.5"/>
                <rgb name="color1" value="0.1, 0.3, 0.9"/>
                <transform name="to_uv"><scale x="4" y="4"/></transform>
            </texture>
        </emitter>
    </shape>""").format(lights="")


CASES = {
    "spot_ramp": ("a spot light with a wide linear fall-off (cutoff 35, beam width 8 degrees).",
                  STAGE.format(lights=SPOT.format(cutoff=35, beam=8, texture=""))),
    "spot_textured": ("a spot light projecting a 16 x 8 RGB PNG (bilinear) through its cone.",
                      STAGE.format(lights=SPOT.format(cutoff=30, beam=30, texture=(
                          '        <texture type="bitmap" name="texture">\n'
                          '            <string name="filename" value="../materials/textures/tiles.png"/>\n'
                          '        </texture>\n')))),
    "projector": ("a projector casting a 5 x 3 PNG (nearest) onto the sphere and floor.",
                  STAGE.format(lights="""    <emitter type="projector">
        <transform name="to_world"><lookat origin="2, -4, 3" target="0, 0, -0.6" up="0, 0, 1"/></transform>
        <float name="fov" value="35"/>
        <float name="scale" value="6"/>
        <texture type="bitmap" name="irradiance">
            <string name="filename" value="../materials/textures/palette5x3.png"/>
            <string name="filter_type" value="nearest"/>
        </texture>
    </emitter>
""")),
    "reflecting_emitter": ("an emitting sphere (radiance 0.3) that also reflects diffusely, lit by a point light.",
                           STAGE.replace("""    <shape type="sphere">
        <bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.55, 0.5"/></bsdf>
    </shape>""", """    <shape type="sphere">
        <bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.55, 0.5"/></bsdf>
        <emitter type="area"><rgb name="radiance" value="0.3, 0.2, 0.1"/></emitter>
    </shape>""").format(lights="""    <emitter type="point">
        <point name="position" x="-3" y="-3" z="4.5"/>
        <rgb name="intensity" value="60"/>
    </emitter>
""")),
    "area_bitmap": ("a rectangle emitting a 16 x 8 RGB PNG as its radiance (bilinear), facing the "
                    "camera behind the sphere, lighting the sphere and floor.",
                    STAGE.format(lights="""    <shape type="rectangle">
        <transform name="to_world"><scale x="2.5" y="1.2"/><rotate x="1" angle="90"/><translate y="2" z="0.4"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf>
        <emitter type="area">
            <texture type="bitmap" name="radiance">
                <string name="filename" value="../materials/textures/tiles.png"/>
            </texture>
        </emitter>
    </shape>
""")),
    "area_checker_sphere": ("the sphere itself emitting a checkerboard radiance (4 x 4 checks in uv), lighting "
                            "the floor.", checker_sphere("")),
    "area_checker_sphere_rotated": ("the checkerboard-emitting sphere turned by its to_world (60 degrees about x, "
                                    "then 25 about z): its texture coordinates turn with it.",
                                    checker_sphere("""
        <transform name="to_world"><rotate x="1" angle="60"/><rotate z="1" angle="25"/></transform>""")),
}


def cornell_mesh():
    """The Cornell box of scenes/mitsuba/cornell-box.xml lit by an emitting icosphere (an OBJ
    mesh of 320 triangles) instead of its ceiling rectangle."""
    text = (ROOT / "scenes" / "mitsuba" / "cornell-box.xml").read_text()
    text = re.sub(r"^<\?xml.*?\n<!--.*?-->\n", "", text, flags=re.S)
    light = re.search(r"    <!-- The light:.*?</shape>\n", text, re.S)
    mesh = """    <!-- The light: an icosphere mesh of radius 0.6 hanging below the ceiling. -->
    <shape type="obj">
        <string name="filename" value="../../../scenes/mitsuba/meshes/icosphere.obj"/>
        <transform name="to_world"><scale value="0.6"/><translate x="2.78" y="4.3" z="2.795"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf>
        <emitter type="area"><rgb name="radiance" value="6"/></emitter>
    </shape>
"""
    text = text[:light.start()] + mesh + text[light.end():]
    text = text.replace('<default name="res" value="400"/>', '<default name="res" value="64"/>')
    return ("the Cornell box lit by an emitting OBJ mesh (an icosphere) instead of its rectangle.", text)


def main():
    DIR.mkdir(parents=True, exist_ok=True)
    cases = dict(CASES)
    cases["cornell_mesh"] = cornell_mesh()
    for case, (what, body) in cases.items():
        (DIR / f"{case}.xml").write_text(HEADER.format(case=case, what=what) + body)
        print(f"wrote {case}.xml")


if __name__ == "__main__":
    main()
