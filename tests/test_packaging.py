"""`pip install .` installs one import package, ``omninoise``, holding every runtime package, the models and the
licence, and nothing else at the top level of site-packages."""
import os
import re
import subprocess
import sys
import tomllib
import zipfile

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
LAYERS = ("backend", "export", "cli", "training", "blender_addon")


def _pyproject() -> dict:
    with open(os.path.join(ROOT, "pyproject.toml"), "rb") as fh:
        return tomllib.load(fh)


def test_every_package_folder_is_listed_under_omninoise():
    listed = set(_pyproject()["tool"]["setuptools"]["packages"])
    on_disk = {"omninoise." + os.path.relpath(d, ROOT).replace(os.sep, ".")
               for top in LAYERS for d, _, files in os.walk(os.path.join(ROOT, top)) if "__init__.py" in files}
    assert on_disk <= listed, sorted(on_disk - listed)
    # the others listed are folders of data only (models, presets, assets: the wheel's build names any it misses)
    for name in sorted(listed - on_disk - {"omninoise"}):
        folder = os.path.join(ROOT, *name.split(".")[1:])
        assert os.path.isdir(folder) and "__init__.py" not in os.listdir(folder), name
        assert any(os.path.isfile(os.path.join(folder, f)) for f in os.listdir(folder)), f"{name}: no files"
    # a folder of modules without __init__.py imports from a checkout (a namespace package) but is left out of the
    # wheel; Blender's presets are data (package-data), not modules
    presets = os.path.join(ROOT, "blender_addon", "presets")
    loose = [os.path.relpath(d, ROOT) for top in LAYERS for d, _, files in os.walk(os.path.join(ROOT, top))
             if any(f.endswith(".py") for f in files) and "__init__.py" not in files and not d.startswith(presets)]
    assert not loose, loose
    assert _pyproject()["tool"]["setuptools"]["package-dir"] == {"omninoise": "."}


def test_versions_agree():
    """One version in the package metadata, the extension manifest and ``omninoise.__version__``."""
    from omninoise.backend.version import __version__

    with open(os.path.join(ROOT, "blender_manifest.toml"), "rb") as fh:
        manifest = tomllib.load(fh)
    assert _pyproject()["project"]["version"] == manifest["version"] == __version__
    with open(os.path.join(ROOT, "CHANGELOG.md"), encoding="utf-8") as fh:
        assert re.search(r"^## \[?%s\]?" % re.escape(__version__), fh.read(), re.M), "CHANGELOG names the version"


