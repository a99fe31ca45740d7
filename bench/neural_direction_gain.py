"""How much does knowing the direction lower the ε error, per noise level?  `python bench/neural_direction_gain.py --model M`.

For an oriented class (fibers by default) and timesteps t from the noisy end down, two columns:
- **ideal**: a Gaussian model of the class at its default settings, with the power spectrum P_θ measured from zoo
  images. Per frequency, x_t = α x₀ + σ ε gives the best ε error s P / (s P + 1) (s = SNR = α²/σ²) when the
  direction is known, and 1 - 2c + c² (s P + 1) with c = 1 / (s P̄ + 1) for the Wiener filter of the mixture over
  directions P̄, the best a direction-blind linear model does. Their relative difference is what the direction
  is worth to the loss at that noise level.
- **model**: each model's ε error (mean square, n zoo images at random directions, the same noise for both) with
  the right direction and with the direction turned by 90°, and their relative difference.
A model that uses the parameter approaches the ideal gain; one that ignores it scores 0. Prints a table, and writes
JSON with ``-o``.
"""
from __future__ import annotations

import argparse
import os
import sys

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from omninoise.export.atomic import write_json  # noqa: E402

TIMESTEPS = (980, 950, 900, 850, 800, 700, 500)


def ideal_gain(name: str, size: int, n: int, timesteps=TIMESTEPS) -> list:
    """[(t, snr, error with the direction known, error of the direction mixture's Wiener filter)] for the Gaussian
    model of class ``name`` (zoo spectra of n images at one direction, and at 12 directions for the mixture)."""
    import torch

    from omninoise.backend.neural.schedule import cosine_alphas_cumprod
    from omninoise.training import zoo
    from omninoise.training.evaluate import oriented_params

    def power(theta):
        p = {k: np.full(n, v) for k, v in oriented_params(name, theta).items()}
        x = zoo.generate(name, p, torch.arange(n) + 900, size).numpy() * 2 - 1
        return (np.abs(np.fft.fft2(x) / size) ** 2).mean(0)  # per-pixel power at each frequency

    P = power(0.3)
    Pbar = np.mean([power(th) for th in np.linspace(0, np.pi, 12, endpoint=False)], 0)
    ab = cosine_alphas_cumprod()
    out = []
    for t in timesteps:
        s = ab[t] / (1 - ab[t])
        c = 1 / (s * Pbar + 1)
        out.append((t, float(s), float((s * P / (s * P + 1)).mean()), float((1 - 2 * c + c * c * (s * P + 1)).mean())))
    return out


def model_gain(folder: str, name: str, size: int, n: int, timesteps=TIMESTEPS) -> list:
    """[(t, ε error with the right direction, with the direction + 90°)] of the export in ``folder`` (torch rebuilt
    from it) on n zoo images of class ``name`` at random directions."""
    import torch

    from omninoise.training import zoo
    from omninoise.training.diffusion import Diffusion
    from omninoise.training.evaluate import ORIENTED, oriented_params
    from omninoise.training.warm_start import torch_from_export

    pname = ORIENTED[name][0]
    spec = next(p for p in zoo.CLASSES[name].params if p.name == pname)
    period = np.pi  # every oriented class repeats its images after a half turn
    rng = np.random.default_rng(0)
    theta = rng.uniform(0, period, n)
    params = {k: np.full(n, v) for k, v in oriented_params(name, theta).items()}
    wrong = dict(params, **{pname: np.mod(theta + period / 2, period)})
    assert spec.lo <= wrong[pname].min() and wrong[pname].max() <= spec.hi
    x0 = zoo.generate(name, params, torch.arange(n) + 500, size)[:, None] * 2 - 1
    m = torch_from_export(folder).eval()
    ids = torch.full((n, size, size), zoo.CLASS_NAMES.index(name), dtype=torch.long)

    def cond(p):
        vec = zoo.condition_vector(name, p)[:, : m.n_params]
        return m.embed(ids, vec.view(n, -1, 1, 1).expand(-1, -1, size, size))

    right, turned = cond(params), cond(wrong)
    d = Diffusion()
    out = []
    for t in timesteps:
        eps = torch.randn(x0.shape, generator=torch.Generator().manual_seed(int(t)))
        tt = torch.full((n,), int(t), dtype=torch.long)
        xt = d.q_sample(x0, tt, eps)
        with torch.no_grad():
            a = float(((m(xt, tt.float(), right) - eps) ** 2).mean())
            b = float(((m(xt, tt.float(), turned) - eps) ** 2).mean())
        out.append((t, a, b))
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--model", action="append", default=[], help="a model folder (repeat to compare)")
    ap.add_argument("--noise", default="fibers", help="an oriented class: fibers, phasor, gabor or gabor_texture")
    ap.add_argument("--size", type=int, default=64)
    ap.add_argument("--n", type=int, default=48, help="zoo images per measurement")
    ap.add_argument("--threads", type=int, default=0, help="torch threads (0: its default)")
    ap.add_argument("-o", "--out", help="JSON output")
    a = ap.parse_args()
    import torch

    from omninoise.training.evaluate import ORIENTED

    if a.noise not in ORIENTED:
        ap.error(f"--noise must be one of {', '.join(ORIENTED)}, got {a.noise!r}")
    if a.threads:
        torch.set_num_threads(a.threads)
    ideal = ideal_gain(a.noise, a.size, a.n)
    models = {f: model_gain(f, a.noise, a.size, a.n) for f in a.model}
    head = "| t | SNR | ideal: known | ideal: mixture | ideal gain |" + "".join(
        f" {os.path.basename(os.path.normpath(f))}: right / turned | gain |" for f in models)
    print(head + "\n|" + "---|" * (5 + 2 * len(models)))
    for i, (t, s, known, mix) in enumerate(ideal):
        cells = "".join(f" {models[f][i][1]:.5f} / {models[f][i][2]:.5f} | {(models[f][i][2] / models[f][i][1] - 1) * 100:+.2f} % |"
                        for f in models)
        print(f"| {t} | {s:.1e} | {known:.5f} | {mix:.5f} | {(mix / known - 1) * 100:+.1f} % |{cells}")
    if a.out:
        write_json(a.out, dict(noise=a.noise, size=a.size, n=a.n,
                               ideal=[dict(t=t, snr=s, known=k, mixture=m) for t, s, k, m in ideal],
                               models={f: [dict(t=t, right=r, turned=w) for t, r, w in v] for f, v in models.items()}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
