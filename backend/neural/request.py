"""One neural-noise image, whatever asked for it: the typed request the command line, job files and the Blender
panel all build, and the one place that turns it into a conditioning grid and an image.

A request is a layout of class specs (Maesumi et al. 2024, Sec. 3.2: a uniform class, a mask blend of two, a
left-to-right gradient of two, the bilinear four-corner blend of Fig. 4, or a painted map of any number) plus the sampler settings. Front-ends parse
their own syntax (flags, TOML keys, panel properties) into it; :meth:`NeuralRequest.check` validates what they
share (classes, parameters, map sizes, sampler), :meth:`NeuralRequest.conditioning` builds the grid and
:func:`generate_request` the image. :meth:`NeuralRequest.key` is a JSON summary (maps by sha256): equal settings
from any front-end give equal keys (tests/cli/test_neural_request.py), and bakes store it to skip up-to-date files.

Shapes: ``mask`` bool (h, w), True where the second spec is; ``regions`` int (h, w), each pixel's index into
``specs``: at the image's size (H, W) or any other of its proportions, drawn at the image's size by nearest pixel
(:func:`map_at`), with transitions measured in the map's pixels (a map painted at 512 px and drawn at 2048 keeps
its transitions' look); images float32 (H, W) in [0, 1], rows top to bottom.
"""
from __future__ import annotations

import hashlib
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ..errors import SettingError
from . import conditioning as C
from .sampler import DEFAULT_SAMPLER, DEFAULT_STEPS, sampler_eta

__all__ = ["LAYOUTS", "NeuralRequest", "check_specs", "generate_request", "regions_from_colours", "region_key",
           "regions_from_map", "map_error", "map_at", "READ_BY", "check_layout_reads"]

#: layout -> how many specs it takes (None: any number, one per painted region)
LAYOUTS = {"uniform": 1, "blend": 2, "gradient": 2, "corners": 4, "painted": None}


#: the settings (a job's keys) that only some ways of laying out an image's classes read -> (those layouts, what
#: the setting does; ``{name}`` a setting's name as the front end shows it). ``animated`` is an animation's: its
#: keyframes set the classes
READ_BY = {
    "noise": (("uniform", "blend"), "is the class of the whole image, or of a blend's unmasked part"),
    "params": (("uniform", "blend"), "sets the parameters of {noise}"),
    "noise2": (("blend",), "is the class of a blend's masked part"),
    "params2": (("blend",), "sets the parameters of {noise2}"),
    "width": (("blend", "painted"), "shapes the transitions of {blend} and {map}"),
    "sharpness": (("blend", "painted"), "shapes the transitions of {blend} and {map}"),
    "regions": (("painted",), "names the colours of {map}"),
    "latent": (("animated",), "moves the starting noise from frame to frame of {keys}"),
    "drift": (("animated",), "moves the starting noise from frame to frame of {keys}"),
}
#: the setting that lays the classes out in each layout but the uniform one
CHOSEN_BY = {"blend": "blend", "gradient": "gradient", "corners": "corners", "painted": "map", "animated": "keys"}


def check_layout_reads(layout: str, given, shown: Callable[[str], str] = str) -> None:
    """SettingError naming the first of ``given`` (:data:`READ_BY` names) that an image laid out as ``layout`` (a
    :data:`LAYOUTS` name, ``animated``, or a front end's own whose chooser ``shown`` names) does not read: it would
    change nothing, and the image would not be the one asked for. ``shown(name)`` writes a setting's name as the
    front end does (a job's key, a flag)."""
    for key in given:
        if key not in READ_BY or layout in READ_BY[key][0]:
            continue
        layouts, does = READ_BY[key]
        choosers = [shown(CHOSEN_BY[name]) for name in layouts if name in CHOSEN_BY]
        here = (f"with {shown(CHOSEN_BY.get(layout, layout))}" if layout != "uniform"
                else f"without {' or '.join(choosers)}")
        does = does.format(**{name: shown(name) for name in ("noise", "noise2", "blend", "map", "keys")})
        raise SettingError(shown(key), f"{does}; {here}, it would change nothing")


