"""Networks of the neural solid texture (Henzler, Mitra, Ritschel, CVPR 2020, Sec. 3-4).

    z = g(y)                  encoder: exemplar patch (B, 3, 128, 128) -> code z (B, 8)
    {e, T_1..T_m} = h(z)      translator: z -> extended code e (B, 64) and one D x D transform per octave
    s(x | z) = f(n | e),  n_i = noise(T_i 2^(i-1) x | xi_i)                                   (Eq. 5)

The decoder f is an MLP (four layers of 128, ReLU, then RGB through a
sigmoid) over [n, e]; position x never enters it, which is what gives
diversity by construction (Sec. 4).  Single mode optimises e and T directly
(with the decoder); space mode trains g, h and f jointly.

Colour (``colour="affine"``, the photo models): the decoder's output d is
linear, and the colour is mu + L d with the exemplar's mean colour mu and the
Cholesky factor L of its colour covariance, computed from the exemplar's
pixels (:func:`colour_stats`), not learned.  The mean colour of the texture
is then the photo's by construction whatever the encoder makes of it (the
first space model, which had to learn colour through a sigmoid, was off by
0.165 on unseen photos); the network learns the whitened texture.
``colour="sigmoid"`` is the paper's RGB through a sigmoid (earlier models).

Every T_i starts as a fixed random rotation R_i (seeded), so the octaves'
lattices are not aligned with each other or with the axes; the translator and
the single-mode parameters learn T_i = R_i (I + Delta_i).
"""
from __future__ import annotations

import math

import torch
from torch import nn

from omninoise.backend.solid.brick import FEATURES as BRICK_FEATURES
from omninoise.backend.solid.cellular import FEATURES as CELL_FEATURES
from omninoise.backend.solid.spin import check_mode
from omninoise.backend.solid.waves import FEATURES as WAVE_FEATURES
from ..precision import autocast
from .brick import brick_features
from .cellular import cellular_features
from .value_noise import value_noise, spun_torch
from .waves import wave_features

__all__ = [
    "shape_features", "colour_stats", "spectral_aspect", "COLOUR_STATS", "spectral_gains", "detail_levels",
    "GAIN_RANGE", "max_scales", "Decoder", "Encoder", "Translator", "SolidTexture", "random_rotations",
    "FIXED_AXES", "FIXED_AXES_2D", "fixed_axis_index", "check_fixed_axis", "check_max_stretch", "axis_frame",
    "axis_rotations", "slice_points",
]


def shape_features(cellular: int, bricks: int) -> int:
    """How many values the cellular and brick octaves add to the decoder's input (after the value noise)."""
    return CELL_FEATURES * cellular + BRICK_FEATURES * bricks


def random_rotations(octaves: int, dim: int, seed: int = 0) -> torch.Tensor:
    """Fixed random rotations (octaves, dim, dim) float32 (QR of a seeded Gaussian, det +1)."""
    g = torch.Generator().manual_seed(seed)
    out = []
    for _ in range(octaves):
        q, r = torch.linalg.qr(torch.randn(dim, dim, generator=g, dtype=torch.float64))
        q = q * torch.sign(torch.diagonal(r)).unsqueeze(0)
        if torch.det(q) < 0:
            q[:, 0] = -q[:, 0]
        out.append(q)
    return torch.stack(out).to(torch.float32)


#: ``fixed_axis`` -> the axis of space the photo's direction lies on: "columns" (its horizontal) on x, "rows"
#: (its vertical) on z
FIXED_AXES = {"columns": 0, "rows": 2}
#: the same in a 2D model, whose plane is the photo's: its horizontal is x, its vertical y
FIXED_AXES_2D = {"columns": 0, "rows": 1}


def fixed_axis_index(fixed_axis: str, dim: int) -> int:
    """The coordinate (0 .. dim - 1) that ``fixed_axis`` puts the photo's direction on."""
    return (FIXED_AXES_2D if dim == 2 else FIXED_AXES)[fixed_axis]


def check_fixed_axis(fixed_axis: str) -> None:
    if fixed_axis and fixed_axis not in FIXED_AXES:
        raise ValueError(f"fixed_axis must be '', 'columns' or 'rows', got {fixed_axis!r}")


