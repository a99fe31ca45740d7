"""The upright Gaussian rest: a photo's orientation kept on walls.

The isotropic Gaussian rest of gaussian_rest.py draws every wave in a uniformly random direction, so a wood photo's
grain or a cliff's strata become blotches in every cut.  Photos of materials are mostly taken of walls, and the
structures an artist expects to keep (strata, grain, ripples, planks) stand upright or lie level in the world.
The upright rest keeps them on walls: each wave takes a photo coefficient's vertical frequency on z and its
horizontal frequency, turned about z by a uniform angle psi, in the xy-plane:

    k_j = (R_j cos psi_j, R_j sin psi_j, v_j)

so the solid is the same in distribution on every wall (any vertical plane) and each wall shows the photo's
joint spectrum of (horizontal, vertical) frequency.  A wall shows a horizontal frequency R at R |cos psi|
(psi measured from the wall's normal's perpendicular), so for each vertical frequency the horizontal magnitudes
are deprojected from the photo's by Richardson-Lucy with the kernel of :func:`circle_inside` (as gaussian_rest.py does
for plane cuts of a sphere's directions).  Colours, importance weights, phases and MIN_CYCLES are gaussian_rest.py's.

What it cannot keep: a tilt.  A solid that is the same on every wall is the same on a wall and on its mirror
image (psi and psi + pi), so strata tilted by 30 degrees in the photo are drawn level; the photo is turned by less
than 45 degrees before its spectrum is read, so that its dominant direction (:func:`orientation`) lies along its
rows or columns (diagonal planks become level ones, not a lattice of both diagonals).  And floors: a horizontal
cut shows only the horizontal frequencies, isotropically, so it loses the photo's layering; the encode-time check
(gaussian_rest.choose_mix) sees floors beside walls and takes the upright rest only where the whole comes closer.

The gate: the check chooses among the rests it is offered, and each offer is one more chance for the check's
noise (structure at the scale of its 128² planes) to choose.  The upright rest is offered only where the rest's
spectrum is oriented: :func:`orientation`'s coherence above UPRIGHT_GATE.  Calibrated on the training split (80
photos, every sixth; ``docs/evaluations/solid_upright_gate_train_*.json``): offered to
every photo, the check took it for 26, and by the held-out evaluation's distance against the texture without it
(photos more than 5 % closer / farther): coherence above 0.15, 9 photos, pooled x, y and z slices 6 / 1, their
band-pass levels 7 / 0, walls 5 / 1, floors 0 / 6 (the trade-off above); from 0.10 to 0.15, 6 photos, 4 / 1; at
0.10 and below, 11 photos, 3 / 3 (the check's noise, not the photo's layers, chose there).

Offered, the upright rest costs one more set of check renders: encoding a 256² wood photo takes 1.9 s instead of
1.1 s (AMD EPYC, 2 cores); the texture's evaluation costs what the isotropic rest's does (the same number of
waves).

Shapes: photos float (H, W, 3) sRGB in [0, 1]; frequencies float64 (M, 3) cycles per unit.
"""
from __future__ import annotations

import numpy as np

from .gaussian_rest import (BINS, COUNT, REST_CHOICES, WAVE_SEED, colour_picks, deproject, rest_spectrum, rest_waves,
                       wave_amplitudes, wave_sampling)

__all__ = ["circle_inside", "orientation", "spectrum_orientation", "upright_waves", "candidates", "UPRIGHT_GATE"]

UPRIGHT_GATE = 0.15     #: the upright rest is offered where the rest's spectral coherence is above this (module doc)


def circle_inside(a: np.ndarray, R: np.ndarray) -> np.ndarray:
    """The fraction of horizontal frequencies of magnitude R, turned about z by a uniform angle psi, that a wall
    shows above a: a wall shows R |cos psi|, so (2 / pi) arccos(a / R)."""
    return (2.0 / np.pi) * np.arccos(np.clip(np.minimum(a, R) / R, 0.0, 1.0))


def orientation(residual: np.ndarray) -> tuple:
    """How strongly a photo's ``residual`` (H, W, 3) is oriented, from its power spectrum: (coherence in [0, 1], angle in
    radians of the dominant frequency direction from the photo's columns axis, counter-clockwise with rows
    pointing down).  The spectrum's structure tensor T = sum P(f) f f^T / |f|^2 (every frequency's direction
    weighted by its power, periodic component, nothing below MIN_CYCLES): coherence (l1 - l2) / (l1 + l2) of its
    eigenvalues, 0 for an isotropic texture, 1 for parallel stripes (Bigun & Granlund 1987 read gradients; the
    spectrum sees strata that gradients of a rough rock face hide)."""
    return spectrum_orientation(rest_spectrum(residual, 1.0))


