"""backend/solid/synthesis.py (Kopf et al. 2007 solid synthesis by optimisation; Kwatra et al. 2005 in 2D) and
python -m bench solid-methods: the tile copies a photo's structure at its frequency and orientation, keeps its colours, wraps around, and reports
progress, cancels and bad settings in one line."""
import json

import numpy as np
import pytest

from omninoise.backend.errors import SettingError
from omninoise.backend.grid import Cancelled
from omninoise.backend.solid.synthesis import SynthesisSettings, TileField, synthesise


def _stripes(period: float = 8.0, size: int = 64, along: str = "cols", saw: bool = False) -> np.ndarray:
    """A colour photo of stripes: brightness varies along columns (vertical stripes) or rows (horizontal ones);
    ``saw``: a sawtooth that ramps up from the photo's top row downwards, then drops.  With a little noise, as
    a photo has."""
    i = np.arange(size, dtype=np.float64)
    t = (i % period) / period if saw else 0.5 + 0.5 * np.sin(2 * np.pi * i / period)
    v = np.broadcast_to(t[None, :] if along == "cols" else t[:, None], (size, size))
    v = v + np.random.default_rng(3).normal(0.0, 0.03, (size, size))
    return np.stack([0.2 + 0.6 * v, 0.3 + 0.4 * v, 0.5 - 0.3 * v], -1).astype(np.float32)


def _peak(profile: np.ndarray) -> int:
    """The strongest non-zero frequency (cycles per length) of a 1D profile."""
    p = np.abs(np.fft.rfft(profile - profile.mean()))
    return int(np.argmax(p[1:]) + 1)


SMALL = dict(size=32, levels=2, iterations=(2, 2), sharpness=(10.0, 10.0), candidates=3000)


def test_2d_tile_copies_the_stripes_period_direction_and_colours():
    photo = _stripes(8.0)
    tile = synthesise(photo, SynthesisSettings(dim=2, **SMALL))
    assert tile.shape == (32, 32, 3) and tile.dtype == np.float32
    g = tile[..., 0]
    assert _peak(g.mean(0)) == 32 // 8                       # across columns: the photo's period, 4 per tile
    assert g.mean(1).std() < 0.25 * g.mean(0).std()          # and no stripes across rows
    # histogram matching: the tile's colours are the photo's (means within 0.02, same range)
    assert np.abs(tile.reshape(-1, 3).mean(0) - photo.reshape(-1, 3).mean(0)).max() < 0.02
    assert tile.min() >= photo.min() - 1e-4 and tile.max() <= photo.max() + 1e-4


@pytest.mark.long
@pytest.mark.parametrize("seed", range(3))
def test_the_products_2d_settings_keep_stripes_whole(seed):
    """image_settings (what method "synthesis" draws): square and sawtooth stripes of a 128² photo stay vertical
    stripes in a 64 px tile, on every seed.  With sharp weights on every level (k = 10) the coarse pieces settled on
    different phases and most seeds drew offset pieces with horizontal seams."""
    from omninoise.backend.solid.synthesis import image_settings

    x = np.arange(128)
    for profile in ((x % 16 < 8) * 0.6 + 0.2, (x % 20) / 20.0 * 0.8 + 0.1):
        photo = np.broadcast_to(profile[None, :, None] * np.array([1.0, 0.8, 0.5]), (128, 128, 3))
        g = synthesise(photo.astype(np.float32), image_settings(64, photo.shape, seed)).mean(2)
        assert np.abs(np.diff(g, axis=1)).mean() > 10.0 * np.abs(np.diff(g, axis=0)).mean()


