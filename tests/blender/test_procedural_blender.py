"""The procedural solids' live node group (blender_addon/procedural_nodes.py) against the engine
(backend/solid/procedural), in Geometry Nodes fields and in a Cycles bake, and the Solid Texture panel's
Procedural Solid: its preview and its node group operator."""
import json
import os

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")

from omninoise import blender_addon  # noqa: E402
from omninoise.backend.colour import srgb_to_linear  # noqa: E402
from omninoise.backend.errors import SettingError  # noqa: E402
from omninoise.backend.solid.procedural import fit  # noqa: E402
from omninoise.backend.solid.procedural.field import ProceduralField  # noqa: E402
from omninoise.backend.solid.procedural.ramp import fit_ramp  # noqa: E402
from omninoise.backend.solid.procedural.tint import fit_tint  # noqa: E402
from omninoise.blender_addon.compat import ensure_node_tree  # noqa: E402
from omninoise.blender_addon.field_eval import evaluate_field  # noqa: E402
from omninoise.blender_addon.procedural_nodes import (FIELD_KEY, add_procedural_node,  # noqa: E402
                                                      build_procedural_group, follow_form, noise_trees)
from omninoise.blender_addon.wave_nodes import tree_implementation  # noqa: E402
from omninoise.blender_addon.wave_osl import osl_available  # noqa: E402
from test_wave_node import _bake, _uv_plane  # noqa: E402  (the Cycles EMIT bake and its plane, of the Wave Noise tests)

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
FAMILY_PARAMS = {"rings": dict(spacing=0.13, tilt=0.4, azimuth=1.0, centre_u=0.3, centre_v=-0.5, grain=0.2),
                 "layers": dict(spacing=0.21, tilt=1.2, azimuth=0.3, profile="tri"),
                 "cells": dict(size=0.2, stretch=1.4, jitter=0.9, gap=0.08),
                 "bonds": dict(length=0.4, height=0.13, offset=0.5, joint=0.15),
                 "herringbone": dict(length=0.3, height=0.11, offset=0.5, joint=0.15, pattern="herringbone"),
                 "herringbone45": dict(length=0.5, height=0.16, offset=0.3, joint=0.15, pattern="herringbone45")}
#: the cases drawn with a tint (tint.py): a random photo's, at 2 cycles per unit
TINTED = ("layers", "cells")


def _field(case: str) -> ProceduralField:
    rng = np.random.default_rng(0)
    family = "bonds" if case.startswith("herringbone") else case
    p = dict(FAMILY_PARAMS[case], turbulence=0.3, turb_freq=2.0, detail=0.2, flip=False)
    draft = ProceduralField(family, p, fit_ramp(np.linspace(-1, 2, 8), rng.uniform(0, 1, (16, 3))), seed=3)
    values = draft.values(rng.uniform(-2, 2, (4000, 3)))
    tint = fit_tint(rng.uniform(0, 1, (32, 32, 3)), 2.0, 3) if case in TINTED else None
    return ProceduralField(family, p, fit_ramp(values, rng.uniform(0, 1, (16, 3))), seed=3, tint=tint)


@pytest.mark.parametrize("family", list(FAMILY_PARAMS))
def test_geometry_nodes_field_equals_engine(family):
    f = _field(family)
    grp = build_procedural_group(f, "GeometryNodeTree")
    pts = np.random.default_rng(1).uniform(-1.5, 1.5, (2000, 3)).astype(np.float32)

    def output(name, channel=None):
        def build(tree, pos):
            g = tree.nodes.new("GeometryNodeGroup")
            g.node_tree = grp
            tree.links.new(pos, g.inputs["Vector"])
            if channel is None:
                return g.outputs[name]
            sep = tree.nodes.new("ShaderNodeSeparateXYZ")
            tree.links.new(g.outputs[name], sep.inputs[0])
            return sep.outputs[channel]
        return evaluate_field(pts, build)

    gapped = f.family in ("cells", "bonds")
    try:
        value = output("Value")
        srgb = np.stack([output("sRGB", c) for c in range(3)], 1)
        linear = np.stack([output("Color", c) for c in range(3)], 1)
        gaps = output("Gap Mask") if gapped else None
        assert ("Gap Mask" in grp.interface.items_tree) == gapped
    finally:
        bpy.data.node_groups.remove(grp)
    ref = f.evaluate(pts.astype(np.float64))
    assert np.abs(value - f.values(pts.astype(np.float64))).max() < 1e-4
    if gapped:
        want = f.gaps(pts.astype(np.float64))
        assert np.abs(gaps - want).max() < 1e-4 and 0.05 < want.mean() < 0.95
    assert np.abs(srgb - ref).max() < 1e-3 and np.median(np.abs(srgb - ref)) < 1e-5
    assert np.abs(linear - srgb_to_linear(ref)).max() < 1e-3
    assert ref.std(0).min() > 0.05                      # a pattern, not a constant


