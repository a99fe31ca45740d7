"""Brick (staggered lattice) features of the neural solid textures: joints where the definition puts
them, one value per brick, the stagger, stored references and the torch twin against the runtime."""
import numpy as np
import pytest

from omninoise.backend.solid import brick as Bk

REF_POINTS = np.array([[0.25, -1.5, 3.75], [1000.125, -2000.5, 0.0], [-0.5, 0.5, -0.5]])
REF_T = np.stack([np.eye(3) * 0.5, np.array([[0, 1, 0], [-1, 0, 0], [0, 0, 1.0]]), np.eye(3)]).astype(np.float32)


def test_joints_values_and_stagger_2d():
    T = np.eye(2, dtype=np.float32)[None]
    # bed joints at integer y, head joints at integer x in even rows and half-integers in odd rows
    pts = np.array([[0.3, 2.0], [0.3, 2.5], [1.0, 2.5], [1.5, 3.5], [1.0, 3.5], [0.75, 0.25]])
    f = Bk.brick_features(pts, T, 4, 1)
    np.testing.assert_allclose(f[:, 0], [-1.0, 1.0, 1.0, 1.0, 1.0, 0.0], atol=1e-6)
    np.testing.assert_allclose(f[:, 1], [0.2, 0.2, -1.0, -1.0, 1.0, 0.0], atol=1e-6)
    # one value per brick: the same inside a brick, another across a head joint or in the next row
    inside = Bk.brick_features(np.array([[0.1, 0.2], [0.9, 0.8], [0.5, 0.5]]), T, 4, 1)[:, 2]
    assert np.ptp(inside) == 0
    vals = Bk.brick_features(np.array([[0.5, 0.5], [1.5, 0.5], [0.5, 1.5], [0.3, 1.5]]), T, 4, 1)[:, 2]
    assert len(set(vals[:3].tolist())) == 3 and vals[2] != vals[3]    # odd row: bricks span [-0.5, 0.5), [0.5, 1.5)
    values = Bk.brick_features(np.random.default_rng(0).uniform(-300, 300, (20000, 2)), T, 4, 1)[:, 2]
    assert abs(values.mean()) < 0.05 and values.min() < -0.95 and values.max() > 0.95


def test_3d_joints_in_both_directions_and_reference():
    T = np.eye(3, dtype=np.float32)[None]
    f = Bk.brick_features(np.array([[0.5, 0.5, 0.0], [0.0, 0.5, 0.5], [0.5, 0.5, 0.5]]), T, 2, 1)
    np.testing.assert_allclose(f[:, 1], [-1.0, -1.0, 1.0], atol=1e-6)
    # stored as opensimplex keeps its samples: the hash, stagger and layout are part of every trained model
    ref = np.array([
        [0.0, 0.5, 0.8456, 1.0, -1.0, 0.1085, -1.0, -1.0, -0.9863],
        [0.0, 0.75, 0.0968, 0.0, 1.0, 0.4702, -1.0, -1.0, -0.1222],
        [0.0, 0.0, -0.3803, -1.0, 1.0, -0.0127, -1.0, -1.0, 0.1241]], np.float32)
    got = Bk.brick_features(REF_POINTS, REF_T, 7, 3)
    assert got.shape == (3, 9) and got.dtype == np.float32
    np.testing.assert_allclose(got, ref, atol=1e-4)


def test_errors_name_what_is_wrong():
    with pytest.raises(ValueError, match="brick octaves must be 0..2"):
        Bk.brick_features(np.zeros((4, 2)), np.zeros((2, 2, 2), np.float32), 0, 3)
