"""Is each class's generated image nearest to its own zoo class? `python -m bench neural-nearest --model M [...]`.

The test: every class's generated images at 256² should be nearer, by spectrum and histogram, to the zoo's
images of that class than to those of any other class, except classes that are near-duplicates in the zoo
itself.  This prints and writes (``-o``, JSON) both halves of that test with the measure of
``training/evaluate.py`` (:func:`look`: the shape of the radial power spectrum in 24 log-spaced bands and 32
value quantiles; distances in units of the median distance between two zoo classes).  The spectrum is taken of
each image's periodic component (Moisan 2011, :func:`training.evaluate.periodic_component`): five zoo classes
tile (gaussian, fibers, gabor, phasor, gabor_texture) and a model's images do not, and the jumps at the borders
of an image that does not tile spread about 1e-4 of its power into every top band, more than a smooth class
holds there:

- **the zoo against itself**: per class, zoo images split in two halves (seeds alternate); half A of class c
  is compared with half B of every class.  Classes c' at least as near to A_c as c's own half B are
  near-duplicates of c *by this measure* (the measure cannot tell them apart on ground truth), listed with
  their distances;
- **each model**: ``--n`` images per class (default parameters, seeds 11, 12, ...) at ``--size``² with the
  default sampler, their look's nearest zoo class (half B) and whether it is the class itself or one of its
  zoo near-duplicates.
"""
from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

from omninoise.backend.neural import conditioning as C
from omninoise.backend.neural.generate import generate
from omninoise.backend.neural.model import NeuralNoiseModel
from omninoise.export.atomic import write_json


def zoo_halves(classes, size: int, n: int) -> dict:
    """{class: (half A, half B)} float32 (n // 2, size, size) zoo images at default parameters."""
    import torch

    from omninoise.training import zoo

    out = {}
    for name in classes:
        imgs = zoo.generate(name, zoo.default_params(name), torch.arange(n) + 600, size).numpy()
        out[name] = (imgs[0::2], imgs[1::2])
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--model", action="append", default=[], help="a model folder (repeat to compare)")
    ap.add_argument("--label", action="append", help="a label per --model")
    ap.add_argument("--classes", help="comma-separated (default: the first model's trained classes, else the zoo's)")
    ap.add_argument("--size", type=int, default=256)
    ap.add_argument("--n", type=int, default=2, help="generated images per class")
    ap.add_argument("--zoo-n", type=int, default=8, help="zoo images per class (two halves)")
    ap.add_argument("--threads", type=int, default=0)
    ap.add_argument("--floor", type=float, default=0.0,
                    help="count spectrum bands under this share of the power as equal (training.evaluate.look)")
    ap.add_argument("-o", "--out", default=os.path.join(ROOT, "out", "bench", "neural_nearest.json"))
    a = ap.parse_args(argv)
    from omninoise.training import zoo
    from omninoise.training.evaluate import look, look_scales, nearest_looks

    models = [NeuralNoiseModel(m, threads=a.threads) for m in a.model]
    labels = a.label or [os.path.basename(os.path.normpath(m)) for m in a.model]
    if len(labels) != len(models):
        ap.error("give one --label per --model")
    if a.classes:
        classes = [c.strip() for c in a.classes.split(",") if c.strip()]
    elif models:
        classes = list(models[0].config["trained_classes"])
    else:
        classes = list(zoo.CLASS_NAMES)
    halves = zoo_halves(classes, a.size, a.zoo_n)
    refs = {c: look(h[1], a.floor) for c, h in halves.items()}
    scale = look_scales(refs)
    report = dict(size=a.size, n=a.n, zoo_n=a.zoo_n, floor=a.floor, scale=dict(spectrum=scale[0], histogram=scale[1]),
                  zoo={}, models={})
    dups = {}
    for c in classes:
        ranked = nearest_looks(look(halves[c][0], a.floor), refs, scale)
        own = dict(ranked)[c]
        dups[c] = [(o, d) for o, d in ranked if o != c and d <= own]
        other = next((o, d) for o, d in ranked if o != c)
        report["zoo"][c] = dict(own=round(own, 3), nearest_other=[other[0], round(other[1], 3)],
                                near_duplicates={o: round(d, 3) for o, d in dups[c]})
    pairs = sorted({tuple(sorted((c, o))) for c in classes for o, _ in dups[c]})
    report["zoo_near_duplicate_pairs"] = [[x, y, round(float(np.abs(refs[x]["spectrum"] - refs[y]["spectrum"]).mean()
                                                           / scale[0] + np.abs(refs[x]["histogram"]
                                                                               - refs[y]["histogram"]).mean()
                                                           / scale[1]), 3)] for x, y in pairs]
    for label, m in zip(labels, models):
        rows, t0 = {}, time.perf_counter()
        for c in classes:
            imgs = np.stack([generate(m, C.uniform(m, (c, {}), a.size, a.size), seed=11 + i) for i in range(a.n)])
            ranked = nearest_looks(look(imgs, a.floor), refs, scale)
            ok = {c} | {o for o, _ in dups[c]}
            rows[c] = dict(nearest=[[o, round(d, 3)] for o, d in ranked[:3]], own=round(dict(ranked)[c], 3),
                           passes=ranked[0][0] in ok)
            print(f"{label} {c}: nearest {ranked[0][0]} ({ranked[0][1]:.2f}), own {dict(ranked)[c]:.2f}"
                  f"{'' if rows[c]['passes'] else '  FAILS'}", file=sys.stderr)
        report["models"][label] = dict(folder=m.folder, step=m.config.get("step"), classes=rows,
                                       passes=sum(r["passes"] for r in rows.values()),
                                       seconds=round(time.perf_counter() - t0, 1))
    print(f"zoo near-duplicate pairs by this measure: {report['zoo_near_duplicate_pairs']}")
    head = "| class | zoo: own half | zoo: nearest other |" + "".join(f" {lb}: nearest | {lb}: own |" for lb in labels)
    print(head)
    print("|---" * (3 + 2 * len(labels)) + "|")
    for c in classes:
        z = report["zoo"][c]
        line = f"| {c} | {z['own']} | {z['nearest_other'][0]} ({z['nearest_other'][1]}) |"
        for lb in labels:
            r = report["models"][lb]["classes"][c]
            mark = "" if r["passes"] else " ✗"
            line += f" {r['nearest'][0][0]} ({r['nearest'][0][1]}){mark} | {r['own']} |"
        print(line)
    for lb in labels:
        print(f"{lb}: {report['models'][lb]['passes']} of {len(classes)} classes nearest to their own zoo class "
              f"(or a zoo near-duplicate)")
    os.makedirs(os.path.dirname(os.path.abspath(a.out)), exist_ok=True)
    write_json(a.out, report)
    return 0


if __name__ == "__main__":
    sys.exit(main())
