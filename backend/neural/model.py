"""The exported neural noise model, run by onnxruntime (no torch).

A model folder holds ``neural_noise.json`` and, by its ``form`` (see
``training/export_onnx.py``), either ``encoder.onnx`` + ``denoiser.onnx``
(``split``: the conditioning's SPADE maps are computed once per image and only
the denoiser runs at every step) or one ``eps.onnx`` (``one-piece``, the form of
older exports, still loaded).  Loading checks every file's sha256 against the
JSON before onnxruntime sees it; sessions are created on first use.  The graphs'
``tile`` input switches every convolution between zero and circular padding
(seamless tiles).  A split export may also hold int8 denoisers (``training/quantize_onnx.py``), run when
``precision`` is int8 (:mod:`.precision`: a faster draft mode; float32 is the default).
"""
from __future__ import annotations

import numpy as np

from ..errors import SettingError
from ..onnx_models import ModelError, SessionCache, fingerprint, load_model_json, sha256_file, verify_files
from .precision import resolve as resolve_precision
from .schedule import alphas_from_config

__all__ = ["NeuralNoiseModel", "ModelError", "PrecisionUnavailable", "sha256_file"]

_F = np.float32


class PrecisionUnavailable(ModelError):
    """The model folder cannot run the requested precision (no int8 denoisers, or damaged ones); the
    float32 model itself is fine."""


def _tile_flag(tileable: bool) -> np.ndarray:
    """The graphs' ``tile`` input: [1.0] circular padding (seamless tiles), [0.0] zero padding."""
    return np.array([1.0 if tileable else 0.0], _F)


