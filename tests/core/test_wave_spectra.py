"""Spectral evidence for wave noise (Guehl et al. 2025, Sec. 4, 5 and Fig. 20)."""
import numpy as np
import pytest

from omninoise.backend import Spectrum, WaveSettings, compile_noise, evaluate_grid
from omninoise.backend.grid import evaluate_points
from conftest import radial_psd

E, N = 4.0, 256


def img(settings, size=N, extent=E, time=0.0):
    return evaluate_grid(compile_noise(settings), size, extent, settings.output, time, settings.cellular)


@pytest.mark.parametrize("dim", [2, 3])
def test_bandpass_power_inside_band(dim):
    s = WaveSettings(dim=dim, spectrum=Spectrum("bandpass", 6.0, 12.0), directions=16, seed=4)
    n = 96 if dim == 3 else N
    a = img(s, size=n)
    # the n-D spectrum (a 2D slice of a 3D shell would project power to lower radii)
    F = np.abs(np.fft.fftn(a - a.mean())) ** 2
    f = np.fft.fftfreq(n, d=E / n)
    R = np.sqrt(sum(g ** 2 for g in np.meshgrid(*([f] * dim), indexing="ij")))
    inside = F[(R >= 6.0) & (R <= 12.0)].sum() / F.sum()
    assert inside > 0.85, inside


def reference_field(spectrum, n, extent, rng):
    """Inverse-FFT reference: random phases, amplitude A(|xi|) on the FFT grid."""
    f = np.fft.fftfreq(n, d=extent / n)
    R = np.hypot(*np.meshgrid(f, f, indexing="ij"))
    c = spectrum.amplitude(R) * np.exp(2j * np.pi * rng.random((n, n)))
    return np.fft.ifft2(c).real


def smoothed_psd(images) -> np.ndarray:
    """Periodogram of standardised images, summed over the images and a 5x5 box of bins (periodic)."""
    P = 0.0
    for a in images:
        P = P + np.abs(np.fft.fft2((a - a.mean()) / a.std())) ** 2
    return sum(np.roll(np.roll(P, i, 0), j, 1) for i in range(-2, 3) for j in range(-2, 3))


def log_psd_error(images, ref, lo, hi):
    """RMS of log(PSD / reference PSD) over the 2D frequency bins with lo <= |xi| <= hi, scale removed.

    The 2D spectrum, not its radial average: a few directions put the power in a
    few angular lobes, which a radial average would hide (Fig. 20)."""
    f = np.fft.fftfreq(N, d=E / N)
    R = np.hypot(*np.meshgrid(f, f, indexing="ij"))
    band = (R >= lo) & (R <= hi)
    r = np.log(smoothed_psd(images)[band]) - np.log(smoothed_psd([ref])[band])
    return float(np.sqrt(np.mean((r - r.mean()) ** 2)))


def test_log_psd_error_falls_with_directions():
    spec = Spectrum("gaussian", 3.0, 12.0)
    ref = reference_field(spec, N, E, np.random.default_rng(0))
    errs = {k: log_psd_error([img(WaveSettings(dim=2, spectrum=spec, directions=k, seed=seed)) for seed in range(3)],
                             ref, 4.0, 11.0) for k in (1, 4, 32)}
    assert errs[32] < 0.9 * errs[4] < 0.9 * 0.5 * errs[1], errs
    assert errs[32] < 0.45, errs


def angular_power(a, lo, hi, sectors=8):
    _, _, F, R, f = radial_psd(a, E)
    FX, FY = np.meshgrid(f, f, indexing="ij")
    ang = np.mod(np.arctan2(FY, FX), np.pi)
    band = (R >= lo) & (R <= hi)
    sec = np.minimum((ang / np.pi * sectors).astype(int), sectors - 1)
    return np.array([F[band & (sec == s)].sum() for s in range(sectors)]) / F[band].sum()


def test_isotropic_angular_power_is_flat():
    p = np.mean([angular_power(img(WaveSettings(dim=2, spectrum=Spectrum("bandpass", 6, 12),
                                                directions=32, seed=s)), 6, 12) for s in range(3)], axis=0)
    assert p.max() / p.min() < 1.6, p


def test_lobes_concentrate_angular_power():
    # one lobe around the x axis, +-15 degrees: the image's spectrum sits at angle 0 (mod pi)
    s = WaveSettings(dim=2, spectrum=Spectrum("bandpass", 6, 12), directions=16, seed=1,
                     anisotropy="lobes", lobes=(((1.0, 0.0), 1.0),), spread=15.0)
    a = img(s)
    p = angular_power(a.T, 6, 12)  # arrays are (y, x): transpose so axis 0 is x
    assert p[0] + p[-1] > 0.8, p


