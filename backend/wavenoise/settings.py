"""Plain, serialisable wave-noise settings and their compilation into evaluators.

:class:`WaveSettings` holds only numbers, strings and tuples, so the CLI, job
files and Blender properties can all build one; :func:`compile_noise` turns it
into a :class:`~backend.wavenoise.wave.WaveNoise` or :class:`~backend.wavenoise.cellular.CellularNoise`.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field, fields, replace

import numpy as np

from .byexample import PLANES, check_example, example_table
from .cellular import CellularNoise
from .directions import DirectionSet, Domain
from .. import limits
from ..errors import SettingError
from .spectra import Spectrum
from .tables import DEFAULT_SIZE, build_axis_table, build_table, build_waveform_table
from .schema import ANISOTROPY, WAVE_SETTINGS
from .wave import Transition, WaveNoise

__all__ = ["ANISOTROPY", "WaveSettings", "compile_noise", "table_rng", "settings_to_dict", "settings_from_dict",
           "READ_WITH", "check_none", "check_read", "check_time", "field_of",
           "spectrum_to_dict", "read_settings"]



@dataclass(frozen=True)
class WaveSettings:
    """Everything that defines a wave noise.

    dim              2, 3 or 4 (4D: the fourth coordinate is W / time)
    spectrum         isotropic amplitude profile (cycles per unit)
    directions       number of wave directions K
    seed             integer in [0, 2^24): table phases and every hashed random number
    output           real | imag | modulus | phase
    speed            wave speed v (units per unit time, Eq. 9); animated noise when non-zero
    slice_width      W in world units; None = 6 / (mean frequency of the table)
    waveform         gaussian | crystal | wired | custom (with ``profile``)
    cellular         none | polytope | code | stit
    cell_size        cellular plane spacing (world units); None = 1 / fmin-ish
    stit_probability, stit_depth   STIT recursion controls
    anisotropy       none | axes (``axis_spectra``, one per axis) | lobes (``lobes``)
    lobes            ((axis vector), weight) pairs; ``spread`` = lobe half-angle, degrees
    example          grayscale image (H, W) for by-example noise; ``example_plane``,
                     ``example_extent`` (world units across the image), ``sectors``
    transition_to    a second Spectrum to blend towards along ``transition_axis``
                     from ``transition_origin`` over ``transition_length``
    table_size       samples per wave table (N_x)
    table_period     world units per table period (None: (256 - 1) / fmax)
    """

    dim: int = 2
    spectrum: Spectrum = field(default_factory=Spectrum)
    directions: int = 16
    seed: int = 0
    output: str = "real"
    speed: float = 0.0
    slice_width: float | None = None
    waveform: str = "gaussian"
    profile: tuple = ()
    cellular: str = "none"
    cell_size: float | None = None
    stit_probability: float = 0.5
    stit_depth: int = 3
    anisotropy: str = "none"
    axis_spectra: tuple = ()
    lobes: tuple = ()
    spread: float = 20.0
    example: np.ndarray | None = field(default=None, compare=False, repr=False)
    example_plane: str = "xy"
    example_extent: float = 1.0
    sectors: int = 8
    transition_to: Spectrum | None = None
    transition_origin: tuple = ()
    transition_axis: tuple = ()
    transition_length: float = 1.0
    table_size: int = DEFAULT_SIZE
    table_period: float | None = None

    def replace(self, **kw) -> "WaveSettings":
        return replace(self, **kw)

    def validate(self) -> "WaveSettings":
        """The fields against :data:`backend.wavenoise.schema.WAVE_SETTINGS` (exact types, ranges, known
        names), then the rules that join fields; SettingError naming the first field that is wrong."""
        check_none({f.name: getattr(self, f.name) for f in fields(self)})
        try:
            d = {k: v for k, v in settings_to_dict(self).items() if v != []}  # () is a tuple setting left unset
        except SettingError:
            raise
        except (TypeError, ValueError) as exc:  # a tuple field holding something that is not a number
            raise SettingError("wave settings", f"expected numbers in the tuple settings ({exc})") from None
        WAVE_SETTINGS.check(d, "")
        if self.waveform == "custom":
            if len(self.profile) == 0:
                raise SettingError("profile", "waveform custom needs a profile: one period's samples")
            if max(self.profile) == min(self.profile):
                raise SettingError("profile", f"all {len(self.profile)} samples are {self.profile[0]:g}; "
                                              "a waveform needs samples that vary")
        if self.example is not None:
            if self.example_plane not in PLANES:
                raise SettingError("example_plane", f"must be one of {', '.join(PLANES)}, got {self.example_plane!r}")
            if self.dim not in (2, 3):
                raise SettingError("example", "by-example noise is 2D or 3D")
            check_example(self.example)
        spectra = [("spectrum", self.spectrum)] + [(f"axis_spectra[{i}]", sp) for i, sp in enumerate(self.axis_spectra)]
        if self.transition_to is not None:
            spectra.append(("transition_to", self.transition_to))
        for name, sp in spectra:
            try:
                sp.validate()
            except SettingError as exc:
                raise exc.under(name) from None
        if self.anisotropy == "axes" and len(self.axis_spectra) != self.dim:
            raise SettingError("axis_spectra", f"per-axis anisotropy needs {self.dim} spectra, one per axis, "
                                               f"got {len(self.axis_spectra)}")
        if self.anisotropy == "lobes" and not self.lobes:
            raise SettingError("lobes", "lobe anisotropy needs at least one (axis, weight) lobe")
        directions = [(f"lobes[{i}]", "lobe axis", axis) for i, (axis, _) in enumerate(self.lobes)]
        for name, what, v in directions + [("transition_axis", "transition axis", self.transition_axis)]:
            if len(v) and (len(v) != self.dim or not np.linalg.norm(v) > 0):   # a direction: non-zero
                raise SettingError(name, f"{what} {tuple(v)} must be a non-zero {self.dim}-vector")
        if len(self.transition_origin) not in (0, self.dim):
            raise SettingError("transition_origin", f"transition origin {tuple(self.transition_origin)} must be a "
                                                    f"{self.dim}-vector")
        return self

    def max_frequency(self) -> float:
        """The highest frequency any of the noise's spectra (or its by-example image) holds, cycles per unit."""
        spectra = [self.spectrum, *self.axis_spectra] + ([self.transition_to] if self.transition_to else [])
        f = max(float(sp.fmax) for sp in spectra)
        if self.example is not None:
            f = max(f, max(np.shape(self.example)) / (2.0 * float(self.example_extent)))
        return f

    def check_reach(self, name: str, reach: float) -> None:
        """Refuse a request whose farthest point lies ``reach`` world units from the origin (time times speed
        included) when that is more than :data:`~backend.limits.MAX_CYCLES` waves (or cells) away: float32
        phases there no longer hold the waves, and the noise would come out as a few flat values."""
        per_unit = 1.0 / float(self.cell_size) if self.cellular != "none" and self.cell_size else self.max_frequency()
        if not reach * per_unit <= limits.MAX_CYCLES:
            raise SettingError(name, f"reaches {reach:g} units from the origin, {reach * per_unit:.3g} "
                                     f"{'cells' if self.cellular != 'none' else 'waves'} away; keep it within "
                                     f"{limits.MAX_CYCLES:g} (a smaller extent, time or frequency)")

    @property
    def animated(self) -> bool:
        return self.speed != 0.0


