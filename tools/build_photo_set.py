"""Rebuild the photo set of the neural solid textures from Debian's packages: ``python tools/build_photo_set.py``.

Real colour material photographs, from two packages whose
copyright files license them for redistribution:

* ``0ad-data`` (every texture CC-BY-SA-3.0, Wildfire Games): the terrain
  textures (ground, rock, cliffs, gravel, sand, soil, grass, forest floor,
  snow, paving), DDS inside ``mods/public/public.zip``, which Pillow decodes;
* ``ufoai-textures`` and ``supertuxkart-data`` (per file, from their DEP-5
  copyright files): wood, marble, metal, rust, brick, concrete, carpet,
  floors, rock; only files licensed CC-BY-SA-3.0, CC-BY-3.0, CC0, public
  domain or Expat are taken (GPL and CC-BY-SA-4.0 textures are left out, so
  the set and the weights trained on it are CC-BY-SA-3.0 as a whole).

Each source image gives one crop: the image is scaled so that its short side
is ``SOURCE_SIDE`` px (the packages' textures are 512-2048 px for one game
tile; this puts them at comparable pixels per unit), the centre ``CROP`` px
square is cut, and it is kept only if it is a stationary texture (the four
quadrants agree in mean colour and contrast, it is neither flat nor mostly
transparent).  Crops are JPEG (quality 90, no chroma subsampling; the sources are DXT-compressed
already) under ``data/photos/{train,val}/``; a crop's split is fixed by a hash
of its source path (``VAL_FRACTION`` held out, whole photos, never pixels).

``data/photos/manifest.json`` lists per crop: package, version, path inside
it, licence, authors, the source's sha256, the crop box and the crop's sha256;
``data/photos/ATTRIBUTION.md`` is the attribution the licences ask for.

The packages are fetched with ``apt-get download`` into ``--cache`` (about
1.7 GB, kept for reruns) unless ``--from DIR`` names a folder where they were
unpacked (``dpkg-deb -x``).
"""
from __future__ import annotations

import argparse
import glob
import hashlib
import io
import os
import re
import subprocess
import sys
import zipfile

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from omninoise.export.atomic import atomic_path, write_json  # noqa: E402

OUT = os.path.join(ROOT, "data", "photos")
PACKAGES = ("0ad-data", "ufoai-textures", "supertuxkart-data")
SOURCE_SIDE = 512          #: short side of a source after scaling, px
CROP = 256                 #: side of a stored crop, px
VAL_FRACTION = 0.15        #: share of source photos held out
LICENCES = ("CC-BY-SA-3.0", "CC-BY-3.0", "CC0", "CC0-1.0", "public-domain", "Expat")

#: category by keyword in the file name (first match wins); files matching none are skipped
CATEGORIES = (
    ("wood", ("wood", "parquet", "plank")),
    ("marble", ("marble",)),
    ("rust", ("rust",)),
    ("metal", ("metal", "metall")),
    ("brick", ("brick",)),
    ("fabric", ("carpet", "fabric", "cloth")),
    ("paving", ("paving", "cobble", "tiles", "slabs", "floor")),
    ("concrete", ("concrete", "conc")),
    ("gravel", ("gravel", "pebble", "shingle")),
    ("rock", ("cliff", "rock", "stone", "boulder", "granite")),
    ("sand", ("sand", "desert", "dune")),
    ("snow", ("snow", "ice")),
    ("grass", ("grass", "meadow", "steppe", "savanna", "forestfloor", "forest_floor", "moss", "leaves")),
    ("soil", ("dirt", "soil", "mud", "ground", "earth", "farmland", "clay", "wall_dirt")),
)
#: maps of other things than colour, and images that are not materials
EXCLUDE = re.compile(r"(_norm|_nrm|_normal|_nm|_spec|_sm|_ao|_height|_gloss|_mask|lava|water|ocean|road|path|edge|decal|blend|test)",
                     re.I)


