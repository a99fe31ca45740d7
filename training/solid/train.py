"""Train a neural solid texture: ``python -m omninoise.training.solid.train --config CONFIG.json --out RUN``.

Single mode (``mode: "single"``): one exemplar; the decoder f, the code e and
the transforms T_i are optimised directly (Henzler et al. 2020, Sec. 4,
"Spaces-of").  Space mode (``mode: "space"``): encoder g, translator h and
decoder f trained jointly over many exemplars; each step encodes a random
128 px patch P_e and asks the sampler's slice P_s to match its statistics.

Every step (Sec. 3, Fig. 5): random crops of the exemplar(s) -> the sampler at
pixel centres of random 2D slices of the D-dimensional domain (axis-aligned
and, with probability ``oblique``, rotated planes in 3D), fresh seeds xi and
a random offset per slice -> style loss (Gram matrices of fixed random
multi-scale features + colour histogram, :mod:`.features`, or sliced Wasserstein
distances of such features, :mod:`.swd`; optionally the power spectrum's band
shares, :mod:`.spectrum`, and the level-set morphology, :mod:`.soft_morphology`)
-> Adam with a cosine learning-rate decay.

``RUN/ckpt.pt`` is written atomically every ``checkpoint_every`` steps (a run
resumes from it), ``RUN/log.jsonl`` has one line per ``log_every`` steps.
Config keys and defaults: :class:`SolidConfig`.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import shutil
import sys
import time
from dataclasses import asdict, dataclass, replace

import torch

from omninoise import export as _ex
from ..threads import cpu_threads
from ..config import check_config_keys
from ..model_card import cpu_name
from ..precision import check_precision, resolve as resolve_precision
from . import exemplars as ex
from .features import RandomFeatures, histogram_loss, style_loss
from .value_noise import octave_seeds
from .model import (MAX_STRETCH, SolidTexture, fixed_axis_index, axis_rotations, check_fixed_axis, check_max_stretch,
                    colour_stats, max_scales, shape_features, slice_points, spectral_aspect, spectral_gains)
from .soft_morphology import soft_morphology_loss
from .spectrum import spectrum_loss
from .structure_features import StructureFeatures, load_structure_net
from .swd import SlicedFeatures, swd_loss
from .warm_start import exported_weights, warm_start
from .waves import photo_waves, wave_share
from omninoise.backend.onnx_models import load_model_json
from omninoise.backend.solid.harmonic import photo_harmonics, remove_harmonics
from omninoise.backend.solid.spin import check_mode

__all__ = ["SolidConfig", "load_config", "build_model", "train", "render", "fit_schedule", "noise_gain",
           "snapshot_path"]


@dataclass
class SolidConfig:
    name: str = "solid"
    mode: str = "single"            # "single" or "space"
    exemplars: tuple = ("gravel",)  # names (see exemplars.PHOTOS / PROCEDURAL) or image paths
    dim: int = 3                    # 2: plane textures; 3: solid textures from 2D slices
    octaves: int = 8
    channels: int = 3               # noise values per octave (<= 3)
    cellular: int = 0               # the first this many octaves also give Worley features (cellular.py)
    bricks: int = 0                 # ... and staggered-lattice (brick) features (brick.py)
    waves: int = 0                  # single 2D: the exemplar's this many strongest periodic components (waves.py)
    code_dim: int = 64              # |e|
    z_dim: int = 8                  # |z| (space mode)
    width: int = 128
    layers: int = 4
    decoder_init: str = "he"        # "he" (Kaiming normal) or "torch" (nn.Linear's default; gravel_3d)
    crop: int = 128                 # training crop / slice size, px
    batch: int = 4
    steps: int = 2000
    lr: float = 2e-3
    lr_min: float = 1e-4
    px_per_unit: float = 128.0      # exemplar pixels per unit of texture space
    exemplar_scale: float = 1.0     # resample the exemplar by this factor before cropping
    oblique: float = 0.5            # probability of a rotated (not axis-aligned) slice, 3D
    augment: bool | None = None     # random rotations/flips of crops; default: on in 3D
    extent: float = 64.0            # slice offsets drawn from [-extent, extent]^D units
    hist_weight: float = 10.0
    colour: str = "sigmoid"         # "sigmoid" (RGB through a sigmoid) or "affine" (mu + L d from the exemplar)
    transform: str = "free"         # space mode: "free" T_i = R_i (I + tanh Delta) or "bounded" (model.bounded_transform)
    film: bool = False              # the code modulates every hidden layer of the decoder (model.Decoder)
    standardise: bool = False       # space mode: the encoder sees each crop with its channels standardised
    spectral: bool = False          # octave i's noise times the exemplar's measured gain g_i (model.spectral_gains)
    loss: str = "gram"              # "gram" (random-feature Gram matrices) or "swd" (sliced Wasserstein, swd.py)
    swd_width: int = 32             # swd: random filters per size and pyramid level
    swd_kernels: tuple = (3, 7)     # swd: filter sizes
    swd_levels: int = 5             # swd: pyramid levels
    spectrum_weight: float = 0.0    # weight of the power-spectrum band term (spectrum.py); 0: off
    morphology_weight: float = 0.0  # weight of the soft level-set morphology term (soft_morphology.py); 0: off
    structure_weight: float = 0.0   # weight of the learned structure term (structure_features.py); 0: off
    structure_net: str = ""         # ... the trained structure network it reads (a file of train_structure_net)
    isotropy_weight: float = 0.0    # weight of a penalty on the octave transforms' anisotropy (isotropy_penalty):
                                    # a stretch must buy more of the texture loss than it costs; 0: off
    max_stretch: float = MAX_STRETCH  # bounded space models: the largest stretch of an octave's transform
                                    # (model.bounded_transform); 0: the translator cannot stretch, only turn and
                                    # scale, so no octave draws strokes
    min_spacing: float = 0.0        # bounded space models: no octave's lattice finer than this many px (model.max_scales); 0: off
    seed: int = 0
    log_every: int = 25
    checkpoint_every: int = 250
    snapshot_every: int = 0         # also keep the model's weights every this many steps and at the end in
                                    # RUN/snapshots/ (weight averaging: python -m omninoise.training.solid.average
                                    # --snapshots RUN); 0: off
    threads: int = 0                # CPU threads for torch and numba (0: their defaults)
    device: str = "cpu"             # "cpu" or "cuda" / "cuda:N" (model, loss and crops there; the random draws
                                    # stay on the CPU's generator, so a run's data is the same on any device)
    precision: str = "auto"         # "auto", "fp32" or "bf16": the decoder's matrix products under bf16 autocast
                                    # ("auto": where the device computes bf16 natively, training/precision.py);
                                    # noise, transforms, encoder and loss stay fp32. Recorded in the hardware line
    init_from: str = ""             # a run folder to continue (its ckpt.pt and log.jsonl seed a new run)
    init_onnx: str = ""             # or an export folder to continue (its weights; Adam's moments start afresh) ...
    init_sha256: str = ""           # ... whose weights have this fingerprint (backend.onnx_models.fingerprint)
    warmup: int = 0                 # steps of linear learning-rate warm-up from where this run starts
    fixed_axis: str = ""            # 3D: "columns" (image horizontal along x: wood grain) or "rows" (image vertical
                                    # along z: brick courses) slices only through that axis (model.slice_points);
                                    # 2D single: the lattices start with their rows along the photo's rows or columns
    init_stretch: bool = False      # single mode with fixed_axis: the transforms start scaled along that axis by
                                    # the exemplar's spectral aspect (model.spectral_aspect; grain starts long)
    hold_out: bool = False          # single mode: train on a photo's left three quarters only (its right quarter
                                    # is the held-out part python -m bench solid-singles measures on)
    noise_ramp: int = 0             # the value noise enters the decoder with a gain rising from 0 to 1 over the
                                    # run's first noise_ramp steps, so the shape features (cellular, bricks) draw
                                    # alone at first and the decoder learns to read them (noise_gain); 0: off.
                                    # Space models: the ramp multiplies the spectral gains
    harmonic_rest: bool = False     # space photo models: train on each photo less its harmonic part
                                    # (backend.solid.harmonic.remove_harmonics), so the decoder learns the
                                    # indeterministic rest the part leaves to it; the export says so (solid.json
                                    # "harmonic_rest") and the runtime then encodes photos' rests
    spin: str = ""                  # backend.solid.spin: "lattice" turns each octave's lattice by a rotation drawn
                                    # from its seed (no stretch can line up with the lattice), "octave" turns each
                                    # octave's whole field; "" neither (solid.json "spin"; the runtime turns the same)

    @classmethod
    def from_dict(cls, d: dict) -> "SolidConfig":
        check_config_keys(cls, d)
        d = dict(d)
        for key in ("exemplars", "swd_kernels"):
            if key in d:
                d[key] = tuple(d[key])
        cfg = cls(**d)
        if cfg.mode not in ("single", "space"):
            raise ValueError(f"mode must be 'single' or 'space', got {cfg.mode!r}")
        if cfg.dim not in (2, 3):
            raise ValueError(f"dim must be 2 or 3, got {cfg.dim}")
        if cfg.loss not in ("gram", "swd"):
            raise ValueError(f"loss must be 'gram' or 'swd', got {cfg.loss!r}")
        if cfg.colour not in ("sigmoid", "affine"):
            raise ValueError(f"colour must be 'sigmoid' or 'affine', got {cfg.colour!r}")
        for key in ("cellular", "bricks"):
            if not 0 <= getattr(cfg, key) <= cfg.octaves:
                raise ValueError(f"{key} must be 0..{cfg.octaves} (octaves with {key} features), "
                                 f"got {getattr(cfg, key)}")
        n_exemplars = len(ex.expand(cfg.exemplars))
        if cfg.spectral and (cfg.mode != "space" or cfg.colour != "affine"):
            raise ValueError("spectral gains are measured from the exemplar: they need mode 'space' and colour 'affine'")
        check_mode(cfg.spin)
        check_max_stretch(cfg.max_stretch, cfg.transform)
        for key in ("spectrum_weight", "morphology_weight", "structure_weight", "isotropy_weight"):
            if not (math.isfinite(getattr(cfg, key)) and getattr(cfg, key) >= 0):
                raise ValueError(f"{key} must be a number >= 0, got {getattr(cfg, key)!r}")
        if cfg.structure_weight and not cfg.structure_net:
            raise ValueError("structure_weight needs structure_net, the file of a trained structure network "
                             "(python -m omninoise.training.solid.structure_features --out FILE)")
        if cfg.noise_ramp:
            if not (isinstance(cfg.noise_ramp, int) and 0 < cfg.noise_ramp < cfg.steps):
                raise ValueError(f"noise_ramp must be a whole number of steps in 1 .. steps - 1, got {cfg.noise_ramp!r}")
            if not (cfg.cellular or cfg.bricks):
                raise ValueError("noise_ramp needs shape features (cellular or bricks) to draw while the noise is off")
        if cfg.min_spacing:
            if not (math.isfinite(cfg.min_spacing) and cfg.min_spacing > 0):
                raise ValueError(f"min_spacing must be a number >= 0 (px), got {cfg.min_spacing!r}")
            if cfg.mode != "space" or cfg.transform != "bounded":
                raise ValueError("min_spacing caps the bounded transforms: it needs mode 'space' and transform 'bounded'")
        if cfg.waves and not (isinstance(cfg.waves, int) and cfg.waves > 0 and cfg.mode == "single" and cfg.dim == 2):
            raise ValueError(f"waves must be a whole number >= 0 and needs mode 'single' and dim 2, got {cfg.waves!r}")
        if not (isinstance(cfg.snapshot_every, int) and cfg.snapshot_every >= 0):
            raise ValueError(f"snapshot_every must be a whole number of steps >= 0, got {cfg.snapshot_every!r}")
        if cfg.init_onnx and not cfg.init_sha256:
            raise ValueError("init_onnx needs init_sha256 (the fingerprint of the weights the run starts from)")
        if cfg.init_onnx and cfg.init_from:
            raise ValueError("give init_from (a run folder) or init_onnx (an export), not both")
        check_fixed_axis(cfg.fixed_axis)
        check_precision(cfg.precision)
        if not (cfg.device == "cpu" or cfg.device == "cuda" or
                (cfg.device.startswith("cuda:") and cfg.device[5:].isdigit())):
            raise ValueError(f"device must be 'cpu', 'cuda' or 'cuda:N', got {cfg.device!r}")
        if cfg.fixed_axis and cfg.augment:
            raise ValueError("fixed_axis keeps the photo's orientation on an axis: it needs augment false (rotated "
                             "crops would turn the grain)")
        if cfg.fixed_axis and cfg.dim == 2 and cfg.mode != "single":
            raise ValueError("in 2D, fixed_axis sets where a single model's lattices start (model.axis_rotations): "
                             "it needs mode 'single' (a 2D plane is the photo's own, never turned)")
        if cfg.init_stretch and not (cfg.mode == "single" and cfg.fixed_axis):
            raise ValueError("init_stretch scales the transforms along the fixed axis: it needs mode 'single' and "
                             "fixed_axis")
        if cfg.harmonic_rest and (cfg.mode != "space" or cfg.colour != "affine"):
            raise ValueError("harmonic_rest trains on photos less their harmonic part, which the runtime adds in the "
                             "photo's colour frame: it needs mode 'space' and colour 'affine'")
        if cfg.hold_out and cfg.mode != "single":
            raise ValueError("hold_out keeps a quarter of the one exemplar for evaluation: it needs mode 'single' "
                             "(space models hold out whole photos: photos:val)")
        if cfg.mode == "single" and n_exemplars != 1:
            raise ValueError(f"single mode takes exactly one exemplar, got {n_exemplars}")
        return cfg


def initial_stretch(img: torch.Tensor, fixed_axis: str) -> float:
    """The scale in [1/16, 1] that ``init_stretch`` gives the transforms along the fixed axis: the exemplar's
    feature length along the image axis that lies on it, relative to across (:func:`.model.spectral_aspect`)
    - "columns": the image's horizontal; "rows": its vertical.  Features are only ever lengthened."""
    a = spectral_aspect(img)
    return float(min(1.0, max(1.0 / 16.0, a if fixed_axis == "columns" else 1.0 / a)))