def test_axis_tables_make_axis_dependent_spectra():
    s = WaveSettings(dim=2, directions=32, seed=2, anisotropy="axes",
                     axis_spectra=(Spectrum("bandpass", 10, 14), Spectrum("bandpass", 3, 5)))
    a = img(s)  # (y, x)
    fx = np.abs(np.fft.fft(a, axis=1)) ** 2
    fy = np.abs(np.fft.fft(a, axis=0)) ** 2
    freqs = np.fft.fftfreq(N, d=E / N)
    mean_fx = np.sum(np.abs(freqs)[None, :] * fx) / fx.sum()
    mean_fy = np.sum(np.abs(freqs)[:, None] * fy) / fy.sum()
    assert mean_fx > 1.5 * mean_fy, (mean_fx, mean_fy)


def test_animated_psd_preserved_over_time():
    s = WaveSettings(dim=2, spectrum=Spectrum("bandpass", 6, 12), directions=16, seed=3, speed=0.5)
    a0, a1 = img(s, time=0.0), img(s, time=2.0)
    f, p0, *_ = radial_psd(a0, E)
    _, p1, *_ = radial_psd(a1, E)
    band = (f >= 6) & (f <= 12)
    rel = np.linalg.norm(p0[band] - p1[band]) / np.linalg.norm(p0[band])
    assert rel < 0.35, rel
    assert abs(np.corrcoef(a0.ravel(), a1.ravel())[0, 1]) < 0.5  # it moved
    # small time steps move continuously
    a_eps = img(s, time=0.01)
    assert np.corrcoef(a0.ravel(), a_eps.ravel())[0, 1] > 0.95


def test_variance_independent_of_direction_count():
    v = []
    for k in (4, 16, 64):
        vals = [img(WaveSettings(dim=2, spectrum=Spectrum("bandpass", 6, 12), directions=k, seed=s), size=128).var()
                for s in range(4)]
        v.append(np.mean(vals))
    assert max(v) / min(v) < 1.3, v
    assert 0.3 < np.mean(v) < 0.7  # E|N|^2 = 1 -> Var(Re N) = 0.5


def test_large_coordinates_do_not_collapse():
    s = WaveSettings(dim=3, spectrum=Spectrum("bandpass", 4, 8), directions=16, seed=5)
    noise = compile_noise(s)
    g = np.arange(128, dtype=np.float32) * np.float32(2.0 / 128)
    for origin in (0.0, 1.0e4):
        x = np.stack(np.meshgrid(g, g, indexing="ij"), -1).reshape(-1, 2) + np.float32(origin)
        pts = np.concatenate([x, np.full((len(x), 1), np.float32(origin))], 1)
        a = evaluate_points(noise, pts, "real").reshape(128, 128)
        f, p, F, R, _ = radial_psd(a, 2.0)
        assert 0.25 < a.var() < 0.9, (origin, a.var())
        assert F[(R >= 3) & (R <= 9)].sum() / F.sum() > 0.7, origin


def test_four_d_is_continuous_in_w():
    s = WaveSettings(dim=4, spectrum=Spectrum("bandpass", 4, 8), directions=32, seed=6)
    noise = compile_noise(s)
    a = evaluate_grid(noise, 48, 2.0, time=0.0)[:, :, 0]
    b = evaluate_grid(noise, 48, 2.0, time=0.005)[:, :, 0]
    c = evaluate_grid(noise, 48, 2.0, time=3.0)[:, :, 0]
    assert np.corrcoef(a.ravel(), b.ravel())[0, 1] > 0.95
    assert abs(np.corrcoef(a.ravel(), c.ravel())[0, 1]) < 0.3


def test_outputs_real_imag_modulus_phase():
    base = WaveSettings(dim=2, spectrum=Spectrum("bandpass", 4, 8), directions=8, seed=7)
    re, im = img(base, size=64), img(base.replace(output="imag"), size=64)
    mod, ph = img(base.replace(output="modulus"), size=64), img(base.replace(output="phase"), size=64)
    assert np.allclose(mod, np.hypot(re, im), atol=1e-5)
    assert np.allclose(ph, np.arctan2(im, re), atol=1e-5)
    assert ph.min() >= -np.pi and ph.max() <= np.pi and mod.min() >= 0


def test_transition_moves_frequency_content():
    s = WaveSettings(dim=2, spectrum=Spectrum("bandpass", 3, 5), directions=32, seed=8,
                     transition_to=Spectrum("bandpass", 10, 14), transition_origin=(0.0, 0.0),
                     transition_axis=(1.0, 0.0), transition_length=E)
    a = img(s)  # (y, x); frequency rises with x
    left, right = a[:, :48], a[:, -48:]

    def mean_freq(block):
        F = np.abs(np.fft.fft(block - block.mean(), axis=0)) ** 2
        fr = np.abs(np.fft.fftfreq(block.shape[0], d=E / N))
        return np.sum(fr[:, None] * F) / F.sum()

    assert mean_freq(right) > 1.8 * mean_freq(left)
