"""The Wave Noise node group against the engine: Geometry Nodes fields and Cycles bakes.

Agreement is measured at the very points Blender evaluated: for Cycles the
shading positions are baked too (a bake interpolates positions in float32, so
they differ from the ideal pixel centres by ~5e-5).
"""
import numpy as np
import pytest

bpy = pytest.importorskip("bpy")

from omninoise.backend import Spectrum, WaveSettings, compile_noise  # noqa: E402
from omninoise.backend.wavenoise.wave import select_output  # noqa: E402
from omninoise.blender_addon.field_eval import evaluate_field  # noqa: E402
from omninoise.blender_addon.compat import ensure_node_tree  # noqa: E402
from omninoise.blender_addon.wave_nodes import SETTINGS_KEY, add_wave_node, build_wave_group, settings_from_json  # noqa: E402,E501

OUT = {"Value": "real", "Imaginary": "imag", "Modulus": "modulus", "Phase": "phase"}
#: the group's input socket of each keyword of _engine (and of CASES' keyword dicts)
SOCKETS = {"scale": "Scale", "time": "Time", "w": "W"}


def _engine(s, pts, scale=1.0, time=0.0, w=0.0):
    x = pts[:, : min(s.dim, 3)]
    if s.dim == 4:
        x = np.concatenate([x, np.full((len(x), 1), w, np.float32)], 1)
    return compile_noise(s).evaluate((x * np.float32(scale)).astype(np.float32), time, accelerate=False)


def _node_field(s, pts, output, scale=1.0, time=0.0, w=0.0):
    grp = build_wave_group(s, "GeometryNodeTree")

    def build(tree, pos):
        g = tree.nodes.new("GeometryNodeGroup")
        g.node_tree = grp
        tree.links.new(pos, g.inputs["Vector"])
        g.inputs["Scale"].default_value = scale
        g.inputs["Time"].default_value = time
        g.inputs["W"].default_value = w
        return g.outputs[output]

    try:
        return evaluate_field(pts, build)
    finally:
        bpy.data.node_groups.remove(grp)


CASES = {
    "2d": (WaveSettings(dim=2, spectrum=Spectrum("bandpass", 2, 6), directions=8, seed=3), {}),
    "3d": (WaveSettings(dim=3, spectrum=Spectrum("bandpass", 2, 6), directions=8, seed=3), {"scale": 1.7}),
    "4d": (WaveSettings(dim=4, spectrum=Spectrum("bandpass", 2, 6), directions=8, seed=3), {"w": 0.7}),
    "3d+t": (WaveSettings(dim=3, spectrum=Spectrum("gaussian", 2, 6), directions=8, seed=4, speed=0.8),
             {"time": 1.3}),
    "2d+t": (WaveSettings(dim=2, spectrum=Spectrum("gaussian", 2, 6), directions=6, seed=4, speed=0.5),
             {"time": 2.5}),
    "lobes": (WaveSettings(dim=3, spectrum=Spectrum("gaussian", 2, 6), directions=12, seed=7, anisotropy="lobes",
                           lobes=(((1.0, 0.2, 0.3), 1.0), ((0.0, 1.0, 0.0), 0.5)), spread=25.0), {}),
    "axes": (WaveSettings(dim=3, directions=8, seed=7, anisotropy="axes",
                          axis_spectra=(Spectrum("bandpass", 1, 3), Spectrum("bandpass", 4, 6),
                                        Spectrum("bandpass", 2, 3))), {}),
    "axes2d": (WaveSettings(dim=2, directions=8, seed=7, anisotropy="axes",
                            axis_spectra=(Spectrum("bandpass", 1, 3), Spectrum("bandpass", 4, 6))), {}),
    "crystal": (WaveSettings(dim=2, spectrum=Spectrum("gaussian", 2, 6), directions=8, seed=7, waveform="crystal"),
                {}),
}


@pytest.mark.parametrize("case", list(CASES))
def test_geometry_nodes_field_equals_engine(case):
    s, kw = CASES[case]
    pts = np.random.default_rng(1).uniform(-2, 3, (1500, 3)).astype(np.float32)
    z = _engine(s, pts, **kw)
    for output in ("Value", "Imaginary", "Modulus"):
        got = _node_field(s, pts, output, **kw)
        ref = select_output(z, OUT[output])
        d = np.abs(got - ref)
        # same hashes, same float32 maths: most points agree to ~1e-7; the float32
        # table coordinate bounds the rest (~1e-4)
        assert np.median(d) < 1e-6 and np.percentile(d, 99) < 3e-5 and d.max() < 2e-4, (output, d.max())
        assert ref.std() > 0.1


