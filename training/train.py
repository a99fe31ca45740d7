"""Train the neural noise model: ``python -m omninoise.training.train --config CONFIG.json --out RUN``.

Data is generated on the fly by :mod:`.zoo` (no files), on the CPU or the GPU.
Every step: a zoo batch -> CutMix (p = 0.5) -> (random flips, ``flips``) -> ε-prediction loss
with offset noise and the spherical embedding penalty -> AdamW (lr 8e-5,
β = (0.9, 0.99), weight decay 0.01), gradient clipping at 1, EMA of the weights.
``RUN/ckpt.pt`` is written atomically every ``checkpoint_every`` steps and a
run resumes from it; ``RUN/log.jsonl`` has one line per ``log_every`` steps and
``RUN/samples_STEP.png`` shows DDIM samples of the EMA model.  A fresh run may
start from a shipped export's weights (``init_onnx`` + ``init_sha256``, see
:mod:`.warm_start`), since checkpoints are not kept in git.

Config keys (JSON) and defaults: see :class:`TrainConfig`.
"""
from __future__ import annotations

import argparse
import copy
import json
import os
import sys
import time
from dataclasses import asdict

import numpy as np
import torch

from . import zoo
from .batches import worker_batches
from .cutmix import cutmix_sources, mix_by_sources
from .diffusion import Diffusion
from .config import TrainConfig, check_config_keys, load_config  # noqa: F401  (re-exported)
from .precision import autocast, resolve
from .threads import cpu_threads
from .unet import UNet
from .warm_start import exported_weights, warm_start
from omninoise.backend.onnx_models import ModelError

__all__ = ["TrainConfig", "train", "load_config", "build_model", "model_names", "check_config_keys"]


#: a run stops (keeping its last checkpoint) after this many consecutive steps with a non-finite loss or gradient
MAX_SKIPPED_IN_A_ROW = 20


def build_model(cfg: TrainConfig, state: dict | None = None) -> UNet:
    """A fresh UNet for the current zoo, or one shaped like a checkpoint's weights (``state``).

    The zoo is append-only, so a checkpoint made with fewer classes or parameters
    uses the first n class ids and parameter slots.
    """
    n_classes, n_params = len(zoo.CLASS_NAMES), len(zoo.PARAM_NAMES)
    if state is not None:
        n_classes = state["class_emb.weight"].shape[0]
        n_params = state["cond_mlp.0.weight"].shape[1] - state["class_emb.weight"].shape[1]
    return UNet(n_classes, n_params, emb_dim=cfg.emb_dim, widths=cfg.widths, deep=cfg.deep)


def random_mirror(imgs, idm, pm, rng: np.random.Generator):
    """Mirror the whole batch left-right and up-down, each with p = 0.5: images (B, 1, H, W), class maps (B, H, W),
    parameter maps (B, P, H, W).  Only with ``TrainConfig.flips``: a mirror reflects an oriented class's direction
    (damascus's bands, a gabor, fibers or phasor orientation θ -> π - θ) while its conditioning keeps θ."""
    if rng.random() < 0.5:
        imgs, idm, pm = imgs.flip(-1), idm.flip(-1), pm.flip(-1)
    if rng.random() < 0.5:
        imgs, idm, pm = imgs.flip(-2), idm.flip(-2), pm.flip(-2)
    return imgs, idm, pm


def model_names(model: UNet) -> tuple:
    """The zoo class names and parameter names a model was built for (prefixes of the zoo's)."""
    return list(zoo.CLASS_NAMES[: model.n_classes]), list(zoo.PARAM_NAMES[: model.n_params])


def _device(name: str) -> torch.device:
    if name == "auto":
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    return torch.device(name)


def _save(path: str, obj) -> None:
    from omninoise import export

    with export.atomic_path(path) as tmp:
        torch.save(obj, tmp)


def _conditions(ids: torch.Tensor, conds: torch.Tensor, size: int):
    """Per-sample class ids (B,) and conditions (B, P) -> uniform maps (B, S, S) and (B, P, S, S)."""
    B = ids.shape[0]
    return ids.view(B, 1, 1).expand(B, size, size).clone(), conds.view(B, -1, 1, 1).expand(-1, -1, size, size).clone()


