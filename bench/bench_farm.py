"""Farm speed-up, measured: `python -m bench farm [--frames 12] [--size 48] [-o JSON]`.

The same job (an animated 3D wave-noise sequence through the fire ramp, one .vdb per frame) baked three ways
in one run: on this machine as `omninoise bake` does, and on local Dask clusters of 1 and 2 worker processes.
Prints seconds, the speed-up of 2 workers over 1, the overhead per task (cluster time minus the one-machine
time, per frame) and the bytes per frame; writes them to docs/benchmarks/farm.json (``docs/benchmarks.md``).
"""
from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time

from bench.stamp import DATA, stamp
from omninoise.backend.jobs import run_job
from omninoise.cli import farm
from omninoise.export.atomic import write_json

JOB = """
[[bake]]
name = "fire"
output = "out/fire_####.vdb"
resolution = [{n}, {n}, {n}]
bounds = [[0, 0, 0], [2, 2, 2]]
transfer = "fire"
frames = [1, {frames}]
[bake.source]
dim = 3
speed = 0.5
directions = 16
spectrum = {{kind = "fractal", fmin = 1, fmax = 8, exponent = 1.0}}
"""


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--frames", type=int, default=12)
    ap.add_argument("--size", type=int, default=48)
    ap.add_argument("-o", "--out", default=os.path.join(DATA, "farm.json"))
    a = ap.parse_args(argv)
    text = JOB.format(n=a.size, frames=a.frames)
    res = {}
    with tempfile.TemporaryDirectory() as tmp:
        def job(name):
            os.makedirs(os.path.join(tmp, name))
            path = os.path.join(tmp, name, "job.toml")
            with open(path, "w", encoding="utf-8") as fh:
                fh.write(text)
            return path

        warm = job("warm")
        run_job(warm)  # numba compiled and cached before anything is timed
        t = time.perf_counter()
        run_job(job("local"))
        res["one machine"] = time.perf_counter() - t
        size = os.path.getsize(os.path.join(tmp, "local", "out", "fire_0001.vdb"))
        for n in (1, 2):
            client = farm.local_client(n)
            try:
                client.run(lambda: __import__("omninoise.cli.farm"))
                farm.run_farm(warm, client, force=True)  # workers import and compile once
                t = time.perf_counter()
                farm.run_farm(job(f"w{n}"), client)
                res[f"{n} worker{'s' if n > 1 else ''}"] = time.perf_counter() - t
            finally:
                client.close()
                client.cluster.close()
    print(f"{a.frames} frames of {a.size}³ (fire ramp, 16 directions), {size / 1024:.0f} KiB per frame")
    print("| run | seconds | per frame |")
    print("|---|---|---|")
    for k, v in res.items():
        print(f"| {k} | {v:.2f} | {v / a.frames:.3f} |")
    speedup, overhead = res["1 worker"] / res["2 workers"], (res["1 worker"] - res["one machine"]) / a.frames
    print(f"speed-up 2 workers / 1 worker: {speedup:.2f}x; overhead per task on 1 worker: {overhead * 1000:.0f} ms")
    write_json(a.out, dict(stamp=stamp(), frames=a.frames, size=a.size, bytes_per_frame=size,
                           seconds={k: round(v, 3) for k, v in res.items()}, speedup_2_over_1=round(speedup, 2),
                           overhead_per_task_ms=round(overhead * 1000, 1)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
