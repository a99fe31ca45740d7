"""Blender's conventions, on every supported Blender: undo, menus (F3), tooltips, sub-panels, presets."""
import importlib
import os
import re
import sys

import pytest

bpy = pytest.importorskip("bpy")

from omninoise import blender_addon  # noqa: E402
from conftest import Recorder, _has_openvdb  # noqa: E402
from omninoise.blender_addon import compat, menus, neural_ui, presets, solid_ui, wave_ui  # noqa: E402
from omninoise.backend.transfer import PRESETS, preset  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
UI_MODULES = ("preferences", "presets", "wave_ui", "bake_ui", "neural_ui", "solid_ui", "menus")
#: words the interface leaves to the docs (citations, equation numbers) and spellings it uses as Blender does
NOT_IN_THE_UI = re.compile(r"\bEq\.|\bFig\.|\bAlg\.|et al\.|Guehl|Henzler|Maesumi|\bcolour|\bColour|\[\[")


@pytest.fixture(scope="module", autouse=True)
def addon(tmp_path_factory):
    old = os.environ.get("BLENDER_USER_SCRIPTS")
    os.environ["BLENDER_USER_SCRIPTS"] = str(tmp_path_factory.mktemp("user_scripts"))  # user presets go here
    blender_addon.register()
    yield
    blender_addon.unregister()
    if old is None:
        del os.environ["BLENDER_USER_SCRIPTS"]
    else:
        os.environ["BLENDER_USER_SCRIPTS"] = old


@pytest.fixture
def scene(tmp_path):
    bpy.ops.wm.read_homefile(use_empty=True)
    sc = bpy.context.scene
    b = sc.omninoise_bake
    b.folder = sc.omninoise_neural.folder = sc.omninoise_solid.folder = str(tmp_path) + os.sep
    b.bounds_mode = "CUSTOM"
    b.volume_resolution, b.image_resolution = (8, 8, 8), (16, 16)
    n = sc.omninoise_neural
    n.size, n.steps, n.frame_start, n.frame_end = 16, 2, 1, 2
    bpy.ops.omninoise.swatch_add()
    s = sc.omninoise_solid
    s.texture, s.size, s.margin, s.voxels = "single:gravel_3d", 16, 1, 6
    bpy.ops.mesh.primitive_cube_add()      # UVs, a mesh, the active object
    return sc


def _operators():
    """(class, registered operator) of every operator the extension registers."""
    out = []
    for name in UI_MODULES:
        for cls in importlib.import_module(f"omninoise.blender_addon.{name}").classes:
            if issubclass(cls, bpy.types.Operator):
                mod, op = cls.bl_idname.split(".")
                out.append((cls, getattr(getattr(bpy.ops, mod), op)))
    return out


# -- tooltips ---------------------------------------------------------------------------------------------

def test_every_property_and_operator_has_a_plain_words_tooltip():
    checked, bad = 0, []
    for name in UI_MODULES:
        for cls in importlib.import_module(f"omninoise.blender_addon.{name}").classes:
            if issubclass(cls, bpy.types.Operator):
                mod, op = cls.bl_idname.split(".")
                rna = getattr(getattr(bpy.ops, mod), op).get_rna_type()
                texts = [(cls.bl_idname, rna.description, rna.name)]
                props = [p for p in rna.properties if p.identifier != "rna_type" and not p.is_hidden]
            elif issubclass(cls, (bpy.types.PropertyGroup, bpy.types.AddonPreferences)):
                texts = []
                props = [p for p in cls.bl_rna.properties
                         if p.identifier in getattr(cls, "__annotations__", {}) and not p.is_hidden]
            else:
                continue
            for p in props:
                texts.append((f"{cls.__name__}.{p.identifier}", p.description, p.name))
                for item in getattr(p, "enum_items", ()):
                    texts.append((f"{cls.__name__}.{p.identifier}:{item.identifier}", item.description, item.name))
            for where, description, label in texts:
                checked += 1
                if not description.strip() or NOT_IN_THE_UI.search(description + " " + label):
                    bad.append((where, label, description))
    assert checked > 150 and not bad, bad


