"""Type stubs of gpurt's compiled module; the public names are re-exported by `gpurt`."""

import os
from typing import Any, Dict, List, Literal, Optional, Sequence, Tuple, TypedDict, Union, final

import numpy as np
import numpy.typing as npt

from . import Image

__all__ = ["__version__", "SceneError", "Scene", "Renderer", "render", "info", "to_srgb8", "png", "release", "_devices_opened"]

__version__: str

_Backend = Literal["auto", "gpu", "cpu"]
_Aov = Optional[Literal["color", "normal", "depth", "cost", "uv"]]
_Shading = Optional[Literal["phong", "blinn-phong"]]
_Ambient = Union[float, Sequence[float], None]
_PathLike = Union[str, "os.PathLike[str]"]

class _Camera(TypedDict, total=False):
    eye: Sequence[float]
    look_at: Sequence[float]
    up: Sequence[float]
    fov: float

class SceneError(ValueError):
    """A scene that cannot be read: its message is the command line's `FILE:LINE:COL: message`;
    `path`, `line`, `column` and `reason` hold its parts (`line` and `column` None where the
    fault has no place in the text, `offset` the byte of a binary STL's)."""

    path: str
    line: Optional[int]
    column: Optional[int]
    offset: Optional[int]
    reason: str

@final
class Scene:
    """A scene read from a file or a string: NFF (with the P3D dialect), STL, OBJ, PLY or glTF."""

    @staticmethod
    def open(path: _PathLike) -> "Scene":
        """Reads a scene file: NFF, STL, OBJ, PLY or glTF by its first bytes or its extension, gzip too."""
    @staticmethod
    def from_string(
        text: Union[str, bytes], format: Literal["nff", "p3d", "stl", "obj", "ply", "gltf"] = "nff", name: str = "<string>"
    ) -> "Scene":
        """Reads a scene from a string (or bytes, for binary STL)."""
    def info(self) -> Dict[str, Any]:
        """What the scene holds, as the dict `gpurt info --json` prints."""
    @property
    def name(self) -> str:
        """The name the scene's messages use."""
    @property
    def warnings(self) -> List[str]:
        """The reader's warnings, each naming its line."""
    def render(
        self,
        *,
        width: Optional[int] = None,
        height: Optional[int] = None,
        spp: Optional[int] = None,
        depth: Optional[int] = None,
        ambient: _Ambient = None,
        backend: _Backend = "auto",
        shading: _Shading = None,
        aov: _Aov = None,
        time: Optional[float] = None,
    ) -> Image:
        """Renders the scene from its own camera: see `gpurt.render`."""
    @property
    def time_range(self) -> Optional[Tuple[float, float, int]]:
        """`(start, end, frames)` of a scene that moves (AFF); None otherwise."""
    def frame_time(self, frame: int) -> float:
        """The time of frame `frame` (from 0) of the animation."""
    def at(self, time: float) -> "Scene":
        """The scene as it is at `time`: still, for `gpurt.Renderer`."""

@final
class Renderer:
    """A session for many frames of one scene, read, packed and uploaded once."""

    def __new__(
        cls,
        scene: Union[_PathLike, Scene],
        *,
        width: Optional[int] = None,
        height: Optional[int] = None,
        spp: Optional[int] = None,
        depth: Optional[int] = None,
        ambient: _Ambient = None,
        backend: _Backend = "auto",
        shading: _Shading = None,
    ) -> "Renderer":
        """Reads (when `scene` is a path) and packs the scene for frames of this size."""
    def render(
        self,
        *,
        spp: Optional[int] = None,
        depth: Optional[int] = None,
        ambient: _Ambient = None,
        aov: _Aov = None,
        shading: _Shading = None,
        camera: Optional[_Camera] = None,
    ) -> Image:
        """Traces one frame, from the scene's camera or `camera`."""
    @property
    def backend(self) -> Literal["gpu", "cpu"]:
        """Where this renderer traces."""
    @property
    def device(self) -> str:
        """The adapter, or the CPU and its threads."""
    @property
    def scene_uploads(self) -> Optional[int]:
        """How many times the scene went to the GPU; None on the CPU."""
    @property
    def frames_rendered(self) -> int:
        """How many frames this renderer has traced."""
    @property
    def rays(self) -> int:
        """Rays the last frame traced, as `gpurt --stats` counts them."""
    @property
    def size(self) -> Tuple[int, int]:
        """(width, height) of the frames."""

def render(
    scene: Union[_PathLike, Scene],
    *,
    width: Optional[int] = None,
    height: Optional[int] = None,
    spp: Optional[int] = None,
    depth: Optional[int] = None,
    ambient: _Ambient = None,
    backend: _Backend = "auto",
    shading: _Shading = None,
    aov: _Aov = None,
    time: Optional[float] = None,
) -> Image:
    """Renders a scene into a float32 (height, width, 3) array of linear values."""

def info(path: _PathLike) -> Dict[str, Any]:
    """`Scene.open(path).info()`."""

def to_srgb8(array: npt.ArrayLike) -> npt.NDArray[np.uint8]:
    """The 8-bit image the command line writes as PNG for these linear values."""

def png(array: npt.ArrayLike, aov: _Aov = None) -> bytes:
    """The PNG file the command line writes for these values and AOV."""

def release() -> None:
    """Drops the GPU device `render` keeps between calls (and the scene it holds); the next render opens one again."""

def _devices_opened() -> int:
    """GPU devices `render` has opened in this process."""