@pytest.mark.parametrize("tile, shape, levels", [
    (256, (256, 256, 3), 4),     # the default tile from a held-out photo: its neighbourhoods span 64 px
    (256, (128, 128, 3), 3),     # a small photo: three levels, as before
    (512, (512, 700, 3), 5),     # the photo's short side counts
    (1024, (4096, 4096, 3), 6),
    (1024, (256, 256, 3), 4),    # the photo limits it
    (128, (4096, 4096, 3), 3),   # the tile limits it
    (260, (256, 256, 3), 3),     # 260 is a multiple of 4, not of 8
    (32, (256, 256, 3), 3),      # never fewer than three
    (256, (7,), 3),              # not an image: synthesise says so
])
def test_the_product_draws_as_many_levels_as_tile_and_photo_allow(tile, shape, levels):
    from omninoise.backend.solid.synthesis import COARSE_SHARPNESS, FINE_SHARPNESS, image_levels, image_settings

    assert image_levels(tile, shape) == levels
    s = image_settings(tile, shape, seed=5)
    assert (s.levels, s.size, s.dim, s.seed) == (levels, tile, 2, 5)
    assert s.iterations == (16,) * (levels - 2) + (6, 2)
    assert s.sharpness == (COARSE_SHARPNESS,) * (levels - 1) + (FINE_SHARPNESS,)


