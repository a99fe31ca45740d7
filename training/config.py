"""The neural noise training configuration (``configs/neural_noise_*.json``), read by training, warm starts
and export alike (a module of its own so that none of them imports another for it)."""
from __future__ import annotations

import json
from dataclasses import dataclass, field, fields

from . import zoo
from .precision import check_precision

__all__ = ["TrainConfig", "load_config", "check_config_keys"]


def check_config_keys(cls, d: dict) -> None:
    """ValueError naming the first key of ``d`` that is not a field of the config dataclass ``cls``."""
    known = {f.name for f in fields(cls)}
    unknown = sorted(set(d) - known)
    if unknown:
        raise ValueError(f"unknown config key {unknown[0]!r}; known: {', '.join(sorted(known))}")


@dataclass
class TrainConfig:
    size: int = 64                 # training resolution (px); multiples of 8
    batch: int = 16
    steps: int = 100_000
    lr: float = 8e-5
    betas: tuple = (0.9, 0.99)
    weight_decay: float = 0.01
    grad_clip: float = 1.0
    ema_decay: float = 0.999
    cutmix_p: float = 0.5
    # Mirror training images at random (the stages before the orientation stage did, p = 0.5 per axis). Off: a
    # mirror turns damascus's fixed band direction and the orientation of gabor, gabor_texture, fibers and phasor
    # into its reflection while the conditioning still says the original, so the model learned "this direction
    # or its mirror image" and at 256² drew both in patches.
    flips: bool = False
    offset_noise: float = 0.1
    emb_lambda: float = 0.02
    min_snr_gamma: float = 0.0     # min-SNR-γ loss weighting (Hang et al. 2023), 5 in the paper; 0: plain MSE
    low_snr_weight: float = 1.0    # weight min(1/ᾱ_t, W) on the noisiest steps (.diffusion); 1: plain MSE
    emb_dim: int = 32
    widths: tuple = (32, 64, 128)
    deep: int = 0                  # levels of the zero-initialised deep branch at the bottleneck (.unet.DeepBranch)
    classes: tuple = field(default_factory=lambda: zoo.CLASS_NAMES)
    # Per-class sampling weights {name: weight} (1 where absent): a class of weight 2 fills twice the share of the
    # batches. Empty: equal shares. (The oriented classes, whose direction parameter the model must learn to follow.)
    class_weights: dict = field(default_factory=dict)
    seeds_per_set: int = 4
    sets_per_class: int = 16384
    seed: int = 0
    device: str = "auto"
    log_every: int = 50
    checkpoint_every: int = 1000
    sample_every: int = 5000
    sample_steps: int = 20
    threads: int = 0               # CPU threads for torch and numba (0: their defaults), see .threads
    workers: int = 0               # processes that make the batches ahead of the loop (.batches; 0: the loop does)
    init_onnx: str = ""            # a fresh run starts from this export's weights (see .warm_start) ...
    init_sha256: str = ""          # ... whose weights have this fingerprint (backend.onnx_models.fingerprint)
    precision: str = "auto"        # auto | fp32 | bf16: bf16 autocast where the CPU/GPU computes bf16 natively (.precision)
    channels_last: bool = False    # NHWC activations and weights (faster with bf16 on oneDNN)

    @classmethod
    def from_dict(cls, d: dict) -> "TrainConfig":
        check_config_keys(cls, d)
        d = dict(d)
        for k in ("betas", "widths", "classes"):
            if k in d:
                d[k] = tuple(d[k])
        bad = [c for c in d.get("classes", ()) if c not in zoo.CLASSES]
        if bad:
            raise ValueError(f"unknown class {bad[0]!r}")
        if "class_weights" in d:
            if not isinstance(d["class_weights"], dict):
                raise ValueError(f"class_weights must map class names to weights, got {d['class_weights']!r}")
            zoo.class_probabilities(d.get("classes", zoo.CLASS_NAMES), d["class_weights"])
        levels = len(d.get("widths", (32, 64, 128))) + int(d.get("deep", 0))
        if d.get("size", 64) % (1 << levels):
            raise ValueError(f"size must be a multiple of {1 << levels} (2^levels of the U-Net), got {d['size']}")
        if int(d.get("deep", 0)) < 0:
            raise ValueError(f"deep must be >= 0, got {d['deep']}")
        check_precision(d.get("precision", "auto"))
        if not isinstance(d.get("workers", 0), int) or d.get("workers", 0) < 0:
            raise ValueError(f"workers must be an integer >= 0, got {d['workers']!r}")
        if d.get("init_onnx") and not d.get("init_sha256"):
            raise ValueError("init_onnx needs init_sha256 (the fingerprint of the weights the run starts from)")
        return cls(**d)


def load_config(path: str) -> TrainConfig:
    with open(path, encoding="utf-8") as fh:
        return TrainConfig.from_dict(json.load(fh))
