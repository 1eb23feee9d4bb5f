#!/usr/bin/env python3
"""caustic's vcm against LuxCoreRender's BIDIRVMCPU (vertex connection and merging) at equal time.

Translates a caustic TOML scene into LuxCore's scene properties (quads, boxes and spheres as
triangle meshes, spheres at 192 x 96 segments with smooth normals; diffuse, mirror, glass, rough
metal and rough plastic materials; point, spherical area and constant lights), renders it with
LuxCore (`pip install pyluxcore`) and with caustic for the same wall time on the same number of
threads, and prints each renderer's error against its own long render of the same scene.

Each renderer is measured against itself because the translation is close, not exact (a
tessellated sphere, LuxCore's roughness and light units): what is compared is how fast each
converges on the same kind of light transport. The errors are the relative RMSE (the RMSE over
all pixels and channels divided by the reference's mean, so that the two renderers' different
light units do not enter) and the relative MSE (`rel_mse`), which a few very bright pixels do
not dominate. References are cached in the output folder (`--ref-time` seconds each).

Both renderers use the scene's pixel filter (caustic's default, the one-pixel box; LuxCore's own
default would be a Blackman-Harris of radius 2), and the references take another seed (7) than
the timed runs (run k takes seed k), so that no run shares its reference's samples.

    scripts/luxcore_compare.py scenes/13-cornell-caustics.toml [--time 10] [--ref-time 300] [--runs N]
        [--threads 2] [--caustic target/release/caustic] [--out /tmp/luxcore-compare] [--refs-only]
"""
import argparse
import math
import os
import subprocess
import sys
import time
import tomllib

import numpy as np

# The EXR reader's bindings load before pyluxcore: pyluxcore brings TBB's malloc proxy, and
# OpenEXR (or Mitsuba's bitmap reader) loaded after it aborted the script (free(): invalid
# pointer).
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from rmse import read_rgb  # noqa: E402


def read_exr(path):
    """Linear RGB of an EXR written by caustic (`scripts/rmse.py`'s reader, imported above)."""
    return read_rgb(str(path))


def quad_mesh(corner, e1, e2):
    c, a, b = (np.array(v, dtype=np.float64) for v in (corner, e1, e2))
    points = [c, c + a, c + a + b, c + b]
    # caustic's quad faces along e1 x e2.
    return points, [(0, 1, 2), (0, 2, 3)], None


def box_mesh(lo, hi):
    x0, y0, z0 = lo
    x1, y1, z1 = hi
    p = [(x0, y0, z0), (x1, y0, z0), (x1, y1, z0), (x0, y1, z0), (x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)]
    faces = [(0, 2, 1), (0, 3, 2), (4, 5, 6), (4, 6, 7), (0, 1, 5), (0, 5, 4), (3, 6, 2), (3, 7, 6), (0, 4, 7), (0, 7, 3), (1, 2, 6), (1, 6, 5)]
    return [np.array(v, dtype=np.float64) for v in p], faces, None


def sphere_mesh(center, radius, nu=192, nv=96):
    c = np.array(center, dtype=np.float64)
    points, normals, faces = [], [], []
    for j in range(nv + 1):
        theta = math.pi * j / nv
        for i in range(nu + 1):
            phi = 2 * math.pi * i / nu
            n = np.array([math.sin(theta) * math.cos(phi), math.cos(theta), math.sin(theta) * math.sin(phi)])
            points.append(c + radius * n)
            normals.append(n)
    row = nu + 1
    for j in range(nv):
        for i in range(nu):
            a, b, d, e = j * row + i, j * row + i + 1, (j + 1) * row + i, (j + 1) * row + i + 1
            if j > 0:
                faces.append((a, e, b))
            if j < nv - 1:
                faces.append((a, d, e))
    # Wound outwards (counter-clockwise seen from outside).
    def outward(f):
        p0, p1, p2 = (points[i] for i in f)
        return f if np.dot(np.cross(p1 - p0, p2 - p0), p0 + p1 + p2 - 3 * c) > 0 else (f[0], f[2], f[1])
    return points, [outward(f) for f in faces], normals


def fmt(v):
    return " ".join(f"{float(x):.9g}" for x in v)


def luxcore_material(name, m):
    """LuxCore properties of caustic material `m` (the subset the comparison scenes use)."""
    p = f"scene.materials.{name}"
    kind = m.get("type", "diffuse")
    if kind == "diffuse":
        kd = np.array(m.get("color", [0.8, 0.8, 0.8])) * m.get("kd", 1.0)
        return [f'{p}.type = "matte"', f"{p}.kd = {fmt(kd)}"]
    if kind == "reflective":
        kr = np.array(m.get("color", [1, 1, 1])) * m.get("kr", 1.0)
        return [f'{p}.type = "mirror"', f"{p}.kr = {fmt(kr)}"]
    if kind == "dielectric":
        return [f'{p}.type = "glass"', f"{p}.kr = 1 1 1", f"{p}.kt = 1 1 1", f"{p}.interiorior = {m.get('ior', 1.5)}", f"{p}.exteriorior = 1"]
    if kind == "roughconductor":
        # LuxCore's roughness is the microfacet alpha's square root in its GGX.
        r = math.sqrt(m.get("alpha", 0.1))
        return [f'{p}.type = "metal2"', f'{p}.preset = "aluminium"', f"{p}.uroughness = {r}", f"{p}.vroughness = {r}"]
    if kind == "roughplastic":
        r = math.sqrt(m.get("alpha", 0.1))
        return [f'{p}.type = "glossy2"', f"{p}.kd = {fmt(m.get('color', [0.5, 0.5, 0.5]))}", f"{p}.ks = 0.04 0.04 0.04",
                f"{p}.uroughness = {r}", f"{p}.vroughness = {r}"]
    sys.exit(f"luxcore_compare: material type {kind!r} is not translated")


