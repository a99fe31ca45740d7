"""Bakes: box grids, slabs, VDB/EXR/PNG outputs, sequences, up-to-date keys, cancel, atomicity."""
import os
import tracemalloc

import numpy as np
import pytest

import omninoise.backend.bake as bake_mod
from omninoise.backend import WaveSettings, compile_noise, evaluate_points
from omninoise.backend.bake import BakeSpec, Cancelled, frame_path, run_bake
from omninoise.backend.errors import SettingError
from omninoise.backend.grid import evaluate_box
from omninoise.backend.sources import BoxGrid, WaveSource
from omninoise.backend.wavenoise.spectra import Spectrum
from omninoise.backend.transfer import preset
from omninoise.export import read_metadata, read_volume
from omninoise.export.images import read_image
from omninoise.export.vdb import openvdb_module

S3 = WaveSettings(dim=3, spectrum=Spectrum("fractal", 1.0, 6.0), seed=11)


def centres(grid: BoxGrid) -> np.ndarray:
    """World positions of every sample, (N, 3) float64, in the grid's array order."""
    axes = [grid.first[a] + np.arange(n) * grid.voxel[a] for a, n in enumerate(grid.resolution)]
    if grid.rank == 2:
        y, x = np.meshgrid(axes[1], axes[0], indexing="ij")
        return np.stack([x, y, np.full_like(x, grid.bounds[0][2])], -1).reshape(-1, 3)
    z, y, x = np.meshgrid(axes[2], axes[1], axes[0], indexing="ij")
    return np.stack([x, y, z], -1).reshape(-1, 3)


@pytest.mark.parametrize("settings, shape, output", [
    (WaveSettings(dim=2, seed=3), (23, 37), "real"),
    (WaveSettings(dim=3, seed=4), (5, 9, 13), "modulus"),
    (WaveSettings(dim=3, seed=4), (9, 13), "imag"),              # image of a 3D noise: plane z = lo[2]
    (WaveSettings(dim=4, seed=5), (4, 6, 8), "phase"),
    (WaveSettings(dim=3, seed=6, speed=0.7), (4, 6, 8), "real"),
    (WaveSettings(dim=3, seed=7, cellular="stit"), (4, 6, 8), "real"),
])
def test_box_grid_matches_points(settings, shape, output):
    noise = compile_noise(settings.replace(output=output))
    lo = np.array([-0.7, 1.3, 0.25, 0.4][: settings.dim], np.float32)
    step = np.array([0.031, 0.047, 0.083][: len(shape)])
    box = evaluate_box(noise, shape, lo, step, output, 0.3, settings.cellular, chunk=50)
    idx = np.indices(shape).reshape(len(shape), -1)[::-1]  # x, y[, z]
    pts = np.tile(lo, (idx.shape[1], 1))
    pts[:, : len(shape)] += (idx.T * step).astype(np.float32)
    ref = evaluate_points(noise, pts, output, 0.0 if settings.dim == 4 else 0.3, settings.cellular).reshape(shape)
    tol = 2e-3 if output == "phase" else 1e-3  # compiled rows vs numpy points (float32 ordering)
    err = np.abs(box - ref)
    if output == "phase":
        err = np.minimum(err, 2 * np.pi - err)
    assert np.quantile(err, 0.99) < tol / 4 and err.max() < tol