def test_phase_output_where_defined():
    s, kw = CASES["3d"]
    pts = np.random.default_rng(2).uniform(-2, 3, (1500, 3)).astype(np.float32)
    z = _engine(s, pts, **kw)
    got = _node_field(s, pts, "Phase", **kw)
    d = np.abs(np.angle(np.exp(1j * (got - select_output(z, "phase")))))
    strong = np.abs(z) > 0.1  # phase is ill-conditioned where the modulus vanishes
    assert d[strong].max() < 2e-3 and np.median(d) < 1e-6


def _uv_plane(name: str, z: float = 0.0):
    """A 2 x 2 plane at height ``z`` with a UV map over it and an empty material ``name``, in the scene, to bake
    -> (object, material)."""
    mesh = bpy.data.meshes.new("plane")
    mesh.from_pydata([(-1, -1, z), (1, -1, z), (1, 1, z), (-1, 1, z)], [], [(0, 1, 2, 3)])
    uv = mesh.uv_layers.new(name="UV")
    for i, c in enumerate([(0, 0), (1, 0), (1, 1), (0, 1)]):
        uv.data[i].uv = c
    ob = bpy.data.objects.new("plane", mesh)
    bpy.context.scene.collection.objects.link(ob)
    mat = bpy.data.materials.new(name)
    ob.data.materials.append(mat)
    return ob, mat


def _plane_material(grp, kw):
    ob, mat = _uv_plane("wave")
    nt = ensure_node_tree(mat)
    nt.nodes.clear()
    g = add_wave_node(nt, grp)
    tc = g.inputs["Vector"].links[0].from_node
    for key, val in kw.items():
        g.inputs[SOCKETS[key]].default_value = val
    comb = nt.nodes.new("ShaderNodeCombineXYZ")
    for i, o in enumerate(("Value", "Imaginary", "Modulus")):
        nt.links.new(g.outputs[o], comb.inputs[i])
    em = nt.nodes.new("ShaderNodeEmission")
    nt.links.new(comb.outputs[0], em.inputs["Color"])
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    nt.links.new(em.outputs[0], out.inputs["Surface"])
    return ob, nt, tc, comb, em


def _bake(ob, nt, size):
    img = bpy.data.images.new("bake", size, size, alpha=False, float_buffer=True)
    img.colorspace_settings.name = "Non-Color"
    it = nt.nodes.new("ShaderNodeTexImage")
    it.image = img
    nt.nodes.active = it
    bpy.context.view_layer.objects.active = ob
    ob.select_set(True)
    bpy.ops.object.bake(type="EMIT", margin=0)
    px = np.array(img.pixels[:], np.float32).reshape(size, size, 4)
    nt.nodes.remove(it)
    bpy.data.images.remove(img)
    return px


@pytest.mark.parametrize("case", ["2d", "3d", "4d", "3d+t"])
def test_cycles_bake_equals_engine(case):
    s, kw = CASES[case]
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = 1
    grp = build_wave_group(s, "ShaderNodeTree")
    ob, nt, tc, comb, em = _plane_material(grp, kw)
    vals = _bake(ob, nt, 48)
    nt.links.new(tc.outputs["Object"], em.inputs["Color"])  # bake the shading positions too
    pos = _bake(ob, nt, 48)[..., :3].reshape(-1, 3)
    assert np.abs(pos[:, :2]).max() > 0.9  # the plane was covered
    z = _engine(s, np.ascontiguousarray(pos), **kw)
    for c, o in enumerate(("real", "imag", "modulus")):
        d = np.abs(vals[..., c].ravel() - select_output(z, o))
        assert np.percentile(d, 99) < 5e-5 and d.max() < 2e-4, (o, d.max())


