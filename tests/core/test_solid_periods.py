"""A tile's few repeats (backend/solid/periods.py): periods found from the autocorrelation, the lattice they span,
and a harmonic part that keeps the head joints of a tile holding two courses of two bricks."""
import numpy as np

from omninoise.backend.solid.harmonic import HarmonicConfig, harmonic_field, photo_harmonics
from omninoise.backend.solid.model import plane_points
from omninoise.backend.solid.motif import on_grid
from omninoise.backend.solid.periods import autocorrelation, frame_lines, period_lattice, translations

PPU = 128.0


def brick_tile(H=160, W=256, course=80, brick=128, seed=0):
    """(photo (H, W, 3), its noise-free pattern's luminance (H, W)): a tileable running bond of bricks of one
    random tone each, with grey mortar joints 6 px wide and pixel noise; two courses of two bricks by default."""
    rng = np.random.default_rng(seed)
    r, c = np.mgrid[0:H, 0:W]
    row = r // course
    col = (c + (row % 2) * brick // 2) % W // brick
    joint = (r % course < 6) | ((c + (row % 2) * brick // 2) % brick < 6)
    tone = 0.55 + 0.06 * rng.standard_normal((H // course, W // brick))[row, col]
    pattern = np.where(joint, 0.75, 0.55)
    lum = np.where(joint, 0.75, tone) + 0.03 * rng.standard_normal((H, W))
    img = np.clip(lum[..., None] * np.array([1.0, 0.62, 0.42]), 0.0, 1.0)
    return img, pattern


def mean_free(img):
    return (img - img.mean((0, 1))).transpose(2, 0, 1)


def field(h, H, W):
    p = plane_points(max(H, W), PPU).reshape(max(H, W), max(H, W), 2)[:H, :W].reshape(-1, 2)
    return harmonic_field(p, h).reshape(H, W, 3)


def test_the_autocorrelation_is_one_at_zero_and_at_a_whole_period():
    img, _ = brick_tile()
    u = mean_free(img)
    R, tx, ty = autocorrelation(u)
    assert np.isclose(R[0, 0], 1.0)
    # an image that is two copies side by side matches itself exactly one copy over
    twice = np.concatenate([u, u], axis=2)
    R2, _, _ = autocorrelation(twice)
    assert np.isclose(R2[0, 256], 1.0)
    # shifts beyond the reach are not measured
    assert R[0, int(0.6 * 256) + 2] == -1.0


def test_a_tile_of_two_courses_of_two_bricks_has_its_running_bond():
    img, _ = brick_tile()
    B, T = period_lattice(mean_free(img))
    assert B is not None and T.shape == (2, 2)
    # the same lattice as (128, 0) and (64, 80) px (a brick along the course, half a brick and a course up): four
    # cells in the tile, on the DFT's grid
    true = np.array([(128.0, 0.0), (64.0, 80.0)])
    assert abs(abs(np.linalg.det(T)) - abs(np.linalg.det(true))) < 0.02 * abs(np.linalg.det(true))
    coef = np.linalg.solve(true.T, T.T)
    assert np.abs(coef - np.round(coef)).max() < 0.02
    assert on_grid(B, 0.05)


def test_the_few_repeats_keep_the_head_joints_the_peak_test_misses():
    """The peak test finds the courses alone (its ring around each peak holds the pattern's other harmonics, one
    or two bins away); the periods' lattice brings the head joints: the part follows the bond's pattern."""
    img, pattern = brick_tile()
    H, W = pattern.shape
    # the lines across the frame (the courses) left out of both: the periods' part against the peaks'
    with_periods = photo_harmonics(img, PPU, HarmonicConfig(lines=False))
    peaks = photo_harmonics(img, PPU, HarmonicConfig(periods=False, lines=False))
    assert with_periods.share > peaks.share + 0.1
    p = pattern - pattern.mean()
    corr = {k: np.corrcoef(field(h, H, W).mean(2).ravel(), p.ravel())[0, 1]
            for k, h in (("periods", with_periods), ("peaks", peaks))}
    assert corr["periods"] > 0.75 and corr["peaks"] < corr["periods"] - 0.2      # 0.81 and 0.53 measured
    # the head joints: the columns 6 px wide where the bond puts them, in the middle of each course
    lum = field(with_periods, H, W).mean(2)
    head = lum[20:60, 0:6].mean(), lum[20:60, 30:90].mean()
    assert head[0] > head[1] + 0.05


def test_textures_without_a_lattice_of_periods_have_none():
    rng = np.random.default_rng(3)
    # a smooth random texture (1/f^1.5): no return of its autocorrelation
    F = np.fft.fft2(rng.standard_normal((160, 256)))
    f = np.hypot(*np.meshgrid(np.fft.fftfreq(256), np.fft.fftfreq(160)))
    rock = np.real(np.fft.ifft2(F / np.maximum(f, 1 / 256) ** 1.5))
    rock = np.repeat(((rock - rock.mean()) / rock.std() * 0.1 + 0.5)[..., None], 3, 2)
    assert period_lattice(mean_free(rock)) == (None, None)
    a, b = photo_harmonics(rock, PPU), photo_harmonics(rock, PPU, HarmonicConfig(periods=False))
    assert np.array_equal(a.freq, b.freq) and a.share == b.share
    # planks: boards of random tones along x, 50 px wide, no joints across them.  A shift along the boards
    # correlates all the way (a ridge of R, not a peak), so no 2D lattice is taken from its wiggles
    r = np.arange(160)[:, None] * np.ones((1, 256))
    tone = 0.5 + 0.1 * rng.standard_normal(4)[(r // 50).astype(int) % 4]
    planks = np.repeat((tone + 0.01 * rng.standard_normal((160, 256)))[..., None], 3, 2)
    R, tx, ty = autocorrelation(mean_free(planks))
    T, _ = translations(R, tx, ty)
    assert not np.any((np.abs(T[:, 1]) < 3) & (np.abs(T[:, 0]) > 10))     # no translation along the boards
    assert period_lattice(mean_free(planks)) == (None, None)


def test_a_pattern_repeated_once_is_no_lattice():
    """A tile holding one brick of each course (a cell bigger than half the tile) repeats nothing inside the
    frame: no lattice (fewer than MIN_REPEATS cells)."""
    img, _ = brick_tile(H=160, W=256, course=80, brick=256)
    B, _ = period_lattice(mean_free(img))
    assert B is None


def test_a_large_tile_is_measured_on_its_block_means():
    """A 1024 x 640 px tile (over SIDE px) is searched on its 4 x 4 block means; its periods come back in the
    tile's own pixels: a brick of 512 px along the course, half a brick and a course of 320 px up."""
    img, _ = brick_tile(H=640, W=1024, course=320, brick=512)
    B, T = period_lattice(mean_free(img))
    true = np.array([(512.0, 0.0), (256.0, 320.0)])
    assert B is not None
    assert abs(abs(np.linalg.det(T)) - abs(np.linalg.det(true))) < 0.02 * abs(np.linalg.det(true))
    coef = np.linalg.solve(true.T, T.T)
    assert np.abs(coef - np.round(coef)).max() < 0.02
    assert on_grid(B, 0.05)


def test_a_strip_of_a_few_rows_has_no_lattice():
    """A photo one to three px high or wide cannot hold two cells of a lattice (it was an FFT of no points: a
    1 x 5000 px strip made the neural texture's encoding fail); a long strip of 4 or 16 rows is searched on block
    means that keep rows, and a photo of them encodes."""
    rng = np.random.default_rng(0)
    for h in (1, 2, 3):
        assert period_lattice(mean_free(rng.random((h, 5000, 3)))) == (None, None)
        assert period_lattice(mean_free(rng.random((5000, h, 3)))) == (None, None)
    for h in (4, 16):
        B, T = period_lattice(mean_free(rng.random((h, 5000, 3))))
        assert (B is None) == (T is None)
    assert len(photo_harmonics(rng.random((1, 5000, 3)), PPU)) == 0


def floor_tile(H=192, W=224, grout=4, seed=0):
    """(photo (H, W, 3), its grout mask (H, W)): one floor tile of a library, framed by its grout along the top and
    left edges (so that it tiles), its face a smooth random texture with pixel noise."""
    rng = np.random.default_rng(seed)
    F = np.fft.fft2(rng.standard_normal((H, W)))
    f = np.hypot(*np.meshgrid(np.fft.fftfreq(W), np.fft.fftfreq(H)))
    face = np.real(np.fft.ifft2(F / np.maximum(f, 1 / W) ** 1.2))
    face = 0.6 + 0.04 * (face - face.mean()) / face.std() + 0.02 * rng.standard_normal((H, W))
    r, c = np.mgrid[0:H, 0:W]
    mask = (r < grout) | (c < grout)
    lum = np.where(mask, 0.35, face)
    return np.clip(lum[..., None] * np.array([1.0, 0.9, 0.8]), 0.0, 1.0), mask


def test_a_tile_framed_by_its_grout_draws_its_joints_and_not_its_face():
    """One floor tile per frame repeats nothing inside it (no lattice of periods, no peak), but its grout runs
    straight across the frame: its rows and columns are lines, and the part draws the joints, not a plaid of the
    face's row and column means."""
    img, mask = floor_tile()
    H, W = mask.shape
    assert period_lattice(mean_free(img)) == (None, None)
    none, h = photo_harmonics(img, PPU, HarmonicConfig(lines=False)), photo_harmonics(img, PPU)
    assert len(none) == 0 and len(h) > 0 and h.share > 0.1
    lum = field(h, H, W).mean(2)
    assert np.corrcoef(lum.ravel(), mask.ravel())[0, 1] < -0.9          # dark where the grout is
    # both joints, and a flat face: the part varies by under a tenth of the joints' depth away from them
    face = lum[20:, 20:]
    assert lum[:4, 20:].mean() < face.mean() - 0.15 and lum[20:, :4].mean() < face.mean() - 0.15
    assert face.std() < 0.1 * (face.mean() - lum[:4, 20:].mean())


def test_shading_and_texture_rows_are_not_lines():
    """A smooth random texture with a broad dark band across it (shading, 40 px wide): the band is the local level
    of its rows, not a line; so is every row of the texture: no line is read."""
    rng = np.random.default_rng(5)
    F = np.fft.fft2(rng.standard_normal((160, 256)))
    f = np.hypot(*np.meshgrid(np.fft.fftfreq(256), np.fft.fftfreq(160)))
    rock = np.real(np.fft.ifft2(F / np.maximum(f, 1 / 256) ** 1.5))
    rock = (rock - rock.mean()) / rock.std() * 0.05 + 0.5
    band = 0.25 * np.exp(-0.5 * ((np.arange(160) - 80) / 20.0) ** 2)[:, None]
    img = np.repeat((rock - band)[..., None], 3, 2)
    fx, fy, A = frame_lines(mean_free(img))
    assert len(fx) == 0
    # a joint 3 px wide, as dark as the band, is a line
    thin = 0.25 * (np.abs(np.arange(160) - 80) <= 1)[:, None]
    fx, fy, A = frame_lines(mean_free(np.repeat((rock - thin)[..., None], 3, 2)))
    assert len(fx) > 0 and np.all(fx == 0)
