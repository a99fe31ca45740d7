"""``omninoise solid``: solid textures from shipped textures or photos, as an image or a volume."""
from __future__ import annotations

import argparse
import os
import sys

import numpy as np

from omninoise.backend import limits
from omninoise.backend.bake import check_bake_memory, output_type
from omninoise.backend.errors import SettingError
from omninoise.backend.solid.request import METHODS, method_for
from omninoise.backend.solid.gaussian_rest import REST_CHOICES
from omninoise.backend.solid.procedural.field import DEFAULT_KINDS, KINDS

from . import listing
from .common import Bar, add_command

__all__ = ["add_parser", "run", "solid_request"]


#: the flags of the request's settings whose names differ
FLAGS = {"periodic": "--no-periodic", "gaussian": "--no-gaussian"}


def _kinds(text: str) -> tuple:
    """``--families`` "cells,bonds" as a tuple of names (SolidRequest.check names one it does not know)."""
    return tuple(k.strip() for k in text.split(","))


def add_parser(sub) -> argparse.ArgumentParser:
    """The subcommand's parser, added to ``sub`` (the top parser's subparsers)."""
    s = add_command(sub, "solid", "solid textures from shipped textures or photos",
                    "Solid textures (Henzler et al. 2020): a shipped texture or any photo becomes a 3D texture, written as "
                    "an image (--dim 2: the plane y = 0 seen from the front, x right, z up) or a volume (--dim 3).",
                    """omninoise solid --list
omninoise solid --exemplar wood_3d --dim 3 --size 128 -o wood.vdb
omninoise solid --exemplar photo.jpg --size 512 -o like.png
omninoise solid --exemplar gravel --to marble --mix 0.5 -o halfway.png
omninoise solid --method spectral --exemplar photo.jpg --dim 3 --size 128 -o rock.vdb
omninoise solid --method procedural --exemplar bricks.jpg --dim 3 --size 128 -o wall.vdb
omninoise solid --method procedural --exemplar bricks.jpg -o wall.json
omninoise solid --exemplar wall.json --dim 3 --size 256 -o wall.vdb
omninoise solid --method synthesis --exemplar photo.jpg --tile 256 --size 1024 -o tileable.png
omninoise solid --method spectral --exemplar photo.jpg --dim 3 --size 256 -o rock.vdb --save-job rock.toml""")
    g = s.add_argument_group("texture and output")
    g.add_argument("--exemplar", help="a shipped texture (see --list) or an image file; --method procedural: "
                                        "also a fitted solid saved as .json (-o)")
    g.add_argument("-o", "--out", help="2D: .png (sRGB), .exr or .npy (linear); 3D: .vdb or .npy (linear); "
                                       "--method procedural: .json, the fitted solid to draw again (--exemplar)")
    g.add_argument("--dim", type=int, choices=(2, 3), default=2, help="2: an image; 3: a volume")
    g.add_argument("--size", type=int, default=256, help="pixels (or voxels) per side")
    g.add_argument("--scale", type=float, default=1.0, help="zoom: output pixels per exemplar pixel")
    g.add_argument("--seed", type=int, default=0, help="another seed gives another texture of the same kind")
    g.add_argument("--method", choices=METHODS,
                   help="neural: the models' texture, 2D or 3D; spectral: the photo's spectrum and colours on every "
                        "cut, 2D or 3D, no network; procedural: rings, layers, cells or bricks fitted to the photo, "
                        "2D or 3D, no network; auto: procedural where it is closer to the photo than neural and keeps "
                        "its structure as well, else neural; synthesis: a seamless 2D image copied from the photo "
                        "(default: neural; procedural for a saved procedural solid, a .json exemplar)")
    g.add_argument("--list", action="store_true", help="print the shipped textures")
    g.add_argument("--json", action="store_true", help="with --list: print it as JSON")
    g.add_argument("--model", help="a model folder (default: the exemplar's own shipped model, else the "
                                   "texture-space model)")
    g.add_argument("--save-job", metavar="JOB.toml",
                   help="write a job file that bakes -o (omninoise bake, a farm) instead of drawing it: a volume, "
                        "or a 2D texture's image (a 2D model's, --method synthesis)")
    g.add_argument("-q", "--quiet", action="store_true", help="no progress or notes")
    g = s.add_argument_group("photos (the texture-space model)")
    g.add_argument("--refine", type=int, default=0, metavar="N", help="improve a photo's code with N search steps")
    g.add_argument("--to", metavar="EXEMPLAR", help="interpolate towards this exemplar")
    g.add_argument("--mix", type=float, default=0.5, help="interpolation weight of --to, 0 to 1")
    g.add_argument("--no-periodic", dest="periodic", action="store_false",
                   help="leave out the photo's periodic part (courses, plank seams, tile joints)")
    g.add_argument("--no-gaussian", dest="gaussian", action="store_false",
                   help="never mix in fine detail drawn from the photo's spectrum (by default mixed in where a "
                        "check on rendered planes finds it closer)")
    g.add_argument("--rest", default="auto", choices=REST_CHOICES,
                   help="that detail's kind: auto (the check chooses), isotropic, or upright (layers and grain "
                        "kept on walls)")
    g = s.add_argument_group("--method procedural and auto")
    g.add_argument("--families", type=_kinds, default=DEFAULT_KINDS, metavar="KIND,...",
                   help=f"the kinds of solid the fit tries, of {', '.join(KINDS)} (default: "
                        f"{','.join(DEFAULT_KINDS)}; herringbone: bricks laid in a herringbone)")
    g = s.add_argument_group("--method synthesis")
    g.add_argument("--tile", type=int, default=256, help="the tile's side, px (a multiple of 4 in [32, 1024])")
    return s