def check_specs(model, specs, names) -> None:
    """Each class spec (name, params) of ``specs`` known to ``model`` with its parameters in range; else the
    SettingError naming the setting that gave it: ``names`` holds, spec by spec, (the setting of its class, the
    setting of its parameters), as a front end calls them (``--noise2`` and ``--param2``; ``source.corners[2]``)."""
    for spec, (noise, params) in zip(specs, names):
        try:
            model.param_vector(*spec)
        except SettingError as exc:
            raise SettingError(noise if exc.setting == "noise" else params, exc.message) from None


def map_error(arr, height: int, width: int, what: str, image: str = "the image",
              at: str = "the image's size") -> str | None:
    """Why the ``what`` ("mask" or "map") ``arr`` (h, w, ...; None: not given) cannot draw a ``width`` x ``height``
    image, in the words of its caller (``image`` and where it is drawn, ``at``), or None where it can: its own size,
    or another of the image's proportions (within one pixel of the image's height at its width)."""
    if arr is not None:
        h, w = arr.shape[:2]
        if (h, w) == (height, width) or (h > 0 and w > 0 and abs(h * width / w - height) < 1.0):
            return None
    got = "none" if arr is None else f"{arr.shape[1]}x{arr.shape[0]}"
    return f"{what} is {got} but {image} is {width}x{height}: a {what} is drawn at {at} and must have its proportions"


