"""The procedural noise zoo: training data for the neural noise model (Maesumi et al. 2024).

The paper trained on 18 Adobe Substance noises; we cannot use them, so this zoo
rebuilds their families as batched torch generators (plus Gabor and Phasor
noise of the paper's Appendix B, Blender's texture nodes, and wave noise from our
own engine).  Each class has 1-4 interpretable parameters with documented
ranges and units.  Lengths are in pixels at the reference scale, where 128 px
is one "unit"; an image of another size shows more or fewer features of the
same pixel size, as the model must.

    >>> imgs = generate("cells_f1", {"scale": torch.tensor([8.0])}, seeds=torch.tensor([3]), size=128)
    >>> imgs.shape, imgs.dtype          # (1, 128, 128), float32 in [0, 1]

Conditioning (Sec. 3.1): the parameter vector is the union of every class's
parameter names (:data:`PARAM_NAMES`), each normalised to [0, 1] over its
class's range, zero where a class lacks it.  Parameter sets are drawn from a
Halton sequence (Sec. 4), several seeds per set.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np
import torch

from . import noise_ops as ops

__all__ = ["Param", "NoiseClass", "CLASSES", "CLASS_NAMES", "PARAM_NAMES", "generate", "halton",
           "condition_vector", "sample_params", "ZooSampler", "REF_PX", "default_params", "parse_params", "describe"]

REF_PX = 128.0  #: pixels per unit


@dataclass(frozen=True)
class Param:
    name: str
    lo: float
    hi: float
    unit: str
    integer: bool = False
    #: > 0: the images repeat every ``period`` of this parameter (an orientation of a kernel that is symmetric under
    #: a half turn: pi), and the conditioning carries ((v - lo) mod period) / period, so that one turn of the network's
    #: input is one turn of the pattern; 0: the range maps linearly onto [0, 1]
    period: float = 0.0

    def to_unit(self, v):
        return (v - self.lo) / (self.hi - self.lo)

    def condition(self, v: torch.Tensor) -> torch.Tensor:
        """Physical values (B,) -> the conditioning's [0, 1] values (B,) (see ``period``)."""
        if self.period > 0:
            return torch.remainder(v - self.lo, self.period) / self.period
        return ((v - self.lo) / (self.hi - self.lo)).clamp(0.0, 1.0)

    def from_unit(self, u):
        v = self.lo + u * (self.hi - self.lo)
        return torch.round(v) if self.integer and torch.is_tensor(v) else (round(v) if self.integer else v)


@dataclass(frozen=True)
class NoiseClass:
    name: str
    family: str
    params: tuple
    fn: Callable
    doc: str

    def param(self, name: str) -> Param:
        for p in self.params:
            if p.name == name:
                return p
        raise KeyError(name)


# -- generators: (x, y, seed, p: dict of (B,) tensors, size) -> (B, H, W) -------------------

def _u(p, k):
    return p[k].view(-1, 1, 1)


def _cells_f1(x, y, s, p, n):
    f1, _, _ = ops.worley(x * _u(p, "scale"), y * _u(p, "scale"), s, p["jitter"])
    return f1


def _cells_borders(x, y, s, p, n):
    f1, f2, _ = ops.worley(x * _u(p, "scale"), y * _u(p, "scale"), s, p["jitter"])
    return f2 - f1


def _warp(x, y, s, amount, scale, octaves=3, salt=7):
    r = torch.full_like(amount, 0.5)
    wx = ops.fbm(x * scale, y * scale, s, octaves, r, salt=salt)
    wy = ops.fbm(x * scale, y * scale, s, octaves, r, salt=salt + 50)
    a = amount.view(-1, 1, 1)
    return x + a * wx, y + a * wy


def _cells_distorted(x, y, s, p, n):
    sc = _u(p, "scale")
    wx, wy = _warp(x * sc, y * sc, s, p["distortion"], 0.5)
    f1, _, _ = ops.worley(wx, wy, s, torch.ones_like(p["scale"]))
    return f1