def axis_frame(fixed_axis: str, t: float) -> list:
    """The image axes (u, v) in space, [u (3,), v (3,)] as lists, of the plane through the fixed axis turned by
    angle t about it: "columns": u = x, v = (0, cos t, sin t); "rows": u = (cos t, sin t, 0), v = z (image up)."""
    c, s = math.cos(t), math.sin(t)
    return [[1.0, 0.0, 0.0], [0.0, c, s]] if fixed_axis == "columns" else [[c, s, 0.0], [0.0, 0.0, 1.0]]


def axis_rotations(octaves: int, fixed_axis: str, seed: int = 0, dim: int = 3) -> torch.Tensor:
    """Transforms (octaves, dim, dim) float32 that keep a direction of space on the lattice's second axis (the
    brick lattice's rows, :mod:`backend.solid.brick`) and turn the plane across it by a seeded uniform angle
    per octave: "columns" keeps x, "rows" keeps z (det +1).  A single-exemplar model trained with
    ``fixed_axis`` starts from these, so its lattices start aligned with the photo's direction.

    In 2D the plane is the photo's own and is never turned (``slice_points``), so there is nothing to turn
    about the axis: "rows" is the identity (the lattice's rows run along the photo's rows, p_1 = y) and
    "columns" the quarter turn with p_1 = x, for every octave."""
    if dim == 2:
        T = torch.eye(2) if fixed_axis == "rows" else torch.tensor([[0.0, -1.0], [1.0, 0.0]])
        return T.expand(octaves, 2, 2).clone()
    g = torch.Generator().manual_seed(seed)
    axis = FIXED_AXES[fixed_axis]
    a, b = [k for k in range(3) if k != axis]
    out = []
    for _ in range(octaves):
        t = float(torch.rand(1, generator=g)) * 2.0 * math.pi
        c, s = math.cos(t), math.sin(t)
        T = torch.zeros(3, 3, dtype=torch.float64)
        T[0, a], T[0, b] = c, s          # p_0: a direction across the axis
        T[1, axis] = 1.0                 # p_1: along the axis
        T[2, a], T[2, b] = s, -c         # p_2: the other direction across it
        if torch.det(T) < 0:
            T[2] = -T[2]
        out.append(T)
    return torch.stack(out).to(torch.float32)


COLOUR_STATS = 12   #: mu (3) and L (3 x 3, row-major) appended to a photo model's code z
GAIN_RANGE = (0.1, 3.0)   #: spectral gains are clamped to this range


def detail_levels(px_per_unit: float, octaves: int) -> list:
    """The Haar-pyramid level whose detail octave i of the noise makes: value noise of lattice spacing
    s = px_per_unit / 2^i px varies at frequencies below 1/(2 s), the band of level log2(s) (level L: means
    over 2^L px blocks minus means over 2^(L+1) px blocks), clamped to >= 0."""
    top = int(round(math.log2(px_per_unit)))
    return [max(top - i, 0) for i in range(octaves)]


def spectral_gains(img: torch.Tensor, octaves: int = 8, px_per_unit: float = 128.0) -> torch.Tensor:
    """Per-octave gains g_i of an exemplar: (B, 3, H, W) -> (B, octaves) in GAIN_RANGE.

    The luminance's variance is split over the levels of a Haar pyramid (band_L = G_L - up(G_{L+1}) with 2x2
    means G; the bands' mean squares add up to the variance); octave i reads the share s_i of its level
    (:func:`detail_levels`) and g_i = sqrt(m s_i / sum_j s_j): 1 everywhere for an image whose detail is
    spread evenly, larger where it has more.  The sampler multiplies octave i's noise by g_i before the
    decoder (Eq. 5), so a fine-grained photo gets fine-grained noise and a smooth one smooth noise, measured
    from the photo as its colours are (the numpy twin: ``backend.solid.model.spectral_gains``)."""
    levels = detail_levels(px_per_unit, octaves)
    y = img.mean(1, keepdim=True)
    g = y - y.mean(dim=(2, 3), keepdim=True)
    energy = []
    for _ in range(max(levels) + 1):
        h, w = g.shape[-2] // 2 * 2, g.shape[-1] // 2 * 2
        if h < 2 or w < 2:          # coarser than the image: the coarsest level it has stands in
            energy.append(energy[-1] if energy else g.new_zeros(g.shape[0]))
            continue
        g = g[..., :h, :w]
        c = torch.nn.functional.avg_pool2d(g, 2)
        band = g - torch.nn.functional.interpolate(c, scale_factor=2, mode="nearest")
        energy.append((band ** 2).mean(dim=(1, 2, 3)))
        g = c
    e = torch.stack([energy[L] for L in levels], dim=1) + 1e-12
    return torch.sqrt(octaves * e / e.sum(dim=1, keepdim=True)).clamp(*GAIN_RANGE)


