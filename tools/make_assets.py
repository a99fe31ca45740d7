"""Build the asset library the extension ships: blender_addon/assets/omninoise_assets.blend, its catalogs and the
previews, and the README's sheet of them (docs/img/assets.png).

    .venv-bpy42/bin/python -m tools.make_assets

Run it with the oldest supported Blender's bpy (4.2): every newer Blender opens a file an older one saved. The
materials read object positions, so they need no UV map; each is rendered in Cycles on a sphere (the cloud on a
cube) for its preview. The Wave Noise groups are built from Blender's own nodes, so Cycles, EEVEE and Geometry
Nodes all render them, and they carry their settings, so the Wave Noise panel edits them once appended.
"""
from __future__ import annotations

import os
import shutil
import sys
import tempfile

import bpy
import numpy as np

from omninoise import blender_addon
from omninoise.blender_addon import solid_ui, wave_ui
from omninoise.blender_addon.compat import ensure_node_tree
from omninoise.blender_addon.wave_nodes import add_wave_node
from omninoise.export.atomic import atomic_path

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
FOLDER = os.path.join(ROOT, "blender_addon", "assets")
BLEND = os.path.join(FOLDER, "omninoise_assets.blend")
SHEET = os.path.join(ROOT, "docs", "img", "assets.png")
PREVIEW = 256

#: catalog path -> a fixed UUID (the catalog file and every asset in it agree run after run)
CATALOGS = {"OmniNoise/Materials": "6b7c0f0e-5f3a-4a52-9d0e-3f8a2d6c1a01",
            "OmniNoise/Volumes": "6b7c0f0e-5f3a-4a52-9d0e-3f8a2d6c1a02",
            "OmniNoise/Node Groups": "6b7c0f0e-5f3a-4a52-9d0e-3f8a2d6c1a03"}


def _props(tree, **values):
    """Set a Wave Noise tree's settings (the panel's properties) and rebuild it once, from Blender's nodes."""
    p = tree.omninoise_wave
    p.implementation = "NODES"
    for k, v in values.items():
        setattr(p, k, v)
    wave_ui.rebuild(p, bpy.context)
    assert not p.error, p.error
    return tree


def _ramp(nt, stops, x=-300):
    ramp = nt.nodes.new("ShaderNodeValToRGB")
    ramp.location = (x, 0)
    els = ramp.color_ramp.elements
    while len(els) < len(stops):
        els.new(0.5)
    for e in els:
        e.position = 1.0
    for i, (pos, _) in enumerate(stops):
        els[i].position = pos
    for e, (_, col) in zip(sorted(els, key=lambda e: e.position), stops):
        e.color = (*col, 1.0)
    return ramp


def _material(name: str):
    mat = bpy.data.materials.new(name)
    nt = ensure_node_tree(mat)
    bsdf = next(n for n in nt.nodes if n.type == "BSDF_PRINCIPLED")
    return mat, nt, bsdf


def _object_positions(nt, x=-900):
    tc = nt.nodes.new("ShaderNodeTexCoord")
    tc.location = (x, 0)
    return tc.outputs["Object"]


def _wave_material(name, tree, stops, roughness, bump=0.0, output="Value", value_range=(-1.5, 1.5)):
    """A material whose Base Color is ``stops`` over the group's ``output``, mapped from ``value_range`` to the
    ramp's 0 to 1 (wave noise spreads about -1.5 to 1.5; a cell code is 0 to 1)."""
    mat, nt, bsdf = _material(name)
    node = add_wave_node(nt, tree, (-900, 0))
    nt.links.new(_object_positions(nt, -1200), node.inputs["Vector"])
    rng = nt.nodes.new("ShaderNodeMapRange")
    rng.location = (-600, 0)
    rng.inputs["From Min"].default_value, rng.inputs["From Max"].default_value = value_range
    nt.links.new(node.outputs[output], rng.inputs["Value"])
    ramp = _ramp(nt, stops)
    nt.links.new(rng.outputs["Result"], ramp.inputs["Fac"])
    nt.links.new(ramp.outputs["Color"], bsdf.inputs["Base Color"])
    bsdf.inputs["Roughness"].default_value = roughness
    if bump:
        b = nt.nodes.new("ShaderNodeBump")
        b.location = (-300, -300)
        b.inputs["Strength"].default_value = bump
        nt.links.new(node.outputs[output], b.inputs["Height"])
        nt.links.new(b.outputs["Normal"], bsdf.inputs["Normal"])
    return mat