def _voronoi(x, y, s, p, n):
    sc = _u(p, "scale")
    wx, wy = _warp(x * sc, y * sc, s, p["distortion"], 0.5)
    _, _, v = ops.worley(wx, wy, s, torch.ones_like(p["scale"]))
    return v


def _microscope(x, y, s, p, n):
    sc = _u(p, "scale")
    wx, wy = _warp(x * sc, y * sc, s, p["distortion"], 0.8, octaves=4)
    f1, f2, _ = ops.worley(wx, wy, s, torch.full_like(p["scale"], 0.9))
    return ops.blur(torch.exp(-12.0 * (f2 - f1)), torch.full_like(p["scale"], 1.0))


def _perlin(x, y, s, p, n):
    return ops.perlin(x * _u(p, "scale"), y * _u(p, "scale"), s)


def _gaussian(x, y, s, p, n):
    ix = torch.floor(x * REF_PX).to(torch.int64)
    iy = torch.floor(y * REF_PX).to(torch.int64)
    white = ops.hash_unit(ix, iy, s.view(-1, 1, 1), 3) - 0.5
    return ops.blur(white, p["blur"])


def _clouds(x, y, s, p, n):
    sc = _u(p, "scale")
    octs = int(p["detail"].max().item())
    # per-sample octave count: octaves above a sample's detail get zero amplitude
    total = torch.zeros_like(x)
    norm = torch.zeros_like(sc)
    amp = torch.ones_like(sc)
    r = _u(p, "roughness")
    for o in range(octs):
        on = (o < p["detail"]).to(torch.float32).view(-1, 1, 1)
        total = total + on * amp * ops.perlin(x * sc * 2 ** o, y * sc * 2 ** o, s, 101 * o)
        norm = norm + on * amp
        amp = amp * r
    return total / norm


def _liquid(x, y, s, p, n):
    sc = _u(p, "scale")
    wx, wy = _warp(x * sc, y * sc, s, p["distortion"] * 2.0, 1.0, octaves=4, salt=11)
    return ops.fbm(wx, wy, s, 5, torch.full_like(p["scale"], 0.5), salt=300)


def _spots(x, y, s, p, n):
    v = ops.fbm(x * _u(p, "scale"), y * _u(p, "scale"), s, 3, torch.full_like(p["scale"], 0.45))
    v = ops.normalise(v)
    t = 1.0 - _u(p, "coverage")
    return torch.sigmoid((v - t) * 40.0)


def _fibers(x, y, s, p, n):
    ix = torch.floor(x * REF_PX).to(torch.int64)
    iy = torch.floor(y * REF_PX).to(torch.int64)
    white = ops.hash_unit(ix, iy, s.view(-1, 1, 1), 5) - 0.5
    sc = _u(p, "scale") / REF_PX  # cycles per pixel across fibres
    L = _u(p, "length")
    theta = _u(p, "orientation")  # a parameter, not drawn from the seed: see _ORIENTATION

    def resp(fx, fy):
        u = fx * torch.cos(theta) + fy * torch.sin(theta)   # along the fibres' normal
        v = -fx * torch.sin(theta) + fy * torch.cos(theta)  # along the fibres
        return torch.exp(-((u.abs() - sc) ** 2) / (2 * (sc * 0.5) ** 2)) * torch.exp(-(v * L * 8) ** 2)

    fib = ops.fft_filter(white, resp)
    return fib.abs()


def _galvanic(x, y, s, p, n):
    sc = _u(p, "scale")
    # clamped at 0: where |fbm| > 0.5 the ridge went negative and its fractional power below was NaN (one
    # 128² image in about 2700, enough to turn a GPU stage's weights into NaN at step ~1000)
    ridged = (1.0 - ops.fbm(x * sc, y * sc, s, 5, torch.full_like(sc.view(-1), 0.55)).abs() * 2.0).clamp(min=0.0)
    f1, f2, _ = ops.worley(x * sc * 2, y * sc * 2, s, torch.ones_like(sc.view(-1)), salt=40)
    return ridged ** (1.0 + 4.0 * _u(p, "contrast")) * (0.6 + 0.4 * torch.tanh(8 * (f2 - f1)))