@pytest.mark.parametrize("use", ["none", "axes", "bump"])
@pytest.mark.parametrize("dim,k", [(2, 64), (3, 32), (4, 32)])
def test_cycles_compiles_many_directions(dim, k, use):
    """Cycles' SVM stack (255 floats) holds the largest direction counts the node offers, with one table or one
    per axis, and with the Value also bumping a BSDF's normal (Cycles compiles a Bump's height three times)."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.samples = 1
    kw = {}
    if use == "axes":
        kw = dict(anisotropy="axes",
                  axis_spectra=tuple(Spectrum("bandpass", 2 * a, 6 * a) for a in (1, 2, 0.5, 1)[:dim]))
    grp = build_wave_group(WaveSettings(dim=dim, spectrum=Spectrum("bandpass", 2, 6), directions=k, seed=3, **kw),
                           "ShaderNodeTree")
    ob, nt, _, comb, em = _plane_material(grp, {})
    if use == "bump":
        bump = nt.nodes.new("ShaderNodeBump")
        nt.links.new(comb.inputs[0].links[0].from_socket, bump.inputs["Height"])
        bsdf = nt.nodes.new("ShaderNodeBsdfPrincipled")
        nt.links.new(bump.outputs["Normal"], bsdf.inputs["Normal"])
        both = nt.nodes.new("ShaderNodeAddShader")
        out = em.outputs[0].links[0].to_socket
        nt.links.new(em.outputs[0], both.inputs[0])
        nt.links.new(bsdf.outputs[0], both.inputs[1])
        nt.links.new(both.outputs[0], out)
    px = _bake(ob, nt, 8)
    assert px[..., 0].std() > 0.1  # an overflowing shader bakes to a constant


def test_rebuild_keeps_links_and_interface():
    s, _ = CASES["3d"]
    grp = build_wave_group(s, "ShaderNodeTree")
    mat = bpy.data.materials.new("links")
    nt = ensure_node_tree(mat)
    nt.nodes.clear()
    g = nt.nodes.new("ShaderNodeGroup")
    g.node_tree = grp
    em = nt.nodes.new("ShaderNodeEmission")
    nt.links.new(g.outputs["Modulus"], em.inputs["Strength"])
    before = len(grp.nodes)
    s2 = s.replace(directions=5, dim=2, seed=9)
    build_wave_group(s2, tree=grp)
    assert len(nt.links) == 1 and nt.links[0].from_socket.name == "Modulus"
    assert settings_from_json(grp[SETTINGS_KEY]) == s2
    assert sum(n.bl_idname == "ShaderNodeGroup" for n in grp.nodes) == 5 and len(grp.nodes) < before
    assert before
    assert not [t for t in bpy.data.node_groups if t.name.startswith(".") and t.users == 0]


@pytest.mark.parametrize("cellular", [False, True])
def test_every_input_and_output_has_a_tooltip_and_a_rebuild_restores_them(cellular):
    """Hovering a socket of the Wave Noise or Wave Cellular node says what it is, as on Blender's own texture nodes;
    a group saved without tooltips (an older file) gets them when it is rebuilt."""
    from omninoise.blender_addon.cellular_nodes import build_cellular_group

    build = build_cellular_group if cellular else build_wave_group
    s = WaveSettings(dim=3, cellular="polytope") if cellular else CASES["3d"][0]
    grp = build(s, "ShaderNodeTree")
    try:
        items = [i for i in grp.interface.items_tree if i.item_type == "SOCKET"]
        assert len(items) == 6 if cellular else 8
        assert all(i.description for i in items), [i.name for i in items if not i.description]
        assert ("Not read" in grp.interface.items_tree["Time"].description) == cellular
        for i in items:
            i.description = ""
        build(s.replace(seed=4), tree=grp)
        assert all(i.description for i in items)
    finally:
        bpy.data.node_groups.remove(grp)


def test_table_image_is_float_and_survives_save(tmp_path):
    s, _ = CASES["2d"]
    grp = build_wave_group(s, "ShaderNodeTree")
    grp.use_fake_user = True
    img = next(i for i in bpy.data.images if i.name.startswith("OmniNoise packed"))
    assert img.packed_file is not None and not img.use_half_precision and img.is_float
    ref = np.array(img.pixels[:], np.float32)
    # one texel holds what a lerp needs: R, G = T[j] and B, A = T[j + 1] - T[j] (negative alpha kept)
    px = ref.reshape(img.size[1], img.size[0], 4)
    assert np.allclose(px[:, :, 2:], np.roll(px[:, :, :2], -1, axis=1) - px[:, :, :2], atol=1e-6)
    assert px[..., 3].min() < 0
    name = img.name
    path = str(tmp_path / "t.blend")
    bpy.ops.wm.save_as_mainfile(filepath=path)
    bpy.ops.wm.open_mainfile(filepath=path)
    img = bpy.data.images[name]
    assert np.array_equal(np.array(img.pixels[:], np.float32), ref)
    bpy.ops.wm.read_factory_settings(use_empty=True)


def test_settings_key_and_the_key_of_older_files():
    """The settings live under a key no registered property uses (before 5.0 the two share storage);
    trees saved by OmniNoise 0.1 on Blender 5.0 under the old key still give their settings."""
    from omninoise.blender_addon.compat import VERSION
    from omninoise.blender_addon.wave_nodes import LEGACY_SETTINGS_KEY, tree_settings_json

    s, _ = CASES["2d"]
    grp = build_wave_group(s, "ShaderNodeTree")
    assert SETTINGS_KEY != LEGACY_SETTINGS_KEY and settings_from_json(tree_settings_json(grp)) == s
    if VERSION < (5, 0):
        pytest.skip("before Blender 5.0 the old key names the registered property and holds no settings")
    text = grp[SETTINGS_KEY]
    del grp[SETTINGS_KEY]
    grp[LEGACY_SETTINGS_KEY] = text  # as OmniNoise 0.1 stored it
    assert tree_settings_json(grp) == text
    del grp[LEGACY_SETTINGS_KEY]
    assert tree_settings_json(grp) is None
    bpy.data.node_groups.remove(grp)


def test_in_the_interface_a_setting_rebuilds_its_group_once_it_rests(monkeypatch):
    """A dragged slider changes a setting many times a second and a rebuild takes 0.5 s or more: in the interface
    the group is rebuilt once, REBUILD_DELAY_S after the last change, with the last values; a group removed
    meanwhile is skipped.  Scripts (background Blender) rebuild at once."""
    from omninoise import blender_addon
    from omninoise.blender_addon import wave_ui

    bpy.ops.wm.read_factory_settings(use_empty=True)
    blender_addon.register()
    registered = []                                             # the timer, as bpy.app.timers would hold it
    try:
        tree = wave_ui.new_wave_node_tree("Wave", "ShaderNodeTree")
        props = tree.omninoise_wave
        props.fmin = 1.5                                        # background: at once
        assert settings_from_json(tree[SETTINGS_KEY]).spectrum.fmin == 1.5
        built = []
        real = wave_ui.build_wave_group
        monkeypatch.setattr(wave_ui, "build_wave_group", lambda s, **k: built.append(s.spectrum.fmin) or real(s, **k))
        monkeypatch.setattr(wave_ui, "deferred", lambda: True)
        monkeypatch.setattr(bpy.app.timers, "register", lambda f, first_interval=0.0: registered.append(f))
        monkeypatch.setattr(bpy.app.timers, "is_registered", lambda f: f in registered)
        for v in (2.0, 2.5, 3.0):                               # a drag
            props.fmin = v
        assert built == [] and registered == [wave_ui.rebuild_due]
        assert settings_from_json(tree[SETTINGS_KEY]).spectrum.fmin == 1.5
        assert 0.0 < wave_ui.rebuild_due() <= wave_ui.REBUILD_DELAY_S      # not yet at rest: look again
        monkeypatch.setattr(wave_ui, "_due_at", [0.0])
        assert wave_ui.rebuild_due() is None and built == [3.0]
        assert settings_from_json(tree[SETTINGS_KEY]).spectrum.fmin == 3.0 and not props.error
        props.fmin = 4.0
        bpy.data.node_groups.remove(tree)
        monkeypatch.setattr(wave_ui, "_due_at", [0.0])
        assert wave_ui.rebuild_due() is None and built == [3.0]
    finally:
        registered.clear()
        blender_addon.unregister()


def test_a_settings_error_in_the_panel_names_the_setting_as_the_panel_does():
    """The Wave Noise panel shows why a group could not be built under the setting's label, not the settings'
    dotted name (spectrum.fmin); it clears once the settings are good again."""
    from omninoise import blender_addon
    from omninoise.blender_addon import wave_ui

    bpy.ops.wm.read_factory_settings(use_empty=True)
    blender_addon.register()
    try:
        props = wave_ui.new_wave_node_tree("Wave", "ShaderNodeTree").omninoise_wave
        props.fmin = 9.0
        assert props.error == f"Min Frequency: 9 is greater than fmax {props.fmax:g}"
        props.fmin = 1.0
        assert not props.error
        props.dimensions, props.anisotropy, props.axis = "3", "lobes", (0.0, 0.0, 0.0)
        assert props.error == "Axis: lobe axis (0.0, 0.0, 0.0) must be a non-zero 3-vector"
        assert wave_ui.setting_label(props, "axis_spectra[1].fmax") == "Axis Frequency"
        assert wave_ui.setting_label(props, "table size") == "table size"       # no such property: as it is
    finally:
        blender_addon.unregister()

def _tree_dump(tree) -> list:
    """Every node of a tree and its sub-groups, in order: kind, operation, inputs' values and links, image."""
    out = []
    for n in tree.nodes:
        row = [n.bl_idname, getattr(n, "operation", None)]
        for s in n.inputs:
            v = getattr(s, "default_value", None)
            if isinstance(v, float):
                v = round(v, 7)
            elif v is not None and hasattr(v, "__len__") and not isinstance(v, str):
                v = tuple(round(float(c), 7) for c in v)
            elif v is not None and not isinstance(v, (int, bool, str)):
                v = v.name                                   # an image socket (Geometry Nodes)
            row.append((s.name, v, s.is_linked))
        row.append(getattr(getattr(n, "image", None), "name", None))
        if n.bl_idname in ("ShaderNodeGroup", "GeometryNodeGroup"):
            row.append(_tree_dump(n.node_tree))
        out.append(row)
    return out


