"""Random phase noise as a solid (backend/solid/spectral_solid.py): the power design meets the projections a solid
can meet, the photo's spectrum is read with its rows running up, the B-spline field reads a band-limited field
exactly between voxels, and the slices of a drawn solid have the photo's mean, variance and spectrum.  Small
periods keep it to seconds."""
import numpy as np
import pytest

from omninoise.backend.errors import SettingError
from omninoise.backend.solid.model import slice_points
from omninoise.backend.solid.spectral_solid import (MAX_READ, PX_PER_UNIT, SplineField, bspline_prefilter, slice_spectrum,
                                          solid_power, spectral_tile)


def _radial_power(img: np.ndarray, bands) -> np.ndarray:
    """Power of img (H, W, 3) minus its mean, summed over channels, in bands of cycles per px."""
    u = img - img.mean((0, 1))
    F = np.fft.fft2(u.transpose(2, 0, 1)) / (u.shape[0] * u.shape[1])
    P = (np.abs(F) ** 2).sum(0)
    r = np.hypot(*np.meshgrid(np.fft.fftfreq(u.shape[0]), np.fft.fftfreq(u.shape[1]), indexing="ij"))
    return np.array([P[(r >= a) & (r < b)].sum() for a, b in bands])


def _gaussian_photo(n: int, seed: int, lowest: float = 1.0 / 32) -> np.ndarray:
    """A (n, n, 3) Gaussian texture with an isotropic 1/f power spectrum from ``lowest`` cycles per px up (a
    tile's period can hold nothing longer than itself) and correlated colours, mean 0.5."""
    rng = np.random.default_rng(seed)
    f = np.hypot(*np.meshgrid(np.fft.fftfreq(n), np.fft.fftfreq(n), indexing="ij"))
    amp = np.where(f >= lowest, np.maximum(f, 1.0 / n) ** -0.5, 0.0)
    g = np.real(np.fft.ifft2(amp * np.fft.fft2(rng.standard_normal((n, n)))))
    h = np.real(np.fft.ifft2(amp * np.fft.fft2(rng.standard_normal((n, n)))))
    g, h = g / g.std(), h / h.std()
    rgb = np.stack([0.5 + 0.12 * g, 0.5 + 0.10 * g + 0.03 * h, 0.5 + 0.05 * g - 0.06 * h], -1)
    return np.clip(rgb, 0.0, 1.0).astype(np.float32)


def test_the_design_meets_projections_a_solid_has():
    """Targets that are the projections of a solid (an isotropic one, nothing on the coordinate axes) are met;
    the design stays non-negative, keeps the total and leaves the coordinate axes empty."""
    n = 16
    k = np.fft.fftfreq(n, 1.0 / n)
    kz, ky, kx = np.meshgrid(k, k, k, indexing="ij")
    P0 = np.exp(-np.sqrt(kz ** 2 + ky ** 2 + kx ** 2) / 3.0)
    P0[0, 0, :] = P0[0, :, 0] = P0[:, 0, 0] = 0.0
    T = P0.sum(2)
    np.testing.assert_allclose(P0.sum(1), T, rtol=1e-12)            # isotropic: the three projections agree
    P = solid_power(T, iterations=200)
    assert P.min() >= 0.0 and np.isclose(P.sum(), T.sum(), rtol=1e-9)
    assert P[0, 0, :].sum() == P[0, :, 0].sum() == P[:, 0, 0].sum() == 0.0
    for proj in (P.sum(2), P.sum(1), P.sum(0)):
        assert np.abs(proj - T).sum() / T.sum() < 0.02
    # and it is not the flat start: before any iteration the projections are far
    assert np.abs(solid_power(T, iterations=0, isotropic_iterations=0).sum(2) - T).sum() / T.sum() > 0.3


