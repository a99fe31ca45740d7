"""The arrangement features and the soft level-set morphology term of the solid-texture loss."""
import numpy as np
import pytest

torch = pytest.importorskip("torch")

from omninoise.training.solid.arrangement import ArrangementFeatures, gaussianise, luminance  # noqa: E402
from omninoise.training.solid.morphology import morphology_distance  # noqa: E402
from omninoise.training.solid.photo_eval import voronoi_pavement  # noqa: E402
from omninoise.training.solid.soft_morphology import soft_curves, soft_functionals, soft_morphology_loss  # noqa: E402
from omninoise.training.solid.train import SolidConfig, loss_features, texture_loss  # noqa: E402

torch.set_num_threads(2)


def _t(img: np.ndarray) -> torch.Tensor:
    """(H, W) or (H, W, 3) numpy -> (1, 3, H, W) float32."""
    a = np.asarray(img, np.float32)
    if a.ndim == 2:
        a = np.repeat(a[..., None], 3, -1)
    return torch.from_numpy(a).permute(2, 0, 1)[None].contiguous()


def _speckle(size: int, rng) -> np.ndarray:
    """Pixel noise blurred over about one pixel: the model's speckle."""
    a = rng.random((size + 2, size + 2))
    return ((a[1:-1, 1:-1] * 2 + a[:-2, 1:-1] + a[2:, 1:-1] + a[1:-1, :-2] + a[1:-1, 2:]) / 6).astype(np.float32)


@pytest.mark.parametrize("pixels, perim, chi", [
    ([(2, 2)], 4, 1),                                                      # one pixel: 4 edges, one component
    ([(2, 2), (3, 3)], 8, 1),                                              # diagonal pair: 8-connected, one component
    ([(1, 1), (1, 2), (1, 3), (2, 1), (2, 3), (3, 1), (3, 2), (3, 3)], 16, 0),   # a ring: one component, one hole
    ([(1, 1), (4, 4)], 8, 2),                                              # two apart
])
def test_soft_functionals_equal_the_hard_counts_on_binary_images(pixels, perim, chi):
    b = torch.zeros(6, 6, dtype=torch.float64)
    for y, x in pixels:
        b[y, x] = 1
    p, c = soft_functionals(b)
    assert p.item() == pytest.approx(perim / 36) and c.item() == pytest.approx(chi / 36)


def test_soft_curves_approach_the_evaluation_measure_as_tau_shrinks():
    rng = np.random.default_rng(3)
    a, b = voronoi_pavement(64, 12, rng), _speckle(64, rng)
    hard = morphology_distance(a, b)
    soft = soft_morphology_loss(_t(a).double(), _t(b).double(), tau=1e-6).item()
    assert soft == pytest.approx(hard, abs=0.03)          # only the quantile's definition differs (rank vs interpolated)


def test_blind_to_colour_and_contrast_and_at_full_resolution_to_tone_curves():
    rng = np.random.default_rng(4)
    img, ref = _t(voronoi_pavement(64, 12, rng)), _t(voronoi_pavement(64, 12, rng))
    tinted = img * torch.tensor([0.3, 0.8, 0.5]).view(1, 3, 1, 1) + 0.1          # colour and contrast
    assert soft_morphology_loss(tinted, ref).item() == pytest.approx(soft_morphology_loss(img, ref).item(), abs=1e-6)
    # a tone curve keeps the ranks of the full-resolution level (coarser levels blur before ranking)
    curved = img ** 2.2
    assert soft_morphology_loss(curved, ref, levels=1).item() == \
        pytest.approx(soft_morphology_loss(img, ref, levels=1).item(), abs=1e-6)
    feats = ArrangementFeatures(width=8, levels=3)
    for fa, fb in zip(feats(img), feats(curved)):
        assert torch.allclose(fa, fb, atol=1e-6)


def test_stones_are_nearer_to_stones_than_speckle_is():
    rng = np.random.default_rng(5)
    ref = torch.cat([_t(voronoi_pavement(96, 16, rng)) for _ in range(2)])
    stones = torch.cat([_t(voronoi_pavement(96, 16, rng)) for _ in range(2)])
    speckle = torch.cat([_t(_speckle(96, rng)) for _ in range(2)])
    near, far = soft_morphology_loss(stones, ref).item(), soft_morphology_loss(speckle, ref).item()
    assert near * 3 < far, (near, far)


def test_gaussianise_gives_exact_normal_quantiles_and_the_standardisation_gradient():
    y = torch.tensor([[[[0.3, 0.1], [0.9, 0.5]]]], requires_grad=True)
    g = gaussianise(y)
    q = torch.special.ndtri((torch.arange(4, dtype=torch.float64) + 0.5) / 4).float()
    assert torch.allclose(g.flatten(), q[[1, 0, 3, 2]])
    g.flatten()[2].backward()                       # d g(p) / d y = d ((y(p) - mean) / std) / d y
    ref = y.detach().clone().requires_grad_(True)
    ((ref - ref.mean()) / ref.flatten().std()).flatten()[2].backward()
    assert torch.allclose(y.grad, ref.grad)
    assert luminance(torch.ones(1, 3, 2, 2)).shape == (1, 1, 2, 2)


def test_pixels_optimised_with_the_term_move_from_speckle_towards_stones():
    rng = np.random.default_rng(6)
    ref = torch.cat([_t(voronoi_pavement(64, 12, rng)) for _ in range(2)])
    x = _t(_speckle(64, rng)).requires_grad_(True)
    opt = torch.optim.Adam([x], lr=0.02)
    before = soft_morphology_loss(x, ref).item()
    for _ in range(40):
        loss = soft_morphology_loss(x, ref)
        opt.zero_grad()
        loss.backward()
        opt.step()
    after = soft_morphology_loss(x.detach(), ref).item()
    assert np.isfinite(after) and after < 0.7 * before, (before, after)


def test_config_weight_enters_the_training_loss_and_bad_weights_are_refused():
    rng = np.random.default_rng(7)
    img, ref = _t(_speckle(64, rng)), _t(voronoi_pavement(64, 12, rng))
    base = dict(mode="single", exemplars=["gravel"], loss="swd", swd_width=4, swd_levels=3)
    off, on = SolidConfig.from_dict(base), SolidConfig.from_dict({**base, "morphology_weight": 0.5})
    feats = loss_features(off)
    l0 = texture_loss(off, feats, img, ref, torch.Generator().manual_seed(0)).item()
    l1 = texture_loss(on, feats, img, ref, torch.Generator().manual_seed(0)).item()
    assert l1 == pytest.approx(l0 + 0.5 * soft_morphology_loss(img, ref).item(), rel=1e-5)
    for bad in (-1.0, float("nan")):
        with pytest.raises(ValueError, match="morphology_weight"):
            SolidConfig.from_dict({**base, "morphology_weight": bad})


def test_soft_curves_shape():
    c = soft_curves(torch.rand(2, 3, 48, 48), levels=3)
    assert c.shape == (2, 3, 2, 9) and torch.isfinite(c).all()
