"""One request for every front-end: equal neural-noise settings from command-line flags and from a job
file give equal requests and equal images (the panel's: tests/blender/test_neural_blender.py); job files take every
layout the command line does. On the committed tiny model (no torch)."""
import os

import numpy as np
import pytest

from omninoise.cli.main import build_parser, main
from omninoise.cli.neural import neural_request
from omninoise.backend.errors import SettingError
from omninoise.backend.neural.model import NeuralNoiseModel
from omninoise.backend.neural.request import NeuralRequest, generate_request
from omninoise.backend.sources import source_from_dict
from omninoise.export.images import write_png

TINY = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "data", "tiny_neural")
SAMPLING = ["--size", "32", "--seed", "3", "--steps", "3", "--sampler", "ddim"]


@pytest.fixture(scope="module")
def model():
    return NeuralNoiseModel(TINY)


@pytest.fixture
def maps(tmp_path):
    mask = np.zeros((32, 32), np.uint8)
    mask[:, 12:] = 255
    write_png(str(tmp_path / "mask.png"), mask)
    paint = np.zeros((32, 32, 3), np.uint8)
    paint[8:24, 8:24] = (255, 0, 0)
    paint[:, 28:] = (0, 0, 255)
    write_png(str(tmp_path / "paint.png"), paint)
    return tmp_path


CASES = {
    "uniform": (["--noise", "spots", "--param", "coverage=0.4"],
                dict(noise="spots", params={"coverage": 0.4})),
    "blend": (["--noise", "spots", "--blend", "mask.png", "--noise2", "perlin", "--param2", "scale=10", "--width", "8"],
              dict(noise="spots", blend="mask.png", noise2="perlin", params2={"scale": 10}, width=8)),
    "gradient": (["--gradient", "spots:coverage=0.3", "cells_f1:scale=10"],
                 dict(gradient=["spots:coverage=0.3", {"noise": "cells_f1", "params": {"scale": 10}}])),
    "corners": (["--corners", "spots:coverage=0.3", "perlin", "cells_f1:scale=10,jitter=0.5", "spots"],
                dict(corners=["spots:coverage=0.3", "perlin", {"noise": "cells_f1", "params": {"scale": 10, "jitter": 0.5}},
                              "spots"])),
    "painted": (["--map", "paint.png", "--region", "#000000=spots", "--region", "#ff0000=perlin:scale=9",
                 "--region", "#0000ff=cells_f1", "--sharpness", "2"],
                dict(map="paint.png", regions={"#000000": "spots", "#ff0000": {"noise": "perlin", "params": {"scale": 9}},
                                               "#0000ff": "cells_f1"}, sharpness=2)),
}


@pytest.mark.parametrize("layout", sorted(CASES))
def test_flags_and_job_tables_give_the_same_request(layout, model, maps, monkeypatch):
    flags, table = CASES[layout]
    monkeypatch.chdir(maps)
    cli = neural_request(build_parser().parse_args(["neural", "--model", TINY, *flags, *SAMPLING, "-o", "x.png"]),
                         model)
    job = source_from_dict(dict(kind="neural", model=TINY, seed=3, steps=3, sampler="ddim", **table),
                           str(maps)).request((32, 32))
    assert cli.layout == job.layout == layout
    assert cli.key() == job.key()
    np.testing.assert_array_equal(cli.conditioning(model), job.conditioning(model))


def test_a_painted_job_bakes_the_command_lines_image(model, maps):
    flags, _ = CASES["painted"]
    assert main(["neural", "--model", TINY, "--quiet", *[f if not f.endswith(".png") else str(maps / f) for f in flags],
                 *SAMPLING, "-o", str(maps / "cli.npy")]) == 0
    (maps / "job.toml").write_text(f"""
[[bake]]
name = "painted"
output = "job.png"
resolution = [32, 32]
[bake.source]
kind = "neural"
model = "{TINY}"
map = "paint.png"
regions = {{"#000000" = "spots", "#ff0000" = "perlin:scale=9", "#0000ff" = {{noise = "cells_f1"}}}}
sharpness = 2
seed = 3
steps = 3
sampler = "ddim"
""")
    assert main(["bake", str(maps / "job.toml"), "--quiet"]) == 0
    from omninoise.export.images import read_image

    np.testing.assert_allclose(read_image(str(maps / "job.png")), np.load(maps / "cli.npy"), atol=0.5 / 255 + 1e-6)


