"""Evaluate Blender texture nodes at arbitrary points through Geometry Nodes.

Used by tests (the numpy hash and, later, the Wave Noise node must reproduce
Blender's own values) and by ``bench/`` (Blender's Noise and Gabor textures as
speed peers).  Works in background Blender and in the ``bpy`` module.

A point-cloud mesh whose vertices are the query points gets a Geometry Nodes
modifier; the node tree computes a float field from the Position and stores it
as a named point attribute, which is read back from the evaluated mesh.
"""
from __future__ import annotations

from typing import Callable

import bpy
import numpy as np

__all__ = ["evaluate_field", "white_noise_node_values"]

#: builder(tree, position_socket) -> float output socket
FieldBuilder = Callable[[bpy.types.NodeTree, bpy.types.NodeSocket], bpy.types.NodeSocket]


def evaluate_field(points: np.ndarray, build: FieldBuilder, w: np.ndarray | None = None,
                   name: str = "omninoise_eval") -> np.ndarray:
    """Evaluate a node-built float field at ``points``.

    points: float32 (P, 3) positions; w: optional float32 (P,) stored as the point
    attribute ``w`` (read it with a Named Attribute node).  Returns float32 (P,).
    """
    pts = np.ascontiguousarray(points, dtype=np.float32).reshape(-1, 3)
    mesh = bpy.data.meshes.new(name)
    mesh.vertices.add(len(pts))
    mesh.vertices.foreach_set("co", pts.ravel())
    if w is not None:
        attr = mesh.attributes.new("w", "FLOAT", "POINT")
        attr.data.foreach_set("value", np.ascontiguousarray(w, dtype=np.float32).ravel())
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    tree = bpy.data.node_groups.new(name, "GeometryNodeTree")
    try:
        tree.interface.new_socket("Geometry", in_out="INPUT", socket_type="NodeSocketGeometry")
        tree.interface.new_socket("Geometry", in_out="OUTPUT", socket_type="NodeSocketGeometry")
        gin = tree.nodes.new("NodeGroupInput")
        gout = tree.nodes.new("NodeGroupOutput")
        pos = tree.nodes.new("GeometryNodeInputPosition")
        store = tree.nodes.new("GeometryNodeStoreNamedAttribute")
        store.data_type = "FLOAT"
        store.domain = "POINT"
        store.inputs["Name"].default_value = "value"
        tree.links.new(gin.outputs[0], store.inputs["Geometry"])
        tree.links.new(build(tree, pos.outputs["Position"]), store.inputs["Value"])
        tree.links.new(store.outputs["Geometry"], gout.inputs[0])
        obj.modifiers.new(name, "NODES").node_group = tree
        evaluated = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
        emesh = evaluated.to_mesh()
        out = np.empty(len(pts), dtype=np.float32)
        emesh.attributes["value"].data.foreach_get("value", out)
        evaluated.to_mesh_clear()
        return out
    finally:
        bpy.data.objects.remove(obj)
        bpy.data.meshes.remove(mesh)
        bpy.data.node_groups.remove(tree)


def white_noise_node_values(xyzw: np.ndarray) -> np.ndarray:
    """Blender's White Noise Texture (4D, Value output) at float32 (P, 4) inputs."""
    xyzw = np.asarray(xyzw, dtype=np.float32).reshape(-1, 4)

    def build(tree, position):
        attr = tree.nodes.new("GeometryNodeInputNamedAttribute")
        attr.data_type = "FLOAT"
        attr.inputs["Name"].default_value = "w"
        wn = tree.nodes.new("ShaderNodeTexWhiteNoise")
        wn.noise_dimensions = "4D"
        tree.links.new(position, wn.inputs["Vector"])
        tree.links.new(attr.outputs["Attribute"], wn.inputs["W"])
        return wn.outputs["Value"]

    return evaluate_field(xyzw[:, :3], build, w=xyzw[:, 3])
