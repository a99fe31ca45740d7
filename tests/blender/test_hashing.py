"""The numpy lookup3 port must equal Blender's White Noise node bit for bit."""
import numpy as np
import pytest

from omninoise.backend.wavenoise.hashing import float_bits, hash_uint, white_noise4

# Stored reference samples (lookup3, Blender's constants): guard against
# regressions even where bpy is unavailable.
GOLDEN_UINT = {0: 0x9519DC65, 1: 0x4AD7C6A0, 12345: 0x0FB78C24}


def test_hash_uint_golden():
    got = {k: int(hash_uint(np.array([k], np.uint32))[0]) for k in GOLDEN_UINT}
    assert got == GOLDEN_UINT


def test_white_noise_range_and_uniformity():
    rng = np.random.default_rng(0)
    v = white_noise4(*rng.integers(-10000, 10000, (4, 200000)).astype(np.float32))
    assert v.dtype == np.float32 and v.min() >= 0 and v.max() <= 1
    hist = np.histogram(v, bins=20, range=(0, 1))[0] / len(v)
    assert np.abs(hist - 0.05).max() < 0.004


def test_float_bits_roundtrip():
    x = np.float32([0.0, 1.0, -2.5, 1e4])
    assert np.array_equal(float_bits(x).view(np.float32), x)


def test_matches_blender_white_noise_node():
    pytest.importorskip("bpy")
    from omninoise.blender_addon.field_eval import white_noise_node_values

    rng = np.random.default_rng(1)
    ids = rng.integers(-5000, 5000, (400, 4)).astype(np.float32)
    real = (rng.normal(size=(400, 4)) * 37.0).astype(np.float32)
    x = np.concatenate([ids, real])
    ours = white_noise4(*x.T)
    theirs = white_noise_node_values(x)
    assert np.array_equal(ours, theirs), np.abs(ours - theirs).max()
