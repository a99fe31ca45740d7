"""The Wave Cellular node against backend.wavenoise.cellular (polytope distance and cell code), in Geometry Nodes."""
import numpy as np
import pytest

bpy = pytest.importorskip("bpy")

from omninoise.backend import Spectrum, WaveSettings, compile_noise  # noqa: E402
from omninoise.backend.errors import SettingError  # noqa: E402
from omninoise.blender_addon.cellular_nodes import build_cellular_group  # noqa: E402
from omninoise.blender_addon.field_eval import evaluate_field  # noqa: E402
from omninoise.blender_addon.compat import ensure_node_tree  # noqa: E402
from test_wave_node import _bake, _uv_plane  # noqa: E402  (the Cycles EMIT bake and its plane, of the Wave Noise tests)


def _node(s, pts, output, w=None, scale=1.0):
    grp = build_cellular_group(s, "GeometryNodeTree")

    def build(tree, pos):
        g = tree.nodes.new("GeometryNodeGroup")
        g.node_tree = grp
        tree.links.new(pos, g.inputs["Vector"])
        g.inputs["Scale"].default_value = scale
        if w is not None:
            attr = tree.nodes.new("GeometryNodeInputNamedAttribute")
            attr.data_type = "FLOAT"
            attr.inputs["Name"].default_value = "w"
            tree.links.new(attr.outputs["Attribute"], g.inputs["W"])
        return g.outputs[output]

    try:
        return evaluate_field(pts, build, w=w)
    finally:
        bpy.data.node_groups.remove(grp)


@pytest.mark.parametrize("dim, mode, directions", [(2, "polytope", 6), (3, "code", 4), (4, "polytope", 3)])
def test_cellular_node_matches_engine(dim, mode, directions):
    s = WaveSettings(dim=dim, cellular=mode, directions=directions, cell_size=0.7, seed=5,
                     spectrum=Spectrum("bandpass", 2, 4))
    rng = np.random.default_rng(dim)
    pts = rng.uniform(-3, 3, (3000, 3)).astype(np.float32)
    w = rng.uniform(-2, 2, 3000).astype(np.float32) if dim == 4 else None
    x = pts[:, : min(dim, 3)] if dim < 4 else np.concatenate([pts, w[:, None]], 1)
    ref = compile_noise(s).evaluate(np.ascontiguousarray(x, np.float32))
    dist = _node(s, pts, "Distance", w)
    cell = _node(s, pts, "Cell", w)
    assert np.quantile(np.abs(dist - ref.distance), 0.995) < 1e-4
    # a point within float rounding of a plane may land in the neighbouring slab: allow a handful
    assert np.mean(np.abs(cell - ref.cell) > 1e-6) < 0.005
    assert len(np.unique(np.round(cell, 6))) > 20  # many cells, not a constant


def test_stit_stays_bake_only():
    with pytest.raises(SettingError, match="STIT is bake-only"):
        build_cellular_group(WaveSettings(dim=2, cellular="stit"), "GeometryNodeTree")


@pytest.mark.parametrize("dim, directions", [(2, 64), (3, 32), (4, 32)])
def test_cycles_bake_equals_engine_at_the_most_directions(dim, directions):
    """The largest direction counts the node offers (2 K plane families) compile within Cycles' SVM stack and
    bake the engine's distance and cells."""
    from omninoise.blender_addon.wave_nodes import add_wave_node

    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    sc.render.engine = "CYCLES"
    sc.cycles.samples = 1
    sc.cycles.device = "CPU"
    s = WaveSettings(dim=dim, cellular="polytope", directions=directions, cell_size=0.4, seed=2)
    grp = build_cellular_group(s)
    ob, mat = _uv_plane("cells", 0.3)
    nt = ensure_node_tree(mat)
    nt.nodes.clear()
    g = add_wave_node(nt, grp)
    comb = nt.nodes.new("ShaderNodeCombineXYZ")
    nt.links.new(g.outputs["Distance"], comb.inputs[0])
    nt.links.new(g.outputs["Cell"], comb.inputs[1])
    em = nt.nodes.new("ShaderNodeEmission")
    nt.links.new(comb.outputs[0], em.inputs["Color"])
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    nt.links.new(em.outputs[0], out.inputs["Surface"])
    vals = _bake(ob, nt, 32)
    nt.links.new(g.inputs["Vector"].links[0].from_socket, em.inputs["Color"])  # the shading positions
    pos = _bake(ob, nt, 32)[..., :3].reshape(-1, 3)
    assert np.abs(pos[:, :2]).max() > 0.9
    x = pos[:, :dim] if dim < 4 else np.concatenate([pos, np.zeros((len(pos), 1), np.float32)], 1)
    ref = compile_noise(s).evaluate(np.ascontiguousarray(x, np.float32))
    dist, cell = vals[..., 0].ravel(), vals[..., 1].ravel()
    assert np.quantile(np.abs(dist - ref.distance), 0.99) < 1e-4
    assert np.mean(np.abs(cell - ref.cell) > 1e-6) < 0.01
    assert len(np.unique(np.round(cell, 5))) > 20  # many cells, not an overflowing shader's constant


def test_add_menu_operator_and_live_rebuild():
    from omninoise import blender_addon
    from omninoise.blender_addon.wave_ui import new_cellular_node_tree

    blender_addon.register()
    try:
        tree = new_cellular_node_tree("Wave Cellular", "GeometryNodeTree")
        props = tree.omninoise_wave
        assert props.is_cellular and [s.name for s in tree.interface.items_tree if s.in_out == "OUTPUT"] == \
            ["Cell", "Distance"]
        count = len(tree.nodes)
        props.directions = 6  # 12 families instead of 8: the group rebuilds in place
        assert len(tree.nodes) > count and not props.error
        pts = np.random.default_rng(0).uniform(-2, 2, (500, 3)).astype(np.float32)
        s = props.to_settings()
        ref = compile_noise(s).evaluate(pts)

        def build(t, pos):
            g = t.nodes.new("GeometryNodeGroup")
            g.node_tree = tree
            t.links.new(pos, g.inputs["Vector"])
            return g.outputs["Distance"]

        assert np.quantile(np.abs(evaluate_field(pts, build) - ref.distance), 0.99) < 1e-4
    finally:
        blender_addon.unregister()