def _bricks(size: int = 256, course: int = 32, width: int = 64, mortar: int = 4) -> np.ndarray:
    """A photo of a brick wall: courses ``course`` px apart, each shifted by half a brick, bricks of random tones
    between light mortar, with a little noise."""
    rng = np.random.default_rng(0)
    y, x = np.mgrid[:size, :size]
    row = y // course
    xs = x + (row % 2) * (width // 2)
    brick = row * 7 + xs // width
    tone = rng.uniform(0.35, 0.75, brick.max() + 1)[brick]
    v = np.where(((y % course) < mortar) | ((xs % width) < mortar), 0.9, tone) + rng.normal(0, 0.04, (size, size))
    return np.stack([v, 0.55 * v + 0.1, 0.4 * v + 0.05], -1).clip(0, 1).astype(np.float32)


@pytest.mark.long
def test_the_products_levels_keep_brick_courses_whole():
    """A 256² brick wall, a 256 px tile: the courses run across the tile, so its row means vary as much as the
    photo's (mortar rows against brick rows).  Drawn with three levels (the product before) the bricks came out as
    offset pieces and the row means' spread was 0.56 to 0.59 of the photo's on four seeds; with four, 0.65 to 0.86."""
    from omninoise.backend.solid.synthesis import image_settings

    photo = _bricks()
    ref = photo[..., 0].mean(1).std()
    spread = [synthesise(photo, image_settings(256, photo.shape, seed))[..., 0].mean(1).std() / ref
              for seed in (0, 3)]
    assert np.mean(spread) > 0.63


def test_upright_solid_lays_the_photos_rows_along_z_the_right_way_up():
    """Horizontal sawtooth stripes on the walls (planes "walls"): layers normal to z, ramping as the photo does
    read bottom to top (its top row at the largest z).  The coarse level needs many iterations before the slices
    agree on one phase, and with the default sharp weights on every level the layers came out at half the photo's
    period (two short ramps for one long); Kopf's plain weights (k = 1) on the coarse level give the photo's."""
    photo = _stripes(8.0, along="rows", saw=True)
    tile = synthesise(photo, SynthesisSettings(dim=3, planes="walls", size=32, levels=2, iterations=(12, 3),
                                               sharpness=(1.0, 10.0), candidates=3000))     # (z, y, x, 3)
    assert tile.shape == (32, 32, 32, 3)
    g = tile[..., 0]
    layers = g.mean(axis=(1, 2))
    assert _peak(layers) == 32 // 8
    assert layers.std() > 4 * g.mean(axis=(0, 1)).std() and layers.std() > 4 * g.mean(axis=(0, 2)).std()
    # the photo ramps up from its top row down, so upwards (bottom to top) it falls: most steps up z are down
    assert np.median(np.diff(photo[::-1, 0, 0])) < 0 and np.median(np.diff(layers)) < 0


def _ring_share(img: np.ndarray, lo: float, hi: float) -> float:
    """The share of an image's power at radial frequencies in [lo, hi) cycles per side."""
    P = np.abs(np.fft.fft2(img - img.mean())) ** 2
    f = np.fft.fftfreq(img.shape[0]) * img.shape[0]
    r = np.hypot(f[:, None], f[None, :])
    return float(P[(r >= lo) & (r < hi)].sum() / P.sum())


def test_isotropic_solid_keeps_the_photos_scale_on_every_slice_family():
    """Dots 8 px apart: the x, y and z slices of the solid put most of their power near the photo's frequency
    (4 cycles per 32 voxels; white noise would put about a fifth there, the photo all of it)."""
    i = np.arange(64.0)
    v = 0.5 + 0.25 * np.cos(2 * np.pi * i / 8)[:, None] + 0.25 * np.cos(2 * np.pi * i / 8)[None, :]
    v = v + np.random.default_rng(3).normal(0.0, 0.03, v.shape)
    photo = np.stack([v, 0.5 * v + 0.2, 0.8 - 0.5 * v], -1).astype(np.float32)
    g = synthesise(photo, SynthesisSettings(dim=3, size=32, levels=2, iterations=(12, 3), sharpness=(1.0, 10.0),
                                            candidates=3000))[..., 0]
    assert _ring_share(v[:32, :32], 3.5, 6.5) > 0.95
    for img in (g[:, :, 5], g[:, 7, :], g[9, :, :]):
        assert _ring_share(img, 3.5, 6.5) > 0.7


@pytest.mark.long
def test_every_voxel_stays_a_mean_of_photo_colours_on_a_small_photo(monkeypatch):
    """Each iteration sets a voxel to a weighted mean of photo colours, so before histogram matching it lies inside
    the photo's colour range.  On a small photo (every neighbourhood searched, exact copies among them) the
    weights at k = 10 fall to 1e-30 and less; dividing by a floor of 1e-12 once turned such voxels black, and the
    histogram matching painted them as flat blotches of the darkest colours."""
    import omninoise.backend.solid.synthesis as syn
    from omninoise.backend.solid.synthesis import image_settings
    rng = np.random.default_rng(5)
    v = rng.random((100, 100, 3))
    for _ in range(2):                       # a little spatial correlation, as a photo of gravel has
        v = (v + np.roll(v, 1, 0) + np.roll(v, 1, 1)) / 3.0
    photo = (0.35 + 0.5 * (v - v.min()) / (v.max() - v.min())).astype(np.float32)
    means = []
    real = syn._match_histogram
    monkeypatch.setattr(syn, "_match_histogram", lambda tile, *a: means.append(tile.copy()) or real(tile, *a))
    synthesise(photo, image_settings(128, photo.shape))
    lo, hi = photo.reshape(-1, 3).min(0) - 1e-4, photo.reshape(-1, 3).max(0) + 1e-4
    for t in means:
        assert (t.reshape(-1, 3) >= lo).all() and (t.reshape(-1, 3) <= hi).all()


def test_the_search_cuts_out_only_the_neighbourhoods_it_keeps():
    """A large photo's neighbourhoods are subsampled before any is cut out (a 4096² photo's every 8 x 8 one would
    take about 13 GB); each kept row is the photo's neighbourhood at its position, row-major, colours last."""
    from omninoise.backend.solid.synthesis import _Searcher

    photo = np.random.default_rng(0).random((40, 50, 3)).astype(np.float32)
    s = _Searcher(photo, 4, 8, 100, np.random.default_rng(1))
    assert s.X.shape == (100, 48) and len(np.unique(s.pos, axis=0)) == 100
    for (r, c), x in zip(s.pos, s.X):
        np.testing.assert_array_equal(x, photo[r:r + 4, c:c + 4].reshape(-1))
    every = _Searcher(photo, 4, 8, 10 ** 6, np.random.default_rng(1))     # fewer than asked for: all of them
    assert every.X.shape == (37 * 47, 48)


@pytest.mark.parametrize("dim", [2, 3])
def test_a_photo_of_one_colour_is_that_colour_without_a_search(monkeypatch, dim):
    """Every neighbourhood of a photo of one colour is alike: the tile is the colour, and no level is searched."""
    import omninoise.backend.solid.synthesis as synthesis

    def searched(*args, **kwargs):
        raise AssertionError("a level was searched")

    monkeypatch.setattr(synthesis, "_level", searched)
    seen = []
    s = SynthesisSettings(dim=dim, size=32, levels=2, patch=5, iterations=(1, 1), sharpness=(1.0, 1.0))
    tile = synthesise(np.full((48, 48, 3), (0.2, 0.4, 0.6), np.float32), s, progress=seen.append)
    assert tile.shape == (32,) * dim + (3,) and (tile == np.float32([0.2, 0.4, 0.6])).all() and seen == [1.0]


def test_tile_field_samples_voxel_centres_and_wraps():
    rng = np.random.default_rng(1)
    tile = rng.random((8, 8, 8, 3)).astype(np.float32)
    f = TileField(tile, px_per_unit=4.0)
    k, j, i = 3, 5, 6
    centre = (np.array([[i, j, k]]) + 0.5) / 4.0             # (x, y, z) of voxel (z=k, y=j, x=i)
    np.testing.assert_allclose(f.evaluate(centre)[0], tile[k, j, i], atol=1e-6)
    pts = rng.uniform(-3, 3, (50, 3))
    np.testing.assert_allclose(f.evaluate(pts), f.evaluate(pts + np.array([2.0, -4.0, 6.0])), atol=1e-5)
    mid = (centre + np.array([[0.125, 0.0, 0.0]]))           # half-way to the next voxel along x
    np.testing.assert_allclose(f.evaluate(mid)[0], 0.5 * (tile[k, j, i] + tile[k, j, (i + 1) % 8]), atol=1e-6)
    flat = TileField(tile[0], 4.0)
    assert flat.evaluate(pts[:, :2]).shape == (50, 3)
    with pytest.raises(SettingError, match="points"):
        flat.evaluate(pts)
    with pytest.raises(SettingError, match="tile"):
        TileField(tile[..., :2], 4.0)
    with pytest.raises(SettingError, match="px_per_unit"):
        TileField(tile, 0.0)


def test_progress_and_cancel():
    photo = _stripes(8.0)
    seen = []
    synthesise(photo, SynthesisSettings(dim=2, **SMALL), progress=seen.append)
    assert seen == sorted(seen) and seen[-1] == pytest.approx(1.0) and len(seen) == 4
    with pytest.raises(Cancelled):
        synthesise(photo, SynthesisSettings(dim=3, **SMALL), cancel=lambda: True)


@pytest.mark.parametrize("kw, field", [(dict(dim=4), "dim"), (dict(planes="floors"), "planes"),
                                       (dict(size=30), "size"), (dict(size=16, levels=3, iterations=(1, 1, 1)), "size"),
                                       (dict(sharpness=(1.0, 10.0)), "sharpness"),
                                       (dict(iterations=(1, 1)), "iterations"), (dict(stride=0), "stride"),
                                       (dict(sharpness=(1.0, 0.0, 10.0)), "sharpness"), (dict(components=0), "components")])
def test_bad_settings_name_the_field_in_one_line(kw, field):
    with pytest.raises(SettingError) as e:
        SynthesisSettings(**kw)
    assert e.value.setting == field
    assert "\n" not in str(e.value)


def test_bad_photos_are_refused_in_one_line():
    with pytest.raises(SettingError, match="RGB"):
        synthesise(np.zeros((64, 64), np.float32))
    with pytest.raises(SettingError, match="non-finite"):
        synthesise(np.full((64, 64, 3), np.nan, np.float32))
    with pytest.raises(SettingError, match="at least 36 px"):
        synthesise(np.zeros((20, 64, 3), np.float32))


@pytest.mark.long
@pytest.mark.parametrize("dim", [2, 3])
def test_bench_measures_held_out_photos_beside_random_phase(bench_script, tmp_path, dim, capsys):
    out = str(tmp_path / "syn")
    mod = bench_script("solid_synthesis")
    assert mod.main(["--dim", str(dim), "--only", "beige_bricks", "--size", "64" if dim == 2 else "32",
                     "--iterations", "1,1,1", "--sharpness", "1,1,10",
                     "--seeds", "1", "--sheet", "--out", out]) == 0
    doc = json.load(open(out + ".json"))
    (name, r), = doc["photos"].items()
    assert name == "brick__beige_bricks.jpg" and doc["settings"]["dim"] == dim
    for k in ("pooled", "walls", "axes", "random_phase_pooled", "random_phase_walls", "random_phase_axes"):
        assert np.isfinite(r[k]) and r[k] > 0
    assert doc["summary"]["photos"] == 1 and doc["summary"]["by_category"]["brick"]["photos"] == 1
    from PIL import Image
    # 3D: photo | x, y, z slices, two oblique cuts | the random phase solid's x, y, z | random phase (128 px); 2D:
    # photo | tile | 2 x 2 of it | random phase (the tile's)
    assert Image.open(out + ".png").size == ((10 * 128, 128) if dim == 3 else (4 * 64, 64))
    if dim == 3:        # cuts at random orientations, beside the axis cuts
        assert 0 < r["oblique_band"] < r["oblique"] < r["pixel_shuffle"]
    assert 0 < r["pooled"] < r["pixel_shuffle"]
    # the band-pass figures (no residue level) are there; the photo's own crops (the floor) are far closer than its
    # shuffled pixels
    assert 0 < r["pooled_band"] and 0 < r["random_phase_pooled_band"]
    assert 0 < r["photo_crop_band"] and r["photo_crop"] < 0.5 * r["pixel_shuffle"]
    # spot noise drawn in 2D alike (the Gaussian draw a Gaussian solid's slices compare with)
    assert 0 < r["gaussian_2d_pooled"] < r["pixel_shuffle"] and 0 < r["gaussian_2d_pooled_band"]
    s = doc["summary"]
    assert s["beats_gaussian_2d_pooled"] == int(r["pooled"] < r["gaussian_2d_pooled"])
    assert s["beats_random_phase_pooled_band"] == int(r["pooled_band"] < r["random_phase_pooled_band"])
    assert s["photo_crop_beats_random_phase_pooled"] == int(r["photo_crop"] < r["random_phase_pooled"])
    if dim == 3:    # the Gaussian solids, and the closer of the two
        iso, up = r["random_phase_solid_isotropic_pooled"], r["random_phase_solid_upright_pooled"]
        assert 0 < min(iso, up) == r["random_phase_solid_pooled"] < r["pixel_shuffle"]
        assert s["beats_random_phase_solid_pooled"] == int(r["pooled"] < min(iso, up))
        assert 0.1 < r["axis_imbalance"] < 0.5        # beige brick's courses: oriented, not stripes
    assert "brick__beige_bricks" in capsys.readouterr().out


@pytest.mark.long
def test_bench_draws_the_products_tiles_by_default_in_2d(bench_script, tmp_path):
    """Without --iterations and --sharpness the 2D bench draws what the product draws from each photo
    (image_settings): it records the levels and the whole tiles' colour error, and the sheet shows two seeds."""
    out = str(tmp_path / "product")
    mod = bench_script("solid_synthesis")
    assert mod.main(["--dim", "2", "--only", "beige_bricks", "--size", "64", "--seeds", "2", "--sheet",
                     "--out", out]) == 0
    doc = json.load(open(out + ".json"))
    (name, r), = doc["photos"].items()
    assert r["levels"] == 3 and 0 <= r["colour_tile"] < 0.03 and "levels per photo" in doc["settings"]
    assert doc["summary"]["max_colour_tile"] == r["colour_tile"]
    from PIL import Image
    assert Image.open(out + ".png").size == (5 * 64, 64)     # photo | two tiles | 2 x 2 of the first | random phase


@pytest.mark.long
def test_bench_scales_photos_down_first_with_photo_side(bench_script, tmp_path):
    """--photo-side measures small photos (swatches): the photo is scaled to that short side before synthesis."""
    out = str(tmp_path / "small")
    mod = bench_script("solid_synthesis")
    assert mod.main(["--dim", "2", "--only", "beige_bricks", "--size", "256", "--seeds", "1", "--photo-side", "128",
                     "--out", out]) == 0
    doc = json.load(open(out + ".json"))
    (name, r), = doc["photos"].items()
    # a 256 px tile gets four levels from the 256 px photo, three from it scaled to 128 px (image_levels)
    assert doc["photo_side"] == 128 and r["levels"] == 3
    assert 0 < r["pooled"] < r["pixel_shuffle"]


@pytest.mark.long
def test_bench_measures_the_spectral_solid_without_the_marginals(bench_script, tmp_path, monkeypatch):
    """--method spectral --no-marginals --flat-start measures the Gaussian tile as drawn (the map onto the photo's
    marginals, which the request draws, left out: tests/core/test_spectral_solid.py compares the two) from flat
    power; the JSON says so, and holds the cuts at random orientations beside the axis cuts."""
    from omninoise.backend.solid import spectral_solid

    monkeypatch.setattr(spectral_solid, "PERIOD", 32)
    out = str(tmp_path / "plain")
    mod = bench_script("solid_synthesis")
    assert mod.main(["--method", "spectral", "--only", "beige_bricks", "--seeds", "1", "--no-marginals",
                     "--flat-start", "--out", out]) == 0
    doc = json.load(open(out + ".json"))
    r = doc["photos"]["brick__beige_bricks.jpg"]
    assert doc["method"] == "spectral" and doc["marginals"] is False and doc["periodic"] is True
    assert doc["isotropic_start"] is False
    assert 0 < r["pooled"] < r["pixel_shuffle"] and r["colour"] < 0.03
    assert 0 < r["oblique_band"] and 0 < r["oblique"] < r["pixel_shuffle"]
    assert doc["summary"]["median_oblique"] == r["oblique"]


def test_the_evaluation_cuts_planes_at_any_orientation():
    """The benches' oblique cuts (photo_eval.oblique_points): square to an axis they are the axis cuts' planes (x
    right and y up on a floor, y right and z up on a wall normal to x); at any normal, rows and columns are
    orthonormal in the plane, one photo px apart, the columns horizontal and the rows running down."""
    from omninoise.backend.solid.model import slice_points
    from omninoise.training.solid import photo_eval as mod

    ppu = 128.0

    for axis, normal in (("z", (0, 0, 1)), ("x", (1, 0, 0))):
        np.testing.assert_allclose(mod.oblique_points(8, ppu, normal, (0.1, 0.2, 0.3)),
                                   slice_points(8, ppu, axis, (0.1, 0.2, 0.3)), atol=1e-12)
    for normal in mod.OBLIQUE_NORMALS:
        p = mod.oblique_points(4, ppu, normal, (0, 0, 0)).reshape(4, 4, 3)
        col, row = (p[0, 1] - p[0, 0]) * ppu, (p[1, 0] - p[0, 0]) * ppu
        np.testing.assert_allclose([np.linalg.norm(col), np.linalg.norm(row), col @ row, col @ normal,
                                    row @ normal], [1, 1, 0, 0, 0], atol=1e-9)
        assert abs(col[2]) < 1e-12 and row[2] <= 0
    seen = []          # oblique_slices: one cut per normal, through its own point, of the field it is given
    cuts = mod.oblique_slices(lambda p: seen.append(p) or p[:, :1] * np.ones(3), ppu, 4)
    assert len(cuts) == len(seen) == 6 and all(c.shape == (4, 4, 3) and c.dtype == np.float32 for c in cuts)
    for p, normal, o in zip(seen, mod.OBLIQUE_NORMALS, mod.OBLIQUE_OFFSETS):
        np.testing.assert_allclose((p - o) @ normal, 0, atol=1e-9)
