"""UV texel -> 3D surface positions for solid-texture bakes (Blender-free)."""
import numpy as np
import pytest

from omninoise.backend.grid import Cancelled

from omninoise.backend.solid.surface import dilate, texel_positions


def _square(z=0.0):
    """Two triangles: UV square [0,1]^2 mapped onto the 3D square [-1,1]^2 at height z."""
    uv = np.array([[[0, 0], [1, 0], [1, 1]], [[0, 0], [1, 1], [0, 1]]], float)
    pos = np.concatenate([uv * 2 - 1, np.full((2, 3, 1), z)], axis=2)
    return uv, pos


def test_square_covers_every_texel_with_the_affine_position():
    uv, pos = _square(0.5)
    mask, pts = texel_positions(uv, pos, 16, 8)
    assert mask.all()
    j, i = np.meshgrid(np.arange(16), np.arange(8))
    np.testing.assert_allclose(pts[..., 0], -1 + 2 * (j + 0.5) / 16, atol=1e-12)
    np.testing.assert_allclose(pts[..., 1], -1 + 2 * (i + 0.5) / 8, atol=1e-12)   # row 0 = bottom (v = 0)
    np.testing.assert_allclose(pts[..., 2], 0.5)


def test_partial_coverage_and_degenerate_triangles():
    uv = np.array([[[0, 0], [0.5, 0], [0, 0.5]], [[0.7, 0.7], [0.7, 0.7], [0.8, 0.9]]], float)
    pos = np.zeros((2, 3, 3))
    pos[0, :, 0] = [0, 1, 0]
    pos[0, :, 1] = [0, 0, 1]
    mask, pts = texel_positions(uv, pos, 10, 10)
    # the first triangle covers the texel centres with x + y <= 5 (in texels)
    i, j = np.nonzero(mask)
    assert ((i + 0.5) + (j + 0.5) <= 5.0 + 1e-9).all() and mask.sum() == 15
    np.testing.assert_allclose(pts[mask][:, 0], (j + 0.5) / 5.0)   # barycentric x from u
    with pytest.raises(ValueError, match="uv must have shape"):
        texel_positions(np.zeros((2, 3)), pos, 4, 4)
    with pytest.raises(Cancelled):
        texel_positions(uv, pos, 4, 4, cancel=lambda: True)


def test_dilate_extends_islands_without_touching_them():
    mask = np.zeros((6, 6), bool)
    mask[2:4, 2:4] = True
    vals = np.zeros((6, 6, 3))
    vals[mask] = [1.0, 2.0, 3.0]
    m1, v1 = dilate(mask, vals, 1)
    assert m1[1:5, 1:5].all() and m1.sum() == 16
    np.testing.assert_allclose(v1[m1], np.broadcast_to([1.0, 2.0, 3.0], (16, 3)))
    m3, _ = dilate(mask, vals, 10)
    assert m3.all()
    assert not mask[0, 0] and vals[0, 0, 0] == 0.0     # inputs unchanged
