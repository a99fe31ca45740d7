"""Cycles render time of the procedural solids' node groups (blender_addon/procedural_nodes.py) against Blender's
own Wave Texture, the node artists build wood and marble from by hand.

The scene of ``python -m bench node`` (a plane filling an orthographic camera's R x R frame, emission shader, Cycles
on the CPU), one group per family read through its sRGB output (the ramp's colours, as the Wave Texture's Color is
read) with the settings of the parity tests (tests/blender/test_procedural_blender.py), each rendered once to
compile and then timed; nanoseconds per pixel-sample from the difference between S and 2S samples (set-up and
compilation cancel), the ratio to the Wave Texture, the node count (sub-groups included) and the seconds the group
took to build (the fastest of its builds). Bonds are timed in courses and in a herringbone, layers also with a tint
(backend/solid/procedural/tint.py: one more Wave Noise group), and each family also with its noises' amplitudes
(Turbulence, Grain, Detail, Tint) at 0, which Cycles folds away. The "OSL:" rows render with Cycles' Open Shading
Language, the groups' Wave Noise trees in their OSL form (one Script node each, as the groups take it there), each
against the Wave Texture rendered by OSL too. Writes docs/benchmarks/procedural_node.json, with Blender's version.

    python -m bench procedural-node [--res 128] [--samples 4] [--repeat 2]
"""
from __future__ import annotations

import argparse
import os
import sys
import time

import bpy  # noqa: F401  (the scene below is Blender's)
import numpy as np

from bench.bench_node import _timed, scene, shade, texture
from bench.stamp import DATA, stamp
from omninoise.backend.solid.procedural.field import ProceduralField
from omninoise.backend.solid.procedural.ramp import fit_ramp
from omninoise.backend.solid.procedural.tint import fit_tint
from omninoise.blender_addon.procedural_nodes import build_procedural_group
from omninoise.export.atomic import write_json

#: the families' settings (the parity tests')
PARAMS = {"rings": dict(spacing=0.13, tilt=0.4, azimuth=1.0, centre_u=0.3, centre_v=-0.5, grain=0.2),
          "layers": dict(spacing=0.21, tilt=1.2, azimuth=0.3, profile="tri"),
          "cells": dict(size=0.2, stretch=1.4, jitter=0.9, gap=0.08),
          "bonds": dict(length=0.4, height=0.13, offset=0.5, joint=0.15),
          "herringbone": dict(length=0.5, height=0.16, offset=0.3, joint=0.15, pattern="herringbone45")}


def procedural(case: str, noise: bool = True, tint: bool = False, form: str = "nodes"):
    """A group of the family ``case`` (a key of PARAMS); ``noise`` False: Turbulence, Grain, Detail and Tint at 0;
    ``tint``: with a tint (a random photo's, at 2 cycles per unit, as the parity tests draw it); ``form``: its Wave
    Noise groups' ("osl": rendered with Open Shading Language).  ``make.builds`` holds each build's seconds."""
    def make(nt):
        rng = np.random.default_rng(0)
        family = "bonds" if case == "herringbone" else case
        p = dict(PARAMS[case], turbulence=0.3, turb_freq=2.0, detail=0.2, flip=False)
        if not noise:
            p.update(turbulence=0.0, detail=0.0)
            if "grain" in p:
                p["grain"] = 0.0
        t = fit_tint(rng.uniform(0, 1, (32, 32, 3)), 2.0, 3) if tint else None
        f = ProceduralField(family, p, fit_ramp(np.linspace(-1, 2, 64), rng.uniform(0, 1, (16, 3))), seed=3, tint=t)
        t0 = time.perf_counter()
        grp = build_procedural_group(f, implementation=form)
        make.builds.append(time.perf_counter() - t0)
        n = nt.nodes.new("ShaderNodeGroup")
        n.node_tree = grp
        if tint and not noise:
            n.inputs["Tint"].default_value = 0.0

        def count(tree):
            return sum(1 + (count(x.node_tree) if x.bl_idname == "ShaderNodeGroup" else 0) for x in tree.nodes)

        return (n.inputs["Vector"], n.outputs["sRGB"]), count(grp)
    make.builds = []
    return make


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--res", type=int, default=128)
    ap.add_argument("--samples", type=int, default=4)
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("-o", "--out", default=os.path.join(DATA, "procedural_node.json"))
    a = ap.parse_args(argv)
    wave = texture("ShaderNodeTexWave", Scale=5.0, Distortion=2.0, Detail=2.0)
    cases = [("Blender Wave Texture", wave, False)]
    cases += [(f"Procedural {f}", procedural(f), False) for f in PARAMS]
    cases += [("Procedural layers, tinted", procedural("layers", tint=True), False)]
    cases += [(f"Procedural {f}, noises at 0", procedural(f, noise=False), False) for f in PARAMS
              if f != "herringbone"]
    cases += [("Procedural layers, tinted, noises at 0", procedural("layers", noise=False, tint=True), False)]
    cases += [("OSL: Blender Wave Texture", wave, True)]
    cases += [(f"OSL: Procedural {f}", procedural(f, form="osl"), True) for f in PARAMS]
    cases += [("OSL: Procedural layers, tinted", procedural("layers", tint=True, form="osl"), True)]
    res = {}
    for name, make, osl in cases:
        times = {}
        for spp in (a.samples, 2 * a.samples):
            sc, mat = scene(a.res, spp, osl=osl)
            nodes = shade(mat, make)
            bpy.ops.render.render()      # compile and warm up
            times[spp] = min(_timed() for _ in range(a.repeat))
        per = (times[2 * a.samples] - times[a.samples]) / (a.res * a.res * a.samples)
        res[name] = dict(ns_per_pixel_sample=round(per * 1e9, 1), nodes=nodes)
        if getattr(make, "builds", None):
            res[name]["build_seconds"] = round(min(make.builds), 3)
    for name, r in res.items():     # each against the Wave Texture rendered as it is, by SVM or by OSL
        ref = res[("OSL: " if name.startswith("OSL: ") else "") + "Blender Wave Texture"]["ns_per_pixel_sample"]
        r["vs_wave_texture"] = round(r["ns_per_pixel_sample"] / ref, 1)
    print(f"Cycles CPU, {os.cpu_count()} cores, {a.res}^2 px, {a.samples} and {2 * a.samples} samples")
    for name, r in res.items():
        print(f"  {name:24s} {r['ns_per_pixel_sample']:10.1f} ns  {r['vs_wave_texture']:6.1f}x  {r['nodes']:5d} nodes"
              + (f"  built in {r['build_seconds']:.3f} s" if "build_seconds" in r else ""))
    write_json(a.out, dict(stamp=stamp(), blender=bpy.app.version_string, res=a.res, samples=a.samples, results=res))
    return 0


if __name__ == "__main__":
    sys.exit(main())
