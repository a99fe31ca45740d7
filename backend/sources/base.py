"""What every bake source shares: the voxel-centred :class:`BoxGrid`, the :class:`Source` protocol, the points of
a grid block and the check of a job table's keys.

Grids are voxel-centred: a :class:`BoxGrid` with ``resolution`` (nx, ny[, nz]) over world ``bounds`` puts sample
(i, j, k) at ``lo + (i + 1/2, j + 1/2, k + 1/2) * voxel``, which is where OpenVDB puts voxel centres under a linear
transform with that voxel size and translation ``lo + voxel / 2``.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Protocol

import numpy as np

from .. import limits
from ..errors import SettingError
from ..paths import in_job

__all__ = ["BoxGrid", "Source", "grid_points", "check_keys", "job_image"]


@dataclass(frozen=True)
class BoxGrid:
    """A voxel-centred grid.

    resolution  (nx, ny) for images or (nx, ny, nz) for volumes, x first
    bounds      ((x0, y0, z0), (x1, y1, z1)) world box; an image lies in the plane z = z0
    """

    resolution: tuple
    bounds: tuple = ((0.0, 0.0, 0.0), (1.0, 1.0, 1.0))

    def validate(self) -> "BoxGrid":
        res = tuple(self.resolution)
        if len(res) not in (2, 3) or any(int(n) != n or n < 1 for n in res):
            raise SettingError("resolution", f"expected 2 or 3 positive whole numbers, got {list(res)}")
        lo, hi = (np.asarray(b, np.float64) for b in self.bounds)
        if lo.shape != (3,) or hi.shape != (3,):
            raise SettingError("bounds", f"expected [[x0, y0, z0], [x1, y1, z1]], got {self.bounds}")
        n = len(res)
        if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))):
            raise SettingError("bounds", f"must be finite numbers, got {self.bounds}")
        if max(np.abs(lo).max(), np.abs(hi).max()) > limits.MAX_COORD:
            raise SettingError("bounds", f"coordinates must lie within +-{limits.MAX_COORD:g} units, got {self.bounds}")
        if not np.all(hi[:n] > lo[:n]):
            raise SettingError("bounds", f"max must exceed min on x, y{', z' if n == 3 else ''}: {self.bounds}")
        if not np.all(hi[:n] - lo[:n] >= limits.MIN_LENGTH):
            raise SettingError("bounds", f"the box must be at least {limits.MIN_LENGTH:g} units wide on x, "
                                         f"y{', z' if n == 3 else ''}: {self.bounds}")
        if np.prod(np.asarray(res, np.float64)) > 2 ** 34:
            raise SettingError("resolution", f"{list(res)} is more than 2^34 voxels")
        return self

    @property
    def rank(self) -> int:
        return len(self.resolution)

    @property
    def shape(self) -> tuple:
        """Array shape: (ny, nx) or (nz, ny, nx)."""
        return tuple(int(n) for n in reversed(self.resolution))

    @property
    def voxel(self) -> np.ndarray:
        """float64 (rank,): spacing along x, y[, z]."""
        lo, hi = (np.asarray(b, np.float64) for b in self.bounds)
        n = np.asarray(self.resolution, np.float64)
        return (hi[: self.rank] - lo[: self.rank]) / n

    @property
    def first(self) -> np.ndarray:
        """float64 (3,): world position of sample 0 (the first voxel's centre)."""
        p = np.asarray(self.bounds[0], np.float64).copy()
        p[: self.rank] += 0.5 * self.voxel
        return p

    def to_dict(self) -> dict:
        return dict(resolution=[int(n) for n in self.resolution],
                    bounds=[[float(c) for c in b] for b in self.bounds])


class Source(Protocol):
    """What a bake needs from a noise.

    kind      short name ("wave")
    dim       coordinates the noise takes: 2, 3 or 4 (4D: W is the bake's time)
    animated  True when the output changes with time (``animated_by``, where a kind has it: the settings that
              make it change, for a frame range of one that does not)
    chunkable True when any sub-box may be evaluated alone (else the whole grid at once)
    unit      (optional, False when absent) True when every value lies in [0, 1] (neural noise): an 8-bit PNG holds
              the values as they are, not stretched over their percentiles as a preview of unbounded noise is
    """

    kind: str
    dim: int
    animated: bool
    chunkable: bool

    def evaluate(self, shape: tuple, first: np.ndarray, step: np.ndarray, time: float,
                 progress: Callable[[float], None] | None = None,
                 cancel: Callable[[], bool] | None = None, start: tuple | None = None) -> np.ndarray:
        """float32 ``shape`` ((ny, nx) or (nz, ny, nx)) at first + (start + index) * step.

        first (3,) world position of the grid's sample 0; step (rank,); start (rank,)
        index of this box's first sample, x first (default zeros).  A slab's values
        must equal the same samples of the whole grid.
        """

    def to_dict(self) -> dict:
        """Everything that determines the values, as plain JSON types (for up-to-date checks)."""

    # A source may also make its texture at its first use (a fit, a choice: :class:`~.solid._Prepared`): ``ready``
    # says whether it is made, ``prepare(progress, cancel)`` makes it; a bake makes it before drawing a file that is
    # not up to date, and ``to_dict`` does not need it.


def grid_points(shape, first, step, start=None) -> np.ndarray:
    """The points of a grid block (the solid sources' evaluate): ``shape`` (ny, nx) or (nz, ny, nx) samples from
    index ``start`` (x, y[, z]; zeros when None) of a grid whose first sample is at ``first`` with spacing ``step``
    -> float64 (N, 2 or 3) (x, y[, z]), x fastest."""
    n = len(shape)
    start = np.zeros(n, int) if start is None else np.asarray(start)
    axes = [first[k] + (start[k] + np.arange(shape[::-1][k])) * step[k] for k in range(n)]   # x, y[, z]
    mesh = np.meshgrid(*reversed(axes), indexing="ij")                                      # (z,) y, x
    return np.stack([m.ravel() for m in reversed(mesh)], axis=1)


def check_keys(d: dict, known: tuple, kind: str) -> None:
    unknown = sorted(set(d) - set(known))
    if unknown:
        raise SettingError(f"source.{unknown[0]}", f"unknown {kind} setting; known: {', '.join(known)}")


def job_image(base_dir: str, value: str, key: str, what: str) -> np.ndarray:
    """The image a job's ``source.KEY`` names (a path beside the job, :func:`~backend.paths.in_job`) read as
    float32 (H, W) by ``export.read_image``; SettingError naming ``source.KEY`` for a missing file ("WHAT not found:
    PATH") or one that cannot be read."""
    import os

    from ... import export

    path = in_job(base_dir, value)
    if not os.path.isfile(path):
        raise SettingError(f"source.{key}", f"{what} not found: {path}")
    try:
        return export.read_image(path)
    except export.ImageError as exc:
        raise SettingError(f"source.{key}", str(exc)) from None
