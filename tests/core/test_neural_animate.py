"""Animated neural noise without torch: keyframes from swatches, latent motion, keyframe-file errors."""
import numpy as np
import pytest

from omninoise.backend.errors import SettingError
from omninoise.backend.neural.animate import even_keys, frame_latent, frame_weight, parse_keys


def test_even_keys_spread_the_classes_over_the_frames():
    specs = [("perlin", {"scale": 4}), ("cells_f1", {}), ("spots", {"scale": 6.5})]
    keys = even_keys(specs, 10, 20, seed=7)
    assert [(k.frame, k.noise, k.seed) for k in keys] == [(10, "perlin", 7), (15, "cells_f1", 8), (20, "spots", 9)]
    assert keys[2].params == {"scale": 6.5} and isinstance(keys[0].params["scale"], float)
    assert [k.frame for k in even_keys(specs[:1], 3, 9)] == [3]  # one class: a still key, the latent may move
    assert [k.frame for k in even_keys(specs, 1, 3)] == [1, 2, 3]
    for args, msg in [(([], 1, 4), "add a swatch"), ((specs, 5, 4), "FIRST <= LAST"), ((specs, 1, 2), "at least 3")]:
        with pytest.raises(SettingError, match=msg):
            even_keys(*args)


def test_latent_motions_keep_a_unit_gaussian_and_move_smoothly():
    keys = even_keys([("perlin", {}), ("spots", {})], 1, 11, seed=3)
    assert frame_weight(keys, 6) == (keys[0], keys[1], 0.5)
    assert frame_weight(keys, 0)[2] == 0.0 and frame_weight(keys, 30)[0] is keys[1]
    for mode in ("fixed", "slerp", "drift"):
        seq = [frame_latent(keys, f, (32, 32), mode, speed=0.1) for f in range(1, 12)]
        assert all(x.dtype == np.float32 and x.shape == (32, 32) for x in seq)
        norms = np.array([np.linalg.norm(x) for x in seq])
        assert np.all(np.abs(norms / 32.0 - 1) < 0.1), (mode, norms / 32)  # |x_T| ~ sqrt(H W)
        steps = np.array([np.abs(b - a).mean() for a, b in zip(seq, seq[1:])])
        if mode == "fixed":
            assert steps.max() == 0
        else:
            assert steps.min() > 0 and steps.max() < 3 * np.median(steps)  # no jumps
    slerp = [frame_latent(keys, f, (32, 32), "slerp") for f in (1, 11)]
    assert np.array_equal(slerp[0], frame_latent(keys[:1], 1, (32, 32), "fixed"))  # the keys' own seeds
    assert not np.array_equal(slerp[0], slerp[1])
    with pytest.raises(SettingError, match="unknown latent motion 'wobble'"):
        frame_latent(keys, 1, (8, 8), "wobble")


@pytest.mark.parametrize("doc, msg", [
    ({}, "no \\[\\[key\\]\\] tables"),
    ({"keys": []}, "unknown top-level key 'keys'"),
    ({"key": [{"frame": 1.5, "noise": "perlin"}]}, "frame: expected a whole number"),
    ({"key": [{"frame": 1, "noise": "perlin", "params": {"scale": float("nan")}}]}, "finite numbers"),
    ({"key": [{"frame": 1, "noise": "perlin"}, {"frame": 1, "noise": "spots"}]}, "two keyframes at frame 1"),
    ({"key": [{"frame": 1, "noise": "perlin", "speed": 2}]}, "unknown key 'speed'"),
])
def test_keyframe_files_say_what_is_wrong(doc, msg):
    with pytest.raises(SettingError, match=msg):
        parse_keys(doc)
