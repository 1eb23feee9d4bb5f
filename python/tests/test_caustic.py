"""The Python package against the command line: the same images pixel for pixel, exact shard
merges, errors that carry their place, Ctrl-C, threads, defines, the display server."""

from __future__ import annotations

import os
import signal
import socket
import struct
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import caustic

ROOT = Path(__file__).resolve().parents[2]
BOX = ROOT / "scenes" / "13-cornell-caustics.toml"
MITSUBA_BOX = ROOT / "scenes" / "mitsuba" / "cornell-box.xml"
# Small renders: the comparisons are exact, so a few samples prove as much as many.
SMALL = dict(width=40, height=30)


def command_line(*args: str) -> subprocess.CompletedProcess:
    """Runs the command line: the `caustic` binary named by CAUSTIC_BIN (CI gives the one cargo
    built), or else the package's own `python -m caustic`."""
    binary = os.environ.get("CAUSTIC_BIN")
    prefix = [binary] if binary else [sys.executable, "-m", "caustic"]
    return subprocess.run([*prefix, *args], capture_output=True, text=True, timeout=300)


def cli_render(tmp_path: Path, scene: Path, *args: str, name: str = "cli.exr") -> Path:
    out = tmp_path / name
    run = command_line("render", str(scene), "-o", str(out), "-q", *args)
    assert run.returncode == 0, run.stderr
    return out


@pytest.mark.parametrize(
    "integrator, extra",
    [
        ("whitted", {}),
        ("path", {"max_depth": 4}),
        ("photon", {"photons": 20000, "caustic_photons": 20000, "gather": 4}),
        ("sppm", {"photons_per_iter": 5000}),
        ("light", {}),
    ],
)
def test_render_equals_the_command_lines_exr_pixel_for_pixel(tmp_path, integrator, extra):
    scene = caustic.load_file(BOX)
    image = caustic.render(scene, spp=3, seed=7, integrator=integrator, **SMALL, **extra)
    assert image.shape == (30, 40, 3) and image.dtype == np.float32
    assert image.mean() > 0
    flags = [f"--{k.replace('_', '-')}={v}" for k, v in {**SMALL, **extra}.items()]
    out = cli_render(tmp_path, BOX, "--spp=3", "--seed=7", f"--integrator={integrator}", *flags)
    np.testing.assert_array_equal(image, caustic.read(out))


def test_layers_equal_the_command_lines_layer_files(tmp_path):
    scene = caustic.load_file(BOX)
    images = caustic.render(scene, spp=2, integrator="path", layers=True, **SMALL)
    assert set(images) == {"image", *caustic.LAYERS}
    out = cli_render(tmp_path, BOX, "--spp=2", "--integrator=path", "--layers", "--width=40", "--height=30")
    np.testing.assert_array_equal(images["image"], caustic.read(out))
    for layer in caustic.LAYERS:
        np.testing.assert_array_equal(images[layer], caustic.read(tmp_path / f"cli.{layer}.exr"), err_msg=layer)


def test_defines_override_the_scenes_defaults_as_dash_d_does(tmp_path):
    default = caustic.load_file(MITSUBA_BOX)
    assert (default.width, default.height) == (400, 400)
    scene = caustic.load_file(MITSUBA_BOX, spp=2, res=24)
    assert (scene.width, scene.height) == (24, 24)
    image = caustic.render(scene)
    out = cli_render(tmp_path, MITSUBA_BOX, "-D", "spp=2", "-D", "res=24")
    np.testing.assert_array_equal(image, caustic.read(out))
    with pytest.raises(caustic.SceneError, match="rse"):
        caustic.load_file(MITSUBA_BOX, rse=24)


def test_set_replaces_scene_keys_as_dash_dash_set_does(tmp_path):
    toml = os.path.join(ROOT, "scenes", "11-cornell-area.toml")
    scene = caustic.load_file(toml, set={"render.width": 20, "render.height": 16, "render.spp": 2})
    assert (scene.width, scene.height) == (20, 16)
    image = caustic.render(scene)
    out = cli_render(tmp_path, toml, "--set", "render.width=20", "--set", "render.height=16", "--set", "render.spp=2")
    np.testing.assert_array_equal(image, caustic.read(out))
    with pytest.raises(caustic.SceneError, match="widht"):
        caustic.load_file(toml, set={"render.widht": 20})