def test_vdb_holds_the_ramp_at_voxel_centres(tmp_path):
    grid = BoxGrid((20, 16, 12), ((-1.0, -0.5, 0.0), (1.0, 1.1, 0.6)))
    tf = preset("fire")
    out = str(tmp_path / "fire.vdb")
    res = run_bake(BakeSpec("fire", WaveSource(S3), grid, out, tf))
    assert res.written == [out]
    v = evaluate_points(compile_noise(S3), centres(grid).astype(np.float32), "real").reshape(grid.shape)
    rgba = tf.rgba(v)
    dens = tf.density(rgba)
    got = read_volume(out, "density", grid.shape)
    np.testing.assert_allclose(got, dens, atol=2e-3)
    col = read_volume(out, "color", grid.shape)
    on = dens > 0.05
    np.testing.assert_allclose(col[on], rgba[..., :3][on], atol=2e-3)
    temp = read_volume(out, "temperature", grid.shape)
    np.testing.assert_allclose(temp[on], tf.kelvin(v)[on], atol=2.0)
    vdb = openvdb_module()
    g = vdb.read(out, "density")
    assert g.activeVoxelCount() == int((got > 0).sum()) < got.size  # sparse: empty voxels inactive
    np.testing.assert_allclose(g.transform.indexToWorld((3, 2, 1)), centres(grid).reshape(12, 16, 20, 3)[1, 2, 3],
                               atol=1e-6)
    assert read_metadata(out)[bake_mod.KEY_NAME] == BakeSpec("fire", WaveSource(S3), grid, out, tf).key(None)


def test_raw_density_without_ramp_and_slabs_change_nothing(tmp_path, monkeypatch):
    grid = BoxGrid((24, 20, 16), ((0, 0, 0), (1.2, 1.0, 0.8)))
    whole, sliced = str(tmp_path / "whole.vdb"), str(tmp_path / "sliced.vdb")
    run_bake(BakeSpec("a", WaveSource(S3), grid, whole))
    monkeypatch.setattr(bake_mod, "SLAB_VOXELS", 24 * 20 * 3)  # 3 z-planes per slab, last one short
    seen = []
    run_bake(BakeSpec("a", WaveSource(S3), grid, sliced), progress=seen.append)
    a, b = read_volume(whole, "density", grid.shape), read_volume(sliced, "density", grid.shape)
    np.testing.assert_array_equal(a, b)
    assert a.min() < 0 < a.max()  # raw values, negative included
    assert seen == sorted(seen) and seen[-1] == 1.0 and len(seen) >= 6


def test_slabs_keep_memory_near_the_slab(tmp_path, monkeypatch):
    """A 96^3 volume (3.4 MiB of float32 values, 17 MiB with colour) bakes holding ~1/16 of it."""
    monkeypatch.setattr(bake_mod, "SLAB_VOXELS", 96 * 96 * 6)
    grid = BoxGrid((96, 96, 96), ((0, 0, 0), (2, 2, 2)))
    spec = BakeSpec("m", WaveSource(WaveSettings(dim=3, directions=4)), grid, str(tmp_path / "m.vdb"),
                    preset("clouds"))
    WaveSource(spec.source.settings).evaluate((1, 1, 1), np.zeros(3), np.ones(3), 0.0)  # warm numba
    tracemalloc.start()
    run_bake(spec)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    dense = 96 ** 3 * 4 * 5  # what a dense float32 density + RGBA bake would hold
    assert peak < dense / 4, f"peak {peak / 2**20:.1f} MiB vs dense {dense / 2**20:.1f} MiB"


def test_image_orientation_and_formats(tmp_path):
    grid = BoxGrid((40, 24), ((0.0, 0.0, 0.35), (2.0, 1.2, 0.35)))
    src = WaveSource(S3)
    exr, png, npy = (str(tmp_path / f"img.{e}") for e in ("exr", "png", "npy"))
    for p in (exr, png, npy):
        run_bake(BakeSpec("img", src, grid, p))
    v = evaluate_points(compile_noise(S3), centres(grid).astype(np.float32), "real").reshape(grid.shape)
    np.testing.assert_allclose(np.load(npy), v, atol=1e-3)  # (y, x), row 0 at y0
    np.testing.assert_allclose(read_image(exr), v[::-1], atol=1e-3)  # image rows: top = y1
    from PIL import Image

    with Image.open(png) as im:
        assert im.size == (40, 24) and im.mode == "L"
    run_bake(BakeSpec("img", src, grid, png, preset("marble")))
    with Image.open(png) as im:
        assert im.mode == "RGBA"
    run_bake(BakeSpec("img", src, grid, exr, preset("marble"), half=True))
    import OpenEXR

    with OpenEXR.File(exr) as f:
        ch = f.channels()
        assert "RGBA" in ch and ch["RGBA"].pixels.dtype == np.float16