@pytest.mark.parametrize("table, msg", [
    (dict(corners=["spots", "perlin", "spots"]), "source.corners: expected 4 items, got 3"),
    (dict(regions={"#ff0000": "spots"}), "source.regions: names the colours of map; without map, it would change"),
    (dict(corners=["spots"] * 4, params={"coverage": 0.5}),
     "source.params: sets the parameters of noise; with corners, it would change nothing"),
    (dict(corners=["spots"] * 4, noise="perlin"), "source.noise: is the class of the whole image, or of a blend's"),
    (dict(map="paint.png", regions={"#000000": "spots"}, noise2="perlin"),
     "source.noise2: is the class of a blend's masked part; with map, it would change nothing"),
    (dict(keys=[{"frame": 1, "noise": "spots"}], width=4.0),
     "source.width: shapes the transitions of blend and map; with keys, it would change nothing"),
    (dict(keys=[{"frame": 1, "noise": "spots"}], noise="perlin"), "source.noise: is the class of the whole image"),
    (dict(noise="spots", drift=0.1), "source.drift: moves the starting noise from frame to frame of keys; without"),
    (dict(map="paint.png", corners=["spots"] * 4), "choose one of blend, gradient, corners and map"),
    (dict(gradient=["spots"]), "source.gradient: expected 2 items, got 1"),
    (dict(gradient=["spots", "perlin"], noise="perlin"), "source.noise: is the class of the whole image"),
    (dict(gradient=["spots", "perlin"], width=8.0),
     "source.width: shapes the transitions of blend and map; with gradient, it would change nothing"),
    (dict(gradient=["spots", "perlin"], corners=["spots"] * 4), "source.corners: choose one of blend, gradient,"),
    (dict(gradient=["spots", "lava"]), "source.gradient[1]: unknown class 'lava'"),     # each named by its key
    (dict(noise="spots", params={"coverage": 9}), "source.params: coverage=9 is outside"),
    (dict(noise="spots", blend="paint.png", noise2="lava"), "source.noise2: unknown class 'lava'"),
    (dict(noise="spots", blend="paint.png", params2={"coverage": 9}), "source.params2: coverage=9 is outside"),
    (dict(map="paint.png", regions={"#ff00": "spots"}), "bad colour '#ff00'"),
    (dict(map="paint.png", regions={"#000000": "spots", "#ff0000": "perlin"}),
     "the map uses (0, 0, 255) but no spec is given for it"),
    (dict(map="paint.png", regions={"#000000": "spots", "#ff0000": "perlin", "#0000ff": "lava"}),
     "source.regions: unknown class 'lava'"),
    (dict(corners=["spots:coverage", "perlin", "spots", "spots"]), "expected NAME=VALUE with a finite number"),
    (dict(corners=["spots", "perlin", {"noise": "spots", "size": 2}, "spots"]),
     "source.corners[2].size: unknown key; known: noise, params"),
])
def test_job_layouts_say_what_is_wrong(table, msg, maps):
    with pytest.raises(SettingError) as e:
        source_from_dict(dict(kind="neural", model=TINY, **table), str(maps))
    assert msg in str(e.value)


def test_requests_check_what_every_front_end_shares(model):
    ok = NeuralRequest("uniform", [("spots", {})], 16, 16, steps=2)
    assert generate_request(model, ok).shape == (16, 16)
    for req, msg in [(NeuralRequest("spiral", [("spots", {})], 16, 16), "unknown layout 'spiral'"),
                     (NeuralRequest("corners", [("spots", {})] * 3, 16, 16), "takes 4 class specs, got 3"),
                     (NeuralRequest("blend", [("spots", {}), ("perlin", {})], 16, 16), "mask is none"),
                     (NeuralRequest("painted", [("spots", {})], 16, 16, regions=np.ones((16, 16), int)),
                      "region indices must lie in [0, 1)"),
                     (NeuralRequest("uniform", [("spots", {"size": 1})], 16, 16), "no parameter 'size'"),
                     (NeuralRequest("uniform", [("spots", {})], 4, 16), "must be >= 8"),
                     (NeuralRequest("uniform", [("spots", {})], 20, 16, tileable=True), "multiples of 8"),
                     (NeuralRequest("uniform", [("spots", {})], 16, 16, steps=0), "must be")]:
        with pytest.raises(SettingError, match=None) as e:
            req.check(model)
        assert msg in str(e.value), (msg, str(e.value))


