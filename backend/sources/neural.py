"""Neural noise (Maesumi et al. 2024) as a bake source, and its job table (``kind = "neural"``)."""
from __future__ import annotations

import hashlib

import numpy as np

from .. import limits
from ..errors import SettingError
from ..paths import in_job
from .base import check_keys, job_image

__all__ = ["NeuralSource", "from_dict", "spec_value"]

#: the keys of a job's neural source table
KEYS = ("model", "noise", "params", "noise2", "params2", "blend", "width", "sharpness", "sampler", "steps", "seed",
        "tileable", "keys", "latent", "drift", "gradient", "corners", "map", "regions")


class NeuralSource:
    """Neural noise (Maesumi et al. 2024) as a 2D bake source: any layout of a
    :class:`backend.neural.request.NeuralRequest` (one class, a mask blend of two, two from left to right, four
    corners, a painted map), or keyframed classes (animation).

    The whole image is denoised at once (``chunkable`` is False); progress is per
    sampler step and cancel is polled after each step.  Pixels are the model's
    pixels: the grid's resolution is the image size and its bounds only place it.
    Image rows run top to bottom like the maps', so a mask lines up with the file
    a bake writes.
    """

    kind = "neural"
    dim = 2
    animated = False
    chunkable = False
    unit = True
    animated_by = "give keys: keyframes of its classes"

    def __init__(self, model_folder: str, noise: str, params: dict | None = None, noise2: str | None = None,
                 params2: dict | None = None, mask: np.ndarray | None = None, width: float = 32.0,
                 sharpness: float = 1.0, steps: int | None = None, seed: int = 0, tileable: bool = False,
                 sampler: str | None = None, keys: list | None = None, latent: str = "fixed", drift: float = 0.05,
                 corners: list | None = None, regions: np.ndarray | None = None, region_specs: list | None = None,
                 gradient: list | None = None, colours: list | None = None):
        from ..neural.generate import check_sampler
        from ..neural.model import ModelError, NeuralNoiseModel
        from ..neural.sampler import DEFAULT_SAMPLER, DEFAULT_STEPS

        self.sampler = DEFAULT_SAMPLER if sampler is None else sampler
        steps = DEFAULT_STEPS if steps is None else steps
        try:
            check_sampler(self.sampler, steps)
        except SettingError as exc:
            raise SettingError("source." + exc.setting, exc.message) from None

        try:
            self.model = NeuralNoiseModel(model_folder)
        except ModelError as exc:
            raise SettingError("source.model", str(exc)) from None
        self.spec = (noise, dict(params or {}))
        self.spec2 = None if mask is None else (noise2 or noise, dict(params2 or {}))
        self.mask = None if mask is None else np.asarray(mask, np.float32)
        self.regions = None if regions is None else np.asarray(regions, np.int64)
        #: the painted map's colours, one 8-bit (r, g, b) per region spec, or None: how a job file written from
        #: this source paints its map (:mod:`backend.job_file`); the regions, not their colours, set the image
        self.colours = None if colours is None else [tuple(int(v) for v in c) for c in colours]
        if corners is not None:
            self.layout, self.specs = "corners", [tuple(c) for c in corners]
        elif gradient is not None:
            self.layout, self.specs = "gradient", [tuple(c) for c in gradient]
        elif self.regions is not None:
            self.layout, self.specs = "painted", [tuple(c) for c in region_specs]
        elif self.mask is not None:
            self.layout, self.specs = "blend", [self.spec, self.spec2]
        else:
            self.layout, self.specs = "uniform", [self.spec]
        self.width, self.sharpness = float(width), float(sharpness)
        self.steps, self.seed, self.tileable = int(steps), int(seed), bool(tileable)
        if not keys:    # unknown classes / parameters fail now, named by the key that gave them; keyframes below
            from ..neural.request import check_specs

            check_specs(self.model, self.specs, self._spec_keys(noise2))
        # animation: keyframes whose `frame` is the bake's time (a job sets time = frame number)
        from ..neural.animate import LATENT_MODES, check_keys

        self.keys = list(keys) if keys else None
        self.animated = self.keys is not None
        self.latent, self.drift = str(latent), limits.finite("source.drift", drift)
        if self.keys is not None:
            if self.layout != "uniform":
                raise SettingError("source.keys", "keyframes set the classes of the whole image; leave out blend, "
                                                  "corners and map")
            if self.latent not in LATENT_MODES:
                raise SettingError("source.latent", f"unknown latent motion {self.latent!r}; choose one of "
                                                    f"{', '.join(LATENT_MODES)}")
            check_keys(self.model, self.keys, "source.keys")

    def _spec_keys(self, noise2: str | None) -> list:
        """(key of the class, key of its parameters) of each of :attr:`specs`, as a job file names them."""
        if self.layout in ("corners", "gradient"):
            return [(f"source.{self.layout}[{i}]",) * 2 for i in range(len(self.specs))]
        if self.layout == "painted":
            return [("source.regions",) * 2] * len(self.specs)
        second = [("source.noise2" if noise2 else "source.noise", "source.params2")] if self.layout == "blend" else []
        return [("source.noise", "source.params")] + second

    @classmethod
    def from_request(cls, model_folder: str, req, colours: list | None = None) -> "NeuralSource":
        """The source that draws the checked :class:`~backend.neural.request.NeuralRequest` ``req`` (a front end's
        image, the Neural Noise panel's) on a ``req.width`` x ``req.height`` grid: the same conditioning, sampler
        and seed. ``colours`` (painted layout): the 8-bit colour of each region, for a job file's map. SettingError
        for a request's setting a source has no key for (a step spacing, an eta, a tile size)."""
        for name in ("spacing", "eta", "tile"):
            if getattr(req, name) is not None:
                raise SettingError(name, "a bake source (a job file) has no such setting (its bake takes the default): "
                                         "leave it out")
        kw = dict(width=req.transition, sharpness=req.sharpness, steps=req.steps, seed=req.seed,
                  tileable=req.tileable, sampler=req.sampler)
        specs = [(n, dict(p)) for n, p in req.specs]
        if req.layout == "blend":
            kw.update(noise2=specs[1][0], params2=specs[1][1], mask=np.asarray(req.mask, np.float32))
        elif req.layout in ("gradient", "corners"):
            kw[req.layout] = specs
        elif req.layout == "painted":
            kw.update(regions=req.regions, region_specs=specs, colours=colours)
        return cls(model_folder, *specs[0], **kw)

    def check_grid(self, shape) -> None:
        """SettingError before anything runs when the grid cannot be baked: not an image, or a blend mask or
        painted map of other proportions (one of another size with the same is drawn at the resolution)."""
        from ..neural.request import map_error

        if len(shape) != 2:
            raise SettingError("grid", "neural noise bakes images (resolution [width, height])")
        for key, what, arr in (("blend", "mask", self.mask), ("map", "map", self.regions)):
            why = None if arr is None else map_error(arr, *shape, what, "the resolution", "the resolution")
            if why is not None:
                raise SettingError(f"source.{key}", why)

    def request(self, shape):
        """The :class:`backend.neural.request.NeuralRequest` of this source on an (H, W) grid (not animated)."""
        from ..neural.request import NeuralRequest

        self.check_grid(shape)
        H, W = shape
        return NeuralRequest(self.layout, self.specs, W, H, mask=None if self.mask is None else self.mask > 0.5,
                             regions=self.regions, transition=self.width, sharpness=self.sharpness, seed=self.seed,
                             steps=self.steps, sampler=self.sampler, tileable=self.tileable)

    def evaluate(self, shape, first, step, time, progress=None, cancel=None, start=None) -> np.ndarray:
        from ..grid import Cancelled
        from ..neural.request import generate_request

        def step_done(i, n, x0):
            if progress is not None:
                progress((i + 1) / n)
            if cancel is not None and cancel():
                raise Cancelled("cancelled")

        if self.keys is None:
            try:
                img = generate_request(self.model, self.request(shape), callback=step_done)
            except SettingError as exc:
                raise SettingError("source." + exc.setting, exc.message) from None
            return np.ascontiguousarray(img[::-1])  # bakes index rows by +y; files put +y at the top
        from ..neural.animate import frame_image

        self.check_grid(shape)
        img = frame_image(self.model, self.keys, float(time), *shape, self.latent, self.drift, seed=self.seed,
                          steps=self.steps, tileable=self.tileable, callback=step_done, sampler=self.sampler)
        return np.ascontiguousarray(img[::-1])

    def to_dict(self) -> dict:
        d = dict(kind=self.kind, model=self.model.config["files"], layout=self.layout,
                 specs=[[n, dict(sorted(p.items()))] for n, p in self.specs], sampler=self.sampler, steps=self.steps,
                 seed=self.seed, tileable=self.tileable)
        if self.layout in ("blend", "painted"):
            arr = self.mask > 0.5 if self.layout == "blend" else self.regions     # what the request reads
            d.update(width=self.width, sharpness=self.sharpness,
                     map_sha256=hashlib.sha256(np.ascontiguousarray(arr).tobytes()).hexdigest())
        if self.keys is not None:
            d.update(keys=[[k.frame, k.noise, k.params, k.seed] for k in self.keys], latent=self.latent)
            if self.latent == "drift":      # the other motions do not read its speed
                d["drift"] = self.drift
        return d


