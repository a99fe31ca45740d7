"""A procedural solid's node group as an artist has edited it, read back as the engine's field
(blender_addon/procedural_nodes.node_field): the same solid the group renders, saved as JSON for the command line
(Save Procedural Solid), loaded from JSON as a live material (Load Procedural Solid), and previewed and baked by the
Solid Texture panel with Source Node Group at the node's own Scale and coordinates."""
import json
import os

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")

from omninoise import blender_addon  # noqa: E402
from omninoise.backend.colour import srgb_to_linear  # noqa: E402
from omninoise.backend.errors import SettingError  # noqa: E402
from omninoise.backend.solid.procedural import saved  # noqa: E402
from omninoise.backend.solid.procedural.field import ProceduralField  # noqa: E402
from omninoise.blender_addon.field_eval import evaluate_field  # noqa: E402
from omninoise.blender_addon.procedural_nodes import (FIELD_KEY, add_procedural_node,  # noqa: E402
                                                      build_procedural_group, node_field, node_space,
                                                      procedural_node)
from conftest import Recorder, needs_openvdb  # noqa: E402
from test_procedural_blender import FAMILY_PARAMS, _field  # noqa: E402  (the group-against-engine tests' fields)

#: an artist's edits per case: (input, value); sizes beyond the fit's search ranges, turned axes, less tint
EDITS = {"rings": (("Spacing", 0.31), ("Axis", (0.2, -1.0, 0.4)), ("Centre", (0.5, 0.1, -2.0)), ("Grain", 0.6)),
         "layers": (("Spacing", 2.7), ("Normal", (-0.3, 0.2, -1.0)), ("Tint", 0.4), ("Tint Frequency", 3.0)),
         "cells": (("Size", 0.35), ("Stretch", 4.0), ("Jitter", 0.5), ("Gap", 0.2), ("Tint", 0.0)),
         "bonds": (("Length", 2.5), ("Height", 0.2), ("Offset", 0.25), ("Joint", 0.3)),
         "herringbone": (("Length", 0.44), ("Height", 0.11), ("Joint", 0.05))}
SHARED = (("Turbulence", 0.7), ("Turbulence Frequency", 1.3), ("Detail", 0.05))


def _edit(node, case):
    for name, value in EDITS[case] + SHARED:
        node.inputs[name].default_value = value


@pytest.mark.parametrize("case", list(EDITS))
def test_an_edited_group_s_field_is_what_the_group_draws(case):
    """The group's nodes (in Geometry Nodes, the engine's equal: test_procedural_blender) with edited inputs and the
    engine's field read back off those inputs draw the same values, and the edits are in the field."""
    f = _field(case)
    grp = build_procedural_group(f, "GeometryNodeTree")
    pts = np.random.default_rng(2).uniform(-1.5, 1.5, (2000, 3)).astype(np.float32)
    read = {}

    def output(channel):
        def build(tree, pos):
            g = tree.nodes.new("GeometryNodeGroup")
            g.node_tree = grp
            _edit(g, case)
            read["field"] = node_field(g)
            tree.links.new(pos, g.inputs["Vector"])
            sep = tree.nodes.new("ShaderNodeSeparateXYZ")
            tree.links.new(g.outputs["sRGB"], sep.inputs[0])
            return sep.outputs[channel]
        return evaluate_field(pts, build)

    try:
        drawn = np.stack([output(c) for c in range(3)], 1)
    finally:
        bpy.data.node_groups.remove(grp)
    field = read["field"]
    ref = field.evaluate(pts.astype(np.float64))
    assert np.abs(drawn - ref).max() < 1e-3 and np.median(np.abs(drawn - ref)) < 1e-5
    assert np.abs(ref - f.evaluate(pts.astype(np.float64))).mean() > 0.02          # the edits changed the solid
    p = field.params
    assert p["turbulence"] == pytest.approx(0.7) and p["turb_freq"] == pytest.approx(1.3)
    key = {"rings": "spacing", "layers": "spacing", "cells": "size"}.get(case, "length")
    assert p[key] == pytest.approx(dict(EDITS[case])[key.title()])
    assert {k: v for k, v in p.items() if isinstance(v, (str, bool))} == \
        {k: v for k, v in f.params.items() if isinstance(v, (str, bool))}         # profile, pattern, flip kept
    if case == "layers":
        assert field.tint.frequency == pytest.approx(3.0)
        np.testing.assert_allclose(field.tint.levels, 0.4 * np.array(f.tint.levels), rtol=1e-6)
    if case == "cells":
        assert f.tint is not None and field.tint is None                          # Tint 0: none drawn


