"""The measuring instrument of bench/eval_neural.py: Fréchet distance, spectra, zoo classifier."""
import numpy as np
import pytest

torch = pytest.importorskip("torch")

from backend.training.evaluate import frechet, radial_psd, train_classifier  # noqa: E402


def test_frechet_distance():
    rng = np.random.default_rng(0)
    a = rng.standard_normal((4000, 3))
    assert frechet(a, a) == pytest.approx(0.0, abs=1e-8)
    assert frechet(a, a + [2.0, 0.0, 0.0]) == pytest.approx(4.0, rel=1e-6)  # |Δμ|²
    b = rng.standard_normal((4000, 3)) * 2.0  # Σ = 4I vs I: tr(I + 4I - 2·2I) = 3
    assert frechet(a, b) == pytest.approx(3.0, rel=0.1)


def test_radial_psd_finds_a_sinusoid():
    x = np.arange(64)
    img = np.sin(2 * np.pi * 9 * x / 64)[None, :] * np.ones((64, 1))
    p = radial_psd(img[None])
    assert int(np.argmax(p)) + 1 == 9


def test_zoo_classifier_learns_distinct_classes():
    clf, acc = train_classifier(("spots", "damascus"), 16, steps=60, batch=32)
    assert acc > 0.85, acc
    with torch.no_grad():
        assert clf.features(torch.rand(3, 1, 16, 16)).shape == (3, 128)