def load_config(path: str) -> SolidConfig:
    with open(path, encoding="utf-8") as fh:
        return SolidConfig.from_dict(json.load(fh))


def _seed_run(src: str, out: str) -> None:
    """Copy a finished run's checkpoint and log into ``out``: training resumes from its last step
    with this config's schedule (a longer ``steps`` restarts the cosine decay from that step)."""
    ckpt = os.path.join(src, "ckpt.pt")
    if not os.path.isfile(ckpt):
        raise ValueError(f"init_from: no checkpoint {ckpt}")
    for name in ("ckpt.pt", "log.jsonl"):
        if os.path.isfile(os.path.join(src, name)):
            with _ex.atomic_path(os.path.join(out, name)) as tmp:
                shutil.copyfile(os.path.join(src, name), tmp)


def build_model(cfg: SolidConfig) -> SolidTexture:
    return SolidTexture(cfg.dim, cfg.octaves, cfg.channels, cfg.code_dim, cfg.z_dim, cfg.mode, cfg.width,
                        cfg.layers, cfg.seed, cfg.decoder_init, cfg.colour, cfg.transform, cfg.film,
                        cfg.standardise, cfg.cellular, cfg.bricks,
                        max_scales(cfg.octaves, cfg.px_per_unit, cfg.min_spacing) if cfg.min_spacing else None,
                        cfg.waves, cfg.spin, cfg.max_stretch)


