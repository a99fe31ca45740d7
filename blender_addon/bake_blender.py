"""Blender data for bakes: Color Ramp <-> transfer function, Volume objects, images.

Main-thread helpers only; the bakes themselves run in :mod:`.tasks` workers.
"""
from __future__ import annotations

import os

import bpy
from mathutils import Vector

from .. import backend
from .compat import ensure_node_tree

__all__ = ["ramp_node", "transfer_from_color_ramp", "apply_preset", "set_ramp", "world_bounds", "load_volume",
           "load_image", "RAMP_GROUP"]

RAMP_GROUP = ".OmniNoise Ramp"  # leading dot: hidden from the node-group lists


def ramp_node(create: bool = True):
    """The ShaderNodeValToRGB whose Color Ramp the bake panel edits (in a hidden node group)."""
    tree = bpy.data.node_groups.get(RAMP_GROUP)
    if tree is None:
        if not create:
            return None
        tree = bpy.data.node_groups.new(RAMP_GROUP, "ShaderNodeTree")
        tree.use_fake_user = True
    node = tree.nodes.get("Ramp")
    if node is None:
        if not create:
            return None
        node = tree.nodes.new("ShaderNodeValToRGB")
        node.name = "Ramp"
        apply_preset(node.color_ramp, "clouds")
    return node


def transfer_from_color_ramp(ramp, value_range, density_scale: float = 1.0, temperature=()):
    """A :class:`backend.transfer.TransferFunction` equal to a Blender Color Ramp.

    Linear, constant and ease RGB ramps convert stop by stop (exact); B-spline,
    cardinal and HSV/HSL ramps are sampled through Blender's own evaluate() at
    257 positions and interpolated linearly between them.
    """
    TF = backend.transfer.TransferFunction
    mode = ramp.interpolation
    if mode in ("LINEAR", "CONSTANT", "EASE") and ramp.color_mode == "RGB":
        els = sorted(ramp.elements, key=lambda e: e.position)
        stops = tuple((float(e.position), tuple(float(c) for c in e.color)) for e in els)
        interp = mode.lower()
    else:
        stops = tuple((i / 256.0, tuple(float(c) for c in ramp.evaluate(i / 256.0))) for i in range(257))
        interp = "linear"
    return TF(stops=stops, range=tuple(float(v) for v in value_range), interpolation=interp,
              density_scale=float(density_scale), temperature=tuple(temperature)).validate()


def apply_preset(ramp, name: str) -> "backend.transfer.TransferFunction":
    """Set a Blender Color Ramp to preset ``name``; returns the preset."""
    return set_ramp(ramp, backend.transfer.preset(name))


def set_ramp(ramp, tf) -> "backend.transfer.TransferFunction":
    """Set a Blender Color Ramp to the stops and interpolation of transfer function ``tf``; returns ``tf``."""
    ramp.color_mode = "RGB"
    ramp.interpolation = tf.interpolation.upper()
    els = ramp.elements
    while len(els) > len(tf.stops):
        els.remove(els[-1])
    while len(els) < len(tf.stops):
        els.new(1.0)
    # Blender re-sorts elements whenever a position changes: park them all at 1, then set ascending
    for e in els:
        e.position = 1.0
    for i, (p, _) in enumerate(tf.stops):
        els[i].position = p
    for e, (_, c) in zip(sorted(els, key=lambda e: e.position), tf.stops):
        e.color = c
    return tf


def world_bounds(obj) -> tuple:
    """World-space axis-aligned bounds of an object: ((x0, y0, z0), (x1, y1, z1))."""
    pts = [obj.matrix_world @ Vector(c) for c in obj.bound_box]
    lo = tuple(min(p[i] for p in pts) for i in range(3))
    hi = tuple(max(p[i] for p in pts) for i in range(3))
    return lo, hi


def _file_path(path: str) -> str:
    """Relative to the .blend when it is saved (files travel with the project), else absolute."""
    path = os.path.abspath(path)
    if bpy.data.filepath:
        try:
            return bpy.path.relpath(path)
        except ValueError:  # another drive on Windows
            return path
    return path


