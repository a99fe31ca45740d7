"""The Wave Noise and Wave Cellular nodes rendered by EEVEE equal the engine (Cycles *and* EEVEE).

EEVEE needs an OpenGL 4.3 context; without a GPU, Mesa's llvmpipe gives one on
the CPU (.ci/run installs it).  The renders run in a fresh Python
(tests/blender_scripts/eevee_wave.py).  EEVEE's film stores passes as half
floats, so agreement is measured in half-float steps of the encoded emission
0.5 + 0.1 v: the engine's value at the pixel centre, encoded, is within 1e-3
(two half-float steps) of the rendered one.  A Linear Image Texture lookup,
which EEVEE samples through mipmaps, misses this by three orders of magnitude
(p99 error 1.6 in v at 48 px).

Without an OpenGL context the test skips, unless OMNINOISE_REQUIRE_EEVEE=1
(set by .ci/run) makes that a failure.
"""
import ctypes.util
import json
import os
import subprocess
import sys

import numpy as np
import pytest

OpenEXR = pytest.importorskip("OpenEXR")
pytest.importorskip("bpy")

from omninoise.backend import WaveSettings, compile_noise  # noqa: E402
from omninoise.backend.wavenoise.settings import settings_to_dict  # noqa: E402
from omninoise.backend.wavenoise.wave import select_output  # noqa: E402
from test_wave_node import CASES as NODE_CASES, SOCKETS, _engine  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCRIPT = os.path.join(ROOT, "tests", "blender_scripts", "eevee_wave.py")
RES = 40
ENC = 0.1  # as in the script
REQUIRED = os.environ.get("OMNINOISE_REQUIRE_EEVEE") == "1"

#: the cases of the Cycles bake test (tests/blender/test_wave_node.py), and the Wave Cellular node's default
CASES = {name: NODE_CASES[name] for name in ("2d", "3d", "4d", "3d+t")}
CELLS = WaveSettings(dim=3, cellular="polytope", directions=16, cell_size=0.4, seed=2)


def _unavailable(reason: str):
    if REQUIRED:
        pytest.fail(f"EEVEE required (OMNINOISE_REQUIRE_EEVEE=1) but {reason}")
    pytest.skip(reason)


@pytest.fixture(scope="module")
def renders(tmp_path_factory):
    if ctypes.util.find_library("EGL") is None:
        _unavailable("no libEGL (install Mesa: libegl-mesa0 libgl1-mesa-dri)")
    d = tmp_path_factory.mktemp("eevee")
    spec = {name: {"settings": settings_to_dict(s), "inputs": {SOCKETS[k]: v for k, v in kw.items()}}
            for name, (s, kw) in CASES.items()}
    spec["cells"] = {"settings": settings_to_dict(CELLS), "inputs": {}}
    with open(d / "cases.json", "w", encoding="utf-8") as fh:
        json.dump(spec, fh)
    r = subprocess.run([sys.executable, SCRIPT, str(d / "cases.json"), str(d), str(RES)],
                       capture_output=True, text=True, cwd=ROOT, timeout=900)
    if r.returncode != 0 or not all((d / f"{n}.exr").is_file() for n in spec):
        tail = (r.stderr or r.stdout).strip().splitlines()[-3:]
        _unavailable(f"EEVEE did not render (exit {r.returncode}): {' | '.join(tail)}")
    return d


def _read(path):
    """Combined colour and the P AOV: one part per layer (Blender 5.0+) or one part with every
    layer's channels (4.x); the OpenEXR module groups NAME.R/G/B/A into NAME either way."""
    with OpenEXR.File(str(path)) as f:
        channels = {name: ch for part in f.parts for name, ch in part.channels.items()}
        color = channels["ViewLayer.Combined"].pixels
        pos = channels["ViewLayer.P"].pixels
    return np.asarray(color, np.float32), np.asarray(pos, np.float32)


def _centres(res: int) -> np.ndarray:
    """Object-space pixel centres of the plane, float32 (res * res, 3), EXR row order (top row first)."""
    g = (np.arange(res, dtype=np.float64) + 0.5) * 2.0 / res - 1.0
    x, y = np.meshgrid(g, -g)
    return np.stack([x, y, np.zeros_like(x)], -1).reshape(-1, 3).astype(np.float32)


@pytest.mark.parametrize("case", list(CASES))
def test_eevee_render_equals_engine(renders, case):
    s, kw = CASES[case]
    color, pos = _read(renders / f"{case}.exr")
    pts = _centres(RES)
    # EEVEE shaded every pixel at its centre (the AOV is half float: 2^-11 steps near 1)
    assert np.abs(pos[..., :3].reshape(-1, 3) - pts).max() < 1e-3
    z = _engine(s, pts, **kw)
    for c, out in enumerate(("real", "imag", "modulus")):
        ref = select_output(z, out)
        got = color[..., c].ravel()
        enc = np.float32(0.5) + np.float32(ENC) * ref
        assert enc.min() > 0.0, "encoding would clamp"
        err = np.abs(got - enc)
        assert err.max() < 1e-3, (case, out, float(err.max()))
        assert np.corrcoef(got, ref)[0, 1] > 0.9999


def test_eevee_renders_the_cellular_node(renders):
    """The Wave Cellular node (3D, 16 directions: 32 plane families) in EEVEE: the engine's distance everywhere
    and its cell at all but a few pixels (where float rounding puts a pixel centre on a plane's other side)."""
    color, _ = _read(renders / "cells.exr")
    ref = compile_noise(CELLS).evaluate(_centres(RES))
    enc = lambda v: np.float32(0.5) + np.float32(ENC) * v  # noqa: E731
    dist = np.abs(color[..., 0].ravel() - enc(ref.distance))
    cell = np.abs(color[..., 1].ravel() - enc(ref.cell))
    assert dist.max() < 1e-3, float(dist.max())
    assert np.mean(cell < 1e-3) > 0.99 and len(np.unique(np.round(ref.cell, 4))) > 50