_SPECTRUM_KEYS = ("kind", "fmin", "fmax", "exponent", "split", "ratio", "samples")


def spectrum_to_dict(sp: Spectrum) -> dict:
    d = dict(kind=sp.kind, fmin=float(sp.fmin), fmax=float(sp.fmax), exponent=float(sp.exponent))
    if sp.kind == "twolevel":
        d.update(split=float(sp.split), ratio=float(sp.ratio))
    if sp.samples:
        d["samples"] = [float(v) for v in sp.samples]
    return d


def _spectrum_from(value, where: str) -> Spectrum:
    if isinstance(value, Spectrum):
        return value
    if not isinstance(value, dict):
        raise SettingError(where, f"expected a table like {{kind = \"bandpass\", fmin = 2, fmax = 8}}, got {value!r}")
    unknown = sorted(set(value) - set(_SPECTRUM_KEYS))
    if unknown:
        raise SettingError(where, f"unknown key {unknown[0]!r}; known: {', '.join(_SPECTRUM_KEYS)}")
    d = dict(value)
    if "samples" in d:
        d["samples"] = tuple(float(v) for v in d["samples"])
    return Spectrum(**d)


def settings_to_dict(s: WaveSettings) -> dict:
    """WaveSettings -> plain dict of JSON/TOML types (by-example images are left out)."""
    out = {}
    for f in fields(s):
        if f.name == "example":
            continue
        try:
            v = _plain(f.name, getattr(s, f.name))
        except (TypeError, ValueError) as exc:    # a tuple field holding something that is not a number
            raise SettingError(f.name, f"expected numbers ({exc})") from None
        if v is not None:
            out[f.name] = v
    return out


def _plain(name: str, v):
    """One WaveSettings field as JSON/TOML types."""
    if name in ("spectrum", "transition_to"):
        return None if v is None else spectrum_to_dict(v)
    if name == "axis_spectra":
        return [spectrum_to_dict(a) for a in v]
    if name == "lobes":
        return [[[float(c) for c in a], float(w)] for a, w in v]
    if isinstance(v, (tuple, np.ndarray)):
        return [float(c) for c in v]
    return v