def _leaky_paint(x, y, s, p, n):
    sc = _u(p, "scale")
    L = _u(p, "length")
    streak = ops.fbm(x * sc * 4.0, y * sc / L, s, 4, torch.full_like(sc.view(-1), 0.5))
    drips = ops.fbm(x * sc, y * sc, s, 3, torch.full_like(sc.view(-1), 0.5), salt=77)
    return torch.relu(streak * 1.5 + drips)


def _rust(x, y, s, p, n):
    r = p["roughness"]
    base = ops.normalise(ops.fbm(x * 3.0, y * 3.0, s, 6, r))
    blotch = torch.sigmoid((base - (1.0 - _u(p, "coverage"))) * 25.0)
    fine = ops.fbm(x * 24.0, y * 24.0, s, 3, r, salt=91)
    return blotch * (0.7 + 0.3 * fine)


def _damascus(x, y, s, p, n):
    wx, wy = _warp(x, y, s, p["distortion"] * 0.4, 2.0, octaves=4, salt=21)
    return torch.sin(2.0 * math.pi * _u(p, "frequency") * (wx * 0.8 + wy * 0.6))


def _gabor(x, y, s, p, n):
    """Gabor noise (Lagae et al. 2009) as white noise filtered by the kernel's spectrum:
    g(x) = exp(-pi a^2 |x|^2) cos(2 pi F w.x)  <->  Gaussians of width a at +-F w."""
    ix = torch.floor(x * REF_PX).to(torch.int64)
    iy = torch.floor(y * REF_PX).to(torch.int64)
    white = ops.hash_unit(ix, iy, s.view(-1, 1, 1), 13) - 0.5
    F, a, w = _u(p, "frequency"), _u(p, "bandwidth"), _u(p, "orientation")
    cx, cy = F * torch.cos(w), F * torch.sin(w)

    def resp(fx, fy):
        return (torch.exp(-math.pi * ((fx - cx) ** 2 + (fy - cy) ** 2) / a ** 2)
                + torch.exp(-math.pi * ((fx + cx) ** 2 + (fy + cy) ** 2) / a ** 2))

    return ops.fft_filter(white, resp)


def _phasor(x, y, s, p, n):
    """Phasor noise (Tricard et al. 2019): sin of the phase of a one-sided (complex) Gabor noise."""
    B, H, W = x.shape
    ix = torch.floor(x * REF_PX).to(torch.int64)
    iy = torch.floor(y * REF_PX).to(torch.int64)
    white = ops.hash_unit(ix, iy, s.view(-1, 1, 1), 17) - 0.5
    F = _u(p, "frequency") / REF_PX
    spread = _u(p, "spread") * (math.pi / 2) + 0.05
    th = _u(p, "orientation")  # [0, pi) is every phasor: th + pi draws the same image negated
    fy = torch.fft.fftfreq(H, device=x.device).view(1, H, 1)
    fx = torch.fft.fftfreq(W, device=x.device).view(1, 1, W)
    r = torch.sqrt(fx ** 2 + fy ** 2)
    ang = torch.atan2(fy, fx) - th
    d = torch.atan2(torch.sin(ang), torch.cos(ang))
    resp = torch.exp(-((r - F) ** 2) / (2 * (0.15 * F) ** 2)) * torch.exp(-(d ** 2) / (2 * spread ** 2))
    z = torch.fft.ifft2(torch.fft.fft2(white.to(torch.complex64)) * resp)
    return torch.sin(torch.angle(z))


