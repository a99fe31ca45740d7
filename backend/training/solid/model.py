"""Networks of the neural solid texture (Henzler, Mitra, Ritschel, CVPR 2020, Sec. 3-4).

    z = g(y)                  encoder: exemplar patch (B, 3, 128, 128) -> code z (B, 8)
    {e, T_1..T_m} = h(z)      translator: z -> extended code e (B, 64) and one D x D transform per octave
    s(x | z) = f(n | e),  n_i = noise(T_i 2^(i-1) x | xi_i)                                   (Eq. 5)

The decoder f is an MLP (four layers of 128, ReLU, then RGB through a
sigmoid) over [n, e]; position x never enters it, which is what gives
diversity by construction (Sec. 4).  Single mode optimises e and T directly
(with the decoder); space mode trains g, h and f jointly.

Every T_i starts as a fixed random rotation R_i (seeded), so the octaves'
lattices are not aligned with each other or with the axes; the translator and
the single-mode parameters learn T_i = R_i (I + Delta_i).
"""
from __future__ import annotations


import torch
from torch import nn

from .lattice import lattice_noise

__all__ = ["Decoder", "Encoder", "Translator", "SolidTexture", "random_rotations", "slice_points"]


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


class Decoder(nn.Module):
    """f(n | e): (..., m*C + E) -> RGB (..., 3) in (0, 1)."""

    def __init__(self, n_noise: int, code_dim: int = 64, width: int = 128, layers: int = 4, init: str = "he"):
        super().__init__()
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

    def forward(self, noise: torch.Tensor, code: torch.Tensor) -> torch.Tensor:
        return torch.sigmoid(self.net(torch.cat([noise, code], dim=-1)))


class Encoder(nn.Module):
    """g(y): instance-normalised strided convolutions -> texture statistics -> z: (B, 3, S, S) -> (B, z_dim).

    Instance normalisation removes each feature map's mean and spread, so a
    global average of the normalised maps would be the same for every
    exemplar (a first version collapsed exactly so).  The code is therefore
    read from the statistics the normalisation takes away: per-channel mean and
    standard deviation of every block's convolution output (and of the input
    colours), as style encoders do, followed by a two-layer MLP.
    """

    def __init__(self, z_dim: int = 8, widths=(32, 64, 128, 256, 256), hidden: int = 256):
        super().__init__()
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
        x = y * 2.0 - 1.0
        stats = [x.mean(dim=(2, 3)), x.std(dim=(2, 3))]
        for conv, norm in zip(self.convs, self.norms):
            h = conv(x)
            stats += [h.mean(dim=(2, 3)), h.std(dim=(2, 3))]
            x = nn.functional.leaky_relu(norm(h), 0.2)
        return self.fc(torch.cat(stats, dim=1))


class Translator(nn.Module):
    """h(z) -> (e (B, E), T (B, m, D, D)) with T_i = R_i (I + tanh(Delta_i(z))) (entries of Delta bounded by 1)."""

    def __init__(self, z_dim: int, code_dim: int, octaves: int, dim: int, width: int = 128, seed: int = 0):
        super().__init__()
        self.code_dim, self.octaves, self.dim = code_dim, octaves, dim
        self.net = nn.Sequential(nn.Linear(z_dim, width), nn.ReLU(), nn.Linear(width, width), nn.ReLU(),
                                 nn.Linear(width, code_dim + octaves * dim * dim))
        with torch.no_grad():  # start near T = R; the code part keeps its full scale, so e varies with z
            self.net[-1].weight[code_dim:].mul_(0.1)   # from the first step (a x0.1 code part left e nearly
            self.net[-1].bias.zero_()                  # constant and the encoder unused: every code one texture)
        self.register_buffer("R", random_rotations(octaves, dim, seed))

    def forward(self, z: torch.Tensor):
        out = self.net(z)
        e = out[:, :self.code_dim]
        # bounded: an unbounded Delta let a space run grow every T_i to ~100x (all octaves at the pixel
        # scale: fine grain of one average colour for every exemplar)
        delta = torch.tanh(out[:, self.code_dim:]).view(-1, self.octaves, self.dim, self.dim)
        eye = torch.eye(self.dim, device=z.device)
        return e, self.R @ (eye + delta)


