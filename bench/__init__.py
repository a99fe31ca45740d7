"""OmniNoise's benchmarks and evaluations, one entry: ``python -m bench [SUITE [ARGS ...]]``.

``python -m bench`` lists the suites; ``make bench`` runs the speed suites (``SPEED``).  Each suite is one
module of this package with ``main(argv) -> int``; those that measure write their figures as stamped JSON
(:mod:`bench.stamp`) that ``python tools/benchmarks_md.py`` turns into ``docs/benchmarks.md``.
"""
from __future__ import annotations

#: suite name -> (module in this package, what it measures)
SUITES = {
    "wave": ("bench_wave", "wave noise speed against the CPU peers (docs/benchmarks/wave.json)"),
    "neural": ("bench_neural", "neural noise speed: the default sampler against one-piece DDIM (neural_speed.json)"),
    "solid": ("eval_solid", "the shipped solid textures: figures and speed (solid_eval.json with --only-speed)"),
    "farm": ("bench_farm", "a farm bake's speed-up over one process"),
    "node": ("bench_node", "Cycles render time of the Wave Noise node against Blender's own textures (needs bpy)"),
    "procedural-node": ("bench_procedural_node", "Cycles render time of the procedural solids' node groups against "
                                                 "Blender's Wave Texture (needs bpy)"),
    "int8": ("neural_int8", "int8 against fp32 neural denoisers: speed and difference"),
    "neural-eval": ("eval_neural", "a neural noise model's evaluation: Fréchet distances, spectra, classifier"),
    "neural-compare": ("neural_compare", "two neural evaluations side by side (the model card's table)"),
    "neural-nearest": ("neural_nearest", "is each class's image nearest to its own zoo class"),
    "fit": ("eval_fit", "fitting a noise to an image (inverse design) on the zoo's classes"),
    "solid-photos": ("eval_solid_photos", "solid textures on held-out photos against random phase and pixel shuffle"),
    "solid-singles": ("eval_solid_singles", "single-photo solid models on pixels they never saw"),
    "solid-ablation": ("solid_ablation", "each stage and reading of the solid pipeline left out in turn"),
    "solid-methods": ("solid_synthesis", "the spectral solid and tileable synthesis on held-out photos"),
    "solid-procedural": ("eval_procedural", "procedural solids and method auto on held-out structured photos"),
    "sheet-zoo": ("zoo_sheet", "contact sheet: the training zoo's classes at 256 px"),
    "sheet-samplers": ("neural_sampler_sheet", "contact sheet: the samplers on the same seeds"),
    "sheet-structure": ("neural_structure_sheet", "contact sheet: long-range structure of models at 256 px"),
}

#: the suites ``make bench`` runs, with their arguments: the speed figures of docs/benchmarks.md
SPEED = (("wave", []), ("neural", ["--sizes", "256", "512", "1024"]), ("solid", ["--only-speed"]))
