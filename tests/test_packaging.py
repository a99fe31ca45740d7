"""A non-editable install holds every runtime package (issue 23: it used to leave out backend.neural,
backend.solid and training)."""
import os
import tomllib

from setuptools import find_packages

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def test_every_package_folder_is_installed():
    with open(os.path.join(ROOT, "pyproject.toml"), "rb") as fh:
        cfg = tomllib.load(fh)["tool"]["setuptools"]["packages"]["find"]
    found = set(find_packages(ROOT, include=cfg["include"]))
    on_disk = {os.path.relpath(d, ROOT).replace(os.sep, ".")
               for top in ("backend", "export", "cli", "training") for d, _, files in os.walk(os.path.join(ROOT, top))
               if "__init__.py" in files}
    assert on_disk <= found, sorted(on_disk - found)
    assert {"backend.neural", "backend.solid", "cli", "training", "training.solid"} <= found
    assert not any(p.startswith(("tests", "blender_addon", "bench")) for p in found)


def test_a_non_editable_install_runs_every_subcommand(tmp_path):
    """Build the wheel as `pip install .` would, install it (without dependencies: they are this venv's) into a
    folder outside the repository, and run each subcommand from there, with the repository off sys.path."""
    import subprocess
    import sys
    import zipfile

    wheels = tmp_path / "wheels"
    r = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q", "-w",
                        str(wheels), ROOT], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr[-2000:]
    (wheel,) = wheels.glob("omninoise-*.whl")
    names = zipfile.ZipFile(wheel).namelist()
    for module in ("cli/main.py", "backend/neural/generate.py", "backend/solid/model.py", "cli/farm.py",
                   "training/zoo.py", "export/vdb.py"):
        assert module in names, module
    prefix = tmp_path / "prefix"
    r = subprocess.run([sys.executable, "-m", "pip", "install", "--no-deps", "--ignore-installed", "-q", "--prefix", str(prefix),
                        str(wheel)],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr[-2000:]
    (site,) = prefix.glob("lib/python3*/site-packages")
    assert (prefix / "share" / "omninoise" / "models" / "neural_noise" / "denoiser.onnx").is_file()
    code = ("import sys, os; sys.path = [p for p in sys.path if os.path.abspath(p or '.') != %r]; "
            "sys.path.insert(0, %r); import cli.main as c; assert c.__file__.startswith(%r), c.__file__; "
            "out = %r; "
            "rc = [c.main(['wave', '--size', '8', '--quiet', '-o', out + '/w.npy']), "
            "c.main(['transfer', '--list']), c.main(['neural', '--list']), c.main(['solid', '--list']), "
            "c.main(['zoo', '--noise', 'perlin', '--size', '8', '-o', out + '/z.png']), "
            "c.main(['neural', '--noise', 'perlin', '--size', '8', '--steps', '1', '--quiet', '-o', out + '/n.png']), "
            "c.main(['solid', '--exemplar', 'grass', '--size', '8', '--quiet', '-o', out + '/s.png'])]; print('RC', rc)"
            ) % (ROOT, str(site), str(site), str(tmp_path))
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=str(tmp_path), timeout=300)
    assert "RC [0, 0, 0, 0, 0, 0, 0]" in r.stdout, r.stdout[-2000:] + r.stderr[-2000:]


def test_every_shipped_model_folder_is_in_the_data_files():
    with open(os.path.join(ROOT, "pyproject.toml"), "rb") as fh:
        data = tomllib.load(fh)["tool"]["setuptools"]["data-files"]
    models = os.path.join(ROOT, "models")
    for folder, _, files in os.walk(models):
        rel = os.path.relpath(folder, models).replace(os.sep, "/")
        key = "share/omninoise/models" + ("" if rel == "." else "/" + rel)
        assert key in data, f"{key}: add the folder to [tool.setuptools.data-files] in pyproject.toml"
        exts = {os.path.splitext(f)[1] for f in files}
        listed = {os.path.splitext(g)[1] for g in data[key]}
        assert exts <= listed, (key, exts - listed)


def test_omninoise_models_points_every_front_end_at_another_model_folder(tmp_path, monkeypatch, capsys):
    from backend import paths
    from cli.main import main

    monkeypatch.setenv("OMNINOISE_MODELS", str(tmp_path / "farm-models"))
    assert paths.neural_model() == str(tmp_path / "farm-models" / "neural_noise")
    assert main(["neural", "--noise", "perlin", "-o", str(tmp_path / "n.png")]) == 2
    assert str(tmp_path / "farm-models") in capsys.readouterr().err  # the error names the folder it looked in
