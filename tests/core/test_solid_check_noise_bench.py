"""bench/solid_check_noise.py: the check's choice on two disjoint sets of planes, and the planes' layout."""
import json
import os

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))




def test_check_planes_are_x_y_and_z_cuts_per_seed_through_their_own_points():
    from omninoise.backend.solid import spectral
    from omninoise.training.solid.photo_eval import SLICE_OFFSETS

    planes = spectral.check_planes((6, 9))
    assert [(s, a) for s, a, _ in planes] == [(6, "x"), (6, "y"), (6, "z"), (9, "x"), (9, "y"), (9, "z")]
    assert len({o for _, _, o in planes}) == 2
    assert spectral.CHECK_PLANES == spectral.check_planes(spectral.CHECK_SEEDS)
    assert spectral.wall_planes(planes) == tuple(p for p in planes if p[1] in "xy")
    assert spectral.WALL_PLANES == spectral.wall_planes(spectral.CHECK_PLANES)
    assert not {o for _, _, o in spectral.CHECK_PLANES} & set(SLICE_OFFSETS.values())   # not the evaluation's


def test_bench_chooses_twice_per_photo(bench_script, tmp_path, capsys):
    from omninoise.backend.solid.spectral import KINDS, MIXES

    out = tmp_path / "noise.json"
    assert bench_script("solid_check_noise").main(["--limit", "1", "--seeds", "1", "-o", str(out)]) == 0
    doc = json.loads(out.read_text())
    (name, got), = doc["photos"].items()
    assert len(got) == 2 and all(c is None or (c[0] in KINDS and c[1] in MIXES) for c in got)
    assert doc["same"] == int(got[0] == got[1]) and "1 photos, 1 seeds per set" in capsys.readouterr().out
