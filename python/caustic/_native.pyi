"""Type stubs of caustic._native, the Rust half of the package (python/src/lib.rs). Use the
functions of ``caustic`` itself: they wrap these with their Python signatures and numpy arrays."""

from os import PathLike
from pathlib import Path
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple, Union

_Path = Union[str, PathLike[str]]
# (width, height, pixels): the pixels are native-endian float32 RGB, row by row.
_Buffer = Tuple[int, int, bytearray]

__version__: str
#: The render options, in the order of ``caustic::options::Options``.
OPTIONS: List[str]

class CausticError(Exception):
    """An error caustic reports (as the command line would)."""

class SceneError(CausticError):
    """A scene that cannot be loaded or built."""

    file: Optional[str]
    line: Optional[int]
    column: Optional[int]
    message: str

class Scene:
    """A scene as read, before options are applied."""

    @property
    def name(self) -> str: ...
    @property
    def width(self) -> int: ...
    @property
    def height(self) -> int: ...
    @property
    def integrator(self) -> str: ...
    @property
    def files(self) -> List[Path]: ...
    @property
    def warnings(self) -> List[str]: ...

def load_file(
    path: _Path,
    defines: Sequence[Tuple[str, str]],
    strict: bool = False,
    max_memory: Optional[int] = None,
    sets: Sequence[Tuple[str, str]] = ...,
) -> Scene: ...
def load_string(
    text: str,
    format: str,
    name: str,
    base: _Path,
    defines: Sequence[Tuple[str, str]],
    strict: bool = False,
    max_memory: Optional[int] = None,
    sets: Sequence[Tuple[str, str]] = ...,
) -> Scene: ...
def render(
    scene: Scene,
    options: Dict[str, Any],
    time: Optional[float] = None,
    threads: Optional[int] = None,
    layers: bool = False,
    max_memory: Optional[int] = None,
    progress: Optional[Callable[[int, int], Any]] = None,
    output: Optional[_Path] = None,
    shard: Optional[str] = None,
) -> Optional[Dict[str, _Buffer]]: ...
def merge(parts: Sequence[_Path], allow_partial: bool = False) -> Dict[str, _Buffer]: ...
def write(path: _Path, width: int, height: int, pixels: bytes) -> None: ...
def read(path: _Path) -> _Buffer: ...
def main(argv: Sequence[str]) -> int: ...
