"""The harmonic part of an encoded photo (backend/solid/harmonic.py): peaks found where a period is and nowhere
else, the photo's own waves given back in place, the 3D placement, mixing, and the texture an artist gets."""
import os
import re

import numpy as np
import pytest

from omninoise.backend.solid.harmonic import (COUNT, HarmonicConfig, Harmonics, harmonic_field, mix_harmonics,
                                              photo_harmonics, seed_shift)
from omninoise.backend.solid.pipeline import PhotoConfig, photo_code
from omninoise.backend.solid.model import SolidTextureModel, plane_points
from omninoise.backend.onnx_models import sealed

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SPACE = os.path.join(ROOT, "models", "solid", "space")
BRICK = os.path.join(ROOT, "data", "photos", "val", "brick__tex_trak_trak4_brick2a.jpg")
PPU = 128.0


def waves_photo(H=96, W=128):
    """A tileable photo made of three colour plane waves at whole cycles per photo, and its mean."""
    r, c = np.mgrid[0:H, 0:W].astype(np.float64)
    img = np.full((H, W, 3), 0.5)
    for (kx, ky, ph, col) in ((5, 0, 0.3, (0.2, 0.1, 0.05)), (3, 7, 1.1, (0.05, 0.1, 0.0)),
                              (-9, 4, 2.0, (0.0, 0.04, 0.1))):
        img += np.cos(2 * np.pi * (kx * c / W + ky * r / H) + ph)[..., None] * np.array(col)
    return img