def test_a_copied_group_changes_alone():
    """A group copied in Blender (a node's group made single user) shares its direction sub-groups with the
    original: a change of the copy's seed or directions builds its own and leaves the original as it was."""
    s, _ = CASES["3d"]
    original = build_wave_group(s, "ShaderNodeTree")
    copy = original.copy()
    for change in (dict(seed=11), dict(directions=6), dict(directions=9, seed=2)):
        build_wave_group(s.replace(**change), tree=copy)
        assert _tree_dump(copy) == _tree_dump(build_wave_group(s.replace(**change), "ShaderNodeTree")), change
        assert _tree_dump(original) == _tree_dump(build_wave_group(s, "ShaderNodeTree")), change


@pytest.mark.parametrize("tree_type", ["ShaderNodeTree", "GeometryNodeTree"])
@pytest.mark.parametrize("case", ["2d+t", "3d", "4d", "lobes", "axes", "axes2d"])
def test_strata_copied_and_retuned_equal_strata_built_node_by_node(tree_type, case, monkeypatch):
    """A group builds one sub-group per stratum shape and copies it for the other strata of that shape, retuned:
    the group equals one whose every stratum is built node by node, and its strata are separate trees."""
    from omninoise.blender_addon import wave_nodes

    s, _ = CASES[case]
    copied = build_wave_group(s, tree_type)
    subs = [n.node_tree for n in copied.nodes if n.bl_idname.endswith("Group")]
    assert len({t.name for t in subs}) == len(subs) == s.directions
    assert all(t.users == 1 and t.name == f".{copied.name} direction {k + 1}" for k, t in enumerate(subs))
    monkeypatch.setattr(wave_nodes, "_new_stratum", lambda built, shape, *a: wave_nodes._stratum_group(*a))
    assert _tree_dump(copied) == _tree_dump(build_wave_group(s, tree_type))


