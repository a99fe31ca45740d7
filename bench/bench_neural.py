"""Neural noise speed: the default against a one-piece network with DDIM, in one run: `python -m bench neural`.

The reference is the one-piece network (``eps.onnx``, re-exported from the shipped
weights into a temporary folder) sampled by DDIM with 30 steps; the default is
the split export (encoder once, denoiser per step) with the default sampler and
step count, in tiles above 1024 px.  Every configuration runs in a process of its
own, so its peak resident memory is its own.  Per size it prints seconds per step
(one network evaluation), seconds per image (the default also with its int8 denoiser,
``--precision int8``), where the time goes (encoder,
denoiser, numpy around them) and peak RSS; below 1024² the image is generated in
full, above it the per-image figure is encoder + steps x measured step (tiles:
a measured tiled step) and marked "est.".  The network's FLOP count (from torch's
layers, if torch is installed) over the measured step time gives the achieved
GFLOP/s, beside a float32 matrix product of the same machine in the same run.
Also the whole command (`omninoise neural`, model loading included) at 256², and at 1024² for the
new default (with the huge pages the command line gives large images, cli/hugepages.py).

Writes docs/benchmarks/neural_speed.json.  Options: --sizes, --threads, --quick (256² and 512² only).
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

import numpy as np

FULL_UP_TO = 512  # generate whole images up to this size; above, estimate from measured steps


def _worker(a) -> dict:
    """One configuration in this process: prints a JSON line."""
    from omninoise.backend.neural import conditioning as C
    from omninoise.backend.neural.generate import auto_tile, generate, image_eps
    from omninoise.backend.neural.model import NeuralNoiseModel
    from omninoise.backend.neural.sampler import DEFAULT_SPACING, evaluations

    t0 = time.perf_counter()
    m = NeuralNoiseModel(a.model, threads=a.threads, precision=a.precision)
    S = a.size
    cond = C.uniform(m, ("cells_f1", {}), S, S)
    x = np.random.default_rng(0).standard_normal((1, 1, S, S)).astype(np.float32)
    t = np.array([500.0], np.float32)
    tile = auto_tile(S, S) if m.form == "split" else 0
    n_eval = evaluations(a.sampler, a.steps, DEFAULT_SPACING[a.sampler], m.alphas_cumprod)
    out = dict(size=S, form=m.form, sampler=a.sampler, steps=a.steps, evaluations=n_eval, tile=tile,
               load_s=round(time.perf_counter() - t0, 3))
    if tile:
        f, count, cache = image_eps(m, cond[None], False, tile)  # generate()'s tiles and map cache
        t1 = time.perf_counter()
        f(x, t, None)  # first step: encoder of every tile (cached if they fit) + denoiser
        first = time.perf_counter() - t1
        if cache:
            t1 = time.perf_counter()
            f(x, t, None)
            step = time.perf_counter() - t1
            enc = first - step
        else:
            step, enc = first, 0.0
        out.update(tiles=count, maps_cached=cache, encoder_s=round(enc, 3), step_s=round(step, 3))
        out["image_s"] = round(enc + out["evaluations"] * step, 1)
        out["estimated"] = True
    else:
        f = m.eps_fn(False)
        c = cond[None]  # one array: a split model encodes it once (a new array would be encoded again)
        t1 = time.perf_counter()
        f(x, t, c)
        first = time.perf_counter() - t1
        reps = 3 if S <= 512 else 1
        t1 = time.perf_counter()
        for _ in range(reps):
            f(x, t, c)
        step = (time.perf_counter() - t1) / reps
        enc = 0.0
        if m.form == "split":
            t1 = time.perf_counter()
            m.encode(c)
            enc = time.perf_counter() - t1
        out.update(encoder_s=round(enc, 3), step_s=round(step, 3), first_call_s=round(first, 3))
        if S <= FULL_UP_TO:
            t1 = time.perf_counter()
            generate(m, cond, seed=1, steps=a.steps, sampler=a.sampler)  # the sampler's default spacing
            img = time.perf_counter() - t1
            out.update(image_s=round(img, 2), estimated=False,
                       numpy_share=round(max(img - enc - out["evaluations"] * step, 0.0) / img, 3))
        else:
            out.update(image_s=round(enc + out["evaluations"] * step, 1), estimated=True)
    out["peak_rss_mib"] = round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, 1)
    print("RESULT " + json.dumps(out), flush=True)
    return out


def _run(cfg: dict) -> dict:
    cmd = [sys.executable, os.path.abspath(__file__), "--worker"] + [f"--{k}={v}" for k, v in cfg.items()]
    r = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT)
    line = [ln for ln in r.stdout.splitlines() if ln.startswith("RESULT ")]
    if r.returncode == -9 and not line:  # the kernel's out-of-memory killer (24 GB here)
        return dict(size=cfg["size"], failed="killed: out of memory")
    if r.returncode or not line:
        raise RuntimeError(f"worker {cfg} failed: {r.stderr[-2000:]}")
    return json.loads(line[0][7:])


def matmul_gflops(threads: int) -> float:
    """float32 2048² matrix product, best of 5, in GFLOP/s (numpy's BLAS, in a worker with the same threads)."""
    code = ("import numpy as np, time; a=np.random.rand(2048,2048).astype(np.float32); b=a.copy(); a@b; "
            "ts=[]\nfor _ in range(5):\n t=time.perf_counter(); a@b; ts.append(time.perf_counter()-t)\n"
            "print(2*2048**3/min(ts)/1e9)")
    env = dict(os.environ)
    if threads:
        env.update(OMP_NUM_THREADS=str(threads), OPENBLAS_NUM_THREADS=str(threads))
    return float(subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env,
                                check=True).stdout)


