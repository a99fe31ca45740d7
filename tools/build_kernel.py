"""Build the C row kernel of wave noise: ``python tools/build_kernel.py`` (run by ``make setup``).

Compiles ``backend/wavenoise/rows.c`` with the system C compiler (``$CC``, else ``cc``) into
``backend/wavenoise/_omni_rows.so`` (atomic write), which :mod:`backend.wavenoise.ckernel` loads.  No
compiler, or a failed build, is not an error: the engine then runs its numba kernel (the reference) and
this prints why.  ``-ffp-contract=off`` keeps every multiply and add apart, as numba computes them, so
both kernels give the same bits; the AVX2 loops are compiled with a target attribute and chosen at run
time, so the library runs on any x86-64 CPU.  An up-to-date library (newer than ``rows.c``) is kept unless
``--force``; ``--check`` exits 1 when no library could be built.
"""
from __future__ import annotations

import os
import shutil
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from backend.wavenoise import ckernel  # noqa: E402
from export.atomic import atomic_path  # noqa: E402

FLAGS = ["-O3", "-fPIC", "-shared", "-ffp-contract=off", "-fno-math-errno", "-std=c11"]


def build(cc: str | None = None) -> str | None:
    """Compile the kernel; returns the library's path, or None (with the reason printed) when it cannot."""
    cc = cc or os.environ.get("CC") or shutil.which("cc") or shutil.which("gcc") or shutil.which("clang")
    if not cc:
        print("build_kernel: no C compiler (cc, gcc, clang): wave noise runs its numba kernel")
        return None
    src = os.path.join(ROOT, "backend", "wavenoise", "rows.c")
    out = ckernel.library_path()
    try:
        with atomic_path(out) as tmp:
            res = subprocess.run([cc, *FLAGS, src, "-o", tmp, "-lm"], capture_output=True, text=True)
            if res.returncode:  # leaves any earlier library in place; the temporary is removed
                raise RuntimeError(res.stderr.strip())
    except (RuntimeError, OSError) as exc:
        print(f"build_kernel: {cc} failed, wave noise runs its numba kernel:\n{exc}")
        return None
    return out


def up_to_date() -> bool:
    src = os.path.join(ROOT, "backend", "wavenoise", "rows.c")
    lib = ckernel.library_path()
    return os.path.isfile(lib) and os.path.getmtime(lib) >= os.path.getmtime(src)


def main(argv=None) -> int:
    argv = argv if argv is not None else sys.argv[1:]
    check = "--check" in argv
    if up_to_date() and "--force" not in argv:
        return 0
    path = build()
    if path:
        print(f"build_kernel: {os.path.relpath(path, ROOT)}")
    return 1 if check and not path else 0


if __name__ == "__main__":
    sys.exit(main())
