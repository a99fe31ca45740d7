"""Cellular (Worley) features of the neural solid textures: stored references, the brute-force
definition, Lipschitz continuity, feature points, and the torch twin against the runtime."""
import itertools

import numpy as np
import pytest

from omninoise.backend.solid import cellular as C
from omninoise.backend.solid.value_noise import BITS, MASK32, lowbias32

REF_POINTS = np.array([[0.25, -1.5, 3.75], [1000.125, -2000.5, 0.0], [-0.5, 0.5, -0.5]])
REF_T = np.stack([np.eye(3) * 0.5, np.array([[0, 1, 0], [-1, 0, 0], [0, 0, 1.0]]), np.eye(3)]).astype(np.float32)


def _feature_point(seed_i, cell):
    """The jittered feature point of one lattice cell, by the module doc's definition."""
    h = int(seed_i)
    for c in cell:
        h = lowbias32((h + (int(c) & MASK32)) & MASK32)
    levels = (1 << BITS) - 1
    jit = [((h >> (BITS * d)) & levels) / (levels + 1) for d in range(len(cell))]
    return np.asarray(cell, np.float64) + jit, (lowbias32(h) & levels) * (2.0 / levels) - 1.0


def _brute(p, seed_i, reach=2):
    """F1, F2, nearest cell's value over (2 reach + 1)^D cells around p: the definition without the 3^D cut."""
    base = np.floor(p).astype(int)
    found = []
    for off in itertools.product(range(-reach, reach + 1), repeat=len(p)):
        q, v = _feature_point(seed_i, base + off)
        found.append((float(np.linalg.norm(p - q)), v))
    found.sort()
    return found[0][0], found[1][0], found[0][1]


def test_reference_samples():
    # stored as opensimplex keeps its samples: the hash, jitter and layout are part of every trained model
    ref = np.array([
        [-0.1617, -0.8936, -0.1241, -0.2225, -0.6917, 0.306, 0.0603, -0.3887, 0.9433],
        [-0.3066, -0.5883, 0.6442, -0.1093, -0.7033, 0.566, 0.2461, -0.9093, 0.9042],
        [0.0181, -0.497, -0.4761, -0.2658, -0.3725, -0.8436, 0.0104, -0.8978, -0.4174]], np.float32)
    got = C.cellular_features(REF_POINTS, REF_T, 7, 3)
    assert got.shape == (3, 9) and got.dtype == np.float32
    np.testing.assert_allclose(got, ref, atol=1e-4)


@pytest.mark.parametrize("D", [2, 3])
def test_matches_the_brute_force_definition(D):
    rng = np.random.default_rng(D)
    T = rng.normal(size=(2, D, D)).astype(np.float32)
    x = rng.uniform(-20, 20, (300, D))
    got = C.cellular_features(x, T, 3, 2)
    seeds = C.cell_seeds(3, 2)
    agree = 0
    for n in range(len(x)):
        for i in range(2):
            p = (T[i].astype(np.float64) @ x[n]) * 2 ** i
            f1, f2, v = _brute(p, seeds[i])
            want = np.array([2 * f1 - 1, 2 * (f2 - f1) - 1, v])
            agree += np.allclose(got[n, 3 * i:3 * i + 3], want, atol=1e-5)
    # the 3^D search misses a nearer point two cells away only rarely (the usual Worley approximation)
    assert agree >= 0.97 * 600, agree


def test_feature_points_zero_distance_and_cell_constant():
    seeds = C.cell_seeds(11, 1)
    T = np.eye(2, dtype=np.float32)[None]
    for cell in [(0, 0), (-5, 17), (123, -456)]:
        q, v = _feature_point(seeds[0], cell)
        got = C.cellular_features(q[None], T, 11, 1)[0]
        assert got[0] == pytest.approx(-1.0, abs=1e-6)       # F1 = 0 at the feature point
        assert got[2] == pytest.approx(v, abs=1e-6)           # the cell's own value
        near = C.cellular_features(q[None] + [[1e-3, -1e-3]], T, 11, 1)[0]
        assert near[2] == pytest.approx(v, abs=1e-6)          # constant around it


@pytest.mark.parametrize("D", [2, 3])
def test_lipschitz_and_ranges(D):
    # F1 and F2 are 1-Lipschitz in p: no jump, which a skipped neighbour cell would cause
    rng = np.random.default_rng(7)
    T = np.eye(D, dtype=np.float32)[None]
    x = rng.uniform(-50, 50, (20000, D))
    d = rng.normal(size=x.shape)
    d *= 1e-3 / np.linalg.norm(d, axis=1, keepdims=True)
    a, b = C.cellular_features(x, T, 1, 1), C.cellular_features(x + d, T, 1, 1)
    assert np.abs(a[:, 0] - b[:, 0]).max() <= 2 * 1e-3 + 1e-5      # 2 F1 - 1: Lipschitz 2
    assert np.all(a[:, 1] >= -1.0)                                  # F2 >= F1
    assert np.all(np.abs(a) <= 1.0 + 2.0 * np.sqrt(D))
    # the cell value is uniform in [-1, 1] over many cells; F2 - F1 reaches 0 on the borders
    assert abs(a[:, 2].mean()) < 0.05 and a[:, 2].min() < -0.95 and a[:, 2].max() > 0.95
    assert a[:, 1].min() < -0.99


def test_errors_name_what_is_wrong():
    with pytest.raises(ValueError, match="cellular octaves must be 0..2"):
        C.cellular_features(np.zeros((4, 2)), np.zeros((2, 2, 2), np.float32), 0, 3)
    with pytest.raises(ValueError, match="points must have shape"):
        C.cellular_features(np.zeros((4, 4)), np.zeros((2, 4, 4), np.float32), 0, 1)


@pytest.mark.parametrize("D", [2, 3])
def test_compiled_equals_numpy(D):
    from omninoise.backend.solid.value_noise import fast_available
    if not fast_available():
        pytest.skip("numba is not installed")
    rng = np.random.default_rng(D)
    x = rng.uniform(-100, 100, (5000, D))
    T = rng.normal(size=(8, D, D)).astype(np.float32)
    np.testing.assert_allclose(C.cellular_features(x, T, 3, 5), C.cellular_features_numpy(x, T, 3, 5), atol=1e-6)
    np.testing.assert_allclose(C.cellular_features(REF_POINTS, REF_T, 7, 3),
                               C.cellular_features_numpy(REF_POINTS, REF_T, 7, 3), atol=1e-6)