def test_of_the_solids_a_photo_allows_the_isotropic_start_finds_the_isotropic_one():
    """Many solids have the same three axis projections; from flat power the EM settles on one that puts a
    natural photo's low frequencies at 3D frequencies with one large component (sheets along the axes, which cuts
    at other angles show as plaid).  The isotropic start finds the isotropic solid the projections came from: its
    power within 15 % of it (the flat start: over 20 % off), its share on such frequencies the solid's own."""
    n = 32
    k = np.fft.fftfreq(n, 1.0 / n)
    K = np.stack(np.meshgrid(k, k, k, indexing="ij"))
    P0 = (np.sum(K ** 2, 0) + 1.0) ** -1.5        # a natural solid's 1/f^3 power: its cuts' is about 1/f^2
    P0[0, 0, :] = P0[0, :, 0] = P0[:, 0, 0] = 0.0
    T = P0.sum(2)
    s = np.sort(np.abs(K), axis=0)
    sheets = s[2] > 4 * np.maximum(s[1], 1)         # one component over four times the others
    share = P0[sheets].sum() / P0.sum()
    iso, flat = solid_power(T), solid_power(T, isotropic_iterations=0)
    for P in (iso, flat):       # both meet the projections
        for proj in (P.sum(2), P.sum(1), P.sum(0)):
            assert np.abs(proj - T).sum() / T.sum() < 0.01
    assert np.abs(iso - P0).sum() / P0.sum() < 0.15 < 0.2 < np.abs(flat - P0).sum() / P0.sum()
    assert abs(iso[sheets].sum() / iso.sum() - share) < 0.2 * share
    assert flat[sheets].sum() / flat.sum() > 1.5 * share
    # the start alone is a function of |k|: one value per shell of whole cycles
    start = solid_power(T, iterations=0)
    shell = np.rint(np.sqrt(np.sum(K ** 2, 0)))
    on_axis = (K == 0).sum(0) >= 2
    for r in (3, 7, 12):
        v = start[(shell == r) & ~on_axis]
        assert np.ptp(v) <= 1e-9 * v.max()


def test_the_photo_spectrum_is_read_with_its_rows_running_up():
    """Stripes with 3 cycles down the rows and 5 across the columns of a 64 px photo: their power lies at row
    frequency -3 (rows run up in a slice) and column frequency 5, and at the mirror frequency; it sums to about
    their variance; a 128 px photo of stripes of the same cycles per px gives the same bins of a 64-periodic grid."""
    def stripes(n, a, b):
        y, x = np.mgrid[0:n, 0:n]
        v = 0.5 + 0.2 * np.cos(2 * np.pi * (a * y + b * x) / n)
        return np.repeat(v[..., None], 3, axis=2)

    S = slice_spectrum(stripes(64, 3, 5), 64)
    T = np.trace(S, axis1=2, axis2=3)
    peaks = {tuple(int(i) for i in ij) for ij in np.argwhere(T > 0.1 * T.max())}
    assert peaks == {((-3) % 64, 5), (3, (-5) % 64)}
    # the periodic component takes a little from steps across the borders even of a tiling image (Moisan 2011)
    assert np.isclose(T.sum(), 3 * 0.2 ** 2 / 2, rtol=0.05)
    T2 = np.trace(slice_spectrum(stripes(128, 6, 10), 64), axis1=2, axis2=3)
    assert {tuple(int(i) for i in ij) for ij in np.argwhere(T2 > 0.1 * T2.max())} == peaks
    # the colour cross-spectrum is symmetric and positive semi-definite
    assert np.allclose(S, S.transpose(0, 1, 3, 2))
    assert np.linalg.eigvalsh(S[(-3) % 64, 5]).min() > -1e-12