@pytest.mark.parametrize("layout", ["blend", "painted"])
def test_a_mask_or_map_of_another_size_is_drawn_at_the_images_size(layout, model, maps, monkeypatch, capsys):
    """A 32 px mask or painted map drawn as a 64 px image (command line and job file alike) is the image of that
    map grown to 64 px by nearest pixel with its transition width doubled (transitions are in the map's pixels, as
    the Blender panel reads its blend map); a map of other proportions is refused naming it, before any work."""
    flags, table = CASES[layout]
    monkeypatch.chdir(maps)
    sampling = [a if a != "32" else "64" for a in SAMPLING]
    cli = neural_request(build_parser().parse_args(["neural", "--model", TINY, *flags, *sampling, "-o", "x.png"]),
                         model)
    job = source_from_dict(dict(kind="neural", model=TINY, seed=3, steps=3, sampler="ddim", **table),
                           str(maps)).request((64, 64))
    assert cli.key() == job.key() and job.key()["map_size"] == [32, 32]
    small = cli.mask if layout == "blend" else cli.regions
    grown = np.repeat(np.repeat(small, 2, axis=0), 2, axis=1)
    big = NeuralRequest(layout, cli.specs, 64, 64, **{"mask" if layout == "blend" else "regions": grown},
                        transition=2 * cli.transition, sharpness=cli.sharpness, seed=3, steps=3, sampler="ddim")
    np.testing.assert_array_equal(cli.conditioning(model), big.conditioning(model))
    np.testing.assert_allclose(generate_request(model, job), generate_request(model, big), atol=1e-6)
    with pytest.raises(SettingError, match=r"is 32x32 but the image is 64x48: a (mask|map) is drawn at the image's "
                                           r"size and must have its proportions"):
        NeuralRequest(layout, cli.specs, 64, 48, mask=cli.mask, regions=cli.regions).check(model)
    flag = "--blend" if layout == "blend" else "--map"
    assert main(["neural", "--model", TINY, *flags, "--size", "48", "-o", "x.png"]) == 0
    wide = np.zeros((16, 32), np.uint8)
    write_png(str(maps / "wide.png"), wide)
    args = [a if a not in ("mask.png", "paint.png") else "wide.png" for a in flags]
    assert main(["neural", "--model", TINY, *args, "--size", "32", "-o", "y.png", "--quiet"]) == 2
    assert f"{flag}: " in capsys.readouterr().err and not (maps / "y.png").exists()
    with pytest.raises(SettingError, match=f"^source.{'blend' if layout == 'blend' else 'map'}: (mask|map) is 32x16 "
                                           "but the resolution is 32x32"):
        source_from_dict(dict(kind="neural", model=TINY, **dict(table, **{"blend" if layout == "blend" else "map":
                                                                          "wide.png"})), str(maps)).check_grid((32, 32))


def test_a_map_with_soft_edges_is_told_apart_from_one_missing_colour():
    """A map painted with a soft or anti-aliased brush blends its regions' colours at their edges: every blend is a
    colour of no spec. The message names the first and says how many there are (it named one colour of hundreds)."""
    from omninoise.backend.neural.request import regions_from_map

    px = np.zeros((8, 32, 3), np.float32)
    px[:, :, 0] = np.clip((np.arange(32) - 12) / 8.0, 0, 1)     # black to red over 8 px
    with pytest.raises(SettingError, match=r"the map uses \(32, 0, 0\) but no spec is given for it \(7 colours have "
                                           r"none, on 56 px, the first at x 13, y 0 from the top left: paint the map "
                                           "with hard edges"):
        regions_from_map(px, [(0, 0, 0), (255, 0, 0)], "--map")
    with pytest.raises(SettingError, match=r"uses 10 but no spec is given for it \(7 grey levels have none, on 56 px, "
                                           "the first at x 13, y 0 "):
        regions_from_map(px, [0, 76], "--map")
    hard = np.round(px)
    with pytest.raises(SettingError, match=r"uses \(255, 0, 0\) but no spec is given for it \(on 120 px, the first "
                                           r"at x 17, y 0 from the top left\)$"):     # 15 columns of red, 8 rows
        regions_from_map(hard, [(0, 0, 0)], "--map")
    stray = np.zeros((8, 32, 3), np.float32)
    stray[5, 20] = (1 / 255, 0, 0)          # one pixel a brush left a shade off black: where to find it
    with pytest.raises(SettingError, match=r"uses \(1, 0, 0\) but no spec is given for it \(on 1 px, the first at "
                                           r"x 20, y 5 from the top left\)$"):
        regions_from_map(stray, [(0, 0, 0)], "--map")
    assert set(np.unique(regions_from_map(hard, [(0, 0, 0), (255, 0, 0)]))) == {0, 1}


def test_a_jobs_png_holds_the_noise_as_the_command_line_writes_it(tmp_path):
    """Neural noise lies in [0, 1]: a job's 8-bit PNG holds its grey levels as they are, as `omninoise neural -o`
    writes them, not stretched over their percentiles as a preview of wave noise is (the shipped model, whose perlin
    spans part of the range: the tiny model's images fill it, where a stretch changes nothing)."""
    from omninoise.export.images import read_image

    assert main(["neural", "--noise", "perlin", "--size", "32", "--steps", "2", "--seed", "1", "--quiet",
                 "-o", str(tmp_path / "cli.png")]) == 0
    assert main(["neural", "--noise", "perlin", "--size", "32", "--steps", "2", "--seed", "1", "--quiet",
                 "-o", str(tmp_path / "cli.npy")]) == 0
    (tmp_path / "job.toml").write_text('[[bake]]\nname = "n"\noutput = "job.png"\nresolution = [32, 32]\n'
                                       '[bake.source]\nkind = "neural"\nnoise = "perlin"\nsteps = 2\nseed = 1\n')
    assert main(["bake", str(tmp_path / "job.toml"), "--quiet"]) == 0
    job, cli, raw = read_image(str(tmp_path / "job.png")), read_image(str(tmp_path / "cli.png")), \
        np.load(tmp_path / "cli.npy")
    assert 0.05 < raw.min() and raw.max() < 0.95            # a stretch would move these grey levels
    np.testing.assert_array_equal(job, cli)
    np.testing.assert_allclose(job, raw, atol=0.5 / 255 + 1e-6)
