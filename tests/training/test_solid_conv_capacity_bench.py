"""bench/solid_conv_capacity.py: a tiny fit of the convolutional generator runs end to end in 2D and upright 3D,
writes its table, sheet and weights, and the weights reload into a generator that draws the same texture."""
import json
import os

import pytest

torch = pytest.importorskip("torch")

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CONFIG = os.path.join(ROOT, "configs", "solid", "capacity", "brick_w128l4.json")




@pytest.mark.parametrize("dim", [2, 3])
def test_tiny_fit_measures_draws_and_keeps_its_weights(bench_script, tmp_path, dim, capsys):
    mod = bench_script("solid_conv_capacity")
    out = str(tmp_path / "cap")
    extra = ["--upright", "--scale", "0.25"] if dim == 3 else []
    assert mod.main([CONFIG, "--dim", str(dim), "--steps", "2", "--crop", "32", "--batch", "1", "--width", "4",
                     "--scales", "3", "--seeds", "1", "--flat", "--precision", "fp32", "--out", out] + extra) == 0
    row = json.load(open(out + ".json"))["rows"][0]
    assert row["dim"] == dim and row["steps"] == 2 and row["photo"] == "brick__tex_buildings_wall_brick01"
    assert 0 < row["random_phase"] < row["pixel_shuffle"] and row["model"] > 0
    from PIL import Image
    # photo | one texture (3D upright: the x wall; the y wall is the second view) | random phase noise
    with Image.open(out + ".png") as im:
        assert im.size == ((3 if dim == 2 else 4) * row["size"], row["size"])
    saved = torch.load(out + "_brick_w128l4.pt", weights_only=False)
    net = mod.ConvGenerator(saved["dim"], saved["scales"], saved["noise"], saved["width"], saved["grow"])
    net.load_state_dict(saved["state"])
    assert "| brick_w128l4 |" in capsys.readouterr().out


def test_a_long_fit_keeps_checkpoints_and_resumes_only_with_its_settings(bench_script, tmp_path, capsys):
    mod = bench_script("solid_conv_capacity")
    out = str(tmp_path / "cap")
    args = [CONFIG, "--dim", "3", "--upright", "--scale", "0.25", "--steps", "3", "--crop", "16", "--batch", "1",
            "--width", "4", "--scales", "2", "--seeds", "1", "--flat", "--precision", "fp32", "--out", out]
    assert mod.main(args + ["--save-every", "2"]) == 0
    ckpt = torch.load(out + "_brick_w128l4.ckpt", weights_only=False)
    assert ckpt["step"] == ckpt["steps"] == 3 and ckpt["setting"]["width"] == 4
    weights = torch.load(out + "_brick_w128l4.pt", weights_only=False)["state"]
    for k, v in weights.items():
        torch.testing.assert_close(ckpt["net"][k], v)
    capsys.readouterr()
    assert mod.main(args + ["--resume"]) == 0           # the fit is done: it is measured again, not retrained
    assert "resuming" in capsys.readouterr().out and json.load(open(out + ".json"))["rows"][0]["steps"] == 3
    with pytest.raises(SystemExit, match="other settings.*width"):
        mod.main([a if a != "4" else "6" for a in args] + ["--resume"])
