"""The solid model card (training/solid/model_card.py): a regenerated card keeps the sections other tools
wrote, names each model's loss and config file, and tabulates the single-exemplar photo models' evaluation."""
import json
import os

import pytest

torch = pytest.importorskip("torch")  # omninoise.training needs torch

from omninoise.training.solid import model_card as mc

EXISTING = """# Neural solid texture models

old top

## Models

| old table |

## Limits

- old limit

<!-- photo-space:begin -->
## Photo texture space

ledger
<!-- photo-space:end -->

## Decoder capacity

capacity text
"""


def test_regenerated_card_keeps_the_sections_it_does_not_write():
    out = mc.keep_other_sections(EXISTING, "# Neural solid texture models\n\nnew top\n\n## Limits\n\n- new limit\n")
    assert "new top" in out and "- new limit" in out
    assert "old top" not in out and "old table" not in out and "old limit" not in out
    # the marker stays with the section it opens; the order of kept sections is the card's
    assert out.index("<!-- photo-space:begin -->\n## Photo texture space") < out.index("## Decoder capacity")
    assert out.count("<!-- photo-space:end -->") == 1 and "capacity text" in out
    # idempotent: regenerating twice gives the same card
    assert mc.keep_other_sections(out, "# Neural solid texture models\n\nnew top\n\n## Limits\n\n- new limit\n") == out


def test_loss_label_and_config_file_of_a_retrained_model(tmp_path):
    assert mc.loss_label({"loss": "swd", "spectrum_weight": 0.2, "structure_weight": 0.2, "colour": "affine"}) == \
        "swd + spectrum 0.2 + structure 0.2, colour affine"
    assert mc.loss_label({"loss": "swd", "bricks": 3, "fixed_axis": "rows"}) == "swd, 3 brick octaves, fixed_axis rows"
    assert mc.loss_label({}) == "gram"
    assert mc.loss_label({"loss": "swd", "hist_weight": 30.0, "bricks": 3, "noise_ramp": 400}) == \
        "swd + colour 30, 3 brick octaves, value noise ramped in over 400 steps"
    assert mc.loss_label({"loss": "swd", "hist_weight": 10.0}) == "swd"
    # two config files share a name (the model and the one it replaced): the run's own config picks its file
    (tmp_path / "sub").mkdir()
    old = {"name": "wood_3d", "exemplars": ["wood"], "steps": 1500}
    new = {"name": "wood_3d", "exemplars": ["data/photos/train/wood__x.jpg"], "steps": 500}
    (tmp_path / "wood_3d.json").write_text(json.dumps(old))
    (tmp_path / "sub" / "wood_3d.json").write_text(json.dumps(new))
    index = mc._config_index(str(tmp_path))
    assert mc._config_files(dict(new, lr=0.002), index) == [os.path.join("sub", "wood_3d.json")]
    assert mc._config_files(dict(old, lr=0.002), index) == ["wood_3d.json"]


def test_singles_section_reads_the_evaluation(tmp_path):
    row = dict(photo="data/photos/train/wood__oldwood.jpg", dim=3, swd=90.5, space=120.0, random_phase=100.0,
               pixel_shuffle=400.0, photo_crop=50.0, colour=0.01, space_colour=0.02, morph=0.5,
               morph_random_phase=0.9, morph_space=0.7)
    doc = dict(rows={"wood_3d": row}, summary=dict(models=1, median_swd=90.5, median_space=120.0,
                                                      median_random_phase=100.0, median_colour=0.01,
                                                      worst_colour=0.01,
                                                      beats=dict(space=1, random_phase=1, pixel_shuffle=1)))
    path = tmp_path / "singles.json"
    path.write_text(json.dumps(doc))
    text = "\n".join(mc.singles_section(str(path)))
    assert "| wood_3d | wood__oldwood.jpg (public-domain) | **90.5** | 120.0 | 100.0 | 400.0 | — | 50.0 | 0.01 |" in text
    assert "lower than the space model's on 1" in text
