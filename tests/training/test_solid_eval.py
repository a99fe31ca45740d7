"""The solid-texture evaluation's metrics behave: real pixels beat flat colour, copies have no diversity."""
import numpy as np
import pytest

torch = pytest.importorskip("torch")

from omninoise.training.solid import exemplars as ex  # noqa: E402
from omninoise.training.solid.evaluate import baselines, evaluate_exemplar, slices_3d  # noqa: E402


def test_metrics_rank_real_pixels_flat_colour_and_copies():
    held = ex.heldout_region("granite").permute(1, 2, 0).numpy()
    g = np.random.default_rng(0)
    real = np.stack([held[a:a + 64, b:b + 64] for a, b in g.integers(0, 448, (6, 2))])
    flat = np.broadcast_to(held.reshape(-1, 3).mean(0), (6, 64, 64, 3)).copy()
    copies = np.repeat(real[:1], 6, axis=0)
    r = evaluate_exemplar("granite", 1.0, {"real": real, "flat": flat, "copies": copies}, n=6)
    assert r["real"]["style"] < 0.5 * r["flat"]["style"]
    assert r["real"]["psd"] < 0.5 and r["flat"]["psd"] > 2.0
    assert r["copies"]["diversity"] == 0.0 and r["tiled"]["diversity"] == 0.0 and r["real"]["diversity"] > 0.5
    assert r["real"]["success"] > r["copies"]["success"] == 0.0
    assert set(r) == {"real", "flat", "copies", "tiled", "perlin_hist", "linear"}


def test_baselines_match_the_exemplar_colours():
    region = ex.procedural("rust", 0, 128)
    b = baselines(region, 3, 64)
    img = region.permute(1, 2, 0).numpy().reshape(-1, 3)
    for name, t in b.items():
        assert t.shape == (3, 3, 64, 64), name
        got = t.permute(0, 2, 3, 1).numpy().reshape(-1, 3)
        np.testing.assert_allclose(got.mean(0), img.mean(0), atol=0.08, err_msg=name)
    # histogram colouring uses only the exemplar's own colours
    hist = b["perlin_hist"].permute(0, 2, 3, 1).numpy().reshape(-1, 3)
    assert np.isin(hist[:, 0], img[:, 0]).all()


def test_slices_cover_axes_and_oblique_planes():
    seen = []

    def evaluate(p, i):
        seen.append(p)
        return np.zeros((len(p), 3), np.float32)

    out = slices_3d(evaluate, 4, 8, 8.0)
    assert out.shape == (4, 8, 8, 3)
    const = [int((p.std(0) < 1e-9).sum()) for p in seen]
    assert const == [1, 1, 1, 0]      # three axis-aligned slices, then an oblique one


def test_slices_of_a_fixed_axis_model_run_through_its_axis():
    """fixed_axis 'rows': every slice is vertical (z varies down the image, z constant along a row); 'columns':
    x runs along every row, constant down a column."""
    for axis, along_row, down_col in (("rows", None, 2), ("columns", 0, None)):
        seen = []

        def evaluate(p, i):
            seen.append(p.reshape(8, 8, 3))
            return np.zeros((len(p), 3), np.float32)

        slices_3d(evaluate, 6, 8, 8.0, fixed_axis=axis)
        for p in seen:
            if down_col is not None:
                assert np.allclose(p[:, :, 2].std(1), 0) and p[0, 0, 2] > p[-1, 0, 2]   # rows level, top up
            if along_row is not None:
                assert np.allclose(np.diff(p[:, :, 0], axis=1), 1 / 8.0) and np.allclose(p[:, :, 0].std(0), 0)
