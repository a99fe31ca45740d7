"""The schema of every setting a job file, the command line, the Blender panels and the Python API pass in.

One declaration per setting: its exact type, its range and one line of what it does. Job files are checked
against :data:`JOB` (and each ``[bake.source]`` against its kind's table in :data:`SOURCE_TABLES`) before any
bake runs. The wave settings' table (:mod:`backend.wavenoise.schema`) and the ramp's (:data:`TRANSFER`, in
:mod:`backend.transfer`) live beside the types they check, which apply them whichever front end built them
(:meth:`~backend.wavenoise.settings.WaveSettings.validate`, :func:`~backend.transfer.transfer_from_dict`). ``python -m tools.job_reference`` writes ``docs/guide/job-reference.md`` from these
tables.
"""
from __future__ import annotations

import json

from . import limits
from .neural.animate import LATENT_MODES
from .neural.sampler import SAMPLERS
from .schema import AnyOf, Bool, Choice, Field, Float, Int, Items, ListOf, MapOf, Table, Text
from .solid.gaussian_rest import REST_CHOICES
from .solid.methods import METHODS
from .solid.procedural.field import DEFAULT_KINDS, KINDS
from .solid.synthesis import MAX_TILE, MIN_TILE
from .transfer import TRANSFER
from .wavenoise.schema import COORD, FREQUENCY, SEED, SPECTRUM, WAVE_SETTINGS

__all__ = ["SEED", "SPECTRUM", "WAVE_SETTINGS", "WAVE_SOURCE", "NEURAL_SOURCE", "SOLID_SOURCE", "TRANSFER",
           "SOURCE_TABLES", "BAKE", "JOB"]

FILE = Text("a file path (relative to the job file)")

WAVE_SOURCE = Table({
    "kind": Field(Choice(("wave",)), "wave noise (Guehl et al. 2025)", default="wave"),
    **WAVE_SETTINGS.fields,
    "fmin": Field(FREQUENCY, "with spectrum = KIND: lowest frequency"),
    "fmax": Field(Float(0.0, limits.MAX_FREQUENCY, above=True), "with spectrum = KIND: highest frequency"),
    "exponent": Field(Float(-16.0, 16.0), "with spectrum = KIND: fractal exponent"),
    "example": Field(FILE, "by-example noise: a grey image whose spectrum the noise takes"),
    "w_offset": Field(COORD, "4D: W added to every point", default="0"),
}, "a wave source")

CLASS_SPEC = AnyOf((Text('a class spec "CLASS:NAME=VALUE,..."', 1024),
                    Table({"noise": Field(Text("a class name", 256), "the noise class", True),
                           "params": Field(MapOf(Float(), "parameter"), "the class's parameters")},
                          "{noise = CLASS, params = {NAME = VALUE}}")))
PARAMS = MapOf(Float(), "parameter name", 64)
KEYFRAME = Table({"frame": Field(Int(-limits.MAX_FRAMES * 100, limits.MAX_FRAMES * 100), "the key's frame", True),
                  "noise": Field(Text("a class name", 256), "the noise class at that frame", True),
                  "params": Field(PARAMS, "the class's parameters"),
                  "seed": Field(SEED, "the key's seed", default="0")}, "a keyframe table")

NEURAL_SOURCE = Table({
    "kind": Field(Choice(("neural",)), "neural noise (Maesumi et al. 2024)", True),
    "model": Field(FILE, "a model folder", default="the shipped model"),
    "noise": Field(Text("a class name", 256), "the noise class (see `omninoise neural --list`)"),
    "params": Field(PARAMS, "the class's parameters, {scale = 8, ...}"),
    "noise2": Field(Text("a class name", 256), "blend: the class where the mask is white"),
    "params2": Field(PARAMS, "blend: the second class's parameters"),
    "blend": Field(FILE, "a grey mask image: white takes noise2"),
    "gradient": Field(ListOf(CLASS_SPEC, 2, 2), "two class specs: the first on the left edge blending evenly into "
                                                "the second on the right"),
    "corners": Field(ListOf(CLASS_SPEC, 4, 4), "four class specs: top-left, top-right, bottom-left, bottom-right"),
    "map": Field(FILE, "a painted map whose colours name classes"),
    "regions": Field(MapOf(CLASS_SPEC, '"#rrggbb" or grey level "0".."255"'), "map: each colour's class spec"),
    "width": Field(Float(0.0, 1e4, above=True), "transition width of masks and maps, in their px", default="32"),
    "sharpness": Field(Float(0.0, 1e3, above=True), "how sharp transitions are", default="1"),
    "sampler": Field(Choice(tuple(SAMPLERS)), "the diffusion sampler", default="the model's"),
    "steps": Field(Int(1, 1000), "denoising steps; more is finer and slower", default="the sampler's"),
    "seed": Field(SEED, "random seed", default="0"),
    "tileable": Field(Bool(), "an image that tiles seamlessly", default="false"),
    "keys": Field(AnyOf((FILE, ListOf(KEYFRAME, 1, 4096))), "animation: a keyframe file or a list of tables"),
    "latent": Field(Choice(LATENT_MODES), "animation: how the starting noise moves between keys",
                    default="fixed"),
    "drift": Field(Float(-10.0, 10.0), "animation, latent drift: radians per frame", default="0.05"),
}, "a neural source")

