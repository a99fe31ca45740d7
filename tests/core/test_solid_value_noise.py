"""Lattice noise of the neural solid textures: stored reference values, numba = numpy = torch, properties."""
import numpy as np
import pytest

from omninoise.backend.solid import value_noise as L

# Reference samples (as opensimplex keeps): the hash and blend are part of every trained
# model, so a change here would silently break the shipped solid textures.
REF_POINTS = np.array([[0.25, -1.5, 3.75], [1000.125, -2000.5, 0.0], [-0.5, 0.5, -0.5]])
REF_T = np.stack([np.eye(3) * 0.5, np.array([[0, 1, 0], [-1, 0, 0], [0, 0, 1.0]]), np.eye(3)]).astype(np.float32)
REF = np.array([
    [0.04904695, 0.606357, 0.36193812, 0.6793744, -0.10166178, 0.7062561, -0.18670577, -0.6422287, -0.61485827],
    [-0.7210318, -0.56171817, -0.1666034, -0.42882454, 0.27193305, -0.5115469, -0.799609, -0.20234604, -0.1886608],
    [0.11437499, -0.11510282, -0.02255312, -0.22189638, -0.04789834, -0.42521995, 0.370479, 0.1260997, 0.08308896]],
    np.float32)


def test_hash_and_seeds_reference():
    assert [L.lowbias32(v) for v in (0, 1, 123456789)] == [0, 1753845952, 2834422664]
    assert L.octave_seeds(7, 3).tolist() == [3469856777, 2157168926, 1097398595]


def test_reference_samples_numpy_and_compiled():
    np.testing.assert_allclose(L.lattice_noise_numpy(REF_POINTS, REF_T, 7, 3), REF, atol=2e-7)
    np.testing.assert_allclose(L.value_noise(REF_POINTS, REF_T, 7, 3), REF, atol=2e-7)


@pytest.mark.parametrize("D", [2, 3])
def test_compiled_equals_numpy(D):
    rng = np.random.default_rng(D)
    x = rng.uniform(-50, 50, (3000, D))
    T = rng.normal(size=(8, D, D)).astype(np.float32)
    for C in (1, 2, 3):
        a = L.lattice_noise_numpy(x, T, 11, C)
        b = L.value_noise(x, T, 11, C)
        assert a.dtype == b.dtype == np.float32 and a.shape == (3000, 8 * C)
        np.testing.assert_allclose(a, b, atol=1e-6)


def test_channels_are_prefixes_and_seeds_differ():
    rng = np.random.default_rng(0)
    x = rng.uniform(-5, 5, (500, 3))
    T = np.stack([np.eye(3, dtype=np.float32)] * 4)
    a3 = L.value_noise(x, T, 3, 3)
    a1 = L.value_noise(x, T, 3, 1)
    np.testing.assert_array_equal(a3[:, ::3], a1)
    assert np.abs(L.value_noise(x, T, 4, 3) - a3).mean() > 0.1


def test_values_are_lattice_values_and_continuous():
    T = np.eye(2, dtype=np.float32)[None]
    # at integer points the blend returns the lattice value itself: a multiple of 2/1023 minus 1
    k = np.array([[3.0, -7.0], [0.0, 0.0], [-1000.0, 5.0]])
    v = L.value_noise(k, T, 1, 3)
    q = (v + 1.0) * 1023.0 / 2.0
    np.testing.assert_allclose(q, np.round(q), atol=1e-3)
    # continuity across a cell border (C1 smoothstep): tiny steps give tiny changes
    x = np.array([[2.0 - 1e-6, 0.3], [2.0 + 1e-6, 0.3]])
    v = L.value_noise(x, T, 1, 3)
    assert np.abs(v[0] - v[1]).max() < 1e-4


def test_statistics_zero_mean_no_period():
    rng = np.random.default_rng(1)
    T = np.stack([np.eye(3, dtype=np.float32)])
    v = L.value_noise(rng.uniform(-1e4, 1e4, (200000, 3)), T, 0, 3)
    assert abs(float(v.mean())) < 0.01 and 0.3 < float(v.std()) < 0.45
    # far from the origin the field is as rich as near it (no precision collapse at 1e4)
    near = L.value_noise(rng.uniform(0, 8, (4000, 3)), T, 0, 1)
    far = L.value_noise(1e4 + rng.uniform(0, 8, (4000, 3)), T, 0, 1)
    assert abs(float(near.std()) - float(far.std())) < 0.05


def test_bad_shapes_raise():
    with pytest.raises(ValueError, match="points"):
        L.value_noise(np.zeros((4, 4)), np.zeros((8, 4, 4), np.float32), 0)
    with pytest.raises(ValueError, match="transforms"):
        L.value_noise(np.zeros((4, 3)), np.zeros((8, 2, 2), np.float32), 0)
    with pytest.raises(ValueError, match="channels"):
        L.value_noise(np.zeros((4, 3)), np.zeros((8, 3, 3), np.float32), 0, 4)


@pytest.mark.parametrize("D", [2, 3])
def test_torch_twin_matches_runtime(D):
    torch = pytest.importorskip("torch")
    from omninoise.training.solid.value_noise import value_noise, octave_seeds
    rng = np.random.default_rng(5)
    x = rng.uniform(-2, 2, (2, 2000, D)).astype(np.float32)
    T = rng.normal(size=(8, D, D)).astype(np.float32)
    a = value_noise(torch.from_numpy(x), torch.from_numpy(T), octave_seeds([5, 9], 8), 3).numpy()
    for b, s in enumerate((5, 9)):
        # float32 positions in torch against float64 here: at 2^7 |T x| ~ 1e3 the fraction differs by ~1e-4
        np.testing.assert_allclose(a[b], L.value_noise(x[b], T, s, 3), atol=5e-4)
    # gradients reach the transforms through the blend weights
    Tt = torch.from_numpy(T).requires_grad_(True)
    value_noise(torch.from_numpy(x), Tt, octave_seeds([5, 9], 8), 3).square().sum().backward()
    assert torch.isfinite(Tt.grad).all() and Tt.grad.abs().sum() > 0