def marble():
    tree = _props(wave_ui.new_wave_node_tree("Marble Veins", "ShaderNodeTree"), dimensions="3", spectrum="fractal",
                  fmin=0.8, fmax=10.0, exponent=1.3, directions=16, seed=3)
    return _wave_material("Wave Noise Marble", tree,
                          [(0.0, (0.9, 0.89, 0.87)), (0.47, (0.93, 0.92, 0.9)), (0.5, (0.35, 0.35, 0.38)),
                           (0.53, (0.93, 0.92, 0.9)), (1.0, (0.82, 0.81, 0.8))], 0.15)


def veined_stone():
    tree = _props(wave_ui.new_wave_node_tree("Stone", "ShaderNodeTree"), dimensions="3", spectrum="fractal",
                  fmin=1.5, fmax=16.0, exponent=1.0, directions=16, seed=7)
    return _wave_material("Veined Stone", tree,
                          [(0.0, (0.12, 0.11, 0.1)), (0.47, (0.2, 0.19, 0.17)), (0.5, (0.85, 0.83, 0.78)),
                           (0.53, (0.2, 0.19, 0.17)), (1.0, (0.1, 0.1, 0.09))], 0.45, bump=0.2)


def cellular_tiles():
    tree = wave_ui.new_cellular_node_tree("Tiles", "ShaderNodeTree")
    _props(tree, cell_size=0.35, seed=5)
    return _wave_material("Cellular Tiles", tree,
                          [(0.0, (0.45, 0.2, 0.12)), (0.5, (0.65, 0.35, 0.2)), (1.0, (0.8, 0.55, 0.35))], 0.6,
                          bump=0.3, output="Cell", value_range=(0.0, 1.0))


def cloud_volume(folder: str):
    """A Volume object reading a baked OpenVDB cloud: a wave noise volume through the clouds transfer function
    (``omninoise bake``; a live procedural volume shader would be exact but renders minutes slower in the Cycles
    of Blender 5.0 and later), with a Principled Volume material reading its density and color. Blender reads a
    volume's grids from its file only (a packed copy is not read), so ``build`` ships ``cloud.vdb`` beside the
    .blend and the volume names it by a relative path."""
    import subprocess

    job = os.path.join(folder, "cloud.toml")
    with open(job, "w", encoding="utf-8") as fh:
        fh.write('[[bake]]\nname = "cloud"\noutput = "cloud.vdb"\nresolution = [64, 64, 64]\n'
                 'bounds = [[-1, -1, -1], [1, 1, 1]]\ntransfer = "clouds"\nhalf = true\n'
                 '[bake.source]\nkind = "wave"\ndim = 3\nseed = 11\ndirections = 16\n'
                 'spectrum = {kind = "fractal", fmin = 0.5, fmax = 8.0, exponent = 1.2}\n')
    python = os.path.join(ROOT, ".venv", "bin", "python")      # the bake writes OpenVDB (bpy 4.2 has no writer)
    subprocess.run([python, "-m", "omninoise", "bake", job, "--quiet", "--force"], check=True, cwd=ROOT)
    vol = bpy.data.volumes.new("Cloud Volume")
    vol.filepath = os.path.join(folder, "cloud.vdb")
    vol.grids.load()
    mat = bpy.data.materials.new("Cloud Volume")
    nt = ensure_node_tree(mat)
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    pv = nt.nodes.new("ShaderNodeVolumePrincipled")
    pv.location = (-300, 0)
    attr = nt.nodes.new("ShaderNodeAttribute")
    attr.attribute_name, attr.location = "color", (-600, 0)
    nt.links.new(attr.outputs["Color"], pv.inputs["Color"])
    pv.inputs["Density Attribute"].default_value = "density"
    pv.inputs["Density"].default_value = 10.0       # the clouds ramp's density, thickened for a 2-unit cloud
    pv.inputs["Anisotropy"].default_value = 0.3
    nt.links.new(pv.outputs["Volume"], out.inputs["Volume"])
    vol.materials.append(mat)
    return bpy.data.objects.new("Cloud Volume", vol)