def test_a_setting_in_scene_units_shows_blenders_length_unit():
    """A distance or a point in the scene is typed and shown in the scene's units (metres, feet), as Blender's own
    are: a property whose tooltip says "scene units" has a length subtype."""
    found = {}
    for name in UI_MODULES:
        for cls in importlib.import_module(f"omninoise.blender_addon.{name}").classes:
            if issubclass(cls, bpy.types.PropertyGroup):
                for p in cls.bl_rna.properties:
                    if p.type == "FLOAT" and "scene units" in p.description:
                        found[f"{cls.__name__}.{p.identifier}"] = p.subtype
    assert len(found) >= 3 and set(found.values()) <= {"DISTANCE", "XYZ_LENGTH", "TRANSLATION"}, found


# -- menus and F3 -----------------------------------------------------------------------------------------

class _MenuLayout:
    def __init__(self, log):
        self.log, self.operator_context = log, None

    def operator(self, idname, **kw):
        self.log.append(("operator", idname))
        return type("Op", (), {})()

    def menu(self, idname, **kw):
        self.log.append(("menu", idname))

    def separator(self, **kw):
        pass


def _drawn_in_menus() -> set:
    """Operators the extension's entries in Blender's menus draw, submenus followed."""
    log = []
    for name in list(menus.APPENDED) + list(wave_ui.MENUS):
        menu = getattr(bpy.types, name, None)
        if menu is None:
            continue
        for draw in menu._dyn_ui_initialize():
            if draw.__module__.startswith("omninoise"):
                draw(type("Self", (), {"layout": _MenuLayout(log)})(), bpy.context)
    for kind, idname in list(log):
        if kind == "menu":
            getattr(bpy.types, idname).draw(type("Self", (), {"layout": _MenuLayout(log)})(), bpy.context)
    return {idname for kind, idname in log if kind == "operator"}


def test_every_operator_but_the_ui_ones_is_in_a_blender_menu():
    """F3 searches the menus: each operator an artist runs is drawn in one; the rest say INTERNAL."""
    drawn = _drawn_in_menus()
    for cls, op in _operators():
        internal = "INTERNAL" in getattr(cls, "bl_options", set())
        assert internal or cls.bl_idname in drawn, f"{cls.bl_idname} ({cls.bl_label}) is in no menu"
    assert {"omninoise.bake_volume", "omninoise.neural_bake", "omninoise.solid_bake", "omninoise.run_job",
            "node.omninoise_add_wave_noise"} <= drawn


def _disabled() -> dict:
    """{bl_idname: the error a script calling it gets} of every operator of the extension whose poll fails now."""
    out = {}
    for cls, op in _operators():
        if not op.poll():
            with pytest.raises(RuntimeError) as err:
                op()
            out[cls.bl_idname] = str(err.value)
    return out


def test_a_disabled_command_says_why(scene):
    """Blender shows an operator's poll message as the disabled button's tooltip, and a script calling it gets that
    message: no command of the extension is disabled without its reason, and while a task runs, every command that
    starts work names the task."""
    import threading

    from omninoise.blender_addon import tasks

    idle = _disabled()
    assert "OmniNoise is not running a bake, preview or fit" in idle["omninoise.cancel"]
    assert "open one in a node editor" in idle["node.omninoise_add_wave_noise"]
    gate = threading.Event()
    task = tasks.start(tasks.Task("Solid preview", lambda progress, cancel: gate.wait(60)))
    try:
        busy = _disabled()
    finally:
        gate.set()
        tasks.wait(task)
    starts = sorted(set(busy) - set(idle))
    assert "omninoise.cancel" not in busy and {"omninoise.solid_preview", "omninoise.neural_bake",
                                              "omninoise.bake_volume", "omninoise.run_job"} <= set(starts)
    assert all("OmniNoise is busy with Solid preview" in busy[name] for name in starts), busy
    assert not [m for m in {**idle, **busy}.values() if "context is incorrect" in m]
    scene.omninoise_neural.swatches.clear()
    assert "no swatch to remove" in _disabled()["omninoise.swatch_remove"]


