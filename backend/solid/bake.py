"""Solid textures into files: images, volumes and point colours (Henzler et al. 2020 at run time).

The decoder outputs sRGB-encoded colours (it was trained against the
exemplar's file values).  Float outputs (EXR, VDB, .npy, colour attributes)
are scene-linear, so :func:`srgb_to_linear` converts them; 8-bit PNGs keep
the sRGB values.

    grid = BoxGrid((128, 128, 128), ((-1, -1, -1), (1, 1, 1)))
    bake_volume(model, code, grid, "out/gravel.vdb", seed=0, scale=1.0)   # color (vec3) + density grids

Volumes go through the bake pipeline (:class:`backend.sources.SolidSource`), as
job files do.
"""
from __future__ import annotations

import numpy as np

from ..colour import srgb_to_linear
from ..errors import SettingError
from ..sources import BoxGrid
from .model import SolidTextureModel, TextureCode

__all__ = ["srgb_to_linear", "bake_volume"]

_F = np.float32


def bake_volume(model: SolidTextureModel, code: TextureCode, grid: BoxGrid, path: str, seed: int = 0,
                scale: float = 1.0, density: float = 1.0, half: bool = False, progress=None, cancel=None,
                name: str = "solid") -> None:
    """A 3D model's colours over ``grid`` into an OpenVDB file through the bake pipeline
    (:func:`backend.bake.run_bake`): ``color`` (vec3, scene-linear) and ``density`` (constant), slab by
    slab, written atomically with the bake's key.

    ``progress(fraction)``; ``cancel()`` returning True raises Cancelled and writes nothing.
    """
    from ..bake import BakeSpec, run_bake
    from ..sources import SolidSource
    from .request import SolidRequest

    grid.validate()
    if grid.rank != 3:
        raise SettingError("resolution", "a volume needs three resolutions (nx, ny, nz)")
    if model.dim != 3:
        raise SettingError("model", f"model {model.name!r} is 2D; a volume needs a 3D model")
    src = SolidSource(model, SolidRequest(seed=seed), scale, density, code)
    run_bake(BakeSpec(name, src, grid, path, half=half), progress, cancel, force=True)