def neural_blend():
    p = bpy.context.scene.omninoise_neural
    p.swatches.clear()
    for _ in range(4):
        bpy.ops.omninoise.swatch_add()
    for sw, name in zip(p.swatches, ("cells_f1", "perlin", "spots", "damascus")):
        sw.noise = name
    p.mode, p.size, p.steps, p.seed, p.name, p.add_node, p.save = "CORNERS", 256, 10, 0, "Neural Blend", False, "NONE"
    assert bpy.ops.omninoise.neural_bake() == {"FINISHED"}
    ima = bpy.data.images["Neural Blend"]
    mat, nt, bsdf = _material("Neural Noise Blend")
    tex = nt.nodes.new("ShaderNodeTexImage")
    tex.image, tex.projection, tex.projection_blend, tex.location = ima, "BOX", 0.2, (-600, 0)
    nt.links.new(_object_positions(nt), tex.inputs["Vector"])
    ramp = _ramp(nt, [(0.0, (0.05, 0.12, 0.08)), (0.5, (0.3, 0.45, 0.2)), (1.0, (0.85, 0.9, 0.6))])
    nt.links.new(tex.outputs["Color"], ramp.inputs["Fac"])
    nt.links.new(ramp.outputs["Color"], bsdf.inputs["Base Color"])
    return mat


def solid_tile():
    p = bpy.context.scene.omninoise_solid
    p.source, p.image = "IMAGE", bpy.data.images.load(os.path.join(ROOT, "data", "exemplars", "brick.png"))
    p.tile, p.seed, p.name, p.scale = 128, 0, "Brick", 2.0
    assert bpy.ops.omninoise.solid_tileable() == {"FINISHED"}
    ima = bpy.data.images["Brick Tile"]
    bpy.data.images.remove(p.image)
    mat, nt, bsdf = _material("Solid Texture Brick")
    solid_ui._project_tile(nt, ima, solid_ui.tile_repeats(2.0, 128), world=False)
    nt.links.new(nt.nodes["OmniNoise Tile"].outputs["Color"], bsdf.inputs["Base Color"])
    bsdf.inputs["Roughness"].default_value = 0.8
    return mat


def procedural(name: str, photo: str, kinds: tuple):
    """A material drawing a procedural solid of ``kinds`` fitted to ``photo`` (a path under the repository) live
    from its node group, in object space; the joints of cells and bricks sunk by their Gap Mask."""
    from omninoise.backend.solid.procedural.fit import ProceduralConfig, fit_procedural
    from omninoise.blender_addon.procedural_nodes import add_procedural_node, build_procedural_group
    from omninoise.export import read_rgb

    field = fit_procedural(read_rgb(os.path.join(ROOT, photo)), ProceduralConfig(families=kinds)).field
    mat, nt, bsdf = _material(name)
    node = add_procedural_node(nt, build_procedural_group(field, name=name), (-600, 0))
    nt.links.new(node.outputs["Color"], bsdf.inputs["Base Color"])
    bsdf.inputs["Roughness"].default_value = 0.6
    if "Gap Mask" in node.outputs:
        b = nt.nodes.new("ShaderNodeBump")
        b.location, b.invert = (-300, -300), True
        b.inputs["Strength"].default_value = 0.4
        nt.links.new(node.outputs["Gap Mask"], b.inputs["Height"])
        nt.links.new(b.outputs["Normal"], bsdf.inputs["Normal"])
    return mat


