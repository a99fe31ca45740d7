"""Wave noise evaluation (Guehl et al. 2025, Eq. 6, 8, 9 and Algorithm 1).

    N(x, t) = sum_k a_k [ w0 T(frac((x . omega_{k,n}   - v t) / L + zeta_{k,n}))
                        + w1 T(frac((x . omega_{k,n+1} - v t) / L + zeta_{k,n+1})) ]

For each stratum k the space is cut into slices of width W across a slicing
direction s_k orthogonal to the stratum's centre direction (Alg. 1).  Slice n
owns its own jittered wave direction omega_{k,n} (drawn inside stratum k), its
own offset zeta_{k,n} and a jittered border position slpos_n in [0.3, 0.7].
Neighbouring slices are blended over 0.6 W around the border with weights
w0 = cos(pi/2 s), w1 = sin(pi/2 s), s = smoothstep(u): w0^2 + w1^2 = 1, so the
variance does not dip between slices.  Stratum weights a_k = sqrt(1/K) make
E|N|^2 = 1 whatever the number of directions K.

Every random number comes from :func:`backend.wavenoise.hashing.white_noise4`,
Blender's White Noise node; so Blender nodes can evaluate the same function.
A slice's records use the node's Color output, whose three channels are the
4D hash at the input permutations (x, y, z, w), (z, x, w, y), (w, z, y, x)
(:data:`COLOR_PERMUTATIONS`): one node at (k, slice, A, seed) yields the border
position, the wave offset and the first direction jitter; a second at
(k, slice, B, seed) the other jitters.  Evaluation is float32 and chunked by the caller.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import fast
from .directions import DirectionSet, map_directions
from ..errors import SettingError, check_points
from .hashing import MAX_EXACT_ID, white_noise4
from .tables import WaveTable, table_lookup

__all__ = ["WaveNoise", "Transition", "OUTPUTS", "select_output", "STREAM", "COLOR_PERMUTATIONS", "white_color4"]

_F = np.float32
OUTPUTS = ("real", "imag", "modulus", "phase")

#: hash streams (third White Noise input): one per random quantity
STREAM = dict(slice_dir=0, slice_offset=4, slice_a=5, slice_b=6)
#: channel c of the White Noise node's Color = white_noise4 of the inputs in this order
COLOR_PERMUTATIONS = ((0, 1, 2, 3), (2, 0, 3, 1), (3, 2, 1, 0))


def white_color4(x, y, z, w, channel: int) -> np.ndarray:
    """Channel ``channel`` of Blender's White Noise (4D) Color output at (x, y, z, w)."""
    args = (x, y, z, w)
    return white_noise4(*(args[i] for i in COLOR_PERMUTATIONS[channel]))


def border_fraction(zeta: np.ndarray) -> np.ndarray:
    """fract(16 zeta), float32: the slice border's random fraction (exact in float32, as in the node)."""
    t = np.asarray(zeta, _F) * _F(16.0)
    return (t - np.floor(t)).astype(_F)


BLEND_HALF_WIDTH = 0.3   # border ramp half-width, in slice widths
SLPOS_MIN, SLPOS_RANGE = 0.3, 0.4


@dataclass
class Transition:
    """Smooth transition to a phase-aligned second table (Sec. 7.1, Fig. 17).

    values_b: complex64 with the shape of the main table's values.
    The blend factor is clamp(((x - origin) . direction) / length, 0, 1).
    """

    values_b: np.ndarray
    origin: np.ndarray
    direction: np.ndarray
    length: float

    def factor(self, x: np.ndarray) -> np.ndarray:
        d = np.asarray(self.direction, _F)
        t = ((x - np.asarray(self.origin, _F)) @ d) * _F(1.0 / self.length)
        return np.clip(t, _F(0.0), _F(1.0))


def select_output(z: np.ndarray, output: str) -> np.ndarray:
    """Real value from complex noise: real, imag, modulus (ridged) or phase (phasor, radians)."""
    if output == "real":
        return z.real.astype(_F)
    if output == "imag":
        return z.imag.astype(_F)
    if output == "modulus":
        return np.abs(z).astype(_F)
    if output == "phase":
        return np.arctan2(z.imag, z.real).astype(_F)
    raise SettingError("output", f"unknown output {output!r}; choose one of {', '.join(OUTPUTS)}")