def test_opening_another_file_cancels_a_running_task_and_frees_the_commands(scene):
    """File > New or Open while a bake runs: Blender drops the task's timer with the file, so the task was never
    finished and every command stayed disabled ("busy with ...") until Blender restarted. The task is cancelled,
    its worker stopped, and its callbacks, which would fill the closed file's data, do not run."""
    import time

    from omninoise.blender_addon import tasks

    def work(progress, cancel):
        while not cancel():
            time.sleep(0.02)

    done = []
    task = tasks.start(tasks.Task("Solid preview", work, done.append))
    assert not bpy.ops.omninoise.solid_preview.poll()
    bpy.ops.wm.read_homefile(use_empty=True)
    assert tasks.current() is None and task.status == "cancelled" and not done
    assert not task._thread.is_alive() and not bpy.app.timers.is_registered(task.timer)
    assert bpy.ops.omninoise.solid_preview.poll()


def test_operators_that_change_data_record_an_undo_step():
    changing = {"omninoise.bake_volume", "omninoise.bake_image", "omninoise.neural_bake",
                "omninoise.neural_bake_sequence", "omninoise.neural_fit", "omninoise.swatch_add",
                "omninoise.swatch_remove", "omninoise.blend_map_new", "omninoise.swatch_thumbnails",
                "omninoise.solid_preview", "omninoise.solid_tileable", "omninoise.solid_tile_material",
                "omninoise.solid_bake", "omninoise.init_ramp", "omninoise.set_transfer",
                "node.omninoise_add_wave_noise", "node.omninoise_add_wave_cellular"}
    flags = {cls.bl_idname: getattr(cls, "bl_options", set()) for cls, _ in _operators()}
    assert changing <= set(flags)
    for idname in changing:
        assert "UNDO" in flags[idname], idname
    assert "UNDO" not in flags["omninoise.run_job"] and "INTERNAL" in flags["omninoise.cancel"]


# -- undo -------------------------------------------------------------------------------------------------

def _undo_steps() -> list:
    """(index, name) of the undo stack, read from print_undo_steps (it writes to the C stdout)."""
    sys.stdout.flush()
    r, w = os.pipe()
    saved = os.dup(1)
    os.dup2(w, 1)
    try:
        bpy.context.window_manager.print_undo_steps()
    finally:
        os.dup2(saved, 1)
        os.close(w)
        os.close(saved)
    text = os.read(r, 1 << 20).decode(errors="replace")
    os.close(r)
    return [(int(i), n) for i, n in re.findall(r"^\[.{4}\]\s+(\d+) \{[^}]*\} type='[^']*', name='(.*)'$", text, re.M)]


def _counts() -> dict:
    d = bpy.data
    return dict(images=len(d.images), objects=len(d.objects), materials=len(d.materials),
                node_groups=len(d.node_groups), volumes=len(d.volumes),
                color_attributes=sum(len(m.color_attributes) for m in d.meshes),
                swatches=len(bpy.context.scene.omninoise_neural.swatches))


UNDONE = [("omninoise", "bake_volume", {}), ("omninoise", "bake_image", {}), ("omninoise", "neural_bake", {}),
          ("omninoise", "neural_bake_sequence", {}), ("omninoise", "blend_map_new", {}),
          ("omninoise", "swatch_add", {}), ("omninoise", "swatch_thumbnails", {}), ("omninoise", "solid_preview", {}),
          ("omninoise", "solid_bake", {"target": "UV_IMAGE"}), ("omninoise", "solid_bake", {"target": "COLOR_ATTRIBUTE"}),
          ("omninoise", "solid_bake", {"target": "VOLUME"})]


@pytest.mark.parametrize("module, name, settings", UNDONE, ids=[f"{n}{'-' + s['target'] if s else ''}"
                                                                for _, n, s in UNDONE])
