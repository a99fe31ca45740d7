"""The scene the asset tests render each shipped asset in (Cycles here, EEVEE in a fresh Python)."""
import os
import time

import bpy


def _shape(kind: str):
    import bmesh

    me = bpy.data.meshes.new(kind)
    bm = bmesh.new()
    bmesh.ops.create_uvsphere(bm, u_segments=32, v_segments=16, radius=1.0)
    bm.to_mesh(me)
    bm.free()
    return me


def render_assets(blend: str, out: str, res: int, engine: str) -> dict:
    """Append every material, node group and object of ``blend`` and render each (a material on a sphere, a node
    group's first output as emission, an object as it is) at ``res`` px with ``engine`` into ``out``/NAME.png;
    {name: seconds}."""
    bpy.ops.wm.read_homefile(use_empty=True)
    with bpy.data.libraries.load(blend, assets_only=True) as (src, dst):
        dst.materials, dst.node_groups, dst.objects = list(src.materials), list(src.node_groups), list(src.objects)
    sc = bpy.context.scene
    sc.render.engine = engine
    if engine == "CYCLES":
        sc.cycles.samples, sc.cycles.use_denoising = 4, False
    else:
        sc.eevee.taa_render_samples = 4
    sc.render.resolution_x = sc.render.resolution_y = res
    sc.render.image_settings.file_format = "PNG"
    world = bpy.data.worlds.new("grey")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.2, 0.2, 0.2, 1.0)
    sc.world = world
    cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    cam.location, cam.rotation_euler = (0.0, -4.2, 0.0), (1.5708, 0.0, 0.0)
    sc.collection.objects.link(cam)
    sc.camera = cam
    sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", "SUN"))
    sun.rotation_euler = (0.8, 0.0, 0.5)
    sc.collection.objects.link(sun)
    subjects = [(mat.name, mat, "sphere") for mat in dst.materials]
    for group in dst.node_groups:
        mat = bpy.data.materials.new(f"show {group.name}")
        mat.use_nodes = True
        nt = mat.node_tree
        nt.nodes.clear()
        node = nt.nodes.new("ShaderNodeGroup")
        node.node_tree = group
        coords = nt.nodes.new("ShaderNodeTexCoord")
        emit = nt.nodes.new("ShaderNodeEmission")
        outp = nt.nodes.new("ShaderNodeOutputMaterial")
        nt.links.new(coords.outputs["Object"], node.inputs["Vector"])
        nt.links.new(node.outputs[0], emit.inputs["Strength"])
        nt.links.new(emit.outputs[0], outp.inputs["Surface"])
        subjects.append((group.name, mat, "sphere"))
    subjects += [(obj.name, obj, "object") for obj in dst.objects]
    times = {}
    for name, what, kind in subjects:
        if kind == "object":
            obj = what
        else:
            obj = bpy.data.objects.new(name, _shape(kind))
            obj.data.materials.append(what)
        sc.collection.objects.link(obj)
        sc.render.filepath = os.path.join(out, name + ".png")
        t0 = time.perf_counter()
        bpy.ops.render.render(write_still=True)
        times[name] = round(time.perf_counter() - t0, 2)
        sc.collection.objects.unlink(obj)
    return times