def test_load_string_errors_carry_file_line_and_column(tmp_path):
    toml = '[camera]\neye = [0, 0, 5]\nlook_at = [0, 0, 0]\n\n[[objects]]\ntype = "sphere"\nradius = -1\n'
    with pytest.raises(caustic.SceneError) as e:
        caustic.load_string(toml, format="toml", name="mine.toml")
    assert (e.value.file, e.value.line, e.value.column) == ("mine.toml", 7, 10)
    assert "radius = -1" in str(e.value) and str(e.value).startswith("mine.toml:7:10: ")
    assert e.value.message in str(e.value)

    xml = '<scene version="3.0.0">\n  <shape type="sphere">\n    <float name="radius" value="oops"/>\n  </shape>\n</scene>\n'
    with pytest.raises(caustic.SceneError) as e:
        caustic.load_string(xml)
    assert (e.value.file, e.value.line) == ("<string>", 3)
    assert e.value.column >= 5

    # The same text in a file: the command line prints the same message after "error: ".
    path = tmp_path / "mine.toml"
    path.write_text(toml)
    with pytest.raises(caustic.SceneError) as e:
        caustic.load_file(path)
    assert (e.value.file, e.value.line, e.value.column) == (str(path), 7, 10)
    run = command_line("render", str(path), "-o", str(tmp_path / "x.png"))
    assert run.returncode == 1
    assert f"error: {e.value}" in run.stderr

    with pytest.raises(caustic.SceneError) as e:
        caustic.load_file(tmp_path / "missing.toml")
    assert e.value.line is None and "missing.toml" in e.value.file


def test_shards_merged_equal_one_render_bit_for_bit(tmp_path):
    scene = caustic.load_file(BOX)
    for integrator, extra in [("path", {}), ("photon", {"photons": 10000, "caustic_photons": 10000, "gather": 2})]:
        whole = caustic.render(scene, spp=7, integrator=integrator, layers=True, **SMALL, **extra)
        parts = [
            caustic.render_shard(scene, i, 3, tmp_path / f"{integrator}-{i}.exr", spp=7, integrator=integrator,
                                 layers=True, **SMALL, **extra)
            for i in range(3)
        ]
        merged = caustic.merge(parts)
        assert set(merged) == set(whole)
        for k in whole:
            np.testing.assert_array_equal(merged[k], whole[k], err_msg=f"{integrator} {k}")
        # The command line's merge reads the same parts.
        out = tmp_path / f"{integrator}-merged.exr"
        assert command_line("merge", *parts, "-o", str(out), "-q").returncode == 0
        np.testing.assert_array_equal(caustic.read(out), whole["image"])
    with pytest.raises(caustic.CausticError, match="missing samples"):
        caustic.merge([tmp_path / "path-0.exr", tmp_path / "path-2.exr"])


def test_keyboard_interrupt_stops_a_long_render_within_two_seconds():
    scene = caustic.load_file(BOX)
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    sent = []

    def interrupt():
        time.sleep(1.5)
        sent.append(time.monotonic())
        os.kill(os.getpid(), signal.SIGINT)

    timer = threading.Thread(target=interrupt)
    try:
        timer.start()
        start = time.monotonic()
        with pytest.raises(KeyboardInterrupt):
            caustic.render(scene, time=60, integrator="path", progress=False)
        stopped = time.monotonic()
    finally:
        timer.join()
        signal.signal(signal.SIGINT, previous)
    assert sent, "the render ended before it was interrupted"
    assert stopped - sent[0] < 2.0, f"took {stopped - sent[0]:.2f} s to stop"
    assert stopped - start < 10


def test_renders_in_two_threads_run_at_once_and_leave_the_gil_free():
    scene = caustic.load_file(BOX)
    results = {}

    def work(me):
        # One worker each, one to two seconds of rendering each.
        results[me] = caustic.render(scene, spp=192, integrator="path", threads=1, progress=False, **SMALL)

    threads = [threading.Thread(target=work, args=(me,)) for me in "ab"]
    for t in threads:
        t.start()
    # While both render, this thread runs Python: it could not if either held the GIL.
    spins = 0
    while any(t.is_alive() for t in threads):
        spins += 1
    for t in threads:
        t.join()
    assert set(results) == {"a", "b"}
    np.testing.assert_array_equal(results["a"], results["b"])
    np.testing.assert_array_equal(results["a"], caustic.render(scene, spp=192, integrator="path", **SMALL))
    assert spins > 30_000, f"the main thread ran {spins} loops during the renders"


def test_unknown_options_are_type_errors_naming_the_nearest():
    scene = caustic.load_file(BOX)
    with pytest.raises(TypeError, match="'sp'; did you mean 'spp'"):
        caustic.render(scene, sp=4)
    with pytest.raises(TypeError, match="did you mean 'caustic_photons'"):
        caustic.render(scene, caustic_photon=4)
    with pytest.raises(TypeError, match="did you mean antialias=False"):
        caustic.render(scene, no_antialias=True)
    with pytest.raises(ValueError, match="option adc_bailout: expected a number from 0 to 1"):
        caustic.render(scene, adc_bailout=2)
    with pytest.raises(ValueError, match="option spp"):
        caustic.render(scene, spp=-1)
    with pytest.raises(ValueError, match="option integrator"):
        caustic.render(scene, integrator="mlt")
    assert "display_server" in caustic.OPTIONS and "photons" in caustic.OPTIONS