def _resample(img: torch.Tensor, factor: float) -> torch.Tensor:
    if factor == 1.0:
        return img
    return torch.nn.functional.interpolate(img.unsqueeze(0), scale_factor=factor, mode="bilinear",
                                           antialias=factor < 1.0, align_corners=False)[0].clamp(0, 1)


def harmonic_rest(img: torch.Tensor, px_per_unit: float) -> torch.Tensor:
    """A photo (3, H, W) less its harmonic part, measured and removed as the runtime does
    (backend.solid.harmonic: photo_harmonics, remove_harmonics): (3, H, W) in [0, 1]."""
    a = img.permute(1, 2, 0).numpy()
    rest = remove_harmonics(a, photo_harmonics(a, px_per_unit), px_per_unit)
    return torch.from_numpy(rest).permute(2, 0, 1).contiguous()


def training_images(cfg: SolidConfig, rests: bool = True) -> list:
    """The training regions of the config's exemplars, resampled (with ``harmonic_rest`` and ``rests``: their
    rests): list of (3, H, W)."""
    images = [_resample(ex.train_region(ex.exemplar(n), n, cfg.hold_out), cfg.exemplar_scale)
              for n in ex.expand(cfg.exemplars)]
    return [harmonic_rest(i, cfg.px_per_unit) for i in images] if cfg.harmonic_rest and rests else images


