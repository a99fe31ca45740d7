"""Evaluate the shipped neural solid textures: `python -m bench solid [--speed]`.

Quality (Henzler et al. 2020, Table 3): for every exemplar with a shipped
model, style error (independent random-feature Gram distance + colour term),
PSD error, diversity and success of ``ours`` (2D model, and slices of the 3D
model), the texture-space model (its code for the exemplar's *held-out* pixels,
so it measures generalisation), and the baselines of
training/solid/evaluate.py (tiled exemplar, Perlin coloured by the
exemplar's histogram, a linear noise transform).

Speed and memory (Table 2): points per second and peak resident memory for a
2D 1024² image and a 3D 256³ volume, onnxruntime (numba lattice noise + ONNX
decoder, what the add-on runs) against torch with the same weights, each in a
fresh process.  Writes docs/benchmarks/solid_eval.json.
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

import numpy as np

from omninoise.export.atomic import write_json

MODELS = os.path.join(ROOT, "models", "solid")


def quality(n: int, models_dir: str = MODELS) -> dict:
    import torch

    from omninoise.training.solid import exemplars as ex
    from omninoise.training.solid.evaluate import EVAL_SIZE, evaluate_exemplar, slices_3d

    from omninoise.backend.solid.model import load_models

    models = load_models(models_dir)
    space = next((m for m in models.values() if m.mode == "space"), None)
    singles = {}
    for m in models.values():
        if m.mode == "single":
            singles.setdefault(m.config["exemplars"][0], {})[m.dim] = m
    # the space model's codes that name a shipped exemplar (photo models' codes name categories of the
    # photo set, evaluated on held-out photos by python -m bench solid-photos)
    known = set(ex.PHOTOS) | set(ex.PROCEDURAL)
    names = sorted(set(singles) | ((set(space.codes) & known) if space else set()))
    table = {}
    for name in names:
        methods, scale = {}, None
        for dim, m in sorted(singles.get(name, {}).items()):
            code, ppu = m.default_code(), m.config["px_per_unit"]
            scale = m.config["exemplar_scale"]
            if dim == 2:
                methods["ours_2d"] = np.stack([m.evaluate(_plane(EVAL_SIZE, ppu, i), code, i).reshape(EVAL_SIZE, EVAL_SIZE, 3)
                                               for i in range(n)])
            else:
                methods["ours_3d"] = slices_3d(lambda p, i: m.evaluate(p, code, i), n, EVAL_SIZE, ppu,
                                               fixed_axis=m.config.get("config", {}).get("fixed_axis", ""))
        if space is not None and name in space.codes and not space.colour_stats:
            held = ex.heldout_region(name).permute(1, 2, 0).numpy()
            code = space.translate(space.encode(held))
            ppu = space.config["px_per_unit"]
            methods["space_3d"] = slices_3d(lambda p, i: space.evaluate(p, code, i), n, EVAL_SIZE, ppu)
            scale = scale or space.config["exemplar_scale"]
        torch.manual_seed(0)
        table[name] = evaluate_exemplar(name, scale or 1.0, methods, n)
        print(f"{name}: " + ", ".join(f"{k} {v['style']}" for k, v in table[name].items()), file=sys.stderr)
    return table


def _plane(size, ppu, i):
    from omninoise.backend.solid.model import plane_points

    return plane_points(size, ppu) + np.random.default_rng(i).uniform(-50, 50, 2)


def _points(dim: int, size: int, ppu: float):
    c = (np.arange(size) + 0.5) / ppu
    if dim == 2:
        y, x = np.meshgrid(c, c, indexing="ij")
        return np.stack([x.ravel(), y.ravel()], 1)
    z, y, x = np.meshgrid(c, c, c, indexing="ij")
    return np.stack([x.ravel(), y.ravel(), z.ravel()], 1)


def _peak_mib() -> int:
    """This process's peak resident memory (VmHWM: unlike ru_maxrss, not inherited from the parent)."""
    try:
        with open("/proc/self/status", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("VmHWM:"):
                    return round(int(line.split()[1]) / 1024)
    except OSError:
        pass
    return round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)