def solid_request(a: argparse.Namespace):
    """The :class:`backend.solid.request.SolidRequest` of ``omninoise solid``'s flags, checked."""
    from omninoise.backend.solid.request import SolidRequest

    if a.to is None and a.mix != 0.5:
        raise SettingError("--mix", "weighs the texture of --to: give --to EXEMPLAR too")
    given = [k for k, unset in (("model", None), ("to", None), ("mix", 0.5), ("refine", 0), ("periodic", True),
                                ("gaussian", True), ("rest", "auto"), ("tile", 256), ("families", DEFAULT_KINDS))
             if getattr(a, k) != unset]
    return SolidRequest(a.model, a.exemplar, a.to, a.mix, a.refine, a.seed, a.periodic, a.gaussian,
                        a.rest, method_for(a.exemplar, a.method), a.tile, a.families).check("--").check_reads(
        given, "--", FLAGS)


def run(a: argparse.Namespace) -> int:
    from omninoise.backend.solid.model import load_models

    if a.list:
        out = {name: dict(mode=m.mode, dim=m.dim, exemplars=m.config["exemplars"], codes=sorted(m.codes))
               for name, m in load_models().items()}
        listing.show(out, listing.textures_text(out), a.json)
        return 0
    if not a.exemplar or not a.out:
        raise SettingError("solid", "give --exemplar (a shipped texture or an image file) and -o OUT (or --list)")
    if a.size < 1:
        raise SettingError("--size", f"must be >= 1, got {a.size}")
    limits.scale("--scale", a.scale)
    ext = os.path.splitext(a.out)[1].lower()
    if ext == ".json":          # the fitted procedural solid itself, drawn later at any size
        if method_for(a.exemplar, a.method) != "procedural":
            raise SettingError("-o", "a .json output is a fitted procedural solid: give --method procedural")
        for flag, value, unset in (("--dim", a.dim, 2), ("--size", a.size, 256), ("--scale", a.scale, 1.0)):
            if value != unset:
                raise SettingError(flag, "a .json output holds the fitted solid, not a drawing of it: leave "
                                         f"{flag} out, and give it when the .json is drawn (--exemplar)")
    else:
        output_type(a.out, (".png", ".exr", ".npy") if a.dim == 2 else (".vdb", ".npy"), f"a {a.dim}D result", "-o")
        check_bake_memory("--size", (a.size,) * a.dim, ext, "rgb", f"a {a.size}-sample {a.dim}D texture")
    if ext == ".vdb":
        from omninoise.backend.bake import require_vdb

        require_vdb("-o")
    req = solid_request(a).check_pixels("--")      # a photo it cannot use is named before any note or work
    if a.save_job:
        return _save_job(a, req)
    if not a.quiet and req.repeats_as_grid("--"):
        print("note: the photo repeats across and up as a grid (bricks, tiles?); the kinds besides bonds often draw "
              "stones or blotches there: --families bonds lays it in courses", file=sys.stderr)
    from omninoise.export.images import clipped_notes

    for note in [] if a.quiet else clipped_notes(a.exemplar):
        print("note: " + note, file=sys.stderr)

    def report(name, hist):
        if not a.quiet:
            kept = len(hist) > 1 and hist[-1] == hist[0] and min(hist) < hist[0]
            print(f"refined {name}: neighbourhood distance {hist[0]:.4f} -> {min(hist):.4f}"
                  + (" on the searched planes, not closer on fresh ones: the encoder's code is kept" if kept else ""),
                  file=sys.stderr)

    draw_bar = Bar(a.quiet, "drawing ")

    def on_code(code):
        draw_bar.restart()                 # the drawing begins once the code is made (or auto's check is done)
        if a.quiet:
            return
        if code.harmonics is not None:
            h = code.harmonics
            print(f"periodic part: {len(h)} waves at spectral peaks, {100 * h.share:.0f} % of the photo's variance "
                  "(--no-periodic leaves it out)", file=sys.stderr)
        if code.rest is not None:
            from omninoise.backend.solid.gaussian_rest import KIND_WORDS
            print(f"gaussian rest: {100 * code.rest.mix:.0f} % of the rest's variance drawn as "
                  f"{KIND_WORDS[code.rest.kind]}, found closer to the image than the decoder alone (--no-gaussian "
                  "leaves it out)", file=sys.stderr)

    def on_fit(fitted):
        """The kind the procedural fit drew, or what auto kept and why."""
        draw_bar.restart()
        if not a.quiet:
            print(fitted.summary() if hasattr(fitted, "summary") else f"procedural: fitted {fitted.family}",
                  file=sys.stderr)

    stage = {"neural": "encoding ", "synthesis": "synthesis ", "spectral": "spectral solid ",
             "procedural": "procedural fit ", "auto": "auto: fit, encoding, check "}[req.method]
    if ext == ".json":
        from omninoise.backend.solid.procedural import saved

        field = req.procedural_field("--", Bar(a.quiet, stage))
        saved.save(a.out, field)
        if not a.quiet:
            what = "a copy of the saved" if saved.is_saved(a.exemplar) else "the fitted"
            print(f"wrote {what} {field.family} to {a.out}: draw it with --exemplar {a.out}", file=sys.stderr)
        return 0
    if a.dim == 3:  # volumes through the bake pipeline: .vdb color + density grids, or linear RGB .npy
        from omninoise.backend.bake import BakeSpec, run_bake
        from omninoise.backend.sources import BoxGrid, solid_volume

        source, extent = solid_volume(req, a.size, a.scale, "--", Bar(a.quiet, stage), report, on_code, on_fit)
        grid = BoxGrid((a.size,) * 3, ((0.0, 0.0, 0.0), (extent,) * 3))
        run_bake(BakeSpec("solid", source, grid, a.out), Bar(a.quiet, "drawing "), force=True)
        return 0
    _write_image(a.out, req.front_image(a.size, a.scale, "--", Bar(a.quiet, stage), report, on_code, draw_bar,
                                        on_fit))
    return 0


def _save_job(a: argparse.Namespace, req) -> int:
    """``--save-job``: write the job that bakes ``-o`` as this command would draw it, and draw nothing."""
    from omninoise.backend.job_file import check_job_file, solid_spec, write_job

    check_job_file(a.save_job, "--save-job")
    write_job(a.save_job, [solid_spec(req, a.size, a.dim, a.scale, a.out, ("-o", "--save-job", "--"))], None,
              "--save-job")
    if not a.quiet:
        print(f"omninoise solid: wrote {a.save_job}: omninoise bake {a.save_job} draws {a.out}", file=sys.stderr)
    return 0


def _write_image(out: str, rgb: np.ndarray) -> None:
    """A 2D solid texture, sRGB float (H, W, 3) in [0, 1]: .png as it is, .exr and .npy linear."""
    from omninoise.backend.colour import srgb_to_linear
    from omninoise.export.images import write_unit_image

    write_unit_image(out, rgb, None if out.lower().endswith(".png") else srgb_to_linear(rgb))