def test_undo_after_an_operator_restores_the_file_as_it_was(scene, module, name, settings):
    """One undo step per run, named as the operator; undoing it removes exactly what it added."""
    for k, v in settings.items():
        setattr(scene.omninoise_solid, k, v)
    if (name == "bake_volume" or settings.get("target") == "VOLUME") and not _has_openvdb():
        pytest.skip("this bpy build has no OpenVDB Python module")
    bpy.ops.ed.undo_push(message="before")
    before = _counts()
    steps = _undo_steps()
    op = getattr(getattr(bpy.ops, module), name)
    assert op("EXEC_DEFAULT", True) == {"FINISHED"}
    after = _counts()
    assert after != before, (name, after)
    new = _undo_steps()
    assert len(new) == len(steps) + 1 and new[-1][1] == op.get_rna_type().name, new[-3:]
    bpy.ops.ed.undo_history(item=[i for i, n in new if n == "before"][-1])
    assert _counts() == before, name


# -- panels -----------------------------------------------------------------------------------------------

def test_neural_and_solid_panels_are_split_into_sub_panels_with_property_split(scene):
    for parent, module in (("OMNINOISE_PT_neural_image", neural_ui), ("OMNINOISE_PT_solid", solid_ui)):
        children = [c for c in module.classes if getattr(c, "bl_parent_id", "") == parent]
        assert len(children) >= 3 and all(hasattr(bpy.types, c.__name__) for c in children), parent
        for c in children:
            rec = Recorder([])
            section = next(s for s in module.SECTIONS if c.__name__.endswith("_" + s[0]))
            section[2](module._split(rec), scene.omninoise_neural if module is neural_ui else scene.omninoise_solid)
            assert rec.use_property_split is True, c.__name__
        closed = [c for c in children if "DEFAULT_CLOSED" in getattr(c, "bl_options", set())]
        assert closed, parent
    log = []
    neural_ui.draw_neural(Recorder(log), bpy.context)
    main = {a for n, a, t in log if n == "prop"}
    assert {"noise", "mode", "size", "seed"} <= main and not {"steps", "depth", "latent", "fit_image"} & main


# -- presets ----------------------------------------------------------------------------------------------

def _shipped(kind: str) -> list:
    folder = os.path.join(presets.ROOT, "presets", "omninoise", kind)
    return sorted(os.path.join(folder, f) for f in os.listdir(folder) if f.endswith(".py"))


