"""How often the Gaussian rest's check (backend/solid/spectral.py, choose_mix) would decide otherwise on other
planes: ``python bench/solid_check_noise.py [--split train] [--limit 40] [--seeds 2] [-o JSON]``.

For every photo (every k-th of the split, so that about ``--limit`` are read) the texture-space model encodes the
photo as the product does (harmonic part, decoder), and the check chooses its Gaussian rest twice, on two disjoint
sets of planes of the same layout as CHECK_PLANES: x, y and z cuts at ``--seeds`` seeds each (seeds 6, 7, ... and
the next ``--seeds`` after them).  Both sets are equally valid samples of the same solid, so every photo on which
the two choices differ is one the check decides by the chance of its planes.  Prints each photo's two choices
((kind, share) or None: the decoder alone), how many photos agree, how many flip between a rest and none, and the
seconds the checks took.  ``-o JSON`` writes the rows.
"""
from __future__ import annotations

import argparse
import os
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)
sys.path.insert(0, os.path.join(ROOT, "bench"))

from omninoise.export.atomic import write_json  # noqa: E402
from omninoise.backend.solid import spectral  # noqa: E402


def choice(model, photo, code, planes) -> tuple | None:
    """The check's choice (model.gaussian_rest, "auto") on ``planes``: (kind, share) or None."""
    kept = spectral.CHECK_PLANES
    spectral.CHECK_PLANES = planes        # gaussian_rest reads the planes when it is called
    try:
        r = model.gaussian_rest(photo, code)
    finally:
        spectral.CHECK_PLANES = kept
    return None if r is None else (r.kind, r.mix)


def main(argv=None) -> int:
    from eval_solid_photos import photos, read
    from omninoise.backend.solid.model import SolidTextureModel

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--model", default=os.path.join(ROOT, "models", "solid", "space"))
    ap.add_argument("--split", default="train", choices=("train", "val"))
    ap.add_argument("--limit", type=int, default=40)
    ap.add_argument("--seeds", type=int, default=2, help="seeds per set of planes (CHECK_PLANES has 2)")
    ap.add_argument("-o", "--out")
    a = ap.parse_args(argv)
    model = SolidTextureModel(a.model)
    files = photos(a.split)
    if a.limit:
        files = files[::max(1, len(files) // a.limit)][:a.limit]
    sets = [spectral.check_planes(range(6 + i * a.seeds, 6 + (i + 1) * a.seeds)) for i in (0, 1)]
    rows, t0 = {}, time.time()
    for path in files:
        photo = read(path)
        code = model.photo_code(photo, gaussian=False)
        rows[os.path.basename(path)] = got = [choice(model, photo, code, p) for p in sets]
        print(os.path.basename(path), got, flush=True)
    same = sum(x == y for x, y in rows.values())
    flips = sum((x is None) != (y is None) for x, y in rows.values())
    seconds = round(time.time() - t0, 1)
    print(f"{len(rows)} photos, {a.seeds} seeds per set: the same choice on {same}, a rest against none on {flips} "
          f"({seconds} s)")
    if a.out:
        write_json(a.out, dict(split=a.split, seeds=a.seeds, same=same, rest_flips=flips, seconds=seconds,
                               photos=rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
