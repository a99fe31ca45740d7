"""Evaluate a neural noise model: `python -m bench neural-eval --model models/neural_noise`.

Prints the per-class table of training/evaluate.py (Fréchet distance in
a zoo classifier's features, classifier accuracy on generated samples, power-
spectrum error, parameter-response error), the seam ratio of tileable output,
blend locality, and seconds per DDIM step for onnxruntime and torch with the
same weights (torch rebuilt from the export, so no checkpoint is needed);
writes everything to out/bench/neural_eval.json.
"""
from __future__ import annotations

import argparse
import json
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

from omninoise.backend.neural.model import NeuralNoiseModel
from omninoise.backend.neural.sampler import DEFAULT_SAMPLER, DEFAULT_STEPS, sampler_eta
from omninoise.export.atomic import write_json
from omninoise.training.evaluate import evaluate, step_seconds
from omninoise.training.threads import cpu_threads


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--model", default=os.path.join(ROOT, "models", "neural_noise"))
    ap.add_argument("--classes", help="comma-separated classes to evaluate (default: the model's trained classes); "
                                      "two models compare only on the same classes, with the same instrument")
    ap.add_argument("--only", help="comma-separated classes to report, measured with the classifier of every "
                                   "evaluated class (--classes): a larger n for a few classes on the same instrument; "
                                   "no seam or locality figures")
    ap.add_argument("--threads", type=int, default=0, help="CPU threads for torch and numba (0: their defaults); "
                                                           "the classifier is reproducible for a fixed count")
    ap.add_argument("--n", type=int, default=32, help="samples per class")
    # the defaults are the model card's instrument: the runtime's sampler, a classifier of 6000 steps and 3 stages
    ap.add_argument("--steps", type=int, default=DEFAULT_STEPS, help="sampler steps (default: the runtime's)")
    ap.add_argument("--sampler", default=DEFAULT_SAMPLER,
                    help="ddim, dpmpp_2m or heun (see backend/neural/sampler.py; default: the runtime's)")
    ap.add_argument("--eta", type=float, help="step noise of ddim or dpmpp_2m (0: deterministic; default: the "
                                              "sampler's own)")
    ap.add_argument("--spacing", help="timestep spacing: uniform, logsnr, karras or truncated (default: the sampler's own)")
    ap.add_argument("--precision", default="fp32", help="the denoiser's arithmetic: fp32, int8 or auto "
                                                         "(int8 needs the folder's int8 files, training/quantize_onnx.py)")
    ap.add_argument("--clf-steps", type=int, default=6000, help="the classifier's training steps")
    ap.add_argument("--classifier-cache", metavar="DIR",
                    help="keep the trained classifier here and reuse it (same classes, size, steps, threads)")
    ap.add_argument("--size", type=int, default=256, help="resolution for the step timing")
    ap.add_argument("--eval-size", type=int, help="resolution of the quality evaluation (default: the model's "
                                                  "training size); compare two models at one size")
    ap.add_argument("--clf-threads", type=int, help="torch threads the classifier is trained with (and cached "
                                                    "under); default: --threads")
    ap.add_argument("--clf-stages", type=int, default=3, help="stride-2 stages of the classifier (3 or more for "
                                                              "64² and larger: a wider receptive field)")
    ap.add_argument("--timing-only", action="store_true",
                    help="re-time the DDIM step (on a quiet machine) and keep the quality results already in --out")
    ap.add_argument("--no-timing", action="store_true", help="skip the DDIM step timing (a busy machine)")
    ap.add_argument("-o", "--out", default=os.path.join(ROOT, "out", "bench", "neural_eval.json"))
    a = ap.parse_args(argv)
    a.eta = sampler_eta(a.sampler, a.eta)
    model = NeuralNoiseModel(a.model, threads=a.threads, precision=a.precision)
    classes = tuple(model.config["trained_classes"])
    if a.classes:
        classes = tuple(c.strip() for c in a.classes.split(","))
        bad = [c for c in classes if c not in model.config["trained_classes"]]
        if bad:
            print(f"eval_neural: error: {a.model} was not trained on {bad[0]!r}", file=sys.stderr)
            return 2
    only = None
    if a.only:
        only = tuple(c.strip() for c in a.only.split(","))
        bad = [c for c in only if c not in classes]
        if bad:
            print(f"eval_neural: error: --only {bad[0]!r} is not among the evaluated classes", file=sys.stderr)
            return 2
    a.only = only
    if a.timing_only and a.no_timing:
        print("eval_neural: error: --timing-only and --no-timing exclude each other", file=sys.stderr)
        return 2
    with cpu_threads(a.threads):
        return _run(a, model, classes)


def _run(a, model, classes) -> int:
    if a.timing_only:
        with open(a.out, encoding="utf-8") as fh:
            res = json.load(fh)
        if res.get("model", {}).get("sha256") != model.fingerprint:
            print(f"eval_neural: error: {a.out} evaluates another model than {a.model}", file=sys.stderr)
            return 2
        a.n, a.steps = res["model"]["n"], res["model"]["steps"]
        classes = tuple(res["model"].get("classes", classes))
    else:
        res = evaluate(model, classes, a.n, a.steps, a.clf_steps, log=lambda s: print(s, file=sys.stderr),
                       sampler=a.sampler, spacing=a.spacing, classifier_cache=a.classifier_cache,
                       size=a.eval_size, clf_stages=a.clf_stages, clf_threads=a.clf_threads, only=a.only, eta=a.eta)
    if not a.no_timing:
        res["timing"] = step_seconds(a.model, a.size)
    if not a.timing_only:
        from omninoise.backend.neural.sampler import DEFAULT_SPACING

        res["sampler"] = dict(name=a.sampler, steps=a.steps, spacing=a.spacing or DEFAULT_SPACING[a.sampler])
        if a.eta:
            res["sampler"]["eta"] = a.eta
    res["model"] = dict(step=model.config["step"], sha256=model.fingerprint, n=a.n, steps=a.steps,
                        classes=list(classes), precision=model.precision)
    if a.only:
        res["model"]["only"] = list(a.only)
    print("| class | FD | acc | PSD err | low-frequency PSD err | coherence err (zoo) | response err (param) |")
    print("|---|---|---|---|---|---|---|")
    for name, r in res["classes"].items():
        print(f"| {name} | {r['fd']} | {r['acc']} | {r['psd']} | {r.get('psd_low', '—')} | "
              f"{r.get('coherence', '—')} ({r.get('coherence_zoo', '—')}) | {r['response']} ({r['param']}) |")
    oriented = {n: r for n, r in res["classes"].items() if "direction_error" in r}
    if oriented:
        print("\n| class | direction error, degrees (zoo's own spread; 45 = ignores the parameter) |\n|---|---|")
        for name, r in oriented.items():
            print(f"| {name} ({r['direction_param']}) | {r['direction_error']} ({r['direction_error_zoo']}) |")
    print(f"\nzoo accuracy of the classifier: {res['zoo_accuracy']}")
    print(f"seam ratio: tileable {res['seam_tileable']}, plain {res['seam_plain']}; blend locality {res['locality']}")
    t = res.get("timing")
    if t:
        print(f"DDIM step at {t['size']}²: onnxruntime {t['onnxruntime_s']} s, torch {t['torch_s']} s "
              f"(torch / ort = {t['ratio']}; max |Δε| {t['max_eps_difference']:.1e})")
    os.makedirs(os.path.dirname(a.out), exist_ok=True)
    write_json(a.out, res)
    return 0


if __name__ == "__main__":
    sys.exit(main())
