"""Build the extension with Blender's builder, install it into temporary user folders, enable/disable."""
import json
import os
import shutil
import subprocess
import sys

import pytest

pytest.importorskip("bpy")
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


#: the test zip carries this machine's C kernel wheel (build_dist.py --kernel) where it can be built
KERNEL = sys.platform.startswith("linux") and bool(shutil.which(os.environ.get("CC") or "cc"))


@pytest.fixture(scope="module")
def built_zip(tmp_path_factory):
    # staged and built in a folder of this run: the runs on several Blenders at once share no build/ folder
    out, work = tmp_path_factory.mktemp("dist"), tmp_path_factory.mktemp("build")
    r = subprocess.run([sys.executable, os.path.join(ROOT, "tools", "build_dist.py"), "--no-wheels", "--out",
                        str(out), "--work", str(work)] + (["--kernel"] if KERNEL else []), capture_output=True,
                       text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    zips = [f for f in os.listdir(out) if f.endswith(".zip")]
    assert len(zips) == 1 and "valid" in r.stdout
    return os.path.join(out, zips[0])


def test_zip_holds_runtime_files_only(built_zip):
    import zipfile
    names = zipfile.ZipFile(built_zip).namelist()
    assert "blender_manifest.toml" in names and "blender_addon/wave_nodes.py" in names
    assert "LICENSE" in names and "api.py" in names        # the licence travels; omninoise.wave() works in Blender
    assert ("THIRD_PARTY_LICENSES.md" in names) == any(n.startswith("wheels/") for n in names)
    assert "backend/wavenoise/wave.py" in names and "export/images.py" in names
    assert "blender_addon/solid_ui.py" in names and "backend/solid/model.py" in names
    assert "models/solid/gravel_3d/decoder.onnx" in names and "models/solid/gravel_3d/solid.json" in names
    assert not [n for n in names if n.startswith(("tests/", "bench/", "demo/", "tools/", "training/"))
                or "__pycache__" in n or "_omni_rows" in n]  # the kernel comes as a wheel, not this machine's build
    assert bool([n for n in names if n.startswith("wheels/omninoise_rows-")]) == KERNEL


def test_runtime_never_imports_torch():
    """What the add-on imports (backend, bakes, jobs, export) stays free of torch."""
    code = ("import sys, omninoise.backend, omninoise.backend.bake, omninoise.backend.jobs, omninoise.backend.sources, omninoise.export, omninoise.export.vdb, "
            "omninoise.backend.neural.model, omninoise.backend.neural.conditioning, omninoise.backend.neural.generate, omninoise.backend.neural.sampler, "
            "omninoise.backend.solid.model, omninoise.backend.solid.bake, omninoise.backend.solid.surface, omninoise.backend.solid.value_noise, omninoise.cli.main; "
            "print('torch' in sys.modules)")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert r.returncode == 0 and r.stdout.strip() == "False", r.stderr


def test_install_enable_disable_in_temporary_user_folders(built_zip, tmp_path):
    env = dict(os.environ)
    for key in ("CONFIG", "SCRIPTS", "EXTENSIONS", "DATAFILES"):
        env[f"BLENDER_USER_{key}"] = str(tmp_path / key.lower())
    script = os.path.join(ROOT, "tests", "blender_scripts", "install_extension.py")
    r = subprocess.run([sys.executable, script, built_zip], capture_output=True, text=True, env=env,
                       cwd=str(tmp_path), timeout=600)
    line = [ln for ln in r.stdout.splitlines() if ln.startswith("RESULT ")]
    assert r.returncode == 0 and line, r.stdout[-3000:] + r.stderr[-3000:]
    out = json.loads(line[0][7:])
    assert out["install"] == ["FINISHED"] and out["enabled"] and out["props"] and out["menu_op"]
    assert out["directions_default"] == 16 and out["directions_after_edit"] == 5
    assert "at most 32" in out["error"] and out["directions_after_error"] == 5
    # the Automatic form follows the scene's shading system (OSL script / Blender's nodes)
    want = ("osl", 1) if out["osl_available"] else ("nodes", 0)
    assert (out["form_osl_scene"], out["scripts_osl_scene"]) == want
    assert (out["form_svm_scene"], out["groups_svm_scene"]) == ("nodes", 5)
    assert out["cache_dir"].startswith(str(tmp_path))  # the user folder, not the extension's own
    assert out["api_wave_shape"] == [8, 8]
    # the installed extension found the kernel in the wheel Blender installed, and it computes the engine's noise
    assert out["kernel_available"] == KERNEL
    if KERNEL:
        assert out["kernel_path"].startswith(str(tmp_path)) and "omninoise_rows" in out["kernel_path"]
    # numba's row kernel is bit-equal to the C one (within 2e-6 in the block walk); numpy's point path
    # computes coordinates by matmul, not along rows, and stays within test_ckernel's 1e-3 bound
    assert out["kernel_vs_other"] < (1e-5 if out["other_path"] == "numba" else 1e-3), out["other_path"]
    assert out["kernel_signal"] > 0.1
    # without numba (Blender's own Python) points run the wheel's point kernel, and the cells its cell kernel
    assert out["points_compiled"] == KERNEL and out["points_vs_numpy"] < 1e-5
    assert out["cells_same"]
    assert not out["disabled_props"] and out["reenabled_props"]
    if not out["openvdb"]:  # the bpy 4.2 wheel: a one-line message instead of a volume
        assert out["bake"] == ["ERROR"] and "OpenVDB Python module" in out["bake_error"]
        assert len(out["bake_error"].strip().splitlines()) == 1
    else:
        assert out["bake"] == ["FINISHED"] and out["bake_grids"] == ["color", "density"]
        assert out["bake_file"].startswith(str(tmp_path)) and out["bake_file"].endswith("Installed.vdb")
    assert not out["disabled_bake_props"]
    assert os.path.isdir(tmp_path / "extensions" / "user_default" / "omninoise")
    # disabling with a task running leaves nothing running; enable/disable x 3 more is clean
    assert out["task_running_before_disable"] and out["task_timer_before_disable"]
    assert not out["task_thread_alive_after_disable"]
    assert not out["task_timer_after_disable"] and out["task_status_after_disable"] == "cancelled"
    assert out["cycles"] == [[True, False]] * 3 and out["threads_left"] == []
