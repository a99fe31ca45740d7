"""The table of wave settings: each key's exact type, range and meaning (see :mod:`backend.schema`).

:meth:`backend.wavenoise.settings.WaveSettings.validate` checks its fields against :data:`WAVE_SETTINGS`,
so the command line, job files, the Blender node and the Python API meet the same rules.
"""
from __future__ import annotations

from .. import limits
from ..schema import AnyOf, Choice, Field, Float, Int, Items, ListOf, Table
from .byexample import PLANES
from .cellular import CELLULAR_MODES
from .hashing import MAX_EXACT_ID
from .spectra import SPECTRUM_KINDS
from .tables import WAVEFORMS
from .wave import OUTPUTS

__all__ = ["ANISOTROPY", "SEED", "COORD", "LENGTH", "FREQUENCY", "SPECTRUM", "WAVE_SETTINGS"]

ANISOTROPY = ("none", "axes", "lobes")
SEED = Int(0, 2 ** 32 - 1)
WAVE_SEED = Int(0, MAX_EXACT_ID - 1)    #: the wave hashes read a seed as a float32 id, exact below 2^24
COORD = Float(-limits.MAX_COORD, limits.MAX_COORD)
LENGTH = Float(limits.MIN_LENGTH, limits.MAX_COORD)
FREQUENCY = Float(0.0, limits.MAX_FREQUENCY)
VECTOR = ListOf(COORD, 2, 4)

SPECTRUM = Table({
    "kind": Field(Choice(SPECTRUM_KINDS), "the amplitude profile over frequency", True),
    "fmin": Field(FREQUENCY, "lowest frequency, cycles per unit", default="0"),
    "fmax": Field(Float(0.0, limits.MAX_FREQUENCY, above=True), "highest frequency, cycles per unit",
                  default="8"),
    "exponent": Field(Float(-16.0, 16.0), "fractal: amplitude falls as f^-exponent", default="1"),
    "split": Field(Float(0.0, 1.0), "twolevel: where the band splits, 0 to 1 from fmin to fmax", default="0.5"),
    "ratio": Field(Float(0.0, 1e6), "twolevel: amplitude of the upper band over the lower", default="1"),
    "samples": Field(ListOf(Float(0.0, 1e6), 2, 4096), "custom: amplitudes spaced evenly from fmin to fmax"),
}, "a spectrum table")

WAVE_SETTINGS = Table({
    "dim": Field(Choice((2, 3, 4)), "dimensions of the noise; 4D's fourth coordinate is W or time", default="2"),
    "spectrum": Field(AnyOf((Choice(SPECTRUM_KINDS), SPECTRUM)),
                      "a spectrum table, or its kind with fmin, fmax, exponent beside it", default="gaussian"),
    "directions": Field(Int(1, limits.MAX_DIRECTIONS), "number of wave directions; more is smoother and slower",
                        default="16"),
    "seed": Field(WAVE_SEED, "random seed of the tables and directions", default="0"),
    "output": Field(Choice(OUTPUTS), "which part of the complex noise is written", default="real"),
    "speed": Field(Float(-limits.MAX_SPEED, limits.MAX_SPEED), "wave speed in units per unit time; non-zero "
                   "animates", default="0"),
    "slice_width": Field(LENGTH, "width of the slice a 3D or 4D table integrates, world units",
                         default="6 / mean frequency"),
    "waveform": Field(Choice(WAVEFORMS), "the profile of each wave", default="gaussian"),
    "profile": Field(ListOf(Float(-1e6, 1e6), 2, limits.MAX_TABLE_SIZE), "custom waveform: one period's samples"),
    "cellular": Field(Choice(CELLULAR_MODES), "cellular variant (cells cut by the waves' planes)", default="none"),
    "cell_size": Field(Float(1e-6, limits.MAX_COORD), "cellular: spacing of the cutting planes, world units",
                       default="from the spectrum"),
    "stit_probability": Field(Float(0.0, 1.0), "stit: chance that a cell splits again", default="0.5"),
    "stit_depth": Field(Int(0, 8), "stit: how many times cells split", default="3"),
    "anisotropy": Field(Choice(ANISOTROPY), "directions: all, one spectrum per axis, or lobes", default="none"),
    "axis_spectra": Field(ListOf(SPECTRUM, 1, 4), "axes: one spectrum table per axis"),
    "lobes": Field(ListOf(Items((VECTOR, Float(0.0, 1e6)), "[[axis x, y(, z(, w))], weight]"), 1, 64),
                   "lobes: directions the waves favour, each with its weight"),
    "spread": Field(Float(0.0, 90.0, above=True), "half-angle of a lobe or of a by-example band, degrees",
                    default="20"),
    "example_plane": Field(Choice(tuple(PLANES)), "by-example 3D: the plane the image lies in", default="xy"),
    "example_extent": Field(LENGTH, "by-example: world units across the image", default="1"),
    "sectors": Field(Int(1, 64), "by-example: angular sectors read from the image's spectrum", default="8"),
    "transition_to": Field(SPECTRUM, "a second spectrum the noise blends towards"),
    "transition_origin": Field(VECTOR, "where the blend starts, world units", default="the origin"),
    "transition_axis": Field(VECTOR, "the direction the blend runs", default="x"),
    "transition_length": Field(LENGTH, "world units over which the blend runs", default="1"),
    "table_size": Field(Int(16, limits.MAX_TABLE_SIZE), "samples per wave table", default="4096"),
    "table_period": Field(LENGTH, "world units per table period", default="255 / fmax"),
}, "wave settings")