def test_extras_declare_the_optional_dependencies():
    extras = _pyproject()["project"]["optional-dependencies"]
    names = {k: {re.split(r"[<>=!~ \[]", d)[0].lower() for d in v} for k, v in extras.items()}
    assert {"numba"} <= names["fast"] and {"dask", "distributed"} <= names["farm"]
    assert {"torch", "onnx"} <= names["train"]


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    """The wheel `pip install .` builds, installed (without dependencies: they are this venv's) into a prefix
    outside the repository: (wheel, site-packages folder)."""
    tmp = tmp_path_factory.mktemp("install")
    wheels = tmp / "wheels"
    r = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q", "-w",
                        str(wheels), ROOT], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr[-2000:]
    # every folder that ships files is a package of pyproject.toml's list (setuptools warns of one it is not)
    absent = sorted(set(re.findall(r"Package '([^']+)' is absent from the `packages` configuration", r.stderr)))
    assert not absent, f"add to [tool.setuptools] packages: {absent}"
    (wheel,) = wheels.glob("omninoise-*.whl")
    prefix = tmp / "prefix"
    r = subprocess.run([sys.executable, "-m", "pip", "install", "--no-deps", "--ignore-installed", "-q", "--prefix",
                        str(prefix), str(wheel)], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr[-2000:]
    (site,) = prefix.glob("lib/python3*/site-packages")
    return wheel, site


def test_the_wheel_holds_one_package_with_its_models_and_licence(installed):
    wheel, site = installed
    tops = {n.split("/")[0] for n in zipfile.ZipFile(wheel).namelist()}
    assert {t for t in tops if not t.endswith(".dist-info")} == {"omninoise"}, tops
    assert sorted(p.name for p in site.iterdir() if not p.name.endswith(".dist-info")) == ["omninoise"]
    pkg = site / "omninoise"
    for f in ("__init__.py", "__main__.py", "api.py", "LICENSE", "cli/main.py", "backend/neural/generate.py",
              "backend/solid/model.py", "cli/farm.py", "training/zoo.py", "export/vdb.py",
              "models/neural_noise/denoiser.onnx", "models/neural_noise/neural_noise.json",
              "models/solid/space/encoder.onnx", "models/fit_bank/bank.npz"):
        assert (pkg / f).is_file(), f
    for folder, _, files in os.walk(os.path.join(ROOT, "models")):     # every shipped model file travels
        for f in files:
            rel = os.path.relpath(os.path.join(folder, f), ROOT)
            assert (pkg / rel).is_file(), f"{rel}: add its pattern to [tool.setuptools.package-data]"
    meta = next(n for n in zipfile.ZipFile(wheel).namelist() if n.endswith("METADATA"))
    text = zipfile.ZipFile(wheel).read(meta).decode()
    for field in ("License-Expression: GPL-3.0-or-later", "License-File: LICENSE", "Provides-Extra: fast",
                  "Provides-Extra: farm", "Provides-Extra: train", "Project-URL:"):
        assert field in text, field
    assert any(n.endswith(".dist-info/licenses/LICENSE") for n in zipfile.ZipFile(wheel).namelist())


def test_the_installed_package_runs_every_subcommand_and_the_api(installed, tmp_path):
    """From the installed copy, with the repository off sys.path: ``python -m omninoise --version``, each
    subcommand, and the four API calls."""
    _, site = installed
    env = dict(os.environ, PYTHONPATH=str(site))
    r = subprocess.run([sys.executable, "-I", "-c", "import sys; sys.path.insert(0, %r); "
                        "sys.argv = ['omninoise', '--version']; import runpy; "
                        "runpy.run_module('omninoise', run_name='__main__')" % str(site)],
                       capture_output=True, text=True, cwd=str(tmp_path), timeout=120)
    assert r.returncode == 0 and re.match(r"omninoise \d+\.\d+\.\d+ \(wave noise: ", r.stdout), r.stdout + r.stderr
    code = ("import sys; sys.path.insert(0, %r); import omninoise, omninoise.cli.main as c; "
            "assert omninoise.__file__.startswith(%r), omninoise.__file__; out = %r; "
            "rc = [c.main(['wave', '--size', '8', '--quiet', '-o', out + '/w.npy']), "
            "c.main(['transfer', '--list']), c.main(['neural', '--list']), c.main(['solid', '--list']), "
            "c.main(['zoo', '--noise', 'perlin', '--size', '8', '-o', out + '/z.png']), "
            "c.main(['neural', '--noise', 'perlin', '--size', '8', '--steps', '1', '--quiet', '-o', out + '/n.png']), "
            "c.main(['solid', '--exemplar', 'grass', '--size', '8', '--quiet', '-o', out + '/s.png'])]; "
            "a = [omninoise.wave(8).shape, omninoise.neural('perlin', 8, steps=1).shape, "
            "omninoise.solid('grass', 8).shape]; print('RC', rc, a)"
            ) % (str(site), str(site), str(tmp_path))
    r = subprocess.run([sys.executable, "-I", "-c", code], capture_output=True, text=True, cwd=str(tmp_path),
                       timeout=300, env=env)
    assert "RC [0, 0, 0, 0, 0, 0, 0] [(8, 8), (8, 8), (8, 8, 3)]" in r.stdout, r.stdout[-2000:] + r.stderr[-2000:]


def test_omninoise_models_points_every_front_end_at_another_model_folder(tmp_path, monkeypatch, capsys):
    from omninoise.backend import paths
    from omninoise.cli.main import main

    monkeypatch.setenv("OMNINOISE_MODELS", str(tmp_path / "farm-models"))
    for argv in (["neural", "--noise", "perlin"], ["solid", "--exemplar", "gravel_2d"]):    # no such folder
        assert main(argv + ["-o", str(tmp_path / "n.png")]) == 2
        assert capsys.readouterr().err.strip() == (f"omninoise {argv[0]}: error: OMNINOISE_MODELS: {tmp_path}/farm-"
                                                   "models is not a folder (it names the folder of models, which "
                                                   "holds neural_noise and solid)")
    (tmp_path / "farm-models").mkdir()
    assert paths.neural_model() == str(tmp_path / "farm-models" / "neural_noise")
    assert main(["neural", "--noise", "perlin", "-o", str(tmp_path / "n.png")]) == 2
    assert str(tmp_path / "farm-models") in capsys.readouterr().err  # the error names the folder it looked in
    assert not (tmp_path / "n.png").exists()


def test_the_docstring_examples_run():
    """Every docstring example of the runtime (the package, its API, the backend, the writers and the command
    line) is a doctest: each module that shows one runs it."""
    import doctest
    import importlib

    names = []
    for folder in ("", "backend", "export", "cli"):
        for dirpath, _, files in os.walk(os.path.normpath(os.path.join(ROOT, folder))):
            if folder == "" and dirpath != ROOT:
                continue
            for f in sorted(files):
                path = os.path.join(dirpath, f)
                if f.endswith(".py") and ">>> " in open(path, encoding="utf-8").read():
                    rel = os.path.relpath(path, ROOT)[:-3].replace(os.sep, ".")
                    names.append("omninoise" + ("" if rel == "__init__" else "." + rel.removesuffix(".__init__")))
    assert {"omninoise", "omninoise.api", "omninoise.backend.paths"} <= set(names)
    for name in names:
        res = doctest.testmod(importlib.import_module(name), optionflags=doctest.ELLIPSIS)
        assert res.attempted > 0 and res.failed == 0, (name, res)


def test_the_extension_lists_each_bundled_wheels_licence(tmp_path):
    """build_dist writes THIRD_PARTY_LICENSES.md from the wheels' own metadata, pointing at their licence texts."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("build_dist", os.path.join(ROOT, "tools", "build_dist.py"))
    bd = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bd)
    wheels = []
    for name, meta, lic in (("alpha", "License-Expression: MIT\n", "alpha-1.0.dist-info/licenses/LICENSE"),
                            ("beta", "License: " + "x" * 200 + "\nClassifier: License :: OSI Approved :: BSD License\n",
                             "beta-2.0.dist-info/LICENSE.txt")):
        version = "1.0" if name == "alpha" else "2.0"
        w = tmp_path / f"{name}-{version}-py3-none-any.whl"
        with zipfile.ZipFile(w, "w") as z:
            z.writestr(f"{name}-{version}.dist-info/METADATA",
                       f"Metadata-Version: 2.4\nName: {name}\nVersion: {version}\n{meta}\nlong description")
            z.writestr(lic, "licence text")
        wheels.append(str(w))
    text = open(bd.write_third_party(str(tmp_path), wheels), encoding="utf-8").read()
    assert "| alpha | 1.0 | MIT | alpha-1.0.dist-info/licenses/LICENSE |" in text
    assert "| beta | 2.0 | BSD License | beta-2.0.dist-info/LICENSE.txt |" in text
