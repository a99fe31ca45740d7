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