def _blender_noise(x, y, s, p, n):
    """Blender's Noise Texture (2D): fBm of Perlin with Detail octaves (fractional), Roughness,
    lacunarity 2 and Distortion (a noise offset of the coordinates), at Scale per 128 px."""
    sc = _u(p, "Scale")
    px, py = x * sc, y * sc
    dist = _u(p, "Distortion")
    px = px + dist * ops.perlin(px + 13.5, py + 7.25, s, 61)
    py = py + dist * ops.perlin(px + 3.75, py + 21.5, s, 62)
    detail = p["Detail"].view(-1, 1, 1)
    r = _u(p, "Roughness")
    total = torch.zeros_like(x)
    norm = torch.zeros_like(sc)
    amp = torch.ones_like(sc)
    for o in range(int(math.floor(float(p["Detail"].max()))) + 2):
        w = (detail - o + 1).clamp(0.0, 1.0)  # the last octave fades in with Detail's fraction
        total = total + w * amp * ops.perlin(px * 2 ** o, py * 2 ** o, s, 201 * o)
        norm = norm + w * amp
        amp = amp * r
    return total / norm


def _blender_voronoi(x, y, s, p, n):
    """Blender's Voronoi Texture, F1 Distance (Euclidean), Scale per 128 px and Randomness."""
    f1, _, _ = ops.worley(x * _u(p, "Scale"), y * _u(p, "Scale"), s, p["Randomness"], salt=500)
    return f1


def _blender_wave(x, y, s, p, n):
    """Blender's Wave Texture, Bands along X, Sine profile:
    n = 20 Scale x + Distortion (2 fbm(Scale x, Scale y) - 1), value = 1/2 + 1/2 sin(n - pi/2)."""
    sc = _u(p, "Scale")
    octs = 1 + int(p["Detail"].max().item())
    d = ops.fbm(x * sc, y * sc, s, octs, torch.full_like(p["Scale"], 0.5), salt=700)  # about [-0.7, 0.7]
    return torch.sin(20.0 * sc * x + _u(p, "Distortion") * d * 2.0 - math.pi / 2)


def _blender_gabor(x, y, s, p, n):
    """Blender's Gabor Texture (2D), statistically: impulses of exp(-pi d^2) cos(2 pi F o.d) in
    Scale-scaled space, orientation theta + (1 - Anisotropy) U(-pi, pi); as white noise filtered
    by the angular average of the kernels' power spectra (the same second-order statistics)."""
    ix = torch.floor(x * REF_PX).to(torch.int64)
    iy = torch.floor(y * REF_PX).to(torch.int64)
    white = ops.hash_unit(ix, iy, s.view(-1, 1, 1), 23) - 0.5
    sc = _u(p, "Scale") / REF_PX  # scaled units per pixel
    F0 = _u(p, "Frequency") * sc  # cycles per pixel
    th, spread = _u(p, "Orientation"), (1.0 - _u(p, "Anisotropy")) * math.pi

    def resp(fx, fy):
        power = torch.zeros(x.shape[0], fy.shape[1], fx.shape[2], device=x.device)
        for k in range(32):
            phi = th + spread * ((k + 0.5) / 32 * 2.0 - 1.0)
            cx, cy = F0 * torch.cos(phi), F0 * torch.sin(phi)
            g = (torch.exp(-math.pi * ((fx - cx) ** 2 + (fy - cy) ** 2) / sc ** 2)
                 + torch.exp(-math.pi * ((fx + cx) ** 2 + (fy + cy) ** 2) / sc ** 2))
            power = power + g ** 2
        return torch.sqrt(power / 32)

    return ops.fft_filter(white, resp)


