"""The OSL form of the Wave Noise node against the engine, in Cycles with Open Shading Language.

Same cases and same instrument as tests/blender/test_wave_node.py's Cycles bake
(the shading positions are baked too), with the scene's shading system set to OSL.
"""
import numpy as np
import pytest

bpy = pytest.importorskip("bpy")

from omninoise.backend import Spectrum, WaveSettings  # noqa: E402
from omninoise.backend.errors import SettingError  # noqa: E402
from omninoise.backend.wavenoise.wave import select_output  # noqa: E402
from omninoise.blender_addon.wave_nodes import IMPLEMENTATION_KEY, build_wave_group, tree_implementation  # noqa: E402
from omninoise.blender_addon.wave_osl import osl_available, osl_source  # noqa: E402
from test_wave_node import CASES, _bake, _engine, _plane_material  # noqa: E402

pytestmark = pytest.mark.skipif(not osl_available(), reason="this bpy has no OSL")


def _osl_scene():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.shading_system = True
    scene.cycles.samples = 1
    return scene


@pytest.mark.parametrize("case", ["2d", "3d", "4d", "3d+t", "2d+t", "lobes", "axes", "crystal"])
def test_osl_bake_equals_engine(case):
    s, kw = CASES[case]
    _osl_scene()
    grp = build_wave_group(s, "ShaderNodeTree", implementation="osl")
    assert tree_implementation(grp) == "osl" and grp[IMPLEMENTATION_KEY] == "osl"
    assert [n.bl_idname for n in grp.nodes].count("ShaderNodeScript") == 1 and len(grp.nodes) <= 6
    ob, nt, tc, comb, em = _plane_material(grp, kw)
    vals = _bake(ob, nt, 48)
    nt.links.new(tc.outputs["Object"], em.inputs["Color"])
    pos = _bake(ob, nt, 48)[..., :3].reshape(-1, 3)
    assert np.abs(pos[:, :2]).max() > 0.9
    z = _engine(s, np.ascontiguousarray(pos), **kw)
    for c, o in enumerate(("real", "imag", "modulus")):
        ref = select_output(z, o)
        d = np.abs(vals[..., c].ravel() - ref)
        assert ref.std() > 0.05, o
        assert np.percentile(d, 99) < 5e-5 and d.max() < 2e-4, (case, o, d.max())


def test_osl_form_without_osl_renders_nothing_but_nodes_form_does():
    """What the form choice is for: Cycles' SVM ignores Script nodes, so only the node form renders there."""
    s, kw = CASES["3d"]
    scene = _osl_scene()
    scene.cycles.shading_system = False
    grp = build_wave_group(s, "ShaderNodeTree", implementation="osl")
    ob, nt, *_ = _plane_material(grp, kw)
    assert np.abs(_bake(ob, nt, 8)[..., 0]).max() == 0.0
    build_wave_group(s, tree=grp, implementation="nodes")
    assert tree_implementation(grp) == "nodes"
    assert _bake(ob, nt, 8)[..., 0].std() > 0.05


def test_osl_many_directions_and_saved_file(tmp_path):
    """No SVM stack limit in OSL; the script and its bytecode travel in the .blend."""
    s = WaveSettings(dim=3, spectrum=Spectrum("bandpass", 2, 6), directions=64, seed=5)
    _osl_scene()
    grp = build_wave_group(s, "ShaderNodeTree", implementation="osl")
    ob, nt, *_ = _plane_material(grp, {})
    before = _bake(ob, nt, 16)[..., 0]
    assert before.std() > 0.05
    path = str(tmp_path / "osl.blend")
    bpy.ops.wm.save_as_mainfile(filepath=path)
    bpy.ops.wm.open_mainfile(filepath=path)
    ob = bpy.data.objects["plane"]
    nt = ob.data.materials[0].node_tree
    assert np.array_equal(_bake(ob, nt, 16)[..., 0], before)


def test_osl_refused_where_it_cannot_work():
    s, _ = CASES["3d"]
    with pytest.raises(SettingError, match="shader trees"):
        build_wave_group(s, "GeometryNodeTree", implementation="osl")
    with pytest.raises(SettingError, match="choose nodes or osl"):
        build_wave_group(s, "ShaderNodeTree", implementation="svm")


def test_osl_source_is_deterministic_and_carries_the_table():
    from omninoise.backend import compile_noise

    noise = compile_noise(CASES["2d"][0])
    a, b = osl_source(noise), osl_source(noise)
    assert a == b and f"#define TN {noise.table.size}" in a
    assert ("%.9g" % float(noise.table.values.real[0, 7])) in a


def test_automatic_form_renders_in_both_shading_systems(tmp_path):
    """An Automatic group switched by the render itself (render_pre): the first OSL render and the
    first SVM render after a switch both show the noise, never the black of the wrong form."""
    from omninoise import blender_addon
    from omninoise.blender_addon import wave_ui

    bpy.ops.wm.read_factory_settings(use_empty=True)
    blender_addon.register()
    try:
        scene = bpy.context.scene
        scene.render.engine = "CYCLES"
        scene.cycles.device = "CPU"
        scene.cycles.samples = 1
        scene.render.resolution_x = scene.render.resolution_y = 16
        scene.render.image_settings.file_format = "OPEN_EXR"
        tree = wave_ui.new_wave_node_tree("Wave", "ShaderNodeTree")
        tree.omninoise_wave.directions = 4
        ob, nt, *_ = _plane_material(tree, {})
        cam = bpy.data.objects.new("cam", bpy.data.cameras.new("cam"))
        cam.data.type, cam.data.ortho_scale, cam.location = "ORTHO", 2.0, (0.0, 0.0, 3.0)
        scene.collection.objects.link(cam)
        scene.camera = cam
        forms = []
        for osl in (True, False, True):
            scene.cycles.shading_system = osl
            scene.render.filepath = str(tmp_path / f"r{len(forms)}.exr")
            bpy.ops.render.render(write_still=True)
            forms.append(tree.get(IMPLEMENTATION_KEY))
            img = bpy.data.images.load(scene.render.filepath)
            px = np.array(img.pixels[:], np.float32).reshape(16, 16, 4)
            bpy.data.images.remove(img)
            assert px[..., :3].std() > 0.02, (osl, forms)
        assert forms == ["osl", "nodes", "osl"]
    finally:
        blender_addon.unregister()


def test_rebuilds_reuse_the_compiled_bytecode(monkeypatch):
    """Switching an Automatic node between forms rebuilds the script: the same source compiles once."""
    from omninoise.blender_addon import wave_osl

    s, _ = CASES["3d"]
    _osl_scene()
    calls = []
    real = wave_osl._compile
    monkeypatch.setattr(wave_osl, "_compile", lambda code: calls.append(code) or real(code))
    monkeypatch.setattr(wave_osl, "_BYTECODE", {})
    grp = build_wave_group(s, "ShaderNodeTree", implementation="osl")
    first = next(n for n in grp.nodes if n.bl_idname == "ShaderNodeScript").bytecode
    build_wave_group(s, tree=grp, implementation="nodes")
    build_wave_group(s, tree=grp, implementation="osl")
    assert len(calls) == 1
    assert next(n for n in grp.nodes if n.bl_idname == "ShaderNodeScript").bytecode == first
    import dataclasses

    build_wave_group(dataclasses.replace(s, seed=s.seed + 1), tree=grp, implementation="osl")
    assert len(calls) == 2  # another noise: another source, compiled