SOLID_SOURCE = Table({
    "kind": Field(Choice(("solid",)), "a solid texture from a photo (Henzler et al. 2020)", True),
    "method": Field(Choice(METHODS), "neural solid, 2D synthesis, spectral solid, procedural solid, or auto (procedural where closer and as structured, else neural)", default="neural; procedural for a saved procedural solid (.json)"),
    "model": Field(FILE, "a shipped model's name or a model folder", default="chosen from the exemplar"),
    "exemplar": Field(FILE, "the photo (an image file or a training exemplar's name); method procedural: also a "
                            "solid saved as .json (omninoise solid -o)"),
    "to": Field(FILE, "a second exemplar to mix towards"),
    "mix": Field(Float(0.0, 1.0), "share of the second exemplar", default="0.5"),
    "refine": Field(Int(0, limits.MAX_REFINE), "search steps refining the encoded code", default="0"),
    "seed": Field(SEED, "random seed", default="0"),
    "periodic": Field(Bool(), "keep the photo's periodic part (courses, planks)", default="true"),
    "gaussian": Field(Bool(), "mix in the photo's Gaussian rest where it is closer", default="true"),
    "rest": Field(Choice(REST_CHOICES), "the kind of Gaussian rest", default="auto"),
    "tile": Field(Int(MIN_TILE, MAX_TILE), "synthesis: the periodic image's side, px (a multiple of 4)",
                  default="256"),
    "families": Field(ListOf(Choice(KINDS), 1, len(KINDS)),
                      "procedural and auto: the kinds of solid the fit tries (herringbone: bricks laid in a "
                      "herringbone)", default=json.dumps(list(DEFAULT_KINDS))),
    "scale": Field(Float(*limits.SCALE_RANGE), "texture units per world unit", default="1"),
    "density": Field(Float(0.0, 1e6), "a volume's constant density", default="1"),
}, "a solid source")

#: ``kind`` -> the table of a ``[bake.source]`` of that kind (a registered kind without one is checked by its
#: builder alone)
SOURCE_TABLES = {"wave": WAVE_SOURCE, "neural": NEURAL_SOURCE, "solid": SOLID_SOURCE}

BAKE = Table({
    "name": Field(Text("a name", 256), "unique in the job; used in messages and --only", default="bake N"),
    "output": Field(FILE, "the file written: .vdb, .exr, .png or .npy; '#' is the frame number", True),
    "resolution": Field(ListOf(Int(1, 1 << 20), 2, 3), "[nx, ny] for an image, [nx, ny, nz] for a volume", True),
    "bounds": Field(Items((ListOf(COORD, 3, 3), ListOf(COORD, 3, 3)),
                          f"[[x0, y0, z0], [x1, y1, z1]], each {COORD.describe()}"),
                    "the world box sampled, voxel-centred", default="[[0, 0, 0], [1, 1, 1]]"),
    "transfer": Field(AnyOf((Text("a preset name or a ramp .json file"), TRANSFER)),
                      "colour and density from the noise value"),
    "frames": Field(Items((Int(-10 ** 9, 10 ** 9), Int(-10 ** 9, 10 ** 9)),
                          "[first, last], whole numbers in [-1000000000, 1000000000]"),
                    "a numbered sequence of frames, inclusive"),
    "time": Field(Float(-limits.MAX_TIME, limits.MAX_TIME), "time (4D: W) of the first frame, for an animated source",
                  default="0"),
    "time_step": Field(Float(0.0, limits.MAX_TIME, above=True), "time between frames, for a bake with frames",
                       default="1/24"),
    "half": Field(Bool(), ".exr and .vdb: 16-bit half floats", default="false"),
    "source": Field(Table(what="a [bake.source] table"), "what is baked; see the source tables below", True),
}, "a [[bake]] table")

JOB = Table({
    "output_root": Field(FILE, "the folder outputs must lie in", default="the job file's folder"),
    "defaults": Field(Table(what="a [defaults] table"), "keys merged into every bake (a bake's own keys win)"),
    "bake": Field(ListOf(Table(what="a [[bake]] table"), 1, 10_000), "the bakes, run in order", True),
}, "a job file")