def test_the_shipped_presets_are_those_the_tool_writes():
    import subprocess

    r = subprocess.run([sys.executable, "-m", "tools.make_presets", "--check"], cwd=ROOT, capture_output=True,
                       text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    assert len(_shipped("transfer")) == len(PRESETS) and len(_shipped("wave")) >= 6 and len(_shipped("neural")) > 20
    assert len(_shipped("solid")) >= 6


def test_every_shipped_preset_loads_through_blenders_preset_menu(scene):
    b, n = scene.omninoise_bake, scene.omninoise_neural
    found = bpy.utils.preset_paths("omninoise/wave")
    if compat.reads_extension_presets():              # the shipped folder itself, read-only
        assert presets.ROOT in [os.path.dirname(os.path.dirname(os.path.dirname(p))) for p in found]
    else:                                              # Blender 4.2.0: copies in the user's presets folder
        user = bpy.utils.user_resource("SCRIPTS", path=os.path.join("presets", "omninoise"))
        for kind in presets.SUBDIRS:
            names = sorted(os.path.basename(p) for p in _shipped(kind))
            assert names and set(names) <= set(os.listdir(os.path.join(user, kind))), kind
        assert os.path.join(user, "wave") in found
    for path in _shipped("transfer"):
        assert bpy.ops.script.execute_preset(filepath=path, menu_idname="OMNINOISE_PT_transfer_presets") == {"FINISHED"}
        tf = preset(os.path.basename(path)[:-3])
        assert (b.range_min, b.range_max) == pytest.approx(tf.range) and b.density_scale == pytest.approx(tf.density_scale)
    tree = wave_ui.new_wave_node_tree("W", "ShaderNodeTree")
    for target in (tree.omninoise_wave, b.wave):
        for path in _shipped("wave"):
            with bpy.context.temp_override(omninoise_wave=target):
                assert bpy.ops.script.execute_preset(filepath=path, menu_idname="OMNINOISE_PT_wave_presets") == \
                    {"FINISHED"}
            assert not target.error, (path, target.error)
    # the node group was rebuilt from the last preset: its stored settings are the preset's
    from omninoise.blender_addon.wave_nodes import settings_from_json, tree_settings_json

    assert settings_from_json(tree_settings_json(tree)) == tree.omninoise_wave.to_settings()
    for path in _shipped("neural"):
        assert bpy.ops.script.execute_preset(filepath=path, menu_idname="OMNINOISE_PT_neural_presets") == {"FINISHED"}
        assert len(n.swatches) >= 1 and neural_ui.panel_request(n, 16) is not None, path
    s = scene.omninoise_solid
    for path in _shipped("solid"):
        s.method, s.families = "NEURAL", {"RINGS"}
        assert bpy.ops.script.execute_preset(filepath=path, menu_idname="OMNINOISE_PT_solid_presets") == {"FINISHED"}
        assert s.source == "IMAGE" and s.families, path
    bpy.ops.script.execute_preset(filepath=next(p for p in _shipped("solid") if "brick" in p),
                                  menu_idname="OMNINOISE_PT_solid_presets")
    assert (s.method, set(s.families)) == ("PROCEDURAL", {"BONDS"})


def test_presets_save_and_load(scene):
    """The + of each preset menu writes the settings into the user's presets; loading it brings them back."""
    b, n = scene.omninoise_bake, scene.omninoise_neural
    bpy.ops.omninoise.set_transfer(transfer=__import__("json").dumps(preset("fire").to_dict()))
    b.range_min, b.density_scale = -0.25, 7.5
    assert bpy.ops.omninoise.transfer_preset_add(name="Hot Glow") == {"FINISHED"}
    b.range_min, b.density_scale = 0.0, 1.0
    path = bpy.utils.preset_find("Hot_Glow", "omninoise/transfer")
    assert path and bpy.ops.script.execute_preset(filepath=path, menu_idname="OMNINOISE_PT_transfer_presets") == {"FINISHED"}
    assert (b.range_min, b.density_scale) == pytest.approx((-0.25, 7.5))
    b.wave.fmin, b.wave.waveform, b.wave.seed = 1.25, "crystal", 9
    with bpy.context.temp_override(omninoise_wave=b.wave):
        assert bpy.ops.omninoise.wave_preset_add(name="Shards") == {"FINISHED"}
    b.wave.fmin, b.wave.waveform = 2.0, "gaussian"
    path = bpy.utils.preset_find("Shards", "omninoise/wave")
    with bpy.context.temp_override(omninoise_wave=b.wave):
        bpy.ops.script.execute_preset(filepath=path, menu_idname="OMNINOISE_PT_wave_presets")
    assert (b.wave.fmin, b.wave.waveform, b.wave.seed) == (pytest.approx(1.25), "crystal", 9)  # the seed is not kept
    bpy.ops.omninoise.swatch_add()
    n.swatches[1].noise, n.swatches[1].p0, n.mode = "spots", 7.5, "GRADIENT"
    assert bpy.ops.omninoise.neural_preset_add(name="Two") == {"FINISHED"}
    bpy.ops.omninoise.swatch_remove()
    n.mode = "SINGLE"
    path = bpy.utils.preset_find("Two", "omninoise/neural")
    bpy.ops.script.execute_preset(filepath=path, menu_idname="OMNINOISE_PT_neural_presets")
    assert [s.noise for s in n.swatches][1] == "spots" and n.swatches[1].p0 == pytest.approx(7.5) and n.mode == "GRADIENT"
    assert bpy.ops.omninoise.neural_preset_add(name="Two", remove_name=True) == {"FINISHED"}
    assert not bpy.utils.preset_find("Two", "omninoise/neural")
    s = scene.omninoise_solid
    s.method, s.families, s.periodic, s.seed = "AUTO", {"CELLS", "HERRINGBONE"}, False, 5
    assert bpy.ops.omninoise.solid_preset_add(name="Yard") == {"FINISHED"}
    s.method, s.families, s.periodic, s.seed = "NEURAL", {"RINGS"}, True, 0
    path = bpy.utils.preset_find("Yard", "omninoise/solid")
    bpy.ops.script.execute_preset(filepath=path, menu_idname="OMNINOISE_PT_solid_presets")
    assert (s.method, set(s.families), s.periodic, s.seed) == ("AUTO", {"CELLS", "HERRINGBONE"}, False, 0)