def _cube_with_group(f, scale=1.0):
    bpy.ops.mesh.primitive_cube_add(size=2.0, location=(0.3, -0.2, 0.1))
    obj = bpy.context.active_object
    mat = bpy.data.materials.new("Edited")
    mat.use_nodes = True
    obj.data.materials.append(mat)
    node = add_procedural_node(mat.node_tree, build_procedural_group(f, name="Edited Procedural"))
    node.inputs["Scale"].default_value = scale
    return obj, node


def _assert_baked(obj, name: str, field, scale: float) -> None:
    """The colour attribute ``name`` of ``obj``'s mesh holds ``field`` (linear) at its vertices' object positions
    times ``scale`` (a float32 socket value), within 1e-5."""
    me = obj.data
    co = np.empty(len(me.vertices) * 3, np.float32)
    me.vertices.foreach_get("co", co)
    rgba = np.empty(len(me.vertices) * 4, np.float32)
    me.color_attributes[name].data.foreach_get("color", rgba)
    ref = srgb_to_linear(field.evaluate(co.reshape(-1, 3).astype(np.float64) * np.float32(scale)))
    assert np.abs(rgba.reshape(-1, 4)[:, :3] - ref).max() < 1e-5


def test_save_load_and_bake_the_node_group_as_edited(tmp_path):
    bpy.ops.wm.read_homefile(use_empty=True)
    blender_addon.register()
    try:
        from omninoise.blender_addon import solid_ui

        f = _field("layers")
        obj, node = _cube_with_group(f, scale=1.7)
        _edit(node, "layers")
        edited = node_field(node)
        assert node_space(node) == (pytest.approx(1.7), False)

        path = str(tmp_path / "edited.json")
        assert bpy.ops.omninoise.solid_save_procedural(filepath=path) == {"FINISHED"}
        assert json.load(open(path))["format"] == saved.FORMAT
        assert saved.read(path).to_dict() == edited.to_dict()

        # Source Node Group: the bake draws the node as edited, at its Scale, in the object's space
        p = bpy.context.scene.omninoise_solid
        p.source, p.target, p.name, p.scale = "NODE_GROUP", "COLOR_ATTRIBUTE", "Baked", 0.5
        assert bpy.ops.omninoise.solid_bake() == {"FINISHED"}
        _assert_baked(obj, "Baked", edited, 1.7)
        log = []                            # the panel names the node and draws neither Scale nor Seed
        solid_ui.draw_solid_all(Recorder(log), bpy.context)
        assert not {"scale", "seed", "coords", "texture", "image", "method"} & {a for n, a, t in log if n == "prop"}
        labels = {t for n, a, t in log if n == "label"}
        assert {"Edited > Edited Procedural", "Scale and coordinates: the node's"} <= labels
        assert {"Save", "Load"} <= {t for n, a, t in log if n == "operator"}
        assert bpy.ops.omninoise.solid_preview() == {"FINISHED"}
        ima = bpy.data.images["Baked Preview"]
        px = np.empty(ima.size[0] * ima.size[1] * 4, np.float32)
        ima.pixels.foreach_get(px)
        assert np.abs(np.flipud(px.reshape(128, 128, 4)[..., :3]) - edited.image(128)).max() <= 0.5 / 255 + 1e-4

        # Load: a new mesh draws the saved solid live; its node reads back as the file
        bpy.ops.mesh.primitive_uv_sphere_add()
        sphere = bpy.context.active_object
        p.scale, p.coords = 2.0, "WORLD"
        assert bpy.ops.omninoise.solid_load_procedural(filepath=path) == {"FINISHED"}
        loaded = procedural_node(sphere)
        assert loaded.node_tree.name.startswith("edited Procedural")
        assert node_space(loaded) == (pytest.approx(2.0), True)
        back = node_field(loaded)
        pts = np.random.default_rng(3).uniform(-1, 1, (3000, 3))
        assert np.abs(back.evaluate(pts) - edited.evaluate(pts)).max() < 1e-4     # float32 sockets
        bsdf = next(n for n in sphere.active_material.node_tree.nodes if n.type == "BSDF_PRINCIPLED")
        assert bsdf.inputs["Base Color"].links[0].from_node == loaded
    finally:
        blender_addon.unregister()


