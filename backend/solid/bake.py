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

from ..errors import SettingError
from ..sources import BoxGrid
from .model import SolidTextureModel, TextureCode

__all__ = ["srgb_to_linear", "grid_points", "bake_volume", "evaluate_grid"]

_F = np.float32


def srgb_to_linear(c: np.ndarray) -> np.ndarray:
    """sRGB-encoded values in [0, 1] -> scene-linear float32 (IEC 61966-2-1)."""
    c = np.clip(np.asarray(c, _F), 0.0, 1.0)
    return np.where(c <= 0.04045, c / 12.92, np.power((c + 0.055) / 1.055, 2.4)).astype(_F)


def grid_points(grid: BoxGrid, z0: int = 0, z1: int | None = None) -> np.ndarray:
    """Voxel/pixel centres of ``grid`` (slices z0..z1 of a volume) as float64 (N, 3), x fastest."""
    first, step = grid.first, grid.voxel
    nx, ny = int(grid.resolution[0]), int(grid.resolution[1])
    xs = first[0] + np.arange(nx) * step[0]
    ys = first[1] + np.arange(ny) * step[1]
    if grid.rank == 2:
        zs = np.array([first[2]])
    else:
        z1 = int(grid.resolution[2]) if z1 is None else z1
        zs = first[2] + np.arange(z0, z1) * step[2]
    z, y, x = np.meshgrid(zs, ys, xs, indexing="ij")
    return np.stack([x.ravel(), y.ravel(), z.ravel()], axis=1)


def evaluate_grid(model: SolidTextureModel, code: TextureCode, grid: BoxGrid, seed: int = 0, scale: float = 1.0,
                  progress=None, cancel=None) -> np.ndarray:
    """sRGB float32 (ny, nx, 3) or (nz, ny, nx, 3): the texture at the grid's centres times ``scale``
    (texture units per world unit).  A 2D model reads x, y only."""
    grid.validate()
    pts = grid_points(grid) * float(scale)
    if model.dim == 2:
        pts = pts[:, :2]
    prog = None if progress is None else (lambda d, n: progress(d / n))
    return model.evaluate(pts, code, seed, progress=prog, cancel=cancel).reshape(grid.shape + (3,))


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

    grid.validate()
    if grid.rank != 3:
        raise SettingError("resolution", "a volume needs three resolutions (nx, ny, nz)")
    if model.dim != 3:
        raise SettingError("model", f"model {model.name!r} is 2D; a volume needs a 3D model")
    src = SolidSource(model, seed=seed, scale=scale, density=density, code=code)
    run_bake(BakeSpec(name, src, grid, path, half=half), progress, cancel, force=True)