def field_of(setting: str) -> str:
    """The field behind a setting's name in an error: "spectrum.fmax" -> "fmax" (a spectrum's own), "lobes[0][1]"
    -> "lobes", "axis_spectra[0].fmin" -> "axis_spectra", "cell size" -> "cell_size"; a front end names that field
    as its user knows it (a flag, a panel's label)."""
    parts = re.split(r"[.\[]", setting.replace(" ", "_"))
    return parts[-1] if parts[0] == "spectrum" else parts[0]

#: settings that change the noise only beside another: name -> (whether ``s`` reads it, what it needs: one or more
#: alternatives, each (setting, value) pairs that must all hold; value None: any but the default). ``exponent`` is
#: the spectrum's; a 2D by-example noise reads neither its plane nor a band's spread.
READ_WITH = {
    "exponent": (lambda s: s.spectrum.kind == "fractal", ((("spectrum", "fractal"),),)),
    "profile": (lambda s: s.waveform == "custom", ((("waveform", "custom"),),)),
    "cell_size": (lambda s: s.cellular != "none", ((("cellular", None),),)),
    "stit_probability": (lambda s: s.cellular == "stit", ((("cellular", "stit"),),)),
    "stit_depth": (lambda s: s.cellular == "stit", ((("cellular", "stit"),),)),
    "axis_spectra": (lambda s: s.anisotropy == "axes", ((("anisotropy", "axes"),),)),
    "lobes": (lambda s: s.anisotropy == "lobes", ((("anisotropy", "lobes"),),)),
    "spread": (lambda s: s.anisotropy == "lobes" or (s.example is not None and s.dim == 3),
               ((("anisotropy", "lobes"),), (("example", None), ("dim", 3)))),
    "example_plane": (lambda s: s.example is not None and s.dim == 3, ((("example", None), ("dim", 3)),)),
    "example_extent": (lambda s: s.example is not None, ((("example", None),),)),
    "sectors": (lambda s: s.example is not None, ((("example", None),),)),
    "transition_length": (lambda s: s.transition_to is not None, ((("transition_to", None),),)),
}


def _read_spectrum(sp: Spectrum | None) -> Spectrum | None:
    """``sp`` with the exponent at its default where its kind does not read it (all but fractal)."""
    if sp is None or sp.kind == "fractal":
        return sp
    return replace(sp, exponent=Spectrum().exponent)


def read_settings(s: WaveSettings) -> WaveSettings:
    """``s`` with every setting the noise does not read (:data:`READ_WITH`) at its default: the same noise, one
    form of it (a bake's key, a job file)."""
    defaults = {f.name: getattr(WaveSettings(), f.name) for f in fields(WaveSettings)}
    kept = replace(s, **{name: defaults[name] for name, (reads, _) in READ_WITH.items()
                         if name != "exponent" and not reads(s)})
    return replace(kept, spectrum=_read_spectrum(kept.spectrum), transition_to=_read_spectrum(kept.transition_to),
                   axis_spectra=tuple(_read_spectrum(a) for a in kept.axis_spectra))


def check_read(s: WaveSettings, given, shown=None) -> None:
    """SettingError naming the first of ``given`` (setting names, as :data:`READ_WITH`) that ``s`` does not read: it
    would change nothing, and the noise would not be the one asked for. ``shown(name, value=None)`` writes a setting,
    or a setting holding a value, as the front end does (default: a job file's ``cellular = "stit"``)."""
    shown = shown or (lambda k, v=None: k if v is None else f"{k} = {v!r}".replace("'", '"'))
    for key in given:
        read, needs = READ_WITH.get(key, (None, None))
        if read is not None and not read(s):
            what = " or ".join(" with ".join(shown(k, v) for k, v in alt) for alt in needs)
            raise SettingError(shown(key), f"is read only with {what}; without it, it would change nothing")


def check_none(values: dict) -> None:
    """SettingError naming the first of ``values`` (WaveSettings fields) that is None where None is not its default:
    None is "not given" only where it is the default (it would be left out)."""
    for f in fields(WaveSettings):
        if f.name in values and values[f.name] is None and f.default is not None:
            raise SettingError(f.name, "expected a value, got None")


def check_time(name: str, time: float, s: WaveSettings, speed: str = "speed", dim4: str = "dim = 4") -> None:
    """Refuse a time ``name`` other than 0 for noise that does not change with it (still, 2D or 3D): it would
    change nothing. ``speed`` and ``dim4`` name the settings that make it read, as the front end does."""
    if time != 0.0 and not (s.dim == 4 or s.animated):
        raise SettingError(name, f"is read only with {speed} (animated noise) or {dim4} (its fourth coordinate); "
                                 "without them, it would change nothing")