def test_the_group_exposes_the_fitted_parameters_and_stores_the_field():
    f = _field("rings")
    grp = build_procedural_group(f)
    try:
        names = [s.name for s in grp.interface.items_tree if s.in_out == "INPUT"]
        assert names == ["Vector", "Scale", "Spacing", "Axis", "Centre", "Grain", "Turbulence",
                         "Turbulence Frequency", "Detail"]
        assert grp.interface.items_tree["Spacing"].default_value == pytest.approx(0.13)
        assert all(s.description for s in grp.interface.items_tree if s.item_type == "SOCKET")   # tooltips
        assert ProceduralField.from_dict(__import__("json").loads(grp[FIELD_KEY])).to_dict() == f.to_dict()
    finally:
        bpy.data.node_groups.remove(grp)
    f = _field("cells")                                           # a tinted field: its amount and frequency too
    grp = build_procedural_group(f)
    try:
        names = [s.name for s in grp.interface.items_tree if s.in_out == "INPUT"]
        assert names[-2:] == ["Tint", "Tint Frequency"]
        assert grp.interface.items_tree["Tint"].default_value == 1.0
        assert grp.interface.items_tree["Tint Frequency"].default_value == pytest.approx(f.tint.frequency)
    finally:
        bpy.data.node_groups.remove(grp)


def test_the_group_s_sliders_stop_where_the_engine_s_parameters_do():
    """Lengths, sizes and frequencies stop at the engine's least (no slider reaches a division by 0), shares at
    their range's top (a cell's Jitter over 1 would leave the cubes the group searches), amplitudes at 0, and every
    one, a vector's components too, at +-MAX_PARAM, past which the engine refuses them (drawn in float32, a Centre
    of 1e39 is infinite)."""
    from omninoise.backend.solid.procedural.family import MAX_PARAM as M

    want = {"cells": {"Size": (0.01, M), "Stretch": (0.3, M), "Jitter": (0.0, 1.0), "Gap": (0.0, 0.45),
                      "Turbulence Frequency": (0.25, M), "Detail": (0.0, M)},
            "bonds": {"Length": (0.02, M), "Height": (0.01, M), "Offset": (0.0, 1.0), "Joint": (0.0, 0.5),
                      "Turbulence": (0.0, M)},
            "rings": {"Spacing": (0.005, M), "Grain": (0.0, M), "Centre": (-M, M), "Axis": (-M, M)},
            "layers": {"Normal": (-M, M)}}
    for family, bounds in want.items():
        grp = build_procedural_group(_field(family))
        try:
            for name, (lo, hi) in bounds.items():
                s = grp.interface.items_tree[name]
                assert s.min_value == pytest.approx(lo), (family, name, s.min_value)
                assert s.max_value == pytest.approx(hi), (family, name, s.max_value)
        finally:
            bpy.data.node_groups.remove(grp)


def _summed(node):
    """(the nodes reading it, the last node) of the chain of Multiply Adds that sums the intervals of the Map Range
    ``node`` and the others on its chain."""
    n = node.outputs["Result"].links[0].to_node
    while n.outputs[0].links and all(lk.to_node.bl_idname == "ShaderNodeMath" and lk.to_node.operation ==
                                     "MULTIPLY_ADD" for lk in n.outputs[0].links):
        n = n.outputs[0].links[0].to_node
    return [lk.to_node for lk in n.outputs[0].links], n