def spectral_aspect(img: torch.Tensor) -> float:
    """How much longer an exemplar's features run across than down: (3, H, W) -> sqrt(E[f_x²] / E[f_y²]), the
    spread of horizontal over vertical frequencies in the luminance's power spectrum (Hann window, mean
    removed).  1 for an isotropic texture; < 1 when features run horizontally (grain along the rows), > 1 when
    they run vertically (planks standing up)."""
    y = img.double().mean(0)
    y = y - y.mean()
    H, W = y.shape
    win = torch.outer(torch.hann_window(H, periodic=False, dtype=torch.float64),
                      torch.hann_window(W, periodic=False, dtype=torch.float64))
    P = torch.fft.fft2(y * win).abs() ** 2
    fy = torch.fft.fftfreq(H, dtype=torch.float64).view(-1, 1)
    fx = torch.fft.fftfreq(W, dtype=torch.float64).view(1, -1)
    return float(torch.sqrt((P * fx ** 2).sum() / (P * fy ** 2).sum().clamp_min(1e-30)))


def colour_stats(img: torch.Tensor, eps: float = 1e-4) -> torch.Tensor:
    """Mean colour and Cholesky factor of the colour covariance: (B, 3, H, W) -> (B, 12) = [mu, L.ravel()]."""
    x = img.flatten(2)                                   # (B, 3, P)
    mu = x.mean(2)
    xc = x - mu.unsqueeze(2)
    cov = xc @ xc.transpose(1, 2) / x.shape[2] + eps * torch.eye(3, dtype=img.dtype, device=img.device)
    L = torch.linalg.cholesky(cov)
    return torch.cat([mu, L.flatten(1)], dim=1)


def apply_colour(d: torch.Tensor, stats: torch.Tensor) -> torch.Tensor:
    """rgb = mu + L d: d (B, N, 3), stats (B, 12) -> (B, N, 3)."""
    mu, L = stats[:, :3], stats[:, 3:].view(-1, 3, 3)
    return mu.unsqueeze(1) + torch.einsum("bij,bnj->bni", L, d)


class Decoder(nn.Module):
    """f(n | e): noise (..., m*C) and code (..., E) -> RGB (..., 3) in (0, 1) (``sigmoid``) or whitened colour
    d (..., 3) (linear).  Noise and code broadcast against each other (one code (B, 1, E) for N points).

    The first layer is one ``nn.Linear`` over [n, e] (the paper's input), applied as W_n n + (W_e e + b) so a
    code is projected once, not once per point.  ``film``: the code also modulates every further hidden
    layer, h <- relu((1 + gamma_l(e)) * (W_l h + b_l) + beta_l(e)) (feature-wise linear modulation, Perez et
    al. 2018), starting at the identity (gamma = beta = 0).  The first texture-space model on photos, which
    had only the first layer's shift, collapsed to one texture for every photo: its decoder's output
    differed between photos by 1.4 % of its spread within an image.
    """

    def __init__(self, n_noise: int, code_dim: int = 64, width: int = 128, layers: int = 4, init: str = "he",
                 sigmoid: bool = True, film: bool = False):
        super().__init__()
        self.sigmoid, self.n_noise, self.width, self.layers = sigmoid, n_noise, width, layers
        mods, cin = [], n_noise + code_dim
        for _ in range(layers):
            mods += [nn.Linear(cin, width), nn.ReLU()]
            cin = width
        mods += [nn.Linear(cin, 3)]
        self.net = nn.Sequential(*mods)
        # He initialisation keeps the activations' variance through the ReLU stack, so the output
        # varies with the noise from the first step (torch's default shrinks it ~2.5x per layer and
        # training sat on a ~100-step plateau of near-constant colour)
        if init not in ("he", "torch"):
            raise ValueError(f"decoder init must be 'he' or 'torch', got {init!r}")
        for lin in self.net if init == "he" else ():
            if isinstance(lin, nn.Linear):
                nn.init.kaiming_normal_(lin.weight, nonlinearity="relu" if lin.out_features != 3 else "linear")
                nn.init.zeros_(lin.bias)
        self.film = nn.Linear(code_dim, 2 * width * (layers - 1)) if film else None
        if film:
            nn.init.zeros_(self.film.weight)
            nn.init.zeros_(self.film.bias)

    def forward(self, noise: torch.Tensor, code: torch.Tensor) -> torch.Tensor:
        first = self.net[0]
        w = first.weight
        h = torch.relu(noise @ w[:, :self.n_noise].T + (code @ w[:, self.n_noise:].T + first.bias))
        mod = self.film(code).chunk(2 * (self.layers - 1), dim=-1) if self.film is not None else None
        for j in range(1, self.layers):
            y = self.net[2 * j](h)
            if mod is not None:
                y = (1.0 + mod[2 * j - 2]) * y + mod[2 * j - 1]
            h = torch.relu(y)
        y = self.net[2 * self.layers](h)
        return torch.sigmoid(y) if self.sigmoid else y


