"""The shipped asset library: Blender lists it after one click, every asset appends with its preview and catalog,
and renders in Cycles and in EEVEE."""
import ctypes.util
import json
import os
import subprocess
import sys

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")

from omninoise import blender_addon  # noqa: E402
from omninoise.blender_addon import preferences  # noqa: E402
from omninoise.export.images import read_image  # noqa: E402
from asset_scene import render_assets  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BLEND = os.path.join(preferences.ASSETS, "omninoise_assets.blend")
MATERIALS = ["Wave Noise Marble", "Veined Stone", "Cellular Tiles", "Neural Noise Blend", "Solid Texture Brick",
             "Procedural Brick Wall", "Procedural Tile Grid", "Procedural Wood Grain"]
GROUPS = ["Wave Noise", "Wave Cellular"]
OBJECTS = ["Cloud Volume"]
REQUIRED = os.environ.get("OMNINOISE_REQUIRE_EEVEE") == "1"


@pytest.fixture(scope="module", autouse=True)
def addon():
    blender_addon.register()
    yield
    blender_addon.unregister()


def test_one_click_lists_the_library_and_another_takes_it_out():
    libs = bpy.context.preferences.filepaths.asset_libraries
    before = len(libs)
    assert bpy.ops.omninoise.asset_library_add() == {"FINISHED"}
    assert bpy.ops.omninoise.asset_library_add() == {"FINISHED"}       # a second click adds nothing
    lib = preferences.asset_library()
    assert len(libs) == before + 1 and lib.name == "OmniNoise" and lib.import_method.startswith("APPEND")
    assert os.path.samefile(bpy.path.abspath(lib.path), preferences.ASSETS)
    assert bpy.ops.omninoise.asset_library_remove() == {"FINISHED"}
    assert preferences.asset_library() is None and len(libs) == before


def test_every_asset_appends_with_its_preview_description_and_catalog():
    with bpy.data.libraries.load(BLEND, assets_only=True) as (src, dst):
        assert sorted(src.materials) == sorted(MATERIALS) and sorted(src.node_groups) == sorted(GROUPS)
        assert sorted(src.objects) == sorted(OBJECTS)
        dst.materials, dst.node_groups, dst.objects = list(src.materials), list(src.node_groups), list(src.objects)
    with open(os.path.join(preferences.ASSETS, "blender_assets.cats.txt"), encoding="utf-8") as fh:
        catalogs = {line.split(":")[0]: line.split(":")[1] for line in fh if line[:1].isalnum() and ":" in line}
    cloud = dst.objects[0]
    # Blender reads a volume's grids from its file only: the OpenVDB file ships beside the .blend
    assert cloud.type == "VOLUME" and cloud.data.packed_file is None
    assert os.path.samefile(bpy.path.abspath(cloud.data.filepath), os.path.join(preferences.ASSETS, "cloud.vdb"))
    cloud.data.grids.load()
    assert {"density", "color"} <= {g.name for g in cloud.data.grids}
    for idb in list(dst.materials) + list(dst.node_groups) + list(dst.objects):
        d = idb.asset_data
        assert d is not None and d.description and d.catalog_id in catalogs, idb.name
        assert catalogs[d.catalog_id].startswith("OmniNoise/"), idb.name
        assert idb.preview is not None and tuple(idb.preview.image_size) == (256, 256), idb.name
        px = np.array(idb.preview.image_pixels_float[:]).reshape(256, 256, 4)
        assert px[..., :3].std() > 0.02, idb.name                   # a rendered picture, not a blank
    marble = bpy.data.materials["Wave Noise Marble"]
    tree = next(n.node_tree for n in marble.node_tree.nodes if n.type == "GROUP")
    assert tree.omninoise_wave.is_wave and not tree.omninoise_wave.error   # the Wave Noise panel edits it
    # the procedural solids draw their fitted field live: a running bond, a stack bond of tiles, straight grain
    from omninoise.blender_addon.procedural_nodes import FIELD_KEY

    for name, family, offset in (("Procedural Brick Wall", "bonds", 0.5), ("Procedural Tile Grid", "bonds", 0.0),
                                 ("Procedural Wood Grain", "layers", None)):
        group = next(n.node_tree for n in bpy.data.materials[name].node_tree.nodes if n.type == "GROUP")
        assert json.loads(group[FIELD_KEY])["family"] == family, name
        if offset is not None:
            assert group.interface.items_tree["Offset"].default_value == pytest.approx(offset, abs=1e-6), name
    for idb in list(dst.objects):
        bpy.data.objects.remove(idb)
    for idb in list(dst.materials) + list(dst.node_groups):
        (bpy.data.materials if isinstance(idb, bpy.types.Material) else bpy.data.node_groups).remove(idb)


def _check_renders(folder, engine: str) -> None:
    for name in MATERIALS + GROUPS + OBJECTS:
        img = read_image(os.path.join(folder, name + ".png"))
        assert np.all(np.isfinite(img)) and img.std() > 0.01, (engine, name, float(img.std()))


def test_every_asset_renders_in_cycles(tmp_path):
    times = render_assets(BLEND, str(tmp_path), 32, "CYCLES")
    assert sorted(times) == sorted(MATERIALS + GROUPS + OBJECTS)
    _check_renders(tmp_path, "Cycles")


def test_every_asset_renders_in_eevee(tmp_path):
    """EEVEE needs an OpenGL 4.3 context (Mesa's llvmpipe on a machine without a GPU); the renders run in a fresh
    Python (tests/blender_scripts/eevee_assets.py)."""
    if ctypes.util.find_library("EGL") is None:
        if REQUIRED:
            pytest.fail("EEVEE required (OMNINOISE_REQUIRE_EEVEE=1) but there is no libEGL")
        pytest.skip("no libEGL (install Mesa: libegl-mesa0 libgl1-mesa-dri)")
    script = os.path.join(ROOT, "tests", "blender_scripts", "eevee_assets.py")
    r = subprocess.run([sys.executable, script, BLEND, str(tmp_path), "32"], capture_output=True, text=True,
                       cwd=ROOT, timeout=900)
    lines = [ln for ln in r.stdout.splitlines() if ln.startswith("{")]
    if r.returncode != 0 or not lines:
        tail = " | ".join((r.stderr or r.stdout).strip().splitlines()[-3:])
        if REQUIRED:
            pytest.fail(f"EEVEE did not render (exit {r.returncode}): {tail}")
        pytest.skip(f"EEVEE did not render (exit {r.returncode}): {tail}")
    assert sorted(json.loads(lines[-1])) == sorted(MATERIALS + GROUPS + OBJECTS)
    _check_renders(tmp_path, "EEVEE")