@pytest.mark.parametrize("family", ["rings", "layers", "cells", "bonds"])
def test_each_noise_is_read_through_a_multiply_by_its_amplitude(family):
    """Cycles folds a Multiply by a constant 0 and drops the Wave Noise group behind it (a Multiply Add it does not
    fold): so every noise's value reaches the pattern only through a Multiply by its amplitude input, and an
    artist's Turbulence, Grain, Detail or Tint of 0 leaves that noise out of the render (the tint's noise through
    its levels' Map Range nodes, whose sum is what the Multiply reads)."""
    f = _field(family)
    grp = build_procedural_group(f)
    try:
        amplitudes = {"Turbulence", "Grain", "Detail", "Tint"}
        noises = [n for n in grp.nodes if n.bl_idname == "ShaderNodeGroup" and "turbulence" in n.node_tree.name]
        assert len(noises) == {"rings": 3}.get(family, 2) + (family in TINTED)
        read = []
        for n in noises:
            users = [link.to_node for link in n.outputs["Value"].links]
            if users and users[0].bl_idname == "ShaderNodeMapRange":          # the tint's levels
                assert all(u.bl_idname == "ShaderNodeMapRange" for u in users)
                users, n = _summed(users[-1])
            assert users and all(u.bl_idname == "ShaderNodeMath" and u.operation == "MULTIPLY" for u in users)
            for u in users:
                other = [link.from_socket for sock in u.inputs[:2] for link in sock.links if link.from_node != n]
                assert len(other) == 1 and other[0].node.bl_idname == "NodeGroupInput"
                read.append(other[0].name)
        assert set(read) <= amplitudes and ("Tint" in read) == (family in TINTED)
    finally:
        bpy.data.node_groups.remove(grp)


def _cycles_scene(osl: bool = False):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device, scene.cycles.samples = "CPU", 1
    scene.cycles.shading_system = osl
    return scene


@pytest.mark.parametrize("family", ["rings", "layers", "bonds", "cells", "herringbone", "herringbone45"])
def test_cycles_bake_equals_engine(family):
    """A plane baked in Cycles through the group's sRGB output (and for cells and bonds its Gap Mask), at the
    shading positions Cycles used (baked too): within 1e-3 of the engine on all but the pixels a float32 position
    puts across an edge."""
    _cycles_scene()
    _bake_equals_engine(_field(family), "nodes")


@pytest.mark.skipif(not osl_available(), reason="this bpy has no OSL")
@pytest.mark.parametrize("family,built", [("rings", "osl"), ("layers", "osl"), ("cells", "nodes"), ("bonds", "nodes")])
def test_osl_bake_equals_engine(family, built):
    """With Cycles on Open Shading Language, the group's Wave Noise trees in their OSL form (one Script node each,
    several times faster there), built so or switched to it from their node form by follow_form: the same bake
    within 1e-3 of the engine (layers and cells with a tint: all four noises)."""
    _cycles_scene(osl=True)
    _bake_equals_engine(_field(family), built, "osl")


def _bake_equals_engine(f, built: str, form: str | None = None):
    """The bake of a group of ``f`` built with its noises in the form ``built``, then switched to ``form``."""
    ob, mat = _uv_plane("procedural", 0.05)   # z = 0.05 cuts the bonds' courses 0.13 high through their units
    nt = ensure_node_tree(mat)
    nt.nodes.clear()
    grp = build_procedural_group(f, implementation=built)
    assert {tree_implementation(t) for t in noise_trees(grp)} == {built}
    if form is not None:
        assert follow_form(form) == (0 if form == built else len(noise_trees(grp)))
        assert {tree_implementation(t) for t in noise_trees(grp)} == {form}
    g = add_procedural_node(nt, grp)
    em = nt.nodes.new("ShaderNodeEmission")
    nt.links.new(g.outputs["sRGB"], em.inputs["Color"])
    nt.links.new(em.outputs[0], nt.nodes.new("ShaderNodeOutputMaterial").inputs["Surface"])
    vals = _bake(ob, nt, 48)[..., :3].reshape(-1, 3)
    if f.family in ("cells", "bonds"):
        nt.links.new(g.outputs["Gap Mask"], em.inputs["Color"])
        gaps = _bake(ob, nt, 48)[..., 0].ravel()
    nt.links.new(g.inputs["Vector"].links[0].from_node.outputs["Object"], em.inputs["Color"])
    pos = _bake(ob, nt, 48)[..., :3].reshape(-1, 3)
    assert np.abs(pos[:, :2]).max() > 0.9
    d = np.abs(vals - f.evaluate(pos.astype(np.float64))).max(1)
    assert np.percentile(d, 99) < 1e-3 and np.median(d) < 1e-4, (np.percentile(d, 99), d.max())
    if f.family in ("cells", "bonds"):
        want = f.gaps(pos.astype(np.float64))
        d = np.abs(gaps - want)
        assert np.percentile(d, 99) < 1e-3 and 0.05 < want.mean() < 0.95, (np.percentile(d, 99), want.mean())


