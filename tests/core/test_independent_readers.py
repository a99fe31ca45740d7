"""Our files read by readers that share no code with our writers: Debian's `python3-openvdb` (pyopenvdb, the
system Python) for .vdb and OpenImageIO's `oiiotool` (openimageio-tools) for .exr. Each reads what we meant to
write: grid names, classes and voxel size; every voxel and pixel value against the `.npy` of the same settings.

Skipped where the packages are not installed (`apt-get install python3-openvdb openimageio-tools`).
"""
import json
import os
import re
import shutil
import subprocess

import numpy as np
import pytest

from omninoise.cli.main import main

SYSTEM_PY = "/usr/bin/python3"
WAVE = ["wave", "--fmin", "1", "--fmax", "4", "--seed", "6", "--extent", "3", "--quiet"]


def _has_pyopenvdb() -> bool:
    if not os.path.isfile(SYSTEM_PY):
        return False
    return subprocess.run([SYSTEM_PY, "-c", "import pyopenvdb"], capture_output=True).returncode == 0


needs_pyopenvdb = pytest.mark.skipif(not _has_pyopenvdb(), reason="Debian's python3-openvdb is not installed")
needs_oiio = pytest.mark.skipif(shutil.which("oiiotool") is None, reason="openimageio-tools is not installed")

READ_VDB = r"""
import json, sys
import pyopenvdb as vdb
grids, meta = vdb.readAll(sys.argv[1])
out = {}
for g in grids:
    acc = g.getConstAccessor()
    n = int(sys.argv[2])
    vals = [[[acc.getValue((i, j, k)) for i in range(n)] for j in range(n)] for k in range(n)]  # [z][y][x]
    out[g.name] = dict(type=type(g).__name__, cls=g.gridClass, voxel=list(g.transform.voxelSize()),
                       active=g.activeVoxelCount(), values=vals,
                       origin=list(g.transform.indexToWorld((0, 0, 0))))
print(json.dumps(out))
"""


def read_vdb(path: str, n: int) -> dict:
    res = subprocess.run([SYSTEM_PY, "-c", READ_VDB, path, str(n)], capture_output=True, text=True, check=True)
    return json.loads(res.stdout)


def read_exr_oiio(path: str) -> tuple:
    """(header text, values float64 (H, W, C)) as oiiotool prints them."""
    info = subprocess.run(["oiiotool", "--info", "-v", path], capture_output=True, text=True, check=True).stdout
    dump = subprocess.run(["oiiotool", "--info", "--dumpdata", path], capture_output=True, text=True, check=True).stdout
    px = {}
    for m in re.finditer(r"Pixel \((\d+), (\d+)\): ([^\n]+)", dump):
        px[(int(m.group(2)), int(m.group(1)))] = [float(v) for v in m.group(3).split()]
    H, W = max(k[0] for k in px) + 1, max(k[1] for k in px) + 1
    return info, np.array([[px[(y, x)] for x in range(W)] for y in range(H)])


@needs_pyopenvdb
def test_pyopenvdb_reads_our_volumes_voxel_for_voxel(tmp_path):
    n = 12
    npy, raw, fire, half = (str(tmp_path / f) for f in ("v.npy", "raw.vdb", "fire.vdb", "half.vdb"))
    for out, extra in ((npy, []), (raw, []), (fire, ["--transfer", "fire"]), (half, ["--transfer", "fire", "--half"])):
        assert main(WAVE + ["--dim", "3", "--size", str(n), "-o", out] + extra) == 0
    ref = np.load(npy)                                         # [z, y, x] at cell centres
    got = read_vdb(raw, n)["density"]
    assert got["type"] == "FloatGrid" and got["cls"] == "fog volume" and got["active"] == n ** 3
    assert got["voxel"] == pytest.approx([3.0 / n] * 3)
    assert got["origin"] == pytest.approx([1.5 / n] * 3)         # voxel (0, 0, 0) sits at the first cell centre
    np.testing.assert_allclose(np.array(got["values"]), ref, atol=1e-6)
    f = read_vdb(fire, n)
    assert set(f) == {"density", "color", "temperature"} and f["color"]["type"] == "Vec3SGrid"
    dens = np.array(f["density"]["values"])
    assert 0 < f["density"]["active"] < n ** 3 and dens.min() == 0.0 and dens.max() > 0.1
    h = read_vdb(half, n)
    np.testing.assert_allclose(np.array(h["density"]["values"]), dens, atol=2e-3)  # 16-bit halves, same field
    np.testing.assert_allclose(np.array(h["color"]["values"]), np.array(f["color"]["values"]), atol=4e-3)


@needs_oiio
def test_oiiotool_reads_our_images_pixel_for_pixel(tmp_path):
    n = 16
    npy, exr, half, rgba = (str(tmp_path / f) for f in ("w.npy", "w.exr", "h.exr", "rgba.exr"))
    for out, extra in ((npy, []), (exr, []), (half, ["--half"]), (rgba, ["--transfer", "marble"])):
        assert main(WAVE + ["--size", str(n), "-o", out] + extra) == 0
    ref = np.load(npy)[::-1]                                   # images put +y at the top
    info, got = read_exr_oiio(exr)
    assert "1 channel, float openexr" in info and "channel list: Y" in info
    np.testing.assert_allclose(got[..., 0], ref, atol=1e-6)
    info, got = read_exr_oiio(half)
    assert "half openexr" in info
    np.testing.assert_allclose(got[..., 0], ref, atol=2e-3)
    info, got = read_exr_oiio(rgba)
    assert "4 channel" in info and "channel list: R, G, B, A" in info
    assert got.shape == (n, n, 4) and 0.0 <= got.min() and got[..., 3].max() <= 1.0 + 1e-6


SOLID = ["solid", "--exemplar", "gravel_3d", "--seed", "2", "--quiet"]


@needs_pyopenvdb
@needs_oiio
def test_independent_readers_read_our_solid_textures(tmp_path):
    """A solid texture's volume (a colour grid and a constant density) and its RGB EXR, value for value."""
    n = 8
    npy, vdb, img, exr = (str(tmp_path / f) for f in ("s.npy", "s.vdb", "i.npy", "i.exr"))
    for out, dim in ((npy, 3), (vdb, 3), (img, 2), (exr, 2)):
        assert main(SOLID + ["--dim", str(dim), "--size", str(n), "-o", out]) == 0
    ref = np.load(npy)                                         # [z, y, x, rgb], linear
    v = read_vdb(vdb, n)
    assert v["color"]["type"] == "Vec3SGrid" and v["color"]["active"] == n ** 3
    assert v["density"]["cls"] == "fog volume" and np.ptp(np.array(v["density"]["values"])) == 0.0
    np.testing.assert_allclose(np.array(v["color"]["values"]), ref, atol=1e-6)
    assert ref.std() > 0.01                                    # a texture, not a constant
    info, got = read_exr_oiio(exr)
    assert "3 channel, float openexr" in info and "channel list: R, G, B" in info
    np.testing.assert_allclose(got, np.load(img), atol=1e-6)