def _volume_material(name: str, temperature: bool):
    mat = bpy.data.materials.get(name) or bpy.data.materials.new(name)
    ensure_node_tree(mat)
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    out.location = (300, 0)
    pv = nt.nodes.new("ShaderNodeVolumePrincipled")
    pv.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    pv.inputs["Color Attribute"].default_value = "color"
    pv.inputs["Density"].default_value = 1.0
    pv.inputs["Density Attribute"].default_value = "density"
    pv.inputs["Temperature Attribute"].default_value = "temperature"
    pv.inputs["Blackbody Intensity"].default_value = 1.0 if temperature else 0.0
    nt.links.new(pv.outputs["Volume"], out.inputs["Volume"])
    return mat


def load_volume(name: str, paths: list, frames, temperature: bool, collection=None):
    """A Volume object reading the baked .vdb (or numbered sequence), with a Principled Volume material.

    Re-baking under the same name reloads the files in place and keeps the object.
    """
    vol = bpy.data.volumes.get(name) or bpy.data.volumes.new(name)
    vol.filepath = _file_path(paths[0])
    vol.is_sequence = False  # read the first file now, so a bad file fails here with Blender's reason
    vol.grids.unload()
    vol.grids.load()
    if vol.grids.error_message:
        raise RuntimeError(f"Blender could not read {paths[0]}: {vol.grids.error_message}")
    if frames is not None:
        start, end = int(frames[0]), int(frames[1])
        vol.is_sequence = True
        vol.frame_start = start
        vol.frame_duration = end - start + 1
        vol.frame_offset = start - 1  # file numbers equal scene frames
        vol.sequence_mode = "EXTEND"  # hold the first / last file outside the range
    mat = _volume_material(f"OmniNoise {name}", temperature)
    if not vol.materials:
        vol.materials.append(mat)
    else:
        vol.materials[0] = mat
    obj = bpy.data.objects.get(name)
    if obj is None or obj.data != vol:
        obj = bpy.data.objects.new(name, vol)
        (collection or bpy.context.scene.collection).objects.link(obj)
    return obj


def load_image(name: str, paths: list, frames, raw: bool, target_material=None):
    """The baked image as a datablock, wired into an Image Texture node.

    The node goes into ``target_material`` (the active object's material) when
    given, else into a new material ``OmniNoise <name>`` feeding Base Color.
    """
    img = bpy.data.images.get(name)
    path = _file_path(paths[0])
    if img is None or img.filepath != path:
        img = bpy.data.images.load(os.path.abspath(paths[0]), check_existing=False)
        img.name = name
        img.filepath = path
    else:
        img.reload()
    if raw:
        img.colorspace_settings.name = "Non-Color"
    if frames is not None:
        img.source = "SEQUENCE"
    mat = target_material
    if mat is None:
        mat = bpy.data.materials.get(f"OmniNoise {name}") or bpy.data.materials.new(f"OmniNoise {name}")
        ensure_node_tree(mat)
    nt = mat.node_tree
    node = next((n for n in nt.nodes if n.type == "TEX_IMAGE" and n.image == img), None)
    if node is None:
        node = nt.nodes.new("ShaderNodeTexImage")
        node.image = img
        node.location = (-400, 300)
        bsdf = next((n for n in nt.nodes if n.type == "BSDF_PRINCIPLED"), None)
        if bsdf is not None and target_material is None:
            nt.links.new(node.outputs["Color"], bsdf.inputs["Base Color"])
    if frames is not None:
        iu = node.image_user
        iu.frame_start = int(frames[0])
        iu.frame_offset = int(frames[0]) - 1
        iu.frame_duration = int(frames[1]) - int(frames[0]) + 1
        iu.use_auto_refresh = True
    nt.nodes.active = node
    return img, mat, node


def output_folder(path: str) -> str:
    """An absolute, existing output folder for a panel path ('//' = beside the .blend); a SettingError naming
    the folder where it is a file or cannot be made."""
    from .preferences import cache_dir

    if path.startswith("//") and not bpy.data.filepath:
        base = cache_dir()
        path = os.path.join(base, path[2:])
    folder = bpy.path.abspath(path) if path else cache_dir()
    folder = os.path.abspath(folder)
    if os.path.exists(folder) and not os.path.isdir(folder):
        raise backend.SettingError("folder", f"{folder} is a file, not a folder")
    try:
        os.makedirs(folder, exist_ok=True)
    except OSError as exc:
        raise backend.SettingError("folder", f"cannot make {folder}: {exc.strerror or exc}") from None
    return folder