def map_at(arr: np.ndarray, height: int, width: int) -> tuple:
    """(``arr`` (h, w) drawn at (height, width) by nearest pixel, the factor its pixels grow by): a painted region
    keeps its index and a mask its two values, with no value between (blurring is the transitions' work)."""
    h, w = arr.shape[:2]
    if (h, w) == (height, width):
        return arr, 1.0
    return arr[(np.arange(height) * h // height)[:, None], (np.arange(width) * w // width)[None, :]], width / w


def _spec(s) -> tuple:
    """A (class, {parameter: value}) pair with its values as floats: SettingError naming ``param`` for parameters
    that are no table of numbers (front ends check names and ranges against the model)."""
    try:
        name, params = s
    except (TypeError, ValueError):
        raise SettingError("noise", f"expected a (class, parameters) pair, got {s!r}") from None
    if params is None:
        params = {}
    if not isinstance(params, dict):
        raise SettingError("param", f"expected a table of parameter values, got {params!r}")
    bad = [k for k, v in params.items() if isinstance(v, bool) or not isinstance(v, (int, float, np.number))]
    if bad:
        raise SettingError("param", f"{bad[0]}: expected a number, got {params[bad[0]]!r}")
    return str(name), {str(k): float(v) for k, v in params.items()}


@dataclass(frozen=True, eq=False)
class NeuralRequest:
    """A neural-noise image: ``layout`` of ``specs`` ((class, {parameter: value}) pairs), ``width`` x ``height``
    pixels, transitions of ``transition`` px of the mask or map with exponent ``sharpness`` (blend and painted
    layouts), and the sampler settings of :func:`backend.neural.generate.generate`."""

    layout: str
    specs: tuple
    width: int
    height: int
    mask: np.ndarray | None = field(default=None, repr=False)
    regions: np.ndarray | None = field(default=None, repr=False)
    transition: float = 32.0
    sharpness: float = 1.0
    seed: int = 0
    steps: int = DEFAULT_STEPS
    sampler: str = DEFAULT_SAMPLER
    spacing: str | None = None
    eta: float | None = None
    tileable: bool = False
    tile: int | None = None

    def __post_init__(self):
        object.__setattr__(self, "specs", tuple(_spec(s) for s in self.specs))
        if self.mask is not None:
            object.__setattr__(self, "mask", np.asarray(self.mask) > 0.5)
        if self.regions is not None:
            object.__setattr__(self, "regions", np.asarray(self.regions, np.int64))

    # -- validation -------------------------------------------------------------------------
    def check(self, model) -> "NeuralRequest":
        """SettingError naming the field (layout, noise, map, size, steps, sampler ...) when the request cannot
        be generated by ``model``; the request itself when it can."""
        from .generate import check_sampler

        if self.layout not in LAYOUTS:
            raise SettingError("layout", f"unknown layout {self.layout!r}; choose one of {', '.join(LAYOUTS)}")
        need = LAYOUTS[self.layout]
        if need is not None and len(self.specs) != need:
            raise SettingError("noise", f"a {self.layout} layout takes {need} class specs, got {len(self.specs)}")
        if not self.specs:
            raise SettingError("noise", "no class: give at least one")
        if self.width < 8 or self.height < 8:
            raise SettingError("size", f"must be >= 8, got {self.width}x{self.height}")
        for s in self.specs:
            model.param_vector(*s)  # unknown classes or parameters, with their names
        for layout, key, what, arr in (("blend", "blend", "mask", self.mask), ("painted", "map", "map", self.regions)):
            why = map_error(arr, self.height, self.width, what) if self.layout == layout else None
            if why is not None:
                raise SettingError(key, why)
        if self.layout == "painted":
            if self.regions.min() < 0 or self.regions.max() >= len(self.specs):
                raise SettingError("map", f"region indices must lie in [0, {len(self.specs)}), "
                                          f"got {self.regions.min()}..{self.regions.max()}")
        from ..settings_schema import NEURAL_SOURCE     # the job file's rules, whichever front end asks

        f = NEURAL_SOURCE.fields
        for key, value in (("width", self.transition), ("sharpness", self.sharpness), ("seed", self.seed),
                           ("tileable", self.tileable)):
            f[key].type.check(value, key)
        check_sampler(self.sampler, self.steps, self.spacing, self.eta)
        k = model.multiple_of
        if self.tileable and (self.width % k or self.height % k):
            raise SettingError("size", f"tileable output needs sides that are multiples of {k}, got "
                                       f"{self.width}x{self.height}")
        return self

    # -- the grid ----------------------------------------------------------------------------
    def conditioning(self, model) -> np.ndarray:
        """float32 (E + P, height, width) conditioning grid."""
        H, W = self.height, self.width
        if self.layout == "uniform":
            return C.uniform(model, self.specs[0], H, W)
        if self.layout == "blend":
            mask, grow = map_at(self.mask, H, W)
            return C.blend(model, self.specs[0], self.specs[1], C.mask_weight(mask, self.transition * grow,
                                                                             self.sharpness))
        if self.layout == "gradient":  # the first spec on the left blending linearly into the second on the right
            w = np.broadcast_to(np.linspace(0.0, 1.0, W, dtype=np.float32)[None, :], (H, W))
            return C.blend(model, self.specs[0], self.specs[1], w)
        if self.layout == "corners":
            return C.four_corner(model, list(self.specs), H, W)
        regions, grow = map_at(self.regions, H, W)
        present = sorted(int(i) for i in np.unique(regions))
        return C.painted(model, regions, {i: self.specs[i] for i in present}, self.transition * grow, self.sharpness)

    def key(self) -> dict:
        """A JSON summary: every setting, maps by sha256 (equal keys: equal images)."""
        d = dict(layout=self.layout, specs=[[n, dict(sorted(p.items()))] for n, p in self.specs], width=self.width,
                 height=self.height, seed=self.seed, steps=self.steps, sampler=self.sampler, spacing=self.spacing,
                 eta=sampler_eta(self.sampler, self.eta), tileable=self.tileable)
        if self.layout in ("blend", "painted"):
            d.update(transition=self.transition, sharpness=self.sharpness)
            arr = self.mask if self.layout == "blend" else self.regions
            d["map_sha256"] = hashlib.sha256(np.ascontiguousarray(arr).tobytes()).hexdigest()
            if arr.shape != (self.height, self.width):      # the bytes alone do not tell a 64x32 map from 32x64
                d["map_size"] = [arr.shape[1], arr.shape[0]]
        return d


def generate_request(model, req: NeuralRequest, callback: Callable | None = None,
                     x_T: np.ndarray | None = None) -> np.ndarray:
    """The request's image float32 (height, width) in [0, 1] (rows top to bottom)."""
    from .generate import generate

    req.check(model)
    return generate(model, req.conditioning(model), req.seed, req.steps, req.tileable, callback=callback,
                    sampler=req.sampler, spacing=req.spacing, eta=req.eta, tile=req.tile, x_T=x_T)


def regions_from_colours(rgb: np.ndarray, colours: list, tolerance: float | None = None,
                         where: str = "map") -> np.ndarray:
    """A painted colour map float (H, W, 3) in [0, 1] -> region indices int (H, W) into ``colours`` (0-1 RGB).

    ``tolerance`` None: every pixel must be one of the colours at 8 bits (files, whose colours are exact);
    SettingError naming the first colour that has none. A number: the nearest colour, and SettingError if more
    than 1 % of the pixels lie farther than ``tolerance`` (max over channels) from every colour (paintings, whose
    brush edges blend colours)."""
    px = np.asarray(rgb, np.float32)[..., :3]
    cols = np.asarray(colours, np.float32).reshape(-1, 3)
    if tolerance is None:
        q = np.rint(np.clip(px, 0, 1) * 255).astype(np.int64)
        cq = np.rint(np.clip(cols, 0, 1) * 255).astype(np.int64)
        code = (q[..., 0] << 16) | (q[..., 1] << 8) | q[..., 2]
        ccode = (cq[:, 0] << 16) | (cq[:, 1] << 8) | cq[:, 2]
        out = np.full(code.shape, -1, np.int64)
        for i, c in enumerate(ccode):
            out[code == c] = i
        if (out < 0).any():
            y, x = np.argwhere(out < 0)[0]
            raise _unmatched(where, tuple(int(v) for v in q[y, x]), code[out < 0], "colours", (x, y))
        return out
    d = np.abs(px[:, :, None, :] - cols[None, None]).max(-1)  # (H, W, colours)
    nearest, err = d.argmin(-1), d.min(-1)
    if np.mean(err > tolerance) > 0.01:
        raise SettingError(where, f"{np.mean(err > tolerance) * 100:.0f}% of the map matches no swatch colour; "
                                  "paint with the swatch colours")
    return nearest.astype(np.int64)


def region_key(key: str, where: str = "region"):
    """A painted map's region key: '#rrggbb' -> (r, g, b) 8-bit, '17' -> grey level 17."""
    key = str(key).strip()
    if key.startswith("#"):
        try:
            if len(key) != 7:
                raise ValueError(key)
            return tuple(int(key[i: i + 2], 16) for i in (1, 3, 5))
        except ValueError:
            raise SettingError(where, f"bad colour {key!r}; use #rrggbb") from None
    try:
        k = int(key)
    except ValueError:
        raise SettingError(where, f"bad index {key!r}; use 0-255 or #rrggbb") from None
    if not 0 <= k <= 255:
        raise SettingError(where, f"bad index {key!r}; use 0-255 or #rrggbb")
    return k


def regions_from_map(px: np.ndarray, keys: list, where: str = "map") -> np.ndarray:
    """A painted map file's pixels float (H, W, C) in [0, 1] and its region keys (:func:`region_key`) -> region
    indices int (H, W). Keys are 8-bit values: any '#rrggbb' key reads the map as colours, else as grey levels
    (0.299 R + 0.587 G + 0.114 B); a pixel of no key is an error naming its value."""
    px = np.asarray(px, np.float32)
    px = px[..., :3] if px.shape[2] >= 3 else np.repeat(px[..., :1], 3, axis=2)
    img = np.rint(np.clip(px, 0, 1) * 255.0).astype(np.uint8)
    if any(isinstance(k, tuple) for k in keys):
        cols = [np.array(k, np.float32) / 255.0 if isinstance(k, tuple) else np.full(3, k / 255.0, np.float32)
                for k in keys]
        return regions_from_colours(img.astype(np.float32) / 255.0, cols, None, where)
    grey = np.rint(img.astype(np.float32) @ np.array([0.299, 0.587, 0.114], np.float32)).astype(np.uint8)
    regions = np.full(grey.shape, -1, np.int64)
    for i, k in enumerate(keys):
        regions[grey == k] = i
    if (regions < 0).any():
        y, x = np.argwhere(regions < 0)[0]
        raise _unmatched(where, int(grey[y, x]), grey[regions < 0], "grey levels", (x, y))
    return regions


def _unmatched(where: str, first, values: np.ndarray, noun: str, at: tuple) -> SettingError:
    """The error of a map's pixels of no key: the first one's value and place ``at`` (x, y: px from the top left
    of the file, as image editors count), and where there are more such values, how many and on how many pixels
    (a map painted with soft or anti-aliased edges blends its regions' colours)."""
    kinds = len(np.unique(values))
    place = f"the first at x {int(at[0])}, y {int(at[1])} from the top left"
    more = (f" (on {values.size} px, {place})" if kinds == 1 else
            f" ({kinds} {noun} have none, on {values.size} px, {place}: paint the map with hard edges, one flat "
            "colour per region, or give each a spec)")
    return SettingError(where, f"the map uses {first} but no spec is given for it{more}")
