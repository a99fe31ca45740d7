"""Fit a :class:`~training.solid.conv_generator.ConvGenerator` to one photo (the capacity question).

Each step draws fresh noise, generates ``batch`` textures of side ``cfg.crop`` (2D images, or 3D volumes of which
one random slice normal to each axis is kept, as Gutierrez et al. 2020 train solid generators from 2D
exemplars, Sec. 3.2), colours them with the photo's mean and colour Cholesky factor (rgb = mu + L d, as the
affine per-point decoders) and asks them to match random crops of the photo under the config's texture loss
(``train.texture_loss``: sliced Wasserstein distances of random features, the colour histogram and the optional
terms). Adam with the config's cosine learning-rate decay; gradients clipped to norm 1. The generator's
convolutions may run under bf16 autocast; colour and loss stay fp32. A fit hands out checkpoints (step, schedule
length, weights, optimiser, the random generator's state, seconds) and resumes from one exactly: a fit stopped and
resumed draws the same crops and noise and ends with the same weights as one run straight through.

Shapes: photo (3, H, W) float32 in [0, 1]; generated textures (B, 3, S, S[, S]).
"""
from __future__ import annotations

import copy
import math
import time

import torch

from ..precision import autocast
from . import exemplars as ex
from .conv_generator import ConvGenerator, draw_noise
from .model import apply_colour, colour_stats

__all__ = ["colour", "volume_slices", "fit", "FIT_FROM", "FIT_TO"]

FIT_FROM, FIT_TO = 5, 25     # with a time budget: the steps whose rate sets the number of steps


def colour(d: torch.Tensor, stats: torch.Tensor) -> torch.Tensor:
    """Whitened colour d (B, 3, ...) and colour statistics (1 or B, 12) -> rgb (B, 3, ...) = mu + L d."""
    rgb = apply_colour(d.flatten(2).transpose(1, 2), stats.expand(d.shape[0], -1))
    return rgb.transpose(1, 2).reshape(d.shape)


def volume_slices(vol: torch.Tensor, generator: torch.Generator, upright: bool = False) -> torch.Tensor:
    """Random slices of volumes (B, 3, Z, Y, X), the same indices for every volume: one normal to each axis,
    (3B, 3, S, S) with the z slices first; or, ``upright``, only the two through the vertical axis, (2B, 3, S, S),
    the x slices first, each with z along its rows (a wall's view, as ``fixed_axis`` models are trained)."""
    S = vol.shape[-1]
    i, j, k = (int(v) for v in torch.randint(0, S, (3,), generator=generator))
    walls = [vol[:, :, :, :, k], vol[:, :, :, j]]
    return torch.cat(walls if upright else [vol[:, :, i]] + walls)


def fit(cfg, net: ConvGenerator, photo: torch.Tensor, steps: int, feats, loss_fn, precision: str = "fp32",
        log=print, device: str = "cpu", upright: bool = False, budget_seconds: float | None = None,
        resume: dict | None = None, save=None, save_every: int = 0) -> tuple:
    """Train ``net`` in place for ``steps`` on ``photo`` with ``cfg``'s crop, batch, learning rates, seed and
    log_every; ``loss_fn(cfg, feats, images, crops, generator)`` is the texture loss. ``net`` and ``feats`` on
    ``device``; the random draws stay on the CPU's generator, so a fit's data is the same on any device.
    In 3D, ``upright`` asks only the slices through the vertical axis to match the photo, upright (courses,
    strata and grain keep their direction; otherwise crops are turned and flipped at random, since each slice of
    an isotropic solid may show the photo any way up). ``budget_seconds``: the rate of steps FIT_FROM to FIT_TO
    sets how many steps fit in the budget (never more than ``steps``), and the learning-rate decay follows them.
    ``save(checkpoint)`` is called every ``save_every`` steps and at the end with a dict that ``resume`` takes
    back: the fit goes on from its step to its schedule's length (``steps`` and the budget are then ignored).
    Returns (seconds taken, steps taken)."""
    dev = torch.device(device)
    stats = colour_stats(photo.unsqueeze(0)).to(dev)
    g = torch.Generator().manual_seed(cfg.seed)
    opt = torch.optim.Adam(net.parameters(), lr=cfg.lr)
    t0 = time.time()
    step = 0
    if resume is not None:
        net.load_state_dict(resume["net"])
        opt.load_state_dict(resume["opt"])
        g.set_state(resume["generator"])
        step, steps, budget_seconds = resume["step"], resume["steps"], None
        t0 -= resume["seconds"]

    def checkpoint() -> dict:       # copies: the live state dicts' tensors change with the next step
        return copy.deepcopy(dict(step=step, steps=steps, net=net.state_dict(), opt=opt.state_dict(),
                                  generator=g.get_state(), seconds=time.time() - t0))

    while step < steps:
        lr = cfg.lr_min + 0.5 * (cfg.lr - cfg.lr_min) * (1 + math.cos(math.pi * step / steps))
        for grp in opt.param_groups:
            grp["lr"] = lr
        views = 1 if net.dim == 2 else 2 if upright else 3
        ref = ex.random_crops(photo, cfg.batch * views, cfg.crop, g, augment=net.dim == 3 and not upright).to(dev)
        z = draw_noise(cfg.batch, cfg.crop, net.dim, net.scales, net.noise, g, dev)
        with autocast(precision, dev):
            d = net(z)
        img = colour(d.float(), stats)
        if net.dim == 3:
            img = volume_slices(img, g, upright)
        loss = loss_fn(cfg, feats, img, ref, g)
        opt.zero_grad(set_to_none=True)
        loss.backward()
        torch.nn.utils.clip_grad_norm_(net.parameters(), 1.0)
        opt.step()
        step += 1
        if budget_seconds is not None and step in (FIT_FROM, FIT_TO):
            if dev.type == "cuda":
                torch.cuda.synchronize(dev)     # the rate of finished steps, not of queued kernels
            if step == FIT_FROM:
                t_fit = time.time()
            else:
                rate = (time.time() - t_fit) / (FIT_TO - FIT_FROM)
                steps = max(FIT_TO, min(steps, FIT_TO + int((budget_seconds - (time.time() - t0)) / rate)))
                log(f"{rate:.3f} s a step: {steps} steps fit in {budget_seconds:.0f} s")
        if step % cfg.log_every == 0 or step == steps:
            log(f"step {step}/{steps} loss {loss.item():.4f} ({time.time() - t0:.0f} s)")
        if save is not None and ((save_every and step % save_every == 0) or step == steps):
            save(checkpoint())
    return time.time() - t0, steps