class Encoder(nn.Module):
    """g(y): instance-normalised strided convolutions -> texture statistics -> z: (B, 3, S, S) -> (B, z_dim).

    Instance normalisation removes each feature map's mean and spread, so a
    global average of the normalised maps would be the same for every
    exemplar (a first version collapsed exactly so).  The code is therefore
    read from the statistics the normalisation takes away: per-channel mean and
    standard deviation of every block's convolution output (and of the input
    colours), as style encoders do, followed by a two-layer MLP.
    """

    def __init__(self, z_dim: int = 8, widths=(32, 64, 128, 256, 256), hidden: int = 256, standardise: bool = False):
        super().__init__()
        self.standardise = standardise
        self.convs = nn.ModuleList()
        self.norms = nn.ModuleList()
        cin = 3
        for w in widths:
            self.convs.append(nn.Conv2d(cin, w, 4, 2, 1))
            self.norms.append(nn.InstanceNorm2d(w, affine=True))
            cin = w
        n_stats = 2 * (3 + sum(widths))
        # the statistics' scales differ by orders of magnitude between layers: normalise the vector first
        self.fc = nn.Sequential(nn.LayerNorm(n_stats), nn.Linear(n_stats, hidden), nn.LeakyReLU(0.2),
                                nn.Linear(hidden, z_dim))

    def forward(self, y: torch.Tensor) -> torch.Tensor:
        if self.standardise:
            # each colour channel to zero mean and unit spread: the code sees texture, not colour or
            # contrast (a photo model gets those measured, mu + L d); its input statistics are then constant
            x = (y - y.mean(dim=(2, 3), keepdim=True)) / (y.std(dim=(2, 3), keepdim=True) + 1e-3)
        else:
            x = y * 2.0 - 1.0
        stats = [x.mean(dim=(2, 3)), x.std(dim=(2, 3))]
        for conv, norm in zip(self.convs, self.norms):
            h = conv(x)
            stats += [h.mean(dim=(2, 3)), h.std(dim=(2, 3))]
            x = nn.functional.leaky_relu(norm(h), 0.2)
        return self.fc(torch.cat(stats, dim=1))


#: bounded transforms: eigenvalues of the symmetric stretch S within +-MAX_STRETCH, octave scale within e^+-MAX_LOG_SCALE
MAX_STRETCH = 0.6
MAX_LOG_SCALE = 0.5


def check_max_stretch(max_stretch, transform: str) -> float:
    """``max_stretch`` (:func:`bounded_transform`) as a float, or ValueError naming what is wrong: a number in [0, 1)
    (1 would let a transform collapse), and other than MAX_STRETCH only with the bounded transform."""
    if not (isinstance(max_stretch, (int, float)) and 0.0 <= max_stretch < 1.0):
        raise ValueError(f"max_stretch must be a number in [0, 1) (1 would let a transform collapse), "
                         f"got {max_stretch!r}")
    if max_stretch != MAX_STRETCH and transform != "bounded":
        raise ValueError("max_stretch needs transform 'bounded'")
    return float(max_stretch)