def _sha(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def category(name: str) -> str | None:
    base = os.path.basename(name).lower()
    if EXCLUDE.search(base):
        return None
    for cat, words in CATEGORIES:
        if any(w in base for w in words):
            return cat
    return None


def split_of(source: str) -> str:
    """'val' for about VAL_FRACTION of source paths (a hash of the path: stable across rebuilds)."""
    h = int(hashlib.sha256(source.encode()).hexdigest()[:8], 16) / 0xFFFFFFFF
    return "val" if h < VAL_FRACTION else "train"


def stationary(a: np.ndarray) -> tuple[bool, str]:
    """Is an RGB crop float (S, S, 3) in [0, 1] a usable stationary texture?  (ok, reason if not)."""
    lum = a.mean(2)
    if lum.std() < 0.02:
        return False, "flat"
    S = a.shape[0] // 2
    quads = [a[:S, :S], a[:S, S:], a[S:, :S], a[S:, S:]]
    means = np.array([q.reshape(-1, 3).mean(0) for q in quads])
    stds = np.array([q.mean(2).std() for q in quads])
    if np.abs(means - means.mean(0)).max() > 0.08:
        return False, "quadrant colours differ"
    if stds.max() > 1.8 * stds.min() + 0.01:
        return False, "quadrant contrast differs"
    return True, ""


def parse_dep5(text: str) -> dict:
    """DEP-5 copyright file -> {file pattern: (licence, authors)} for its Files paragraphs."""
    out = {}
    for para in re.split(r"\n\s*\n", text):
        m = re.search(r"^Files:(.*?)(?=^\S)", para + "\nX", re.S | re.M)
        lic = re.search(r"^License:\s*(\S+)", para, re.M)
        if not m or not lic:
            continue
        cp = re.search(r"^Copyright:(.*?)(?=^\S|\Z)", para, re.S | re.M)
        authors = "; ".join(s.strip() for s in (cp.group(1) if cp else "").strip().splitlines() if s.strip())
        for f in m.group(1).split():
            out[f] = (lic.group(1), authors)
    return out


def _version(deb_dir: str, pkg: str) -> str:
    debs = glob.glob(os.path.join(deb_dir, f"{pkg}_*.deb"))
    return os.path.basename(debs[0]).split("_")[1] if debs else "unknown"


def fetch(cache: str, packages: tuple = PACKAGES) -> str:
    """apt-get download + dpkg-deb -x the packages into ``cache``; returns the unpack folder."""
    os.makedirs(os.path.join(cache, "x"), exist_ok=True)     # dpkg-deb -x makes its folder, not the parents
    for pkg in packages:
        if not glob.glob(os.path.join(cache, f"{pkg}_*.deb")):
            subprocess.run(["apt-get", "download", pkg], cwd=cache, check=True)
        x = os.path.join(cache, "x", pkg)
        if not os.path.isdir(x):
            deb = glob.glob(os.path.join(cache, f"{pkg}_*.deb"))[0]
            subprocess.run(["dpkg-deb", "-x", deb, x], check=True)
    return os.path.join(cache, "x")


def sources(unpacked: str):
    """Yield (package, path inside it, bytes, licence, authors, category)."""
    z = zipfile.ZipFile(os.path.join(unpacked, "0ad-data", "usr/share/games/0ad/mods/public/public.zip"))
    for name in sorted(z.namelist()):
        if name.startswith("art/textures/terrain/types/") and name.endswith(".dds"):
            cat = category(name.replace(".cached.dds", "").replace(".png", "").replace(".dds", ""))
            if cat:
                yield "0ad-data", "mods/public/public.zip:" + name, z.read(name), "CC-BY-SA-3.0", "Wildfire Games", cat
    root = os.path.join(unpacked, "ufoai-textures")
    lic = parse_dep5(open(os.path.join(root, "usr/share/doc/ufoai-textures/copyright"), encoding="utf-8").read())
    z = zipfile.ZipFile(os.path.join(root, "usr/share/games/ufoai/base/0textures.pk3"))
    for name in sorted(z.namelist()):
        key = "base/" + name
        if key not in lic or lic[key][0] not in LICENCES or not name.endswith((".png", ".jpg")):
            continue
        cat = category(name.rsplit(".", 1)[0])
        if cat:
            yield "ufoai-textures", "base/0textures.pk3:" + name, z.read(name), lic[key][0], lic[key][1], cat
    yield from _stk(unpacked)


def stk_licence(lic: dict, rel: str, globs: list | None = None):
    """(licence, authors) of a supertuxkart-data file from its DEP-5 paragraphs ``lic``: its own, else the first
    pattern that matches it (``globs``: lic's patterns, when a caller reads many files), else None."""
    import fnmatch

    if globs is None:
        globs = [(k, v) for k, v in lic.items() if any(ch in k for ch in "*?[")]
    return lic.get(rel) or next((v for k, v in globs if fnmatch.fnmatch(rel, k)), None)


def _stk(unpacked: str):
    root = os.path.join(unpacked, "supertuxkart-data")
    lic = parse_dep5(open(os.path.join(root, "usr/share/doc/supertuxkart-data/copyright"), encoding="utf-8").read())
    globs = [(k, v) for k, v in lic.items() if any(ch in k for ch in "*?[")]
    base = os.path.join(root, "usr/share/games/supertuxkart")
    for path in sorted(glob.glob(os.path.join(base, "data", "**", "*.*"), recursive=True)):
        rel = os.path.relpath(path, base)
        if not rel.endswith((".png", ".jpg")):
            continue
        cat = category(os.path.basename(rel).rsplit(".", 1)[0])
        L = stk_licence(lic, rel, globs)
        if cat and L and L[0] in LICENCES:
            with open(path, "rb") as fh:
                yield "supertuxkart-data", rel, fh.read(), L[0], L[1], cat


def crop(data: bytes):
    """Source bytes -> (crop uint8 (CROP, CROP, 3), box in the scaled source) or (None, reason)."""
    from PIL import Image

    with Image.open(io.BytesIO(data)) as im:
        im.load()
        if min(im.size) < CROP:
            return None, "small"
        if im.mode in ("RGBA", "LA", "P"):
            alpha = np.asarray(im.convert("RGBA"))[..., 3]
            if (alpha < 250).mean() > 0.02:
                return None, "transparent"
        rgb = im.convert("RGB")
    a, box = scaled_centre(rgb)
    ok, why = stationary(a.astype(np.float32) / 255.0)
    return (a, box) if ok else (None, why)


def scaled_centre(rgb) -> tuple:
    """A PIL RGB image scaled so that its short side is SOURCE_SIDE px (never enlarged) -> (its centre CROP px square
    uint8 (CROP, CROP, 3), the box [x, y, w, h, scaled W, H])."""
    from PIL import Image

    f = SOURCE_SIDE / min(rgb.size)
    if f < 1.0:
        rgb = rgb.resize((max(CROP, round(rgb.size[0] * f)), max(CROP, round(rgb.size[1] * f))), Image.LANCZOS)
    W, H = rgb.size
    x0, y0 = (W - CROP) // 2, (H - CROP) // 2
    return np.asarray(rgb)[y0:y0 + CROP, x0:x0 + CROP], [x0, y0, CROP, CROP, W, H]


def build(unpacked: str, out: str, deb_dir: str) -> dict:
    from PIL import Image

    entries, skipped, seen, names = [], {}, set(), set()
    for pkg, path, data, licence, authors, cat in sources(unpacked):
        src_sha = _sha(data)
        if src_sha in seen:            # the packages hold some textures twice
            skipped["duplicate"] = skipped.get("duplicate", 0) + 1
            continue
        seen.add(src_sha)
        a, box = crop(data)
        if a is None:
            skipped[box] = skipped.get(box, 0) + 1
            continue
        split = split_of(path)
        stem = re.sub(r"[^a-z0-9]+", "_", path.split(":", 1)[-1].lower().replace(".cached.dds", "")
                      .rsplit(".", 1)[0].replace("art/textures/terrain/types/", "").replace("textures/", "").replace("data/", ""))
        fname = f"{split}/{cat}__{stem.strip('_')}.jpg"
        if fname in names:             # the same name in two packages or folders: add the source's hash
            fname = f"{split}/{cat}__{stem.strip('_')}_{src_sha[:6]}.jpg"
        names.add(fname)
        buf = io.BytesIO()
        Image.fromarray(a).save(buf, "JPEG", quality=90, subsampling=0)
        with atomic_path(os.path.join(out, fname)) as tmp:
            with open(tmp, "wb") as fh:
                fh.write(buf.getvalue())
        entries.append(dict(file=fname, category=cat, split=split, package=pkg, version=_version(deb_dir, pkg),
                            path=path, licence=licence, authors=authors, source_sha256=src_sha,
                            crop=box, sha256=_sha(buf.getvalue())))
    manifest = dict(description="colour material photographs for the neural solid textures "
                                "(tools/build_photo_set.py); crop = [x, y, w, h, scaled source W, H]",
                    crop=CROP, source_side=SOURCE_SIDE, val_fraction=VAL_FRACTION, skipped=skipped,
                    photos=sorted(entries, key=lambda e: e["file"]))
    write_json(os.path.join(out, "manifest.json"), manifest)
    _attribution(out, manifest)
    return manifest


def _attribution(out: str, manifest: dict) -> None:
    write_attribution(out, "the photo set", "Crops of textures from Debian's packages, under the licences below (the "
                      "set as a whole, and the models trained on it, under CC-BY-SA-3.0). Rebuilt by `python "
                      "tools/build_photo_set.py`; `manifest.json` has the package version, path, crop and sha256 of "
                      "each file.", manifest["photos"])


def write_attribution(out: str, what: str, intro: str, entries: list) -> None:
    """``out``/ATTRIBUTION.md: a heading naming ``what``, ``intro`` and a row per manifest entry (file, licence,
    authors, package, version and path)."""
    lines = [f"# Attribution of {what}", "", intro, "", "| file | licence | authors | source |", "|---|---|---|---|"]
    for e in entries:
        lines.append(f"| {e['file']} | {e['licence']} | {e['authors'] or '—'} | {e['package']} {e['version']}: "
                     f"`{e['path']}` |")
    with atomic_path(os.path.join(out, "ATTRIBUTION.md")) as tmp:
        with open(tmp, "w", encoding="utf-8") as fh:
            fh.write("\n".join(lines) + "\n")


def package_arguments(description: str, out: str, argv=None, packages: tuple = PACKAGES) -> tuple:
    """(arguments, the unpacked packages' folder, the .deb files' folder) of a tool that reads the packages:
    ``--cache`` (fetched there), ``--from`` (unpacked already) and ``-o``."""
    ap = argparse.ArgumentParser(description=description)
    ap.add_argument("--cache", default=os.path.expanduser("~/.cache/omninoise/debs"),
                    help="where the .deb files are downloaded and unpacked")
    ap.add_argument("--from", dest="unpacked", help="a folder with the packages already unpacked (one folder each)")
    ap.add_argument("-o", "--out", default=out)
    a = ap.parse_args(argv)
    unpacked = a.unpacked or fetch(a.cache, packages)
    return a, unpacked, os.path.dirname(os.path.abspath(unpacked)) if a.unpacked else a.cache


def main(argv=None) -> int:
    a, unpacked, deb_dir = package_arguments(__doc__.split("\n")[0], OUT, argv)
    for old in glob.glob(os.path.join(a.out, "*", "*.jpg")):
        os.remove(old)
    for split in ("train", "val"):
        os.makedirs(os.path.join(a.out, split), exist_ok=True)
    m = build(unpacked, a.out, deb_dir)
    cats = {}
    for e in m["photos"]:
        cats.setdefault(e["category"], [0, 0])[e["split"] == "val"] += 1
    print(f"{len(m['photos'])} crops (skipped: {m['skipped']})")
    for c, (tr, va) in sorted(cats.items()):
        print(f"  {c:9s} train {tr:3d}  val {va:3d}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