def network_gflop(model_folder: str, size: int) -> dict | None:
    """GFLOP of one encoder and one denoiser pass at size² (convolutions and linear layers), via torch."""
    try:
        import torch

        from omninoise.training.warm_start import torch_from_export
    except ImportError:
        return None
    net = torch_from_export(model_folder)
    count = {"n": 0}

    def hook(mod, inp, out):
        if isinstance(mod, torch.nn.Conv2d):
            k = mod.weight[0].numel()  # Cin/groups * kh * kw
            count["n"] += 2 * k * out.numel()
        elif isinstance(mod, torch.nn.Linear):
            count["n"] += 2 * mod.in_features * out.numel()

    hs = [m.register_forward_hook(hook) for m in net.modules() if isinstance(m, (torch.nn.Conv2d, torch.nn.Linear))]
    C = net.emb_dim + net.n_params
    with torch.no_grad():
        maps = net.encode(torch.zeros(1, C, size, size))
        enc = count["n"]
        count["n"] = 0
        net.denoise(torch.zeros(1, 1, size, size), torch.tensor([500.0]), maps)
    for h in hs:
        h.remove()
    return dict(encoder=enc / 1e9, denoiser=count["n"] / 1e9)


def whole_command(args: list, threads: int, size: int = 256) -> float:
    with tempfile.TemporaryDirectory() as d:
        t0 = time.perf_counter()
        subprocess.run([sys.executable, "-m", "omninoise", "neural", "--noise", "cells_f1", "--size", str(size), "--quiet",
                        "--threads", str(threads), "-o", os.path.join(d, "n.png")] + args, check=True, cwd=ROOT)
        return time.perf_counter() - t0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--model", default=os.path.join(ROOT, "models", "neural_noise"))
    ap.add_argument("--size", type=int, default=256, help=argparse.SUPPRESS)
    ap.add_argument("--sampler", default="ddim", help=argparse.SUPPRESS)
    ap.add_argument("--steps", type=int, default=30, help=argparse.SUPPRESS)
    ap.add_argument("--precision", default="fp32", help=argparse.SUPPRESS)
    ap.add_argument("--sizes", type=int, nargs="+", default=[256, 512, 1024, 2048])
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--quick", action="store_true", help="256² and 512² only")
    ap.add_argument("-o", "--out", default=os.path.join(ROOT, "docs", "benchmarks", "neural_speed.json"))
    a = ap.parse_args(argv)
    if a.worker:
        _worker(a)
        return 0
    from omninoise.backend.neural.sampler import DEFAULT_SAMPLER, DEFAULT_STEPS
    from omninoise.training.export_onnx import reexport

    sizes = [s for s in a.sizes if s <= 512] if a.quick else a.sizes
    tmp = tempfile.mkdtemp(prefix="omninoise_onepiece_")
    reexport(a.model, tmp, one_piece=True)  # the one-piece network, from the shipped weights
    from bench.stamp import stamp

    from omninoise.backend.neural.precision import int8_dot_products

    res = dict(stamp=stamp(), threads=a.threads, matmul_gflops=round(matmul_gflops(a.threads), 1),
               int8_dot_products=int8_dot_products(), rows=[])
    flops = network_gflop(a.model, 256)
    print(f"float32 matmul 2048²: {res['matmul_gflops']} GFLOP/s on {a.threads} threads")
    if flops:
        res["gflop_256"] = {k: round(v, 1) for k, v in flops.items()}
        print(f"one network evaluation at 256²: encoder {flops['encoder']:.1f} GFLOP + denoiser "
              f"{flops['denoiser']:.1f} GFLOP")
    print("| size | path | s/step | encoder s | s/image | numpy share | peak RSS MiB | GFLOP/s |")
    print("|---|---|---|---|---|---|---|---|")
    for S in sizes:
        pair = []
        default = f"default: split, {DEFAULT_SAMPLER} {DEFAULT_STEPS}"
        for label, folder, sampler, steps, precision in (
                ("one-piece, DDIM 30", tmp, "ddim", 30, "fp32"),
                (default, a.model, DEFAULT_SAMPLER, DEFAULT_STEPS, "fp32"),
                (f"{default}, int8 (--precision int8)", a.model, DEFAULT_SAMPLER, DEFAULT_STEPS, "int8")):
            r = _run(dict(model=folder, size=S, sampler=sampler, steps=steps, threads=a.threads, precision=precision))
            r["path"] = label
            if "failed" in r:
                res["rows"].append(r)
                pair.append(None)
                print(f"| {S}² | {label} | {r['failed']} | | | | | |", flush=True)
                continue
            if flops and not r.get("tile"):
                per_step = (flops["denoiser"] + (flops["encoder"] if r["form"] == "one-piece" else 0)) * (S / 256) ** 2
                r["gflops_per_s"] = round(per_step / r["step_s"], 1)
            res["rows"].append(r)
            pair.append(r)
            est = " est." if r.get("estimated") else ""
            tiles = f" ({r['tiles']} tiles)" if r.get("tiles") else ""
            print(f"| {S}² | {label}{tiles} | {r['step_s']} | {r['encoder_s']} | {r['image_s']}{est} | "
                  f"{r.get('numpy_share', '')} | {r['peak_rss_mib']} | {r.get('gflops_per_s', '')} |", flush=True)
        if None not in pair[:2]:
            print(f"|  | speed-up per image | {pair[0]['step_s'] / pair[1]['step_s']:.2f}x per step | | "
                  f"{pair[0]['image_s'] / pair[1]['image_s']:.2f}x | | | |", flush=True)
    old = whole_command(["--model", tmp, "--sampler", "ddim", "--steps", "30"], a.threads)
    new = whole_command([], a.threads)
    res["whole_command_256"] = dict(one_piece_ddim30_s=round(old, 2), default_s=round(new, 2), ratio=round(old / new, 2))
    print(f"\nwhole command at 256² (start-up and model loading included): one-piece DDIM 30 {old:.1f} s, default {new:.1f} s "
          f"({old / new:.2f}x)")
    if 1024 in sizes:   # the default only (DDIM 30 takes about nine minutes); huge pages as users get them
        big = whole_command([], a.threads, 1024)
        res["whole_command_1024"] = dict(default_s=round(big, 2))
        print(f"whole command at 1024², default: {big:.1f} s")
    os.makedirs(os.path.dirname(a.out), exist_ok=True)
    from omninoise.export.atomic import write_json

    write_json(a.out, res)
    return 0


if __name__ == "__main__":
    sys.exit(main())