def bounded_transform(raw: torch.Tensor, R: torch.Tensor, max_scale: torch.Tensor | None = None,
                      max_stretch: float = MAX_STRETCH) -> torch.Tensor:
    """T_i = R_i exp(c_i) (I + S_i) from raw (B, m, D*D + 1): S_i = sym(M_i) scaled so its Frobenius norm
    (a bound on every eigenvalue) stays <= ``max_stretch`` (MAX_STRETCH), c_i = MAX_LOG_SCALE tanh(raw_i[-1]).
    ``max_stretch`` 0: T_i = exp(c_i) R_i, a turn and a scale, no stretch (octaves that cannot draw strokes; the
    raw layout is the same, so a stretching model's weights continue into one that cannot).

    Singular values of T_i then lie in [0.4, 1.6] x e^+-0.5: anisotropic (grain, layers) up to a ratio of 4,
    but never the near-singular T of the free parametrisation, whose zero singular values extruded the
    noise along one direction (the diagonal streaks of the first space model: its T_i had singular values
    down to 0.0).

    ``max_scale`` (m,): a cap on each T_i's largest singular value, exp(c_i) (1 + ||S_i||_F) <= max_scale_i
    (exp(c_i) is lowered where it would pass it), so octave i's lattice is never finer than the spacing the
    cap was made for (:func:`max_scales`)."""
    B, m, _ = raw.shape
    D = R.shape[-1]
    M = raw[..., :D * D].view(B, m, D, D)
    S = 0.5 * (M + M.transpose(-1, -2))
    n = S.flatten(2).norm(dim=2).view(B, m, 1, 1)
    stretch = max_stretch * torch.tanh(n)                  # ||S_i||_F after scaling, >= its largest |eigenvalue|
    S = S * (stretch / n.clamp_min(1e-6))
    c = torch.exp(MAX_LOG_SCALE * torch.tanh(raw[..., D * D:])).view(B, m, 1, 1)
    if max_scale is not None:
        c = torch.minimum(c, max_scale.view(1, m, 1, 1) / (1.0 + stretch))
    eye = torch.eye(D, dtype=raw.dtype, device=raw.device)
    return R @ ((eye + S) * c)


def max_scales(octaves: int, px_per_unit: float, min_spacing: float) -> torch.Tensor:
    """Per-octave caps on the transforms' largest singular value, (octaves,) float32: octave i's lattice
    spacing is px_per_unit / 2^i exemplar pixels (Eq. 5), divided by its transform's largest singular value,
    so a cap of (px_per_unit / 2^i) / min_spacing keeps every lattice at least ``min_spacing`` px apart.

    Value noise on a lattice finer than 2 px is white at the pixel scale: an octave at 1 px (octave 8 of
    128 px/unit), which the first photo models also stretched 2.6x finer, gave the speckle their slices
    show (the finest spectrum ring 1.4x the photo's).  Coarse octaves' caps exceed the bounded range and
    change nothing."""
    if not (math.isfinite(min_spacing) and min_spacing > 0):
        raise ValueError(f"min_spacing must be a number > 0 (px), got {min_spacing!r}")
    return torch.tensor([px_per_unit / 2 ** i / min_spacing for i in range(octaves)], dtype=torch.float32)


class Translator(nn.Module):
    """h(z) -> (e (B, E), T (B, m, D, D)): ``free`` T_i = R_i (I + tanh(Delta_i(z))) (entries of Delta bounded
    by 1: the first models), or ``bounded`` (:func:`bounded_transform`)."""

    def __init__(self, z_dim: int, code_dim: int, octaves: int, dim: int, width: int = 128, seed: int = 0,
                 transform: str = "free", max_scale: torch.Tensor | None = None, max_stretch: float = MAX_STRETCH):
        super().__init__()
        if transform not in ("free", "bounded"):
            raise ValueError(f"transform must be 'free' or 'bounded', got {transform!r}")
        self.max_stretch = check_max_stretch(max_stretch, transform)
        if max_scale is not None and (transform != "bounded" or tuple(max_scale.shape) != (octaves,)):
            raise ValueError("max_scale needs the bounded transform and one cap per octave")
        self.code_dim, self.octaves, self.dim, self.transform = code_dim, octaves, dim, transform
        per = dim * dim + (transform == "bounded")
        self.net = nn.Sequential(nn.Linear(z_dim, width), nn.ReLU(), nn.Linear(width, width), nn.ReLU(),
                                 nn.Linear(width, code_dim + octaves * per))
        with torch.no_grad():  # start near T = R; the code part keeps its full scale, so e varies with z
            self.net[-1].weight[code_dim:].mul_(0.1)   # from the first step (a x0.1 code part left e nearly
            self.net[-1].bias.zero_()                  # constant and the encoder unused: every code one texture)
        self.register_buffer("R", random_rotations(octaves, dim, seed))
        # not in the state dict: made from the config (min_spacing), so exports without it still load
        self.register_buffer("max_scale", max_scale, persistent=False)

    def forward(self, z: torch.Tensor):
        out = self.net(z)
        e = out[:, :self.code_dim]
        if self.transform == "bounded":
            return e, bounded_transform(out[:, self.code_dim:].view(z.shape[0], self.octaves, -1), self.R,
                                        self.max_scale, self.max_stretch)
        # bounded: an unbounded Delta let a space run grow every T_i to ~100x (all octaves at the pixel
        # scale: fine grain of one average colour for every exemplar)
        delta = torch.tanh(out[:, self.code_dim:]).view(-1, self.octaves, self.dim, self.dim)
        eye = torch.eye(self.dim, device=z.device)
        return e, self.R @ (eye + delta)


