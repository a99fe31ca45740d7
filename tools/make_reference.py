"""Write the stored reference values of tests/core/test_reference_values.py: ``python tools/make_reference.py``.

Run it only on purpose: when a change is meant to alter outputs (a new shipped model, a fixed bug in an
engine). The test then compares every later run with these numbers, so a change that silently alters the wave
engine, the zoo or a shipped model's output fails the suite (the opensimplex approach: noise tested against
stored samples). Each file records what made it (command line or model fingerprint).

    tests/data/reference/wave.json     wave-noise variants: 24 points each, from CLI flag sets
    tests/data/reference/zoo.json      every zoo class at its default parameters: an 8 x 8 image, seed 0
    tests/data/reference/models.json   each shipped model's first outputs for a fixed seed
"""
from __future__ import annotations

import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

import numpy as np  # noqa: E402

from omninoise.export.atomic import write_json  # noqa: E402

OUT = os.path.join(ROOT, "tests", "data", "reference")

#: wave-noise variants as command lines of `omninoise wave` (the flags a user types)
WAVE_VARIANTS = {
    "2d_gaussian": ["--fmin", "2", "--fmax", "6", "--seed", "3"],
    "2d_fractal_crystal": ["--spectrum", "fractal", "--fmin", "1", "--fmax", "8", "--exponent", "1.2",
                        "--waveform", "crystal", "--seed", "5"],
    "2d_bandpass_modulus": ["--spectrum", "bandpass", "--fmin", "3", "--fmax", "5", "--output", "modulus"],
    "2d_lobes": ["--anisotropy", "lobes", "--lobe", "1,0:1", "--spread", "15", "--fmin", "2", "--fmax", "4"],
    "2d_stit": ["--cellular", "stit", "--cell-size", "0.5", "--seed", "2", "--fmin", "4", "--fmax", "8"],
    "3d_fractal": ["--dim", "3", "--spectrum", "fractal", "--fmin", "1", "--fmax", "6", "--seed", "7"],
    "3d_animated": ["--dim", "3", "--speed", "0.5", "--time", "1.25", "--fmin", "2", "--fmax", "4"],
    "4d": ["--dim", "4", "--time", "0.5", "--fmin", "2", "--fmax", "4", "--seed", "11"],
    "2d_table_period": ["--table-size", "256", "--period", "8", "--fmin", "2", "--fmax", "6"],
}


def wave_points(dim: int) -> np.ndarray:
    return np.random.default_rng(1234).uniform(0.0, 3.0, (24, dim)).astype(np.float32)


def wave_values(flags: list) -> np.ndarray:
    from omninoise.cli.main import build_parser
    from omninoise.cli.wave import settings_from_args
    from omninoise.backend.grid import evaluate_points
    from omninoise.backend.wavenoise.settings import compile_noise

    a = build_parser().parse_args(["wave"] + flags + ["-o", "x.npy"])
    s = settings_from_args(a)
    return evaluate_points(compile_noise(s), wave_points(s.dim), s.output, a.time, s.cellular)


def zoo_values(name: str) -> np.ndarray:
    import torch

    from omninoise.training import zoo

    return zoo.generate(name, zoo.default_params(name), torch.tensor([0]), 8)[0].numpy()


def neural_values(folder: str) -> np.ndarray:
    from omninoise.backend.neural import conditioning as C
    from omninoise.backend.neural.generate import generate
    from omninoise.backend.neural.model import NeuralNoiseModel

    m = NeuralNoiseModel(folder, threads=1)
    # the sampler pinned (not the default), so the values follow the weights alone
    return generate(m, C.uniform(m, (m.classes[0], {}), 16, 16), seed=1, steps=2, sampler="dpmpp_2m", eta=0.0,
                    spacing="logsnr")


def solid_values(folder: str) -> np.ndarray:
    from omninoise.backend.solid.model import SolidTextureModel

    m = SolidTextureModel(folder, threads=1)
    pts = np.random.default_rng(99).uniform(-1.0, 1.0, (16, m.dim))
    return m.evaluate(pts, m.default_code(), seed=2)


def shipped_models() -> dict:
    """{key: (kind, folder)} of every shipped model."""
    out = {"neural_noise": ("neural", os.path.join(ROOT, "models", "neural_noise"))}
    solid = os.path.join(ROOT, "models", "solid")
    for name in sorted(os.listdir(solid)):
        if os.path.isfile(os.path.join(solid, name, "solid.json")):
            out["solid/" + name] = ("solid", os.path.join(solid, name))
    return out


def model_fingerprint(kind: str, folder: str) -> str:
    from omninoise.backend.onnx_models import fingerprint, load_model_json

    return fingerprint(load_model_json(folder, "neural_noise.json" if kind == "neural" else "solid.json")["files"])


def main() -> int:
    from omninoise.training import zoo

    os.makedirs(OUT, exist_ok=True)
    r = lambda a: np.round(np.asarray(a, np.float64), 7).tolist()  # noqa: E731
    write_json(os.path.join(OUT, "wave.json"), {k: dict(flags=v, values=r(wave_values(v)))
                                                 for k, v in WAVE_VARIANTS.items()})
    write_json(os.path.join(OUT, "zoo.json"), {n: r(zoo_values(n)) for n in zoo.CLASS_NAMES})
    models = {}
    for key, (kind, folder) in shipped_models().items():
        vals = neural_values(folder) if kind == "neural" else solid_values(folder)
        models[key] = dict(kind=kind, fingerprint=model_fingerprint(kind, folder), values=r(vals))
    write_json(os.path.join(OUT, "models.json"), models)
    print(OUT)
    return 0


if __name__ == "__main__":
    sys.exit(main())