def test_the_spline_field_reads_a_band_limited_field_between_voxels():
    """The coefficients of a periodic field sampled twice as finely as its highest frequency (prefiltered by
    bspline_prefilter) read back the field itself anywhere, not its voxels blurred; voxel centres at
    (i + 1/2) / voxels_per_unit, indexed (z, y, x)."""
    M, over = 32, 2
    vpu = PX_PER_UNIT * over
    i = (np.arange(M) + 0.5) / vpu                               # voxel centres, units
    z, y, x = np.meshgrid(i, i, i, indexing="ij")
    period = M / vpu
    k = 2 * np.pi / period * np.array([3.0, -5.0, 7.0])          # x, y, z cycles per period (highest 7 of 16)

    def field(px, py, pz):
        return np.cos(k[0] * px + k[1] * py + k[2] * pz + 0.3)

    samples = field(x, y, z)
    b = bspline_prefilter(M)
    c = np.real(np.fft.ifftn(np.fft.fftn(samples) / (b[:, None, None] * b[None, :, None] * b[None, None, :])))
    f = SplineField(np.repeat(c[..., None], 3, axis=3).astype(np.float32) * 0.25, (0.5, 0.5, 0.5), over)
    pts = np.random.default_rng(0).uniform(-2.0, 2.0, (4000, 3))
    want = 0.5 + 0.25 * field(pts[:, 0], pts[:, 1], pts[:, 2])
    got = f.evaluate(pts)
    assert np.abs(got - want[:, None]).max() < 0.01
    # trilinear reading of the same voxels is off by far more: the B-spline is what keeps the detail
    from omninoise.backend.solid.synthesis import TileField

    lin = TileField(np.repeat(0.5 + 0.25 * samples[..., None], 3, axis=3).astype(np.float32), vpu).evaluate(pts)
    assert np.abs(lin - want[:, None]).max() > 3 * np.abs(got - want[:, None]).max()
    assert f.period == pytest.approx(period)
    np.testing.assert_allclose(f.evaluate(pts + period), got, atol=1e-5)         # periodic along every axis
    np.testing.assert_allclose(f.evaluate(pts[:, :2]), f.evaluate(np.c_[pts[:, :2], np.zeros(len(pts))]))


@pytest.fixture(scope="module")
def drawn():
    photo = _gaussian_photo(128, 1)
    return photo, SplineField(spectral_tile(photo, seed=3, period=64), photo.reshape(-1, 3).mean(0))


def test_slices_of_the_solid_have_the_photo_mean_variance_and_spectrum(drawn):
    """Twelve slices normal to x, y and z at arbitrary offsets (not on voxel centres): mean colour within 0.02,
    per-channel variance within 25 %, power in three octaves of frequency within a factor 1.5 of the photo's, and
    the colour correlation of red and blue kept."""
    photo, f = drawn
    rng = np.random.default_rng(5)
    imgs = [f.evaluate(slice_points(64, PX_PER_UNIT, ax, rng.uniform(-3, 3, 3))).reshape(64, 64, 3)
            for ax in "xyz" for _ in range(4)]
    s = np.stack(imgs)
    assert np.abs(s.mean((0, 1, 2)) - photo.mean((0, 1))).max() < 0.02
    ratio = s.var((1, 2)).mean(0) / photo.var((0, 1))
    assert np.all((ratio > 0.75) & (ratio < 1.25)), ratio
    bands = [(1 / 32, 1 / 16), (1 / 16, 1 / 8), (1 / 8, 1 / 4)]
    crops = [photo[a:a + 64, b:b + 64] for a in (0, 64) for b in (0, 64)]
    want = np.mean([_radial_power(c, bands) for c in crops], 0)
    got = np.mean([_radial_power(im, bands) for im in imgs], 0)
    assert np.all((got / want > 1 / 1.5) & (got / want < 1.5)), got / want
    corr = lambda a: np.corrcoef(a[..., 0].ravel(), a[..., 2].ravel())[0, 1]   # noqa: E731
    assert abs(corr(s) - corr(photo)) < 0.15


def test_a_seed_draws_another_texture_and_the_same_seed_the_same(drawn):
    photo, f = drawn
    again = spectral_tile(photo, seed=3, period=64)
    np.testing.assert_array_equal(again, f.coeffs)
    other = spectral_tile(photo, seed=4, period=64)
    assert np.abs(other - f.coeffs).mean() > 0.5 * np.abs(f.coeffs).mean()


def test_progress_rises_to_one_and_cancel_stops():
    photo = _gaussian_photo(64, 2)
    seen = []
    spectral_tile(photo, period=16, progress=seen.append)
    assert seen == sorted(seen) and seen[-1] == pytest.approx(1.0) and len(seen) > 10
    from omninoise.backend.grid import Cancelled

    calls = []
    with pytest.raises(Cancelled):
        spectral_tile(photo, period=16, cancel=lambda: calls.append(1) or len(calls) > 3)