class SolidTexture(nn.Module):
    """Decoder plus either single-mode parameters (e, T) or an encoder and translator (space mode)."""

    def __init__(self, dim: int = 3, octaves: int = 8, channels: int = 3, code_dim: int = 64, z_dim: int = 8,
                 mode: str = "single", width: int = 128, layers: int = 4, seed: int = 0, decoder_init: str = "he",
                 colour: str = "sigmoid", transform: str = "free", film: bool = False, standardise: bool = False,
                 cellular: int = 0, bricks: int = 0, max_scale: torch.Tensor | None = None, waves: int = 0,
                 spin: str = "", max_stretch: float = MAX_STRETCH):
        super().__init__()
        #: backend.solid.spin: "lattice" reads octave i at Q(xi_i) T_i 2^(i-1) x, "octave" at T_i Q(xi_i)^T 2^(i-1) x
        self.spin = check_mode(spin)
        if mode not in ("single", "space"):
            raise ValueError(f"mode must be 'single' or 'space', got {mode!r}")
        if colour not in ("sigmoid", "affine"):
            raise ValueError(f"colour must be 'sigmoid' or 'affine', got {colour!r}")
        self.dim, self.octaves, self.channels, self.code_dim, self.mode = dim, octaves, channels, code_dim, mode
        for key, k in (("cellular", cellular), ("bricks", bricks)):
            if not 0 <= k <= octaves:
                raise ValueError(f"{key} must be 0..{octaves} (octaves with {key} features), got {k}")
        self.colour, self.cellular, self.bricks = colour, cellular, bricks
        if waves and (mode != "single" or dim != 2):
            raise ValueError("waves are measured from one photo's plane: they need mode 'single' and dim 2")
        #: decoder inputs: value noise (octaves x channels), then the shape features, then the waves
        self.n_noise = octaves * channels + shape_features(cellular, bricks) + WAVE_FEATURES * waves
        #: the photo's periodic components (waves.photo_waves: rows f_x, f_y, phi, a), set before training;
        #: None (and not in the state dict, so models without them load as before) when there are none
        self.register_buffer("waves", torch.zeros(waves, 4) if waves else None)
        self.decoder = Decoder(self.n_noise, code_dim, width, layers, decoder_init, sigmoid=colour == "sigmoid",
                               film=film)
        #: "fp32" or "bf16": the decoder runs under bf16 autocast in :meth:`sample` (set by the trainer from a
        #: config's ``precision``; not part of the weights, and an export always traces fp32)
        self.precision = "fp32"
        if mode == "single":
            self.code = nn.Parameter(torch.rand(code_dim) * 2.0 - 1.0)     # U(-1, 1) as the authors' code
            self.T = nn.Parameter(random_rotations(octaves, dim, seed).clone())
        else:
            self.encoder = Encoder(z_dim, standardise=standardise)
            self.translator = Translator(z_dim, code_dim, octaves, dim, seed=seed, transform=transform,
                                         max_scale=max_scale, max_stretch=max_stretch)

    def codes(self, exemplars: torch.Tensor | None = None, batch: int = 1):
        """(e (B, E), T (B, m, D, D)) for a batch: the single-mode parameters, or h(g(exemplars))."""
        if self.mode == "single":
            return self.code.unsqueeze(0).expand(batch, -1), self.T.unsqueeze(0).expand(batch, -1, -1, -1)
        return self.translator(self.encoder(exemplars))

    def sample(self, x: torch.Tensor, e: torch.Tensor, T: torch.Tensor, seeds: torch.Tensor,
               stats: torch.Tensor | None = None, gains: torch.Tensor | None = None) -> torch.Tensor:
        """s(x | z) (Eq. 5): x (B, N, D), e (B, E), T (B, m, D, D), seeds int64 (B, m) -> RGB (B, N, 3);
        ``stats`` (B, 12): the exemplars' :func:`colour_stats` (``colour="affine"`` only); ``gains`` (B, m): the
        exemplars' :func:`spectral_gains`, multiplying each octave's noise (``spectral`` models).
        The decoder reads the value noise (B, N, m C), then the first ``cellular`` octaves' Worley features
        (B, N, 3 cellular; ``cellular.py``), then the first ``bricks`` octaves' brick features (``brick.py``), then
        the photo's waves (B, N, 2 K; ``waves.py``, at x itself: they are the photo's own frequencies)."""
        if self.spin:
            T = spun_torch(T, seeds, self.spin)
        n = value_noise(x, T, seeds, self.channels)
        if gains is not None:
            B, N, _ = n.shape
            n = (n.view(B, N, self.octaves, self.channels) * gains.view(B, 1, self.octaves, 1)).view(B, N, -1)
        if self.cellular:
            n = torch.cat([n, cellular_features(x, T, seeds, self.cellular)], dim=-1)
        if self.bricks:
            n = torch.cat([n, brick_features(x, T, seeds, self.bricks)], dim=-1)
        if self.waves is not None:
            n = torch.cat([n, wave_features(x, self.waves)], dim=-1)
        with autocast(self.precision, n.device):   # bf16 for the MLP's matrix products only (train.py precision)
            out = self.decoder(n, e.unsqueeze(1)).float()
        if self.colour == "affine":
            if stats is None:
                raise ValueError("an affine-colour model needs the exemplars' colour statistics")
            out = apply_colour(out, stats)
        return out

    def n_params(self) -> int:
        return sum(p.numel() for p in self.parameters())