def sample_grid(model: UNet, cfg: TrainConfig, device, names=None, seed: int = 0) -> np.ndarray:
    """DDIM samples of a few classes at their default parameters: float32 (n, S, S) in [0, 1]."""
    from omninoise.backend.neural.sampler import ddim_sample, initial_noise

    names = list(names or cfg.classes[:8])
    S = cfg.size
    ids = torch.tensor([zoo.CLASS_NAMES.index(n) for n in names], device=device)
    conds = torch.cat([zoo.condition_vector(n, zoo.default_params(n)) for n in names])[:, : model.n_params].to(device)
    idm, pm = _conditions(ids, conds, S)
    with torch.no_grad():
        cond = model.embed(idm, pm)

        def eps(x, t, c):
            return model(torch.from_numpy(x).to(device), torch.from_numpy(t).to(device), cond).cpu().numpy()

        x0 = ddim_sample(eps, initial_noise(seed, (len(names), 1, S, S)), None, steps=cfg.sample_steps)
    return (x0[:, 0] + 1.0) * 0.5


def train(cfg: TrainConfig, out: str, max_steps: int | None = None, log=print, max_seconds: float | None = None) -> dict:
    """Train (or resume) into folder ``out``; stops after ``max_steps`` more steps if given, or at the first step
    that ends ``max_seconds`` of wall time after the loop began (a GPU machine's time limit), with a checkpoint either way.
    Returns the last log."""
    with cpu_threads(cfg.threads):
        return _train(cfg, out, max_steps, log, max_seconds)


def _train(cfg: TrainConfig, out: str, max_steps: int | None, log, max_seconds: float | None = None) -> dict:
    os.makedirs(out, exist_ok=True)
    device = _device(cfg.device)
    torch.manual_seed(cfg.seed)
    ckpt = os.path.join(out, "ckpt.pt")
    state = torch.load(ckpt, map_location=device, weights_only=False) if os.path.isfile(ckpt) else None
    model = build_model(cfg, state["model"] if state else None)
    if state is None and cfg.init_onnx:
        warm_start(model, exported_weights(cfg.init_onnx, cfg.init_sha256))
        log(f"started from {cfg.init_onnx} ({cfg.init_sha256[:12]}...)")
    model = model.to(device)
    precision = resolve(cfg.precision, device)
    fmt = torch.channels_last if cfg.channels_last else torch.contiguous_format
    model = model.to(memory_format=fmt)
    ema = copy.deepcopy(model).eval()
    for p_ in ema.parameters():
        p_.requires_grad_(False)
    opt = torch.optim.AdamW(model.parameters(), lr=cfg.lr, betas=cfg.betas, weight_decay=cfg.weight_decay)
    diff = Diffusion(offset_noise=cfg.offset_noise, emb_lambda=cfg.emb_lambda, device=device,
                     min_snr_gamma=cfg.min_snr_gamma, low_snr_weight=cfg.low_snr_weight)
    rng = np.random.default_rng(cfg.seed)
    gen = torch.Generator(device=device).manual_seed(cfg.seed)
    step = 0
    if state is not None:
        model.load_state_dict(state["model"])
        ema.load_state_dict(state["ema"])
        opt.load_state_dict(state["opt"])
        step = state["step"]
        rng.bit_generator.state = state["rng"]
        gen.set_state(state["gen"].to(gen.get_state().device) if hasattr(state["gen"], "to") else state["gen"])
        log(f"resumed at step {step}")
    log(f"precision {precision}, channels_last {cfg.channels_last}, {torch.get_num_threads()} threads")
    with open(os.path.join(out, "config.json"), "w", encoding="utf-8") as fh:
        json.dump(asdict(cfg), fh, indent=2)
    del state
    sampler = zoo.ZooSampler(cfg.size, cfg.classes, cfg.seeds_per_set, cfg.sets_per_class, rng=rng, device=device,
                             class_weights=cfg.class_weights)
    end = cfg.steps if max_steps is None else min(cfg.steps, step + max_steps)
    t0, last, losses = time.time(), {}, []
    skipped, in_a_row = 0, 0  # steps skipped for a non-finite loss or gradient (see below)
    batches = worker_batches(cfg, step, end, pin=device.type == "cuda") if cfg.workers else None
    while step < end:
        if batches is not None:  # made ahead by worker processes, batch k from its own generator (.batches)
            imgs, ids, conds, src = next(batches)
            src = src.to(device, non_blocking=True)
        else:
            imgs, ids, conds = sampler.batch(cfg.batch)
            src = cutmix_sources(ids, cfg.size, cfg.size, rng, p=cfg.cutmix_p).to(device)
        # mixed on the training device; older runs' models read a prefix of the parameter slots
        imgs, idm, pm = mix_by_sources(imgs, ids, conds[:, : model.n_params], src)
        if cfg.flips:
            imgs, idm, pm = random_mirror(imgs, idm, pm, rng)
        x0 = (imgs * 2.0 - 1.0).contiguous(memory_format=fmt)
        model.train()
        with autocast(precision, device):
            loss, mse = diff.loss(model, x0, model.embed(idm, pm).contiguous(memory_format=fmt), gen)
        opt.zero_grad(set_to_none=True)
        finite = bool(torch.isfinite(loss))
        if finite:
            loss.backward()
            finite = bool(torch.isfinite(torch.nn.utils.clip_grad_norm_(model.parameters(), cfg.grad_clip)))
        if not finite:
            # One non-finite batch (a NaN pixel, an overflow) would turn every weight into NaN through the clipped
            # update and the EMA after it (a 128² GPU stage did, at step ~1000). Skip the update instead; stop,
            # keeping the last checkpoint, when it keeps happening.
            skipped, in_a_row = skipped + 1, in_a_row + 1
            names = sorted({zoo.CLASS_NAMES[i] for i in ids.tolist()})
            log(f"step {step + 1}: non-finite loss or gradient, update skipped (classes in the batch: {', '.join(names)})")
            if in_a_row >= MAX_SKIPPED_IN_A_ROW:
                raise RuntimeError(f"training diverged: {in_a_row} steps in a row with a non-finite loss or gradient "
                                   f"at step {step + 1}; the checkpoint in {out} is the last good one")
            continue
        in_a_row = 0
        opt.step()
        with torch.no_grad():
            for pe, pm_ in zip(ema.parameters(), model.parameters()):
                pe.lerp_(pm_, 1.0 - cfg.ema_decay)
        step += 1
        losses.append(float(mse.detach()))
        if max_seconds is not None and time.time() - t0 >= max_seconds:
            end = step  # out of wall time: log and checkpoint this step, then stop
        if step % cfg.log_every == 0 or step == end:
            last = dict(step=step, mse=float(np.mean(losses)), loss=float(loss.detach()), seconds=round(time.time() - t0, 2),
                        precision=precision, threads=torch.get_num_threads(), skipped=skipped,
                        emb_norm=float(model.class_emb.weight.detach().norm(dim=1).mean()))
            losses = []
            with open(os.path.join(out, "log.jsonl"), "a", encoding="utf-8") as fh:
                fh.write(json.dumps(last) + "\n")
            log(json.dumps(last))
        if step % cfg.checkpoint_every == 0 or step == end:
            _save(ckpt, dict(model=model.state_dict(), ema=ema.state_dict(), opt=opt.state_dict(), step=step,
                             rng=rng.bit_generator.state, gen=gen.get_state(), config=asdict(cfg)))
        if cfg.sample_every and step % cfg.sample_every == 0:
            save_samples(ema, cfg, device, os.path.join(out, f"samples_{step:07d}.png"))
    return last


