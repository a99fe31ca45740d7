"""``omninoise neural``: neural noise from the trained diffusion model: one class, blends, painted maps,
animations between keyframes, and fits to an image."""
from __future__ import annotations

import argparse
import os
import sys

from omninoise.backend import limits
from omninoise.backend.bake import output_type
from omninoise.backend.errors import SettingError
from omninoise.backend.neural.animate import LATENT_MODES
from omninoise.backend.neural.generate import check_memory as neural_memory
from omninoise.backend.neural.precision import PRECISIONS
from omninoise.backend.paths import neural_model

from . import listing
from .common import Bar, add_command, class_args, flag_image, param_items, set_threads

IMAGE_TYPES = (".png", ".exr", ".npy")   #: what a neural noise image is written as

__all__ = ["add_parser", "run", "neural_request"]


def add_parser(sub) -> argparse.ArgumentParser:
    """The subcommand's parser, added to ``sub`` (the top parser's subparsers)."""
    n = add_command(sub, "neural", "neural noise from the trained diffusion model",
                    "Neural noise (Maesumi et al. 2024): one diffusion model for 23 noise classes and their blends, at "
                    "any size, on the CPU. One class, a blend through a mask, two from left to right, four corners or "
                    "a painted map; animated between keyframes; or fitted to an image.",
                    """omninoise neural --list
omninoise neural --noise cells_f1 --param scale=12 --size 256 --seed 7 --tileable -o cells.png
omninoise neural --noise cells_f1 --blend mask.png --noise2 noise --size 256 -o blend.png
omninoise neural --gradient spots:coverage=0.3 cells_f1 --size 512 -o gradient.png
omninoise neural --map painted.png --region '#ff0000=spots' --region '#0000ff=gabor' -o map.png
omninoise neural --keys anim.toml --frames 1 48 --latent slerp -o morph_####.png
omninoise neural --fit photo.jpg --report fit.json -o fitted.png
omninoise neural --map painted.png --region '#ff0000=spots' --region '#0000ff=gabor' -o map.exr --save-job map.toml""")
    g = n.add_argument_group("noise and output")
    class_args(g)
    g.add_argument("--tileable", action="store_true", help="a seamless tile (size a multiple of 8)")
    g.add_argument("--model", help="another model folder (default: the shipped model)")
    g.add_argument("--save-job", metavar="JOB.toml",
                   help="write a job file that draws -o with these settings (omninoise bake JOB.toml, a farm) "
                        "instead of drawing it now")
    g.add_argument("-q", "--quiet", action="store_true", help="no progress bar or notes")
    g = n.add_argument_group("blends")
    g.add_argument("--blend", metavar="MASK", help="a grayscale mask image: white areas take --noise2 / --param2")
    g.add_argument("--noise2", help="class of the masked area (default: --noise)")
    g.add_argument("--param2", action="append", default=[], metavar="NAME=VALUE", help="its parameters (repeat)")
    g.add_argument("--width", type=float, default=32.0,
                   help="blend transition width, px of the mask or map (one of another size, with the image's "
                        "proportions, is drawn at --size)")
    g.add_argument("--sharpness", type=float, default=1.0, help="blend sharpness exponent (1: linear)")
    g.add_argument("--gradient", nargs=2, metavar=("LEFT", "RIGHT"),
                   help="left-to-right blend: LEFT on the left edge blending evenly into RIGHT on the right, each "
                        "CLASS[:NAME=V,...]")
    g.add_argument("--corners", nargs=4, metavar="SPEC",
                   help="four-corner blend: top-left top-right bottom-left bottom-right, each CLASS[:NAME=V,...]")
    g.add_argument("--map", metavar="PAINTED", help="a painted map: an indexed, grey or colour-coded image")
    g.add_argument("--region", action="append", default=[], metavar="KEY=SPEC",
                   help="--map: a grey index (0-255) or #rrggbb colour = CLASS[:NAME=V,...] (repeat)")
    g = n.add_argument_group("animation")
    g.add_argument("--keys", metavar="KEYS.toml", help="keyframes of class and parameters over frames (needs "
                                                       "--frames)")
    g.add_argument("--frames", type=int, nargs=2, metavar=("FIRST", "LAST"),
                   help="write frames FIRST..LAST into -o with '#' for the frame number")
    g.add_argument("--latent", choices=LATENT_MODES, default="fixed",
                   help="how the initial latent moves: fixed, slerp between the keys' seeds, or drift")
    g.add_argument("--drift", type=float, default=0.05, help="--latent drift: radians per frame")
    g = n.add_argument_group("inverse design")
    g.add_argument("--fit", metavar="IMAGE", help="find the classes, parameters and seed whose noise looks like "
                                                  "IMAGE and write that noise to -o")
    g.add_argument("--report", metavar="FIT.json", help="--fit: write the fitted classes, parameters and seed here")
    g.add_argument("--fit-size", type=int, default=64, help="--fit: side of the windows compared, px")
    g = n.add_argument_group("sampling and speed")
    g.add_argument("--sampler", default=None, help="ddim, dpmpp_2m or heun (default: dpmpp_2m)")
    g.add_argument("--steps", type=int, default=None, help="model evaluations (default: 10)")
    g.add_argument("--spacing", default=None,
                   help="timestep spacing: uniform, logsnr, karras or truncated (default: the sampler's own)")
    g.add_argument("--eta", type=float, default=None,
                   help="ddim or dpmpp_2m: fresh noise per step, 0 (deterministic) to 1 (default: 0.3 for "
                        "dpmpp_2m, 0 for ddim; animation always 0)")
    g.add_argument("--tile", type=int, default=None,
                   help="draw in overlapping tiles of this side (default: whole up to 1024 px, else 512 px tiles; "
                        "0: never)")
    g.add_argument("--threads", type=int, default=0, help="CPU threads (0: all cores)")
    g.add_argument("--precision", default="fp32", choices=PRECISIONS,
                   help="int8: about 1.8x faster steps on CPUs with int8 dot products (VNNI), a draft")
    return n


