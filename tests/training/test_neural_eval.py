"""The measuring instrument of python -m bench neural-eval: Fréchet distance, spectra, zoo classifier."""
import numpy as np
import pytest

torch = pytest.importorskip("torch")

from omninoise.training.evaluate import frechet, radial_psd, train_classifier  # noqa: E402


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


def test_orientation_coherence_tells_bands_from_isotropic_texture():
    from omninoise.training.evaluate import orientation_coherence

    y, x = np.mgrid[0:64, 0:64].astype(np.float64)
    rng = np.random.default_rng(1)
    bands = [np.sin(2 * np.pi * (np.cos(a) * x + np.sin(a) * y) / 11.0) for a in (0.0, 0.7, 2.1)]
    white = rng.standard_normal((4, 64, 64))
    coh = orientation_coherence(np.stack(bands))
    assert coh.shape == (3,) and coh.min() > 0.9, coh  # straight bands at any angle
    assert orientation_coherence(white).max() < 0.1  # isotropic
    # bands whose orientation turns across the image (long-range orientation lost) score low
    patch = np.concatenate([np.concatenate([bands[0][:32, :32], bands[2][:32, 32:]], 1),
                            np.concatenate([bands[2][32:, :32], bands[0][32:, 32:]], 1)], 0)
    assert orientation_coherence(patch[None])[0] < 0.6
    assert orientation_coherence(np.zeros((1, 16, 16)))[0] == 0.0


def test_low_frequency_psd_error_sees_what_the_full_error_averages_away():
    from omninoise.training.evaluate import psd_error

    rng = np.random.default_rng(2)
    y, x = np.mgrid[0:64, 0:64]
    real = rng.standard_normal((8, 64, 64)) + 3 * np.sin(2 * np.pi * x / 32.0)[None]  # a long-range band
    gen = rng.standard_normal((8, 64, 64))  # the same fine grain without it
    assert psd_error(gen, real, low=True) > 3 * psd_error(gen, real)
    assert psd_error(real, real, low=True) == 0.0


