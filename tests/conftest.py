import os
import sys
import tempfile

import numpy as np
import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def _package_from_checkout():
    """``import omninoise`` is this checkout (the repository root is the package) in-process, also where the
    environment has not installed it or has installed another copy (``make`` installs it editable; tests that start
    a fresh interpreter need that install)."""
    import importlib.util

    init = os.path.join(ROOT, "__init__.py")
    spec = importlib.util.find_spec("omninoise")
    if spec is not None and spec.origin and os.path.samefile(spec.origin, init):
        return
    spec = importlib.util.spec_from_file_location("omninoise", init, submodule_search_locations=[ROOT])
    module = importlib.util.module_from_spec(spec)
    sys.modules["omninoise"] = module
    spec.loader.exec_module(module)


_package_from_checkout()

#: the user's cache folder (what Blender bakes of unsaved files use where the package is registered by a script,
#: as these tests do) lies in a folder of the test run, not in the home folder
os.environ["XDG_CACHE_HOME"] = tempfile.mkdtemp(prefix="omninoise-tests-cache-")
#: and the user's scripts folder (user presets, the shipped presets where a Blender copies them there) too
os.environ["BLENDER_USER_SCRIPTS"] = tempfile.mkdtemp(prefix="omninoise-tests-scripts-")

#: folders whose every test is long (``make test-long``): Blender's (bpy start-up, renders) and training's (torch)
LONG_FOLDERS = ("blender", "training")
#: files whose every test is long: the documents' examples and the installed wheel run whole commands
LONG_FILES = ("test_doc_examples.py", "test_packaging.py")


def pytest_collection_modifyitems(config, items):
    """``make test`` runs the tests not marked ``long`` (a few minutes on two cores); ``make test-long`` the long
    integration tests: every test in LONG_FOLDERS and LONG_FILES, and the tests marked ``@pytest.mark.long``."""
    tests = os.path.join(ROOT, "tests")
    for item in items:
        parts = os.path.relpath(str(item.path), tests).split(os.sep)
        if parts[0] in LONG_FOLDERS or parts[-1] in LONG_FILES:
            item.add_marker(pytest.mark.long)


def radial_psd(img: np.ndarray, extent: float, nbins: int | None = None):
    """Radially averaged power spectrum of a 2D image: (freqs cycles/unit, power)."""
    n = img.shape[0]
    F = np.abs(np.fft.fft2(img - img.mean())) ** 2
    f = np.fft.fftfreq(n, d=extent / n)
    R = np.hypot(*np.meshgrid(f, f, indexing="ij"))
    df = 1.0 / extent
    b = np.rint(R / df).astype(int)
    nb = nbins or n // 2
    tot = np.bincount(b.ravel(), F.ravel(), minlength=nb + 1)[: nb + 1]
    cnt = np.bincount(b.ravel(), minlength=nb + 1)[: nb + 1]
    return np.arange(nb + 1) * df, tot / np.maximum(cnt, 1), F, R, f


@pytest.fixture
def psd():
    return radial_psd


def load_bench_script(name: str):
    """``bench.<name>``, the checkout's ``bench`` package imported without putting the checkout on ``sys.path``."""
    import importlib
    import importlib.util

    here = os.path.join(ROOT, "bench")
    if os.path.dirname(getattr(sys.modules.get("bench"), "__file__", "") or "") != here:
        spec = importlib.util.spec_from_file_location("bench", os.path.join(here, "__init__.py"),
                                                      submodule_search_locations=[here])
        sys.modules["bench"] = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(sys.modules["bench"])
    return importlib.import_module("bench." + name)


@pytest.fixture
def bench_script():
    """A loader of bench scripts: ``bench_script("solid_synthesis")`` is ``bench.solid_synthesis``."""
    return load_bench_script


class Recorder:
    """A UILayout stand-in that records what a panel's draw() asks for: (call, property, text) tuples."""

    def __init__(self, log):
        self.log = log
        self.enabled = True

    def __getattr__(self, name):
        def call(*args, **kw):
            self.log.append((name, args[1] if len(args) > 1 else None, kw.get("text")))
            return Recorder(self.log) if name in ("row", "column", "box") else type("Op", (), {})()
        return call


def _has_openvdb() -> bool:
    try:
        from omninoise.export.vdb import openvdb_module

        openvdb_module()
        return True
    except (RuntimeError, ImportError):
        return False


#: .vdb steps need Blender's OpenVDB module, which the bpy 4.2 and 4.3 wheels lack (Blender itself ships pyopenvdb)
needs_openvdb = pytest.mark.skipif(not _has_openvdb(), reason="this bpy build has no OpenVDB Python module "
                                                             "(the bpy 4.2 and 4.3 wheels; Blender ships pyopenvdb)")
