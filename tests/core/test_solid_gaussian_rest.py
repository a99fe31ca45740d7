"""The Gaussian rest of an encoded photo (backend/solid/gaussian_rest.py) and the band distance that decides it
(backend/solid/band_distance.py): cuts of the solid have the photo's radial spectrum, variance and colours; the
check keeps the decoder where it is as close and mixes the rest in where the decoder is far; seeds, mixing and
the texture an artist gets."""
import json
import os

import numpy as np
import pytest

from omninoise.backend.solid.band_distance import band_distance
from omninoise.backend.solid.pipeline import PhotoConfig, photo_code
from omninoise.backend.solid.model import SolidTextureModel, slice_points
from omninoise.backend.solid.gaussian_rest import (CHECK_PLANES, COUNT, MARGIN, MIXES, RENDER, GaussianRest,
                                                   deproject, choose_mix, mix_rests, rest_field, rest_waves)

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SPACE = os.path.join(ROOT, "models", "solid", "space")
PPU = 128.0


def band_photo(n=128, seed=0):
    """A Gaussian texture (n, n, 3) with flat power from 6 to 40 cycles per 128 px (per texture unit at PPU) and
    none elsewhere, its colours along one axis (brown-grey)."""
    rng = np.random.default_rng(seed)
    fy, fx = np.meshgrid(np.fft.fftfreq(n), np.fft.fftfreq(n), indexing="ij")
    r = np.hypot(fy, fx) * 128
    g = np.real(np.fft.ifft2(np.fft.fft2(rng.standard_normal((n, n))) * ((r >= 6) & (r <= 40))))
    return np.clip(0.45 + 0.08 * (g / g.std())[..., None] * np.array([1.0, 0.8, 0.5]), 0, 1)


def radial_power(img, bins):
    """The radial power spectrum of an image (H, W, 3) (mean removed, summed over channels), in cycles per
    photo side, as bins (len bins - 1,)."""
    a = img - img.mean((0, 1))
    P = (np.abs(np.fft.fft2(a.transpose(2, 0, 1))) ** 2).sum(0)
    fy, fx = np.meshgrid(np.fft.fftfreq(a.shape[0]), np.fft.fftfreq(a.shape[1]), indexing="ij")
    r = np.hypot(fy, fx) * a.shape[0]
    return np.histogram(r.ravel(), bins, weights=P.ravel())[0]


def test_deprojection_inverts_the_abel_kernel():
    """A solid's radial power on one annulus shows in plane cuts spread below it; deproject gives it back."""
    edges = np.linspace(0, 10, 41)
    R = 0.5 * (edges[:-1] + edges[1:])[None, :]
    inside = lambda a: np.sqrt(np.clip(1 - (np.minimum(a, R) / R) ** 2, 0, 1))
    K = inside(edges[:-1, None]) - inside(edges[1:, None])
    p3 = np.zeros(40)
    p3[30] = 1.0
    p2 = K @ p3
    assert p2[30] < 0.5 and p2[:30].sum() > 0.5           # a cut sees most of it lower down
    got = deproject(p2, edges, iterations=2000)
    assert got.argmax() == 30 and got[30] / got.sum() > 0.8


def test_cuts_of_the_solid_have_the_photo_s_radial_spectrum_variance_and_colour(monkeypatch):
    img = band_photo()
    bins = np.arange(0, 65, 2.0)
    centre = 0.5 * (bins[1:] + bins[:-1])
    want = radial_power(img, bins)
    want /= want.sum()

    def cuts_of(waves):
        r = GaussianRest(*waves, 1.0)
        return [rest_field(slice_points(128, PPU, ax, (0.3, 1.7, 2.9)), r, seed).reshape(128, 128, 3)
                for ax in "xyz" for seed in (1, 2)]

    def spectrum(cuts):
        got = np.mean([radial_power(c, bins) for c in cuts], axis=0)
        return got / got.sum()

    freq, amp = rest_waves(img, PPU)
    assert freq.shape == (COUNT, 3) and amp.shape == (COUNT, 3)
    cuts = cuts_of((freq, amp))
    got = spectrum(cuts)
    assert abs((centre * got).sum() / (centre * want).sum() - 1.0) < 0.03
    assert np.abs(got - want).sum() < 0.25
    # without the deprojection the cuts' spectrum slides down (each wave shows at R sin(theta), pi / 4 R on average)
    import omninoise.backend.solid.gaussian_rest as spectral
    monkeypatch.setattr(spectral, "deproject", lambda p2, edges: p2)
    flat = spectrum(cuts_of(rest_waves(img, PPU)))
    assert (centre * flat).sum() / (centre * want).sum() < 0.85 and np.abs(flat - want).sum() > 0.35
    var = np.mean([c.reshape(-1, 3).var(0).sum() for c in cuts])
    assert abs(var / img.reshape(-1, 3).var(0).sum() - 1.0) < 0.15
    cov = np.mean([np.cov(c.reshape(-1, 3).T) for c in cuts], axis=0)
    assert cov[0, 1] / np.sqrt(cov[0, 0] * cov[1, 1]) > 0.95      # the photo's colours vary along one axis