def spectrum_orientation(spectrum) -> tuple:
    """:func:`orientation` of a rest from its :func:`~backend.solid.gaussian_rest.rest_spectrum` (at any scale: the
    coherence and the angle do not depend on it), (0, 0) for None (a flat photo)."""
    if spectrum is None:
        return 0.0, 0.0
    _, P, fx, fy, _ = spectrum
    r2 = np.maximum(fx * fx + fy * fy, 1e-300)
    txx, tyy, txy = ((P * g / r2).sum() for g in (fx * fx, fy * fy, fx * fy))
    tr = txx + tyy
    if not tr > 0:
        return 0.0, 0.0
    return float(np.hypot(txx - tyy, 2.0 * txy) / tr), float(0.5 * np.arctan2(2.0 * txy, txx - tyy))


def upright_waves(residual: np.ndarray, px_per_unit: float, count: int = COUNT, seed: int = WAVE_SEED, spectrum=None):
    """The upright Gaussian rest of a photo's ``residual`` (H, W, 3; the photo less its harmonic part) (module doc), as :func:`rest_waves`: (freq float64
    (count, 3), amp complex128 (count, 3)) at full variance, None for a flat photo.  The photo is first turned by
    less than 45 degrees so that its dominant direction (:func:`orientation`) lies along its rows or columns.
    ``spectrum``: :func:`~backend.solid.gaussian_rest.rest_spectrum` of the same rest and scale, where the caller has
    it already (it is the photo's periodic component and FFT: 0.7 s for a 1024² photo)."""
    spec = rest_spectrum(residual, px_per_unit) if spectrum is None else spectrum
    if spec is None:
        return None
    F, P, fx, fy, V = spec
    _, angle = spectrum_orientation(spec)
    turn = angle - np.round(angle / (0.5 * np.pi)) * 0.5 * np.pi        # to the nearest axis, |turn| <= 45 deg
    c, s = np.cos(turn), np.sin(turn)
    h, v = np.abs(c * fx + s * fy), np.abs(-s * fx + c * fy)          # horizontal and vertical frequency
    # bins centred on multiples of w (a photo's frequencies are multiples of ppu / side: floor bins would put
    # each on a bin's lower edge and the draws half a bin lower), the first one [0, w / 2]
    w = max(h.max(), v.max()) / (BINS - 0.5) * (1.0 + 1e-9)
    edges = np.concatenate([[0.0], (np.arange(BINS) + 0.5) * w])
    bh, bv = (np.minimum(np.rint(x / w).astype(np.int64), BINS - 1) for x in (h, v))
    p2 = np.bincount(bv * BINS + bh, P, BINS * BINS).reshape(BINS, BINS)   # (vertical bin, horizontal bin)
    p3 = deproject(p2, edges, inside=circle_inside)                 # each row: walls show R |cos psi|
    rng = np.random.default_rng(seed)
    share = (p3 / p3.sum()).ravel()
    q = wave_sampling(share)
    kb = rng.choice(BINS * BINS, size=count, p=q)
    kh = kb % BINS
    R = rng.uniform(edges[kh], edges[kh + 1])
    psi = rng.uniform(0.0, 2.0 * np.pi, count)
    # colours and vertical frequencies from the photo's coefficients of the wave's cell, or the nearest with power
    pick = colour_picks(F, P, bv * BINS + bh, kb, rng)
    freq = np.stack([R * np.cos(psi), R * np.sin(psi), v[pick]], axis=1)
    return freq, wave_amplitudes(F, P, pick, 2.0 * V * share[kb] / (count * q[kb]), rng)


def candidates(residual: np.ndarray, px_per_unit: float, choice: str = "auto", gate: float = UPRIGHT_GATE) -> dict:
    """The Gaussian rests a photo's ``residual`` (H, W, 3; the photo less its harmonic part) offers the check (gaussian_rest.choose_mix): {kind: waves}.  For
    ``choice`` "auto" the isotropic rest (:func:`~backend.solid.gaussian_rest.rest_waves`) always and the upright one
    (:func:`upright_waves`) where the rest's spectrum is oriented (:func:`orientation`'s coherence above
    ``gate``); for "isotropic" or "upright" (an artist's choice, gaussian_rest.REST_CHOICES) that one alone.  {} for
    a flat photo."""
    if choice not in REST_CHOICES:
        raise ValueError(f"a Gaussian rest is one of {', '.join(REST_CHOICES)}, not {choice!r}")
    spec = rest_spectrum(residual, px_per_unit)            # once, for every kind and the gate
    if spec is None:
        return {}
    out = {} if choice == "upright" else {"isotropic": rest_waves(residual, px_per_unit, spectrum=spec)}
    if choice == "upright" or (choice == "auto" and spectrum_orientation(spec)[0] > gate):
        out["upright"] = upright_waves(residual, px_per_unit, spectrum=spec)
    return out
