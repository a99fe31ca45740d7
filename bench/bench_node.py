"""Cycles render time of a plane shaded by the Wave Noise node vs Blender's own textures.

Headless Cycles (CPU), orthographic camera on a plane filling the frame,
emission shader, R x R pixels, S samples; each shader is rendered once to
compile, then timed over ``--repeat`` renders (the minimum is kept).  Prints ns
per pixel-sample (from the difference between S and 2S samples, so set-up and
shader compilation cancel) and ratios against Blender's Gabor Texture (the built-in noise
nearest to wave noise: a sum of random waves), the node count of each built tree, and writes
docs/benchmarks/node.json with Blender's version (``docs/benchmarks.md`` shows it).  Two "floor"
rows time the cheapest trees any table-lookup wave node could be at 16
directions (see :func:`lookup_floor`): what Alg. 1 costs in SVM at the least.  The
"OSL:" rows render with Cycles' Open Shading Language, the Wave Noise group in its
OSL form (blender_addon/wave_osl.py), and Gabor under OSL for comparison.

    python -m bench node [--res 256] [--samples 4] [--repeat 2] [-o JSON]
"""
from __future__ import annotations

import argparse
import os
import sys
import time

import bpy
import numpy as np

from bench.stamp import DATA, stamp
from omninoise.backend import Spectrum, WaveSettings
from omninoise.blender_addon.compat import ensure_node_tree
from omninoise.blender_addon.wave_nodes import build_wave_group
from omninoise.export.atomic import write_json