def noise_gain(cfg: SolidConfig, step: int) -> float:
    """The value noise's gain at a step: (step + 1) / noise_ramp up to 1 (1 without a ramp)."""
    return min(1.0, (step + 1) / cfg.noise_ramp) if cfg.noise_ramp else 1.0


def render(model: SolidTexture, e: torch.Tensor, T: torch.Tensor, x: torch.Tensor, seeds, size: int,
           stats: torch.Tensor | None = None, gains: torch.Tensor | None = None) -> torch.Tensor:
    """Sampler images at slice points x (B, size*size, D) -> (B, 3, size, size)."""
    s = octave_seeds(seeds, model.octaves, x.device)
    return model.sample(x, e, T, s, stats, gains).view(x.shape[0], size, size, 3).permute(0, 3, 1, 2)


def texture_loss(cfg: SolidConfig, feats, img: torch.Tensor, ref: torch.Tensor, gen: torch.Generator) -> torch.Tensor:
    """The config's style loss of rendered images against reference crops (both (B, 3, S, S))."""
    per_sample = cfg.mode == "space"
    if cfg.loss == "gram":
        loss = style_loss(feats, img, ref, cfg.hist_weight, per_sample=per_sample)
    else:
        loss = swd_loss(feats, img, ref, per_sample=per_sample, generator=gen) + \
            cfg.hist_weight * histogram_loss(img, ref, per_sample=per_sample)
    if cfg.spectrum_weight:
        loss = loss + cfg.spectrum_weight * spectrum_loss(img, ref, per_sample=per_sample)
    if cfg.morphology_weight:
        loss = loss + cfg.morphology_weight * soft_morphology_loss(img, ref, per_sample=per_sample)
    if cfg.structure_weight:
        loss = loss + cfg.structure_weight * swd_loss(structure_features(cfg.structure_net, img.device), img, ref,
                                                      per_sample=per_sample, generator=gen)
    return loss