def test_sequences_number_frames_and_move(tmp_path):
    anim = WaveSource(S3.replace(speed=1.5))
    grid = BoxGrid((12, 12, 12))
    spec = BakeSpec("seq", anim, grid, str(tmp_path / "clouds_###.vdb"), frames=(8, 10), time=0.5, time_step=0.25)
    res = run_bake(spec)
    assert [os.path.basename(p) for p in res.written] == ["clouds_008.vdb", "clouds_009.vdb", "clouds_010.vdb"]
    a, b = (read_volume(p, "density", grid.shape) for p in res.written[:2])
    assert np.abs(a - b).mean() > 0.05  # the waves moved
    one = run_bake(BakeSpec("one", anim, grid, str(tmp_path / "t.vdb"), time=0.75))
    np.testing.assert_array_equal(read_volume(one.written[0], "density", grid.shape), b)  # frame 9 = time 0.75
    assert frame_path("/a/b_##.exr", 7) == "/a/b_07.exr"


@pytest.mark.parametrize("kw, match", [
    (dict(output="v.vdb", grid=BoxGrid((8, 8))), "needs a 3D grid"),
    (dict(output="v.png", grid=BoxGrid((8, 8, 8))), "needs a 2D grid"),
    (dict(output="v.tif"), r"a bake is written as .vdb, .exr, .png, .npy, not '.tif'"),
    (dict(output=""), "output path is a folder, not a file"),      # not "unsupported type (none)"
    (dict(output=".exr"), "'.exr' is a name without a type: give the file a name before .exr"),   # a hidden file
    (dict(output="v_##.vdb", frames=(1, 2)), "does not change over time"),
    (dict(output="v.vdb", frames=(1, 2), source=WaveSource(S3.replace(speed=1.0))), "needs '#'"),
    (dict(output="v.vdb", frames=(3, 1), source=WaveSource(S3.replace(speed=1.0))), "end >= start"),
    (dict(output="nowhere/v.vdb"), "folder does not exist"),
    (dict(output="v.vdb", grid=BoxGrid((8, 8, 8), ((0, 0, 1), (1, 1, 0)))), "max must exceed min"),
    (dict(output="v.vdb", source=WaveSource(WaveSettings(dim=2))), "2D noise"),
])
def test_bad_bakes_fail_before_work(tmp_path, kw, match):
    d = dict(name="bad", source=WaveSource(S3), grid=BoxGrid((8, 8, 8)))
    d.update(kw)
    d["output"] = str(tmp_path / d["output"])
    with pytest.raises(SettingError, match=match):
        run_bake(BakeSpec(**d))


def test_up_to_date_skips_and_changes_rebake(tmp_path):
    grid = BoxGrid((10, 10, 10))
    out = str(tmp_path / "u.vdb")
    assert run_bake(BakeSpec("u", WaveSource(S3), grid, out)).written == [out]
    stamp = os.stat(out).st_mtime_ns
    assert run_bake(BakeSpec("u", WaveSource(S3), grid, out)).skipped == [out]
    assert os.stat(out).st_mtime_ns == stamp
    assert run_bake(BakeSpec("u", WaveSource(S3.replace(seed=12)), grid, out)).written == [out]
    assert run_bake(BakeSpec("u", WaveSource(S3.replace(seed=12)), grid, out), force=True).written == [out]
    with open(out, "wb") as fh:
        fh.write(b"not a vdb")
    assert run_bake(BakeSpec("u", WaveSource(S3.replace(seed=12)), grid, out)).written == [out]


