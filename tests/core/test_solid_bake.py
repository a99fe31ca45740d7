"""Solid textures through the bake pipeline and job files (colour sources)."""
import os

import numpy as np
import pytest

from omninoise.backend.bake import BakeSpec, run_bake
from omninoise.backend.errors import SettingError
from omninoise.backend.jobs import run_job
from omninoise.backend.solid.bake import srgb_to_linear
from omninoise.backend.solid.model import SolidTextureModel
from omninoise.backend.solid.request import SolidRequest
from omninoise.backend.sources import BoxGrid, SolidSource, source_from_dict

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
GRAVEL = os.path.join(ROOT, "models", "solid", "gravel_3d")


def grid_points(grid: BoxGrid) -> np.ndarray:
    """Voxel/pixel centres of ``grid``, x fastest: the reference positions (N, 3)."""
    first, step = grid.first, grid.voxel
    xs = first[0] + np.arange(grid.resolution[0]) * step[0]
    ys = first[1] + np.arange(grid.resolution[1]) * step[1]
    zs = first[2] + np.arange(grid.resolution[2]) * step[2] if grid.rank == 3 else np.array([first[2]])
    z, y, x = np.meshgrid(zs, ys, xs, indexing="ij")
    return np.stack([x.ravel(), y.ravel(), z.ravel()], axis=1)


def _ref(grid: BoxGrid, seed=0, scale=1.0):
    m = SolidTextureModel(GRAVEL)
    return srgb_to_linear(m.evaluate(grid_points(grid) * scale, m.default_code(), seed)).reshape(grid.shape + (3,))


def test_vdb_npy_exr_png(tmp_path):
    from omninoise.export.vdb import read_volume
    grid = BoxGrid((10, 8, 6), ((-1.0, -1.0, -1.0), (1.0, 0.6, 0.2)))
    src = SolidSource(GRAVEL, SolidRequest(seed=2), scale=1.5, density=0.7)
    ref = _ref(grid, 2, 1.5)
    run_bake(BakeSpec("v", src, grid, str(tmp_path / "a.vdb")))
    np.testing.assert_allclose(read_volume(str(tmp_path / "a.vdb"), "color", grid.shape), ref, atol=1e-6)
    np.testing.assert_allclose(read_volume(str(tmp_path / "a.vdb"), "density", grid.shape), 0.7, atol=1e-7)
    run_bake(BakeSpec("n", src, grid, str(tmp_path / "a.npy")))
    np.testing.assert_allclose(np.load(tmp_path / "a.npy"), ref, atol=1e-6)
    img = BoxGrid((12, 9), ((0.0, 0.0, 0.3), (1.2, 0.9, 0.3)))
    run_bake(BakeSpec("e", src, img, str(tmp_path / "a.exr")))
    import OpenEXR
    with OpenEXR.File(str(tmp_path / "a.exr")) as f:
        rgb = np.asarray(f.channels()["RGB"].pixels)
    np.testing.assert_allclose(rgb[::-1], _ref(img, 2, 1.5), atol=1e-6)   # file rows top-down
    run_bake(BakeSpec("p", src, img, str(tmp_path / "a.png")))
    from omninoise.export.images import read_rgb
    png = read_rgb(str(tmp_path / "a.png"))
    from omninoise.export.images import encode_srgb8
    np.testing.assert_array_equal((png * 255).round().astype(np.uint8), encode_srgb8(_ref(img, 2, 1.5)[::-1]))


def test_slabs_change_nothing(tmp_path, monkeypatch):
    import omninoise.backend.bake as B
    grid = BoxGrid((8, 8, 12))
    src = SolidSource(GRAVEL)
    run_bake(BakeSpec("a", src, grid, str(tmp_path / "a.npy")))
    monkeypatch.setattr(B, "SLAB_VOXELS", 64)
    run_bake(BakeSpec("b", src, grid, str(tmp_path / "b.npy")))
    np.testing.assert_array_equal(np.load(tmp_path / "a.npy"), np.load(tmp_path / "b.npy"))


def test_job_file(tmp_path):
    job = tmp_path / "job.toml"
    job.write_text('''
[[bake]]
name = "block"
output = "out/block.vdb"
resolution = [6, 6, 6]
bounds = [[-1, -1, -1], [1, 1, 1]]
[bake.source]
kind = "solid"
model = "gravel_3d"
seed = 4
''')
    outcomes = run_job(str(job))
    assert outcomes[0].result.written == [str(tmp_path / "out" / "block.vdb")]
    again = run_job(str(job))                     # up-to-date key: skipped
    assert again[0].result.skipped and not again[0].result.written


@pytest.mark.parametrize("source, msg", [
    ({"kind": "solid"}, "source.exemplar: the space model needs an exemplar"),
    ({"kind": "solid", "model": "gravel_3d", "colour": 1}, r"source.colour: unknown key; known: kind, method"),
    ({"kind": "solid", "model": "gravel_3d", "exemplar": "x.png"}, "holds one texture"),
    ({"kind": "solid", "model": "nope"}, "no solid.json"),
    ({"kind": "solid", "model": "gravel_3d", "scale": 0}, r"source.scale: must lie in \[0.0001, 10000\]"),
])
def test_bad_sources(tmp_path, source, msg):
    with pytest.raises(SettingError, match=msg):
        source_from_dict(source, str(tmp_path))


def test_transfer_is_refused(tmp_path):
    from omninoise.backend.transfer import preset
    spec = BakeSpec("t", SolidSource(GRAVEL), BoxGrid((4, 4, 4)), str(tmp_path / "t.vdb"), preset("clouds"))
    with pytest.raises(SettingError, match="has its own colours"):
        run_bake(spec)


def test_evaluate_reports_fractions_and_cancels_between_chunks():
    """The core's one progress contract: ``progress(fraction)``, rising to 1.0; cancel stops before the next chunk."""
    from omninoise.backend.grid import Cancelled

    m = SolidTextureModel(GRAVEL)
    pts = np.random.default_rng(1).uniform(-2, 2, (1000, 3))
    seen = []
    out = m.evaluate(pts, m.default_code(), 0, chunk=300, progress=seen.append)
    assert seen == pytest.approx([0.3, 0.6, 0.9, 1.0]) and out.shape == (1000, 3)
    calls = []
    with pytest.raises(Cancelled):
        m.evaluate(pts, m.default_code(), 0, chunk=300, progress=calls.append, cancel=lambda: len(calls) >= 2)
    assert calls == pytest.approx([0.3, 0.6])
