"""caustic from Python: load scenes, render them to numpy arrays, split renders into shards and
merge them exactly, write PNG and OpenEXR files, and run the command line.

    >>> import caustic
    >>> scene = caustic.load_file("scenes/13-cornell-caustics.toml")
    >>> image = caustic.render(scene, spp=16, integrator="sppm")   # (H, W, 3) float32, linear
    >>> caustic.write("box.png", image)

Render options have the command line's names (``--spp-axis`` is ``spp_axis=``, ``--no-antialias``
is ``antialias=False``; ``caustic.OPTIONS`` lists them) and give the same image: a render from
Python equals ``caustic render`` with the same options pixel for pixel. Rendering releases the
GIL, so renders in several threads run at once, and Ctrl-C stops a render promptly with
``KeyboardInterrupt``.
"""

from __future__ import annotations

import os
import sys
import time as _time
import warnings
from typing import Any, Callable, Dict, Iterable, Mapping, Optional, Sequence, Union

import numpy as np

from . import _native
from ._native import CausticError, Scene, SceneError

__all__ = [
    "CausticError",
    "CausticWarning",
    "LAYERS",
    "OPTIONS",
    "Scene",
    "SceneError",
    "load_file",
    "load_string",
    "main",
    "merge",
    "read",
    "render",
    "render_shard",
    "write",
]

__version__: str = _native.__version__

#: The render options ``render`` and ``render_shard`` take as keywords (the command line's
#: options, with ``_`` for ``-``).
OPTIONS: tuple = tuple(_native.OPTIONS)

#: The parts of an image that ``layers=True`` returns beside it; they add up to the image.
LAYERS: tuple = ("direct", "specular", "caustic", "indirect")

PathLike = Union[str, "os.PathLike[str]"]
Images = Union[np.ndarray, Dict[str, np.ndarray]]
Progress = Union[None, bool, Callable[[int, int], Any]]


class CausticWarning(UserWarning):
    """What a loader could not render exactly (an unsupported Mitsuba plugin, say)."""