def _wave_engine(kind: str):
    def gen(x, y, s, p, n):
        from omninoise.backend.grid import evaluate_box
        from omninoise.backend.wavenoise.settings import WaveSettings, compile_noise
        from omninoise.backend.wavenoise.spectra import Spectrum

        out = []
        for b in range(x.shape[0]):
            seed = int(s[b].item()) % (1 << 24)
            if kind == "bandpass":
                f = float(p["frequency"][b])
                bw = float(p["bandwidth"][b])
                st = WaveSettings(dim=2, spectrum=Spectrum("bandpass", f * (1 - bw / 2), f * (1 + bw / 2)),
                                  directions=16, seed=seed)
            else:
                st = WaveSettings(dim=2, cellular="stit", cell_size=2.0 / float(p["scale"][b]), directions=3,
                                  stit_probability=float(p["split"][b]), stit_depth=3, seed=seed)
            noise = compile_noise(st)
            lo = np.array([float(x[b, 0, 0]), float(y[b, 0, 0])], np.float32)
            img = evaluate_box(noise, (x.shape[1], x.shape[2]), lo, (1 / REF_PX, 1 / REF_PX), "real",
                               cellular=st.cellular)
            out.append(torch.from_numpy(img))
        return torch.stack(out).to(x.device)

    return gen


#: The direction of fibres and of phasor noise's waves (radians, modulo pi).  It was once drawn from each image's
#: seed: a hidden variable that one whole image shares, which a network of finite reach cannot agree on across a
#: 256-px image (each region picked its own direction).  As a parameter it reaches every pixel through the
#: conditioning, and the artist sets it.
_ORIENTATION = Param("orientation", 0.0, math.pi, "radians, modulo pi")