def save_samples(model: UNet, cfg: TrainConfig, device, path: str) -> None:
    """A row of EMA samples (first 8 classes, default parameters) as a PNG."""
    from omninoise import export

    imgs = sample_grid(model, cfg, device)
    row = np.concatenate(list(imgs), axis=1)
    export.write_png(path, export.preview_8bit(row, 0.0, 1.0))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m omninoise.training.train", description=__doc__.split("\n")[0])
    ap.add_argument("--config", required=True, help="JSON config (see TrainConfig)")
    ap.add_argument("--out", required=True, help="run folder: checkpoint, log, samples")
    ap.add_argument("--max-steps", type=int, help="stop after this many more steps (resume later)")
    ap.add_argument("--max-seconds", type=float, help="stop, with a checkpoint, once this much wall time has passed")
    a = ap.parse_args(argv)
    try:
        if a.max_seconds is not None and not a.max_seconds > 0:
            raise ValueError(f"--max-seconds must be > 0, got {a.max_seconds:g}")
        cfg = load_config(a.config)
        if cfg.init_onnx and not os.path.isfile(os.path.join(a.out, "ckpt.pt")):
            exported_weights(cfg.init_onnx, cfg.init_sha256)  # a bad start fails here, in one line
    except (OSError, ValueError, ModelError) as exc:
        print(f"train: error: {exc}", file=sys.stderr)
        return 2
    try:
        train(cfg, a.out, a.max_steps, max_seconds=a.max_seconds)
    except RuntimeError as exc:  # diverged: the message names the step and the checkpoint kept
        print(f"train: error: {exc}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
