"""Bake sources: anything that fills a box grid with noise values or colours.

A source answers ``evaluate(grid box) -> float32 array`` (:class:`~.base.Source`); :mod:`backend.bake` slices the
bake into slabs, maps values through a transfer function and hands them to writers.  One module a kind: wave noise
(:mod:`.wave`), neural noise (:mod:`.neural`) and solid textures (:mod:`.solid`), each with the builder of its job
table, registered here by the kind that job files name (``kind = "..."`` in ``[bake.source]``).
"""
from __future__ import annotations

import json

from ..errors import SettingError
from . import neural, solid, wave
from .base import BoxGrid, Source
from .neural import NeuralSource
from .solid import (AutoSource, EncodedSource, SolidSource, SpectralSource, SynthesisSource, solid_px_per_unit,
                    solid_request_from_dict, solid_source, solid_volume)
from .wave import WaveSource

__all__ = ["BoxGrid", "Source", "WaveSource", "NeuralSource", "SolidSource", "SpectralSource", "SynthesisSource",
           "AutoSource", "EncodedSource", "solid_volume", "solid_source", "solid_px_per_unit",
           "solid_request_from_dict", "source_from_dict", "register_source", "source_kinds", "describe", "SOURCES"]

#: kind -> builder(table without "kind", base_dir) -> source.  A new kind of source is one module with a class
#: of the :class:`Source` protocol and one :func:`register_source` call; job files, the farm and the bake
#: pipeline then take it (``kind = "..."`` in ``[bake.source]``) with no other change.
SOURCES: dict = {}


def register_source(kind: str, from_dict) -> None:
    """Make ``kind = KIND`` in job files build a source with ``from_dict(table, base_dir)``."""
    if not isinstance(kind, str) or not kind.isidentifier():
        raise ValueError(f"a source kind is an identifier, got {kind!r}")
    SOURCES[kind] = from_dict


register_source("wave", wave.from_dict)
register_source("neural", neural.from_dict)
register_source("solid", solid.from_dict)


def source_kinds() -> tuple:
    return tuple(SOURCES)


def source_from_dict(d: dict, base_dir: str = ".") -> Source:
    """A source from a job-file table: ``kind`` (default "wave") names a registered builder (:data:`SOURCES`).

    Wave: the keys of :class:`~backend.wavenoise.settings.WaveSettings`; ``example = "img.png"``
    (relative to ``base_dir``) for by-example noise; ``w_offset`` for 4D.
    Neural: noise, params, [blend = "mask.png", noise2, params2 | corners = [4 specs] | map = "painted.png",
    regions = {"#rrggbb" = SPEC}], [width, sharpness],
    steps, seed, tileable, [model = folder], [keys, latent, drift] (see :class:`NeuralSource`).
    Solid: model (a folder, or a shipped model's name), [exemplar, refine], seed, scale, density
    (see :class:`SolidSource`).
    """
    from ..schema import did_you_mean, shown_value
    from ..settings_schema import SOURCE_TABLES

    if not isinstance(d, dict):
        raise SettingError("source", f"expected a [bake.source] table, got {shown_value(d)}")
    kind = d.get("kind", "wave")
    if not isinstance(kind, str) or kind not in SOURCES:
        hint = did_you_mean(kind, SOURCES) if isinstance(kind, str) else ""
        raise SettingError("source.kind", f"unknown source {shown_value(kind)}{hint}; choose one of "
                                          f"{', '.join(SOURCES)}")
    d = dict(SOURCE_TABLES[kind].check(d, "source")) if kind in SOURCE_TABLES else dict(d)
    d.pop("kind", None)
    return SOURCES[kind](d, base_dir)


def describe(obj) -> str:
    """Canonical JSON of a to_dict()-able object or plain value (for hashing)."""
    if hasattr(obj, "to_dict"):
        obj = obj.to_dict()
    return json.dumps(obj, sort_keys=True, separators=(",", ":"))