def test_classifier_stages_widen_the_receptive_field():
    from omninoise.training.evaluate import Classifier

    two, three = Classifier(4), Classifier(4, stages=3)
    x = torch.zeros(1, 1, 64, 64, requires_grad=True)
    for net, expect in ((two, 21), (three, 45)):
        out = net.body(x * 2.0 - 1.0)
        centre = out[0, :, out.shape[2] // 2, out.shape[3] // 2].sum()
        (g,) = torch.autograd.grad(centre, x)
        rows = np.nonzero(g[0, 0].abs().sum(1).numpy())[0]
        assert rows.max() - rows.min() + 1 == expect, (rows.max() - rows.min() + 1)
    assert three.features(torch.rand(2, 1, 64, 64)).shape == (2, 128)


def test_look_tells_spectra_and_histograms_apart_and_finds_the_nearest_class():
    """look(): spectrum shape and value quantiles; nearest_looks ranks a new sample of each kind first,
    a contrast change moves only the histogram term, and identical sets are at distance 0."""
    from omninoise.training.evaluate import look, look_distance, look_scales, nearest_looks

    S = 64
    yy, xx = np.mgrid[0:S, 0:S] / S

    def kind(name, n, seed):
        r = np.random.default_rng(seed)
        if name == "white":
            return r.random((n, S, S))
        if name == "stripes":
            ph = r.random(n)[:, None, None] * 6.283
            return 0.5 + 0.5 * np.sin(2 * np.pi * 8 * xx[None] + ph)
        f = np.fft.fft2(r.standard_normal((n, S, S)))  # smooth blobs: low-passed noise
        k = np.hypot(*np.meshgrid(np.fft.fftfreq(S), np.fft.fftfreq(S), indexing="ij"))
        img = np.real(np.fft.ifft2(f * np.exp(-(k / 0.04) ** 2)))
        lo, hi = img.min(axis=(1, 2), keepdims=True), img.max(axis=(1, 2), keepdims=True)
        return (img - lo) / (hi - lo)

    refs = {k: look(kind(k, 4, 1)) for k in ("white", "stripes", "blobs")}
    scale = look_scales(refs)
    assert all(s > 0 for s in scale)
    for k in refs:
        ranked = nearest_looks(look(kind(k, 4, 2)), refs, scale)
        assert ranked[0][0] == k and ranked[0][1] < 0.5 * ranked[1][1]
    assert look_distance(refs["white"], refs["white"], scale) == 0.0
    w = kind("white", 4, 1)
    dimmer = look(0.25 + 0.5 * w)  # same spectrum shape, other contrast: only the histogram moves
    np.testing.assert_allclose(dimmer["spectrum"], refs["white"]["spectrum"], atol=1e-9)
    assert np.abs(dimmer["histogram"] - refs["white"]["histogram"]).mean() > 0.05

    # a faint grain (1e-2 amplitude, about 2e-5 of the blobs' power in each top band) moves the plain log spectrum
    # a lot and the floored one hardly; a real change of shape (blobs against white) moves both
    b = kind("blobs", 4, 1)
    grain = b + 1e-2 * np.random.default_rng(3).standard_normal(b.shape)
    plain = np.abs(look(grain)["spectrum"] - look(b)["spectrum"]).max()
    floored = np.abs(look(grain, 1e-4)["spectrum"] - look(b, 1e-4)["spectrum"]).max()
    assert plain > 1.0 and floored < 0.05, (plain, floored)
    assert np.abs(look(w, 1e-4)["spectrum"] - look(b, 1e-4)["spectrum"]).mean() > 0.3


def test_periodic_component_solves_moisans_equation_and_removes_the_border_cross():
    """u = p + s (Moisan 2011): the discrete periodic Laplacian of s is the boundary image v, s has mean 0; a crop
    of a smooth tiling field, which jumps at its borders, gets its top-band power back down near the field's own,
    and look() then puts the crop beside the whole field (it did not: the crop's border cross looked like grain)."""
    from omninoise.backend.periodic import periodic_component
    from omninoise.training.evaluate import look, radial_psd

    r = np.random.default_rng(5)
    S = 256
    k = np.hypot(*np.meshgrid(np.fft.fftfreq(S), np.fft.fftfreq(S), indexing="ij"))
    field = np.real(np.fft.ifft2(np.fft.fft2(r.standard_normal((4, S, S))) * np.exp(-(k / 0.02) ** 2)))
    field = 0.5 + 0.15 * field / field.std()
    u = field[:, 37:101, 90:154]  # 64² crops: they do not tile
    p = periodic_component(u)
    s_ = u - p
    lap = sum(np.roll(s_, sh, axis=ax) for sh in (1, -1) for ax in (1, 2)) - 4 * s_
    v = np.zeros_like(u)
    v[:, 0, :] += u[:, -1, :] - u[:, 0, :]
    v[:, -1, :] -= u[:, -1, :] - u[:, 0, :]
    v[:, :, 0] += u[:, :, -1] - u[:, :, 0]
    v[:, :, -1] -= u[:, :, -1] - u[:, :, 0]
    np.testing.assert_allclose(lap, v, atol=1e-9)
    np.testing.assert_allclose(s_.mean(axis=(1, 2)), 0, atol=1e-12)

    def top(imgs):  # share of the power in the top quarter of the radial spectrum
        q = radial_psd(imgs)
        return q[3 * len(q) // 4:].sum() / q.sum()

    assert top(u) > 100 * top(p), (top(u), top(p))  # the border cross dominated the raw crops' top bands
    assert top(p) < 3e-5, top(p)
    assert top(field) < 1e-6
    crop2 = field[:, 150:214, 10:74]
    d_pc = np.abs(look(u)["spectrum"] - look(crop2)["spectrum"]).mean()
    assert d_pc < 0.2, d_pc


def test_known_params_keeps_what_the_model_was_trained_with():
    """An export made before fibers gained 'orientation' is evaluated without it (it draws its own); a model
    that has it is told it."""
    from omninoise.backend.neural.model import NeuralNoiseModel
    from omninoise.backend.paths import neural_model
    from omninoise.training import zoo
    from omninoise.training.evaluate import known_params

    model = NeuralNoiseModel(neural_model())
    params = zoo.default_params("fibers")
    assert "orientation" in params
    own = {p["name"] for p in model.class_params["fibers"]["params"]}
    assert known_params(model, "fibers", params) == {k: v for k, v in params.items() if k in own}
    assert set(known_params(model, "perlin", zoo.default_params("perlin"))) == {"scale"}
    model.class_params = dict(model.class_params, fibers=dict(params=[{"name": "scale"}, {"name": "orientation"}]))
    assert set(known_params(model, "fibers", params)) == {"scale", "orientation"}


def test_cached_classifier_is_keyed_by_the_zoo(tmp_path, monkeypatch):
    """A classifier trained on the zoo before a class changed is another instrument: the cache does not reuse it."""
    from omninoise.training import evaluate as E

    calls = []
    real = E.train_classifier
    monkeypatch.setattr(E, "train_classifier", lambda *a, **k: calls.append(1) or real(*a, **k))
    E.cached_classifier(("perlin", "spots"), 16, 2, str(tmp_path), stages=2, threads=1)
    E.cached_classifier(("perlin", "spots"), 16, 2, str(tmp_path), stages=2, threads=1)
    assert len(calls) == 1 and len(list(tmp_path.glob("classifier_*.pt"))) == 1
    described = E.zoo.describe()
    described["perlin"]["params"][0]["period"] = 0.5  # conditioning only: the same images, the same instrument
    monkeypatch.setattr(E.zoo, "describe", lambda: described)
    E.cached_classifier(("perlin", "spots"), 16, 2, str(tmp_path), stages=2, threads=1)
    assert len(calls) == 1
    described["perlin"]["params"][0]["max"] = 99
    monkeypatch.setattr(E.zoo, "describe", lambda: described)
    E.cached_classifier(("perlin", "spots"), 16, 2, str(tmp_path), stages=2, threads=1)
    assert len(calls) == 2 and len(list(tmp_path.glob("classifier_*.pt"))) == 2


def test_gradient_direction_of_bands():
    """Bands whose gradient points at angle a (0 along +x, the array's columns) give a, modulo 180."""
    from omninoise.training.evaluate import gradient_direction

    y, x = np.mgrid[0:96, 0:96].astype(np.float64)
    for deg in (0, 30, 90, 150):
        a = np.radians(deg)
        img = np.cos(2 * np.pi * 0.07 * (x * np.cos(a) + y * np.sin(a)))
        got = gradient_direction(img[None])[0]
        assert abs((got - deg + 90) % 180 - 90) < 1.0, (deg, got)


def test_direction_error_tells_a_model_that_follows_the_parameter_from_one_that_ignores_it():
    """fibers at 0/45/90/135 degrees: zoo images of other seeds (a model that follows 'orientation') lie within a
    few degrees of the zoo's direction; bands at one fixed direction (a model that draws its own) are 45 off on
    average. gabor_texture is measured on its own parameter name, 'Orientation'."""
    from omninoise.training import zoo
    from omninoise.training.evaluate import angle_difference, direction_error

    S = 64

    def follows(spec, count, seed0):
        name, params = spec
        return zoo.generate(name, {k: np.full(count, v) for k, v in params.items()}, torch.arange(count) + seed0,
                            S).numpy()

    y, x = np.mgrid[0:S, 0:S].astype(np.float64)
    a = np.radians(120.0)
    bands = 0.5 + 0.5 * np.cos(2 * np.pi * 0.1 * (x * np.cos(a) + y * np.sin(a)))

    def ignores(spec, count, seed0):
        return np.repeat(bands[None], count, 0)

    good = direction_error("fibers", follows, S)
    assert good["direction_param"] == "orientation"
    assert good["direction_error"] < 10 and good["direction_error_zoo"] < 10, good
    bad = direction_error("fibers", ignores, S)
    assert 35 < bad["direction_error"] < 55, bad
    assert direction_error("gabor_texture", follows, S)["direction_param"] == "Orientation"
    np.testing.assert_allclose(angle_difference([10, 170, 0, 90], [170, 10, 135, 0]), [20, 20, 45, 90])
