"""Spun lattices (backend.solid.spin): one rotation per octave seed, uniform, stored reference values."""
import numpy as np
import pytest

from omninoise.backend.solid import spin as S
from omninoise.backend.solid.value_noise import octave_seeds

# the rotations are part of every model trained with spun lattices: a change here would silently change them
REF_3D = np.array([[-0.43438676, -0.7625306, -0.47943214], [-0.8624078, 0.19849654, 0.46567357],
                   [-0.25992474, 0.61574847, -0.74383664]], np.float32)


def test_rotations_are_proper_and_reproducible():
    seeds = octave_seeds(7, 8)
    for dim in (2, 3):
        Q = S.octave_spins(seeds, dim)
        assert Q.shape == (8, dim, dim) and Q.dtype == np.float32
        np.testing.assert_allclose(Q @ np.swapaxes(Q, 1, 2), np.broadcast_to(np.eye(dim), Q.shape), atol=1e-6)
        np.testing.assert_allclose(np.linalg.det(Q), 1.0, atol=1e-6)
        assert len({q.tobytes() for q in Q}) == 8          # every octave its own
        np.testing.assert_array_equal(S.octave_spins(seeds.reshape(2, 4), dim).reshape(Q.shape), Q)   # batch shapes
    np.testing.assert_allclose(S.octave_spins(seeds, 3)[0], REF_3D, atol=1e-7)
    with pytest.raises(ValueError, match="2 or 3 dimensions"):
        S.octave_spins(seeds, 4)


@pytest.mark.parametrize("dim", [2, 3])
def test_rotations_are_uniform(dim):
    """Haar measure: every entry has mean 0 and variance 1/dim; in 3D the rotation axis and angle are those of a
    uniform rotation (trace 1 + 2 cos theta has mean 0 and variance 1)."""
    Q = S.octave_spins(np.arange(40000, dtype=np.int64), dim).astype(np.float64)
    assert np.abs(Q.mean(axis=0)).max() < 0.015
    np.testing.assert_allclose((Q ** 2).mean(axis=0), 1.0 / dim, atol=0.01)
    if dim == 3:
        tr = np.trace(Q, axis1=1, axis2=2)
        assert abs(tr.mean()) < 0.02 and abs(tr.var() - 1.0) < 0.03


def test_spun_turns_each_octave():
    rng = np.random.default_rng(1)
    T = rng.normal(size=(8, 3, 3)).astype(np.float32)
    seeds = octave_seeds(3, 8)
    Q = S.octave_spins(seeds, 3)
    lattice, octave = S.spun(T, seeds, "lattice"), S.spun(T, seeds, "octave")
    np.testing.assert_allclose(lattice, Q @ T, atol=1e-5)
    np.testing.assert_allclose(octave, T @ np.swapaxes(Q, 1, 2), atol=1e-5)
    np.testing.assert_array_equal(S.spun(T, seeds, ""), T)
    # a rotation keeps each transform's singular values: the same stretch, turned
    for got in (lattice, octave):
        np.testing.assert_allclose(np.linalg.svd(got, compute_uv=False), np.linalg.svd(T, compute_uv=False), rtol=1e-5)
    # "lattice" keeps the stretch's world axes (right singular vectors) and turns the lattice; "octave" turns them
    _, _, v0 = np.linalg.svd(T)
    _, _, v1 = np.linalg.svd(lattice)
    _, _, v2 = np.linalg.svd(octave)
    np.testing.assert_allclose(np.abs(np.einsum("mi,mi->m", v0[:, 0], v1[:, 0])), 1.0, atol=1e-4)
    turned = np.einsum("mij,mj->mi", Q, v0[:, 0])
    np.testing.assert_allclose(np.abs(np.einsum("mi,mi->m", turned, v2[:, 0])), 1.0, atol=1e-4)
    with pytest.raises(ValueError, match="spin must be one of"):
        S.spun(T, seeds, "world")


def test_turned_octaves_draw_the_field_turned():
    """"octave": the field of octave i at x is the unturned field at Q_i^T x (one octave, a point set and its
    preimage)."""
    from omninoise.backend.solid.value_noise import value_noise
    rng = np.random.default_rng(2)
    T = rng.normal(size=(1, 3, 3)).astype(np.float32)
    seeds = octave_seeds(5, 1)
    Q = S.octave_spins(seeds, 3)[0].astype(np.float64)
    x = rng.uniform(-2, 2, (500, 3))
    np.testing.assert_allclose(value_noise(x, S.spun(T, seeds, "octave"), 5, 3),
                               value_noise(x @ Q, T, 5, 3), atol=2e-4)


def test_bake_keys_know_the_spin():
    """A model's spin is part of what it draws: the shipped space model turns its octaves, and a bake's key says so
    (the same weights unturned would draw another texture)."""
    from omninoise.backend.paths import solid_models
    from omninoise.backend.solid.model import SolidTextureModel
    from omninoise.backend.sources import SolidSource
    import os

    space = SolidTextureModel(os.path.join(solid_models(), "space"))
    assert space.spin == "octave"
    code = space.code("sand", gaussian=False)       # the decoder's texture (sand's rest would replace it all)
    turned = SolidSource(space, code=code).to_dict()
    space.spin = ""
    plain = SolidSource(space, code=code).to_dict()
    assert turned["spin"] == "octave" and "spin" not in plain
    pts = np.random.default_rng(0).uniform(0, 1, (64, 3))
    unturned = space.evaluate(pts, code, seed=3)
    space.spin = "octave"
    assert np.abs(space.evaluate(pts, code, seed=3) - unturned).mean() > 0.01
