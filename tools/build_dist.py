"""Build the installable extension zips with Blender's own builder (``make dist``).

1. Download the pinned wheels Blender lacks (onnxruntime, OpenEXR and their
   dependencies, minus numpy, which Blender bundles) for every Python the
   supported Blenders run (3.11: Blender 4.2-5.0; 3.13: Blender 5.1+) on
   linux-x64, windows-x64 and macos-arm64 into ``wheels/`` (kept between runs).
   One zip per platform carries both; Blender installs the wheels that match
   its own Python and the builder lists both versions in ``python_versions``.
   With the ``ziglang`` package installed (``make dist`` installs it), also build the C row kernel of wave
   noise for each platform (``tools/build_kernel.py``: Zig cross-compiles it) as the wheel
   ``omninoise_rows``, so installed extensions bake wave noise with it instead of numpy.
2. Stage the runtime files only (extension root, ``blender_addon``, ``backend``,
   ``export``; no tests, bench, demo or training code) into ``build/extension`` (``--work`` names
   another folder than ``build``) and list the platforms and wheels in the staged manifest.
3. Run ``blender_ext.py build --split-platforms`` from the ``bpy`` wheel (the
   same as ``blender --command extension build``), then ``validate`` each zip.

Usage: python tools/build_dist.py [--out dist] [--work build] [--no-wheels [--kernel]]
(``--no-wheels`` builds one zip without bundled wheels, which the tests install; the wheels are only needed
by the neural features.  ``--kernel`` adds this machine's kernel wheel, built with its own C compiler, to
that zip, for this machine's platform only.)
"""
from __future__ import annotations

import argparse
import importlib.util
import os
import re
import shutil
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
#: where the files are staged and the kernel built, unless --work names another folder
BUILD = os.path.join(ROOT, "build")
sys.path.insert(0, os.path.join(ROOT, "tools"))

import build_kernel  # noqa: E402
PINS = {"onnxruntime": "1.31.1", "OpenEXR": "3.5.3"}
#: the Pythons of the supported Blenders: 4.2 LTS-5.0 run 3.11, 5.1 and newer 3.13
PYTHONS = ("3.11", "3.13")
PLATFORMS = {  # Blender platform -> pip platform tag
    "linux-x64": "manylinux_2_28_x86_64",
    "windows-x64": "win_amd64",
    "macos-arm64": "macosx_14_0_arm64",
}
RUNTIME = ("__init__.py", "api.py", "blender_manifest.toml", "LICENSE", "blender_addon", "backend", "export", "models")
EXCLUDE_DIRS = {"__pycache__"}
#: the C row kernel built for this machine (tools/build_kernel.py) is not a file of the platform-independent
#: extension: installed extensions run the numpy path of wave noise, or numba where Blender's Python has it
EXCLUDE_PREFIXES = ("_omni_rows.",)


def blender_ext() -> str:
    spec = importlib.util.find_spec("bpy")
    if spec is None or not spec.origin:
        sys.exit("make dist: the bpy module is not installed (run make test or pip install bpy==5.0.1)")
    base = os.path.dirname(spec.origin)
    for d in sorted(os.listdir(base)):
        p = os.path.join(base, d, "scripts", "addons_core", "bl_pkg", "cli", "blender_ext.py")
        if os.path.exists(p):
            return p
    sys.exit(f"make dist: blender_ext.py not found under {base}")


def _has_pins(folder: str, py: str) -> bool:
    """Every pinned package has a wheel for Python ``py`` (cp311 ...) in ``folder``."""
    cp = "cp" + py.replace(".", "")
    have = [f.lower() for f in os.listdir(folder) if f.endswith(".whl")]
    return all(any(f.startswith(n.lower() + "-" + v + "-") and f"-{cp}-" in f for f in have) for n, v in PINS.items())


def download_wheels() -> list[str]:
    out = []
    for plat, tag in PLATFORMS.items():
        dest = os.path.join(ROOT, "wheels", plat)
        os.makedirs(dest, exist_ok=True)
        for py in PYTHONS:
            if not _has_pins(dest, py):
                cmd = [sys.executable, "-m", "pip", "download", "--quiet", "--only-binary=:all:", "--python-version",
                       py, "--platform", tag, "-d", dest] + [f"{n}=={v}" for n, v in PINS.items()]
                print(f"downloading wheels for {plat}, Python {py}", flush=True)
                subprocess.run(cmd, check=True)
        for f in sorted(os.listdir(dest)):
            if f.endswith(".whl") and not f.startswith(("numpy-", build_kernel.PACKAGE + "-")):
                out.append(os.path.join(dest, f))
        kernel = build_kernel.kernel_wheel(plat, os.path.join(ROOT, "build", "kernel", plat))
        if kernel:
            out.append(kernel)
    return out