def slice_points(batch: int, size: int, px_per_unit: float, dim: int, oblique: float, extent: float,
                 generator: torch.Generator, fixed_axis: str = "") -> torch.Tensor:
    """Pixel-centre positions of random 2D slices of the D-dimensional domain (Fig. 5): (B, size*size, D).

    2D: the plane itself, shifted by a random offset (orientation kept: the
    exemplar's orientation is the texture's).  3D: planes through a random
    point, axis-aligned (a random axis permutation) or, with probability
    ``oblique``, randomly rotated.

    ``fixed_axis`` (3D) keeps one image axis on one axis of space, for materials with a direction (Kopf et al.
    2007 give such solids one exemplar per view; here one view constrains every plane through the axis):
    "columns": the image's horizontal runs along x (wood grain: every plane containing x, rotated about it
    by a uniform angle, shows the photo; planes across x, the end grain, are left free); "rows": the
    image's vertical runs along -z (a brick wall: every vertical plane shows the courses, the top of the
    photo up).
    """
    u = (torch.arange(size, dtype=torch.float32) + 0.5) / px_per_unit
    vv, uu = torch.meshgrid(u, u, indexing="ij")
    plane = torch.stack([uu.flatten(), -vv.flatten()], dim=-1)                  # image rows go down
    off = (torch.rand(batch, 1, dim, generator=generator) * 2.0 - 1.0) * extent
    if dim == 2:
        return plane.unsqueeze(0) + off
    check_fixed_axis(fixed_axis)
    frames = []
    for _ in range(batch):
        if fixed_axis:
            t = float(torch.rand(1, generator=generator)) * 2.0 * math.pi
            u, v = (torch.tensor(w) for w in axis_frame(fixed_axis, t))
            frames.append(torch.stack([u, v, torch.linalg.cross(u, v)], dim=1))
        elif torch.rand(1, generator=generator).item() < oblique:
            q, r = torch.linalg.qr(torch.randn(3, 3, generator=generator))
            frames.append(q * torch.sign(torch.diagonal(r)).unsqueeze(0))
        else:
            perm = torch.randperm(3, generator=generator)
            frames.append(torch.eye(3)[:, perm])
    Fm = torch.stack(frames)                                                    # columns: u axis, v axis, normal
    return torch.einsum("bij,nj->bni", Fm[:, :, :2], plane) + off
