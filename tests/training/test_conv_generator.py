"""training/solid/conv_generator.py and conv_fit.py: the multi-scale convolutional generator is periodic (a
circular shift of its noise shifts its texture), sees a neighbourhood (unlike the per-point decoder), refuses bad
input with one line, a short fit learns a photo's orientation in 2D and in 3D slices, and a fit resumes exactly."""
import numpy as np
import pytest

torch = pytest.importorskip("torch")

from omninoise.training.solid.conv_fit import FIT_TO, colour, fit, volume_slices  # noqa: E402
from omninoise.training.solid.conv_generator import ConvGenerator, draw_noise  # noqa: E402
from omninoise.training.solid.model import colour_stats  # noqa: E402
from omninoise.training.solid.swd import SlicedFeatures, swd_loss  # noqa: E402


@pytest.mark.parametrize("dim,grow", [(2, True), (2, False), (3, False)])
def test_shapes_and_periodicity(dim, grow):
    torch.manual_seed(0)
    net = ConvGenerator(dim, scales=3, noise=2, width=4, grow=grow).eval()
    z = draw_noise(2, 16, dim, 3, 2, torch.Generator().manual_seed(1))
    assert [t.shape for t in z] == [torch.Size((2, 2) + (16 >> k,) * dim) for k in range(3)]
    with torch.no_grad():
        d = net(z)
        # shift every scale's noise by 4 / 2^k cells along the last axis: the texture moves by 4 px, wrapping
        shifted = net([torch.roll(t, 4 >> k, dims=-1) for k, t in enumerate(z)])
    assert d.shape == (2, 3) + (16,) * dim and d.dtype == torch.float32
    torch.testing.assert_close(shifted, torch.roll(d, 4, dims=-1), atol=1e-5, rtol=1e-5)
    assert d.std() > 1e-3


def test_a_point_sees_its_neighbourhood_and_across_the_border():
    torch.manual_seed(0)
    net = ConvGenerator(2, scales=2, noise=2, width=4).eval()
    z = draw_noise(1, 16, 2, 2, 2, torch.Generator().manual_seed(1))
    z2 = [t.clone() for t in z]
    z2[0][0, :, 0, 0] += 1.0           # one finest-scale noise value at the corner
    with torch.no_grad():
        change = (net(z2) - net(z)).abs().sum(1)[0]
    assert change[0, 0] > 0 and change[1, 1] > 0        # the point and its neighbours
    assert change[-1, -1] > 0                            # wrapping: the opposite corner is a neighbour too
    assert change[8, 8] == 0                             # far points do not see it at the finest scale


def test_bad_input_is_refused():
    with pytest.raises(ValueError, match="dim must be 2 or 3"):
        ConvGenerator(4)
    with pytest.raises(ValueError, match="scales"):
        ConvGenerator(2, scales=0)
    with pytest.raises(ValueError, match="not divisible"):
        draw_noise(1, 20, 2, 4, 2, torch.Generator())
    with pytest.raises(ValueError, match="3 scales, got 2"):
        ConvGenerator(2, scales=3, noise=2, width=4)(draw_noise(1, 16, 2, 2, 2, torch.Generator()))


def test_colour_and_slices():
    photo = torch.rand(3, 8, 8)
    stats = colour_stats(photo.unsqueeze(0))
    d = torch.zeros(2, 3, 4, 4)
    torch.testing.assert_close(colour(d, stats)[1, :, 2, 3], photo.mean((1, 2)))
    vol = torch.arange(2 * 3 * 4 ** 3, dtype=torch.float32).view(2, 3, 4, 4, 4)
    s = volume_slices(vol, torch.Generator().manual_seed(0))
    assert s.shape == (6, 3, 4, 4)
    i, j, k = (int(v) for v in torch.randint(0, 4, (3,), generator=torch.Generator().manual_seed(0)))
    torch.testing.assert_close(s[0], vol[0, :, i])
    torch.testing.assert_close(s[3], vol[1, :, :, :, k])
    torch.testing.assert_close(s[5], vol[1, :, :, j])
    walls = volume_slices(vol, torch.Generator().manual_seed(0), upright=True)
    assert walls.shape == (4, 3, 4, 4)
    torch.testing.assert_close(walls[1], vol[1, :, :, :, k])        # normal to x: rows are z
    torch.testing.assert_close(walls[2], vol[0, :, :, j])           # normal to y: rows are z


class _Cfg:
    crop, batch, lr, lr_min, seed, log_every = 16, 2, 5e-3, 1e-3, 0, 1000