def brick_photo(H=128, W=128, course=16, brick=32, seed=0):
    """Staggered courses of noisy bricks with light mortar joints: a period in both directions."""
    rng = np.random.default_rng(seed)
    r, c = np.mgrid[0:H, 0:W]
    row = r // course
    joint = (r % course < 2) | (((c + (row % 2) * brick // 2) % brick) < 2)
    img = np.where(joint[..., None], 0.85, 0.45 + 0.05 * rng.standard_normal((H, W, 1)))
    return np.clip(img * np.array([1.0, 0.6, 0.45]), 0, 1)


def photo_plane(h, H, W):
    """The field at the photo's pixel centres (H, W, 3)."""
    p = plane_points(max(H, W), PPU).reshape(max(H, W), max(H, W), 2)[:H, :W].reshape(-1, 2)
    return harmonic_field(p, h).reshape(H, W, 3)


def test_a_photo_of_waves_is_given_back_in_place():
    img = waves_photo()
    h = photo_harmonics(img, PPU)
    assert len(h) == 3 and h.share > 0.99
    # within 1 % of the waves' amplitude: the periodic component (Moisan) differs from a tiling image by the
    # faint smooth part its ordinary steps across the edges make
    assert np.abs(photo_plane(h, *img.shape[:2]) - (img - img.mean((0, 1)))).max() < 2e-3
    # frequencies in cycles per unit: 5 cycles over 128 px at 128 px per unit is 5 cycles per unit
    assert np.any(np.all(np.isclose(h.freq, [5.0, 0.0]), axis=1))


def test_aperiodic_photos_have_no_harmonic_part():
    rng = np.random.default_rng(3)
    white = rng.random((128, 128, 3))
    # 1/f noise (rock-like) and one dark line across the photo (a ridge in the spectrum, not a peak)
    F = np.fft.fft2(rng.standard_normal((128, 128)))
    f = np.hypot(*np.meshgrid(np.fft.fftfreq(128), np.fft.fftfreq(128)))
    pink = np.real(np.fft.ifft2(F / np.maximum(f, 1 / 128)))
    pink = np.repeat(((pink - pink.min()) / np.ptp(pink))[..., None], 3, axis=2)
    line = pink.copy()
    line[60:62] = 0.0
    for img in (white, pink):
        assert photo_harmonics(img, PPU).share < 0.03
    # the peak test sees a ridge, not a peak; a line straight across the whole frame is read by the lines reading
    # (backend/solid/periods.py: a library tile's joint, a plank seam), and only the line
    assert photo_harmonics(line, PPU, HarmonicConfig(lines=False)).share < 0.03
    h = photo_harmonics(line, PPU)
    assert len(h) > 0 and np.all(h.freq[:, 0] == 0.0)
    back = photo_plane(h, 128, 128).mean(2)
    assert back[60:62].mean() < -0.2 and np.abs(np.delete(back, range(56, 66), axis=0)).max() < 0.1


def test_courses_and_head_joints_are_found():
    img = brick_photo()
    h = photo_harmonics(img, PPU)
    assert h.share > 0.3 and 0.0 < h.keep < 1.0
    back = photo_plane(h, 128, 128).mean(2)
    lum = img.mean(2) - img.mean()
    assert np.corrcoef(back.ravel(), lum.ravel())[0, 1] > 0.7
    # a course frequency (8 cycles over 128 px vertically) and a head-joint one (horizontal, 4 per 128 px)
    assert np.any(np.all(np.isclose(np.abs(h.freq), [0.0, 8.0]), axis=1))
    assert np.any(np.isclose(np.abs(h.freq[:, 0]), 4.0))
    # every harmonic of the bond that passes the test is kept (64 here: more than the 32 the cap once was), the
    # strongest first, and a lower cap keeps the strongest of them
    h = photo_harmonics(img, PPU, HarmonicConfig(lobe=0))
    assert len(h) == 64 and COUNT >= 64
    power = (np.abs(h.amp) ** 2).sum(1)         # the colour power the peaks are ranked by
    assert np.all(np.diff(power) <= 1e-12)
    h8 = photo_harmonics(img, PPU, HarmonicConfig(count=8, lobe=0))
    assert len(h8) == 8 and np.array_equal(h8.freq, h.freq[:8]) and h8.share < h.share


def test_3d_placement_walls_show_the_photo_floors_its_profile():
    """q = (x + y, z): planes normal to x and to y show the photo (z up), translated; planes normal to z show a
    function of x + y only (the photo in profile)."""
    h = photo_harmonics(waves_photo(), PPU)
    p = plane_points(64, PPU)
    u, v = p[:, 0], p[:, 1]
    flat = harmonic_field(p, h)
    c = 0.37
    front = harmonic_field(np.stack([u - c, np.full_like(u, c), v], 1), h)      # y = c, shifted by -c in x
    side = harmonic_field(np.stack([np.full_like(u, c), u - c, v], 1), h)       # x = c
    assert np.abs(front - flat).max() < 1e-5 and np.abs(side - flat).max() < 1e-5
    floor = harmonic_field(np.stack([u, v, np.full_like(u, c)], 1), h)          # z = c: a function of u + v
    along = harmonic_field(np.stack([u + 0.25, v - 0.25, np.full_like(u, c)], 1), h)
    assert np.abs(floor - along).max() < 1e-5 and floor.std() > 0.01


def test_2d_images_of_3d_models_are_the_front_view():
    """model.image's default plane is y = 0 (x right, z up): there an encoded photo's harmonic part stands as in
    the photo."""
    m = SolidTextureModel(SPACE)
    photo = waves_photo(128, 128)
    code = m.translate(m.encode(photo), m.harmonics(photo))
    zero = code.__class__(code.e, code.T, code.mu, np.zeros((3, 3), np.float32), code.gains, code.harmonics)
    img = m.image(64, zero, seed=0)                                             # the harmonic part alone, + mu
    assert np.abs(img - code.mu - photo_plane(code.harmonics, 64, 64)).max() < 1e-4
    assert np.abs(m.image(64, zero, seed=0, axis="y") - img).max() == 0.0


def test_another_seed_moves_the_harmonic_part():
    """Seed 0 keeps the photo's placement; another seed translates the whole part (every wave alike, so the
    pattern holds together), differently per seed and the same every time."""
    h = photo_harmonics(brick_photo(), PPU)
    p = plane_points(32, PPU)
    assert np.all(seed_shift(0) == 0) and np.all(seed_shift(5) == seed_shift(5))
    assert np.abs(seed_shift(5) - seed_shift(6)).max() > 1.0
    for s in (1, 7):
        assert np.abs(harmonic_field(p, h, s) - harmonic_field(p + seed_shift(s), h)).max() < 1e-4
        assert np.abs(harmonic_field(p, h, s) - harmonic_field(p, h)).max() > 0.05


def test_mixing_weights_powers():
    a = photo_harmonics(waves_photo(), PPU)
    b = photo_harmonics(brick_photo(), PPU)
    assert mix_harmonics(None, None, 0.3) is None
    m = mix_harmonics(a, b, 0.25)
    assert len(m) == len(a) + len(b)
    assert len(mix_harmonics(a, b, 0.0)) == len(a) and mix_harmonics(a, None, 1.0) is None   # weight 0: left out
    assert np.isclose(m.share, 0.75 * a.share + 0.25 * b.share)
    p = plane_points(32, PPU)
    assert np.allclose(harmonic_field(p, mix_harmonics(a, None, 0.0)), harmonic_field(p, a), atol=1e-6)
    assert np.allclose(harmonic_field(p, mix_harmonics(a, b, 1.0)), harmonic_field(p, b), atol=1e-6)
    assert Harmonics(np.zeros((0, 2)), np.zeros((0, 3), complex), 0.0).keep == 1.0


@pytest.fixture(scope="module")
def space():
    return SolidTextureModel(SPACE)


def test_an_encoded_brick_photo_gets_its_courses_in_place(space):
    from omninoise.export import read_rgb

    photo = read_rgb(BRICK)
    z, h = space.encode(photo), space.harmonics(photo)
    assert h is not None and h.share > 0.3
    with_h, without = space.translate(z, h), space.translate(z)
    assert with_h.harmonics is h and without.harmonics is None
    S = 128
    crop = photo[:S, :S].mean(2)
    a = space.image(S, with_h, seed=0).mean(2)
    b = space.image(S, without, seed=0).mean(2)
    # the photo's own phases: the texture at the origin lines up with the photo's top-left corner
    assert np.corrcoef(a.ravel(), crop.ravel())[0, 1] > 0.5
    assert abs(np.corrcoef(b.ravel(), crop.ravel())[0, 1]) < 0.2
    # the decoder's part is scaled by sqrt(1 - share): the colour spread stays the photo's, the mean too
    assert abs(a.std() - crop.std()) < 0.35 * crop.std()
    assert np.abs(space.image(S, with_h, seed=1).mean((0, 1)) - photo.mean((0, 1))).max() < 0.03


def test_an_aperiodic_photo_is_left_as_the_decoder_draws_it(space):
    from omninoise.export import read_rgb

    photo = read_rgb(os.path.join(ROOT, "data", "photos", "val", "rock__cliff_rocky.jpg"))
    h = space.harmonics(photo)
    assert h.share < 0.02


@pytest.mark.long
def test_a_large_photo_is_measured_small_at_the_same_scale(space):
    """A photo over HARMONIC_SIDE px is resized before its FFT; its waves keep their frequency in texture units."""
    from omninoise.backend.solid.harmonic import HARMONIC_SIDE

    img = np.tile(brick_photo(), (9, 9, 1))[: HARMONIC_SIDE + 128, : HARMONIC_SIDE + 128]   # 1152 px, period 16 / 32 px
    h = space.harmonics(img)
    assert h.share > 0.2
    # the course frequency, 1 / 16 px at 128 px per unit: 8 cycles per unit
    assert np.any(np.all(np.isclose(np.abs(h.freq), [0.0, 8.0], atol=0.15), axis=1))


def test_a_large_photo_is_encoded_from_a_bounded_grid_of_crops_in_batches(space, monkeypatch):
    """A 4096 px photo once went to the encoder as 3969 crops in one batch (16 GB, 29 s); now at most
    ENCODE_SIDE^2 crops spread over it, ENCODE_BATCH at a time, and a small photo keeps every crop."""
    import omninoise.backend.solid.model as model_mod

    enc = space._session("encoder.onnx")
    seen = []

    class Counting:
        def run(self, names, feeds):
            seen.append(feeds["exemplar"].shape[0])
            return enc.run(names, feeds)

    monkeypatch.setattr(space, "_session", lambda name, real=space._session: Counting() if name == "encoder.onnx"
                        else real(name))
    big = np.tile(brick_photo(), (12, 8, 1))       # 1536 x 1024 px: 23 x 15 crops at 64 px steps
    z = space.encode(big)
    assert sum(seen) == model_mod.ENCODE_SIDE ** 2 and max(seen) <= model_mod.ENCODE_BATCH
    assert np.isfinite(z).all()
    # a 256 px photo: all 9 crops, and the batching does not change the code
    seen.clear()
    small = brick_photo(256, 256)
    a = space.encode(small)
    assert seen == [9]
    monkeypatch.setattr(model_mod, "ENCODE_BATCH", 2)
    assert np.allclose(space.encode(small), a, atol=1e-5)
    # the bounded grid still reads the photo: the big brick photo's code is near the small one's
    # (same bricks), far nearer than a flat grey photo's
    flat = space.encode(np.full((256, 256, 3), 0.5))
    assert np.linalg.norm(z[:space.z_dim] - a[:space.z_dim]) < 0.5 * np.linalg.norm(flat[:space.z_dim] - a[:space.z_dim])


def test_stored_harmonics_round_trip_and_bad_ones_are_named():
    from omninoise.backend.solid.harmonic import from_json, to_json

    h = photo_harmonics(brick_photo(), PPU)
    back = from_json(json_round_trip(to_json(h)))
    assert np.array_equal(back.freq, h.freq) and np.array_equal(back.amp, h.amp) and back.share == h.share
    for bad, why in (({"freq": [[1, 2]], "amp": [[0] * 6] * 2, "share": 0.1}, "1 frequencies, 2 amplitudes"),
                     ({"freq": [[1, 2]], "amp": [[0] * 6], "share": 1.5}, "share in [0, 1)"),
                     ({"freq": [[1, 2]], "share": 0.1}, "must hold freq")):
        with pytest.raises(ValueError, match=re.escape(why)):
            from_json(bad)


def json_round_trip(d):
    import json

    return json.loads(json.dumps(d))


def test_a_single_photo_model_stores_its_harmonic_part(tmp_path):
    """brick_3d ships with the harmonic part of its photo's training region (python -m omninoise.training.solid.harmonics);
    its default code carries it, and the texture differs from the same weights without it; a model that cannot
    store one is refused by name."""
    import json
    import shutil
    from dataclasses import replace

    from omninoise.backend.onnx_models import ModelError

    m = SolidTextureModel(os.path.join(ROOT, "models", "solid", "brick_3d"))
    code = m.default_code()
    assert code.harmonics is not None and len(code.harmonics) > 0
    with_h, without = m.image(64, code, 0), m.image(64, replace(code, harmonics=None), 0)
    assert np.abs(with_h - without).mean() > 0.02
    # the courses: the spectrum of the front view's row means follows the photo's (its training region)
    from omninoise.export import read_rgb

    photo = read_rgb(os.path.join(ROOT, m.config["exemplars"][0]))[:192, :192]

    def rows(a):
        return np.abs(np.fft.rfft(a.mean((1, 2)) - a.mean()))[2:]

    ref = rows(photo)
    r_with = np.corrcoef(rows(m.image(192, code, 0)), ref)[0, 1]
    r_without = np.corrcoef(rows(m.image(192, replace(code, harmonics=None), 0)), ref)[0, 1]
    assert r_with > 0.5 and r_without < 0.3
    shutil.copytree(os.path.join(ROOT, "tests", "data", "tiny_solid", "single3"), tmp_path / "tiny")
    doc = json.loads((tmp_path / "tiny" / "solid.json").read_text())
    with open(os.path.join(ROOT, "models", "solid", "brick_3d", "solid.json"), encoding="utf-8") as f:
        doc["harmonics"] = json.load(f)["harmonics"]
    (tmp_path / "tiny" / "solid.json").write_text(json.dumps(sealed(doc)))
    with pytest.raises(ModelError, match="only single photo models"):
        SolidTextureModel(str(tmp_path / "tiny"))


def jpeg(img: np.ndarray, quality: int) -> np.ndarray:
    import io

    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray((np.clip(img, 0, 1) * 255 + 0.5).astype(np.uint8)).save(buf, format="JPEG", quality=quality)
    return np.asarray(Image.open(io.BytesIO(buf.getvalue())).convert("RGB"), np.float64) / 255.0


def on_block_grid(h, H, W):
    k = np.round(np.abs(h.freq) * np.array([W, H]) / PPU).astype(int)
    return [tuple(x) for x in k if x[0] % (W // 8) == 0 and x[1] % (H // 8) == 0]


def test_jpeg_blocks_draw_no_grid_but_a_period_keeps_its_harmonics(monkeypatch):
    """A held-out photo whose only isolated peaks are its JPEG blocks' (multiples of 1/8 cycle per pixel) gets no
    harmonic part; compressed bricks keep the harmonics of their courses and joints on that lattice."""
    import omninoise.backend.solid.harmonic as hm
    from omninoise.export import read_rgb

    blocky = read_rgb(os.path.join(ROOT, "data", "photos", "val", "sand__desert_city_tile.jpg"))
    with monkeypatch.context() as m:
        m.setattr(hm, "_without_jpeg_grid", lambda idx, *a: idx)
        assert len(on_block_grid(hm.photo_harmonics(blocky, PPU), 256, 256)) >= 2   # the compression's peaks ...
    assert len(photo_harmonics(blocky, PPU)) == 0                                      # ... are dropped
    bricks = jpeg(brick_photo(256, 256), 30)                                           # courses 16 px, bricks 32
    kept = on_block_grid(photo_harmonics(bricks, PPU), 256, 256)
    assert (0, 32) in kept and (32, 0) in kept                                         # their 2nd harmonics


@pytest.mark.long
def test_bake_keys_know_the_harmonic_part(space):
    """A bake is up to date only for the same harmonic part: an encoded photo with and without it, and a single
    model that stores one, give keys that say so."""
    from omninoise.backend.solid.request import SolidRequest
    from omninoise.backend.sources import SolidSource

    on = SolidSource(space, SolidRequest(exemplar=BRICK)).to_dict()
    off = SolidSource(space, SolidRequest(exemplar=BRICK, periodic=False)).to_dict()
    assert on["harmonics_sha256"] is not None and off["harmonics_sha256"] is None
    assert on != off
    brick3d = SolidSource(os.path.join(ROOT, "models", "solid", "brick_3d")).to_dict()
    assert brick3d["harmonics_sha256"] is not None


def test_the_price_of_the_jpeg_rule_stripes_exactly_8_px_apart():
    """The documented limit: stripes whose period divides 8 px (on the compression's lattice) get no harmonic
    part; 16 px, or 30 stripes across 256 px (8.53 px), keep theirs."""
    c = np.arange(256)[None, :].repeat(256, 0).astype(np.float64)

    def stripes(cycles):
        img = 0.5 + 0.3 * np.cos(2 * np.pi * cycles * c / 256)
        return np.repeat(img[..., None], 3, axis=2)

    assert len(photo_harmonics(stripes(32), PPU, HarmonicConfig(lines=False))) == 0          # 8 px
    assert photo_harmonics(stripes(16), PPU, HarmonicConfig(lines=False)).share > 0.9        # 16 px
    assert photo_harmonics(stripes(30), PPU, HarmonicConfig(lines=False)).share > 0.9        # 8.53 px
    # stripes straight across the whole frame come back as lines (periods.frame_lines), 8 px apart too
    assert photo_harmonics(stripes(32), PPU).share > 0.9


@pytest.mark.long
def test_refinement_renders_with_the_harmonic_part(space):
    """--refine searches the code as the texture will be drawn: with the photo's harmonic part, never worse than
    the encoder's code, and the part stays as measured."""
    from omninoise.backend.solid.pipeline import texture_code
    from omninoise.backend.solid.refine import refine_code
    from omninoise.export import read_rgb

    photo = read_rgb(BRICK)
    z, h = space.encode(photo), space.harmonics(photo)
    _, with_h = refine_code(space, z, photo, steps=3, harmonics=h)
    _, without = refine_code(space, z, photo, steps=3)
    assert with_h[0] != without[0] and with_h[-1] <= with_h[0]
    code, _ = texture_code(space, BRICK, config=PhotoConfig(refine=2))
    assert code.harmonics is not None and np.array_equal(code.harmonics.freq, h.freq)


def test_the_rest_of_a_photo_keeps_no_period():
    """remove_harmonics: the photo less its part, at its pixel centres; what is left keeps under 5 % of the power
    of every peak the part took, its mean is the photo's, and a photo without a part comes back as it was (clipped
    to [0, 1])."""
    from omninoise.backend.solid.harmonic import remove_harmonics

    img = brick_photo()
    h = photo_harmonics(img, PPU)
    rest = remove_harmonics(img, h, PPU)
    assert rest.shape == img.shape and rest.dtype == np.float32 and rest.min() >= 0.0 and rest.max() <= 1.0
    assert h.share > 0.5

    def power(a):
        return np.abs(np.fft.fft2(a.mean(2) - a.mean())) ** 2

    H, W, _ = img.shape
    kx = np.round(h.freq[:, 0] * W / PPU).astype(int) % W
    ky = np.round(-h.freq[:, 1] * H / PPU).astype(int) % H
    assert np.all(power(rest)[ky, kx] < 0.05 * power(img)[ky, kx])
    assert np.abs(rest.mean((0, 1)) - img.mean((0, 1))).max() < 0.01
    # the part is removed where it was measured: pixel centres in the photo's frame, not a shifted grid
    assert rest.var((0, 1)).sum() < 0.5 * img.var((0, 1)).sum()
    none = Harmonics(np.zeros((0, 2)), np.zeros((0, 3), complex), 0.0)
    np.testing.assert_array_equal(remove_harmonics(img * 1.5, none, PPU), np.clip(img * 1.5, 0, 1).astype(np.float32))


@pytest.mark.long
def test_a_model_trained_on_rests_encodes_rests_and_draws_them_at_their_own_spread(tmp_path):
    """A space model whose solid.json says ``harmonic_rest`` encodes the photo less its part when the part rides
    along (as training saw its photos) and adds its decoder's part unscaled (k = 1: the code's L is the rest's
    already); without the part it encodes the photo; a single model with the flag is refused by name."""
    import json
    import shutil
    from dataclasses import replace

    from omninoise.backend.onnx_models import ModelError
    from omninoise.backend.solid.harmonic import remove_harmonics
    from omninoise.export import read_rgb

    shutil.copytree(SPACE, tmp_path / "rest")
    doc = json.loads((tmp_path / "rest" / "solid.json").read_text())
    (tmp_path / "rest" / "solid.json").write_text(json.dumps(sealed(dict(doc, harmonic_rest=True))))
    plain, rest = SolidTextureModel(SPACE), SolidTextureModel(str(tmp_path / "rest"))
    photo = read_rgb(BRICK)
    h = rest.harmonics(photo)
    assert h.share > 0.3
    np.testing.assert_allclose(rest.encode(photo, h), plain.encode(remove_harmonics(photo, h, PPU)), atol=1e-6)
    np.testing.assert_array_equal(rest.encode(photo), plain.encode(photo))
    np.testing.assert_array_equal(plain.encode(photo, h), plain.encode(photo))     # other models ignore the part
    code = rest.translate(rest.encode(photo, h), h)
    # photo_code, the pipeline's stages, is this code; without the part it is the whole photo's
    made, whole = photo_code(rest, photo).code, photo_code(rest, photo, PhotoConfig(periodic=False)).code
    np.testing.assert_array_equal(made.e, code.e)
    assert np.array_equal(made.harmonics.freq, h.freq) and whole.harmonics is None
    np.testing.assert_array_equal(whole.e, rest.translate(plain.encode(photo)).e)
    pts = np.random.default_rng(1).uniform(-2, 2, (4000, 3))
    d = plain.evaluate(pts, replace(code, harmonics=None), seed=3) - code.mu       # L d where nothing clips
    field = harmonic_field(pts, h, 3)
    for model, k in ((rest, 1.0), (plain, h.keep)):
        got = model.evaluate(pts, code, seed=3) - code.mu - field
        ok = [(v > 0.01) & (v < 0.99) for v in (code.mu + d, code.mu + k * d + field)]    # where nothing clipped
        inside = np.all(ok[0] & ok[1], 1)
        assert inside.mean() > 0.8
        np.testing.assert_allclose(got[inside], k * d[inside], atol=2e-4)
    single = json.loads(open(os.path.join(ROOT, "tests", "data", "tiny_solid", "single3", "solid.json")).read())
    shutil.copytree(os.path.join(ROOT, "tests", "data", "tiny_solid", "single3"), tmp_path / "single")
    (tmp_path / "single" / "solid.json").write_text(json.dumps(sealed(dict(single, harmonic_rest=True))))
    with pytest.raises(ModelError, match="trained on harmonic rests"):
        SolidTextureModel(str(tmp_path / "single"))


def test_the_field_in_blocks_is_the_field_at_once(monkeypatch):
    """harmonic_field works through the points in blocks of FIELD_BLOCK / K (flat memory for 256 waves); any block
    size gives the same numbers, to the bit."""
    import omninoise.backend.solid.harmonic as hm

    h = photo_harmonics(brick_photo(), PPU)
    pts = np.random.default_rng(5).uniform(-40, 40, (1000, 3))
    whole = harmonic_field(pts, h, seed=2)
    monkeypatch.setattr(hm, "FIELD_BLOCK", 7 * len(h))          # 7 points a block, the last one short
    np.testing.assert_array_equal(hm.harmonic_field(pts, h, seed=2), whole)
    assert whole.dtype == np.float32 and whole.shape == (1000, 3) and np.abs(whole).max() > 0.05


def test_a_period_between_bins_brings_its_main_lobe():
    """Rows 128 / 5.5 px apart fall between two bins of a 128 px photo: the peak's bin alone holds under 40 % of
    the photo's variance and its removal leaves most of the rows; with its main lobe (LOBE) the part holds over
    half, and its removal leaves under 55 % of the rows' spread."""
    from omninoise.backend.solid.harmonic import LOBE, remove_harmonics

    rng = np.random.default_rng(2)
    r = np.arange(128)[:, None, None]
    img = np.clip(0.5 + 0.2 * np.cos(2 * np.pi * 5.5 * r / 128) * np.array([1.0, 0.8, 0.6])
                  + 0.02 * rng.standard_normal((128, 128, 3)), 0, 1)
    alone = photo_harmonics(img, PPU, HarmonicConfig(lobe=0, lines=False))
    lobe = photo_harmonics(img, PPU, HarmonicConfig(lines=False))
    assert LOBE == 1 and 0 < len(alone) < len(lobe) <= 9 * len(alone)
    assert alone.share < 0.4 and lobe.share > 0.5
    rows = img.mean((1, 2)).std()
    assert remove_harmonics(img, alone, PPU).mean((1, 2)).std() > 0.7 * rows
    assert remove_harmonics(img, lobe, PPU).mean((1, 2)).std() < 0.55 * rows
    # whole periods keep their bins alone, and the weak bins around a bond's strong peaks stay out (below
    # 1 / LOBE_DEPTH of the peak: noise, and near the axes the periodic component's correction, which removing
    # would add to the photo, not take away)
    assert len(photo_harmonics(waves_photo(), PPU)) == 3
    assert len(photo_harmonics(brick_photo(), PPU)) == len(photo_harmonics(brick_photo(), PPU,
                                                                            HarmonicConfig(lobe=0)))


def test_a_motif_of_colours_at_one_luminance_is_found_in_the_colour_spectrum():
    """Red diamonds on olive of the same luminance (the held-out carpet's motif): the luminance spectrum holds
    almost none of it, the summed power of the three channels all of it; a wrong spectrum's name is refused."""
    rng = np.random.default_rng(5)
    r, c = np.mgrid[0:128, 0:128]
    motif = ((np.abs((c % 32) - 16) + np.abs((r % 16) - 8) * 2) < 10).astype(float)      # diamonds, 32 x 16 px
    red, olive = np.array([0.75, 0.10, 0.10]), np.array([0.40, 0.35, 0.20])               # means 0.317, 0.317
    img = np.where(motif[..., None] > 0, red, olive) + 0.004 * rng.standard_normal((128, 128, 3))
    lum = photo_harmonics(img, PPU, HarmonicConfig(detect="luminance"))
    col = photo_harmonics(img, PPU, HarmonicConfig(detect="colour"))
    assert lum.share < 0.1 and col.share > 0.8
    assert np.any(np.all(np.isclose(np.abs(col.freq), [4.0, 0.0]), axis=1))        # 4 motifs per 128 px
    back = photo_plane(col, 128, 128)
    assert np.corrcoef(back[..., 1].ravel(), img[..., 1].ravel())[0, 1] > 0.9
    with pytest.raises(ValueError, match="detect must be one of"):
        HarmonicConfig(detect="chroma")


@pytest.mark.long
def test_a_named_code_draws_what_encoding_its_photo_draws(space, tmp_path):
    """--exemplar metal (a name of the texture-space model) is the code of the photo that names it, with that
    photo's harmonic part: the plates' seams, as encoding the photo gives them; --no-periodic and mixing carry the
    part as for a photo; a part stored for a name the model lacks, or on a single model, is refused by name."""
    import json
    import shutil

    from omninoise.backend.onnx_models import ModelError
    from omninoise.backend.solid.pipeline import texture_code
    from omninoise.export import read_rgb

    photo = read_rgb(os.path.join(ROOT, "data", "photos", "train", "metal__metal_plates.jpg"))
    # with its Gaussian rest (backend/solid/gaussian_rest.py), stored to ten and six digits
    named, encoded = space.code("metal"), photo_code(space, photo).code
    assert named.harmonics is not None and named.harmonics.share > 0.4 and named.rest.mix == encoded.rest.mix
    np.testing.assert_allclose(space.image(64, named, seed=2), space.image(64, encoded, seed=2), atol=1e-4)
    assert space.code("metal", gaussian=False).rest is None
    code, _ = texture_code(space, "metal", config=PhotoConfig(gaussian=False))
    assert code.rest is None and texture_code(space, "metal")[0].rest.mix == 1.0
    assert space.code("grass").harmonics is None                     # its photo has no period
    code, _ = texture_code(space, "metal", config=PhotoConfig(periodic=False))
    assert code.harmonics is None
    code, _ = texture_code(space, "metal", to="grass", mix=0.25)
    assert np.isclose(code.harmonics.share, 0.75 * named.harmonics.share)
    folder = tmp_path / "space"
    shutil.copytree(SPACE, folder)
    doc = json.loads((folder / "solid.json").read_text())
    doc["code_harmonics"]["cork"] = doc["code_harmonics"]["metal"]
    (folder / "solid.json").write_text(json.dumps(sealed(doc)))
    with pytest.raises(ModelError, match="stores a harmonic part for code 'cork'"):
        SolidTextureModel(str(folder))
    del doc["code_harmonics"]["cork"]
    doc["code_rests"]["cork"] = doc["code_rests"]["metal"]
    (folder / "solid.json").write_text(json.dumps(sealed(doc)))
    with pytest.raises(ModelError, match="stores a Gaussian rest for code 'cork'"):
        SolidTextureModel(str(folder))
    del doc["code_rests"]["cork"]
    doc["code_rests"]["metal"]["mix"] = 0.0
    (folder / "solid.json").write_text(json.dumps(sealed(doc)))
    with pytest.raises(ModelError, match="code 'metal': a Gaussian rest: 512 frequencies, 512 amplitudes, mix 0.0"):
        SolidTextureModel(str(folder))