def isotropy_penalty(T: torch.Tensor) -> torch.Tensor:
    """Mean over transforms of ||A - I||_F^2 with A = T^T T / (tr(T^T T) / D): 0 for a rotation times a scale,
    ~0.4 for a stretch of 1.45 : 1 along one axis.  T (..., D, D); rotations before or after T change nothing
    (spun lattices included), so only the stretch is charged, not the lattice's orientation or the octave's scale."""
    D = T.shape[-1]
    G = T.transpose(-1, -2) @ T
    A = G / (G.diagonal(dim1=-2, dim2=-1).sum(-1)[..., None, None] / D)
    return (A - torch.eye(D, dtype=T.dtype, device=T.device)).square().sum((-2, -1)).mean()


_STRUCTURE: dict = {}


def structure_features(path: str, device: str = "cpu") -> StructureFeatures:
    """The frozen structure features of a trained network file, loaded once per process and device."""
    key = (os.path.abspath(path), str(device))
    if key not in _STRUCTURE:
        if not os.path.isfile(key[0]):
            raise ValueError(f"structure_net: no trained structure network at {path!r} "
                             f"(make one: python -m omninoise.training.solid.structure_features --out {path})")
        _STRUCTURE[key] = StructureFeatures(load_structure_net(key[0])).to(device)
    return _STRUCTURE[key]


def loss_features(cfg: SolidConfig):
    if cfg.loss == "gram":
        return RandomFeatures(seed=0)
    return SlicedFeatures(seed=0, levels=cfg.swd_levels, width=cfg.swd_width, kernels=cfg.swd_kernels)


def snapshot_path(run: str, step: int) -> str:
    """Where a run keeps its weights of a step (``snapshot_every``): RUN/snapshots/step_NNNNNNN.pt."""
    return os.path.join(run, "snapshots", f"step_{step:07d}.pt")


def _save(path: str, obj) -> None:
    with _ex.atomic_path(path) as tmp:
        torch.save(obj, tmp)