def _spec_arg(text: str, flag: str) -> tuple:
    """'cells_f1:scale=8,jitter=0.5' -> ('cells_f1', {'scale': 8.0, 'jitter': 0.5})."""
    name, _, rest = text.partition(":")
    return name, param_items([p for p in rest.split(",") if p], flag)


def _painted_parts(a: argparse.Namespace) -> tuple:
    """--map and its --region flags -> (regions int (H, W) into specs, specs)."""
    from omninoise.export.images import decode
    from omninoise.backend.neural.request import region_key, regions_from_map

    if not os.path.isfile(a.map):
        raise SettingError("--map", f"map not found: {a.map}")
    if not a.region:
        raise SettingError("--region", "a --map needs --region KEY=SPEC for each of its colours")
    px = flag_image("--map", decode, a.map)
    keys, specs = [], []
    for r in a.region:
        key, sep, spec = r.partition("=")
        if not sep:
            raise SettingError("--region", f"expected KEY=SPEC, got {r!r}")
        k = region_key(key, "--region")
        if k in keys:
            raise SettingError("--region", f"{key!r} is given twice; give each colour or index one spec")
        keys.append(k)
        specs.append(_spec_arg(spec, "--region"))
    return regions_from_map(px, keys, "--map"), specs


#: the flag of each setting :data:`~backend.neural.request.READ_BY` names, and of each layout's chooser
FLAG_OF = {"params": "--param", "params2": "--param2", "regions": "--region"}


def check_reads(a: argparse.Namespace) -> None:
    """Refuse, before any work, a flag that the image asked for does not read (a --region without --map, a --param
    beside --corners, a --width in an animation): it would change nothing, and the image would not be the one
    asked for; and two ways of laying out the classes at once."""
    from omninoise.backend.neural.request import check_layout_reads

    if bool(a.keys) != bool(a.frames):      # named by the one given, before the layout's reads speak of the other
        raise SettingError("--keys" if a.keys else "--frames",
                           "an animation needs both --keys KEYS.toml and --frames FIRST LAST")
    chosen = [f for f, v in (("--blend", a.blend), ("--gradient", a.gradient), ("--corners", a.corners),
                             ("--map", a.map)) if v]
    if len(chosen) > 1:
        raise SettingError(chosen[1], f"choose one of --blend, --gradient, --corners and --map (got "
                                      f"{' and '.join(chosen)})")
    for flag, given in (("--report", a.report), ("--fit-size", a.fit_size != 64)):
        if given and not a.fit:
            raise SettingError(flag, f"a fit {'report' if flag == '--report' else 'window size'} needs --fit IMAGE")
    layout = ("animated" if a.keys or a.frames else "fit" if a.fit else "corners" if a.corners
              else "gradient" if a.gradient else "painted" if a.map else "blend" if a.blend else "uniform")
    given = [k for k, v in (("noise", a.noise), ("params", a.param), ("noise2", a.noise2), ("params2", a.param2),
                            ("width", a.width != 32.0), ("sharpness", a.sharpness != 1.0), ("regions", a.region),
                            ("latent", a.latent != "fixed"), ("drift", a.drift != 0.05)) if v]
    check_layout_reads(layout, given, lambda k: FLAG_OF.get(k, "--" + k))


