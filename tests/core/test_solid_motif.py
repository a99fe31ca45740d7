"""A photo's motif off the DFT's grid (backend/solid/motif.py): peaks located between bins, the lattice they lie
on, and a harmonic part that keeps a photographed brick wall's bricks beyond the photo's frame."""
import os

import numpy as np

from omninoise.backend.solid.harmonic import HarmonicConfig, harmonic_field, photo_harmonics
from omninoise.backend.solid.model import plane_points
from omninoise.backend.solid.motif import (MIN_CELLS, MIN_PEAKS, fit_lattice, lattice_points, motif_waves, on_grid,
                                 refine_peaks, windowed_dtft, windowed_magnitude)
from test_solid_harmonic import brick_photo, waves_photo  # noqa: E402  (a sibling test module)

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BRICK = os.path.join(ROOT, "data", "photos", "val", "brick__tex_trak_trak4_brick2a.jpg")
PPU = 128.0


def field_at(h, H, W, dy=0, dx=0):
    """The harmonic field at the pixel centres of an (H, W) photo moved by (dy, dx) px: (H, W, 3)."""
    p = plane_points(max(H, W) + max(dy, dx), PPU).reshape(max(H, W) + max(dy, dx), -1, 2)
    return harmonic_field(p[dy:dy + H, dx:dx + W].reshape(-1, 2), h).reshape(H, W, 3)


def test_a_wave_between_bins_is_located_and_measured_exactly():
    """A colour wave at 12.37 and -5.81 cycles across a 112 x 96 photo (between bins on both axes): the Hann
    window's offset formula puts it within a hundredth of a bin, and the windowed transform there gives its colour
    amplitude and phase (D = A e^(i phi) / 2) to a percent."""
    H, W, fx, fy, phi = 96, 112, 12.37, -5.81, 0.8
    r, c = np.mgrid[0:H, 0:W].astype(np.float64)
    colour = np.array([0.2, 0.1, 0.05])
    u = (np.cos(2 * np.pi * (fx * c / W + fy * r / H) + phi)[..., None] * colour).transpose(2, 0, 1)
    M = windowed_magnitude(u)
    iy, ix = np.unravel_index(np.argmax(M * (np.fft.fftfreq(W, 1 / W)[None, :] > 0)), M.shape)
    gx, gy = refine_peaks(M, np.array([iy]), np.array([ix]))
    assert abs(gx[0] - fx) < 0.01 and abs(gy[0] - fy) < 0.01
    D = windowed_dtft(u, gx, gy)[0]
    assert np.allclose(D, colour * np.exp(1j * phi) / 2, rtol=0.01, atol=2e-4)
    # the bin nearest the wave is farther off: what the DFT's grid alone gives
    assert max(abs(round(fx) - fx), abs(round(fy) - fy)) > 0.15


def running_bond_peaks(b1=(3.625, 3.5), b2=(0.0, 7.0), noise=0.05, seed=0):
    """Peaks of a running bond's reciprocal lattice (bins), with noise, and decreasing powers."""
    rng = np.random.default_rng(seed)
    n = np.array([(0, 1), (0, 2), (0, 3), (2, -1), (4, -2), (1, 0), (3, -1), (1, 1), (-1, 2), (5, -2), (3, 0),
                  (0, 4), (6, -3)], np.float64)
    B = np.array([b1, b2])
    return n @ B + noise * rng.standard_normal((len(n), 2)), np.geomspace(1.0, 0.01, len(n)), B


def test_a_running_bond_lattice_is_found_from_noisy_peaks():
    F, w, B = running_bond_peaks()
    fit = fit_lattice(F, w)
    assert fit is not None and fit.shape == (2, 2)
    # the same lattice: the same cell area, and every true point within a twentieth of a bin of a fitted one
    assert abs(abs(np.linalg.det(fit)) - abs(np.linalg.det(B))) < 0.05 * abs(np.linalg.det(B))
    pts = np.array([(m, n) for m in range(-6, 7) for n in range(-6, 7)], np.float64) @ B
    coef = np.linalg.solve(fit.T, pts.T).T
    assert np.abs(np.round(coef) @ fit - pts).max() < 0.05 * 6
    assert not on_grid(fit)
    # the same peaks moved onto whole frequencies (a tileable photo) fit a lattice on the grid
    Bg = np.array([(4.0, 3.0), (0.0, 6.0)])
    n = np.linalg.solve(B.T, (F - 0.0).T).T.round()
    assert on_grid(fit_lattice(n @ Bg, w))


def test_peaks_without_a_lattice_fit_none_and_two_peaks_are_not_a_lattice():
    rng = np.random.default_rng(4)
    F = rng.uniform(-40, 40, (20, 2))
    assert fit_lattice(F, rng.uniform(0.1, 1.0, 20)) is None
    assert fit_lattice(np.array([(5.3, 2.1), (-7.7, 9.4)]), np.array([1.0, 0.5])) is None
    # stripes: multiples of one vector, as many as a lattice needs (MIN_PEAKS), and one fewer is not enough
    v = np.array([2.3, 6.1])
    k = np.arange(1, MIN_PEAKS[0] + 1)
    F = np.outer(k, v) + 0.03 * rng.standard_normal((len(k), 2))
    fit = fit_lattice(F, 1.0 / k)
    assert fit is not None and fit.shape == (1, 2) and np.allclose(np.abs(fit[0]), np.abs(v), atol=0.02)
    assert fit_lattice(F[:-1], 1.0 / k[:-1]) is None
    # stripes repeated fewer than twice across the photo are no motif (a 2D motif must repeat MIN_CELLS = 2 x 2)
    short = np.array([0.7, 1.5])
    assert fit_lattice(np.outer(k, short), 1.0 / k) is None and np.linalg.norm(short) < np.sqrt(MIN_CELLS)
    assert fit_lattice(np.outer(k, 1.4 * short), 1.0 / k) is not None