_CLASSES = [
    NoiseClass("cells_f1", "worley", (Param("scale", 4, 20, "cells per 128 px"), Param("jitter", 0.2, 1.0, "cell jitter")),
               _cells_f1, "Worley F1 distance (Substance 'cells 1')"),
    NoiseClass("cells_borders", "worley", (Param("scale", 4, 20, "cells per 128 px"), Param("jitter", 0.2, 1.0, "cell jitter")),
               _cells_borders, "Worley F2 - F1: cell borders (Substance 'cells 4')"),
    NoiseClass("cells_distorted", "worley", (Param("scale", 3, 14, "cells per 128 px"),
                                             Param("distortion", 0.0, 1.5, "warp, cells")),
               _cells_distorted, "Worley F1 of domain-warped coordinates"),
    NoiseClass("voronoi", "worley", (Param("scale", 3, 14, "cells per 128 px"), Param("distortion", 0.0, 1.5, "warp, cells")),
               _voronoi, "flat random value per cell, domain-warped (Substance 'voronoi')"),
    NoiseClass("microscope", "worley", (Param("scale", 3, 10, "cells per 128 px"), Param("distortion", 0.5, 2.0, "warp, cells")),
               _microscope, "strongly warped soft cell membranes (Substance 'microscope view')"),
    NoiseClass("perlin", "gradient", (Param("scale", 2, 16, "cells per 128 px"),), _perlin, "one octave of Perlin noise"),
    NoiseClass("gaussian", "filtered", (Param("blur", 0.5, 8.0, "Gaussian sigma, px"),), _gaussian,
               "blurred white noise"),
    NoiseClass("clouds", "gradient", (Param("scale", 1, 8, "base cells per 128 px"), Param("roughness", 0.3, 0.8, "gain"),
                                      Param("detail", 2, 8, "octaves", integer=True)),
               _clouds, "fBm of Perlin noise (Substance 'clouds 1-3')"),
    NoiseClass("liquid", "gradient", (Param("scale", 1, 6, "cells per 128 px"), Param("distortion", 0.2, 2.0, "warp")),
               _liquid, "domain-warped fBm (Substance 'liquid')"),
    NoiseClass("spots", "threshold", (Param("scale", 2, 16, "cells per 128 px"), Param("coverage", 0.2, 0.8, "white fraction")),
               _spots, "black-and-white spots (Substance 'bnw spots')"),
    NoiseClass("fibers", "filtered", (Param("scale", 6, 24, "fibres per 128 px"), Param("length", 1.0, 8.0, "elongation"),
                                      _ORIENTATION),
               _fibers, "messy oriented fibres (Substance 'messy fibers')"),
    NoiseClass("galvanic", "grunge", (Param("scale", 2, 8, "cells per 128 px"), Param("contrast", 0.0, 1.0, "ridge sharpness")),
               _galvanic, "ridged fBm over cracked cells (Substance 'grunge galvanic')"),
    NoiseClass("leaky_paint", "grunge", (Param("scale", 2, 10, "cells per 128 px"), Param("length", 4, 24, "vertical stretch")),
               _leaky_paint, "vertical paint streaks (Substance 'grunge leaky paint')"),
    NoiseClass("rust", "grunge", (Param("coverage", 0.2, 0.8, "rust fraction"), Param("roughness", 0.4, 0.8, "gain")),
               _rust, "rust blotches with fine grain (Substance 'grunge rust fine')"),
    NoiseClass("damascus", "stripes", (Param("frequency", 3, 20, "stripes per 128 px"),
                                       Param("distortion", 0.2, 2.0, "warp")),
               _damascus, "warped stripes (Substance 'grunge damas')"),
    NoiseClass("gabor", "gabor", (Param("frequency", 0.02, 0.08, "cycles per px"), Param("bandwidth", 0.01, 0.35, "kernel a, 1/px"),
                                  Param("orientation", 0.0, 2 * math.pi, "radians", period=math.pi)),
               _gabor, "Gabor noise (Lagae et al. 2009; the paper's Appendix B, Table 3)"),
    NoiseClass("phasor", "gabor", (Param("frequency", 4, 16, "cycles per 128 px"), Param("spread", 0.0, 1.0, "angle spread"),
                                   _ORIENTATION),
               _phasor, "phasor noise (Tricard et al. 2019; Appendix B)"),
    NoiseClass("noise", "blender", (Param("Scale", 1, 10, "per 128 px"), Param("Detail", 0, 8, "octaves"),
                                    Param("Roughness", 0.3, 0.8, ""), Param("Distortion", 0.0, 2.0, "")),
               _blender_noise, "Blender's Noise Texture (fBm, its input names)"),
    NoiseClass("voronoi_f1", "blender", (Param("Scale", 2, 16, "per 128 px"), Param("Randomness", 0.0, 1.0, "")),
               _blender_voronoi, "Blender's Voronoi Texture, F1 distance"),
    NoiseClass("wave_bands", "blender", (Param("Scale", 0.5, 4.0, "per 128 px (20/2pi bands each)"),
                                         Param("Distortion", 0.0, 10.0, ""), Param("Detail", 0, 4, "octaves", integer=True)),
               _blender_wave, "Blender's Wave Texture, bands along X, sine profile"),
    NoiseClass("wave_bandpass", "wave", (Param("frequency", 2, 12, "cycles per 128 px"),
                                         Param("bandwidth", 0.2, 1.0, "relative band width")),
               _wave_engine("bandpass"), "band-pass wave noise (Guehl et al. 2025)"),
    NoiseClass("wave_cellular", "wave", (Param("scale", 3, 12, "cells per 128 px"), Param("split", 0.2, 0.8, "STIT split probability")),
               _wave_engine("stit"), "STIT cellular wave noise (Guehl et al. 2025, Alg. 2)"),
    NoiseClass("gabor_texture", "blender", (Param("Scale", 2.0, 10.0, "per 128 px"), Param("Frequency", 1.0, 4.0, ""),
                                            Param("Anisotropy", 0.0, 1.0, ""),
                                            Param("Orientation", 0.0, math.pi, "radians")),
               _blender_gabor, "Blender's Gabor Texture (2D), Value output"),
]

#: append-only: a class's index and each parameter's slot are part of every trained model
CLASSES = {c.name: c for c in _CLASSES}
CLASS_NAMES = tuple(c.name for c in _CLASSES)
#: append-only as well: a name keeps the slot it was given when it first appeared (fibres and phasor took up
#: gabor's "orientation" later, so the order is written out rather than derived from the class list)
PARAM_NAMES = ("scale", "jitter", "distortion", "blur", "roughness", "detail", "coverage", "length", "contrast",
               "frequency", "bandwidth", "orientation", "spread", "Scale", "Detail", "Roughness", "Distortion",
               "Randomness", "split", "Frequency", "Anisotropy", "Orientation")
