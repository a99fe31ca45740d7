"""Build the C row kernel of wave noise: ``python tools/build_kernel.py`` (run by ``make setup``).

Compiles ``backend/wavenoise/rows.c`` with the system C compiler (``$CC``, else ``cc``) into
``backend/wavenoise/_omni_rows.so`` (atomic write), which :mod:`backend.wavenoise.ckernel` loads.  No
compiler, or a failed build, is not an error: the engine then runs its numba kernel (the reference) and
this prints why.  ``-ffp-contract=off`` keeps every multiply and add apart, as numba computes them, so
the scalar loops give numba's bits (the AVX2 loops fuse only where they say so, within 2e-6); the AVX2 loops are compiled with a target attribute and chosen at run
time, so the library runs on any x86-64 CPU.  An up-to-date library (newer than ``rows.c``) is kept unless
``--force``; ``--check`` exits 1 when no library could be built.

For the extension (``make dist``), :func:`kernel_wheel` builds the library for a Blender platform with
Zig's C compiler (the ``ziglang`` package from PyPI cross-compiles to Linux, Windows and macOS without
their SDKs) and wraps it in a wheel, ``omninoise_rows``, that Blender installs with the extension; the
runtime finds the library there (:func:`backend.wavenoise.ckernel.library_path`).
"""
from __future__ import annotations

import base64
import hashlib
import io
import os
import shutil
import subprocess
import sys
import tempfile
import zipfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from omninoise.backend.version import __version__  # noqa: E402
from omninoise.backend.wavenoise import ckernel  # noqa: E402
from omninoise.export.atomic import atomic_path  # noqa: E402

SOURCE = os.path.join(ROOT, "backend", "wavenoise", "rows.c")
FLAGS = ["-O3", "-shared", "-ffp-contract=off", "-fno-math-errno", "-std=c11"]
#: Blender platform -> (Zig target, wheel platform tag, library suffix)
TARGETS = {
    "linux-x64": ("x86_64-linux-gnu.2.17", "manylinux_2_17_x86_64", ".so"),
    "windows-x64": ("x86_64-windows-gnu", "win_amd64", ".dll"),
    "macos-arm64": ("aarch64-macos.11.0", "macosx_11_0_arm64", ".dylib"),
}
PACKAGE = "omninoise_rows"


def _compile(cmd: list, out: str) -> str | None:
    """Run a compiler command that writes ``out`` (through a temporary: atomic); None with the reason printed."""
    try:
        with atomic_path(out) as tmp:
            res = subprocess.run(cmd + ["-o", tmp], capture_output=True, text=True)
            if res.returncode:  # leaves any earlier library in place; the temporary is removed
                raise RuntimeError(res.stderr.strip())
    except (RuntimeError, OSError) as exc:
        print(f"build_kernel: {cmd[0]} failed, wave noise runs its numba kernel:\n{exc}")
        return None
    return out


def build(cc: str | None = None, out: str | None = None) -> str | None:
    """Compile the kernel for this machine; returns the library's path, or None (reason printed)."""
    cc = cc or os.environ.get("CC") or shutil.which("cc") or shutil.which("gcc") or shutil.which("clang")
    if not cc:
        print("build_kernel: no C compiler (cc, gcc, clang): wave noise runs its numba kernel")
        return None
    return _compile([cc, *FLAGS, "-fPIC", SOURCE, "-lm"], out or ckernel.local_path())


def zig_available() -> bool:
    import importlib.util
    return importlib.util.find_spec("ziglang") is not None


def build_for(platform: str, out: str) -> str | None:
    """Cross-compile the kernel for a Blender platform (``TARGETS``) with Zig's C compiler."""
    target = TARGETS[platform][0]
    cmd = [sys.executable, "-m", "ziglang", "cc", "-target", target, *FLAGS, "-g0", "-s", SOURCE]
    return _compile(cmd + (["-lm"] if platform == "linux-x64" else []), out)


def _record_hash(data: bytes) -> str:
    return "sha256=" + base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=").decode()


def write_wheel(library: str, platform: str, folder: str) -> str:
    """Wrap a built library in the wheel ``omninoise_rows`` for ``platform``; returns the wheel's path.

    The package holds the library and an ``__init__`` that names it; no Python extension module, so one
    wheel serves every Python version (tag py3-none-PLATFORM)."""
    tag, suffix = TARGETS[platform][1], TARGETS[platform][2]
    version = f"{__version__}.{ckernel.ABI}"
    dist = f"{PACKAGE}-{version}"
    init = (f'"""The C row kernel of OmniNoise\'s wave noise, built for {platform} (see backend/wavenoise/rows.c)."""\n'
            "import os\n\n"
            f"LIBRARY = os.path.join(os.path.dirname(os.path.abspath(__file__)), '_omni_rows{suffix}')\n"
            f"ABI = {ckernel.ABI}\n").encode()
    with open(library, "rb") as fh:
        lib = fh.read()
    files = {
        f"{PACKAGE}/__init__.py": init,
        f"{PACKAGE}/_omni_rows{suffix}": lib,
        f"{dist}.dist-info/METADATA": (f"Metadata-Version: 2.1\nName: {PACKAGE}\nVersion: {version}\n"
                                       "Summary: OmniNoise wave noise row kernel (C, loaded with ctypes)\n"
                                       "License: GPL-3.0-or-later\n").encode(),
        f"{dist}.dist-info/WHEEL": (f"Wheel-Version: 1.0\nGenerator: omninoise build_kernel\nRoot-Is-Purelib: false\n"
                                    f"Tag: py3-none-{tag}\n").encode(),
    }
    record = "".join(f"{n},{_record_hash(d)},{len(d)}\n" for n, d in files.items())
    files[f"{dist}.dist-info/RECORD"] = (record + f"{dist}.dist-info/RECORD,,\n").encode()
    os.makedirs(folder, exist_ok=True)
    path = os.path.join(folder, f"{dist}-py3-none-{tag}.whl")
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as z:
        for name, data in files.items():
            info = zipfile.ZipInfo(name, date_time=(2020, 1, 1, 0, 0, 0))  # fixed: the same bytes every build
            info.external_attr = 0o644 << 16
            info.compress_type = zipfile.ZIP_DEFLATED
            z.writestr(info, data)
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as fh:
            fh.write(buf.getvalue())
    return path


def kernel_wheel(platform: str, folder: str, native: bool = False) -> str | None:
    """Build the kernel for ``platform`` and its wheel in ``folder``; None (reason printed) when it cannot.

    native: compile with this machine's C compiler instead of Zig (only for this machine's platform)."""
    with tempfile.TemporaryDirectory() as tmp:
        lib = os.path.join(tmp, "_omni_rows" + TARGETS[platform][2])
        if native:
            built = build(out=lib)
        elif zig_available():
            built = build_for(platform, lib)
        else:
            print("build_kernel: the ziglang package is not installed: the extension ships without the C kernel")
            return None
        return write_wheel(built, platform, folder) if built else None


def up_to_date() -> bool:
    lib = ckernel.local_path()
    return os.path.isfile(lib) and os.path.getmtime(lib) >= os.path.getmtime(SOURCE)


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
