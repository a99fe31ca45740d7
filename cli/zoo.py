"""``omninoise zoo``: images of the neural model's training classes (needs torch)."""
from __future__ import annotations

import argparse

from omninoise.backend import limits
from omninoise.backend.bake import output_type
from omninoise.backend.errors import SettingError

from . import listing
from .common import add_command, class_args

__all__ = ["add_parser", "run"]


def add_parser(sub) -> argparse.ArgumentParser:
    """The subcommand's parser, added to ``sub`` (the top parser's subparsers)."""
    z = add_command(sub, "zoo", "images of the neural model's training classes (needs torch)",
                    "Ground-truth images of the procedural zoo the neural model was trained on. Needs torch: "
                    "pip install 'omninoise[train]'.",
                    """omninoise zoo --list
omninoise zoo --noise damascus --param frequency=6 --size 256 -o damascus.png""")
    class_args(z)
    return z


def run(a: argparse.Namespace) -> int:
    try:
        from omninoise.training import zoo
    except ImportError as exc:
        raise SettingError("zoo", f"needs torch ({exc})") from None
    if a.list:
        listing.show(zoo.describe(), listing.classes_text(zoo.describe()), a.json)
        return 0
    if not a.noise or not a.out:
        raise SettingError("zoo", "give --noise CLASS and -o OUT (or --list)")
    if a.size < 8:
        raise SettingError("--size", f"must be >= 8, got {a.size}")
    if not 0 <= a.seed < 2 ** 32:
        raise SettingError("--seed", f"must lie in [0, 2^32), got {a.seed}")
    output_type(a.out, (".png", ".exr", ".npy"), "a noise image", "-o")
    limits.check_memory("--size", float(a.size) ** 2 * 4 * 8, f"a {a.size}² zoo image")
    try:
        params = zoo.parse_params(a.noise, a.param)
    except ValueError as exc:
        raise SettingError("--noise" if "class" in str(exc) else "--param", str(exc)) from None
    from omninoise.export.images import write_unit_image

    write_unit_image(a.out, zoo.generate(a.noise, params, [a.seed], a.size)[0].numpy())
    return 0