def _define(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    return str(value)


def _defines(defines: Dict[str, Any]) -> list:
    return [(k, _define(v)) for k, v in defines.items()]


def _warn(scene: Scene) -> Scene:
    for w in scene.warnings:
        warnings.warn(w, CausticWarning, stacklevel=3)
    return scene


def load_file(
    path: PathLike,
    *,
    strict: bool = False,
    max_memory: Optional[int] = None,
    set: Optional[Mapping[str, Any]] = None,
    **defines: Any,
) -> Scene:
    """Read a scene file: caustic's TOML format, or Mitsuba 3 XML for ``.xml``.

    Keywords other than these set the scene's ``$name`` parameters, as ``-D name=value`` does on
    the command line (they win over the file's ``<default>`` or ``[parameters]``; a name the scene
    does not use is an error). ``set`` maps key paths to values as ``--set KEY=VALUE`` does
    (``set={"render.spp": 4, "materials.glass.ior": 1.6}``). ``strict=True`` makes every
    unsupported part of a Mitsuba scene an error; ``max_memory`` (MiB) stops a load that would need
    more (default: half of the machine's).

    Raises ``SceneError`` (with ``file``, ``line``, ``column`` and ``message``) for a scene that
    cannot be read; warnings about parts rendered approximately are ``CausticWarning``\\ s.
    """
    return _warn(_native.load_file(os.fspath(path), _defines(defines), strict, max_memory, _defines(set or {})))


def load_string(
    text: str,
    format: str = "mitsuba",
    base: PathLike = ".",
    *,
    name: Optional[str] = None,
    strict: bool = False,
    max_memory: Optional[int] = None,
    set: Optional[Mapping[str, Any]] = None,
    **defines: Any,
) -> Scene:
    """Read a scene from ``text``: ``format`` is ``"mitsuba"`` (XML) or ``"toml"``.

    Files the scene names (meshes, textures, includes) are read relative to ``base``; ``name``
    (default ``"<string>"``) stands for the file in error messages. Other keywords are as in
    ``load_file``.
    """
    label = name if name is not None else "<string>"
    scene = _native.load_string(
        text, format, label, os.fspath(base), _defines(defines), strict, max_memory, _defines(set or {})
    )
    return _warn(scene)


def _in_notebook() -> bool:
    shell = sys.modules.get("IPython")
    if shell is None:
        return False
    ip = getattr(shell, "get_ipython", lambda: None)()
    return ip is not None and type(ip).__name__ == "ZMQInteractiveShell"


class _Bar:
    """A tqdm bar fed with the render's (done, total) work, or the time used of a budget."""

    def __init__(self, budget: Optional[float]):
        from tqdm.auto import tqdm

        self.bar = tqdm(total=1000, desc="render", unit="‰", leave=False, bar_format="{l_bar}{bar}| {elapsed}<{remaining}")
        self.budget = budget
        self.start = _time.monotonic()

    def __call__(self, done: int, total: int) -> None:
        fractions = []
        if total > 0:
            fractions.append(done / total)
        if self.budget:
            fractions.append((_time.monotonic() - self.start) / self.budget)
        if fractions:
            self.bar.n = int(1000 * min(1.0, max(fractions)))
            self.bar.refresh()

    def close(self) -> None:
        self.bar.close()


def _progress(progress: Progress, budget: Optional[float]):
    """The callback for ``progress``: a callable as it is, True for a tqdm bar, None for a bar
    when tqdm is installed and output goes to a terminal or a notebook."""
    if progress is False:
        return None
    if callable(progress):
        return progress
    if progress is None:
        try:
            import tqdm  # noqa: F401
        except ImportError:
            return None
        if not (sys.stderr.isatty() or _in_notebook()):
            return None
    elif progress is not True:
        raise TypeError(f"progress must be None, True, False or a callable(done, total), not {progress!r}")
    return _Bar(budget)


def _array(width: int, height: int, data: bytearray) -> np.ndarray:
    return np.frombuffer(data, dtype=np.float32).reshape(height, width, 3)


def _images(out: dict, layers: bool) -> Images:
    arrays = {name: _array(*v) for name, v in out.items()}
    return arrays if layers else arrays["image"]


def _run(scene: Scene, options: dict, time: Optional[float], threads: Optional[int], layers: bool,
         max_memory: Optional[int], progress: Progress, output: Optional[str], shard: Optional[str]):
    callback = _progress(progress, time)
    try:
        return _native.render(scene, options, time, threads, layers, max_memory, callback, output, shard)
    finally:
        if isinstance(callback, _Bar):
            callback.close()


def _with(options: dict, **given: Any) -> dict:
    for k, v in given.items():
        if v is not None:
            options[k] = v
    return options


def render(
    scene: Scene,
    spp: Optional[int] = None,
    time: Optional[float] = None,
    seed: Optional[int] = None,
    integrator: Optional[str] = None,
    threads: Optional[int] = None,
    layers: bool = False,
    *,
    progress: Progress = None,
    max_memory: Optional[int] = None,
    **options: Any,
) -> Images:
    """Render ``scene`` and return the image as an ``(H, W, 3)`` float32 array of linear RGB.

    ``spp``: samples per pixel; ``time``: seconds to render for (with ``spp``, whichever ends
    first); ``seed``: the seed of all sampling (the same seed gives the same image on any thread
    count); ``integrator``: ``"whitted"``, ``"path"``, ``"photon"``, ``"sppm"`` or ``"light"``;
    ``threads``: worker threads (default: all cores). Left at None, each is the scene's.
    Other keywords are the command line's options (``caustic.OPTIONS``), e.g. ``width=320``,
    ``max_depth=4``, ``photons=200_000``, ``display_server="127.0.0.1:14158"`` to watch the render
    in tev. With ``layers=True`` the result is a dict: ``"image"`` and the ``caustic.LAYERS``.

    ``progress``: a callable receiving (work done, work in all) a few times a second, True for a
    tqdm bar, False for nothing; by default a bar when tqdm is installed and stderr is a terminal
    or a notebook. The GIL is released while rendering; Ctrl-C raises ``KeyboardInterrupt``.
    """
    options = _with(dict(options), spp=spp, seed=seed, integrator=integrator)
    out = _run(scene, options, time, threads, layers, max_memory, progress, None, None)
    return _images(out, layers)


def render_shard(
    scene: Scene,
    index: Union[int, str],
    count: int,
    output: PathLike,
    spp: Optional[int] = None,
    seed: Optional[int] = None,
    integrator: Optional[str] = None,
    threads: Optional[int] = None,
    layers: bool = False,
    *,
    progress: Progress = None,
    max_memory: Optional[int] = None,
    **options: Any,
) -> str:
    """Render shard ``index`` of ``count`` (counting from 0; ``"auto"`` reads it from the
    scheduler's environment) of the samples to the partial image ``output`` (``.exr``), as
    ``caustic render --shard index/count -o output`` does, and return its path.

    ``merge`` (or ``caustic merge``) adds the parts of all shards into the image one ``render``
    with the same options would make, bit for bit (for SPPM, as independent runs). A shard run
    again resumes from the samples its partial image holds. Options are as in ``render``.
    """
    options = _with(dict(options), spp=spp, seed=seed, integrator=integrator)
    path = os.fspath(output)
    _run(scene, options, None, threads, layers, max_memory, progress, path, f"{index}/{count}")
    return path


def merge(parts: Iterable[PathLike], *, allow_partial: bool = False) -> Images:
    """Add the partial images of a render's shards (``render_shard``, ``caustic render --shard``)
    into its image: an array, or a dict with the layers when the shards were rendered with
    ``layers=True``. Parts of different renders, overlapping parts and missing samples are
    refused (``CausticError``) unless ``allow_partial``.
    """
    out = _native.merge([os.fspath(p) for p in parts], allow_partial)
    return _images(out, layers=len(out) > 1)


def write(path: PathLike, image: np.ndarray) -> None:
    """Write an ``(H, W, 3)`` (or ``(H, W)`` grey) linear image: ``.png`` as 8-bit sRGB (clamped
    to [0, 1]), ``.exr`` as 32-bit float. The file is written whole or not at all."""
    a = np.asarray(image, dtype=np.float32)
    if a.ndim == 2:
        a = np.repeat(a[:, :, None], 3, axis=2)
    if a.ndim != 3 or a.shape[2] != 3:
        raise ValueError(f"expected an (H, W, 3) or (H, W) image, got shape {a.shape}")
    height, width = a.shape[:2]
    _native.write(os.fspath(path), width, height, np.ascontiguousarray(a).tobytes())


def read(path: PathLike) -> np.ndarray:
    """Read an OpenEXR image (such as ``caustic render -o out.exr`` writes) as an ``(H, W, 3)``
    float32 array."""
    return _array(*_native.read(os.fspath(path)))


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run the command line with ``argv`` (default: ``sys.argv[1:]``) and return its exit status;
    ``python -m caustic render scene.toml -o out.png`` is ``caustic render scene.toml -o out.png``.
    """
    args = list(sys.argv[1:] if argv is None else argv)
    return _native.main(["caustic", *args])


def _console() -> None:
    sys.exit(main())
