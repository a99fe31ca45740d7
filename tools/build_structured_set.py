"""Rebuild the held-out structured photos of the procedural solids: ``python tools/build_structured_set.py``.

Photos whose structure runs through the material (planks, grain, a board's figure, veins, strata, tiles, cobbles),
from the packages and under the licence rules of the photo set (``tools/build_photo_set.py``: CC-BY-SA-3.0,
CC-BY-3.0, CC0, public domain or Expat, per file from the packages' DEP-5 copyright files), that the photo set does
not hold: neither model training nor any tuning read them.  Nexuiz's and OpenArena's textures (GPL-2.0-or-later, the
whole package) and the files of UFO:AI, Extreme Tux Racer and Scorched3D under GPL-2.0-or-later are taken here too,
and only here: these photos are evaluated, never trained on, and the repository is GPL-3.0-or-later (UFO:AI's
GPL-2.0-only files, its veined marble and layered rock faces among them, are not).
Each is cut as the photo set cuts its crops (short side scaled to SOURCE_SIDE px, the centre CROP px square) but
without its stationarity filter, which would drop exactly these.  The evaluation of the procedural solids
(``python -m bench solid-procedural``) reads them beside the photo set's held-out brick, paving, tile and wood
photos.

``data/structured/manifest.json`` lists per crop: package, version, path, licence, authors, the source's sha256,
the crop box and the crop's sha256; ``data/structured/ATTRIBUTION.md`` is the attribution the licences ask for.
"""
from __future__ import annotations

import io
import os
import re
import sys
import zipfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from omninoise.export.atomic import atomic_path, write_json  # noqa: E402
from tools.build_photo_set import (CROP, LICENCES, SOURCE_SIDE, _sha, _version, package_arguments,  # noqa: E402
                                   parse_dep5, scaled_centre, stk_licence, write_attribution)

OUT = os.path.join(ROOT, "data", "structured")
#: the licences taken: the photo set's, and GPL-2.0-or-later (module doc)
STRUCTURED_LICENCES = LICENCES + ("GPL-2.0-or-later",)
#: DEP-5 licence names -> SPDX
SPDX = {"GPL-2+": "GPL-2.0-or-later"}
#: where each package keeps the files and archives that SOURCES names
GAMES = {"supertuxkart-data": "usr/share/games/supertuxkart", "ufoai-textures": "usr/share/games/ufoai",
         "nexuiz-textures": "usr/share/games/nexuiz/data", "openarena-081-textures": "usr/share/games/openarena",
         "extremetuxracer-data": "usr/share/games/etr", "scorched3d-data": "usr/share/games/scorched3d"}
#: packages whose DEP-5 file names their files by the source tree's path: the folder that holds GAMES[pkg] there
SOURCE_TREE = {"extremetuxracer-data": "data/", "scorched3d-data": ""}
#: packages that name a texture by its folder (Scorched3D's landscapes each hold a rockside.jpg)
NAMED_BY_FOLDER = ("scorched3d-data",)
PACKAGES = tuple(GAMES)
#: (package, path inside it, category): the structured photos the packages hold under the licences
SOURCES = (("supertuxkart-data", "data/textures/JapanwoodBridge.jpg", "wood"),
           ("supertuxkart-data", "data/textures/japanRedWood.png", "wood"),
           ("supertuxkart-data", "data/textures/bow_tile.jpg", "paving"),
           ("ufoai-textures", "base/0textures.pk3:textures/tex_buildings/tile01.png", "tile"),
           ("ufoai-textures", "base/0textures.pk3:textures/tex_buildings/tile02.png", "tile"),
           ("ufoai-textures", "base/0textures.pk3:textures/tex_buildings/tile03.png", "tile"),
           ("ufoai-textures", "base/0textures.pk3:textures/tex_nature/tree_chopped.jpg", "wood"),
           ("ufoai-textures", "base/0textures.pk3:textures/tex_nature/tree_chopped2.jpg", "wood"),
           ("nexuiz-textures", "textures.pk3:textures/evil2_misc/blue_marble.jpg", "marble"),
           ("nexuiz-textures", "textures.pk3:textures/egyptsoc_mat/wood17.tga", "wood"),
           ("nexuiz-textures", "textures.pk3:textures/desertfactory_wood/wood04.tga", "wood"),
           ("openarena-081-textures", "baseoa/pak4-textures.pk3:textures/proto2/marble02b.jpg", "marble"),
           ("extremetuxracer-data", "terrains/rock01.png", "marble"),
           ("extremetuxracer-data", "terrains/rock06.png", "marble"),
           ("scorched3d-data", "data/globalmods/none/data/textures/landscape/arizona/rockside.jpg", "stone"),
           ("scorched3d-data", "data/globalmods/none/data/textures/landscape/denali/rockside.jpg", "stone"))