def from_dict(d: dict, base_dir: str) -> NeuralSource:
    import os

    from ..neural.request import check_layout_reads

    check_keys(d, KEYS, "neural")
    layouts = [k for k in ("blend", "gradient", "corners", "map") if k in d]
    if len(layouts) > 1:
        raise SettingError(f"source.{layouts[1]}",
                           f"choose one of blend, gradient, corners and map (got {' and '.join(layouts)})")
    # keys beside blend, gradient, corners or map: NeuralSource refuses the pair
    layout = "animated" if "keys" in d else {"map": "painted"}.get(layouts[0], layouts[0]) if layouts else "uniform"
    try:
        check_layout_reads(layout, list(d))     # a key this layout does not read: the image would not be the one asked
    except SettingError as exc:
        raise exc.under("source") from None
    keys = None
    if "keys" in d:  # animation: a keyframe file (relative to the job) or an inline list of [[key]] tables
        from ..neural.animate import parse_keys, read_keys

        if isinstance(d["keys"], str):
            keys = read_keys(in_job(base_dir, d["keys"]), "source.keys")
        elif isinstance(d["keys"], list):
            keys = parse_keys({"key": d["keys"]}, "source.keys")
        else:
            raise SettingError("source.keys", f"expected a keyframe file or a list of tables, got {d['keys']!r}")
        d.setdefault("noise", keys[0].noise)
        d.setdefault("params", keys[0].params)
    if "noise" not in d and "gradient" not in d and "corners" not in d and "map" not in d:
        raise SettingError("source.noise", "a neural source needs noise = CLASS (or gradient, corners, or map and "
                                           "regions)")
    from ..paths import neural_model

    model = in_job(base_dir, d["model"]) if "model" in d else neural_model()
    corners = regions = region_specs = gradient = colours = None
    if "gradient" in d:
        g = d["gradient"]
        if not isinstance(g, list) or len(g) != 2:
            raise SettingError("source.gradient", f"expected two class specs (left, right), got {g!r}")
        gradient = [spec_value(v, f"source.gradient[{i}]") for i, v in enumerate(g)]
    if "corners" in d:
        c = d["corners"]
        if not isinstance(c, list) or len(c) != 4:
            raise SettingError("source.corners", f"expected four class specs (top-left, top-right, bottom-left, "
                                                 f"bottom-right), got {c!r}")
        corners = [spec_value(v, f"source.corners[{i}]") for i, v in enumerate(c)]
    if "map" in d:
        from ... import export
        from ..neural.request import region_key, regions_from_map

        if not isinstance(d["map"], str):
            raise SettingError("source.map", f"expected an image file name, got {d['map']!r}")
        path = in_job(base_dir, d["map"])
        if not os.path.isfile(path):
            raise SettingError("source.map", f"map not found: {path}")
        table = d.get("regions")
        if not isinstance(table, dict) or not table:
            raise SettingError("source.regions", "a map needs regions = {\"#rrggbb\" = SPEC, ...} for its colours")
        region_keys = [region_key(k, "source.regions") for k in table]
        colours = [k if isinstance(k, tuple) else (k, k, k) for k in region_keys]     # a grey level as its grey
        region_specs = [spec_value(v, f"source.regions.{k}") for k, v in table.items()]
        try:
            regions = regions_from_map(export.decode(path), region_keys, "source.map")
        except export.ImageError as exc:
            raise SettingError("source.map", str(exc)) from None
    if gradient is not None or corners is not None or regions is not None:
        d.setdefault("noise", (gradient or corners or region_specs)[0][0])
    mask = None
    if "blend" in d:
        mask = job_image(base_dir, d["blend"], "blend", "mask")
    return NeuralSource(model, d["noise"], d.get("params"), d.get("noise2"), d.get("params2"), mask,
                        d.get("width", 32.0), d.get("sharpness", 1.0), d.get("steps"), d.get("seed", 0),
                        d.get("tileable", False), d.get("sampler"), keys, d.get("latent", "fixed"),
                        d.get("drift", 0.05), corners, regions, region_specs, gradient, colours)


