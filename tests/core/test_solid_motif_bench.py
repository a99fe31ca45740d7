"""bench/solid_motif.py: counts the framings the motif changes, draws a changed one both ways with the neural
texture, scores both against the whole photo, and writes its table and sheet."""
import json


def test_the_motif_bench_counts_draws_and_scores_a_framed_brick_wall(bench_script, tmp_path):
    mod = bench_script("solid_motif")
    out = str(tmp_path / "motif")
    assert mod.main(["--only", "trak4_brick", "--methods", "neural", "--framings", "whole,250x200", "--sheet",
                     "--out", out]) == 0
    d = json.load(open(out + ".json"))
    s = d["summary"]
    # the tileable whole photo is read as before (its lattice lies on the grid); the crop is not
    assert s["photos"] == 1 and s["framings"] == 2 and s["unchanged"] == 1 and s["changed"] == 1
    row = d["rows"]["brick__tex_trak_trak4_brick2a.jpg|250x200"]
    assert row["waves"][1] > row["waves"][0] and row["share"][1] > row["share"][0]
    for k in ("neural_bins", "neural_motif"):
        assert set(row[k]) >= {"pooled", "walls", "band", "walls_band", "oblique", "oblique_band", "colour"}
    # the bricks come back on the walls (136.4 -> 98.9 when measured)
    assert row["neural_motif"]["walls"] < row["neural_bins"]["walls"]
    assert s["neural_walls"]["closer"] == 1
    from PIL import Image
    with Image.open(out + ".jpg") as im:        # crop | the x wall with the bins | with the motif
        assert im.size == (3 * 128, 128)