class WaveNoise:
    """A compiled wave noise: table(s), direction strata and per-stratum constants.

    table         WaveTable (single / axes / sectors)
    directions    DirectionSet (K strata)
    seed          integer in [0, 2^24)
    slice_width   W, world units (slices are W wide across s_k)
    speed         v, world units per unit time (Eq. 9); needs full-sphere domains
    plane         (a, b): axes whose angle selects the row of a 'sectors' table
    """

    def __init__(self, table: WaveTable, directions: DirectionSet, seed: int, slice_width: float,
                 speed: float = 0.0, transition: Transition | None = None, plane: tuple = (0, 1)):
        if not 0 <= int(seed) < MAX_EXACT_ID:
            raise SettingError("seed", f"must lie in [0, {MAX_EXACT_ID}), got {seed}")
        if not slice_width > 0:
            raise SettingError("slice width", f"must be positive, got {slice_width}")
        self.table = table
        self.dirs = directions
        self.dim = directions.domains[0].dim
        self.seed = _F(int(seed))
        self.slice_width = float(slice_width)
        self.speed = float(speed)
        self.transition = transition
        self.plane = plane
        ks = np.arange(directions.count, dtype=_F)
        #: slicing directions s_k pre-divided by W: float32 (K, D)
        normals = directions.hashed_normals(self.seed, STREAM["slice_dir"])
        self.slice_dirs = (normals / _F(self.slice_width)).astype(_F)
        #: slice origin offsets o_k: float32 (K,)
        self.slice_offsets = white_noise4(ks, _F(0), _F(STREAM["slice_offset"]), self.seed)

    # -- random quantities of slice m in stratum k ------------------------------
    def slice_records(self, k: int, m: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """For slice ids m (float32): border position (M,), direction (M, D), offset zeta (M,).

        One White Noise node per slice carries everything a 2D or 3D slice needs:
        A = White Noise (k, m, a, seed), Color (r, g, b) = offset zeta, jitters 0, 1.
        The border position reuses zeta's low bits, SLPOS_MIN + SLPOS_RANGE * fract(16 zeta),
        which are independent of zeta's coarse value (2^20 levels) and cost two math nodes
        instead of a second hash.  4D reads jitter 2 from B = White Noise (k, m, b, seed).
        """
        slpos, zeta, u = self._slice_hashes(_F(k), m)
        lo, hi = self.dirs.lo[k], self.dirs.hi[k]
        u = lo + (hi - lo) * u
        omega = map_directions(u, self.dirs.domains[self.dirs.domain[k]])
        return slpos, omega, zeta

    def strata_records(self, m: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`slice_records` of every stratum at once: slice ids m float32 (K, M), row k for stratum k ->
        border positions (K, M), directions (K, M, D), offsets zeta (K, M); the same values, one hash per
        array instead of one per stratum (a grid's plan hashes all its slices here)."""
        m = np.asarray(m, _F)
        slpos, zeta, u = self._slice_hashes(np.arange(self.dirs.count, dtype=_F)[:, None], m)
        u = self.dirs.lo[:, None, :] + (self.dirs.hi - self.dirs.lo)[:, None, :] * u
        omega = np.empty(m.shape + (self.dim,), _F)
        for d, dom in enumerate(self.dirs.domains):
            ks = np.flatnonzero(self.dirs.domain == d)
            if len(ks):
                omega[ks] = map_directions(u[ks].reshape(-1, self.dim - 1), dom).reshape(len(ks), m.shape[1], -1)
        return slpos, omega, zeta

    def _slice_hashes(self, kk, m):
        """Border positions, offsets zeta and direction jitters (..., D - 1) in [0, 1) of slices m of strata kk
        (float32, broadcast together)."""
        s = self.seed
        a, b = _F(STREAM["slice_a"]), _F(STREAM["slice_b"])
        zeta = white_color4(kk, m, a, s, 0)
        slpos = _F(SLPOS_MIN) + _F(SLPOS_RANGE) * border_fraction(zeta)
        jit = [white_color4(kk, m, a, s, 1 + c) for c in range(min(self.dim - 1, 2))]
        if self.dim == 4:
            jit.append(white_color4(kk, m, b, s, 0))
        return slpos, zeta, np.stack(jit, -1)

    def _lookup(self, values: np.ndarray, omega: np.ndarray, coord: np.ndarray) -> np.ndarray:
        mode = self.table.mode
        if mode == "single":
            return table_lookup(values, 0, coord)
        if mode == "axes":
            out = np.zeros(coord.shape, np.complex64)
            for a in range(values.shape[0]):
                out += (omega[:, a] * omega[:, a]) * table_lookup(values, a, coord)
            return out
        # sectors: row coordinate from the direction's angle in the plane, angles mod pi
        a, b = self.plane
        rows = values.shape[0]
        ang = np.arctan2(omega[:, b], omega[:, a])
        ang = ang - _F(np.pi) * np.floor(ang * _F(1.0 / np.pi))
        r = ang * _F(rows / np.pi) - _F(0.5)
        r0 = np.floor(r)
        t = (r - r0).astype(_F)
        i0 = r0.astype(np.int64) % rows
        i1 = (i0 + 1) % rows
        t0 = table_lookup(values, i0, coord)
        t1 = table_lookup(values, i1, coord)
        return t0 + (t1 - t0) * t

    def _wave(self, x: np.ndarray, omega: np.ndarray, zeta: np.ndarray, shift: np.ndarray | float,
              beta: np.ndarray | None) -> np.ndarray:
        coord = (np.sum(x * omega, axis=1) - shift) * _F(1.0 / self.table.period) + zeta
        val = self._lookup(self.table.values, omega, coord)
        if beta is not None:
            vb = self._lookup(self.transition.values_b, omega, coord)
            val = val + (vb - val) * beta
        return val

    def evaluate(self, x: np.ndarray, time: float | np.ndarray = 0.0, accelerate: bool = True) -> np.ndarray:
        """Complex noise at points x: float32 (P, dim) -> complex64 (P,).

        ``time`` (scalar or (P,)) shifts every wave by speed * time along its
        direction (Eq. 9).  For 4D noise the fourth coordinate is part of x.
        ``accelerate`` uses the compiled path of :mod:`backend.wavenoise.fast` when it applies.
        """
        x = check_points(x, (self.dim,), _F)
        if not np.isfinite(time).all():
            raise SettingError("time", "the time holds NaN or infinite values")
        if len(x) == 0:
            return np.zeros(0, np.complex64)
        if accelerate:
            z = fast.evaluate(self, x, time)
            if z is not None:
                return z
        shift = _F(self.speed) * np.asarray(time, _F)
        beta = self.transition.factor(x) if self.transition is not None else None
        z = np.zeros(len(x), np.complex64)
        for k in range(self.dirs.count):
            p = x @ self.slice_dirs[k] + self.slice_offsets[k]
            n = np.floor(p)
            f = p - n
            n = n + _F(0.0)  # -0.0 -> +0.0 so the hashed bit pattern is canonical
            slpos, om0, ze0, om1, ze1 = self._gather(k, n)
            u = np.clip((f - slpos) * _F(0.5 / BLEND_HALF_WIDTH) + _F(0.5), _F(0.0), _F(1.0))
            sm = u * u * (_F(3.0) - _F(2.0) * u) * _F(np.pi / 2)
            w0, w1 = np.cos(sm), np.sin(sm)
            acc = w0 * self._wave(x, om0, ze0, shift, beta) + w1 * self._wave(x, om1, ze1, shift, beta)
            z += self.dirs.amp[k] * acc
        return z

    def _gather(self, k: int, n: np.ndarray):
        """Slice records of slices n and n+1, computed once per distinct slice id."""
        lo, hi = float(n.min()), float(n.max())
        span = int(hi - lo) + 2
        if span <= max(64, len(n) // 4):
            m = (_F(lo) + np.arange(span, dtype=_F)).astype(_F)
            slpos, omega, zeta = self.slice_records(k, m)
            i = (n - _F(lo)).astype(np.int64)
            return slpos[i], omega[i], zeta[i], omega[i + 1], zeta[i + 1]
        slpos, om0, ze0 = self.slice_records(k, n)
        _, om1, ze1 = self.slice_records(k, n + _F(1.0))
        return slpos, om0, ze0, om1, ze1
