"""Tile plans and feathered weights of tiled neural noise (torch-free)."""
import numpy as np
import pytest

from backend.neural.generate import AUTO_TILE, AUTO_WHOLE, auto_tile
from backend.neural.tiles import feather, plan


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
