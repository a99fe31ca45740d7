"""training/solid/structure_features.py: random-phase twins keep the histogram and the spectrum, the network learns
to tell a structured image from its twin, and the training loss takes the term only with a network file."""
import numpy as np
import pytest

torch = pytest.importorskip("torch")

from omninoise.backend.periodic import periodic_component  # noqa: E402
from omninoise.training.evaluate import radial_psd  # noqa: E402
from omninoise.training.solid.structure_features import (StructureFeatures, StructureNet, load_structure_net,  # noqa: E402
                                               phase_randomised, structure_batch, train_structure_net)


def squares(n, size, rng):
    """Images of scattered hard-edged squares: a structure that random phases destroy."""
    out = np.zeros((n, 3, size, size), np.float32)
    for i in range(n):
        for _ in range(6):
            y, x, s = rng.integers(0, size - 12), rng.integers(0, size - 12), rng.integers(6, 12)
            out[i, :, y:y + s, x:x + s] = rng.uniform(0.5, 1.0)
        out[i] += 0.02 * rng.standard_normal((3, size, size)).astype(np.float32)
    return [torch.from_numpy(im) for im in out]


def test_twins_keep_the_histogram_exactly_and_the_spectrum_closely():
    rng = np.random.default_rng(0)
    g = np.stack([im[0].numpy().astype(np.float64) for im in squares(3, 64, rng)])
    t = phase_randomised(g, rng)
    np.testing.assert_array_equal(np.sort(t, axis=None), np.sort(g.astype(np.float32), axis=None))
    for a, b in zip(g, t):
        np.testing.assert_array_equal(np.sort(a.astype(np.float32), axis=None), np.sort(b, axis=None))
    pa, pb = radial_psd(periodic_component(g)), radial_psd(periodic_component(t.astype(np.float64)))
    assert np.corrcoef(np.log(pa), np.log(pb))[0, 1] > 0.9
    assert np.abs(t - g).mean() > 0.1  # but not the same image


def test_the_network_learns_to_tell_structure_from_its_twin_and_feeds_the_loss(tmp_path):
    rng = np.random.default_rng(1)
    train, val = squares(24, 56, rng), squares(8, 56, rng)
    x, y = structure_batch(train, 4, 48, np.random.default_rng(2))
    assert x.shape == (8, 1, 48, 48) and y.tolist() == [1, 1, 1, 1, 0, 0, 0, 0]
    net, record = train_structure_net(train, val, steps=40, batch=12, size=48, width=8, log=lambda s: None)
    assert record["val_accuracy"] >= 0.7, record  # chance is 0.5 (one step of training: 0.5)
    taps = net.taps(x)
    assert [t.shape[1] for t in taps] == [8, 16, 32] and taps[0].shape[-1] == 48 - 6
    path = tmp_path / "net.pt"
    torch.save(dict(weights=net.state_dict(), record=record), path)
    again = load_structure_net(str(path))
    torch.testing.assert_close(again(x), net(x))
    feats = StructureFeatures(again)
    img = torch.rand(2, 3, 64, 64, requires_grad=True)
    taps = feats(img)
    sum(t.mean() for t in taps).backward()
    assert img.grad is not None and float(img.grad.abs().sum()) > 0
    assert all(not p.requires_grad for p in feats.parameters())


def test_the_training_loss_takes_the_structure_term_only_with_a_network(tmp_path):
    from omninoise.training.solid.train import SolidConfig, loss_features, texture_loss

    base = dict(mode="single", dim=2, exemplars=["data/photos/val/brick__beige_bricks.jpg"], loss="swd",
                colour="affine")
    with pytest.raises(ValueError, match="structure_net"):
        SolidConfig.from_dict({**base, "structure_weight": 0.2})
    with pytest.raises(ValueError, match="structure_weight"):
        SolidConfig.from_dict({**base, "structure_weight": -1.0})
    path = tmp_path / "net.pt"
    missing = SolidConfig.from_dict({**base, "structure_weight": 0.5, "structure_net": str(tmp_path / "none.pt")})
    with pytest.raises(ValueError, match="no trained structure network"):  # configs parse; the loss needs the file
        texture_loss(missing, loss_features(missing), torch.rand(1, 3, 32, 32), torch.rand(1, 3, 32, 32),
                     torch.Generator().manual_seed(0))
    torch.save(dict(weights=StructureNet(4).state_dict(), record=dict(width=4)), path)
    plain = SolidConfig.from_dict(base)
    with_term = SolidConfig.from_dict({**base, "structure_weight": 0.5, "structure_net": str(path)})
    img, ref = torch.rand(2, 3, 48, 48), torch.rand(2, 3, 48, 48) * 0.5
    a = texture_loss(plain, loss_features(plain), img, ref, torch.Generator().manual_seed(0))
    b = texture_loss(with_term, loss_features(with_term), img, ref, torch.Generator().manual_seed(0))
    assert float(b) > float(a)