def scene(res: int, samples: int, osl: bool = False):
    """A Cycles scene: a 2 x 2 plane filling an orthographic camera's R x R frame, with an empty material
    -> (scene, material).  Also the scene of the EEVEE test (tests/blender_scripts/eevee_wave.py)."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    sc.render.engine = "CYCLES"
    sc.cycles.device = "CPU"
    sc.cycles.shading_system = osl  # Open Shading Language: every shader of the scene runs as OSL
    sc.cycles.samples = samples
    sc.cycles.use_denoising = False
    sc.render.resolution_x = sc.render.resolution_y = res
    sc.render.resolution_percentage = 100
    mesh = bpy.data.meshes.new("plane")
    mesh.from_pydata([(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)], [], [(0, 1, 2, 3)])
    ob = bpy.data.objects.new("plane", mesh)
    sc.collection.objects.link(ob)
    cam = bpy.data.cameras.new("cam")
    cam.type = "ORTHO"
    cam.ortho_scale = 2.0
    co = bpy.data.objects.new("cam", cam)
    co.location = (0, 0, 3)
    sc.collection.objects.link(co)
    sc.camera = co
    mat = bpy.data.materials.new("m")
    ensure_node_tree(mat)
    ob.data.materials.append(mat)
    return sc, mat


def shade(mat, make):
    nt = mat.node_tree
    nt.nodes.clear()
    tc = nt.nodes.new("ShaderNodeTexCoord")
    em = nt.nodes.new("ShaderNodeEmission")
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    nt.links.new(em.outputs[0], out.inputs["Surface"])
    sock, count = make(nt)
    nt.links.new(tc.outputs["Object"], sock[0])
    nt.links.new(sock[1], em.inputs["Strength"])
    return count


def texture(kind, **props):
    def make(nt):
        n = nt.nodes.new(kind)
        for k, v in props.items():
            if k in n.inputs:
                n.inputs[k].default_value = v
            else:
                setattr(n, k, v)
        return (n.inputs["Vector"], n.outputs[0]), 1
    return make


def wave(k, implementation="nodes"):
    def make(nt):
        grp = build_wave_group(WaveSettings(dim=3, spectrum=Spectrum("gaussian", 2, 6), directions=k, seed=1),
                               implementation=implementation)
        n = nt.nodes.new("ShaderNodeGroup")
        n.node_tree = grp
        count = len(grp.nodes) + sum(len(g.node_tree.nodes) for g in grp.nodes if g.bl_idname == "ShaderNodeGroup")
        return (n.inputs["Vector"], n.outputs["Value"]), count
    return make


def lookup_floor(k: int, sliced: bool):
    """The cheapest table-lookup trees a wave node could be, for the floor of Alg. 1 in SVM.

    Per direction: dot(x, omega) -> multiply-add -> one unfiltered image lookup -> add
    (no slicing: 4 nodes).  ``sliced`` adds what any slicing needs at the least: one
    White Noise hash of the slice and a second lookup (+3 nodes), still without
    direction jitter, border position or blend weights.
    """
    def make(nt):
        rng = np.random.default_rng(1)
        img = bpy.data.images.new("floor table", 1024, 1, float_buffer=True, alpha=True)
        img.pixels.foreach_set(rng.random(4096).astype(np.float32))
        img.colorspace_settings.name = "Non-Color"
        entry = nt.nodes.new("NodeReroute")
        acc, count = None, 0

        def node(kind, **props):
            n = nt.nodes.new(kind)
            for key, v in props.items():
                setattr(n, key, v)
            return n

        def lookup(coord):
            t = node("ShaderNodeTexImage", image=img, interpolation="Closest")
            nt.links.new(coord, t.inputs["Vector"])
            return t.outputs["Color"]

        for _ in range(k):
            d = rng.normal(size=3)
            dot = node("ShaderNodeVectorMath", operation="DOT_PRODUCT")
            dot.inputs[1].default_value = tuple(d / np.linalg.norm(d))
            nt.links.new(entry.outputs[0], dot.inputs[0])
            ma = node("ShaderNodeMath", operation="MULTIPLY_ADD")
            ma.inputs[1].default_value, ma.inputs[2].default_value = 0.3, float(rng.random())
            nt.links.new(dot.outputs["Value"], ma.inputs[0])
            val = lookup(ma.outputs[0])
            count += 3
            if sliced:
                wn = node("ShaderNodeTexWhiteNoise", noise_dimensions="1D")
                nt.links.new(dot.outputs["Value"], wn.inputs["W"])
                c2 = node("ShaderNodeMath", operation="ADD")
                nt.links.new(ma.outputs[0], c2.inputs[0])
                nt.links.new(wn.outputs["Value"], c2.inputs[1])
                both = node("ShaderNodeMath", operation="ADD")
                nt.links.new(val, both.inputs[0])
                nt.links.new(lookup(c2.outputs[0]), both.inputs[1])
                val = both.outputs[0]
                count += 4
            if acc is None:
                acc = val
            else:
                add = node("ShaderNodeMath", operation="ADD")
                nt.links.new(acc, add.inputs[0])
                nt.links.new(val, add.inputs[1])
                acc = add.outputs[0]
                count += 1
        return (entry.inputs[0], acc), count
    return make


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--res", type=int, default=256)
    ap.add_argument("--samples", type=int, default=4)
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("-o", "--out", default=os.path.join(DATA, "node.json"))
    a = ap.parse_args(argv)
    # (name, tree maker, OSL shading system)
    cases = [
        ("Blender Noise detail 5", texture("ShaderNodeTexNoise", Detail=5.0, Scale=5.0), False),
        ("Blender Voronoi", texture("ShaderNodeTexVoronoi", Scale=5.0), False),
        ("Blender Wave Texture", texture("ShaderNodeTexWave", Scale=5.0, Distortion=2.0, Detail=2.0), False),
        ("Blender Gabor", texture("ShaderNodeTexGabor", Scale=5.0), False),
        ("Wave Noise 8 dirs", wave(8), False),
        ("Wave Noise 16 dirs", wave(16), False),
        ("Wave Noise 32 dirs", wave(32), False),
        ("floor 16: lookup only", lookup_floor(16, False), False),
        ("floor 16: 2 lookups+hash", lookup_floor(16, True), False),
        ("OSL: Blender Gabor", texture("ShaderNodeTexGabor", Scale=5.0), True),
        ("OSL: Wave Noise 8 dirs", wave(8, "osl"), True),
        ("OSL: Wave Noise 16 dirs", wave(16, "osl"), True),
        ("OSL: Wave Noise 32 dirs", wave(32, "osl"), True),
        ("OSL: Wave Noise 64 dirs", wave(64, "osl"), True),
    ]
    res = {}
    for name, make, osl in cases:
        times = {}
        for spp in (a.samples, 2 * a.samples):
            sc, mat = scene(a.res, spp, osl)
            nodes = shade(mat, make)
            bpy.ops.render.render()  # compile and warm up
            times[spp] = min(_timed() for _ in range(a.repeat))
        # per pixel-sample cost from the difference of S and 2S samples: scene set-up and shader
        # compilation (OSL's JIT) are paid once per render and cancel out; reported apart as set-up
        per = (times[2 * a.samples] - times[a.samples]) / (a.res * a.res * a.samples)
        res[name] = dict(ns_per_pixel_sample=round(per * 1e9, 1), nodes=nodes, osl=osl,
                         setup_s=round(times[a.samples] - per * a.res * a.res * a.samples, 3))
    for name, r in res.items():     # each against Gabor rendered as it is, by SVM or by OSL
        ref = res[("OSL: " if r["osl"] else "") + "Blender Gabor"]["ns_per_pixel_sample"]
        r["vs_gabor"] = round(r["ns_per_pixel_sample"] / ref, 2)
    print(f"Cycles CPU, {os.cpu_count()} cores, {a.res}^2 px, {a.samples} and {2 * a.samples} samples")
    print(f"  {'shader':26s} {'ns/px-sample':>12s} {'vs Gabor':>9s} {'nodes':>6s} {'set-up s':>9s}")
    for name, r in res.items():
        print(f"  {name:26s} {r['ns_per_pixel_sample']:12.1f} {r['vs_gabor']:8.2f}x {r['nodes']:6d}"
              f" {r['setup_s']:9.2f}")
    write_json(a.out, dict(stamp=stamp(), blender=bpy.app.version_string, res=a.res, samples=a.samples, results=res))
    return 0


def _timed() -> float:
    t = time.perf_counter()
    bpy.ops.render.render()
    return time.perf_counter() - t


if __name__ == "__main__":
    sys.exit(main())