@pytest.mark.parametrize("photo, period, match", [
    (np.zeros((20, 64, 3), np.float32), 16, "photo is 64 x 20 px"),
    (np.full((64, 64, 3), np.nan, np.float32), 16, "non-finite"),
    (np.zeros((64, 64), np.float32), 16, "RGB image"),
    (np.zeros((64, 64, 3), np.float32), 7, "period must be an even number"),
])
def test_bad_input_is_named(photo, period, match):
    with pytest.raises(SettingError, match=match):
        spectral_tile(photo, period=period)


def test_a_flat_photo_gives_its_flat_colour():
    photo = np.full((64, 64, 3), (0.2, 0.4, 0.6), np.float32)
    f = SplineField(spectral_tile(photo, period=16), photo.reshape(-1, 3).mean(0))
    np.testing.assert_allclose(f.image(16), np.broadcast_to((0.2, 0.4, 0.6), (16, 16, 3)), atol=1e-4)


def test_a_photo_of_one_colour_is_that_colour_without_lifting_a_spectrum(monkeypatch):
    """Method "spectral" on a photo of one colour: no power to lift (the tile took its seconds for zeros)."""
    import omninoise.backend.solid.spectral_solid as spectral

    def lifted(*args, **kwargs):
        raise AssertionError("a spectrum was lifted")

    monkeypatch.setattr(spectral, "spectral_tile", lifted)
    seen = []
    f = spectral.spectral_field(np.full((64, 64, 3), (0.2, 0.4, 0.6)), seed=3, progress=seen.append)
    out = f.evaluate(np.random.default_rng(0).normal(0.0, 50.0, (500, 3)))
    assert (out == np.float32([0.2, 0.4, 0.6])).all()
    assert seen == [1.0]


def test_a_large_photo_is_read_from_its_central_crop():
    """A photo larger than MAX_READ px gives the tile of its central MAX_READ crop (a 4096² photo then takes seconds
    and about 1.3 GB, not 4 GB)."""
    photo = np.random.default_rng(7).random((MAX_READ + 40, MAX_READ + 10, 3)).astype(np.float32)
    crop = photo[20:20 + MAX_READ, 5:5 + MAX_READ]
    np.testing.assert_array_equal(spectral_tile(photo, period=16), spectral_tile(crop, period=16))
    assert not np.array_equal(spectral_tile(photo[:MAX_READ, :MAX_READ], period=16), spectral_tile(crop, period=16))


def test_the_harmonic_part_stands_on_the_walls_and_leaves_the_solid_the_rest(period32):
    """A photo of level stripes 16 px apart with a little noise: its harmonic part (measured as the neural texture
    measures it) is taken out before the spectrum is read, so the Gaussian solid carries only the noise, and the
    field adds the part back upright: a wall's rows follow the stripes' period along z, not along y."""
    from omninoise.backend.solid.harmonic import measure_harmonics

    rng = np.random.default_rng(3)
    r = np.arange(128)[:, None, None]
    photo = np.clip(0.5 + 0.25 * np.cos(2 * np.pi * r / 16) * np.array([1.0, 0.9, 0.7])
                    + 0.03 * rng.standard_normal((128, 128, 3)), 0, 1).astype(np.float32)
    h = measure_harmonics(photo, PX_PER_UNIT)
    assert len(h) >= 1 and h.share > 0.8
    rest = spectral_tile(photo, period=32, harmonics=h)
    whole = spectral_tile(photo, period=32)
    assert rest.var() < 0.2 * whole.var()
    f = SplineField(rest, photo.reshape(-1, 3).mean(0), harmonics=h)
    wall = f.evaluate(slice_points(64, PX_PER_UNIT, "x", (0.3, 0.1, 0.2))).reshape(64, 64, 3).mean(2)
    down = np.abs(np.fft.rfft(wall.mean(1) - wall.mean())) ** 2      # along z (rows)
    assert down.argmax() == 64 // 16 and down[4] > 0.8 * down.sum()
    assert wall.mean(0).std() < 0.1 * wall.mean(1).std()            # level: nothing along y
    assert SplineField(rest, (0.5, 0.5, 0.5), harmonics=None).harmonics is None
    # spectral_field reads the rest once and draws the same tile from it (period32: PERIOD is 32 here)
    from omninoise.backend.solid.spectral_solid import spectral_field

    np.testing.assert_array_equal(spectral_field(photo, 0, h, marginals=False).coeffs, rest)


