"""Tiles of a texture library: ``python bench/solid_periods.py [--tiles DIR] [--split val,train] [--sheet]``.

A texture library's tiles repeat their pattern only two to four times (Sweet Home 3D's bricks: two courses of
two bricks in 256 x 166 px), too few for the harmonic part's peak test, whose ring around a peak then holds the
pattern's other harmonics; backend/solid/periods.py finds such a tile's periods from its autocorrelation instead.
Lines straight across the frame that the part leaves (a single floor tile framed by its grout, plank seams,
slab joints) are a tile's pattern held once; periods.py reads them from the rows and columns that are lines.
This bench reads every image both ways (without the readings ``--without`` names: ``periods``, ``lines`` or both,
the default; and as shipped) and, where the part changes, draws the 3D texture both ways with the neural texture
(the space model, as ``omninoise solid --exemplar TILE`` encodes it) and the spectral solid (``--method
spectral``), scored against the tile as ``bench/solid_motif.py`` scores a framing (x, y and z slices at two seeds,
pooled and walls; six oblique cuts; patch distance x 1000 and its band-pass part; lower is better).  Images where
nothing changes are counted, not drawn (the same code path: the same texture, bit for bit).

The tiles: the textures Sweet Home 3D ships (``sweethome3d``'s jar, GPL-2+; Debian 7.0.2+dfsg-3), fetched with
``apt-get download`` into ``out/cache/sweethome3d`` unless ``--tiles DIR`` names a folder of images; its skies are
left out (not materials).  They are measured here, never stored in the repository or trained on.  ``--split``
adds the photo set's splits (whole photos).  ``--sheet`` writes PREFIX.jpg: the tile (repeated to fill a square) |
the x slice (a wall) of the neural texture without | with the readings | the same two of the spectral solid.
"""
from __future__ import annotations

import argparse
import glob
import os
import subprocess
import sys
import tempfile
import zipfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

import numpy as np  # noqa: E402

from omninoise.backend.solid import harmonic  # noqa: E402
from bench.solid_motif import METHODS, SIZE, compare, draw, same, score  # noqa: E402
from omninoise.export import read_rgb  # noqa: E402
from omninoise.export.atomic import write_json  # noqa: E402
from omninoise.training.solid import photo_eval as pe  # noqa: E402
from omninoise.training.solid.photo_set import photo_set  # noqa: E402

PACKAGE = "sweethome3d"
JAR = "usr/share/sweethome3d/sweethome3d.jar"
TEXTURES = "com/eteks/sweethome3d/io/resources/textures/"
SKIES = ("blueSky", "cloudy", "veryCloudy")


def fetch_tiles(cache: str) -> str:
    """The Sweet Home 3D textures (skies left out) under ``cache``, fetched with apt-get download and unpacked
    from the package's jar on the first call; returns their folder."""
    out = os.path.join(cache, "textures")
    if glob.glob(os.path.join(out, "*.jpg")):
        return out
    os.makedirs(out, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        subprocess.run(["apt-get", "download", PACKAGE], cwd=tmp, check=True, capture_output=True)
        deb = glob.glob(os.path.join(tmp, "*.deb"))[0]
        subprocess.run(["dpkg-deb", "-x", deb, os.path.join(tmp, "x")], check=True)
        with zipfile.ZipFile(os.path.join(tmp, "x", JAR)) as z:
            for name in z.namelist():
                base = os.path.basename(name)
                if name.startswith(TEXTURES) and base.endswith(".jpg") and base[:-4] not in SKIES:
                    with open(os.path.join(out, base), "wb") as f:
                        f.write(z.read(name))
    return out


def square(img: np.ndarray) -> np.ndarray:
    """The tile repeated to fill SIZE x SIZE px (its first SIZE rows and columns of the repetition)."""
    reps = (-(-SIZE // img.shape[0]), -(-SIZE // img.shape[1]), 1)
    return np.tile(img, reps)[:SIZE, :SIZE]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--tiles", default="", help="a folder of tile images (default: Sweet Home 3D's, fetched)")
    ap.add_argument("--no-tiles", action="store_true", help="only the photo set's --split")
    ap.add_argument("--split", default="", help="comma-separated photo set splits to add: val, train")
    ap.add_argument("--without", default="periods,lines",
                    help="comma-separated readings of harmonic.photo_harmonics the first drawing leaves out: periods "
                         "(a tile's few repeats), lines (lines straight across the frame); default both")
    ap.add_argument("--methods", default=",".join(METHODS))
    ap.add_argument("--count", action="store_true", help="only count the images the readings change (no drawing)")
    ap.add_argument("--sheet", action="store_true")
    ap.add_argument("--out", default=os.path.join(ROOT, "out", "bench", "solid_periods"))
    a = ap.parse_args(argv)
    methods = [m for m in a.methods.split(",") if m]
    off = {k: False for k in a.without.split(",") if k}
    if not off or set(off) - {"periods", "lines"}:
        ap.error(f"--without takes periods and/or lines, not {a.without!r}")
    files = []
    if not a.no_tiles:
        folder = a.tiles or fetch_tiles(os.path.join(ROOT, "out", "cache", PACKAGE))
        files += sorted(glob.glob(os.path.join(folder, "*.jpg")) + glob.glob(os.path.join(folder, "*.png")))
    for split in [s for s in a.split.split(",") if s]:
        files += photo_set(split, os.path.join(ROOT, "data", "photos"))
    rows, unchanged, sheet = {}, 0, []
    for path in files:
        name = os.path.basename(path)
        tile = read_rgb(path)
        hb = harmonic.photo_harmonics(tile, 128.0, **off)
        hp = harmonic.photo_harmonics(tile, 128.0)
        if same(hb, hp):
            unchanged += 1
            continue
        head = (f"{name[:40]:40s} {tile.shape[1]:4d} x {tile.shape[0]:<4d} waves {len(hb):3d} -> {len(hp):3d}  "
                f"share {hb.share:.2f} -> {hp.share:.2f}")
        row = {"size": [int(tile.shape[1]), int(tile.shape[0])], "waves": [len(hb), len(hp)],
               "share": [round(hb.share, 3), round(hp.share, 3)]}
        rows[name] = row
        if a.count:
            print(head, flush=True)
            continue
        pics = [square(tile)]
        for method in methods:
            for key, reading in (("without", off), ("with", {})):
                imgs, obl, sec = draw(tile, method, True, **reading)
                r = score(tile, imgs, obl)
                r["seconds"] = round(sec, 1)
                row[f"{method}_{key}"] = r
                pics.append(imgs["x"][0])
        sheet.append(pics)
        print(head + "  " + "  ".join(
            f"{m}: walls {row[m + '_without']['walls']:.1f} -> {row[m + '_with']['walls']:.1f}, oblique "
            f"{row[m + '_without']['oblique']:.1f} -> {row[m + '_with']['oblique']:.1f}, pooled "
            f"{row[m + '_without']['pooled']:.1f} -> {row[m + '_with']['pooled']:.1f}" for m in methods), flush=True)
    summary = {"without": sorted(off), "images": len(files), "unchanged": unchanged, "changed": len(rows)}
    drawn = [r for r in rows.values() if f"{methods[0]}_without" in r] if methods else []
    summary.update(compare(drawn, methods, "without", "with"))
    for k, v in summary.items():
        print(k, v)
    os.makedirs(os.path.dirname(a.out) or ".", exist_ok=True)
    write_json(a.out + ".json", {"summary": summary, "rows": rows})
    if a.sheet and sheet:
        pe.tile_sheet(sheet, a.out + ".jpg")
    return 0


if __name__ == "__main__":
    sys.exit(main())