def test_lattice_points_fill_the_band_once_per_conjugate_pair():
    B = np.array([(3.625, 3.5), (0.0, 7.0)])
    P = lattice_points(B, 96, 112, 2)
    assert np.all(np.abs(P[:, 0]) < 56) and np.all(np.abs(P[:, 1]) < 48)
    assert np.all((P[:, 1] > 0) | ((P[:, 1] == 0) & (P[:, 0] > 0)))
    # no point is the conjugate of another, and no point of the band is missing: together with their conjugates
    # they are every lattice point in it but zero
    allp = np.concatenate([P, -P])
    assert len(np.unique(np.round(allp, 6), axis=0)) == len(allp)
    ref = np.array([(m, n) for m in range(-40, 41) for n in range(-40, 41) if (m, n) != (0, 0)], np.float64) @ B
    inside = (np.abs(ref[:, 0]) < 56) & (np.abs(ref[:, 1]) < 48) & (np.hypot(ref[:, 0] / 112, ref[:, 1] / 96) * 96 >= 2)
    assert len(allp) == inside.sum()


def test_a_brick_wall_framed_off_its_period_keeps_its_bricks_beyond_the_frame():
    """Bricks 32 x 16 px photographed in a 116 x 121 px frame (3.78 bricks, 7.25 courses: no period divides it).
    Read bin by bin, the harmonic part adds up to the photo inside the frame but drifts off the bond beyond it;
    the motif repeats the bond: 10 bricks and 10 courses further on, its field still matches the photo."""
    full = brick_photo(H=128, W=128, course=16, brick=32)
    img = full[:116, :121]
    lum = img.mean(2) - img.mean()
    motif, bins = photo_harmonics(img, PPU), photo_harmonics(img, PPU, HarmonicConfig(motif=False))
    assert motif.share > bins.share
    far = {k: field_at(h, 116, 121, dy=160, dx=320).mean(2) for k, h in (("motif", motif), ("bins", bins))}
    corr = {k: np.corrcoef(v.ravel(), lum.ravel())[0, 1] for k, v in far.items()}
    assert corr["motif"] > 0.8 and corr["bins"] < corr["motif"] - 0.2
    # inside the frame both give the photo back
    assert np.corrcoef(field_at(motif, 116, 121).mean(2).ravel(), lum.ravel())[0, 1] > 0.8


def test_tileable_photos_and_aperiodic_ones_are_read_as_before():
    for img in (brick_photo(), waves_photo()):      # whole periods in the frame: the bins are exact
        a, b = photo_harmonics(img, PPU), photo_harmonics(img, PPU, HarmonicConfig(motif=False))
        assert np.array_equal(a.freq, b.freq) and np.array_equal(a.amp, b.amp) and a.share == b.share
    rng = np.random.default_rng(3)
    F = np.fft.fft2(rng.standard_normal((128, 128)))
    f = np.hypot(*np.meshgrid(np.fft.fftfreq(128), np.fft.fftfreq(128)))
    rock = np.real(np.fft.ifft2(F / np.maximum(f, 1 / 128) ** 1.5))
    rock = np.repeat(((rock - rock.mean()) / rock.std() * 0.1 + 0.5)[..., None], 3, 2)[:117, :123]
    a, b = photo_harmonics(rock, PPU), photo_harmonics(rock, PPU, HarmonicConfig(motif=False))
    assert np.array_equal(a.freq, b.freq) and a.share == b.share
    # even handed the 24 largest bins of its spectrum (a cluster round zero, not peaks), no lattice is taken:
    # a motif must repeat at least MIN_CELLS times in the photo
    u = (rock - rock.mean((0, 1))).transpose(2, 0, 1)
    peaks = np.argsort(-windowed_magnitude(u).ravel())[:24]
    assert motif_waves(u, peaks, np.ones(24), 2, 256, 1e-4) is None


def test_a_photographed_brick_wall_repeats_by_its_own_lattice():
    """The held-out red brick photo cropped to 224 x 232 px (its courses and bricks no longer divide the frame):
    the harmonic part holds more of the photo's variance than the bins did (0.89 against 0.71 when measured), and
    its waves lie on one lattice, so its field repeats exactly by the lattice's translations."""
    from omninoise.export import read_rgb

    img = read_rgb(BRICK)[8:232, 8:240]
    H, W = img.shape[:2]
    h, bins = photo_harmonics(img, PPU), photo_harmonics(img, PPU, HarmonicConfig(motif=False))
    assert h.share > bins.share + 0.1 and len(h) > 50
    f = np.stack([h.freq[:, 0] / PPU * W, -h.freq[:, 1] / PPU * H], 1)      # back to cycles per photo
    B = fit_lattice(f, (np.abs(h.amp) ** 2).sum(1), tol=1e-6, explained=1.0, explained_count=1.0)
    assert B is not None and B.shape == (2, 2) and not on_grid(B)
    rng = np.random.default_rng(0)
    q = rng.uniform(-20, 20, (500, 2))
    for j in range(2):      # t with b_i . (tx / W, ty / H) = delta_ij: one step of the spatial lattice, px
        tx, ty = np.linalg.solve(B, np.eye(2)[j]) * (W, H)
        moved = harmonic_field(q + (tx / PPU, -ty / PPU), h)
        assert np.abs(moved - harmonic_field(q, h)).max() < 1e-3
    # its cell is one brick: 64 x 32 px (the uncropped photo holds 4 bricks a course and 8 courses)
    assert abs(W * H / abs(np.linalg.det(B)) - 64 * 32) < 0.02 * 64 * 32
