"""gpurt: a Whitted ray tracer for NFF/SPD scenes, STL, OBJ, PLY and glTF models, into numpy.

    >>> import gpurt
    >>> img = gpurt.render("scenes/spheres.nff", width=320, height=240, spp=4)
    >>> img.shape, img.dtype
    ((240, 320, 3), dtype('float32'))

``render`` returns a :class:`gpurt.Image`: a float32 numpy array of shape (height, width,
3) with the linear values the command line's EXR of the same render holds, which shows
itself as a picture in Jupyter. :class:`gpurt.Scene` is a parsed scene (``info()``,
``render()``); :class:`gpurt.Renderer` renders many frames of one scene, uploaded once.
Scene errors raise :class:`gpurt.SceneError` (a ``ValueError``) whose message is the
command line's ``FILE:LINE:COL: message``.
"""

import os
from typing import List, Literal, Optional, Union

import numpy as np

from ._native import (
    Renderer,
    Scene,
    SceneError,
    __version__,
    info,
    png as _png,
    release,
    render,
    to_srgb8,
)

__all__ = [
    "Image",
    "Renderer",
    "Scene",
    "SceneError",
    "__version__",
    "info",
    "release",
    "render",
    "to_srgb8",
]


class Image(np.ndarray):
    """A rendered image: a float32 numpy array of shape (height, width, 3), linear RGB.

    It is an ordinary ndarray (a view of the render's own buffer, not a copy) that Jupyter
    shows as a picture through ``_repr_png_``: the PNG the command line writes for the
    same render. ``aov`` is the output it holds: None for colour, or "normal", "depth",
    "cost" (shown as grey and as a heat ramp, scaled to their largest value), "uv".
    """

    aov: Optional[Literal["color", "normal", "depth", "cost", "uv"]]

    def __array_finalize__(self, obj: object) -> None:
        # Views and results of arithmetic keep the AOV of the image they came from.
        self.aov = getattr(obj, "aov", None)

    def _repr_png_(self) -> Optional[bytes]:
        """The image as PNG bytes, for Jupyter; None when this is no longer an image."""
        if self.ndim != 3 or self.shape[2] != 3 or self.size == 0:
            return None
        return _png(np.asarray(self), self.aov)

    def to_srgb8(self) -> np.ndarray:
        """The 8-bit image of these values: see :func:`gpurt.to_srgb8`."""
        return to_srgb8(np.asarray(self))

    def save(self, path: "Union[str, os.PathLike[str]]") -> None:
        """Writes the image as the PNG the command line writes for the same render.

        Only ``.png`` is written (the command line's other formats, EXR among them, come
        from ``gpurt SCENE -o``); the file is written whole or not at all.
        """
        png = self._repr_png_()
        if png is None:
            raise ValueError("not an image of shape (height, width, 3)")
        target = os.fspath(path)
        if not target.lower().endswith(".png"):
            raise ValueError(f"{target}: Image.save writes PNG; give a path ending in .png")
        temp = f"{target}.{os.getpid()}.tmp"
        try:
            with open(temp, "wb") as f:
                f.write(png)
            os.replace(temp, target)
        finally:
            if os.path.exists(temp):
                os.remove(temp)


def __dir__() -> List[str]:
    """The public names only (not the modules and typing helpers this file imports)."""
    return sorted(__all__)
