"""Write ``docs/benchmarks.md`` from the benchmarks' JSON in ``docs/benchmarks/``: ``python tools/benchmarks_md.py``
(``make docs``).

Each benchmark writes its figures with a stamp (:mod:`bench.stamp`: command, machine, software, date, commit); this
page shows today's figures only, one section per benchmark, each with its stamp. A benchmark whose JSON is missing
is listed with the command that makes it. ``--check`` exits 1 when the page differs from what the JSON gives.
"""
from __future__ import annotations

import argparse
import json
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DATA = os.path.join(ROOT, "docs", "benchmarks")
PAGE = os.path.join(ROOT, "docs", "benchmarks.md")


def _stamp(doc: dict) -> list:
    s = doc.get("stamp") or {}
    if not s:
        return ["*No stamp: machine, date and commit unknown.*", ""]
    soft = f"Python {s.get('python')}, numpy {s.get('numpy')}" + (
        f", onnxruntime {s['onnxruntime']}" if s.get("onnxruntime") else "")
    return [f"*Measured on {s.get('machine')} ({soft}), {s.get('date')}, commit `{s.get('commit')}`:* "
            f"`{s.get('command')}`", ""]


def wave(doc: dict) -> list:
    out = [f"Wave noise grids, nanoseconds per sample (median of repeated runs, wall clock); engine: "
           f"{doc.get('engine', '?')}. Peers: 5-octave fractal Perlin (pyfastnoisesimd, FastNoise Lite), "
           "opensimplex and Blender's Noise and Gabor textures, where installed.", ""]
    for grid, rows in doc.items():
        if not isinstance(rows, dict) or grid in ("stamp", "floor", "stream_512") or not grid[0].isdigit():
            continue
        dim, n = grid.split("D_")
        peers = {k: v for k, v in rows.items() if not k.startswith(("wave", "harness"))}
        fastest = min(peers, key=peers.get) if peers else None
        out += [f"**{dim}D, {n}^{dim} samples**", "", "| method | ns per sample | ratio to the fastest peer |",
                "|---|---|---|"]
        for k, v in sorted(rows.items(), key=lambda kv: kv[1]):
            ratio = f"{v / peers[fastest]:.2f}x" if fastest else "—"
            out.append(f"| {k} | {v:.1f} | {ratio} |")
        out.append("")
    m = doc.get("stream_512")
    if m:
        out += [f"A 512³ grid (8 directions) streams in {m['seconds']:.1f} s with a process peak of "
                f"{m['peak_mib']:.0f} MiB for an output of {m['output_mib']:.0f} MiB.", ""]
    return out


def neural(doc: dict) -> list:
    out = [f"Neural noise on {doc.get('threads')} threads: seconds per network evaluation (step) and per image; "
           f"float32 matrix products run at {doc.get('matmul_gflops')} GFLOP/s on the same machine. "
           "`est.`: encoder + steps × a measured step." + (
               "" if "int8_dot_products" not in doc else
               " This CPU " + ("has" if doc["int8_dot_products"] else "has no") + " int8 dot products (VNNI)."), "",
           "| size | path | s per step | encoder s | s per image | peak RSS MiB |", "|---|---|---|---|---|---|"]
    for r in doc.get("rows", []):
        if "failed" in r:
            out.append(f"| {r.get('size')}² | {r.get('path')} | failed: {r['failed']} | | | |")
            continue
        est = " est." if r.get("estimated") else ""
        tiles = f" ({r['tiles']} tiles)" if r.get("tiles") else ""
        out.append(f"| {r['size']}² | {r['path']}{tiles} | {r['step_s']} | {r['encoder_s']} | {r['image_s']}{est} | "
                   f"{r['peak_rss_mib']} |")
    out.append("")
    w = doc.get("whole_command_256")
    if w:
        out.append(f"The whole command at 256² (start-up and model loading included): {w['default_s']} s by default, "
                   f"{w['one_piece_ddim30_s']} s with the one-piece network and DDIM 30.")
    big = doc.get("whole_command_1024")
    if big:
        out.append(f"At 1024²: {big['default_s']} s.")
    return out + [""]