def settings_from_dict(d: dict, example: np.ndarray | None = None) -> WaveSettings:
    """Plain dict (job file table, node JSON) -> WaveSettings; unknown keys fail with their name.

    ``spectrum`` may also be given flat as ``spectrum = "bandpass"`` with ``fmin``,
    ``fmax`` and ``exponent`` beside it.
    """
    known = {f.name for f in fields(WaveSettings)} - {"example"}
    d = dict(d)
    flat = {k: d.pop(k) for k in ("fmin", "fmax", "exponent") if k in d}
    if isinstance(d.get("spectrum"), str) or (flat and "spectrum" not in d):
        d["spectrum"] = dict(kind=d.get("spectrum", "gaussian"), **flat)
    elif flat:
        raise SettingError(", ".join(flat), "give band limits inside the spectrum table, or spectrum as a name")
    unknown = sorted(set(d) - known)
    if unknown:
        raise SettingError(unknown[0], f"unknown wave setting; known: {', '.join(sorted(known))}")
    kw = {}
    for k, v in d.items():
        if k == "spectrum":
            v = _spectrum_from(v, "spectrum")
        elif k == "transition_to":
            v = None if v is None else _spectrum_from(v, "transition_to")
        elif k == "axis_spectra":
            v = tuple(_spectrum_from(a, "axis_spectra") for a in v)
        elif k == "lobes":
            v = tuple((tuple(float(c) for c in a), float(w)) for a, w in v)
        elif k in ("profile", "transition_origin", "transition_axis"):
            v = tuple(float(c) for c in v)
        kw[k] = v
    try:
        return WaveSettings(example=example, **kw).validate()
    except TypeError as exc:  # a value of the wrong type reaching a comparison
        raise SettingError("wave settings", str(exc)) from None


def table_rng(seed: int) -> np.random.Generator:
    """The generator behind a table's random phases: one stream per seed."""
    return np.random.default_rng(np.random.SeedSequence([int(seed), 0x0A11E]))


def _domains(s: WaveSettings) -> tuple[list[Domain], tuple]:
    d = s.dim
    last = tuple(np.eye(d)[d - 1])
    if s.example is not None:
        a, b, c = PLANES[s.example_plane]
        if d == 2:
            return [Domain("cap", 2, np.pi / 2, (0.0, 1.0), full=s.animated)], (0, 1)
        if d == 3:
            return [Domain("band", 3, np.radians(s.spread), (a, b, c))], (a, b)
        raise SettingError("example", "by-example noise is 2D or 3D")
    if s.anisotropy == "lobes":
        doms = []
        for axis, weight in s.lobes:       # validated: non-zero d-vectors
            v = np.asarray(axis, dtype=np.float64)
            doms.append(Domain("cap", d, np.radians(s.spread), tuple(v / np.linalg.norm(v)), weight=float(weight)))
        return doms, (0, 1)
    return [Domain("cap", d, np.pi / 2, last, full=s.animated)], (0, 1)


def compile_noise(s: WaveSettings) -> WaveNoise | CellularNoise:
    """Build tables and direction strata for settings ``s``."""
    s.validate()
    domains, plane = _domains(s)
    dirs = DirectionSet.build(int(s.directions), domains)
    if s.cellular != "none":
        cell = s.cell_size if s.cell_size is not None else 2.0 / max(s.spectrum.fmin, s.spectrum.fmax / 4)
        depth = s.stit_depth if s.cellular == "stit" else 0
        return CellularNoise(dirs, s.seed, cell, s.stit_probability, depth)
    rng = table_rng(s.seed)
    if s.example is not None:
        table = example_table(s.example, s.dim, rng, s.sectors, s.example_extent)
    elif s.waveform != "gaussian":
        table = build_waveform_table(s.waveform, rng, s.spectrum.fmax, s.dim, s.table_size,
                                     profile=np.asarray(s.profile) if s.profile else None)
    elif s.anisotropy == "axes":
        table = build_axis_table(list(s.axis_spectra), s.dim, rng, s.table_size, s.table_period)
    else:
        table = build_table(s.spectrum, s.dim, rng, s.table_size, s.table_period)
    transition = None
    if s.transition_to is not None:
        # same generator state -> identical phases (Sec. 4.3 uni-phase waves)
        pair = build_axis_table([s.spectrum, s.transition_to], s.dim, table_rng(s.seed), s.table_size,
                                s.table_period, mode="sectors")
        table = type(table)(pair.values[:1], pair.period, "single", s.dim, table.meta)
        axis = np.asarray(s.transition_axis or np.eye(s.dim)[0], np.float32)
        origin = np.asarray(s.transition_origin or np.zeros(s.dim), np.float32)
        transition = Transition(pair.values[1:2], origin, axis / np.linalg.norm(axis), float(s.transition_length))
    width = s.slice_width if s.slice_width is not None else 6.0 / table.mean_frequency()
    return WaveNoise(table, dirs, s.seed, width, s.speed, transition, plane)
