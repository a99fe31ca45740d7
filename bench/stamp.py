"""What a benchmark's figures were measured on: machine, software, date and commit, written into its JSON.

``docs/benchmarks.md`` states these beside every table (``python tools/benchmarks_md.py``).
"""
from __future__ import annotations

import datetime
import os
import platform
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
#: where the benchmarks' JSON lives for the benchmarks page
DATA = os.path.join(ROOT, "docs", "benchmarks")


def cpu_name() -> str:
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as fh:
            for line in fh:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def commit() -> str:
    """The checkout's commit (short), with ``+changes`` when the working tree differs from it."""
    try:
        head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True, text=True,
                              check=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=ROOT,
                               capture_output=True, text=True).stdout.strip()
        return head + ("+changes" if dirty else "")
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def stamp(argv: list | None = None) -> dict:
    """{command, machine, cores, python, numpy, onnxruntime, date, commit} of this run."""
    import numpy

    try:
        import onnxruntime
        ort = onnxruntime.__version__
    except ImportError:
        ort = None
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    args = sys.argv if argv is None else argv
    head = args[0] if args[0].startswith("python -m ") else "python " + os.path.relpath(args[0], ROOT)
    return dict(command=" ".join([head, *args[1:]]),
                machine=f"{cpu_name()}, {cores} cores, {platform.system()} {platform.machine()}",
                python=platform.python_version(), numpy=numpy.__version__, onnxruntime=ort,
                date=datetime.date.today().isoformat(), commit=commit())