def solid(doc: dict) -> list:
    out = []
    if doc.get("speed"):
        out += ["Solid textures: every point of a grid evaluated, in a fresh process each (peak memory includes the "
                "interpreter and libraries).", "", "| grid | engine | points per second | seconds | peak MiB |",
                "|---|---|---|---|---|"]
        for r in doc["speed"]:
            out.append(f"| {'×'.join([str(r['size'])] * r['dim'])} | {r['engine']} | {r['points_per_s']:,} | "
                       f"{r['seconds']} | {r['peak_mib']} |")
        out.append("")
    return out


def ablation(doc: dict) -> list:
    out = [f"Each stage and reading of the solid pipeline (`backend/solid/pipeline.py`) left out in turn, on "
           f"{doc.get('photos')} images ({doc.get('split')}), {doc.get('seeds')} seeds: the patch distance of x, y "
           "and z slices pooled (lower is better) and of the walls (x and y slices). A photo counts as closer or "
           "farther with the entry where the entry changes its distance by more than 2 %; lines: the code the "
           "entry takes.", "",
           "| left out | images changed | closer with it | farther with it | median with → without | walls: closer "
           "/ farther | lines |", "|---|---|---|---|---|---|---|"]
    for name, t in doc.get("table", {}).items():
        out.append(f"| {name} | {t['changed']} | {t['closer_pooled']} | {t['farther_pooled']} | "
                   f"{t['median_pooled']} → {t['median_pooled_without']} | {t['closer_walls']} / "
                   f"{t['farther_walls']} | {t['lines']} |")
    return out + [""]


def procedural(doc: dict) -> list:
    s = doc.get("summary", {})
    n = s.get("photos", 0)
    out = [f"Procedural solids (`backend/solid/procedural`) on {n} held-out {doc.get('set')} photos: the patch "
           "distance (lower is better) of the x, y and z cuts (`axes`, two seeds) and of six cuts at random "
           "orientations (`oblique`), for the procedural solid, method auto (the procedural solid where its own check "
           "finds it closer by a margin and its walls keep the photo's structure as well, else the neural texture), "
           "the neural texture (the default) and random phase noise drawn as a solid (the closer, figure by figure, of "
           "two Gaussian solids with the photo's spectrum: isotropic, every cut with its radial spectrum, and upright, "
           "the walls with its horizontal and vertical frequencies). Counts are photos closer than the named "
           "texture.", ""]
    for sfx, title in (("", None), ("_band", "The same over the band-pass levels alone (`photo_eval.band_swd`: "
                                              "without the low-pass residue, where a photo's own crops score worst):")):
        if f"median_procedural_axes{sfx}" not in s:
            continue
        out += ([title, ""] if title else []) + [
            "| texture | median axes | median oblique | closer than random phase solid (axes / oblique) | closer "
            "than the neural texture (axes / oblique) | farther than the neural texture (axes / oblique) |",
            "|---|---|---|---|---|---|"]
        for who, label in (("procedural", "procedural"), ("auto", "auto"), ("neural", "neural (default)"),
                           ("random_phase_solid", "random phase solid")):
            def pair(what):
                return f"{s.get(f'{who}_{what}_axes{sfx}')} / {s.get(f'{who}_{what}_oblique{sfx}')}"
            rp = pair("beats_random_phase_solid") if who != "random_phase_solid" else "—"
            nb = pair("beats_neural") if who in ("procedural", "auto") else "—"
            nf = pair("farther_than_neural") if who in ("procedural", "auto") else "—"
            out.append(f"| {label} | {s.get(f'median_{who}_axes{sfx}')} | {s.get(f'median_{who}_oblique{sfx}')} | "
                       f"{rp} | {nb} | {nf} |")
        out.append("")

        def against(who, kind):
            key = f"{who}_beats_random_phase_solid_{kind}"
            return f"{s.get(f'{key}_axes{sfx}')} / {s.get(f'{key}_oblique{sfx}')}"
        alone = [f"{who}: isotropic {against(who, 'isotropic')}, upright {against(who, 'upright')}"
                 for who in ("procedural", "auto") if f"{who}_beats_random_phase_solid_isotropic_axes{sfx}" in s]
        if alone:
            out += ["Closer than each Gaussian solid alone (axes / oblique): " + "; ".join(alone) + ".", ""]
    if "median_procedural_structure" in s:
        out += [f"Structure: the walls' (x and y cuts') structure error against the photo "
                f"(`backend/solid/procedural/structure.py`: which way it runs, whether it repeats as a grid; lower is "
                f"better), "
                f"median procedural {s['median_procedural_structure']}, auto {s['median_auto_structure']}, neural "
                f"{s['median_neural_structure']}, random phase solid {s['median_random_phase_solid_structure']}. "
                f"Photos where it is more than 0.15 above the neural texture's (the texture loses structure the "
                f"neural texture keeps): procedural {s['procedural_structure_farther_than_neural']}, auto "
                f"{s['auto_structure_farther_than_neural']}, random phase solid "
                f"{s['random_phase_solid_structure_farther_than_neural']} of {n}.", ""]
    fams = ", ".join(f"{k} {v}" for k, v in s.get("families", {}).items())
    timing = ""
    if doc.get("set") == "structured":
        timing = f" Median fit time {s.get('median_fit_seconds')} s per photo on this machine"
        if "median_fit_seconds_without_numba" in s:
            timing += (f"; without numba, as Blender's Python fits, {s['median_fit_seconds_without_numba']} s (the "
                       f"same solid on {s.get('same_fit_without_numba')} of {n})")
        timing += "."
    out += [f"Families fitted: {fams}; auto kept the procedural solid on {s.get('chosen_procedural')} of "
            f"{n}.{timing}", ""]
    return out