def _stripes(size=48, period=6):
    """Horizontal dark and light bands (rows constant): structure with one orientation."""
    rows = (np.arange(size) % period < period // 2).astype(np.float32)
    img = np.repeat(rows[:, None], size, 1)
    return torch.from_numpy(np.stack([0.2 + 0.6 * img, 0.3 + 0.4 * img, 0.5 - 0.3 * img]))


def _anisotropy(img: torch.Tensor) -> float:
    """Energy of differences across rows over that along rows: >> 1 for horizontal bands, ~1 for isotropic."""
    dy = (img[..., 1:, :] - img[..., :-1, :]).square().mean()
    dx = (img[..., :, 1:] - img[..., :, :-1]).square().mean()
    return float(dy / dx)


def _loss(cfg, feats, img, ref, g):
    return swd_loss(feats, img, ref, generator=g)


@pytest.mark.parametrize("dim,steps,upright", [(2, 150, False), (3, 40, False), (3, 120, True)])
def test_a_short_fit_learns_the_photos_orientation(dim, steps, upright):
    torch.manual_seed(0)
    photo = _stripes()
    net = ConvGenerator(dim, scales=2, noise=2, width=8, grow=False)
    feats = SlicedFeatures(seed=0, levels=2, width=8, kernels=(3,))
    stats = colour_stats(photo.unsqueeze(0))

    def sample():
        with torch.no_grad():
            out = colour(net(draw_noise(2, 16, dim, 2, 2, torch.Generator().manual_seed(5))), stats)
        return out if dim == 2 else volume_slices(out, torch.Generator().manual_seed(6), upright)

    first = sample()
    before = _loss(_Cfg, feats, first, photo[None, :, :16, :16].expand(first.shape[0], -1, -1, -1),
                   torch.Generator().manual_seed(7))
    fit(_Cfg, net, photo, steps, feats, _loss, log=lambda s: None, upright=upright)
    imgs = sample()
    after = _loss(_Cfg, feats, imgs, photo[None, :, :16, :16].expand(imgs.shape[0], -1, -1, -1),
                  torch.Generator().manual_seed(7))
    assert after < 0.5 * before
    if dim == 2 or upright:   # horizontal bands, as in the photo: in 2D, and on both walls of an upright solid
        assert min(_anisotropy(s) for s in imgs) > 3.0
    else:            # 3D crops are turned at random, so no solid can band every slice; the slices keep contrast
        assert float(imgs.std((2, 3)).mean()) > 0.5 * float(photo.std((1, 2)).mean())


def test_a_time_budget_sets_the_number_of_steps():
    torch.manual_seed(0)
    net = ConvGenerator(2, scales=2, noise=2, width=4, grow=False)
    feats = SlicedFeatures(seed=0, levels=2, width=4, kernels=(3,))
    lines = []
    seconds, steps = fit(_Cfg, net, _stripes(), 1000, feats, _loss, log=lines.append, budget_seconds=0.0)
    assert steps == FIT_TO and any("steps fit in 0 s" in s for s in lines)
    seconds, steps = fit(_Cfg, net, _stripes(), 30, feats, _loss, log=lines.append, budget_seconds=1e6)
    assert steps == 30          # never more than asked


def test_a_fit_stopped_and_resumed_ends_where_one_run_straight_through_ends():
    feats = SlicedFeatures(seed=0, levels=2, width=4, kernels=(3,))

    def fresh():
        torch.manual_seed(0)
        return ConvGenerator(3, scales=2, noise=2, width=4, grow=False)

    straight = fresh()
    fit(_Cfg, straight, _stripes(), 6, feats, _loss, log=lambda s: None, upright=True)
    saved = []
    first = fresh()
    fit(_Cfg, first, _stripes(), 6, feats, _loss, log=lambda s: None, upright=True,
        save=saved.append, save_every=4)      # kept as handed out: a checkpoint is a copy
    assert [c["step"] for c in saved] == [4, 6] and all(c["steps"] == 6 for c in saved)
    resumed = fresh()         # from step 4: the steps asked for now are the checkpoint's schedule, not these
    seconds, steps = fit(_Cfg, resumed, _stripes(), 1000, feats, _loss, log=lambda s: None, upright=True,
                         resume=saved[0])
    assert steps == 6
    for a, b in zip(straight.state_dict().values(), resumed.state_dict().values()):
        torch.testing.assert_close(a, b, rtol=0, atol=0)
    cut = fresh()             # the resumed fit did not just redo the run: two steps fewer land elsewhere
    fit(_Cfg, cut, _stripes(), 6, feats, _loss, log=lambda s: None, upright=True, resume=dict(saved[0], step=6))
    assert any(not torch.equal(a, b) for a, b in zip(straight.state_dict().values(), cut.state_dict().values()))