def nexuiz_licence(text: str) -> tuple:
    """(licence, authors) of nexuiz-textures from its copyright file (not DEP-5: one licence for the package)."""
    if not re.search(r"either\s+version\s+2\s+of\s+the\s+License,\s+or\s+\(at\s+your\s+option\)\s+any\s+later"
                     r"\s+version", text):
        raise SystemExit("nexuiz-textures: its copyright file no longer grants GPL-2.0-or-later")
    m = re.search(r"Nexuiz is \S+ (.*)", text)
    return "GPL-2.0-or-later", re.sub(r"\s*<[^>]*>", "", m.group(1)).strip() if m else ""


def _licence(text: str, pkg: str, path: str) -> tuple:
    """(licence, authors) of a package's file from the package's copyright file ``text``."""
    if pkg == "nexuiz-textures":
        return nexuiz_licence(text)
    lic = parse_dep5(text)
    if pkg == "ufoai-textures":
        pk3, name = path.split(":", 1)
        licence, authors = lic[pk3.replace("0textures.pk3", "") + name]
    elif pkg == "openarena-081-textures":
        licence, authors = lic["*"]
    elif pkg in SOURCE_TREE:
        licence, authors = dep5_last_match(lic, SOURCE_TREE[pkg] + path)
    else:
        return stk_licence(lic, path)
    return SPDX.get(licence, licence), authors


def dep5_last_match(lic: dict, path: str) -> tuple:
    """(licence, authors) of the source tree's ``path`` under DEP-5 paragraphs ``lic``: the last Files pattern that
    matches it, as the format reads them."""
    import fnmatch

    hits = [v for k, v in lic.items() if fnmatch.fnmatch(path, k)]
    if not hits:
        raise SystemExit(f"{path}: no Files paragraph of its package's copyright file names it")
    return hits[-1]


def stem(pkg: str, path: str) -> str:
    """A source's name in the set: its file's name, lower case, after its folder's where NAMED_BY_FOLDER."""
    parts = path.split(":", 1)[-1].split("/")
    name = parts[-1].rsplit(".", 1)[0].lower()
    return f"{parts[-2].lower()}_{name}" if pkg in NAMED_BY_FOLDER else name


def _read(unpacked: str, pkg: str, path: str) -> tuple:
    """(bytes, licence, authors) of a package's file: under GAMES[pkg], inside an archive where ``path`` is
    "archive:member"."""
    root = os.path.join(unpacked, pkg)
    with open(os.path.join(root, "usr/share/doc", pkg, "copyright"), encoding="utf-8") as fh:
        licence = _licence(fh.read(), pkg, path)
    where = os.path.join(root, GAMES[pkg])
    if ":" in path:
        archive, member = path.split(":", 1)
        with zipfile.ZipFile(os.path.join(where, archive)) as z:
            return (z.read(member),) + licence
    with open(os.path.join(where, path), "rb") as fh:
        return (fh.read(),) + licence


def centre_crop(data: bytes) -> tuple:
    """Source bytes -> (crop uint8 (CROP, CROP, 3), box in the scaled source), as the photo set cuts them."""
    from PIL import Image

    with Image.open(io.BytesIO(data)) as im:
        return scaled_centre(im.convert("RGB"))


def build(unpacked: str, out: str, deb_dir: str) -> dict:
    from PIL import Image

    entries = []
    for pkg, path, cat in SOURCES:
        data, licence, authors = _read(unpacked, pkg, path)
        if licence not in STRUCTURED_LICENCES:
            raise SystemExit(f"{pkg}: {path} is {licence}, not one of {', '.join(STRUCTURED_LICENCES)}")
        a, box = centre_crop(data)
        fname = f"{cat}__{stem(pkg, path)}.jpg"
        buf = io.BytesIO()
        Image.fromarray(a).save(buf, "JPEG", quality=90, subsampling=0)
        with atomic_path(os.path.join(out, fname)) as tmp:
            with open(tmp, "wb") as fh:
                fh.write(buf.getvalue())
        entries.append(dict(file=fname, category=cat, package=pkg, version=_version(deb_dir, pkg), path=path,
                            licence=licence, authors=authors, source_sha256=_sha(data), crop=box,
                            sha256=_sha(buf.getvalue())))
    manifest = dict(description="held-out structured photos of the procedural solids "
                                "(tools/build_structured_set.py); crop = [x, y, w, h, scaled source W, H]",
                    crop=CROP, source_side=SOURCE_SIDE, photos=entries)
    write_json(os.path.join(out, "manifest.json"), manifest)
    write_attribution(out, "the structured photos", "Crops of textures from Debian's packages, under the licences "
                      "below. Rebuilt by `python tools/build_structured_set.py`; `manifest.json` has the package "
                      "version, path, crop and sha256 of each file.", entries)
    return manifest


def main(argv=None) -> int:
    a, unpacked, deb_dir = package_arguments(__doc__.split("\n")[0], OUT, argv, PACKAGES)
    os.makedirs(a.out, exist_ok=True)
    m = build(unpacked, a.out, deb_dir)
    print(f"{len(m['photos'])} structured photos in {os.path.relpath(a.out, ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