def farm(doc: dict) -> list:
    n, frames = doc.get("size"), doc.get("frames", 1)
    out = [f"One job, {frames} frames of an animated {n}³ wave noise volume through the fire ramp (16 directions, "
           f"{doc.get('bytes_per_frame', 0) / 1024:.0f} KiB per frame), baked as `omninoise bake` does on one "
           "machine and on local Dask clusters of 1 and 2 worker processes (`--workers`), each warmed up first.", "",
           "| run | seconds | per frame |", "|---|---|---|"]
    for k, v in doc.get("seconds", {}).items():
        out.append(f"| {k} | {v:.2f} | {v / frames:.3f} |")
    return out + ["", f"2 workers bake {doc.get('speedup_2_over_1')} times as fast as 1; a task on the cluster costs "
                      f"{doc.get('overhead_per_task_ms')} ms more than the same frame on one machine. The machine's "
                      "cores are shared by its workers: a farm's gain comes from more machines.", ""]


def node(doc: dict) -> list:
    blender = f"Blender {doc['blender']}, " if doc.get("blender") else ""
    out = [f"Cycles render time of the Wave Noise node (3D, Gaussian band 2 to 6 cycles per unit) against Blender's "
           f"own textures: a plane filling a {doc.get('res')}² px frame, emission, {blender}CPU; nanoseconds per "
           f"pixel-sample from {doc.get('samples')} and {2 * doc.get('samples', 0)} samples (set-up and shader "
           "compilation cancel). Rows \"OSL:\" render with Cycles' Open Shading Language, where the node is one "
           "compiled script, against Gabor rendered by OSL too. The two \"floor\" rows are the cheapest node trees "
           "any table-lookup wave noise could be at 16 directions: one image read per direction, and two reads with "
           "one hash (slicing without jittered directions or blend weights).", "",
           "| shader | ns per pixel-sample | vs Gabor | nodes |", "|---|---|---|---|"]
    for name, r in doc.get("results", {}).items():
        out.append(f"| {name} | {r['ns_per_pixel_sample']} | {r['vs_gabor']}x | {r['nodes']} |")
    return out + [""]