def wheel_licence(path: str) -> tuple:
    """(name, version, licence, licence files) of a wheel: the licence from its METADATA (License-Expression,
    License, or the licence classifiers), and the paths of the licence texts it carries."""
    import zipfile

    with zipfile.ZipFile(path) as z:
        meta_name = next(n for n in z.namelist() if n.endswith(".dist-info/METADATA"))
        meta = z.read(meta_name).decode("utf-8", "replace").split("\n\n", 1)[0]
        files = sorted(n for n in z.namelist() if (".dist-info/" in n or n.count("/") <= 1) and
                       re.search(r"(LICEN[CS]E|COPYING|NOTICE)", n.rsplit("/", 1)[-1], re.I))
    fields = {}
    for line in meta.splitlines():
        k, _, v = line.partition(": ")
        fields.setdefault(k, []).append(v.strip())
    licence = (fields.get("License-Expression") or fields.get("License") or [""])[0]
    if not licence or len(licence) > 80:        # a whole licence text pasted into the field: use the classifiers
        classes = [c.rsplit(" :: ", 1)[-1] for c in fields.get("Classifier", []) if c.startswith("License ::")]
        licence = ", ".join(classes) or "see the wheel's licence files"
    return fields.get("Name", ["?"])[0], fields.get("Version", ["?"])[0], licence, files


def write_third_party(dst: str, wheels: list[str]) -> str:
    """THIRD_PARTY_LICENSES.md in the staged extension: each bundled wheel, its version, its licence and where in
    the wheel its licence text is (each wheel keeps its own licence files)."""
    rows, seen = [], set()
    for w in sorted(wheels):
        name, version, licence, files = wheel_licence(w)
        if (name, version) in seen:
            continue
        seen.add((name, version))
        rows.append(f"| {name} | {version} | {licence} | {', '.join(files) or 'none (the licence is named in its METADATA)'} |")
    text = ("# Third-party software bundled with OmniNoise\n\n"
            "The extension installs these Python wheels (in `wheels/`). Each wheel carries its own licence text, at "
            "the path given, and Blender installs it with the wheel.\n\n"
            "| package | version | licence | licence text in the wheel |\n|---|---|---|---|\n" + "\n".join(rows) + "\n")
    path = os.path.join(dst, "THIRD_PARTY_LICENSES.md")
    with open(path, "w", encoding="utf-8") as fh:
        fh.write(text)
    return path


def stage(wheels: list[str], platforms=tuple(PLATFORMS), work: str = BUILD) -> str:
    """The runtime files, ``wheels`` and a manifest listing them and ``platforms``, staged in a folder of
    ``work``; its path."""
    dst = os.path.join(work, "extension-nowheels" if not wheels else "extension")
    shutil.rmtree(dst, ignore_errors=True)
    os.makedirs(os.path.join(dst, "wheels"))
    for item in RUNTIME:
        src = os.path.join(ROOT, item)
        if os.path.isdir(src):
            shutil.copytree(src, os.path.join(dst, item),
                            ignore=lambda d, names: [n for n in names if n in EXCLUDE_DIRS or n.endswith(".pyc")
                                                    or n.startswith(EXCLUDE_PREFIXES)])
        else:
            shutil.copy2(src, dst)
    names = []
    for w in wheels:
        name = os.path.basename(w)
        if name not in names:
            shutil.copy2(w, os.path.join(dst, "wheels", name))
            names.append(name)
    if names:
        write_third_party(dst, [os.path.join(dst, "wheels", n) for n in names])
    man = os.path.join(dst, "blender_manifest.toml")
    text = open(man, encoding="utf-8").read()
    extra = ""
    if names:
        extra = ("platforms = [" + ", ".join(f'"{p}"' for p in platforms) + "]\n"
                 "wheels = [\n" + "".join(f'  "./wheels/{n}",\n' for n in names) + "]\n")
    text = re.sub(r"(blender_version_min\s*=.*\n)", lambda m: m.group(1) + extra, text, count=1)
    open(man, "w", encoding="utf-8").write(text)
    return dst


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", default=os.path.join(ROOT, "dist"))
    ap.add_argument("--work", default=BUILD,
                    help="the folder the files are staged and the kernel built in (builds that may run at once, as "
                         "the tests on several Blenders, each name their own)")
    ap.add_argument("--no-wheels", action="store_true", help="one zip without bundled wheels")
    ap.add_argument("--kernel", action="store_true",
                    help="with --no-wheels: add this machine's C kernel wheel (linux-x64 only)")
    a = ap.parse_args()
    tool = blender_ext()
    if a.no_wheels and a.kernel:
        if not sys.platform.startswith("linux"):
            sys.exit("--kernel builds the linux-x64 kernel wheel with this machine's compiler: Linux only")
        wheel = build_kernel.kernel_wheel("linux-x64", os.path.join(a.work, "kernel-native"), native=True)
        if not wheel:
            sys.exit("--kernel: the C kernel did not build (see above)")
        src = stage([wheel], ("linux-x64",), work=a.work)
    else:
        src = stage([] if a.no_wheels else download_wheels(), work=a.work)
    os.makedirs(a.out, exist_ok=True)
    split = [] if a.no_wheels else ["--split-platforms"]
    subprocess.run([sys.executable, tool, "build", "--source-dir", src, "--output-dir", a.out] + split, check=True)
    zips = sorted(f for f in os.listdir(a.out) if f.endswith(".zip"))
    for z in zips:
        subprocess.run([sys.executable, tool, "validate", os.path.join(a.out, z)], check=True)
        print(f"{z}: {os.path.getsize(os.path.join(a.out, z)) / 2**20:.1f} MiB, valid")


if __name__ == "__main__":
    main()