@pytest.fixture
def small_fit(monkeypatch):
    """A quick fit (small slices, a short search): the same stages, a tenth of the work; the fits it makes are
    counted (``fits[0]``) and none is kept past the test (the panel's remembered ones are keyed by its settings)."""
    import functools

    from omninoise.blender_addon import solid_ui

    monkeypatch.setattr(fit, "ProceduralConfig", functools.partial(fit.ProceduralConfig, side=32, budget=6,
                                                                   finalists=1, fit_side=64))
    fits, real = [0], fit.fit_procedural

    def counted(*args, **kw):
        fits[0] += 1
        return real(*args, **kw)

    monkeypatch.setattr(fit, "fit_procedural", counted)
    solid_ui._DONE.clear()
    yield fits
    solid_ui._DONE.clear()


def test_the_panel_fits_previews_and_gives_a_live_node_group(small_fit, tmp_path):
    from omninoise.backend.solid.request import SolidRequest
    from omninoise.export import read_rgb

    bpy.ops.wm.read_homefile(use_empty=True)
    blender_addon.register()
    try:
        path = os.path.join(ROOT, "data", "photos", "val", "brick__tex_trak_trak4_brick2a.jpg")
        p = bpy.context.scene.omninoise_solid
        p.source, p.image, p.method, p.seed, p.scale = "IMAGE", bpy.data.images.load(path), "PROCEDURAL", 2, 1.5
        assert bpy.ops.omninoise.solid_preview() == {"FINISHED"}
        assert p.periodic_info.startswith("Fitted: ")
        assert p.grid_info == "Repeats as a grid: try Bonds alone"       # a brick wall, the default kinds
        assert small_fit[0] == 1
        ima = bpy.data.images["Solid Texture Preview"]
        px = np.empty(ima.size[0] * ima.size[1] * 4, np.float32)
        ima.pixels.foreach_get(px)
        got = np.flipud(px.reshape(128, 128, 4)[..., :3])
        pixels = np.round(read_rgb(path) * 255) / 255
        field = SolidRequest(exemplar=pixels, method="procedural", seed=2).check().procedural_field()
        assert np.abs(got - field.image(128)).max() <= 0.5 / 255 + 1e-4     # the command line's solid
        bpy.ops.mesh.primitive_cube_add()
        fitted = small_fit[0]
        assert bpy.ops.omninoise.solid_procedural_node() == {"FINISHED"}
        assert small_fit[0] == fitted          # the preview's fit: the same photo and settings are fitted once
        mat = bpy.context.active_object.active_material
        node = next(n for n in mat.node_tree.nodes if n.type == "GROUP")
        assert node.inputs["Scale"].default_value == pytest.approx(1.5)
        assert node.node_tree.name.startswith("Solid Texture Procedural")
        bsdf = next(n for n in mat.node_tree.nodes if n.type == "BSDF_PRINCIPLED")
        assert bsdf.inputs["Base Color"].links[0].from_node == node
        stored = ProceduralField.from_dict(json.loads(node.node_tree[FIELD_KEY]))     # the panel's pixels: 1 / 255
        assert stored.family == field.family
        field = stored
        # the bakes draw the same solid: a colour attribute at the cube's vertices (linear), object positions x Scale
        p.target, p.name = "COLOR_ATTRIBUTE", "Baked"
        assert bpy.ops.omninoise.solid_bake() == {"FINISHED"}
        assert small_fit[0] == fitted
        me = bpy.context.active_object.data
        co = np.empty(len(me.vertices) * 3, np.float32)
        me.vertices.foreach_get("co", co)
        rgba = np.empty(len(me.vertices) * 4, np.float32)
        me.color_attributes["Baked"].data.foreach_get("color", rgba)
        ref = srgb_to_linear(field.evaluate(co.reshape(-1, 3).astype(np.float64) * 1.5))
        assert np.abs(rgba.reshape(-1, 4)[:, :3] - ref).max() < 1e-5
        p.method = "AUTO"                     # auto says what it kept
        assert bpy.ops.omninoise.solid_preview() == {"FINISHED"}
        assert p.periodic_info.startswith("Auto: ") and "procedural" in p.periodic_info
        assert small_fit[0] == fitted          # auto's procedural solid is the one fitted above
        from omninoise.blender_addon import solid_ui
        from omninoise.cli.main import build_parser
        from omninoise.cli.solid import solid_request

        p.method, p.families = "PROCEDURAL", {"HERRINGBONE"}       # the kinds the fit tries: the command line's
        flags = build_parser().parse_args(["solid", "--method", "procedural", "--exemplar", path, "--seed", "2",
                                           "--families", "herringbone", "-o", "x.png"])
        assert solid_ui.panel_request(p).key() == solid_request(flags).key()
        assert bpy.ops.omninoise.solid_preview() == {"FINISHED"}
        assert p.periodic_info in ("Fitted: bonds (herringbone)", "Fitted: bonds (herringbone45)")
        assert p.grid_info == ""
        p.families = {"BONDS", "CELLS"}
        bpy.ops.mesh.primitive_cube_add()
        fitted = small_fit[0]
        assert bpy.ops.omninoise.solid_procedural_node() == {"FINISHED"}
        assert small_fit[0] == fitted + 1      # other kinds: another fit
        assert p.grid_info == "Repeats as a grid: try Bonds alone"
        p.families = set()
        with pytest.raises(SettingError, match="pick at least one kind"):
            solid_ui.panel_request(p)
    finally:
        blender_addon.unregister()


