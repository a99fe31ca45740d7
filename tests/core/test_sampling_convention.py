"""One sampling convention for every output of `omninoise wave`.

Sample i of N over an extent E sits at the centre of its cell, (i + 1/2) E / N. `.npy` holds the grid as
[y, x] or [z, y, x]; image files (.exr, .png) put +y at the top (row 0 is the largest y), which is how an image
texture on a plane shows it in Blender; `.vdb` voxel (i, j, k) holds the value at the centre of voxel (x=i, y=j,
z=k). So `.npy`, `.exr` (float and half), `.png` and `.vdb` of the same settings hold the same field.
"""
import numpy as np
import pytest

from omninoise.backend import WaveSettings, compile_noise
from omninoise.cli.main import build_parser, main
from omninoise.cli.wave import settings_from_args
from omninoise.backend.grid import evaluate_grid
from omninoise.export import read_volume
from omninoise.export.images import read_image
from conftest import needs_openvdb

ARGS = ["wave", "--directions", "8", "--fmin", "2", "--fmax", "6", "--seed", "4", "--extent", "2", "--quiet"]


def settings(dim: int) -> WaveSettings:
    return settings_from_args(build_parser().parse_args(ARGS + ["--dim", str(dim), "-o", "x.npy"]))


def reference(dim: int, n: int, extent: float = 2.0) -> np.ndarray:
    """The field at sample centres, straight from the engine (not through the CLI or the bake pipeline)."""
    noise = compile_noise(settings(dim))
    half = 0.5 * extent / n
    return evaluate_grid(noise, n, extent, origin=(half,) * dim)


def test_2d_npy_exr_half_and_png_hold_the_same_field(tmp_path):
    ref = reference(2, 48)
    paths = {k: str(tmp_path / f"w{k}") for k in (".npy", ".exr", "_half.exr", ".png")}
    for key, path in paths.items():
        assert main(ARGS + ["--size", "48", "-o", path] + (["--half"] if "half" in key else [])) == 0
    npy = np.load(paths[".npy"])
    np.testing.assert_allclose(npy, ref, atol=1e-5)  # centres, [y, x]
    np.testing.assert_allclose(read_image(paths[".exr"])[::-1], npy, atol=1e-6)  # +y at the top of the image
    np.testing.assert_allclose(read_image(paths["_half.exr"])[::-1], npy, atol=2e-3)  # --half changes precision only
    png = read_image(paths[".png"])
    lo, hi = npy.min(), npy.max()
    corr = np.corrcoef(png[::-1].ravel(), ((npy - lo) / (hi - lo)).ravel())[0, 1]
    assert corr > 0.999, corr  # the 8-bit preview of the same field, same orientation


def test_an_npy_grid_is_not_sampled_at_the_grid_corners(tmp_path):
    """`-o x.npy` samples at the cell centres, as .vdb and --half do, not at i E / N (the grid's corners)."""
    out = str(tmp_path / "a.npy")
    assert main(ARGS + ["--size", "32", "-o", out]) == 0
    corners = evaluate_grid(compile_noise(settings(2)), 32, 2.0)
    assert np.abs(np.load(out) - corners).max() > 0.05


@needs_openvdb
def test_3d_npy_and_vdb_hold_the_same_field(tmp_path):
    ref = reference(3, 20)
    npy_path, vdb_path = str(tmp_path / "v.npy"), str(tmp_path / "v.vdb")
    for path in (npy_path, vdb_path):
        assert main(ARGS + ["--dim", "3", "--size", "20", "-o", path]) == 0
    npy = np.load(npy_path)
    assert npy.shape == (20, 20, 20)
    np.testing.assert_allclose(npy, ref, atol=1e-5)  # [z, y, x] at centres
    np.testing.assert_allclose(read_volume(vdb_path, "density", (20, 20, 20)), npy, atol=1e-5)


@pytest.mark.parametrize("out", ["x.npy", "x.png"])
def test_half_is_refused_where_it_means_nothing(tmp_path, capsys, out):
    assert main(ARGS + ["--size", "16", "--half", "-o", str(tmp_path / out)]) == 2
    assert "--half" in capsys.readouterr().err
    assert not (tmp_path / out).exists()
