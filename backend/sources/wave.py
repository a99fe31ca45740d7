"""Wave noise (Guehl et al. 2025) as a bake source, and its job table (``kind = "wave"``)."""
from __future__ import annotations

import hashlib

import numpy as np

from .. import limits
from ..errors import SettingError
from .base import job_image

__all__ = ["WaveSource", "from_dict"]

_F = np.float32


class WaveSource:
    """Wave noise (Guehl et al. 2025) from :class:`~backend.wavenoise.settings.WaveSettings`.

    3D grids need a 3D or 4D noise; a 2D grid of a 3D/4D noise is the plane z = z0.
    4D noise takes W = ``w_offset`` + time; 2D+t and 3D+t noise take time directly.
    """

    kind = "wave"
    chunkable = True
    animated_by = "set speed, or dim = 4"

    def __init__(self, settings, w_offset: float = 0.0):
        from ..wavenoise.settings import compile_noise

        self.settings = settings.validate()
        self.w_offset = float(w_offset)
        self.dim = settings.dim
        self.animated = settings.dim == 4 or settings.animated
        #: the tables and directions, built here (2 ms; 0.4 s at the most: 4096 directions, 2^20-sample tables) so
        #: that their own rules (a band that holds no table harmonic, a frequency past the table's Nyquist, lobes
        #: of no weight) are checked where the source is made, before any bake runs
        self.noise = compile_noise(self.settings)

    def check_extent(self, spatial: float, time: float, names: tuple = ("bounds", "time")) -> None:
        """Refuse points ``spatial`` world units from the origin at times up to ``time`` when the waves there
        pass :data:`~backend.limits.MAX_CYCLES` (:meth:`WaveSettings.check_reach`); named by ``names``
        (space, time), whichever reaches farther."""
        w = abs(self.w_offset) + time if self.dim == 4 else time * abs(self.settings.speed)
        self.settings.check_reach(names[1] if w > spatial else names[0], spatial + w)

    def evaluate(self, shape, first, step, time, progress=None, cancel=None, start=None) -> np.ndarray:
        from ..grid import evaluate_box

        rank = len(shape)
        if rank == 3 and self.dim == 2:
            raise SettingError("grid", "a 2D wave noise bakes images only; set dim = 3 or 4 for volumes")
        lo = np.zeros(self.dim, _F)
        k = min(self.dim, 3)
        lo[:k] = np.asarray(first, np.float64)[:k]
        if self.dim == 4:
            lo[3] = _F(self.w_offset + time)
        s = self.settings
        return evaluate_box(self.noise, shape, lo, step, s.output, 0.0 if self.dim == 4 else float(time),
                            s.cellular, progress=progress, cancel=cancel, start=start)

    def to_dict(self) -> dict:
        """The settings the noise reads (:func:`~backend.wavenoise.settings.read_settings`), ``w_offset`` and the
        by-example image's hash."""
        from ..wavenoise.settings import read_settings, settings_to_dict

        d = dict(kind=self.kind, settings=settings_to_dict(read_settings(self.settings)), w_offset=self.w_offset)
        if self.settings.example is not None:
            ex = np.ascontiguousarray(self.settings.example, _F)
            d["example_sha256"] = hashlib.sha256(ex.tobytes() + str(ex.shape).encode()).hexdigest()
        return d


def from_dict(d: dict, base_dir: str) -> WaveSource:
    from ..wavenoise.settings import check_read, settings_from_dict

    example = None
    if "example" in d:
        example = job_image(base_dir, d.pop("example"), "example", "image")
    w_offset = limits.finite("source.w_offset", d.pop("w_offset", 0.0))
    spectrum = d.get("spectrum")
    given = list(d) + (["exponent"] if isinstance(spectrum, dict) and "exponent" in spectrum else [])
    try:
        settings = settings_from_dict(d, example)
        check_read(settings, given)     # a key that changes nothing here: the noise would not be the one asked for
        return WaveSource(settings, w_offset)
    except SettingError as exc:      # the settings' own rules name their keys; a job's are under [bake.source]
        raise exc.under("source") from None