def luxcore_filter(render):
    """The scene's pixel filter in LuxCore's terms. LuxCore's own default is a Blackman-Harris
    filter of radius 2 pixels, which averages each pixel with its neighbours: left in place, it
    lowered LuxCore's relative RMSE to about 0.6x of its box-filtered one on both bundled scenes
    and blurred the sub-pixel highlights that dominate the RMSE, so the comparison measured the
    filters as much as the renderers."""
    name = render.get("filter", "box")
    if name != "box":
        sys.exit(f"luxcore_compare: filter {name!r} is not translated (only caustic's default box)")
    # LuxCore's NONE adds each sample to the pixel it falls in: the one-pixel box.
    return ['film.filter.type = "NONE"']


def luxcore_scene(desc, threads, seconds, seed):
    import pyluxcore

    r = desc.get("render", {})
    width, height = r.get("width", 640), r.get("height", 480)
    cam = desc["camera"]
    props = [
        'scene.camera.type = "perspective"',
        f"scene.camera.lookat.orig = {fmt(cam['eye'])}",
        f"scene.camera.lookat.target = {fmt(cam['look_at'])}",
        f"scene.camera.up = {fmt(cam.get('up', [0, 1, 0]))}",
        f"scene.camera.fieldofview = {cam.get('fov', 45)}",
    ]
    for name, m in desc.get("materials", {}).items():
        props += luxcore_material(name, m)
    meshes = []
    for k, o in enumerate(desc.get("objects", [])):
        kind = o["type"]
        if kind == "quad":
            meshes.append((f"o{k}", quad_mesh(o["corner"], o["edge1"], o["edge2"]), o["material"]))
        elif kind == "box":
            meshes.append((f"o{k}", box_mesh(o["min"], o["max"]), o["material"]))
        elif kind == "sphere":
            meshes.append((f"o{k}", sphere_mesh(o["center"], o["radius"]), o["material"]))
        else:
            sys.exit(f"luxcore_compare: object type {kind!r} is not translated")
    for k, light in enumerate(desc.get("lights", [])):
        kind = light["type"]
        if kind == "point":
            i = np.array(light.get("color", [1, 1, 1])) * light["intensity"]
            props += [f'scene.lights.l{k}.type = "point"', f"scene.lights.l{k}.position = {fmt(light['position'])}",
                      f"scene.lights.l{k}.color = {fmt(i)}", f"scene.lights.l{k}.gain = 1 1 1"]
        elif kind == "area" and light.get("shape") == "sphere":
            # A sphere light's radiance: intensity as caustic reads it for a spherical light
            # (power / (4 pi^2 r^2)); only the shape and relative strength matter here.
            rad = light["intensity"] / (4 * math.pi**2 * light["radius"] ** 2)
            e = np.array(light.get("color", [1, 1, 1])) * rad
            props += [f'scene.materials.light{k}.type = "matte"', f"scene.materials.light{k}.kd = 0 0 0",
                      f"scene.materials.light{k}.emission = {fmt(e)}"]
            meshes.append((f"l{k}", sphere_mesh(light["center"], light["radius"], 48, 24), f"light{k}"))
        elif kind == "constant":
            props += [f'scene.lights.l{k}.type = "constantinfinite"', f"scene.lights.l{k}.color = {fmt(light['color'])}",
                      f"scene.lights.l{k}.gain = 1 1 1"]
        else:
            sys.exit(f"luxcore_compare: light type {kind!r} is not translated")
    scene = pyluxcore.Scene()
    for name, (points, faces, normals), _ in meshes:
        pts = [tuple(map(float, p)) for p in points]
        nrm = [tuple(map(float, n)) for n in normals] if normals is not None else None
        scene.DefineMesh(f"mesh-{name}", pts, faces, nrm, None, None, None)
    for name, _, material in meshes:
        props += [f'scene.objects.{name}.shape = "mesh-{name}"', f'scene.objects.{name}.material = "{material}"']
    sp = pyluxcore.Properties()
    sp.SetFromString("\n".join(props))
    scene.Parse(sp)
    cfg = pyluxcore.Properties()
    cfg.SetFromString("\n".join(luxcore_filter(r) + [
        'renderengine.type = "BIDIRVMCPU"',
        f"renderengine.seed = {seed}",
        'sampler.type = "RANDOM"',
        f"native.threads.count = {threads}",
        f"film.width = {width}",
        f"film.height = {height}",
        f"path.maxdepth = {r.get('max_depth', 10)}",
        f"light.maxdepth = {r.get('max_depth', 10)}",
        f"batch.halttime = {seconds}",
        'film.outputs.0.type = "RGB"',
        'film.outputs.0.filename = "unused.exr"',
    ]))
    return pyluxcore.RenderConfig(cfg, scene), width, height