def test_the_waves_are_the_same_for_the_same_photo_and_seeds_move_them():
    img = band_photo(seed=3)
    a, b = rest_waves(img, PPU), rest_waves(img, PPU)
    assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])
    r = GaussianRest(*a, 1.0)
    pts = slice_points(32, PPU, "z")
    assert np.array_equal(rest_field(pts, r, 4), rest_field(pts, r, 4))
    assert np.abs(rest_field(pts, r, 4) - rest_field(pts, r, 5)).mean() > 0.01
    assert rest_waves(np.full((64, 64, 3), 0.3), PPU) is None          # a flat photo: nothing to draw


def test_band_distance_sees_structure_and_is_near_zero_for_the_same_texture():
    img = band_photo(256)
    same = [img[:128, :128], img[128:, 128:]]
    rng = np.random.default_rng(0)
    shuffled = [img.reshape(-1, 3)[rng.permutation(256 * 256)].reshape(256, 256, 3)[:128, :128]]
    blurred = [np.full((128, 128, 3), img.mean((0, 1)))]
    d_same, d_shuf, d_flat = (band_distance(x, img) for x in (same, shuffled, blurred))
    assert d_same < 0.3 * d_shuf and d_same < 0.3 * d_flat
    assert band_distance(same, img, seed=1) != d_same                   # seeds draw other neighbourhoods
    with pytest.raises(ValueError, match="at least one image"):
        band_distance([], img)


def test_a_prepared_photo_measures_as_band_distance_does_for_any_layout_of_renders():
    """BandReference (the photo's pyramid, draws and sorted projections kept per layout of renders, as the checks
    measure five to nine render sets against one photo) gives band_distance's figure to the bit, whichever layouts
    (counts and shapes of renders) it has met before, and with its own seed."""
    from omninoise.backend.solid.band_distance import BandReference

    img, rng = band_photo(160), np.random.default_rng(4)
    layouts = ([(64, 64, 3)] * 3, [(64, 64, 3)] * 2, [(48, 80, 3), (64, 64, 3)], [(64, 64, 3)] * 3)
    for seed in (0, 3):
        ref = BandReference(img, seed)
        for shapes in layouts + layouts[::-1]:
            renders = [rng.random(s) for s in shapes]
            assert ref.distance(renders) == band_distance(renders, img, seed) == band_distance(renders, ref)
    with pytest.raises(ValueError, match="at least one image"):
        BandReference(img).distance([])


def _layers_from(dec_fn, img):
    """A check's layers: fixed = the photo's mean, decoder = dec_fn(points)."""
    mean = img.mean((0, 1)).astype(np.float32)

    def layers(seed, axis, offset):
        pts = slice_points(RENDER, PPU, axis, offset)
        return np.broadcast_to(mean, (len(pts), 3)).copy(), dec_fn(pts, seed), pts
    return layers


@pytest.mark.long
def test_the_check_mixes_the_rest_in_where_the_decoder_is_far_and_keeps_a_decoder_that_is_close():
    img = band_photo(256)
    waves = rest_waves(img, PPU)
    # a decoder that draws nothing (flat): the Gaussian rest is far closer
    flat = choose_mix(_layers_from(lambda p, s: np.zeros((len(p), 3), np.float32), img), img, {"isotropic": waves})
    assert flat is not None and flat.mix == max(MIXES)
    assert np.allclose(flat.amp, waves[1])                 # t = 1: full amplitude
    # a decoder that draws the same Gaussian texture (another draw of it): no mix is MARGIN closer
    other = rest_waves(img, PPU, seed=99)
    same = choose_mix(_layers_from(lambda p, s: rest_field(p, GaussianRest(*other, 1.0), s + 50), img), img,
                      {"isotropic": waves})
    assert same is None
    assert choose_mix(_layers_from(lambda p, s: np.zeros((len(p), 3), np.float32), img), img, {}) is None
    assert 0.0 < MARGIN < 1.0