def test_a_bake_shows_the_fit_it_starts_with(small_fit, monkeypatch):
    """A bake that fits its procedural solid first shows the fit's progress in the first part of its bar
    (backend.bake.PREPARE_SHARE), then the drawing's, up to the end."""
    from omninoise.backend.bake import PREPARE_SHARE
    from omninoise.blender_addon import tasks

    bpy.ops.wm.read_homefile(use_empty=True)
    blender_addon.register()
    try:
        path = os.path.join(ROOT, "data", "photos", "val", "brick__tex_trak_trak4_brick2a.jpg")
        p = bpy.context.scene.omninoise_solid
        p.source, p.image, p.method, p.target = "IMAGE", bpy.data.images.load(path), "PROCEDURAL", "COLOR_ATTRIBUTE"
        bpy.ops.mesh.primitive_cube_add()
        seen, report = [], tasks.Task._report
        monkeypatch.setattr(tasks.Task, "_report", lambda self, f: seen.append(f) or report(self, f))
        assert bpy.ops.omninoise.solid_bake() == {"FINISHED"}
        assert small_fit[0] == 1
        assert len([f for f in seen if 0 < f < PREPARE_SHARE]) >= 3, seen       # the fit moves the bar
        assert seen == sorted(seen) and seen[-1] == 1.0
    finally:
        blender_addon.unregister()


def test_eevee_render_equals_engine(tmp_path):
    """EEVEE (Mesa's llvmpipe without a GPU) renders the groups as the engine draws them: its film holds half floats,
    so within 2e-3 on 99 % of pixels (a pixel whose centre a float32 position puts across an edge differs).  Rings
    (three Wave Noise groups) and cells (27 cube sub-groups): the largest groups; the Cycles test holds all four."""
    import ctypes.util
    import subprocess
    import sys

    OpenEXR = pytest.importorskip("OpenEXR")
    if ctypes.util.find_library("EGL") is None:
        if os.environ.get("OMNINOISE_REQUIRE_EEVEE") == "1":
            pytest.fail("EEVEE required (OMNINOISE_REQUIRE_EEVEE=1) but there is no libEGL")
        pytest.skip("no libEGL (install Mesa: libegl-mesa0 libgl1-mesa-dri)")
    res = 40
    fields = {fam: _field(fam) for fam in ("rings", "cells")}
    with open(tmp_path / "cases.json", "w", encoding="utf-8") as fh:
        json.dump({k: f.to_dict() for k, f in fields.items()}, fh)
    script = os.path.join(ROOT, "tests", "blender_scripts", "eevee_procedural.py")
    r = subprocess.run([sys.executable, script, str(tmp_path / "cases.json"), str(tmp_path), str(res)],
                       capture_output=True, text=True, cwd=ROOT, timeout=900)
    assert r.returncode == 0, (r.stderr or r.stdout)[-2000:]
    g = (np.arange(res, dtype=np.float64) + 0.5) * 2.0 / res - 1.0
    x, y = np.meshgrid(g, -g)
    centres = np.stack([x, y, np.full_like(x, 0.37)], -1).reshape(-1, 3)
    for fam, f in fields.items():
        with OpenEXR.File(str(tmp_path / f"{fam}.exr")) as fh:
            channels = {n: ch for part in fh.parts for n, ch in part.channels.items()}
            got = np.asarray(channels["ViewLayer.Combined"].pixels, np.float32)[..., :3].reshape(-1, 3)
        err = np.abs(got - f.evaluate(centres)).max(1)
        assert np.percentile(err, 99) < 2e-3 and np.median(err) < 1e-3, (fam, float(np.percentile(err, 99)))