def test_what_a_node_group_bake_cannot_read_is_named(tmp_path):
    bpy.ops.wm.read_homefile(use_empty=True)
    blender_addon.register()
    try:
        from omninoise.blender_addon import solid_ui

        p = bpy.context.scene.omninoise_solid
        p.source = "NODE_GROUP"
        bpy.ops.mesh.primitive_cube_add()
        with pytest.raises(SettingError, match="no procedural node group: the active material of 'Cube' has none"):
            solid_ui.panel_request(p)
        with pytest.raises(RuntimeError, match="no procedural node group"):
            bpy.ops.omninoise.solid_save_procedural(filepath=str(tmp_path / "x.json"))
        with pytest.raises(RuntimeError, match="no procedural node group"):
            bpy.ops.omninoise.solid_save_procedural("INVOKE_DEFAULT")
        assert not os.path.exists(tmp_path / "x.json")
        obj, node = _cube_with_group(_field("rings"))
        nt = obj.active_material.node_tree
        value = nt.nodes.new("ShaderNodeValue")
        nt.links.new(value.outputs[0], node.inputs["Spacing"])
        with pytest.raises(SettingError, match="the Spacing of node 'Group' is linked to another node"):
            solid_ui.panel_request(p)
        nt.links.remove(node.inputs["Spacing"].links[0])
        node.inputs["Axis"].default_value = (0.0, 0.0, 0.0)
        with pytest.raises(SettingError, match="Axis: .*a direction must have a length"):
            solid_ui.panel_request(p)
        node.inputs["Axis"].default_value = (0.0, 0.0, 1.0)
        assert solid_ui.panel_request(p).method == "procedural"
        uv = nt.nodes.new("ShaderNodeTexCoord")
        nt.links.new(uv.outputs["UV"], node.inputs["Vector"])
        p.target = "COLOR_ATTRIBUTE"
        with pytest.raises(RuntimeError, match="the Vector of node 'Group' is not the object's own space"):
            bpy.ops.omninoise.solid_bake()
        node.node_tree.interface.remove(node.node_tree.interface.items_tree["Detail"])    # an artist's change
        with pytest.raises(SettingError, match="node 'Group' has no input 'Detail': its group 'Edited Procedural' "
                                               "was changed"):
            solid_ui.panel_request(p)
        node.node_tree[FIELD_KEY] = '{"family": "rings"}'
        with pytest.raises(SettingError, match="holds no procedural solid that can be read .*params: missing"):
            solid_ui.panel_request(p)
        bad = tmp_path / "bad.json"
        bad.write_text('{"format": "omninoise procedural solid 1", "family": "rings"}')
        with pytest.raises(RuntimeError, match="params: missing"):
            bpy.ops.omninoise.solid_load_procedural(filepath=str(bad))
        with pytest.raises(RuntimeError, match=r"file: pick a saved procedural solid \(.json\) to load"):
            bpy.ops.omninoise.solid_load_procedural()
        bpy.ops.object.camera_add()
        with pytest.raises(RuntimeError, match="object: select a mesh to give the procedural material to"):
            bpy.ops.omninoise.solid_load_procedural(filepath=str(bad))
    finally:
        blender_addon.unregister()


def test_every_family_s_group_reads_back_as_its_field_unedited():
    for case in FAMILY_PARAMS:
        f = _field(case)
        grp = build_procedural_group(f)
        mat = bpy.data.materials.new("Unedited")
        mat.use_nodes = True
        try:
            node = add_procedural_node(mat.node_tree, grp)
            back = node_field(node)
            pts = np.random.default_rng(4).uniform(-1.5, 1.5, (3000, 3))
            diff = np.abs(back.evaluate(pts) - f.evaluate(pts))
            assert back.family == f.family and np.median(diff) < 1e-6 and np.mean(diff > 1e-3) < 0.002, case
            assert isinstance(back, ProceduralField)
        finally:
            bpy.data.materials.remove(mat)
            bpy.data.node_groups.remove(grp)