def test_options_given_as_numpy_scalars_and_ints_for_floats():
    scene = caustic.load_file(BOX)
    a = caustic.render(scene, spp=np.int64(2), max_radius=1, integrator="photon", photons=5000, gather=0, **SMALL)
    b = caustic.render(scene, spp=2, max_radius=1.0, integrator="photon", photons=5000, gather=0, **SMALL)
    np.testing.assert_array_equal(a, b)


def test_progress_callback_sees_the_work_grow_to_its_total():
    scene = caustic.load_file(BOX)
    seen = []
    caustic.render(scene, spp=4, integrator="path", progress=lambda d, t: seen.append((d, t)), **SMALL)
    assert seen and seen[-1][0] == seen[-1][1] == 40 * 30 * 4
    assert all(a[0] <= b[0] for a, b in zip(seen, seen[1:]))


def test_write_and_read(tmp_path):
    image = np.random.default_rng(1).random((5, 7, 3), dtype=np.float32) * 3
    caustic.write(tmp_path / "a.exr", image)
    np.testing.assert_array_equal(caustic.read(tmp_path / "a.exr"), image)
    caustic.write(tmp_path / "a.png", image)
    assert (tmp_path / "a.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    caustic.write(tmp_path / "g.exr", image[:, :, 0])
    np.testing.assert_array_equal(caustic.read(tmp_path / "g.exr")[:, :, 2], image[:, :, 0])
    with pytest.raises(caustic.CausticError, match="unsupported extension"):
        caustic.write(tmp_path / "a.jpg", image)
    with pytest.raises(ValueError):
        caustic.write(tmp_path / "b.exr", np.zeros((2, 2, 4)))


def test_python_dash_m_caustic_is_the_command_line(tmp_path):
    run = subprocess.run([sys.executable, "-m", "caustic", "render", "--help"], capture_output=True, text=True)
    assert run.returncode == 0 and "--display-server" in run.stdout
    run = subprocess.run([sys.executable, "-m", "caustic", "render", "--spp"], capture_output=True, text=True)
    assert run.returncode == 2 and "error" in run.stderr
    out = tmp_path / "m.exr"
    run = subprocess.run([sys.executable, "-m", "caustic", "render", str(BOX), "--spp=1", "--width=16", "--height=12",
                          "--integrator=path", "-q", "-o", str(out)], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    scene = caustic.load_file(BOX)
    np.testing.assert_array_equal(caustic.read(out), caustic.render(scene, spp=1, width=16, height=12, integrator="path"))


def read_tev_messages(conn: socket.socket) -> list:
    """Every message a renderer sent until it closed the connection, read by tev's framing:
    a little-endian u32 length (counting itself), then the message."""
    data = b""
    while chunk := conn.recv(1 << 16):
        data += chunk
    messages, at = [], 0
    while at < len(data):
        (length,) = struct.unpack_from("<I", data, at)
        messages.append(data[at + 4:at + length])
        at += length
    assert at == len(data)
    return messages


def c_string(data: bytes, at: int):
    end = data.index(b"\0", at)
    return data[at:end].decode(), end + 1


def test_display_server_from_python_receives_the_returned_image():
    listener = socket.socket()
    listener.bind(("127.0.0.1", 0))
    listener.listen(1)
    # Never waits forever: a render that did not connect fails the test below.
    listener.settimeout(60)
    got = {}

    def serve():
        conn, _ = listener.accept()
        with conn:
            got["messages"] = read_tev_messages(conn)

    server = threading.Thread(target=serve, daemon=True)
    server.start()
    address = "%s:%d" % listener.getsockname()
    scene = caustic.load_file(BOX)
    image = caustic.render(scene, spp=2, integrator="path", display_server=address, **SMALL)
    server.join(timeout=30)
    listener.close()
    assert "messages" in got, "the viewer received nothing"
    messages = got["messages"]
    # Create (type 4): focus, name, width, height, channels, channel names.
    assert messages[0][0] == 4
    name, at = c_string(messages[0], 2)
    assert name == str(BOX)
    assert struct.unpack_from("<3i", messages[0], at) == (40, 30, 3)
    # The last update (type 5): focus, name, channel count and names, rectangle, planes.
    last = messages[-1]
    assert last[0] == 5 and len(messages) >= 2
    at = c_string(last, 2)[1]
    (n,) = struct.unpack_from("<i", last, at)
    at += 4
    for _ in range(n):
        at = c_string(last, at)[1]
    assert struct.unpack_from("<4i", last, at) == (0, 0, 40, 30)
    planes = np.frombuffer(last[at + 16:], dtype="<f4").reshape(3, 30, 40)
    np.testing.assert_array_equal(np.moveaxis(planes, 0, 2), image)


def test_scene_properties():
    scene = caustic.load_file(BOX)
    assert scene.name == str(BOX) and scene.integrator == "photon"
    assert scene.files[0] == BOX and "400x400" in repr(scene)