def luxcore_render(desc, threads, seconds, seed):
    import pyluxcore

    config, width, height = luxcore_scene(desc, threads, seconds, seed)
    session = pyluxcore.RenderSession(config)
    t0 = time.time()
    session.Start()
    # LuxCore checks its halt conditions when its statistics are updated.
    while not session.HasDone():
        time.sleep(0.05)
        session.UpdateStats()
    session.Stop()
    wall = time.time() - t0
    buf = np.zeros(width * height * 3, dtype=np.float32)
    session.GetFilm().GetOutputFloat(pyluxcore.FilmOutputType.RGB, buf)
    # LuxCore's rows run from the bottom.
    return np.flipud(buf.reshape(height, width, 3)).astype(np.float64), wall


def caustic_render(binary, scene, threads, seconds, out, seed):
    t0 = time.time()
    subprocess.run([binary, "render", scene, "--integrator", "vcm", "--time", str(seconds), "--spp", "1000000",
                    "--threads", str(threads), "--seed", str(seed), "-q", "-o", out], check=True)
    return read_exr(out), time.time() - t0


# The references take another seed than the timed runs (seeds 1, 2, ...): a run that repeats the
# first samples of its own reference would share its noise and read too low an error.
REF_SEED = 7


def rel_rmse(img, ref):
    return float(np.sqrt(np.mean((img - ref) ** 2)) / max(np.mean(ref), 1e-12))


def rel_mse(img, ref):
    """Mean of (img - ref)^2 / (ref^2 + 0.01), the reference scaled to mean 0.18 first: the
    relative MSE of the denoising literature, which a few sub-pixel highlights (a small light
    seen in glass) do not dominate as they dominate the RMSE."""
    s = 0.18 / max(np.mean(ref), 1e-12)
    img, ref = img * s, ref * s
    return float(np.mean((img - ref) ** 2 / (ref**2 + 0.01)))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scene")
    ap.add_argument("--time", type=float, default=10.0)
    ap.add_argument("--ref-time", type=float, default=300.0)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--runs", type=int, default=1)
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    ap.add_argument("--caustic", default=os.path.join(root, "target", "release", "caustic"))
    ap.add_argument("--out", default="/tmp/luxcore-compare")
    ap.add_argument("--refs-only", action="store_true", help="render the cached references and stop")
    args = ap.parse_args()
    import pyluxcore

    pyluxcore.Init(lambda msg: None)
    os.makedirs(args.out, exist_ok=True)
    with open(args.scene, "rb") as f:
        desc = tomllib.load(f)
    stem = os.path.splitext(os.path.basename(args.scene))[0]
    lux_ref_path = os.path.join(args.out, f"{stem}-luxcore-ref-box-seed{REF_SEED}-{args.ref_time:g}s.npy")
    if not os.path.exists(lux_ref_path):
        ref, _ = luxcore_render(desc, args.threads, args.ref_time, REF_SEED)
        np.save(lux_ref_path, ref)
    lux_ref = np.load(lux_ref_path)
    caustic_ref_path = os.path.join(args.out, f"{stem}-caustic-ref-seed{REF_SEED}-{args.ref_time:g}s.exr")
    if not os.path.exists(caustic_ref_path):
        caustic_render(args.caustic, args.scene, args.threads, args.ref_time, caustic_ref_path, REF_SEED)
    caustic_ref = read_exr(caustic_ref_path)
    if args.refs_only:
        return
    load_before = open("/proc/loadavg").read().split()[:3]
    for run in range(args.runs):
        lux, lux_wall = luxcore_render(desc, args.threads, args.time, run + 1)
        ours, our_wall = caustic_render(args.caustic, args.scene, args.threads, args.time, os.path.join(args.out, f"{stem}-vcm.exr"), run + 1)
        print(f"{stem} run {run + 1}: LuxCore BIDIRVMCPU {rel_rmse(lux, lux_ref):.4f} / {rel_mse(lux, lux_ref):.5f} "
              f"({lux_wall:.1f} s), caustic vcm {rel_rmse(ours, caustic_ref):.4f} / {rel_mse(ours, caustic_ref):.5f} "
              f"({our_wall:.1f} s)  [relative RMSE / relative MSE against each one's {args.ref_time:g}-s render]")
    load_after = open("/proc/loadavg").read().split()[:3]
    print(f"load average before {' '.join(load_before)}, after {' '.join(load_after)}")


if __name__ == "__main__":
    main()
    sys.stdout.flush()
    # pyluxcore 2.11 crashes in its teardown at interpreter exit; the results are out by now.
    os._exit(0)
