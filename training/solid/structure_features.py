"""Structure features trained on the photo set: a loss that tells a photo's arrangement from a Gaussian field.

The random-feature losses of :mod:`.swd` and :mod:`.arrangement` hardly separate a photo from the
blotches the solid models draw: a single-exemplar fit of a paving photo ends at a training loss of
0.09-0.11, where the photo's own crops score 0.086 (docs/decisions/solid.md).
Random filters see second-order statistics and local colour; what the blotches lack is the phase
structure of the photo: edges that run on, closed outlines, joints.  So these features are *learned*:
a small CNN is trained to tell a crop of a training photo from the same crop with its Fourier phases
randomised (Galerne et al. 2011: the random-phase texture keeps the power spectrum exactly and
nothing else).  Both are rank-Gaussianised first (:func:`.arrangement.gaussianise`: the same N(0, 1)
marginal), and the phase is randomised on the crop's periodic component (Moisan 2011,
:func:`training.evaluate.periodic_component`), so neither the histogram, the spectrum nor the crop's
border jumps can tell them apart: only the arrangement can.  Its hidden layers are then read like the
random features of :mod:`.swd` (sliced Wasserstein distance of their distributions, Heitz et al. 2021).

No downloaded weights: the network is trained here, by ``train_structure_net`` from the photo set's
training split, in a few minutes on 2 cores; held-out photos measure its accuracy.

Shapes: images (B, 3, H, W) float32 in [0, 1]; the network itself reads (B, 1, H, W) Gaussianised luminance.
"""
from __future__ import annotations

import math
import os
import time

import numpy as np
import torch
import torch.nn.functional as F
from torch import nn

from .arrangement import gaussianise, luminance

__all__ = ["StructureNet", "StructureFeatures", "phase_randomised", "structure_batch", "train_structure_net",
           "save_photo_set_net", "load_structure_net"]


class StructureNet(nn.Module):
    """Three levels of two 'valid' 3 x 3 (first 5 x 5) ReLU convolutions, average pooling between them; the
    logit of 'a real arrangement' from the spatial means of every level's last features."""

    def __init__(self, width: int = 32):
        super().__init__()
        w = (width, 2 * width, 4 * width)
        self.convs = nn.ModuleList([
            nn.Conv2d(1, w[0], 5), nn.Conv2d(w[0], w[0], 3),
            nn.Conv2d(w[0], w[1], 3), nn.Conv2d(w[1], w[1], 3),
            nn.Conv2d(w[1], w[2], 3), nn.Conv2d(w[2], w[2], 3)])
        self.head = nn.Linear(sum(w), 1)
        self.width = width

    def taps(self, g: torch.Tensor) -> list:
        """Feature maps (B, C_l, H_l, W_l) after each level, of Gaussianised luminance g (B, 1, H, W)."""
        out, x = [], g
        for i in range(0, 6, 2):
            if i:
                x = F.avg_pool2d(x, 2)
            x = F.relu(self.convs[i + 1](F.relu(self.convs[i](x))))
            out.append(x)
        return out

    def forward(self, g: torch.Tensor) -> torch.Tensor:
        return self.head(torch.cat([t.mean(dim=(2, 3)) for t in self.taps(g)], 1))[:, 0]