assert {p.name for c in _CLASSES for p in c.params} == set(PARAM_NAMES), "a new parameter name is appended here"


def generate(name: str, params: dict, seeds: torch.Tensor, size: int, device=None) -> torch.Tensor:
    """Images of class ``name``: params {name: (B,) physical values}, seeds (B,) int -> float32 (B, size, size) in [0, 1].

    Each seed also picks the sample's position in the plane (a random offset),
    so two seeds show unrelated patches.
    """
    cls = CLASSES[name]
    seeds = torch.as_tensor(seeds, dtype=torch.int64, device=device).view(-1)
    B = seeds.shape[0]
    p = {}
    for spec in cls.params:
        if spec.name not in params:
            raise KeyError(f"{name} needs parameter {spec.name!r}")
        v = torch.as_tensor(params[spec.name], dtype=torch.float32, device=device).view(-1).expand(B).clone()
        p[spec.name] = v
    z = torch.zeros_like(seeds)
    # a whole number of pixels, so pixel-lattice classes (white noise) never repeat a column
    off = torch.floor(torch.stack([ops.hash_unit(z, z, seeds, 1001), ops.hash_unit(z, z, seeds, 1002)], 1)
                      * (64.0 * REF_PX)) / REF_PX
    x, y = ops.grid(B, size, off, REF_PX, device)
    img = cls.fn(x, y, seeds, p, size)
    return ops.normalise(img.to(torch.float32))


def halton(n: int, dim: int, start: int = 1) -> np.ndarray:
    """Halton points float64 (n, dim) in [0, 1): radical inverses in the first ``dim`` primes."""
    primes = [2, 3, 5, 7, 11, 13, 17, 19, 23, 29][:dim]
    out = np.empty((n, dim))
    for d, b in enumerate(primes):
        for i in range(n):
            k, f, r = start + i, 1.0, 0.0
            while k > 0:
                f /= b
                r += f * (k % b)
                k //= b
            out[i, d] = r
    return out


def sample_params(name: str, index: np.ndarray) -> dict:
    """Parameter sets number ``index`` (int array) of class ``name`` from its Halton sequence -> {name: (n,) floats}."""
    cls = CLASSES[name]
    h = np.stack([halton(1, len(cls.params), int(i) + 1)[0] for i in np.atleast_1d(index)])
    out = {}
    for d, spec in enumerate(cls.params):
        v = spec.lo + h[:, d] * (spec.hi - spec.lo)
        out[spec.name] = np.round(v) if spec.integer else v
    return out


def condition_vector(name: str, params: dict) -> torch.Tensor:
    """float32 (B, len(PARAM_NAMES)): each of the class's parameters mapped to [0, 1], zeros elsewhere."""
    cls = CLASSES[name]
    first = torch.as_tensor(params[cls.params[0].name], dtype=torch.float32).view(-1)
    out = torch.zeros(first.shape[0], len(PARAM_NAMES))
    for spec in cls.params:
        v = torch.as_tensor(params[spec.name], dtype=torch.float32).view(-1)
        out[:, PARAM_NAMES.index(spec.name)] = spec.condition(v)
    return out


def class_probabilities(classes, weights: dict) -> np.ndarray:
    """float64 (n,) shares of ``classes`` drawn with ``weights`` (name -> weight > 0, 1 where absent).
    ValueError naming a weighted class that is not among ``classes``, or a weight that is not positive."""
    for name, w in weights.items():
        if name not in classes:
            raise ValueError(f"class_weights names {name!r}, which is not among the trained classes")
        if not (isinstance(w, (int, float)) and not isinstance(w, bool) and w > 0 and math.isfinite(w)):
            raise ValueError(f"class_weights[{name!r}] must be a positive number, got {w!r}")
    w = np.array([float(weights.get(c, 1.0)) for c in classes])
    return w / w.sum()