def neural_request(a: argparse.Namespace, model):
    """The :class:`backend.neural.request.NeuralRequest` of ``omninoise neural`` flags (checked)."""
    from omninoise.backend.neural.request import NeuralRequest, check_specs
    from omninoise.backend.neural.sampler import DEFAULT_SAMPLER, DEFAULT_STEPS

    if a.size < 8:
        raise SettingError("--size", f"must be >= 8, got {a.size}")
    kw = dict(width=a.size, height=a.size, transition=a.width, sharpness=a.sharpness, seed=a.seed,
              steps=DEFAULT_STEPS if a.steps is None else a.steps, sampler=a.sampler or DEFAULT_SAMPLER,
              spacing=a.spacing, eta=a.eta, tileable=a.tileable, tile=a.tile)
    spec = (a.noise, param_items(a.param, "--param"))
    if a.corners:
        req = NeuralRequest("corners", [_spec_arg(c, "--corners") for c in a.corners], **kw)
    elif a.gradient:
        req = NeuralRequest("gradient", [_spec_arg(c, "--gradient") for c in a.gradient], **kw)
    elif a.map:
        regions, specs = _painted_parts(a)
        req = NeuralRequest("painted", specs, regions=regions, **kw)
    elif a.blend:
        from omninoise.export.images import read_image

        if not os.path.isfile(a.blend):
            raise SettingError("--blend", f"mask not found: {a.blend}")
        mask = flag_image("--blend", read_image, a.blend)
        spec2 = (a.noise2 or a.noise, param_items(a.param2, "--param2"))
        req = NeuralRequest("blend", [spec, spec2], mask=mask > 0.5, **kw)
    else:
        req = NeuralRequest("uniform", [spec], **kw)
    check_specs(model, req.specs, _spec_flags(a))       # each class named by its own flag
    try:
        return req.check(model)
    except SettingError as exc:  # name the flag where the request's field has one
        flag = {"noise": "--noise", "map": "--map", "blend": "--blend", "size": "--size", "seed": "--seed",
                "width": "--width", "transition": "--width", "sharpness": "--sharpness"}.get(exc.setting,
                                                                                           exc.setting)
        raise SettingError(flag, exc.message) from None


def _spec_flags(a: argparse.Namespace) -> list:
    """(flag of the class, flag of its parameters) of each of the request's specs, in order."""
    if a.corners or a.gradient or a.map:
        flag = "--corners" if a.corners else "--gradient" if a.gradient else "--region"
        return [(flag, flag)] * len(a.corners or a.gradient or a.region)
    second = [("--noise2" if a.noise2 else "--noise", "--param2")] if a.blend else []
    return [("--noise", "--param")] + second


