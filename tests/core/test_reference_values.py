"""Stored reference values: the wave engine's variants, every zoo class and each shipped model's
first outputs for a fixed seed, against `tests/data/reference/*.json` (written by `tools/make_reference.py`,
run on purpose when an output is meant to change). A change that alters every output no longer passes.

Tolerances: wave noise 1e-5 (float32 engine), zoo 1e-4 (torch), solid models 1e-4 and the neural model
2e-3 (onnxruntime; its two sampler steps amplify CPU-dependent rounding a little).
"""
import json
import os
import sys

import numpy as np
import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "tools"))
import make_reference as ref  # noqa: E402

DATA = os.path.join(ROOT, "tests", "data", "reference")


def stored(name: str) -> dict:
    with open(os.path.join(DATA, name), encoding="utf-8") as fh:
        return json.load(fh)


WAVE = stored("wave.json")
MODELS = stored("models.json")


@pytest.mark.parametrize("variant", sorted(WAVE))
def test_wave_variants_match_their_stored_values(variant):
    case = WAVE[variant]
    assert case["flags"] == ref.WAVE_VARIANTS[variant], "the variant's flags changed: rerun tools/make_reference.py"
    np.testing.assert_allclose(ref.wave_values(case["flags"]), case["values"], atol=1e-5, rtol=0)


def test_every_zoo_class_matches_its_stored_image():
    pytest.importorskip("torch")
    from omninoise.training import zoo

    want = stored("zoo.json")
    assert list(want) == list(zoo.CLASS_NAMES), "classes were added or renamed: rerun tools/make_reference.py"
    for name in zoo.CLASS_NAMES:
        np.testing.assert_allclose(ref.zoo_values(name), want[name], atol=1e-4, rtol=0, err_msg=name)


def test_every_shipped_model_is_in_the_reference():
    assert sorted(MODELS) == sorted(ref.shipped_models()), "a model was added or removed: rerun tools/make_reference.py"


@pytest.mark.parametrize("key", sorted(MODELS))
def test_shipped_models_match_their_stored_first_outputs(key):
    kind, folder = ref.shipped_models()[key]
    case = MODELS[key]
    assert ref.model_fingerprint(kind, folder) == case["fingerprint"], (
        f"{key}: the shipped weights changed; after evaluating the new model, rerun tools/make_reference.py")
    got = ref.neural_values(folder) if kind == "neural" else ref.solid_values(folder)
    np.testing.assert_allclose(got, case["values"], atol=2e-3 if kind == "neural" else 1e-4, rtol=0)


def test_the_reference_catches_a_changed_output(monkeypatch):
    """The instrument itself: a wave engine whose output moves by 1e-4 fails the comparison."""
    import omninoise.backend.grid
    from omninoise import backend

    real = backend.grid.evaluate_points
    monkeypatch.setattr(backend.grid, "evaluate_points", lambda *a, **k: real(*a, **k) + np.float32(1e-4))
    case = WAVE["2d_gaussian"]
    with pytest.raises(AssertionError):
        np.testing.assert_allclose(ref.wave_values(case["flags"]), case["values"], atol=1e-5, rtol=0)