def fit_schedule(cfg: SolidConfig, step: int, seconds_per_step: float, seconds_left: float) -> SolidConfig:
    """The config with its schedule scaled to end when a time budget does: ``steps`` becomes ``step`` plus as
    many steps as ``seconds_left`` holds at the measured rate, and ``noise_ramp`` keeps its share of the
    schedule (the cosine and the ramp then run their whole course in the time there is)."""
    if not (seconds_per_step > 0 and math.isfinite(seconds_per_step)):
        raise ValueError(f"fit_schedule: seconds per step must be a positive number, got {seconds_per_step!r}")
    steps = step + max(1, int(max(0.0, seconds_left) / seconds_per_step))
    ramp = 0
    if cfg.noise_ramp:
        ramp = max(1, min(steps - 1, round(cfg.noise_ramp * steps / cfg.steps)))
    return replace(cfg, steps=steps, noise_ramp=ramp)


def train_device(name: str) -> torch.device:
    """The torch device of a config's ``device``, or a one-line error when it is not there."""
    dev = torch.device(name)
    if dev.type == "cuda" and not torch.cuda.is_available():
        raise ValueError(f"device {name!r}: torch sees no CUDA device here (train with device 'cpu')")
    return dev


def hardware_here(cfg: SolidConfig, dev: torch.device, precision: str = "fp32") -> str:
    """Where a stretch of training runs, for the model card: the GPU or the CPU and its threads, precision
    ("bf16 decoder": the decoder's products under bf16 autocast, the rest fp32)."""
    prec = "fp32" if precision == "fp32" else "bf16 decoder, fp32 loss"
    if dev.type == "cuda":
        conv = "TF32 convolutions" if torch.backends.cudnn.allow_tf32 else "fp32 convolutions"
        return f"{torch.cuda.get_device_name(dev)}, {prec} ({conv})"
    return f"{cpu_name()}, {cfg.threads or torch.get_num_threads()} threads, {prec}"


def train(cfg: SolidConfig, out: str, max_steps: int | None = None, log=print,
          budget_seconds: float | None = None) -> dict:
    """Train (or resume) into folder ``out``; returns the final checkpoint dict.

    ``budget_seconds``: the run's schedule (``steps``, ``noise_ramp``) is fitted to end after this many seconds
    of training (:func:`fit_schedule`, from the rate of steps 10 to 40 of this stretch); the fitted config is
    the one its checkpoint records."""
    if budget_seconds is not None and not (budget_seconds > 0 and math.isfinite(budget_seconds)):
        raise ValueError(f"budget_seconds must be a positive number, got {budget_seconds!r}")
    with cpu_threads(cfg.threads):
        return _train(cfg, out, max_steps, log, budget_seconds)


_FIT_FROM, _FIT_TO = 10, 40     # the steps of a stretch whose rate fits a budget (after the device warms up)