def test_an_asset_library_material_bakes_and_saves_as_its_node_group_draws(tmp_path):
    """The shipped Procedural Brick Wall on a cube: Source Node Group reads its group (a running bond), and Save
    writes it for the command line."""
    from omninoise.blender_addon import preferences

    bpy.ops.wm.read_homefile(use_empty=True)
    blender_addon.register()
    try:
        with bpy.data.libraries.load(os.path.join(preferences.ASSETS, "omninoise_assets.blend"),
                                     assets_only=True) as (src, dst):
            dst.materials = ["Procedural Brick Wall"]
        bpy.ops.mesh.primitive_cube_add()
        obj = bpy.context.active_object
        obj.data.materials.append(dst.materials[0])
        node = procedural_node(obj)
        field = node_field(node)
        assert field.family == "bonds" and field.params["offset"] == pytest.approx(0.5, abs=1e-6)
        p = bpy.context.scene.omninoise_solid
        p.source, p.target, p.name = "NODE_GROUP", "COLOR_ATTRIBUTE", "Bricks"
        assert bpy.ops.omninoise.solid_bake() == {"FINISHED"}
        scale, world = node_space(node)
        assert not world
        _assert_baked(obj, "Bricks", field, scale)
        path = str(tmp_path / "bricks.json")
        assert bpy.ops.omninoise.solid_save_procedural(filepath=path) == {"FINISHED"}
        assert saved.read(path).to_dict() == field.to_dict()
    finally:
        blender_addon.unregister()


@needs_openvdb
def test_a_volume_bake_of_the_node_group_fills_the_object_s_bounds_with_the_edited_solid(tmp_path):
    bpy.ops.wm.read_homefile(use_empty=True)
    blender_addon.register()
    try:
        obj, node = _cube_with_group(_field("bonds"), scale=1.3)
        _edit(node, "bonds")
        edited = node_field(node)
        p = bpy.context.scene.omninoise_solid
        p.source, p.target, p.voxels, p.folder, p.name = "NODE_GROUP", "VOLUME", 8, str(tmp_path), "Wall"
        assert bpy.ops.omninoise.solid_bake() == {"FINISHED"}
        from omninoise.export.vdb import read_volume

        col = read_volume(str(tmp_path / "Wall.vdb"), "color", (8, 8, 8))
        c = -1 + (np.arange(8) + 0.5) * 0.25            # voxel centres of the cube's own bounds [-1, 1]^3
        z, y, x = np.meshgrid(c, c, c, indexing="ij")
        ref = srgb_to_linear(edited.evaluate(np.stack([x, y, z], -1).reshape(-1, 3) * np.float32(1.3)))
        np.testing.assert_allclose(col.reshape(-1, 3), ref, atol=1e-5)

        # saved as a job: the edited solid beside it as JSON, baked again without Blender to the same volume
        from omninoise.cli.main import main

        job = tmp_path / "wall.toml"
        assert bpy.ops.omninoise.solid_save_job(filepath=str(job)) == {"FINISHED"}
        assert saved.read(str(tmp_path / "wall_solid.json")).to_dict() == edited.to_dict()
        import tomllib

        table = tomllib.loads(job.read_text())["bake"][0]["source"]
        assert table["exemplar"] == "wall_solid.json" and table["scale"] == float(np.float32(1.3))   # the node's
        assert main(["bake", str(job), "--force", "-q"]) == 0
        again = read_volume(str(tmp_path / "Wall.vdb"), "color", (8, 8, 8))
        np.testing.assert_allclose(again, col, atol=1e-6)
    finally:
        blender_addon.unregister()


def test_a_material_linked_from_a_library_is_left_as_it_is(tmp_path):
    """A linked material cannot keep an edit (it is read from its library each time): Load Procedural Solid and a
    bake give the object a material of the file's own in its place; the linked one reads back unchanged."""
    from omninoise.blender_addon import preferences

    bpy.ops.wm.read_homefile(use_empty=True)
    blender_addon.register()
    try:
        with bpy.data.libraries.load(os.path.join(preferences.ASSETS, "omninoise_assets.blend"), link=True,
                                     assets_only=True) as (src, dst):
            dst.materials = ["Procedural Brick Wall"]
        linked = dst.materials[0]
        nodes = len(linked.node_tree.nodes)
        bpy.ops.mesh.primitive_cube_add()
        obj = bpy.context.active_object
        obj.data.materials.append(linked)
        field = node_field(procedural_node(obj))          # read from the library's group: a bake can use it
        path = str(tmp_path / "bricks.json")
        assert bpy.ops.omninoise.solid_save_procedural(filepath=path) == {"FINISHED"}
        assert bpy.ops.omninoise.solid_load_procedural(filepath=path) == {"FINISHED"}
        mat = obj.active_material
        assert mat.library is None and mat.name == "OmniNoise bricks Procedural"
        assert node_field(procedural_node(obj)).to_dict() == field.to_dict()
        assert len(linked.node_tree.nodes) == nodes
    finally:
        blender_addon.unregister()