class ZooSampler:
    """On-the-fly training batches: Halton parameter sets, ``seeds_per_set`` seeds each.

    batch(b) -> images float32 (b, 1, S, S) in [0, 1], class ids int64 (b,), conditions float32 (b, P).
    """

    def __init__(self, size: int, classes=CLASS_NAMES, seeds_per_set: int = 4, sets_per_class: int = 16384,
                 rng: np.random.Generator | None = None, device=None, class_weights: dict | None = None):
        self.size, self.classes, self.device = size, tuple(classes), device
        self.seeds_per_set, self.sets = seeds_per_set, sets_per_class
        self.rng = rng if rng is not None else np.random.default_rng(0)
        #: probability of each class per image: ``class_weights`` (name -> weight, 1 where absent), normalised;
        #: None for equal shares (drawn as before, so older runs resume on the same batches)
        self.p = class_probabilities(self.classes, class_weights) if class_weights else None

    def batch(self, b: int):
        if self.p is None:
            cls_idx = self.rng.integers(0, len(self.classes), size=b)
        else:
            cls_idx = self.rng.choice(len(self.classes), size=b, p=self.p)
        sample = self.rng.integers(0, self.sets * self.seeds_per_set, size=b)
        imgs = torch.empty(b, 1, self.size, self.size)
        conds = torch.zeros(b, len(PARAM_NAMES))
        for c in np.unique(cls_idx):
            sel = np.nonzero(cls_idx == c)[0]
            name = self.classes[c]
            sets = sample[sel] // self.seeds_per_set
            params = sample_params(name, sets)
            seeds = torch.as_tensor(CLASS_NAMES.index(name) * 10_000_000 + sample[sel], dtype=torch.int64)
            imgs[sel, 0] = generate(name, params, seeds, self.size, self.device).cpu()
            conds[sel] = condition_vector(name, params)
        ids = torch.as_tensor([CLASS_NAMES.index(self.classes[c]) for c in cls_idx], dtype=torch.int64)
        return imgs, ids, conds


def default_params(name: str) -> dict:
    """The middle of every parameter's range (integers rounded)."""
    return {p.name: float(p.from_unit(0.5)) for p in CLASSES[name].params}


def parse_params(name: str, items: list) -> dict:
    """['scale=8', ...] -> physical values for class ``name``; unknown names and out-of-range values raise ValueError."""
    if name not in CLASSES:
        raise ValueError(f"unknown noise class {name!r}; choose one of {', '.join(CLASS_NAMES)}")
    cls = CLASSES[name]
    out = default_params(name)
    for item in items or []:
        key, sep, val = item.partition("=")
        if not sep:
            raise ValueError(f"expected NAME=VALUE, got {item!r}")
        try:
            spec = cls.param(key)
        except KeyError:
            raise ValueError(f"{name} has no parameter {key!r}; it has {', '.join(p.name for p in cls.params)}") from None
        try:
            v = float(val)
        except ValueError:
            raise ValueError(f"{key}: {val!r} is not a number") from None
        if not spec.lo <= v <= spec.hi:
            raise ValueError(f"{key}={v:g} is outside [{spec.lo:g}, {spec.hi:g}] ({spec.unit})")
        out[key] = v
    return out


def describe() -> dict:
    """Classes and their parameters as plain JSON types."""
    return {c.name: dict(family=c.family, doc=c.doc, params=[_describe_param(p) for p in c.params]) for c in _CLASSES}


def _describe_param(p: Param) -> dict:
    d = dict(name=p.name, min=p.lo, max=p.hi, unit=p.unit, integer=p.integer)
    if p.period > 0:  # only then: a model exported before periods existed keeps its JSON, and the runtime its mapping
        d["period"] = p.period
    return d