@pytest.mark.parametrize("name", ["Ziegel über Grün", "木目 2", "Кирпич"])
@pytest.mark.parametrize("ext", ["png", "exr", "vdb"])
def test_a_bake_named_in_any_script_writes_and_reads_back_its_name(tmp_path, name, ext):
    """A PNG's text chunks hold Latin-1 only: a bake named beyond it stopped with "'latin-1' codec can't
    encode". Its name is stored as UTF-8 (PNG's iTXt) and read back, by us and by Pillow; the bake is then up to
    date."""
    from PIL import Image

    grid = BoxGrid((6, 6, 6)) if ext == "vdb" else BoxGrid((6, 5))
    out = str(tmp_path / f"{name}.{ext}")
    spec = BakeSpec(name, WaveSource(S3), grid, out)
    assert run_bake(spec).written == [out]
    assert read_metadata(out)["omninoise_bake"] == name
    assert run_bake(spec).skipped == [out]
    if ext == "png":
        with Image.open(out) as im:
            assert im.text["omninoise_bake"] == name and im.text[bake_mod.KEY_NAME] == spec.key(None)


@pytest.mark.parametrize("ext", ["vdb", "exr", "png"])
def test_cancel_leaves_earlier_result_untouched(tmp_path, monkeypatch, ext):
    monkeypatch.setattr(bake_mod, "SLAB_VOXELS", 16 * 4)
    grid = BoxGrid((16, 16, 16) if ext == "vdb" else (16, 16))
    out = str(tmp_path / f"c.{ext}")
    run_bake(BakeSpec("c", WaveSource(S3), grid, out, preset("smoke")))
    before = open(out, "rb").read()
    calls = []

    def cancel():
        calls.append(1)
        return len(calls) > 3

    with pytest.raises(Cancelled):
        run_bake(BakeSpec("c", WaveSource(S3.replace(seed=99)), grid, out, preset("smoke")), cancel=cancel)
    assert open(out, "rb").read() == before
    assert os.listdir(tmp_path) == [f"c.{ext}"]  # no temporary file left behind


def test_failed_write_leaves_no_partial_file(tmp_path, monkeypatch):
    import omninoise.export.vdb
    from omninoise import export

    out = str(tmp_path / "f.vdb")

    def boom(self, path):
        with export.vdb.atomic_path(path, suffix=".vdb") as tmp:
            open(tmp, "wb").write(b"half a file")
            raise OSError("disk full")

    monkeypatch.setattr(export.vdb.VolumeWriter, "write", boom)
    with pytest.raises(OSError, match="disk full"):
        run_bake(BakeSpec("f", WaveSource(S3), BoxGrid((8, 8, 8)), out))
    assert os.listdir(tmp_path) == []


def test_4d_sequences_step_w(tmp_path):
    """4D noise: frame f of a sequence is the volume at W = time + (f - start) * time_step."""
    src = WaveSource(WaveSettings(dim=4, seed=13, spectrum=Spectrum("bandpass", 1.0, 3.0)), w_offset=0.1)
    grid = BoxGrid((10, 8, 6), ((0, 0, 0), (1, 1, 1)))
    seq = run_bake(BakeSpec("w", src, grid, str(tmp_path / "w_#.vdb"), frames=(1, 3),
                            time=0.2, time_step=0.3))
    last = read_volume(seq.written[-1], "density", grid.shape)
    one = run_bake(BakeSpec("w1", src, grid, str(tmp_path / "one.vdb"), time=0.8))
    np.testing.assert_array_equal(read_volume(one.written[0], "density", grid.shape), last)
    noise = compile_noise(src.settings)
    pts = np.concatenate([centres(grid), np.full((grid.shape[0] * 80, 1), 0.9)], 1).astype(np.float32)
    np.testing.assert_allclose(last.ravel(), evaluate_points(noise, pts, "real"), atol=1e-3)
    img = run_bake(BakeSpec("i", src, BoxGrid((12, 10)), str(tmp_path / "i_##.exr"), frames=(4, 5)))
    assert [os.path.basename(p) for p in img.written] == ["i_04.exr", "i_05.exr"]
    assert np.abs(read_image(img.written[0]) - read_image(img.written[1])).mean() > 1e-3