def _procedural(name, photo, kinds):
    return lambda: procedural(name, photo, kinds)


_EDIT = "; its sizes, turbulence and seed are the node group's inputs"
#: (builder, catalog, description, tags, preview shape)
MATERIALS = [
    (marble, "OmniNoise/Materials", "White marble with grey veins that run on through the object (wave noise)",
     ["marble", "stone", "wave noise"], "sphere"),
    (veined_stone, "OmniNoise/Materials", "Dark stone crossed by thin light veins (wave noise)",
     ["stone", "veins", "wave noise"], "sphere"),
    (cellular_tiles, "OmniNoise/Materials", "Irregular tiles cut by random planes (wave cellular noise)",
     ["tiles", "cells", "wave noise"], "sphere"),
    (cloud_volume, "OmniNoise/Volumes", "A cloud two units across: fractal wave noise baked through the clouds "
     "transfer function into OpenVDB (density and color)", ["cloud", "volume", "wave noise"], "volume"),
    (neural_blend, "OmniNoise/Materials", "Four neural noise classes blended across a baked image (cells, "
     "Perlin, spots, Damascus), projected without UVs", ["neural noise", "blend"], "sphere"),
    (solid_tile, "OmniNoise/Materials", "A seamless brick tile made from a photo (data/exemplars/brick.png, CC0), "
     "projected without UVs", ["brick", "solid texture", "photo"], "sphere"),
    (_procedural("Procedural Brick Wall", "data/photos/val/brick__tex_trak_trak4_brick2a.jpg", ("bonds",)),
     "OmniNoise/Materials", "Bricks in a running bond whose courses run on round corners: a procedural solid fitted "
     "to a photo (trak4_brick2a by Georges Grondin, Expat licence)" + _EDIT, ["brick", "procedural solid"], "sphere"),
    (_procedural("Procedural Tile Grid", "data/structured/tile__tile03.jpg", ("bonds",)),
     "OmniNoise/Materials", "Square tiles stacked in a grid, in 3D: a procedural solid fitted to a photo (ufoai "
     "tile03, public domain)" + _EDIT, ["tiles", "procedural solid"], "sphere"),
    (_procedural("Procedural Wood Grain", "data/exemplars/wood.png", ("layers",)),
     "OmniNoise/Materials", "Straight-grained wood whose grain runs through the object: a procedural solid fitted "
     "to the project's generated wood exemplar" + _EDIT, ["wood", "grain", "procedural solid"], "sphere"),
]


def _mark(idb, catalog: str, description: str, tags: list) -> None:
    idb.asset_mark()
    d = idb.asset_data
    d.catalog_id = CATALOGS[catalog]
    d.description = description
    d.author = "OmniNoise"
    for t in tags:
        d.tags.new(t, skip_if_exists=True)


def _preview_scene(shape: str):
    """A scene with a camera, a sun and a grey world around a sphere -> (scene, sphere); for "volume", no subject
    (the caller links the asset object in) -> (scene, None)."""
    sc = bpy.data.scenes.new(f"Preview {shape}")
    sc.render.engine = "CYCLES"
    sc.cycles.samples, sc.cycles.use_denoising = 32, False
    sc.render.resolution_x = sc.render.resolution_y = PREVIEW
    sc.render.film_transparent = False
    sc.view_settings.view_transform = "Standard"
    world = bpy.data.worlds.new(f"Preview {shape}")
    ensure_node_tree(world).nodes["Background"].inputs["Color"].default_value = (0.18, 0.18, 0.2, 1.0)
    sc.world = world
    if shape == "volume":       # the subject is the asset object itself, linked in by the caller
        obj = None
    else:
        import bmesh

        me = bpy.data.meshes.new("sphere")
        bm = bmesh.new()
        bmesh.ops.create_uvsphere(bm, u_segments=64, v_segments=32, radius=1.0)
        bm.to_mesh(me)
        bm.free()
        for f in me.polygons:
            f.use_smooth = True
    if shape != "volume":
        obj = bpy.data.objects.new("Subject", me)
        sc.collection.objects.link(obj)
    cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    cam.location, cam.rotation_euler = (0.0, -4.2, 1.6), (np.radians(70), 0.0, 0.0)
    cam.data.lens = 50
    sc.collection.objects.link(cam)
    sc.camera = cam
    sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", "SUN"))
    sun.data.energy, sun.rotation_euler = 3.0, (np.radians(50), 0.0, np.radians(30))
    sc.collection.objects.link(sun)
    return sc, obj


