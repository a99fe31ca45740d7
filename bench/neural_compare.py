"""Compare two evaluations of `python -m bench neural-eval`: `python -m bench neural-compare BEFORE.json AFTER.json`.

Prints, as Markdown, the tables the model card and the README show for a candidate against the model it would
replace (the test: the median per-class FD at most half, no class worse): the aggregate measures side by side
with their ratio, then one row per class (FD before and after, ratio, accuracy, PSD errors).  Both evaluations must
use one instrument: the same evaluation size, classifier, sampler, samples per class and classes; otherwise the
comparison is refused with a one-line error naming what differs (their FDs would be on different scales).
"""
from __future__ import annotations

import argparse
import json
import sys

import numpy as np

#: what must be equal for two evaluations to be compared (key, what to call it)
INSTRUMENT = (("size", "evaluation size"), ("classifier", "classifier"), ("sampler", "sampler"))


def load(path: str) -> dict:
    try:
        with open(path, encoding="utf-8") as fh:
            d = json.load(fh)
    except (OSError, ValueError) as exc:
        raise SystemExit(f"neural_compare: error: cannot read {path}: {exc}") from None
    if not isinstance(d, dict) or not isinstance(d.get("classes"), dict) or not d["classes"]:
        raise SystemExit(f"neural_compare: error: {path} is not an evaluation of python -m bench neural-eval (no classes)")
    return d


def instrument_difference(a: dict, b: dict) -> str | None:
    """What makes the two evaluations incomparable, or None."""
    for key, name in INSTRUMENT:
        if a.get(key) != b.get(key):
            return f"{name} differs: {a.get(key)} against {b.get(key)}"
    na, nb = (a.get("model") or {}).get("n"), (b.get("model") or {}).get("n")
    if na != nb:
        return f"samples per class differ: {na} against {nb}"
    if set(a["classes"]) != set(b["classes"]):
        only = sorted(set(a["classes"]) ^ set(b["classes"]))
        return f"classes differ: {', '.join(only)} in one evaluation only"
    return None


def summary(a: dict, b: dict) -> dict:
    """Aggregates of two comparable evaluations: medians, means, classes lower, the worst ratio."""
    names = list(a["classes"])
    fa = np.array([a["classes"][c]["fd"] for c in names], float)
    fb = np.array([b["classes"][c]["fd"] for c in names], float)
    ratio = fb / fa
    worst = int(np.argmax(ratio))

    def med(d, key, f=np.median):
        v = [d["classes"][c].get(key) for c in names]
        return float(f(v)) if all(x is not None for x in v) else None

    return dict(classes=names, median_fd=(float(np.median(fa)), float(np.median(fb))),
                mean_fd=(float(fa.mean()), float(fb.mean())), lower=int((fb < fa).sum()),
                worst=(names[worst], float(fa[worst]), float(fb[worst]), float(ratio[worst])),
                acc=(med(a, "acc", np.mean), med(b, "acc", np.mean)), psd=(med(a, "psd"), med(b, "psd")),
                psd_low=(med(a, "psd_low"), med(b, "psd_low")),
                locality=(a.get("locality"), b.get("locality")), seam=(a.get("seam_tileable"), b.get("seam_tileable")))


def _f(v, digits=1) -> str:
    return "—" if v is None else f"{v:.{digits}f}"


def markdown(a: dict, b: dict, labels=("before", "after")) -> str:
    s = summary(a, b)
    la, lb = labels
    n = len(s["classes"])
    (ma, mb), (ea, eb) = s["median_fd"], s["mean_fd"]
    w = s["worst"]
    rows = [f"| measure | {la} | {lb} | ratio |", "|---|---|---|---|",
            f"| median per-class FD ↓ | {_f(ma)} | **{_f(mb)}** | {mb / ma:.2f} |",
            f"| mean per-class FD ↓ | {_f(ea)} | {_f(eb)} | {eb / ea:.2f} |",
            f"| classes with lower FD | | **{s['lower']} of {n}** | worst ratio {w[3]:.2f} ({w[0]} {w[1]:.0f} → {w[2]:.0f}) |",
            f"| generated images classified right (mean) ↑ | {_f(s['acc'][0], 3)} | {_f(s['acc'][1], 3)} | |",
            f"| median PSD error ↓ / low-frequency PSD error ↓ | {_f(s['psd'][0], 3)} / {_f(s['psd_low'][0], 3)} | "
            f"{_f(s['psd'][1], 3)} / {_f(s['psd_low'][1], 3)} | |",
            f"| blend locality ↑ | {_f(s['locality'][0], 3)} | {_f(s['locality'][1], 3)} | |",
            f"| tileable seam ratio (1 = no seam) | {_f(s['seam'][0], 3)} | {_f(s['seam'][1], 3)} | |",
            "", f"| class | FD {la} | FD {lb} | ratio | accuracy {la} → {lb} | PSD error {la} → {lb} |",
            "|---|---|---|---|---|---|"]
    for c in s["classes"]:
        ra, rb = a["classes"][c], b["classes"][c]
        rows.append(f"| {c} | {ra['fd']:.1f} | {rb['fd']:.1f} | {rb['fd'] / ra['fd']:.2f} | "
                    f"{_f(ra.get('acc'), 3)} → {_f(rb.get('acc'), 3)} | {_f(ra.get('psd'), 3)} → {_f(rb.get('psd'), 3)} |")
    return "\n".join(rows)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("before", help="evaluation JSON of the model a candidate would replace")
    ap.add_argument("after", help="evaluation JSON of the candidate")
    ap.add_argument("--labels", default="before,after", help="two comma-separated column names")
    a = ap.parse_args(argv)
    labels = [x.strip() for x in a.labels.split(",")]
    if len(labels) != 2 or not all(labels):
        ap.error("--labels takes two names separated by a comma")
    before, after = load(a.before), load(a.after)
    why = instrument_difference(before, after)
    if why:
        print(f"neural_compare: error: not one instrument: {why}", file=sys.stderr)
        return 2
    print(markdown(before, after, tuple(labels)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
