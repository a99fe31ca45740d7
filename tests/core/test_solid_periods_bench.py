"""bench/solid_periods.py: reads a folder of tiles both ways, draws a changed one both ways, scores both against
the tile, and writes its table and sheet."""
import json

import numpy as np

from test_solid_periods import brick_tile  # a sibling test module


def test_the_periods_bench_counts_draws_and_scores_a_tile(bench_script, tmp_path):
    from PIL import Image

    mod = bench_script("solid_periods")
    tiles = tmp_path / "tiles"
    tiles.mkdir()
    img, _ = brick_tile()
    Image.fromarray((img * 255 + 0.5).astype(np.uint8)).save(tiles / "bricks.png")
    rng = np.random.default_rng(1)
    Image.fromarray(rng.integers(90, 160, (96, 128, 3), dtype=np.uint8)).save(tiles / "noise.png")
    out = str(tmp_path / "periods")
    assert mod.main(["--tiles", str(tiles), "--methods", "neural", "--sheet", "--out", out]) == 0
    d = json.load(open(out + ".json"))
    s = d["summary"]
    assert s["images"] == 2 and s["unchanged"] == 1 and s["changed"] == 1
    row = d["rows"]["bricks.png"]
    assert row["size"] == [256, 160] and row["waves"][1] > row["waves"][0] and row["share"][1] > row["share"][0]
    for k in ("neural_without", "neural_with"):
        assert set(row[k]) >= {"pooled", "walls", "band", "walls_band", "oblique", "oblique_band", "colour"}
    # the head joints come back on the walls (193.0 -> 153.8 when measured)
    assert row["neural_with"]["walls"] < row["neural_without"]["walls"]
    assert s["without"] == ["lines", "periods"]
    with Image.open(out + ".jpg") as im:        # tile | the x wall without the periods | with them
        assert im.size == (3 * 128, 128)