def run(a: argparse.Namespace) -> int:
    from omninoise.backend.neural.model import ModelError, NeuralNoiseModel, PrecisionUnavailable
    from omninoise.backend.neural.request import generate_request

    from omninoise.backend.neural.generate import check_sampler
    from omninoise.backend.neural.sampler import DEFAULT_SAMPLER, DEFAULT_STEPS

    set_threads(a.threads, a.precision)
    sampler = a.sampler or DEFAULT_SAMPLER
    steps = DEFAULT_STEPS if a.steps is None else a.steps
    try:
        check_sampler(sampler, steps, a.spacing, a.eta)
    except SettingError as exc:         # named as the flag the user typed
        raise SettingError(f"--{exc.setting}", exc.message) from None
    if not 0 <= a.seed < 2 ** 32:
        raise SettingError("--seed", f"must lie in [0, 2^32), got {a.seed}")
    tile = a.tile
    if tile is not None and tile < 0:
        raise SettingError("--tile", f"must be >= 0 (0: never tile), got {tile}")
    neural_memory("--size", a.size, a.size, tile)
    folder = a.model or neural_model()
    try:
        model = NeuralNoiseModel(folder)
    except PrecisionUnavailable as exc:
        raise SettingError("--precision", str(exc)) from None
    except ModelError as exc:
        raise SettingError("--model", f"{exc}; train and export one (see models/README.md) or pass --model") from None
    if a.list:
        trained = model.config.get("trained_classes") or list(model.class_params)
        text = listing.classes_text({n: model.class_params[n] for n in trained if n in model.class_params},
                                    [n for n in model.class_params if n not in trained])
        listing.show(dict(classes=model.class_params, trained=trained), text, a.json)
        return 0
    check_reads(a)
    if a.save_job:
        _check_save_job(a)
    if a.keys or a.frames:
        return _animate(a, model, sampler, steps, tile)
    if a.fit:
        return _fit(a, model, sampler, steps, tile)
    if not (a.noise or a.gradient or a.corners or a.map) or not a.out:
        raise SettingError("neural", "give --noise CLASS (or --gradient / --corners / --map) and -o OUT (or --list)")
    output_type(a.out, IMAGE_TYPES, "a neural noise image", "-o")
    req = neural_request(a, model)
    if a.save_job:
        from omninoise.backend.neural.request import region_key
        from omninoise.backend.sources import NeuralSource

        keys = [region_key(r.partition("=")[0], "--region") for r in a.region] if a.map else []
        colours = [k if isinstance(k, tuple) else (k, k, k) for k in keys] or None     # the job's map keeps them
        return _save_job(a, NeuralSource.from_request(model.folder, req, colours))
    bar = Bar(a.quiet)
    try:
        img = generate_request(model, req, callback=lambda i, n, x0: bar((i + 1) / n))
    except SettingError as exc:     # the generator's checks (tiles, sizes), named as the flags the user typed
        flag = {"tile": "--tile", "size": "--size"}.get(exc.setting, exc.setting)
        raise SettingError(flag, exc.message) from None
    from omninoise.export.images import write_unit_image

    write_unit_image(a.out, img)
    return 0


def _check_save_job(a: argparse.Namespace) -> None:
    """``--save-job``, before any work: a .toml name in a folder that exists, and nothing beside it that a job
    cannot hold (a fit, a sampler setting of this run, int8 arithmetic, a .npy whose rows a bake stores +y first)."""
    from omninoise.backend.job_file import check_job_file

    check_job_file(a.save_job, "--save-job")
    if a.fit:
        raise SettingError("--save-job", "a job draws the classes it is given: fit first (--fit IMAGE --report "
                                         "FIT.json), then save the fitted noise's flags as a job")
    for flag, given in (("--spacing", a.spacing), ("--eta", a.eta), ("--tile", a.tile)):
        if given is not None:
            raise SettingError(flag, "a job file has no such setting (its bake takes the default): leave it out "
                                     "beside --save-job")
    if a.precision != "fp32":
        raise SettingError("--precision", "sets this run's arithmetic, not the job's: give it to omninoise bake "
                                          "(--precision int8) where the job runs")
    if a.out and a.out.lower().endswith(".npy"):
        raise SettingError("--save-job", "a job's .npy holds an image's rows from the bottom up (+y first, as "
                                         "every bake's array), -o's from the top: write -o as .png or .exr")


def _save_job(a: argparse.Namespace, source, frames: tuple | None = None) -> int:
    """Write the job (``--save-job``) that draws ``-o`` from ``source``, and its blend mask or painted map beside
    it; draw nothing."""
    from omninoise.backend.bake import BakeSpec
    from omninoise.backend.job_file import write_job
    from omninoise.backend.sources import BoxGrid

    spec = BakeSpec("neural", source, BoxGrid((a.size, a.size)), os.path.abspath(a.out), frames=frames,
                    time=float(frames[0]) if frames else 0.0, time_step=1.0).validate()
    write_job(a.save_job, [spec], {a.blend: "--blend reads", a.map: "--map reads"}, "--save-job")
    if not a.quiet:
        print(f"omninoise neural: wrote {a.save_job}: omninoise bake {a.save_job} draws {a.out}", file=sys.stderr)
    return 0


