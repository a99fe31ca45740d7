"""Wave noise speed against the CPU peers a user would pick instead, in one run.

ns per sample for 2D 1024^2 and 3D 128^3 / 256^3 grids at 8, 16, 32, 64
directions, next to 5-octave fractal Perlin (pyfastnoisesimd, FastNoise Lite),
opensimplex (5 octaves) and Blender's Noise (detail 5) and Gabor textures
evaluated through bpy Geometry Nodes.  Prints ratios wave / fastest peer.
The "wave 16 floor" rows (bench/lookup_floor.c, compiled with cc) are idealised
hand-vectorised AVX2 rows, not an engine: "pure" does one table lerp per
direction per sample and nothing else, a lower bound for any exact kernel;
"blend" does the border ramp's two lerps and weights everywhere; each the faster
of its two table-read forms (register windows or gathers), as the engine picks.
"wave 16 dirs, numba kernel" is the same engine with the C row kernel switched off.
Then streams a 512^3 grid and reports peak memory against the output's size.

Run: make bench   (numbers: median of --repeat runs, wall clock, this machine; JSON in docs/benchmarks/)
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

from omninoise.backend import Spectrum, WaveSettings, compile_noise, evaluate_grid
from omninoise.backend.wavenoise import ckernel, fast
from bench.stamp import DATA, stamp


def timed(fn, repeat):
    fn()  # warm-up (JIT compile, caches)
    ts = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t)
    return float(np.median(ts))


def peers(dim, n, repeat):
    out = {}
    freq = 2.0  # features per unit, grid spans 4 units
    try:
        import pyfastnoisesimd as fns

        p = fns.Noise(seed=1, numWorkers=os.cpu_count() or 1)
        p.noiseType = fns.NoiseType.PerlinFractal
        p.fractal.octaves = 5
        p.frequency = freq * 4.0 / n
        shape = [1, n, n] if dim == 2 else [n, n, n]
        out["pyfastnoisesimd perlin fbm5"] = timed(lambda: p.genAsGrid(shape), repeat)
    except ImportError:
        pass
    try:
        from pyfastnoiselite.pyfastnoiselite import FastNoiseLite, FractalType, NoiseType

        fnl = FastNoiseLite(1)
        fnl.noise_type = NoiseType.NoiseType_Perlin
        fnl.fractal_type = FractalType.FractalType_FBm
        fnl.fractal_octaves = 5
        fnl.frequency = freq * 4.0 / n
        g = np.arange(n, dtype=np.float32)
        coords = np.stack(np.meshgrid(*([g] * dim), indexing="ij"), 0).reshape(dim, -1)
        out["FastNoise Lite perlin fbm5"] = timed(lambda: fnl.gen_from_coords(coords), repeat)
    except ImportError:
        pass
    try:
        import opensimplex

        opensimplex.seed(1)
        g = np.arange(n, dtype=np.float64) * 4.0 / n

        def os5():
            for o in range(5):
                f = freq * 2 ** o
                if dim == 2:
                    opensimplex.noise2array(g * f, g * f)
                else:
                    opensimplex.noise3array(g * f, g * f, g * f)

        out["opensimplex fbm5"] = timed(os5, repeat)
    except ImportError:
        pass
    return out


def blender_peers(dim, n, repeat):
    try:
        import bpy  # noqa: F401
        from omninoise.blender_addon.field_eval import evaluate_field
    except ImportError:
        return {}
    g = np.arange(n, dtype=np.float32) * np.float32(4.0 / n)
    mesh = np.stack(np.meshgrid(*([g] * dim), indexing="ij"), -1).reshape(-1, dim)
    pts = np.zeros((len(mesh), 3), np.float32)
    pts[:, :dim] = mesh

    def noise(tree, pos):
        t = tree.nodes.new("ShaderNodeTexNoise")
        t.noise_dimensions = "3D" if dim == 3 else "2D"
        t.inputs["Scale"].default_value = 2.0
        t.inputs["Detail"].default_value = 5.0
        tree.links.new(pos, t.inputs["Vector"])
        return t.outputs["Fac"]

    def gabor(tree, pos):
        t = tree.nodes.new("ShaderNodeTexGabor")
        t.gabor_type = "3D" if dim == 3 else "2D"
        t.inputs["Scale"].default_value = 2.0
        tree.links.new(pos, t.inputs["Vector"])
        return t.outputs["Value"]

    def white(tree, pos):  # the cost of the evaluation harness itself
        t = tree.nodes.new("ShaderNodeTexWhiteNoise")
        tree.links.new(pos, t.inputs["Vector"])
        return t.outputs["Value"]

    out = {}
    for name, build in (("Blender Noise detail 5", noise), ("Blender Gabor", gabor), ("harness (White Noise)", white)):
        out[name] = timed(lambda: evaluate_field(pts, build), repeat)
    return out


def wave_times(dim, n, repeat, dirs):
    out = {}
    for k in dirs:
        s = WaveSettings(dim=dim, spectrum=Spectrum("fractal", 1.0, 16.0, 1.0), directions=k, seed=1)
        noise = compile_noise(s)
        out[f"wave {k} dirs"] = timed(lambda: evaluate_grid(noise, n, 4.0), repeat)
        if k == 16 and ckernel.available() and fast.available():  # the same grids on numba's row kernel
            before = ckernel.set_enabled(False)
            try:
                out["wave 16 dirs, numba kernel"] = timed(lambda: evaluate_grid(noise, n, 4.0), repeat)
            finally:
                ckernel.set_enabled(before)
    return out


def lookup_floor() -> dict:
    """ns per sample of the idealised AVX2 rows of bench/lookup_floor.c at 16 directions, all cores.

    Keys '<grid> pure|blend' (grid 2D_1024, 3D_128, 3D_256); {} without a C compiler.
    """
    cc = shutil.which(os.environ.get("CC", "cc"))
    if cc is None:
        return {}
    exe = os.path.join(ROOT, "out", "bench", "lookup_floor")
    os.makedirs(os.path.dirname(exe), exist_ok=True)
    subprocess.run([cc, "-O3", "-pthread", os.path.join(ROOT, "bench", "lookup_floor.c"), "-o", exe, "-lm"],
                   check=True)
    r = subprocess.run([exe, str(os.cpu_count() or 1)], capture_output=True, text=True, check=True)
    res = json.loads(r.stdout)
    return {} if "error" in res else res


def peak_memory_512() -> dict:
    # The peak is read from /proc/self/status (VmHWM) after resetting it (clear_refs 5): ru_maxrss, read before,
    # starts at the bench process's own peak, which a child inherits through fork and exec, so the 512^3 grid
    # appeared to need less than its output
    code = (
        "import resource, numpy as np\n"
        "from omninoise.backend import *\n"
        "def hwm():\n"
        "    try:\n"
        "        return int([l for l in open('/proc/self/status') if l.startswith('VmHWM')][0].split()[1])\n"
        "    except (OSError, IndexError):\n"
        "        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss\n"
        "try:\n"
        "    open('/proc/self/clear_refs', 'w').write('5')\n"
        "except OSError:\n"
        "    pass\n"
        "n = compile_noise(WaveSettings(dim=3, spectrum=Spectrum('gaussian', 2, 8), directions=8, seed=1))\n"
        "evaluate_grid(n, 16, 4.0)\n"  # JIT-compile first, so the baseline includes it
        "base = hwm()\n"
        "a = evaluate_grid(n, 512, 4.0)\n"
        "peak = hwm()\n"
        "print(base * 1024, peak * 1024, a.nbytes)\n")
    # the first run fills numba's on-disk cache (compiling takes memory of its own);
    # the second loads the compiled kernel and measures the evaluation alone
    subprocess.run([sys.executable, "-c", code.replace("512", "17")], capture_output=True, check=True)
    t = time.perf_counter()
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    wall = time.perf_counter() - t
    base, peak, nbytes = (int(v) for v in r.stdout.split())
    return dict(output_mib=nbytes / 2**20, peak_mib=peak / 2**20, before_mib=base / 2**20,
                extra_mib=(peak - base - nbytes) / 2**20, seconds=wall)


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--quick", action="store_true", help="smaller grids (smoke run)")
    ap.add_argument("--json", default=os.path.join(DATA, "wave.json"), help="default: docs/benchmarks/wave.json")
    a = ap.parse_args(argv)
    cases = [(2, 256), (3, 48)] if a.quick else [(2, 1024), (3, 128), (3, 256)]
    dirs = (8, 16) if a.quick else (8, 16, 32, 64)
    engine = ("C kernel (" + ("AVX2" if ckernel.vector() else "scalar") + ")" if ckernel.available()
              else "numba" if fast.available() else "numpy")
    print(f"wave noise engine: {engine} grid rows, {os.cpu_count()} cores")
    results = {"stamp": stamp(), "engine": engine}
    floor = {} if a.quick else lookup_floor()
    for dim, n in cases:
        samples = n ** dim
        rows = wave_times(dim, n, a.repeat, dirs)
        rows.update(peers(dim, n, a.repeat))
        if n <= 128:
            rows.update(blender_peers(dim, n, a.repeat))
        ns = {k: v / samples * 1e9 for k, v in rows.items()}
        for kind in ("pure", "blend"):  # already ns per sample
            if f"{dim}D_{n} {kind}" in floor:
                ns[f"wave 16 floor, {kind} (AVX2 C)"] = floor[f"{dim}D_{n} {kind}"]
        peer_ns = {k: v for k, v in ns.items() if not k.startswith("wave") and not k.startswith("harness")}
        fastest = min(peer_ns, key=peer_ns.get) if peer_ns else None
        print(f"\n{dim}D {n}^{dim} ({samples:,} samples)")
        print(f"  {'method':34s} {'ns/sample':>10s}  {'ratio vs ' + (fastest or '-'):s}")
        for k, v in sorted(ns.items(), key=lambda kv: kv[1]):
            ratio = v / peer_ns[fastest] if fastest else float("nan")
            print(f"  {k:34s} {v:10.1f}  {ratio:6.2f}x")
        if "wave 16 dirs, numba kernel" in ns:
            print(f"  wave 16 dirs: numba kernel / C kernel: {ns['wave 16 dirs, numba kernel'] / ns['wave 16 dirs']:.2f}x")
        for kind in ("blend", "pure"):
            fl = ns.get(f"wave 16 floor, {kind} (AVX2 C)")
            if fl:
                print(f"  wave 16 dirs / floor ({kind}): {ns['wave 16 dirs'] / fl:.2f}x")
        results[f"{dim}D_{n}"] = ns
    if ckernel.available():
        print(f"\nC kernel table reads: {ckernel.fetch_mode()} (the faster form on this CPU, timed by the first grid)")
        results["fetch_mode"] = ckernel.fetch_mode()
    if floor:
        results["floor"] = floor
    if not a.quick:
        m = peak_memory_512()
        print(f"\n512^3 grid, 8 dirs: output {m['output_mib']:.0f} MiB, process peak {m['peak_mib']:.0f} MiB "
              f"({m['extra_mib']:.0f} MiB beyond start + output), {m['seconds']:.1f} s")
        results["stream_512"] = m
    os.makedirs(os.path.dirname(a.json), exist_ok=True)
    with open(a.json, "w") as fh:
        json.dump(results, fh, indent=1)


if __name__ == "__main__":
    main()