def phase_randomised(g: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Random-phase twins (Galerne et al. 2011) of images g (n, H, W): the moduli of the Fourier transform of each
    image's periodic component with the phases of white noise's, the mean kept, then rank-mapped back onto the
    image's own values (same histogram).  float32 (n, H, W)."""
    from omninoise.backend.periodic import periodic_component

    p = periodic_component(g)
    n, H, W = g.shape
    phase = np.angle(np.fft.fft2(rng.standard_normal((n, H, W))))
    mod = np.abs(np.fft.fft2(p - p.mean(axis=(1, 2), keepdims=True)))
    f = np.real(np.fft.ifft2(mod * np.exp(1j * phase)))
    out = np.empty_like(g, dtype=np.float32)
    for i in range(n):  # histogram specification: f's ranks take g's sorted values
        out[i].flat[np.argsort(f[i], axis=None)] = np.sort(g[i], axis=None)
    return out


def _gauss(img: torch.Tensor) -> torch.Tensor:
    return gaussianise(luminance(img))


def structure_batch(images: list, batch: int, size: int, rng: np.random.Generator) -> tuple:
    """``batch`` crops of random photos (list of (3, H, W)) and their random-phase twins, Gaussianised:
    (2 batch, 1, size, size) float32 and labels (2 batch,) (1 real, 0 twin)."""
    crops = []
    for _ in range(batch):
        im = images[int(rng.integers(len(images)))]
        _, H, W = im.shape
        y, x = int(rng.integers(H - size + 1)), int(rng.integers(W - size + 1))
        c = im[:, y:y + size, x:x + size]
        c = torch.rot90(c, int(rng.integers(4)), dims=(1, 2))
        crops.append(c)
    real = _gauss(torch.stack(crops))                      # (B, 1, S, S)
    twin = torch.from_numpy(phase_randomised(real[:, 0].numpy().astype(np.float64), rng)).unsqueeze(1)
    x = torch.cat([real, twin]).float()
    y = torch.cat([torch.ones(batch), torch.zeros(batch)])
    return x, y


def train_structure_net(train_images: list, val_images: list, steps: int = 1500, batch: int = 32, size: int = 64,
                        width: int = 32, lr: float = 2e-3, seed: int = 0, log=print) -> tuple:
    """Train a :class:`StructureNet` on photo crops against their random-phase twins: returns (net, record) with
    the held-out accuracy (crops of ``val_images``, whole photos the training never saw)."""
    torch.manual_seed(seed)
    rng = np.random.default_rng(seed)
    net = StructureNet(width)
    opt = torch.optim.AdamW(net.parameters(), lr=lr, weight_decay=1e-4)
    t0 = time.time()
    for step in range(steps):
        for g in opt.param_groups:
            g["lr"] = lr * 0.5 * (1 + math.cos(math.pi * step / steps))
        x, y = structure_batch(train_images, batch, size, rng)
        loss = F.binary_cross_entropy_with_logits(net(x), y)
        opt.zero_grad(set_to_none=True)
        loss.backward()
        opt.step()
        if (step + 1) % 100 == 0:
            log(f"structure net: step {step + 1}/{steps} loss {loss.item():.4f} ({time.time() - t0:.0f} s)")
    net.eval()
    vrng = np.random.default_rng(seed + 1)
    correct = total = 0
    with torch.no_grad():
        for _ in range(8):
            x, y = structure_batch(val_images, 64, size, vrng)
            correct += int(((net(x) > 0).float() == y).sum())
            total += len(y)
    record = dict(steps=steps, batch=batch, size=size, width=width, lr=lr, seed=seed,
                  seconds=round(time.time() - t0, 1), val_accuracy=round(correct / total, 4))
    return net, record


def load_structure_net(path: str) -> StructureNet:
    state = torch.load(path, map_location="cpu", weights_only=False)
    net = StructureNet(state["record"]["width"])
    net.load_state_dict(state["weights"])
    return net.eval()


class StructureFeatures(nn.Module):
    """The trained net's feature maps of an image's Gaussianised luminance, for :func:`.swd.swd_loss` (each
    level's ReLU features are one tap; the net's weights are frozen)."""

    def __init__(self, net: StructureNet):
        super().__init__()
        self.net = net
        for p in self.net.parameters():
            p.requires_grad_(False)

    def forward(self, img: torch.Tensor) -> list:
        return self.net.taps(_gauss(img))


def save_photo_set_net(out: str, steps: int = 1500, width: int = 32, seed: int = 0, threads: int = 2,
                       log=print) -> dict:
    """Train the structure network on the photo set (its training photos, held out on its validation photos, each
    at least 64 px a side) and write it to ``out`` atomically (weights and record); returns the record."""
    from omninoise import export as _ex

    from . import exemplars as ex
    from ..threads import cpu_threads

    size = 64
    with cpu_threads(threads):
        train = [im for im in map(ex.load_image, ex.photo_set("train")) if min(im.shape[1:]) >= size]
        val = [im for im in map(ex.load_image, ex.photo_set("val")) if min(im.shape[1:]) >= size]
        net, record = train_structure_net(train, val, steps=steps, width=width, seed=seed, log=log)
    os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
    with _ex.atomic_path(out) as tmp:
        torch.save(dict(weights=net.state_dict(), record=record), tmp)
    return record


def main(argv=None) -> int:
    import argparse

    ap = argparse.ArgumentParser(prog="python -m omninoise.training.solid.structure_features",
                                 description="Train the structure network on the photo set.")
    ap.add_argument("--out", required=True, help="the network file to write (weights and record)")
    ap.add_argument("--steps", type=int, default=1500)
    ap.add_argument("--width", type=int, default=32)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--threads", type=int, default=2)
    a = ap.parse_args(argv)
    if a.steps < 1 or a.width < 1:
        ap.error("--steps and --width must be at least 1")
    print(save_photo_set_net(a.out, a.steps, a.width, a.seed, a.threads, log=lambda s: print(s, flush=True)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