def procedural_node(doc: dict) -> list:
    blender = f"Blender {doc['blender']}, " if doc.get("blender") else ""
    out = [f"Cycles render time of the procedural solids' live node groups against Blender's Wave Texture: a plane "
           f"filling a {doc.get('res')}² px frame, emission of the group's sRGB output, {blender}CPU; nanoseconds "
           f"per pixel-sample from {doc.get('samples')} and {2 * doc.get('samples', 0)} samples. \"Tinted\": with a "
           f"tint, one Wave Noise group more. Rows \"noises at 0\" set the group's Turbulence, Grain, Detail and "
           f"Tint to 0: Cycles then leaves their Wave Noise groups out. Rows \"OSL:\" render with Cycles' Open "
           f"Shading Language, where the groups' Wave Noise trees take their OSL form (one script each), against "
           f"the Wave Texture rendered by OSL too. \"Built in\": the seconds the group took to build.", "",
           "| shader | ns per pixel-sample | vs Wave Texture | nodes | built in, s |", "|---|---|---|---|---|"]
    for name, r in doc.get("results", {}).items():
        out.append(f"| {name} | {r['ns_per_pixel_sample']} | {r['vs_wave_texture']}x | {r['nodes']} | "
                   f"{r.get('build_seconds', '')} |")
    return out + [""]


#: (JSON file, heading, renderer, the command that makes it)
BENCHES = (
    ("wave.json", "Wave noise", wave, "python -m bench wave"),
    ("node.json", "Wave Noise node: render time", node, "python -m bench node"),
    ("neural_speed.json", "Neural noise", neural, "python -m bench neural --sizes 256 512 1024"),
    ("solid_eval.json", "Solid textures", solid, "python -m bench solid --only-speed"),
    ("solid_ablation.json", "Solid textures: what each stage is worth, held-out photos", ablation,
     "python -m bench solid-ablation -o docs/benchmarks/solid_ablation.json"),
    ("solid_ablation_library.json", "Solid textures: what each stage is worth, a texture library's tiles", ablation,
     "python -m bench solid-ablation --folder TILES -o docs/benchmarks/solid_ablation_library.json"),
    ("solid_procedural.json", "Procedural solids: held-out structured photos", procedural,
     "python -m bench solid-procedural --set structured --sheet -o docs/benchmarks/solid_procedural"),
    ("solid_procedural_stochastic.json", "Procedural solids: held-out stochastic photos (method auto)", procedural,
     "python -m bench solid-procedural --set stochastic -o docs/benchmarks/solid_procedural_stochastic"),
    ("procedural_node.json", "Procedural solids: node group render time", procedural_node,
     "python -m bench procedural-node"),
    ("farm.json", "Farm bakes", farm, "python -m bench farm"),
    ("solid_ablation_crops.json", "Solid textures: what each reading is worth, held-out structured photos cut off their "
     "period", ablation, "python -m bench solid-ablation --folder CROPS --only 'lattice motif' 'main lobes' "
     "'few repeats' lines -o docs/benchmarks/solid_ablation_crops.json"),
)


def page() -> str:
    lines = ["# Benchmarks", "",
             "Today's figures, regenerated from the benchmarks' JSON in `docs/benchmarks/` by "
             "`python tools/benchmarks_md.py` (`make docs`). Each section states the machine, date and commit it "
             "was measured on. Quality evaluations of the models are in their model cards "
             "([neural noise](../models/neural_noise/MODEL_CARD.md), [solid textures](../models/solid/MODEL_CARD.md)).",
             ""]
    for name, heading, render, command in BENCHES:
        lines += [f"## {heading}", ""]
        path = os.path.join(DATA, name)
        if not os.path.isfile(path):
            lines += [f"Not measured yet: `{command}` writes `docs/benchmarks/{name}`.", ""]
            continue
        with open(path, encoding="utf-8") as fh:
            doc = json.load(fh)
        lines += _stamp(doc) + render(doc)
    return "\n".join(lines).rstrip() + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--check", action="store_true", help="exit 1 when docs/benchmarks.md is not up to date")
    a = ap.parse_args(argv)
    text = page()
    if a.check:
        with open(PAGE, encoding="utf-8") as fh:
            same = fh.read() == text
        print("docs/benchmarks.md is " + ("up to date" if same else "out of date: run python tools/benchmarks_md.py"))
        return 0 if same else 1
    tmp = PAGE + ".tmp"
    with open(tmp, "w", encoding="utf-8") as fh:
        fh.write(text)
    os.replace(tmp, PAGE)
    print(f"wrote {os.path.relpath(PAGE, ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