def test_the_noises_follow_the_scene_s_renderer():
    """A procedural group's Wave Noise trees take the form the scene renders fastest, as the Wave Noise node's
    Automatic form does: OSL where Cycles runs Open Shading Language, Blender's nodes elsewhere; a Geometry Nodes
    group keeps its nodes, and a group refuses the OSL form there."""
    from omninoise.blender_addon import wave_ui

    scene = _cycles_scene()
    shader, geometry = build_procedural_group(_field("layers")), build_procedural_group(_field("cells"),
                                                                                          "GeometryNodeTree")

    def forms(grp):
        return {tree_implementation(t) for t in noise_trees(grp)}

    def follow():
        wave_ui._last_scene_state[0] = None
        wave_ui.follow_render_settings()

    assert len(noise_trees(shader)) == 3 and len(noise_trees(geometry)) == 3     # turbulence, detail, tint
    assert forms(shader) == forms(geometry) == {"nodes"}
    scene.cycles.shading_system = True
    follow()
    assert forms(shader) == {"osl" if osl_available() else "nodes"} and forms(geometry) == {"nodes"}
    assert follow_form(wave_ui.scene_form(scene)) == 0
    added = build_procedural_group(_field("rings"))      # built (or appended) in the node form: the next update
    wave_ui.follow_render_settings()                      # brings it to the scene's
    assert forms(added) == {"osl" if osl_available() else "nodes"}
    scene.cycles.shading_system = False
    follow()
    assert forms(shader) == forms(geometry) == forms(added) == {"nodes"}
    with pytest.raises(SettingError, match="OSL form is for shader trees"):
        build_procedural_group(_field("cells"), "GeometryNodeTree", implementation="osl")
    with pytest.raises(SettingError, match="unknown 'svm'"):
        build_procedural_group(_field("cells"), implementation="svm")


def test_a_noise_whose_script_does_not_compile_keeps_its_node_form(monkeypatch):
    """Should Cycles' OSL compiler refuse a script, the group's noises stay (or are built again) in their node form,
    which renders everywhere, rather than an empty tree."""
    from omninoise.blender_addon import wave_osl

    def refuse(*_args, **_kw):
        raise SettingError("osl", "the script did not compile")

    _cycles_scene()
    grp = build_procedural_group(_field("rings"))
    monkeypatch.setattr(wave_osl, "script_node", refuse)
    assert follow_form("osl") == 0
    trees = noise_trees(grp)
    assert len(trees) == 3 and {tree_implementation(t) for t in trees} == {"nodes"}
    assert all(len(t.nodes) > 20 for t in trees)


def test_the_panel_remembers_its_last_textures_by_their_settings():
    """remembered: one make per request key while among the last four; a failed or cancelled make leaves nothing; an
    auto choice also stands for its procedural solid."""
    from types import SimpleNamespace

    from omninoise.blender_addon import solid_ui

    class Req:
        def __init__(self, name, method="procedural"):
            self.name, self.method = name, method

        def key(self):          # as SolidRequest.key: auto's holds its procedural solid's
            if self.method == "auto":
                return {"method": "auto", "procedural": self.replace("procedural").key()}
            return {"name": self.name, "method": self.method}

        def replace(self, method):
            return Req(self.name, method)

    made = []

    def make(progress=None, cancel=None):
        made.append(1)
        return object()

    solid_ui._DONE.clear()
    try:
        first = solid_ui.remembered(Req("a"), make)()
        assert solid_ui.remembered(Req("a"), make)() is first and len(made) == 1
        for name in "bcde":                       # four more: "a" is the oldest and goes
            solid_ui.remembered(Req(name), make)()
        assert solid_ui.remembered(Req("a"), make)() is not first and len(made) == 6

        def fails(progress=None, cancel=None):
            raise RuntimeError("cancelled")

        with pytest.raises(RuntimeError):
            solid_ui.remembered(Req("f"), fails)()
        assert solid_ui._known(solid_ui._memo_keys(Req("f"))[0]) is None
        choice = SimpleNamespace(field=object())
        assert solid_ui.remembered(Req("g", "auto"), lambda progress=None, cancel=None: choice)() is choice
        assert solid_ui._known(solid_ui._memo_keys(Req("g"))[0]) is choice.field
    finally:
        solid_ui._DONE.clear()
