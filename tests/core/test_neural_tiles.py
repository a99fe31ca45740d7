"""Tile plans and feathered weights of tiled neural noise (torch-free)."""
import numpy as np
import pytest

from omninoise.backend.neural.generate import AUTO_TILE, AUTO_WHOLE, auto_tile
from omninoise.backend.neural.tiles import feather, plan


@pytest.mark.parametrize("H,W,tile,overlap,wrap", [(2048, 2048, 512, 64, False), (1000, 376, 256, 32, False),
                                                   (512, 512, 512, 64, False), (2048, 1536, 512, 64, True),
                                                   (96, 160, 64, 16, True)])
def test_tiles_cover_every_pixel_with_the_overlap(H, W, tile, overlap, wrap):
    cover = np.zeros((H, W), np.int32)
    origins = plan(H, W, tile, overlap, wrap)
    th, tw = min(tile, H), min(tile, W)
    for y0, x0 in origins:
        ys, xs = np.arange(y0, y0 + th), np.arange(x0, x0 + tw)
        if not wrap:
            assert ys[0] >= 0 and ys[-1] < H and xs[0] >= 0 and xs[-1] < W
        cover[np.ix_(ys % H, xs % W)] += 1
    assert cover.min() >= 1
    ys = sorted({y for y, _ in origins})
    gaps = np.diff(ys + ([ys[0] + H] if wrap and len(ys) > 1 else []))
    assert len(ys) == 1 or (th - gaps).min() >= overlap  # neighbours overlap by at least `overlap`


def test_feather_ramps_only_towards_neighbours():
    w = feather(64, 48, 16, (True, False, False, True))
    assert w.dtype == np.float32 and w.min() > 0 and w.max() == 1.0
    assert w[0, 10] < 0.05 and w[-1, 10] == 1.0  # ramp at the top (a neighbour), none at the bottom
    assert w[30, -1] < 0.05 and w[30, 0] == 1.0
    np.testing.assert_allclose(w[8, 20], (8 + 0.5) / 16)


def test_automatic_tiling():
    assert auto_tile(AUTO_WHOLE, AUTO_WHOLE) == 0 and auto_tile(AUTO_WHOLE + 8, 64) == AUTO_TILE


def _peak_of_tiled_image(side: int, tile: int) -> int:
    """Peak resident bytes of a process that makes one side x side image in tiles (one evaluation of the shipped
    model, the tiles' encoder maps not kept: MAP_CACHE_BYTES 0), and checks the image."""
    import os
    import subprocess
    import sys

    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    code = (
        "import numpy as np\n"
        "import backend.neural.generate as G\n"
        "from backend.neural import conditioning as C\n"
        "from backend.neural.model import NeuralNoiseModel\n"
        "G.MAP_CACHE_BYTES = 0\n"
        "m = NeuralNoiseModel('models/neural_noise', threads=2)\n"
        f"img = G.generate(m, C.uniform(m, ('clouds', {{}}), {side}, {side}), seed=1, steps=1, sampler='ddim', tile={tile})\n"
        f"assert img.shape == ({side}, {side}) and np.isfinite(img).all() and img.std() > 0.01\n"
        "print([l for l in open('/proc/self/status') if l.startswith('VmHWM')][0].split()[1])\n")
    out = subprocess.run([sys.executable, "-c", code], cwd=root, capture_output=True, text=True, check=True)
    return int(out.stdout.split()[-1]) * 1024


@pytest.mark.long
def test_tiled_generation_bounds_peak_memory():
    """Tiles bound memory by the tile, not the image: in 256 px tiles, going from a 512² image (9 tiles) to a
    1024² one (36 tiles) adds under 300 bytes a pixel, about what the conditioning grid itself takes (4 bytes per
    channel: 168) and the sampler's few image arrays; the one-piece path's encoder maps alone take 2080 bytes a
    pixel.  Kept maps add at most MAP_CACHE_BYTES (2 GB; see generate.image_eps).  The bench states the
    default's figures (3.3 GiB at 2048²)."""
    import os

    if not os.path.exists("/proc/self/status"):
        pytest.skip("peak memory is read from /proc (Linux)")
    small, large = _peak_of_tiled_image(512, 256), _peak_of_tiled_image(1024, 256)
    per_pixel = (large - small) / (1024 * 1024 - 512 * 512)
    assert per_pixel < 300, f"512²: {small / 2**20:.0f} MiB, 1024²: {large / 2**20:.0f} MiB, {per_pixel:.0f} B/px"