def speed_one(engine: str, model: str, run: str, dim: int, size: int) -> dict:
    """One timing in this process: seconds for all points, peak RSS."""
    from omninoise.backend.solid.model import SolidTextureModel

    m = SolidTextureModel(os.path.join(MODELS, model))
    pts = _points(dim, size, m.config["px_per_unit"])
    if dim == 2 and m.dim == 3:
        pts = np.concatenate([pts, np.zeros((len(pts), 1))], 1)
    chunk = 1 << 16
    if engine == "onnxruntime":
        code = m.default_code()
        m.evaluate(pts[:chunk], code, 0)      # warm-up: numba compile cache, session
        t = time.perf_counter()
        out = np.empty((len(pts), 3), np.float32)
        for a in range(0, len(pts), 1 << 20):   # stream, as a bake does
            out[a:a + (1 << 20)] = m.evaluate(pts[a:a + (1 << 20)], code, 0, chunk)
    else:
        import torch

        from omninoise.training.solid.value_noise import octave_seeds
        from omninoise.training.solid.train import SolidConfig, build_model

        state = torch.load(os.path.join(run, "ckpt.pt"), map_location="cpu", weights_only=False)
        tm = build_model(SolidConfig.from_dict(state["config"]))
        tm.load_state_dict(state["model"])
        tm.eval()
        with torch.no_grad():
            e, T = tm.codes(batch=1)
            seeds = octave_seeds([0], tm.octaves)
            # a photo model's colour (mu, L): the export's, as the runtime reads it
            stats = torch.tensor([m.config["colour_code"]], dtype=torch.float32) if m.colour_stats else None
            x = torch.from_numpy(pts.astype(np.float32))
            tm.sample(x[None, :chunk], e, T, seeds, stats)
            t = time.perf_counter()
            out = np.empty((len(pts), 3), np.float32)
            for a in range(0, len(pts), chunk):
                out[a:a + chunk] = tm.sample(x[None, a:a + chunk], e, T, seeds, stats)[0].numpy()
    sec = time.perf_counter() - t
    return dict(engine=engine, dim=dim, size=size, points=len(pts), seconds=round(sec, 3),
                points_per_s=round(len(pts) / sec), peak_mib=_peak_mib(),
                checksum=float(out[::9973].sum()))


def speed(model: str, run: str) -> list:
    """The timings of every engine; torch only where the model's training run (its checkpoint) is at hand."""
    rows = []
    engines = ("onnxruntime", "torch") if os.path.isfile(os.path.join(run, "ckpt.pt")) else ("onnxruntime",)
    for dim, size in ((2, 1024), (3, 256)):
        for engine in engines:
            r = subprocess.run([sys.executable, __file__, "--speed-one", engine, "--model", model, "--run", run,
                                "--dim", str(dim), "--size", str(size)], capture_output=True, text=True, check=True)
            rows.append(json.loads(r.stdout.strip().splitlines()[-1]))
            print(rows[-1], file=sys.stderr)
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, default=8, help="samples (seeds) per method")
    ap.add_argument("--models", default=MODELS, help="folder of model folders to evaluate (candidates before shipping)")
    ap.add_argument("--speed", action="store_true", help="also time onnxruntime against torch")
    ap.add_argument("--only-speed", action="store_true")
    ap.add_argument("--model", default="rust_3d", help="model timed by --speed")
    ap.add_argument("--run", default=os.path.join(ROOT, "runs", "solid", "rust_3d"),
                    help="its training run (torch loads the same weights from ckpt.pt)")
    ap.add_argument("--speed-one", choices=("onnxruntime", "torch"), help=argparse.SUPPRESS)
    ap.add_argument("--dim", type=int, default=3, help=argparse.SUPPRESS)
    ap.add_argument("--size", type=int, default=256, help=argparse.SUPPRESS)
    ap.add_argument("-o", "--out", default=os.path.join(ROOT, "docs", "benchmarks", "solid_eval.json"))
    a = ap.parse_args(argv)
    if a.speed_one:
        print(json.dumps(speed_one(a.speed_one, a.model, a.run, a.dim, a.size)))
        return 0
    res = {}
    if a.only_speed and os.path.isfile(a.out):      # keep the quality table of an earlier run
        with open(a.out, encoding="utf-8") as fh:
            res = json.load(fh)
    if not a.only_speed:
        res["quality"] = quality(a.n, a.models)
        res["n"] = a.n
        print("| exemplar | method | style error ↓ | PSD error ↓ | diversity ↑ | success ↑ |")
        print("|---|---|---|---|---|---|")
        for name, rows in res["quality"].items():
            for meth, r in rows.items():
                print(f"| {name} | {meth} | {r['style']} | {r['psd']} | {r['diversity']} | {r['success']} |")
    if a.speed or a.only_speed:
        res["speed"] = speed(a.model, a.run)
        print("\n| volume | engine | points/s | seconds | peak MiB |")
        print("|---|---|---|---|---|")
        for r in res["speed"]:
            print(f"| {'x'.join([str(r['size'])] * r['dim'])} | {r['engine']} | {r['points_per_s']:,} | "
                  f"{r['seconds']} | {r['peak_mib']} |")
        for dim in (2, 3):
            o, t = (next((r for r in res["speed"] if r["dim"] == dim and r["engine"] == e), None)
                    for e in ("onnxruntime", "torch"))
            if o and t:
                print(f"{dim}D: onnxruntime / torch speed = {o['points_per_s'] / t['points_per_s']:.2f}x")
    from bench.stamp import stamp

    res["stamp"] = stamp()
    os.makedirs(os.path.dirname(a.out), exist_ok=True)
    write_json(a.out, res)
    return 0


if __name__ == "__main__":
    sys.exit(main())
