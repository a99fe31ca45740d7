"""The power-spectrum band term of the solid-texture loss (training/solid/spectrum.py)."""
import math

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from omninoise.training.solid.spectrum import band_index, band_shares, spectrum_loss  # noqa: E402
from omninoise.training.solid.train import SolidConfig, loss_features, texture_loss  # noqa: E402


def _smooth_noise(seed: int, size: int = 96, sigma: float = 3.0) -> torch.Tensor:
    """Grey Gaussian-filtered white noise (1, 3, size, size) in [0, 1]: blobs about ``sigma`` px wide."""
    g = torch.Generator().manual_seed(seed)
    w = torch.randn(1, 1, size, size, generator=g)
    f = torch.fft.fftfreq(size)
    H = torch.exp(-2 * (math.pi * sigma) ** 2 * (f.view(-1, 1) ** 2 + f.view(1, -1) ** 2))
    y = torch.fft.ifft2(torch.fft.fft2(w) * H).real
    y = 0.5 + 0.15 * y / y.std()
    return y.clamp(0, 1).expand(1, 3, size, size).contiguous()


def _stripes(size: int = 96, period: float = 12.0, vertical: bool = False, shift: float = 0.0) -> torch.Tensor:
    u = torch.arange(size, dtype=torch.float32)
    wave = 0.5 + 0.3 * torch.sin(2 * math.pi * (u + shift) / period)
    img = wave.view(1, -1).expand(size, size) if vertical else wave.view(-1, 1).expand(size, size)
    return img.expand(1, 3, size, size).contiguous()


def test_bands_cover_every_coefficient_but_dc_and_shares_sum_to_one():
    idx = band_index(128, 128, radial=8, angular=4)
    assert idx.shape == (128, 65) and idx[0, 0] == -1 and (idx >= 0).sum() == 128 * 65 - 1
    assert set(idx[idx >= 0].tolist()) == set(range(32))          # no empty band at 128 px
    p = band_shares(torch.rand(2, 3, 128, 128))
    assert p.shape == (2, 32) and torch.allclose(p.sum(1), torch.ones(2)) and (p >= 0).all()
    # odd sides too
    assert band_shares(torch.rand(1, 3, 75, 91)).shape == (1, 32)


def test_zero_for_the_same_texture_and_blind_to_contrast_and_mean():
    x = _smooth_noise(0)
    assert spectrum_loss(x, x).item() == 0.0
    dim = 0.3 + 0.2 * (x - 0.5)                    # another mean, 40 % of the contrast: the same shares
    assert spectrum_loss(dim, x).item() < 1e-8


def test_prefers_another_draw_of_the_texture_to_speckle_or_other_sizes():
    ref, other = _smooth_noise(0), _smooth_noise(1)
    g = torch.Generator().manual_seed(2)
    speckle = (0.5 + 0.15 * torch.randn(1, 1, 96, 96, generator=g)).expand(1, 3, 96, 96)
    coarse = _smooth_noise(1, sigma=8.0)
    same = spectrum_loss(other, ref).item()
    assert same < 0.1 * spectrum_loss(speckle, ref).item()
    assert same < 0.1 * spectrum_loss(coarse, ref).item()
    # the speckle's excess is at the finest rings: adding it to the texture raises the loss
    assert spectrum_loss(0.7 * other + 0.3 * speckle, ref).item() > 5 * same


def test_sees_orientation_not_position():
    h = _stripes()
    assert spectrum_loss(_stripes(shift=5.0), h).item() < 1e-3
    assert spectrum_loss(_stripes(vertical=True), h).item() > 1.0


def test_per_sample_and_pooled_references_and_gradients():
    refs = torch.cat([_smooth_noise(0), _stripes()])
    out = torch.cat([_smooth_noise(3), _stripes(shift=2.0)]).requires_grad_()
    paired = spectrum_loss(out, refs, per_sample=True)
    pooled = spectrum_loss(out, refs, per_sample=False)
    assert paired.item() < 0.2 * pooled.item()       # each output against its own reference
    paired.backward()
    assert torch.isfinite(out.grad).all() and out.grad.abs().sum() > 0


def test_config_weight_enters_the_training_loss():
    base = dict(mode="single", dim=2, exemplars=["gravel"], loss="swd", swd_width=4, swd_levels=3)
    off, on = SolidConfig.from_dict(base), SolidConfig.from_dict(dict(base, spectrum_weight=0.5))
    img, ref = _smooth_noise(0), _smooth_noise(1, sigma=8.0)
    feats = loss_features(off)
    a = texture_loss(off, feats, img, ref, torch.Generator().manual_seed(0)).item()
    b = texture_loss(on, feats, img, ref, torch.Generator().manual_seed(0)).item()
    assert b - a == pytest.approx(0.5 * spectrum_loss(img, ref).item(), rel=1e-4)
    for bad in (-0.1, float("nan")):
        with pytest.raises(ValueError, match="spectrum_weight"):
            SolidConfig.from_dict(dict(base, spectrum_weight=bad))


def test_random_phase_of_a_photo_keeps_its_bands():
    """Random phase noise keeps a photo's Fourier modulus: its band shares stay near the photo's, a pixel
    shuffle's do not."""
    from omninoise.training.solid import photo_eval as pe
    from omninoise.training.solid import exemplars as ex

    photo = ex.photo_set("val")[0]
    img = np.asarray(ex.exemplar(photo).permute(1, 2, 0), np.float32)[:128, :128]
    rng = np.random.default_rng(0)
    t = lambda a: torch.from_numpy(np.ascontiguousarray(a)).permute(2, 0, 1)[None]  # noqa: E731
    ref = t(img)
    rp = spectrum_loss(t(pe.random_phase(img, 128, rng)), ref).item()
    shuffle = spectrum_loss(t(pe.pixel_shuffle(img, 128, rng)), ref).item()
    assert rp < 0.25 * shuffle