def _render_preview(sc, path: str) -> None:
    sc.render.filepath = path
    sc.render.image_settings.file_format = "PNG"
    with bpy.context.temp_override(scene=sc):
        bpy.ops.render.render(write_still=True, scene=sc.name)


def _set_preview(idb, png: str) -> None:
    with bpy.context.temp_override(id=idb):
        bpy.ops.ed.lib_id_load_custom_preview(filepath=png)


def _catalog_file() -> str:
    lines = ["# This is an Asset Catalog Definition file for Blender.", "#",
             "# Empty lines and lines starting with `#` will be ignored.",
             "# The first non-ignored line should be the version indicator.",
             '# Other lines are of the format "UUID:catalog/path/for/assets:simple catalog name"', "",
             "VERSION 1", ""]
    lines += [f"{u}:{path}:{path.replace('/', '-')}" for path, u in CATALOGS.items()]
    return "\n".join(lines) + "\n"


def build(out_blend: str = BLEND, sheet: str | None = SHEET) -> list:
    """Build every asset into ``out_blend`` (its catalog file beside it); the names of the assets."""
    bpy.ops.wm.read_homefile(use_empty=True)
    blender_addon.register()
    tmp = tempfile.mkdtemp(prefix="omninoise_assets_")
    bpy.context.scene.omninoise_solid.folder = bpy.context.scene.omninoise_neural.folder = tmp + os.sep
    names, pngs = [], []
    scenes = {}
    for builder, catalog, description, tags, shape in MATERIALS:
        if shape == "volume":       # an object asset: rendered on its own
            idb = builder(tmp)
            if "volume" not in scenes:
                scenes["volume"] = _preview_scene("volume")
            sc, _ = scenes["volume"]
            sc.collection.objects.link(idb)
        else:
            idb = builder()
            if shape not in scenes:
                scenes[shape] = _preview_scene(shape)
            sc, obj = scenes[shape]
            obj.data.materials.clear()
            obj.data.materials.append(idb)
        _mark(idb, catalog, description, tags)
        png = os.path.join(tmp, f"{len(pngs)}.png")
        _render_preview(sc, png)
        _set_preview(idb, png)
        if shape == "volume":
            sc.collection.objects.unlink(idb)
        names.append(idb.name)
        pngs.append((idb.name, png))
        print(f"asset {idb.name}: rendered", flush=True)
    for tree, description in ((wave_ui.new_wave_node_tree("Wave Noise", "ShaderNodeTree"),
                               "Wave noise: a sum of randomly oriented waves (edit it in the Wave Noise panel)"),
                              (wave_ui.new_cellular_node_tree("Wave Cellular", "ShaderNodeTree"),
                               "Cellular wave noise: cells cut by random planes")):
        _props(tree)
        _mark(tree, "OmniNoise/Node Groups", description, ["wave noise", "node group"])
        mat = bpy.data.materials.new(f".preview {tree.name}")
        nt = ensure_node_tree(mat)
        bsdf = next(n for n in nt.nodes if n.type == "BSDF_PRINCIPLED")
        node = add_wave_node(nt, tree, (-600, 0))
        nt.links.new(_object_positions(nt), node.inputs["Vector"])
        nt.links.new(node.outputs[0], bsdf.inputs["Base Color"])
        sc, obj = scenes["sphere"]
        obj.data.materials.clear()
        obj.data.materials.append(mat)
        png = os.path.join(tmp, f"{len(pngs)}.png")
        _render_preview(sc, png)
        _set_preview(tree, png)
        names.append(tree.name)
        pngs.append((tree.name, png))
        print(f"asset {tree.name}: rendered", flush=True)
    # keep only the assets and what they use: preview scenes, their objects, worlds and helper materials go
    for sc, _ in scenes.values():
        for o in list(sc.collection.objects):
            if o.asset_data is None:
                bpy.data.objects.remove(o)
        bpy.data.scenes.remove(sc)
    for mat in list(bpy.data.materials):
        if mat.name.startswith(".preview"):
            bpy.data.materials.remove(mat)
    for idb in list(bpy.data.materials) + list(bpy.data.node_groups) + list(bpy.data.objects):
        if idb.asset_data is not None:
            idb.use_fake_user = True
    bpy.data.orphans_purge(do_local_ids=True, do_linked_ids=True, do_recursive=True)
    for img in bpy.data.images:
        if img.packed_file is None:
            img.pack()            # images travel inside the .blend
    folder = os.path.dirname(os.path.abspath(out_blend))
    os.makedirs(folder, exist_ok=True)
    for vol in bpy.data.volumes:  # OpenVDB files beside it, named relatively (remapped when saved)
        name = os.path.basename(vol.filepath)
        with atomic_path(os.path.join(folder, name)) as part:
            shutil.copyfile(bpy.path.abspath(vol.filepath), part)
        vol.filepath = os.path.join(folder, name)
    with open(os.path.join(os.path.dirname(out_blend), "blender_assets.cats.txt"), "w", encoding="utf-8") as fh:
        fh.write(_catalog_file())
    bpy.context.preferences.filepaths.save_version = 0          # no .blend1 backup beside the shipped file
    bpy.ops.wm.save_as_mainfile(filepath=out_blend, compress=True, copy=True, relative_remap=True)
    if sheet:
        _sheet(pngs, sheet)
    blender_addon.unregister()
    bpy.ops.wm.read_homefile(use_empty=True)      # free the volume's grids before their folder goes
    shutil.rmtree(tmp, ignore_errors=True)
    return names


