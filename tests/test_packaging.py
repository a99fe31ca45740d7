"""A non-editable install holds every runtime package (issue 23: it used to leave out backend.neural,
backend.solid and backend.training)."""
import os
import tomllib

from setuptools import find_packages

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def test_every_package_folder_is_installed():
    with open(os.path.join(ROOT, "pyproject.toml"), "rb") as fh:
        cfg = tomllib.load(fh)["tool"]["setuptools"]["packages"]["find"]
    found = set(find_packages(ROOT, include=cfg["include"]))
    on_disk = {os.path.relpath(d, ROOT).replace(os.sep, ".")
               for top in ("backend", "export") for d, _, files in os.walk(os.path.join(ROOT, top))
               if "__init__.py" in files}
    assert on_disk <= found, sorted(on_disk - found)
    assert {"backend.neural", "backend.solid", "backend.training.solid"} <= found
    assert not any(p.startswith(("tests", "blender_addon", "bench")) for p in found)