def test_mixing_rests_weights_powers():
    a = GaussianRest(np.ones((4, 3)), np.full((4, 3), 2.0 + 0j), 0.5)
    b = GaussianRest(np.zeros((2, 3)), np.full((2, 3), 1.0 + 0j), 1.0)
    m = mix_rests(a, b, 0.25)
    assert len(m) == 6 and np.isclose(m.mix, 0.75 * 0.5 + 0.25 * 1.0)
    assert np.allclose(np.abs(m.amp[:4]) ** 2, 0.75 * 4.0) and np.allclose(np.abs(m.amp[4:]) ** 2, 0.25)
    assert mix_rests(a, None, 0.0) is not None and np.array_equal(mix_rests(a, None, 0.0).amp, a.amp)
    assert mix_rests(None, None, 0.3) is None and mix_rests(a, b, 1.0).mix == 1.0


@pytest.fixture(scope="module")
def space():
    return SolidTextureModel(SPACE)


def test_a_code_with_a_rest_is_drawn_as_its_layers_say(space):
    """evaluate = clip(mu + h + sqrt(1 - t) k L d + sqrt(t) g); the decoder's part is what layers gives."""
    img = band_photo(256)
    code = photo_code(space, img, PhotoConfig(gaussian=False)).code
    waves = rest_waves(img, space.px_per_unit)
    r = GaussianRest(waves[0], waves[1] * np.sqrt(0.5), 0.5)
    pts = slice_points(48, space.px_per_unit, "x", (1.0, 2.0, 3.0))
    fixed, dec = space.layers(pts, code, seed=3)
    assert np.allclose(space.evaluate(pts, code, seed=3), np.clip(fixed + dec, 0, 1), atol=1e-6)
    import dataclasses
    mixed = dataclasses.replace(code, rest=r)
    want = np.clip(fixed + np.sqrt(0.5) * dec + rest_field(pts, r, 3), 0, 1)
    assert np.allclose(space.evaluate(pts, mixed, seed=3), want, atol=1e-5)
    with pytest.raises(Exception, match="without a Gaussian rest"):
        space.layers(pts, mixed)


@pytest.mark.long
def test_an_encoded_rock_photo_gets_a_rest_that_brings_it_closer(space):
    """The product's path on a held-out rock face whose middle scales the decoder does not draw: the check mixes
    the Gaussian rest in, and the texture's cuts come closer to the photo on planes the check did not see."""
    from omninoise.backend.solid.pipeline import texture_code
    from omninoise.export import read_rgb

    path = os.path.join(ROOT, "data", "photos", "val", "rock__rock_grey.jpg")
    photo = read_rgb(path)
    code, _ = texture_code(space, path)
    assert code.rest is not None and code.rest.mix in MIXES
    plain, _ = texture_code(space, path, config=PhotoConfig(gaussian=False))
    assert plain.rest is None

    def cuts(c):
        return [space.image(128, c, seed=s, axis=ax, offset=(2.5, -4.0, 1.5)) for s in (11, 12) for ax in "xyz"]
    assert band_distance(cuts(code), photo, seed=5) < 0.9 * band_distance(cuts(plain), photo, seed=5)
    # mixing with a name (no rest) weights the rest's power
    assert "soil" not in space.code_rests
    half, _ = texture_code(space, path, to="soil", mix=0.5)
    assert np.isclose(half.rest.mix, 0.5 * code.rest.mix)


def test_bake_keys_know_the_gaussian_rest(space):
    from omninoise.backend.sources import SolidSource

    img = band_photo(256)
    code = photo_code(space, img, PhotoConfig(gaussian=False)).code
    waves = rest_waves(img, space.px_per_unit)
    import dataclasses
    a = SolidSource(space, code=code)
    b = SolidSource(space, code=dataclasses.replace(code, rest=GaussianRest(waves[0], waves[1], 1.0)))
    assert a.input_sha256 != b.input_sha256
    assert a.to_dict()["gaussian_rest_sha256"] is None and b.to_dict()["gaussian_rest_sha256"]


