"""The held-out structured photos of the procedural solids (``tools/build_structured_set.py``): their manifest,
licences and attribution."""
import hashlib
import json
import os
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "tools"))

import build_structured_set as bss  # noqa: E402

FOLDER = os.path.join(ROOT, "data", "structured")


def _photos(folder: str) -> list:
    with open(os.path.join(folder, "manifest.json"), encoding="utf-8") as fh:
        return json.load(fh)["photos"]


def test_structured_set_manifest_matches_the_files():
    """Each file's sha256, a licence the tool takes, its package, and a row of the attribution; no photo of them is
    in the photo set."""
    photos = _photos(FOLDER)
    assert {f for f in os.listdir(FOLDER) if f.endswith(".jpg")} == {e["file"] for e in photos}
    assert len(photos) == len(bss.SOURCES)
    for e in photos:
        with open(os.path.join(FOLDER, e["file"]), "rb") as fh:
            assert hashlib.sha256(fh.read()).hexdigest() == e["sha256"], e["file"]
        assert e["licence"] in bss.STRUCTURED_LICENCES and e["package"] in bss.PACKAGES
        assert e["version"] != "unknown" and e["authors"]
    photo_set = _photos(os.path.join(ROOT, "data", "photos"))
    assert not {e["source_sha256"] for e in photos} & {e["source_sha256"] for e in photo_set}
    with open(os.path.join(FOLDER, "ATTRIBUTION.md"), encoding="utf-8") as fh:
        text = fh.read()
    assert all(f"| {e['file']} | {e['licence']} |" in text for e in photos)


def test_nexuiz_licence_is_read_off_its_copyright_file():
    grant = ("Nexuiz is \u00a9 2002 - 2009 Alientrap, Lee Vermeulen <lv@example.org>\n\nThis program is free "
             "software; you can redistribute it and/or\nmodify it under the terms of the GNU General Public "
             "License\nas published by the Free Software Foundation; either version 2\nof the License, or (at your "
             "option) any later version.\n")
    assert bss.nexuiz_licence(grant) == ("GPL-2.0-or-later", "2002 - 2009 Alientrap, Lee Vermeulen")
    with pytest.raises(SystemExit, match="GPL-2.0-or-later"):
        bss.nexuiz_licence(grant.replace("either version 2", "version 2 only"))


def test_ufoai_licences_are_read_per_file():
    """UFO:AI's DEP-5 names a licence per file: GPL-2+ is taken as GPL-2.0-or-later, GPL-2 alone is not taken."""
    dep5 = ("Files:\n base/textures/tex_nature/tree_chopped.jpg\nCopyright:\n Someone\nLicense: GPL-2+\n\n"
            "Files:\n base/textures/tex_ctp1/marble_m_1.jpg\nCopyright:\n Another\nLicense: GPL-2\n")
    member = "base/0textures.pk3:textures/tex_nature/tree_chopped.jpg"
    assert bss._licence(dep5, "ufoai-textures", member) == ("GPL-2.0-or-later", "Someone")
    licence, _ = bss._licence(dep5, "ufoai-textures", "base/0textures.pk3:textures/tex_ctp1/marble_m_1.jpg")
    assert licence == "GPL-2" and licence not in bss.STRUCTURED_LICENCES


def test_source_tree_licences_take_the_last_matching_paragraph():
    """Extreme Tux Racer's and Scorched3D's DEP-5 files name source-tree paths; the last Files pattern that matches
    a file gives its licence, so a mod's own paragraph is not read for the base game's textures."""
    dep5 = ("Files: *\nCopyright: 2001-2014 Gavin Camp\nLicense: GPL-2+\n\n"
            "Files: data/globalmods/apoc/*\nCopyright: Apocalypse mod team\nLicense: CC-BY-SA-3\n")
    base = "data/globalmods/none/data/textures/landscape/arizona/rockside.jpg"
    assert bss._licence(dep5, "scorched3d-data", base) == ("GPL-2.0-or-later", "2001-2014 Gavin Camp")
    assert bss._licence(dep5, "scorched3d-data", "data/globalmods/apoc/data/rock.jpg")[0] == "CC-BY-SA-3"
    etr = "Files: *\nCopyright: Extreme Tux Racer Team\nLicense: GPL-2+\n\nFiles: data/courses/extras/*\n" \
          "Copyright: Milo Fungus\nLicense: GPL-2+\n\nFiles: src/quadtree.*\nCopyright: U. T.\nLicense: quadtree\n"
    assert bss._licence(etr, "extremetuxracer-data", "terrains/rock01.png") == ("GPL-2.0-or-later",
                                                                                 "Extreme Tux Racer Team")
    assert bss._licence(etr, "extremetuxracer-data", "courses/extras/a/terrain.png")[1] == "Milo Fungus"
    with pytest.raises(SystemExit, match="names it"):
        bss.dep5_last_match({"src/*": ("GPL-2+", "")}, "data/terrains/rock01.png")


def test_scorched3d_landscapes_are_named_by_their_folder():
    names = [bss.stem(pkg, path) for pkg, path, _ in bss.SOURCES]
    assert len(set(names)) == len(names)
    assert bss.stem("scorched3d-data", "data/globalmods/none/data/textures/landscape/denali/rockside.jpg") \
        == "denali_rockside"
    assert bss.stem("nexuiz-textures", "textures.pk3:textures/egyptsoc_mat/wood17.tga") == "wood17"
