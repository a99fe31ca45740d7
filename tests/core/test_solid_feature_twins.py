"""The torch twins of the solid decoder's shape features (cellular, brick) against the runtime."""
import numpy as np
import pytest

from omninoise.backend.solid import brick, cellular


@pytest.mark.parametrize("D", [2, 3])
@pytest.mark.parametrize("family", ["cellular", "brick"])
def test_torch_twin_matches_runtime(family, D):
    torch = pytest.importorskip("torch")
    from omninoise.training.solid.brick import brick_features
    from omninoise.training.solid.cellular import cellular_features
    from omninoise.training.solid.value_noise import octave_seeds
    twin, runtime = {"cellular": (cellular_features, cellular.cellular_features),
                     "brick": (brick_features, brick.brick_features)}[family]
    rng = np.random.default_rng(5)
    x = rng.uniform(-2, 2, (2, 2000, D)).astype(np.float32)
    T = rng.normal(size=(8, D, D)).astype(np.float32)
    a = twin(torch.from_numpy(x), torch.from_numpy(T), octave_seeds([5, 9], 8), 4).numpy()
    assert a.shape == (2, 2000, 12)
    for b, s in enumerate((5, 9)):
        close = np.abs(a[b] - runtime(x[b], T, s, 4)) < 5e-4
        # float32 positions in torch: a point within ~1e-4 of a border may fall in the next cell or brick
        assert close.mean() > 0.998, close.mean()
        if family == "cellular":
            assert close[:, 0::3].all()            # F1 is continuous across borders
    # gradients reach the transforms of the octaves that have features, and only those
    Tt = torch.from_numpy(T).requires_grad_(True)
    twin(torch.from_numpy(x), Tt, octave_seeds([5, 9], 8), 4).square().sum().backward()
    assert torch.isfinite(Tt.grad).all() and Tt.grad[:4].abs().sum() > 0 and Tt.grad[4:].abs().sum() == 0