class NeuralNoiseModel:
    """ε-network plus what the sampler and the conditioning need.

    classes      class names (index = class id)
    params       names of the shared parameter vector
    embedding    float32 (n_classes, E) class embeddings
    """

    def __init__(self, folder: str, threads: int = 0, precision: str | None = None):
        self.config = load_model_json(folder, "neural_noise.json")
        self.folder = folder
        self.classes = tuple(self.config["classes"])
        self.params = tuple(self.config["params"])
        self.class_params = self.config["class_params"]
        self.embedding = np.asarray(self.config["class_embedding"], _F)
        self.multiple_of = int(self.config.get("multiple_of", 8))
        self.form = self.config.get("form", "one-piece")
        need = {"split": ("encoder.onnx", "denoiser.onnx"), "one-piece": ("eps.onnx",)}.get(self.form)
        if need is None:
            raise ModelError(f"{folder}: unknown model form {self.form!r}")
        missing = [n for n in need if n not in self.config.get("files", {})]
        if missing:
            raise ModelError(f"{folder}: neural_noise.json lists no sha256 for {missing[0]}")
        #: one sha256 for the weights, whatever the form (see backend.onnx_models.fingerprint)
        self.fingerprint = fingerprint(self.config["files"])
        if self.config.get("prediction", "epsilon") != "epsilon":
            raise ModelError(f"{folder}: prediction {self.config['prediction']!r} is not supported (epsilon only)")
        try:
            #: float64 (T,) ᾱ of the schedule the JSON declares
            self.alphas_cumprod = alphas_from_config(self.config.get("schedule", {"kind": "cosine"}))
        except ValueError as exc:
            raise ModelError(f"{folder}: {exc}") from None
        self.threads = threads
        int8 = self.config.get("int8") or {}
        #: "fp32" or "int8": the denoiser's arithmetic (None: the default, see .precision)
        self.precision = resolve_precision(precision)
        if self.precision == "int8":
            if self.form != "split":
                raise PrecisionUnavailable(f"{folder}: int8 needs a split export (this one is {self.form})")
            try:
                self._check_int8(folder, int8)
            except PrecisionUnavailable:
                raise
            except ModelError as exc:  # a damaged int8 file: the precision is what cannot run
                raise PrecisionUnavailable(str(exc)) from None
        # no CPU arena: at 1024² it kept 11.8 GB against 4.4 GB without, with steps no slower (bench_neural.py),
        # and inside Blender the arena would hold that memory after every bake
        self._sessions = SessionCache(folder, threads, arena=False)

    @staticmethod
    def _check_int8(folder: str, int8: dict) -> None:
        """ModelError unless the folder's int8 denoisers exist and match their sha256 in the JSON."""
        if not int8.get("files"):
            raise PrecisionUnavailable(f"{folder}: no int8 denoisers (make them with python -m omninoise.training.quantize_onnx {folder})")
        verify_files(folder, int8["files"], "neural_noise.json")

    def denoiser_name(self, tileable: bool) -> str:
        """The denoiser file a split export runs: per padding, and int8 when :attr:`precision` says so."""
        files = self.config["files"]
        name = "denoiser_tile.onnx" if tileable and "denoiser_tile.onnx" in files else "denoiser.onnx"
        if self.precision == "int8":
            name = self.config["int8"].get("of", {}).get(name, name)
        return name

    def session(self, name: str | None = None):
        """The onnxruntime session of ``name`` (default: the ε-network of a one-piece export, the denoiser of a split one)."""
        return self._sessions(name or ("denoiser.onnx" if self.form == "split" else "eps.onnx"))

    def encode(self, cond: np.ndarray, tileable: bool = False) -> dict:
        """Split form: cond float32 (B, C, H, W) -> {m00: [1 + γ, β] of ResBlock 0, ...} for the denoiser.

        A spatially constant grid (one class, one parameter set: the common case) is encoded on a small
        grid and expanded, with the same values: every map is a pointwise MLP, a nearest resize and two
        3x3 convolutions of a constant, so it is constant except within EDGE px of each border, where it
        depends only on the distance to that border (zero padding; with circular padding it is constant).
        """
        cond = np.ascontiguousarray(cond, _F)
        small = self._small_grid(cond)
        if small is not None:
            return self._expand(self._encode(cond[:, :, :small, :small], tileable), cond.shape[-2:], small)
        return self._encode(cond, tileable)

    #: border frame (px, at every level) within which a constant grid's maps may vary; the maps' receptive
    #: field reaches 2 px (two 3x3 convolutions), one more keeps a margin
    EDGE = 3

    def _encode(self, cond: np.ndarray, tileable: bool) -> dict:
        sess = self.session("encoder.onnx")
        names = [o.name for o in sess.get_outputs()]
        return dict(zip(names, sess.run(None, {"cond": cond, "tile": _tile_flag(tileable)})))

    def _small_grid(self, cond: np.ndarray):
        """The side of the small grid that encodes ``cond`` exactly, or None (not constant, or small already)."""
        levels = (self.config.get("blocks") or {}).get("levels")
        if not levels:
            return None
        side = (2 * self.EDGE + 2) << max(levels)  # the coarsest level keeps an interior of 2 px
        H, W = cond.shape[-2:]
        if min(H, W) <= side or not np.array_equal(cond, np.broadcast_to(cond[:, :, :1, :1], cond.shape)):
            return None
        return side

    def _expand(self, maps: dict, hw, side: int) -> dict:
        """Maps of the small side x side grid -> maps of an H x W grid: border frames kept, the interior repeated.
        (A map side / 2^l px wide is at level l, whatever the export's names: one tensor per block, or two.)"""
        H, W = hw
        e = self.EDGE
        out = {}
        for name, m in maps.items():
            k = m.shape[-1]
            lvl = (side // k).bit_length() - 1
            h, w = H >> lvl, W >> lvl
            o = np.empty(m.shape[:2] + (h, w), _F)
            rows = ((slice(0, e), slice(0, e)), (slice(e, h - e), slice(e, e + 1)), (slice(h - e, h), slice(k - e, k)))
            cols = ((slice(0, e), slice(0, e)), (slice(e, w - e), slice(e, e + 1)), (slice(w - e, w), slice(k - e, k)))
            for ro, ri in rows:  # nine blocks: corners and edges copied, the interior (and edge runs) broadcast
                for co, ci in cols:
                    o[:, :, ro, co] = m[:, :, ri, ci]
            out[name] = o
        return out

    def eps_fn(self, tileable: bool = False):
        """model(x, t, cond) -> ε callable for the samplers of :mod:`backend.neural.sampler`.

        With a split export the encoder runs when ``cond`` is a new array (by identity:
        a sampler passes the same array at every step) and its maps are reused.
        """
        tile = _tile_flag(tileable)
        if self.form == "one-piece":
            sess = self.session()

            def eps(x, t, cond):
                return sess.run(None, {"x": np.ascontiguousarray(x, _F), "t": np.ascontiguousarray(t, _F),
                                       "cond": np.ascontiguousarray(cond, _F), "tile": tile})[0]

            return eps
        # one denoiser per padding (no tile input), or an older export's one denoiser with a tile input
        sess = self.session(self.denoiser_name(tileable))
        extra = {"tile": tile} if "tile" in {i.name for i in sess.get_inputs()} else {}
        cache = {"cond": None, "maps": None}

        def eps(x, t, cond):
            if cache["cond"] is not cond:
                cache["cond"], cache["maps"] = cond, self.encode(cond, tileable)
            feed = dict(cache["maps"], x=np.ascontiguousarray(x, _F), t=np.ascontiguousarray(t, _F), **extra)
            return sess.run(None, feed)[0]

        return eps

    # -- classes and parameters -----------------------------------------------------------
    def class_id(self, name: str) -> int:
        if name not in self.classes:
            raise SettingError("noise", f"unknown class {name!r}; choose one of {', '.join(self.classes)}")
        return self.classes.index(name)

    def param_vector(self, name: str, values: dict | None = None) -> np.ndarray:
        """Physical parameter values of class ``name`` -> float32 (P,) normalised vector (zeros elsewhere).

        Missing parameters take the middle of their range; unknown names or values
        outside the range raise SettingError naming them.  A parameter with a ``period`` in the
        model's JSON (an orientation whose images repeat every half turn) maps to
        ((v - min) mod period) / period, as the zoo conditioned it in training.
        """
        self.class_id(name)
        spec = {p["name"]: p for p in self.class_params[name]["params"]}
        values = dict(values or {})
        unknown = sorted(set(values) - set(spec))
        if unknown:
            raise SettingError("param", f"{name} has no parameter {unknown[0]!r}; it has {', '.join(spec)}")
        vec = np.zeros(len(self.params), _F)
        for pname, p in spec.items():
            v = float(values.get(pname, 0.5 * (p["min"] + p["max"])))
            if not p["min"] <= v <= p["max"]:
                raise SettingError("param", f"{pname}={v:g} is outside [{p['min']:g}, {p['max']:g}] ({p['unit']})")
            period = p.get("period", 0.0)  # the pattern repeats every period: the input turns once per period
            vec[self.params.index(pname)] = (((v - p["min"]) % period) / period if period > 0
                                             else (v - p["min"]) / (p["max"] - p["min"]))
        return vec