def _sheet(pngs: list, path: str) -> None:
    """The previews side by side, four to a row, as one PNG (numpy and Blender's image API only)."""
    from omninoise.export.images import write_png

    tiles = []
    for name, png in pngs:
        ima = bpy.data.images.load(png)
        w, h = ima.size
        px = np.empty(w * h * 4, np.float32)
        ima.pixels.foreach_get(px)
        tiles.append(np.flipud(px.reshape(h, w, 4)[..., :3]))
        bpy.data.images.remove(ima)
    cols = 4
    rows = -(-len(tiles) // cols)
    sheet = np.empty((rows * PREVIEW, cols * PREVIEW, 3), np.float32)
    sheet[:] = tiles[0][0, 0]           # a free cell is the previews' background
    for i, t in enumerate(tiles):
        r, c = divmod(i, cols)
        sheet[r * PREVIEW:(r + 1) * PREVIEW, c * PREVIEW:(c + 1) * PREVIEW] = t
    write_png(path, np.round(np.clip(sheet, 0, 1) * 255).astype(np.uint8))


if __name__ == "__main__":
    got = build()
    print(f"wrote {os.path.relpath(BLEND, ROOT)}: {', '.join(got)} ({os.path.getsize(BLEND) / 2 ** 20:.1f} MiB)")
    sys.stdout.flush()
    os._exit(0)     # bpy 4.2.23 crashes at interpreter exit once an add-on has been unregistered
    # (tests/blender_scripts/bpy42_exit_crash.py); everything is written by now
