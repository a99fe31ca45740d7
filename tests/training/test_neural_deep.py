"""The U-Net's deep branch (training/unet.py DeepBranch): a deeper model continues shipped weights exactly,
trains, exports and runs in onnxruntime like the shallower one."""
import numpy as np
import pytest

torch = pytest.importorskip("torch")
pytest.importorskip("onnx")

from omninoise.backend.neural import conditioning as C  # noqa: E402
from omninoise.backend.neural.model import NeuralNoiseModel  # noqa: E402
from omninoise.backend.onnx_models import fingerprint  # noqa: E402
from omninoise.training.config import TrainConfig  # noqa: E402
from omninoise.training.export_onnx import export  # noqa: E402
from omninoise.training.train import build_model, train  # noqa: E402
from omninoise.training.unet import UNet, set_circular  # noqa: E402
from omninoise.training.warm_start import exported_weights, torch_from_export, warm_start  # noqa: E402
from tiny_run import TINY  # noqa: E402  (the shallow export itself: the `exported` fixture of conftest.py)


def _deep_from(out, deep=1):
    """A UNet with a deep branch, warm-started from the shallow export in ``out``."""
    sha = fingerprint(NeuralNoiseModel(str(out)).config["files"])
    m = build_model(TrainConfig.from_dict(dict(TINY, deep=deep, size=8 << deep)))
    warm_start(m, exported_weights(str(out), sha))
    return m.eval()


@pytest.mark.parametrize("deep", [1, 2])
def test_a_deep_branch_continues_the_shallow_weights_exactly(exported, deep):
    """Zero at initialisation: the deeper network computes the shipped network's ε, plain and tileable."""
    _, out = exported
    shallow = torch_from_export(str(out))
    deeper = _deep_from(out, deep)
    assert deeper.levels() == shallow.levels() + deep
    rng = np.random.default_rng(1)
    side = 1 << deeper.levels()
    x = torch.from_numpy(rng.standard_normal((2, 1, 2 * side, 3 * side)).astype(np.float32))
    t = torch.tensor([5.0, 800.0])
    cond = torch.from_numpy(rng.standard_normal((2, shallow.emb_dim + shallow.n_params, 2 * side, 3 * side))
                            .astype(np.float32))
    for circular in (False, True):
        with torch.no_grad():
            a = set_circular(shallow, circular)(x, t, cond)
            b = set_circular(deeper, circular)(x, t, cond)
        assert torch.equal(a, b)
    # the branch is really in the forward pass: nonzero output weights change ε
    with torch.no_grad():
        deeper.deep.out.weight.add_(0.01)
        assert (set_circular(deeper, False)(x, t, cond) - a).abs().max() > 1e-4


def test_deep_model_trains_exports_and_runs(exported, tmp_path):
    """A run with deep=1 from the shallow export: the branch learns, the export says multiple_of 16, and
    onnxruntime (split form, encoder shortcut for one-class grids) equals torch."""
    _, out = exported
    sha = fingerprint(NeuralNoiseModel(str(out)).config["files"])
    cfg = TrainConfig.from_dict(dict(TINY, deep=1, steps=3, lr=1e-3, init_onnx=str(out), init_sha256=sha))
    run = tmp_path / "run"
    train(cfg, str(run), log=lambda s: None)
    state = torch.load(run / "ckpt.pt", weights_only=False)
    assert float(state["ema"]["deep.out.weight"].abs().max()) > 0  # the zero convolution got gradients
    export(str(run), str(tmp_path / "model"))
    model = NeuralNoiseModel(str(tmp_path / "model"))
    assert model.multiple_of == 16 and max(model.config["blocks"]["levels"]) == 4
    tm = torch_from_export(str(tmp_path / "model"))
    rng = np.random.default_rng(2)
    x = rng.standard_normal((1, 1, 32, 48)).astype(np.float32)
    t = np.array([300.0], np.float32)
    cond = rng.standard_normal((1, model.embedding.shape[1] + len(model.params), 32, 48)).astype(np.float32)
    for circular in (False, True):
        with torch.no_grad():
            ref = set_circular(tm, circular)(torch.from_numpy(x), torch.from_numpy(t), torch.from_numpy(cond))
        np.testing.assert_allclose(model.eps_fn(circular)(x, t, cond), ref.numpy(), atol=1e-4)
    # a one-class grid takes the small-grid shortcut (the coarsest level now H / 16): the same maps
    grid = C.uniform(model, ("spots", {}), 256, 192)[None]
    small, full = model.encode(grid), model._encode(grid, False)
    assert model._small_grid(grid) is not None
    for k in full:
        np.testing.assert_array_equal(small[k], full[k])


def test_config_checks_size_against_depth():
    with pytest.raises(ValueError, match="multiple of 16"):
        TrainConfig.from_dict(dict(TINY, size=24, deep=1))
    with pytest.raises(ValueError, match="deep must be"):
        TrainConfig.from_dict(dict(TINY, deep=-1))
    assert UNet(3, 2, widths=(8, 16, 16), deep=2).levels() == 5


@pytest.mark.parametrize("deep", [0, 1])
def test_the_exports_folded_denoiser_is_the_same_function(exported, deep):
    """denoise(fold=True) (per-channel scale and shift, strided downsampling: the exported form) equals the
    training form within float rounding, plain and circular, with and without a deep branch whose weights
    are nonzero; and a training pass after it runs the unfolded form again."""
    _, out = exported
    m = _deep_from(out, deep) if deep else torch_from_export(str(out))
    torch.manual_seed(3)
    with torch.no_grad():
        for p in m.parameters():  # GroupNorm affines away from (1, 0), a live deep branch
            p.add_(0.05 * torch.randn_like(p))
    rng = np.random.default_rng(2)
    side = 1 << m.levels()
    x = torch.from_numpy(rng.standard_normal((2, 1, 2 * side, 3 * side)).astype(np.float32))
    t = torch.tensor([5.0, 800.0])
    cond = torch.from_numpy(rng.standard_normal((2, m.emb_dim + m.n_params, 2 * side, 3 * side)).astype(np.float32))
    with torch.no_grad():
        for tile in (None, "circular"):
            maps = m.encode(cond, tile)
            plain = m.denoise(x, t, maps, tile)
            folded = m.denoise(x, t, maps, tile, fold=True)
            assert (plain - folded).abs().max() < 1e-5 and plain.abs().max() > 0.1
            assert torch.equal(m.denoise(x, t, maps, tile), plain)  # fold is per call, not sticky
