"""Stratified sampling of wave directions (Guehl et al. 2025, Sec. 4.2, 5.1, 5.2).

Directions are drawn in a *domain* of the unit sphere S^(d-1) through an
equal-measure parameterisation u in [0, 1]^(d-1) (so pdf = J_omega / |domain|
and the Jacobian cancels in Eq. 6):

* 2D  angle from the cap axis  t = sigma (2 u0 - 1);            omega = (sin t, cos t)
* 3D  phi = 2 pi u0, cos(theta) = 1 - u1 (1 - cos sigma)         (the arccos of Alg. 1)
* 4D  phi = 2 pi u0, cos(theta) = 2 u1 - 1, and psi solving
      (psi - sin psi cos psi) = u2 (sigma - sin sigma cos sigma)  (pdf ~ sin^2 psi, Sec. 5.2)
      by a fixed number of safeguarded Newton steps (no closed-form inverse exists).

The cap is centred on the last axis and rotated onto its real axis by a
Householder reflection.  ``sigma = pi/2`` is the half sphere Omega+ of static
noise; animated noise needs the whole sphere (Sec. 5.3), obtained by letting the
last u coordinate choose a hemisphere.  ``band`` domains (by-example 3D, Sec. 4.4)
hold directions within +-sigma of elevation around a coordinate plane.

Strata are axis-aligned boxes in u-space of exactly equal volume, so every
direction carries the same weight; any count K is allowed.  All maths here is
plain float32 arithmetic that Blender's Math nodes reproduce.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import SettingError
from .hashing import white_noise4

__all__ = ["Domain", "DirectionSet", "strata", "map_directions", "psi_inverse", "NEWTON_STEPS"]

NEWTON_STEPS = 5
_F = np.float32


def strata(count: int, ndim: int) -> tuple[np.ndarray, np.ndarray]:
    """Split [0,1]^ndim into ``count`` equal-volume boxes.

    Returns lo, hi: float32 (count, ndim).  The last axis is cut into
    ~count^(1/ndim) bands whose widths are proportional to how many boxes they
    hold; each band is split recursively along the remaining axes.
    """
    if count < 1:
        raise SettingError("directions", f"must be at least 1, got {count}")
    lo = np.zeros((count, ndim), np.float64)
    hi = np.ones((count, ndim), np.float64)

    def split(idx: np.ndarray, axis: int) -> None:
        n = len(idx)
        if n == 1:
            return
        bands = n if axis == 0 else max(1, int(round(n ** (1.0 / (axis + 1)))))
        counts = np.full(bands, n // bands)
        counts[: n % bands] += 1
        a0, a1 = lo[idx[0], axis], hi[idx[0], axis]
        start = 0
        edge = a0
        for c in counts:
            sub = idx[start:start + c]
            width = (a1 - a0) * c / n
            lo[sub, axis] = edge
            hi[sub, axis] = edge + width
            edge += width
            start += c
            split(sub, axis - 1)

    split(np.arange(count), ndim - 1)
    return lo.astype(_F), hi.astype(_F)


def psi_inverse(u: np.ndarray, sigma: float) -> np.ndarray:
    """Solve psi - sin(psi) cos(psi) = u (sigma - sin(sigma) cos(sigma)), psi in [0, sigma].

    Fixed-count safeguarded Newton iteration from the small-angle guess
    psi0 = cbrt(1.5 c); float32 (same shape as u).
    """
    s = _F(sigma)
    c = u.astype(_F) * (s - np.sin(s) * np.cos(s))
    psi = np.minimum(np.cbrt(_F(1.5) * c), s)
    for _ in range(NEWTON_STEPS):
        sp = np.sin(psi)
        g = psi - sp * np.cos(psi) - c
        dg = _F(2.0) * sp * sp + _F(1e-6)
        psi = np.clip(psi - g / dg, _F(0.0), s)
    return psi


@dataclass(frozen=True)
class Domain:
    """A region of directions.

    kind    'cap' (axis, half-angle ``spread``) or 'band' (plane (a, b), normal c, elevation ``spread``)
    dim     2, 3 or 4
    axis    unit vector (cap) or the three axis indices (a, b, c) for a band
    full    cap only: sample both hemispheres (animated noise)
    weight  share of the total wave power carried by this domain
    """

    kind: str
    dim: int
    spread: float
    axis: tuple
    full: bool = False
    weight: float = 1.0

    def validate(self) -> "Domain":
        if self.kind not in ("cap", "band"):
            raise SettingError("domain", f"unknown kind {self.kind!r}")
        if not 0.0 < self.spread <= np.pi / 2 + 1e-9:
            raise SettingError("spread", f"must lie in (0, 90] degrees, got {np.degrees(self.spread):g}")
        if self.kind == "band" and self.dim != 3:
            raise SettingError("example plane", "plane bands are 3D only")
        return self


def _householder(omega: np.ndarray, axis: np.ndarray) -> np.ndarray:
    """Reflect e_last onto ``axis``: omega - 2 v (v . omega) / (v . v), v = e_last - axis."""
    d = omega.shape[-1]
    v = -np.asarray(axis, dtype=_F)
    v[d - 1] += 1.0
    vv = float(np.dot(v, v))
    if vv < 1e-12:
        return omega
    proj = omega @ v
    return omega - (_F(2.0 / vv) * proj)[..., None] * v


def map_directions(u: np.ndarray, dom: Domain) -> np.ndarray:
    """Map u: float32 (P, dim-1) in [0,1] to unit directions float32 (P, dim)."""
    u = u.astype(_F)
    d = dom.dim
    s = _F(dom.spread)
    sign = None
    if dom.kind == "cap" and dom.full:
        last = u[:, -1] * _F(2.0)
        flip = last >= _F(1.0)
        sign = np.where(flip, _F(-1.0), _F(1.0))
        u = u.copy()
        u[:, -1] = np.where(flip, last - _F(1.0), last)
    if dom.kind == "band":
        a, b, c = dom.axis
        alpha = _F(np.pi) * u[:, 0]
        z = _F(np.sin(dom.spread)) * (_F(2.0) * u[:, 1] - _F(1.0))
        ce = np.sqrt(np.maximum(_F(1.0) - z * z, _F(0.0)))
        out = np.zeros((len(u), 3), _F)
        out[:, a] = ce * np.cos(alpha)
        out[:, b] = ce * np.sin(alpha)
        out[:, c] = z
        return out
    if d == 2:
        t = s * (_F(2.0) * u[:, 0] - _F(1.0))
        out = np.stack([np.sin(t), np.cos(t)], axis=1)
    elif d == 3:
        phi = _F(2.0 * np.pi) * u[:, 0]
        ct = _F(1.0) - u[:, 1] * (_F(1.0) - np.cos(s))
        st = np.sqrt(np.maximum(_F(1.0) - ct * ct, _F(0.0)))
        out = np.stack([st * np.cos(phi), st * np.sin(phi), ct], axis=1)
    elif d == 4:
        phi = _F(2.0 * np.pi) * u[:, 0]
        ct = _F(2.0) * u[:, 1] - _F(1.0)
        st = np.sqrt(np.maximum(_F(1.0) - ct * ct, _F(0.0)))
        psi = psi_inverse(u[:, 2], dom.spread)
        sp = np.sin(psi)
        out = np.stack([sp * st * np.cos(phi), sp * st * np.sin(phi), sp * ct, np.cos(psi)], axis=1)
    else:
        raise SettingError("dim", f"must be 2, 3 or 4, got {d}")
    out = _householder(out.astype(_F), np.asarray(dom.axis, _F))
    if sign is not None:
        out = out * sign[:, None]
    return out.astype(_F)


@dataclass
class DirectionSet:
    """K strata over one or more domains.

    lo, hi:    float32 (K, dim-1) stratum boxes in u-space
    domain:    int (K,) index into ``domains``
    amp:       float32 (K,) amplitude weight sqrt(w_k), sum_k w_k = 1 (variance-preserving)
    """

    domains: list
    lo: np.ndarray
    hi: np.ndarray
    domain: np.ndarray
    amp: np.ndarray

    @property
    def count(self) -> int:
        return len(self.domain)

    @classmethod
    def build(cls, count: int, domains: list) -> "DirectionSet":
        if count < 1:
            raise SettingError("directions", f"must be at least 1, got {count}")
        if count < len(domains):
            raise SettingError("directions", f"{count} directions cannot cover {len(domains)} lobes")
        dim = domains[0].dim
        w = np.array([max(d.weight, 0.0) for d in domains], np.float64)
        if not w.sum() > 0:
            raise SettingError("lobes", "lobe weights must not all be zero")
        w /= w.sum()
        # split the K directions over domains in proportion to their weights (>= 1 each)
        per = np.maximum(1, np.floor(w * count).astype(int))
        while per.sum() > count:
            per[np.argmax(per)] -= 1
        while per.sum() < count:
            per[np.argmax(w * count - per)] += 1
        los, his, doms, amps = [], [], [], []
        for i, (dom, n) in enumerate(zip(domains, per)):
            dom.validate()
            lo, hi = strata(int(n), dim - 1)
            los.append(lo); his.append(hi)
            doms.append(np.full(n, i))
            amps.append(np.full(n, np.sqrt(w[i] / n)))
        return cls(list(domains), np.concatenate(los), np.concatenate(his), np.concatenate(doms),
                   np.concatenate(amps).astype(_F))

    def hashed_normals(self, seed: np.float32, stream: int) -> np.ndarray:
        """Per-stratum unit normals orthogonal to the stratum centres: float32 (K, dim).

        A hashed vector r in [-1, 1]^dim (White Noise at (k, 0, stream + axis, seed))
        with its component along the centre c removed: r - (r . c) c, normalised.
        """
        ks = np.arange(self.count, dtype=_F)
        dim = self.domains[0].dim
        centres = self.centres()
        r = np.stack([white_noise4(ks, _F(0), _F(stream + i), seed) for i in range(dim)], 1)
        r = _F(2.0) * r - _F(1.0)
        r = r - np.sum(r * centres, axis=1, keepdims=True) * centres
        return r / np.linalg.norm(r, axis=1, keepdims=True)

    def centres(self) -> np.ndarray:
        """Direction of each stratum's centre: float32 (K, dim)."""
        out = []
        for k in range(self.count):
            u = (0.5 * (self.lo[k] + self.hi[k]))[None, :]
            out.append(map_directions(u, self.domains[self.domain[k]])[0])
        return np.stack(out)