def _train(cfg: SolidConfig, out: str, max_steps: int | None, log, budget_seconds: float | None = None) -> dict:
    dev = train_device(cfg.device)
    os.makedirs(out, exist_ok=True)
    torch.manual_seed(cfg.seed)
    gen = torch.Generator().manual_seed(cfg.seed + 1)
    model = build_model(cfg).to(dev)    # before the optimiser: a resumed one's moments load onto its parameters
    model.precision = resolve_precision(cfg.precision, dev)
    feats = loss_features(cfg).to(dev)
    opt = torch.optim.Adam(model.parameters(), lr=cfg.lr)
    step, elapsed = 0, 0.0
    prev_hardware = ""
    first = 0              # the step this run's optimiser started at (warm-up counts from it)
    ckpt_path = os.path.join(out, "ckpt.pt")
    if cfg.init_from and not os.path.isfile(ckpt_path):
        _seed_run(cfg.init_from, out)
        log(f"continuing {cfg.init_from}")
    if os.path.isfile(ckpt_path):
        state = torch.load(ckpt_path, map_location="cpu", weights_only=False)
        model.load_state_dict(state["model"])
        opt.load_state_dict(state["opt"])
        step, elapsed = state["step"], state.get("elapsed", 0.0)
        gen.set_state(state["gen"])
        first = state.get("first_step", 0)
        prev_hardware = state.get("hardware", "")
        log(f"resumed at step {step}")
    elif cfg.init_onnx:
        # the export's step and training time carry on, so the ledger and the cosine schedule continue
        model_json = load_model_json(cfg.init_onnx, "solid.json")
        had = shape_features(int(model_json.get("cellular", 0)), int(model_json.get("bricks", 0)))
        new = shape_features(cfg.cellular, cfg.bricks) - had
        if had and new:
            raise ValueError("init_onnx: features can be added only to an export without cellular or brick features")
        if model_json.get("spin", "") and not cfg.spin:
            raise ValueError(f"init_onnx: {cfg.init_onnx} draws with spin {model_json['spin']!r}; set spin in the "
                             "config (the same to keep drawing so), or the run and its export would draw unturned")
        warm_start(model, exported_weights(cfg.init_onnx, cfg.init_sha256), new_features=new)
        step, elapsed = int(model_json.get("step", 0)), float(model_json.get("train_seconds", 0.0))
        first = step
        prev_hardware = str(model_json.get("hardware", "")) or (f"steps 0-{step}: not recorded in the export"
                                                                 if step else "")
        log(f"started from {cfg.init_onnx} ({cfg.init_sha256[:12]}...) at step {step}")
    if cfg.structure_weight:
        structure_features(cfg.structure_net, dev)  # a missing network fails here, before the first step
    images = training_images(cfg)
    if cfg.mode == "single" and cfg.fixed_axis and step == 0:
        with torch.no_grad():   # lattices start aligned with the photo's direction (model.axis_rotations)
            model.T.copy_(axis_rotations(cfg.octaves, cfg.fixed_axis, cfg.seed, cfg.dim))
            if cfg.init_stretch:   # octave i reads T_i x: scaling T's column of the axis stretches features along it
                stretch = initial_stretch(images[0], cfg.fixed_axis)
                model.T[:, :, fixed_axis_index(cfg.fixed_axis, cfg.dim)] *= stretch
                log(f"transforms start stretched along the {cfg.fixed_axis} axis by {1 / stretch:.2f}")
    if cfg.waves and step == 0:     # the photo's periodic components (a resumed run has them in its state)
        with torch.no_grad():
            model.waves.copy_(photo_waves(images[0], cfg.waves, cfg.px_per_unit))
        share = wave_share(images[0], cfg.waves)
        log(f"waves: the photo's {cfg.waves} strongest periodic components carry {share:.1%} of its luminance variance"
            + (" - under 10 %: the photo has no strong period, and the waves will repeat its chance peaks as "
               "stripes (waves are for courses, grids and weaves)" if share < 0.1 else ""))
    augment = (cfg.dim == 3 and not cfg.fixed_axis) if cfg.augment is None else cfg.augment
    end = cfg.steps if max_steps is None else min(cfg.steps, step + max_steps)
    logf = open(os.path.join(out, "log.jsonl"), "a", encoding="utf-8")
    t0 = time.time() - elapsed
    # single mode: one exemplar, so one colour statistic for the whole run
    single_stats = colour_stats(images[0].unsqueeze(0)).expand(cfg.batch, -1).to(dev) if cfg.mode == "single" \
        else None
    state = None
    # where training ran: this stretch's device, after those of the stretches it resumes (recorded in the export)
    here = hardware_here(cfg, dev, model.precision)
    log(f"precision: {model.precision}" + (" (the decoder under bf16 autocast)" if model.precision == "bf16" else ""))
    hardware = prev_hardware if here in prev_hardware.split("; ") else "; ".join(filter(None, [prev_hardware, here]))
    start, t_loop, t_fit = step, time.time(), 0.0
    while step < end:
        lr = cfg.lr_min + 0.5 * (cfg.lr - cfg.lr_min) * (1 + math.cos(math.pi * step / cfg.steps))
        if cfg.warmup:     # fresh Adam moments (a run continued from an export) start with small steps
            lr *= min(1.0, (step - first + 1) / cfg.warmup)
        for g in opt.param_groups:
            g["lr"] = lr
        if cfg.mode == "single":
            ref = ex.random_crops(images[0], cfg.batch, cfg.crop, gen, augment).to(dev)
            e, T = model.codes(batch=cfg.batch)
            stats, gains = single_stats, None
        else:
            # distinct exemplars within a batch (while there are enough): each step contrasts textures
            pick = torch.randperm(len(images), generator=gen).tolist() * (cfg.batch // len(images) + 1)
            pick = pick[:cfg.batch]
            ref = torch.cat([ex.random_crops(images[k], 1, cfg.crop, gen, augment) for k in pick]).to(dev)
            e, T = model.codes(ref)
            stats = colour_stats(ref)
            gains = spectral_gains(ref, cfg.octaves, cfg.px_per_unit) if cfg.spectral else None
        gain = noise_gain(cfg, step)
        if gain < 1.0:   # the octaves' noise times the ramp's gain (model.sample's gains)
            gains = torch.full((cfg.batch, cfg.octaves), gain, device=dev) if gains is None else gains * gain
        x = slice_points(cfg.batch, cfg.crop, cfg.px_per_unit, cfg.dim, cfg.oblique, cfg.extent, gen,
                         cfg.fixed_axis).to(dev)
        seeds = torch.randint(0, 2 ** 31 - 1, (cfg.batch,), generator=gen).numpy()
        img = render(model, e, T, x, seeds, cfg.crop, stats if cfg.colour == "affine" else None, gains)
        loss = texture_loss(cfg, feats, img, ref, gen)
        if cfg.isotropy_weight:
            loss = loss + cfg.isotropy_weight * isotropy_penalty(T)
        opt.zero_grad(set_to_none=True)
        loss.backward()
        torch.nn.utils.clip_grad_norm_(model.parameters(), 1.0)
        opt.step()
        step += 1
        if budget_seconds is not None and step in (start + _FIT_FROM, start + _FIT_TO):
            if dev.type == "cuda":
                torch.cuda.synchronize(dev)     # the rate of finished steps, not of queued kernels
            now = time.time()
            if step == start + _FIT_FROM:
                t_fit = now
            else:
                before = cfg.steps
                cfg = fit_schedule(cfg, step, (now - t_fit) / (_FIT_TO - _FIT_FROM), budget_seconds - (now - t_loop))
                end = cfg.steps if max_steps is None else min(cfg.steps, start + max_steps)
                log(f"schedule fitted to {budget_seconds:.0f} s: steps {before} -> {cfg.steps}"
                    + (f", noise_ramp {cfg.noise_ramp}" if cfg.noise_ramp else ""))
        if step % cfg.log_every == 0 or step == end:
            rec = dict(step=step, loss=round(loss.item(), 5), lr=lr, seconds=round(time.time() - t0, 1))
            logf.write(json.dumps(rec) + "\n")
            logf.flush()
            log(f"step {step}/{cfg.steps} loss {loss.item():.4f} ({rec['seconds']:.0f} s)")
        if cfg.snapshot_every and (step % cfg.snapshot_every == 0 or step == end):
            os.makedirs(os.path.dirname(snapshot_path(out, step)), exist_ok=True)
            _save(snapshot_path(out, step), dict(model={k: v.detach().cpu() for k, v in model.state_dict().items()},
                                                 step=step))
        if step % cfg.checkpoint_every == 0 or step == end:
            state = dict(config=asdict(cfg), model=model.state_dict(), opt=opt.state_dict(), step=step,
                         elapsed=time.time() - t0, gen=gen.get_state(), n_params=model.n_params(),
                         first_step=first, hardware=hardware)
            _save(ckpt_path, state)
    logf.close()
    if state is None:
        state = torch.load(ckpt_path, map_location="cpu", weights_only=False)
    return state


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m omninoise.training.solid.train", description=__doc__.split("\n")[0])
    ap.add_argument("--config", required=True, help="JSON config (keys: SolidConfig)")
    ap.add_argument("--out", required=True, help="run folder (ckpt.pt, log.jsonl)")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=JSON", help="override a config key")
    ap.add_argument("--budget-seconds", type=float, default=None, metavar="S",
                    help="fit the schedule (steps, noise_ramp) to end after S seconds of training; the fitted "
                         "steps are logged and kept in the checkpoint (resume with --set steps=N)")
    a = ap.parse_args(argv)
    with open(a.config, encoding="utf-8") as fh:
        d = json.load(fh)
    for item in a.set:
        k, _, v = item.partition("=")
        d[k] = json.loads(v)
    try:
        cfg = SolidConfig.from_dict(d)
    except (ValueError, TypeError) as err:
        print(f"solid train: error: {err}", file=sys.stderr)
        return 2
    try:
        train(cfg, a.out, budget_seconds=a.budget_seconds)
    except ValueError as err:
        print(f"solid train: error: {err}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