def _animate(a: argparse.Namespace, model, sampler: str, steps: int, tile) -> int:
    """``neural --keys KEYS.toml --frames FIRST LAST -o name_####.png``: one file per frame, each written
    atomically (an interrupted run keeps the frames it finished)."""
    from omninoise.backend.bake import frame_path, has_frame_field
    from omninoise.backend.neural.animate import animate, check_keys, read_keys
    from omninoise.export.images import write_unit_image

    if a.noise or a.gradient or a.corners or a.map or a.blend:
        raise SettingError("--keys", "the keyframes set the classes; leave out --noise, --gradient, --corners, --map "
                                     "and --blend")
    if not a.out or not has_frame_field(a.out):
        raise SettingError("-o", "an animation writes one file per frame: put '#' for the frame number in the "
                                 "name, e.g. -o noise_####.png")
    output_type(a.out, IMAGE_TYPES, "a neural noise image", "-o")
    if a.size < 8:
        raise SettingError("--size", f"must be >= 8, got {a.size}")
    first, last = a.frames
    if last < first:
        raise SettingError("--frames", f"expected FIRST LAST with LAST >= FIRST, got {first} {last}")
    limits.frame_count("--frames", first, last, "run")
    limits.finite("--drift", a.drift)
    keys = read_keys(a.keys)
    check_keys(model, keys)
    if a.save_job:
        from omninoise.backend.sources import NeuralSource

        return _save_job(a, NeuralSource(model.folder, keys[0].noise, keys[0].params, steps=steps,
                                         tileable=a.tileable, sampler=sampler, keys=keys, latent=a.latent,
                                         drift=a.drift), (first, last))
    n = last - first + 1
    bar = Bar(a.quiet, "frames ")
    frames = animate(model, keys, (first, last), a.size, a.size, latent=a.latent, speed=a.drift, steps=steps,
                     sampler=sampler, spacing=a.spacing, eta=a.eta, tileable=a.tileable, tile=tile)
    for i, (f, img) in enumerate(frames):
        write_unit_image(frame_path(a.out, f), img)
        bar((i + 1) / n)
    return 0


def _fit(a: argparse.Namespace, model, sampler: str, steps: int, tile) -> int:
    """``neural --fit IMAGE -o OUT [--report FIT.json]``: inverse design (backend/neural/fit.py), then the fitted
    noise at --size with the sampler settings."""
    import json

    from omninoise.export.atomic import write_json
    from omninoise.export.images import decode, opaque, write_unit_image
    from omninoise.backend.neural.fit import check_fit_size, fit, fitted_conditioning, load_bank, prepare_target
    from omninoise.backend.neural.generate import generate
    from omninoise.backend.onnx_models import ModelError
    from omninoise.backend.paths import fit_bank

    if a.noise or a.gradient or a.corners or a.map or a.blend:
        raise SettingError("--fit", "the fit finds the classes; leave out --noise, --gradient, --corners, --map and "
                                    "--blend")
    if not a.out:
        raise SettingError("-o", "--fit writes the fitted noise: give -o OUT (.png, .exr or .npy)")
    output_type(a.out, IMAGE_TYPES, "a neural noise image", "-o")
    if a.size < 8:
        raise SettingError("--size", f"must be >= 8, got {a.size}")
    check_fit_size(a.fit_size, model.multiple_of, "--fit-size")
    if not os.path.isfile(a.fit):
        raise SettingError("--fit", f"image not found: {a.fit}")
    img = flag_image("--fit", lambda path: opaque(decode(path), path), a.fit)
    try:
        bank = load_bank(fit_bank())
    except ModelError as exc:  # the fit still works, starting from every class at mid-range parameters
        if not a.quiet:
            print(f"note: no inverse-design bank ({exc}); trying every class", file=sys.stderr)
        bank = None
    img = img[..., 0] if img.shape[2] == 1 else img
    # refuses too small and flat images, named by the flag and the file
    for note in prepare_target(img, model.multiple_of, f"--fit {os.path.basename(a.fit)}")[1]:
        if not a.quiet:
            print("note: " + note, file=sys.stderr)
    bar = Bar(a.quiet, "fit    ")
    res = fit(model, img, size=a.fit_size, seed=a.seed, bank=bank, progress=lambda f: bar(0.8 * f))
    cond = fitted_conditioning(model, res, a.size, a.size)
    out = generate(model, cond, res.seed, steps, a.tileable, callback=lambda i, n, x0: bar(0.8 + 0.2 * (i + 1) / n),
                   sampler=sampler, spacing=a.spacing, tile=tile)
    write_unit_image(a.out, out)
    report = dict(res.to_json(), image=os.path.abspath(a.fit), output=os.path.abspath(a.out), size=a.size,
                  model=model.fingerprint)
    if a.report:
        write_json(a.report, report)
    if not a.quiet:
        print(json.dumps(dict(classes=res.classes, params=res.params, seed=res.seed, command=res.command())))
    return 0