def test_reading_the_field_reports_progress_and_cancels(drawn):
    """SplineField.evaluate, which bakes and the panel read through: progress after each chunk, cancel between."""
    from omninoise.backend.grid import Cancelled

    _, f = drawn
    pts = np.random.default_rng(1).uniform(0, 2, (1000, 3))
    seen = []
    got = f.evaluate(pts, chunk=128, progress=seen.append)
    np.testing.assert_array_equal(got, f.evaluate(pts))
    assert len(seen) == 8 and seen == sorted(seen) and seen[-1] == 1.0
    calls = []
    with pytest.raises(Cancelled):
        f.evaluate(pts, chunk=128, cancel=lambda: calls.append(1) or len(calls) > 2)


def _skewed_photo(n: int, seed: int) -> np.ndarray:
    """A (n, n, 3) photo whose values are far from Gaussian: exp of a 1/f Gaussian texture (bright specks on a
    dark ground, skewness about 9), colours along one axis."""
    g = _gaussian_photo(n, seed)[..., 0]
    v = np.exp(1.2 * (g - g.mean()) / g.std())
    v = 0.1 + 0.8 * (v - v.min()) / (v.max() - v.min())
    return (v[..., None] * np.array([1.0, 0.8, 0.6])).astype(np.float32)


def _skew(a: np.ndarray) -> float:
    a = np.asarray(a, np.float64).ravel()
    return float(((a - a.mean()) ** 3).mean() / a.std() ** 3)


@pytest.fixture
def period32(monkeypatch):
    from omninoise.backend.solid import spectral_solid

    monkeypatch.setattr(spectral_solid, "PERIOD", 32)


def _slices(f, n: int = 64) -> np.ndarray:
    rng = np.random.default_rng(11)
    return np.stack([f.evaluate(slice_points(n, PX_PER_UNIT, ax, rng.uniform(-3, 3, 3))).reshape(n, n, 3)
                     for ax in "xyz" for _ in range(3)])


def test_the_marginals_follow_a_skewed_photo(period32):
    """Slices of the spectral field of a photo with bright specks on a dark ground keep its skewed values (the map
    onto its marginals), where the Gaussian tile alone is symmetric; the spread stays the tile's own, the mean the
    photo's, and the map is monotone along each axis."""
    from omninoise.backend.solid.spectral_solid import spectral_field

    photo = _skewed_photo(128, 4)
    mapped, plain = spectral_field(photo, seed=2), spectral_field(photo, seed=2, marginals=False)
    assert plain.marginals is None and mapped.marginals is not None
    a, b = _slices(mapped)[..., 0], _slices(plain)[..., 0]
    want = _skew(photo[..., 0])
    assert want > 1.5 and abs(_skew(b)) < 0.5 and abs(_skew(a) - want) < 0.35 * want, (want, _skew(a), _skew(b))
    assert abs(a.std() / b.std() - 1.0) < 0.15
    assert abs(a.mean() - photo[..., 0].mean()) < 0.02
    m = mapped.marginals
    line = np.linspace(-0.5, 0.5, 201)[:, None] * m.basis[:, 2]    # along the principal axis
    y = m.apply(line) @ m.basis[:, 2]
    assert np.all(np.diff(y) >= -1e-6) and y[-1] > y[0]


def test_the_marginals_leave_a_gaussian_photo_and_a_grey_photo_as_they_are(period32):
    """A Gaussian photo's marginals are the tile's own: the map moves values by a small share of their spread.  A
    grey photo stays grey (its chroma axes barely vary and keep their values) and finite."""
    from omninoise.backend.solid.spectral_solid import spectral_field

    photo = _gaussian_photo(128, 6)
    a, b = _slices(spectral_field(photo, seed=1)), _slices(spectral_field(photo, seed=1, marginals=False))
    assert np.abs(a - b).mean() < 0.05 * b.std()
    grey = np.repeat(_skewed_photo(128, 5)[..., :1], 3, axis=2)
    g = _slices(spectral_field(grey, seed=1))
    assert np.isfinite(g).all() and np.ptp(g, axis=-1).max() < 1e-3
    assert abs(_skew(g[..., 0]) - _skew(grey[..., 0])) < 0.35 * _skew(grey[..., 0])