def spec_value(v, where: str) -> tuple:
    """A class spec of a job file: "CLASS" / "CLASS:NAME=V,..." (as the command line) or {noise, params}."""
    if isinstance(v, str):
        name, _, rest = v.partition(":")
        params = {}
        for item in filter(None, rest.split(",")):
            k, sep, val = item.partition("=")
            try:
                params[k.strip()] = float(val) if sep else float("nan")
            except ValueError:
                raise SettingError(where, f"expected NAME=VALUE with a number, got {item!r}") from None
            if not sep or not np.isfinite(params[k.strip()]):
                raise SettingError(where, f"expected NAME=VALUE with a finite number, got {item!r}")
        return name.strip(), params
    if isinstance(v, dict) and isinstance(v.get("noise"), str) and set(v) <= {"noise", "params"}:
        params = v.get("params", {})
        if not isinstance(params, dict) or not all(isinstance(x, (int, float)) and not isinstance(x, bool)
                                                   and np.isfinite(x) for x in params.values()):
            raise SettingError(where, f"params: expected a table of finite numbers, got {params!r}")
        return v["noise"], {str(k): float(x) for k, x in params.items()}
    raise SettingError(where, f"expected \"CLASS:NAME=VALUE,...\" or {{noise = CLASS, params = {{...}}}}, got {v!r}")
