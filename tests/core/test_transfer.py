"""RGBA transfer functions (Guehl et al. 2025, Sec. 7.1): ramp maths, presets, JSON."""
import json

import numpy as np
import pytest

from omninoise.backend.errors import SettingError
from omninoise.backend.transfer import PRESETS, TransferFunction, load_transfer, preset, transfer_from_dict

RAMP = dict(range=[-1.0, 1.0], stops=[[0.0, [0, 0, 0, 0]], [0.5, [1, 0, 0, 0.5]], [1.0, [1, 1, 1, 1]]])


def test_linear_ramp_values():
    tf = transfer_from_dict(RAMP)
    v = np.array([-5.0, -1.0, -0.5, 0.0, 0.5, 1.0, 9.0], np.float32)
    rgba = tf.rgba(v)
    assert rgba.dtype == np.float32 and rgba.shape == (7, 4)
    np.testing.assert_allclose(rgba[:, 3], [0, 0, 0.25, 0.5, 0.75, 1, 1], atol=1e-6)
    np.testing.assert_allclose(rgba[2, :3], [0.5, 0, 0], atol=1e-6)
    np.testing.assert_allclose(rgba[4, :3], [1, 0.5, 0.5], atol=1e-6)


def test_constant_and_ease():
    const = transfer_from_dict(dict(RAMP, interpolation="constant"))
    a = const.rgba(np.array([-0.01, 0.0, 0.49, 0.99], np.float32))[:, 3]
    np.testing.assert_allclose(a, [0.0, 0.5, 0.5, 0.5])  # holds the left stop until the next
    ease = transfer_from_dict(dict(RAMP, interpolation="ease"))
    t = 0.25  # a quarter into the first segment: smoothstep(0.5) = 0.5, smoothstep(0.25) = 0.15625
    a = ease.rgba(np.array([-1 + 2 * 0.5 * t], np.float32))[0, 3]
    assert a == pytest.approx(0.5 * (t * t * (3 - 2 * t)), abs=1e-6)


def test_density_scale_and_temperature():
    tf = transfer_from_dict(dict(RAMP, density_scale=3.0, temperature=[[0.5, 0.0], [1.0, 1000.0]]))
    v = np.array([0.0, 0.5, 1.0], np.float32)
    np.testing.assert_allclose(tf.density(tf.rgba(v)), [1.5, 2.25, 3.0], atol=1e-6)
    np.testing.assert_allclose(tf.kelvin(v), [0.0, 500.0, 1000.0], atol=1e-3)
    with pytest.raises(SettingError, match="no temperature"):
        transfer_from_dict(RAMP).kelvin(v)


@pytest.mark.parametrize("bad, match", [
    (dict(RAMP, stops=[[0.6, [0, 0, 0, 0]], [0.2, [1, 1, 1, 1]]]), "sorted"),
    (dict(RAMP, stops=[[1.5, [0, 0, 0, 0]]]), r"\[0, 1\]"),
    (dict(RAMP, range=[1, 1]), "different"),
    (dict(RAMP, interpolation="b_spline"), "interpolation"),
    (dict(RAMP, colour=[1]), "unknown key"),
    (dict(RAMP, stops=[[0.0, [0, 0]]]), r"stops\[0\]\[1\]: expected 3 to 4 items, got 2"),
    (dict(preset="lava"), "preset: expected one of clouds, smoke, fire, marble, crystal, got 'lava'"),
    (dict(range=[0, 1]), "needs stops"),
])
def test_bad_ramps_fail_with_a_reason(bad, match):
    with pytest.raises(SettingError, match=match):
        transfer_from_dict(bad)


def test_json_round_trip_and_files(tmp_path):
    tf = preset("fire")
    again = transfer_from_dict(json.loads(json.dumps(tf.to_dict())))
    assert again == tf
    path = tmp_path / "ramp.json"
    path.write_text(json.dumps(dict(RAMP, interpolation="ease")))
    assert load_transfer(str(path)).interpolation == "ease"
    path.write_text(json.dumps(dict(RAMP, interpolation="EASE")))  # names are exact, with a hint
    with pytest.raises(SettingError, match=r"ramp.json.interpolation: .*\(did you mean ease\?\), got 'EASE'"):
        load_transfer(str(path))
    assert load_transfer("smoke") == preset("smoke")
    path.write_text("{not json")
    with pytest.raises(SettingError, match="not valid JSON"):
        load_transfer(str(path))
    with pytest.raises(SettingError, match="neither a preset"):
        load_transfer(str(tmp_path / "missing.json"))
    assert transfer_from_dict(dict(preset="clouds", density_scale=9.0)).density_scale == 9.0


@pytest.mark.parametrize("name", sorted(PRESETS))
def test_presets_fill_part_of_a_wave_volume(name):
    """Each preset, on the real output's distribution, leaves empty space and dense space."""
    from omninoise.backend import WaveSettings, compile_noise, evaluate_grid

    v = evaluate_grid(compile_noise(WaveSettings(dim=3, seed=2)), 32, 4.0)
    tf = preset(name)
    d = tf.density(tf.rgba(v))
    assert d.dtype == np.float32 and d.shape == v.shape
    occupied = float((d > 0.05 * tf.density_scale).mean())
    if name == "marble":  # solid stone everywhere, veins by colour
        assert occupied == 1.0
        lum = tf.rgba(v)[..., :3].mean(-1)
        assert 0.002 < float((lum < 0.4).mean()) < 0.2
    else:
        assert 0.05 < occupied < 0.9, occupied
    if name == "fire":
        k = tf.kelvin(v)
        assert k.max() > 1000 and k.min() == 0.0


def test_validates_as_a_dataclass():
    with pytest.raises(SettingError, match=r"stops: expected 1 to 4096 items, got 0"):
        TransferFunction(stops=()).validate()


@pytest.mark.parametrize("stops, setting, why", [
    ([[0, [-1, 0, 0, 0]], [1, [1, 1, 1, 1]]], r"ramp.json.stops\[0\]\[1\]\[0\]", r"must lie in \[0, 1000000\]"),
    ([[0, [0, 0, 0, 0]], [1, [5, 1, 1, 2]]], "ramp.json.stops", "the alpha of the stop at 1 must lie in"),
    ([[1, [0, 0, 0, 0]], [0, [1, 1, 1, 1]]], "ramp.json.stops", "positions must be sorted"),
])
def test_a_ramp_file_s_colours_and_rules_are_named_under_its_file(stops, setting, why):
    """Scene-linear colours are not negative (a glow may pass 1); alpha lies in [0, 1] (a negative alpha made a
    negative density); an error of the ramp's own rules is named under the file as the schema's are."""
    from omninoise.backend.errors import SettingError
    from omninoise.backend.transfer import transfer_from_dict

    with pytest.raises(SettingError, match=why) as exc:
        transfer_from_dict({"range": [0, 1], "stops": stops}, "ramp.json")
    assert __import__("re").fullmatch(setting, exc.value.setting), exc.value.setting
    glow = transfer_from_dict({"range": [0, 1], "stops": [[0, [0, 0, 0, 0]], [1, [5, 2, 1, 1]]]}, "ramp.json")
    assert glow.rgba(np.array([1.0], np.float32))[0].tolist() == [5.0, 2.0, 1.0, 1.0]