class SolidTexture(nn.Module):
    """Decoder plus either single-mode parameters (e, T) or an encoder and translator (space mode)."""

    def __init__(self, dim: int = 3, octaves: int = 8, channels: int = 3, code_dim: int = 64, z_dim: int = 8,
                 mode: str = "single", width: int = 128, layers: int = 4, seed: int = 0, decoder_init: str = "he"):
        super().__init__()
        if mode not in ("single", "space"):
            raise ValueError(f"mode must be 'single' or 'space', got {mode!r}")
        self.dim, self.octaves, self.channels, self.code_dim, self.mode = dim, octaves, channels, code_dim, mode
        self.decoder = Decoder(octaves * channels, code_dim, width, layers, decoder_init)
        if mode == "single":
            self.code = nn.Parameter(torch.rand(code_dim) * 2.0 - 1.0)     # U(-1, 1) as the authors' code
            self.T = nn.Parameter(random_rotations(octaves, dim, seed).clone())
        else:
            self.encoder = Encoder(z_dim)
            self.translator = Translator(z_dim, code_dim, octaves, dim, seed=seed)

    def codes(self, exemplars: torch.Tensor | None = None, batch: int = 1):
        """(e (B, E), T (B, m, D, D)) for a batch: the single-mode parameters, or h(g(exemplars))."""
        if self.mode == "single":
            return self.code.unsqueeze(0).expand(batch, -1), self.T.unsqueeze(0).expand(batch, -1, -1, -1)
        return self.translator(self.encoder(exemplars))

    def sample(self, x: torch.Tensor, e: torch.Tensor, T: torch.Tensor, seeds: torch.Tensor) -> torch.Tensor:
        """s(x | z) (Eq. 5): x (B, N, D), e (B, E), T (B, m, D, D), seeds int64 (B, m) -> RGB (B, N, 3)."""
        n = lattice_noise(x, T, seeds, self.channels)
        return self.decoder(n, e.unsqueeze(1).expand(-1, x.shape[1], -1))

    def n_params(self) -> int:
        return sum(p.numel() for p in self.parameters())


def slice_points(batch: int, size: int, px_per_unit: float, dim: int, oblique: float, extent: float,
                 generator: torch.Generator) -> torch.Tensor:
    """Pixel-centre positions of random 2D slices of the D-dimensional domain (Fig. 5): (B, size*size, D).

    2D: the plane itself, shifted by a random offset (orientation kept: the
    exemplar's orientation is the texture's).  3D: planes through a random
    point, axis-aligned (a random axis permutation) or, with probability
    ``oblique``, randomly rotated.
    """
    u = (torch.arange(size, dtype=torch.float32) + 0.5) / px_per_unit
    vv, uu = torch.meshgrid(u, u, indexing="ij")
    plane = torch.stack([uu.flatten(), -vv.flatten()], dim=-1)                  # image rows go down
    off = (torch.rand(batch, 1, dim, generator=generator) * 2.0 - 1.0) * extent
    if dim == 2:
        return plane.unsqueeze(0) + off
    frames = []
    for _ in range(batch):
        if torch.rand(1, generator=generator).item() < oblique:
            q, r = torch.linalg.qr(torch.randn(3, 3, generator=generator))
            frames.append(q * torch.sign(torch.diagonal(r)).unsqueeze(0))
        else:
            perm = torch.randperm(3, generator=generator)
            frames.append(torch.eye(3)[:, perm])
    Fm = torch.stack(frames)                                                    # columns: u axis, v axis, normal
    return torch.einsum("bij,nj->bni", Fm[:, :, :2], plane) + off