def test_tiny_and_flat_photos_encode(space):
    """The check reads photos of a few pixels (its neighbourhoods shrink to fit) and a flat photo has no rest."""
    for n in (1, 3, 7):
        img = np.random.default_rng(n).random((n, n + 2, 3)).astype(np.float32)
        code = photo_code(space, img).code
        assert code.rest is None or code.rest.mix in MIXES
    assert photo_code(space, np.full((64, 64, 3), 0.4, np.float32)).rest is None
    assert band_distance([np.zeros((128, 128, 3))], np.zeros((2, 2, 3))) >= 0.0


def test_stored_rests_round_trip_to_six_digits_and_bad_ones_are_named():
    from omninoise.backend.solid.gaussian_rest import rest_from_json, rest_to_json

    img = band_photo(seed=5)
    r = GaussianRest(*rest_waves(img, PPU), 0.75)
    back = rest_from_json(json.loads(json.dumps(rest_to_json(r))))
    assert back.mix == 0.75 and back.freq.shape == r.freq.shape
    np.testing.assert_allclose(back.freq, r.freq, rtol=6e-10)
    np.testing.assert_allclose(back.amp, r.amp, rtol=1e-5, atol=1e-9)
    pts = slice_points(32, PPU, "x", (20.0, 40.0, 60.0))      # far from the origin, where phases grow
    assert np.abs(rest_field(pts, back, 3) - rest_field(pts, r, 3)).max() < 1e-4
    for bad, why in ((dict(freq=[[1, 2, 3]], amp=[[1, 0, 0, 0, 0, 0]]), "must hold freq"),
                     (dict(freq=[[1, 2, 3]], amp=[[1, 0, 0, 0, 0, 0]] * 2, mix=1.0), "1 frequencies, 2 amplitudes"),
                     (dict(freq=[[1, 2, 3]], amp=[[1, 0, 0, 0, 0, 0]], mix=1.5), "mix in \\(0, 1\\]")):
        with pytest.raises(ValueError, match=why):
            rest_from_json(bad)


def test_an_encoding_reports_its_stages_and_its_check_and_stops_when_cancelled(space):
    """photo_code's progress runs sorted to 1 in the stages' shares (stage_shares), with a step for each of the rest
    check's planes, rests and distances (about 2 s of an encoding's 2.5 s on 2 cores); a cancel asked during the
    check stops it there (Cancelled), before its other planes are drawn."""
    from omninoise.backend.grid import Cancelled
    from omninoise.backend.solid.pipeline import stage_shares

    img = band_photo(128)
    seen = []
    photo_code(space, img, progress=seen.append)
    enc, _, rest = stage_shares(PhotoConfig())
    assert seen == sorted(seen) and seen[-1] == 1.0 and 0.0 < enc < 0.2 and rest == 1.0 - enc
    assert sum(enc < f < 1.0 for f in seen) >= len(CHECK_PLANES) + 1 + len(MIXES), seen
    drawn = []
    real = space.layers

    def counted(*args, **kwargs):
        drawn.append(1)
        return real(*args, **kwargs)

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(space, "layers", counted)
        with pytest.raises(Cancelled):
            photo_code(space, img, cancel=lambda: len(drawn) >= 2)
    assert len(drawn) == 2 < len(CHECK_PLANES)


@pytest.mark.long
def test_a_refinement_and_a_second_photo_take_their_shares_of_the_progress(space):
    """A refinement's steps are heard in its share (stage_shares); with ``to``, each photo's stages over its half."""
    from omninoise.backend.solid.pipeline import stage_shares, texture_code

    img, seen = band_photo(128), []
    photo_code(space, img, PhotoConfig(refine=3), progress=seen.append)
    enc, ref, _ = stage_shares(PhotoConfig(refine=3))
    assert seen == sorted(seen) and seen[-1] == 1.0 and sum(enc < f <= enc + ref + 1e-9 for f in seen) >= 3
    seen.clear()
    texture_code(space, img, to=band_photo(128, 1), mix=0.5, progress=seen.append)
    assert seen == sorted(seen) and seen[-1] == 1.0
    assert sum(0.0 < f < 0.5 for f in seen) >= len(CHECK_PLANES) <= sum(0.5 < f < 1.0 for f in seen)