@pytest.mark.parametrize("tree_type", ["ShaderNodeTree", "GeometryNodeTree"])
@pytest.mark.parametrize("dim", [2, 3, 4])
def test_a_change_that_keeps_the_group_s_shape_retunes_it_in_place(tree_type, dim, monkeypatch):
    """A change of band, spectrum, seed or waveform (a slider's) rewrites the constants it moves and the table
    image in place: the group equals one built afresh, node for node, and no node is made; after a change of the
    directions' count too, and no sub-group is left behind."""
    from omninoise.blender_addon import wave_nodes

    base = WaveSettings(dim=dim, directions=6, spectrum=Spectrum("gaussian", 2, 8))
    tree = build_wave_group(base, tree_type)
    for change in (dict(spectrum=Spectrum("gaussian", 2.5, 7)), dict(spectrum=Spectrum("fractal", 1, 8, 1.3)),
                   dict(seed=5), dict(waveform="crystal"), dict(speed=0.7), dict(speed=1.4)):
        s = base.replace(**change)
        made = []
        real_new = wave_nodes.NodeBuilder.new
        monkeypatch.setattr(wave_nodes.NodeBuilder, "new",
                            lambda self, *a, **k: made.append(1) or real_new(self, *a, **k))
        build_wave_group(s, tree=tree)
        monkeypatch.undo()
        assert settings_from_json(tree[SETTINGS_KEY]) == s
        assert _tree_dump(tree) == _tree_dump(build_wave_group(s, tree_type)), change
        if change != dict(speed=0.7):                     # a speed from 0 turns the directions over the whole sphere
            assert made == [], change
        base = s
    for count in (7, 4, 7):
        s = base.replace(directions=count)
        build_wave_group(s, tree=tree)
        assert len([n for n in tree.nodes if n.bl_idname.endswith("Group")]) == count
        assert _tree_dump(tree) == _tree_dump(build_wave_group(s, tree_type)), count
        assert not [t for t in bpy.data.node_groups if t.name.startswith(f".{tree.name} ") and t.users == 0]
    base = s
    sub = next(n.node_tree for n in tree.nodes if n.bl_idname.endswith("Group"))
    for n in list(sub.nodes)[:40]:                        # edited by hand: built again, whole
        n.name = n.name + " edited"
    s = base.replace(directions=7, seed=9)
    build_wave_group(s, tree=tree)
    assert _tree_dump(tree) == _tree_dump(build_wave_group(s, tree_type))
