"""``omninoise`` command line (also ``python -m omninoise``): the top parser and the dispatch.

Each subcommand is one module of this package with ``add_parser(sub)`` and ``run(args) -> int``
(:data:`COMMANDS`); what they share is in :mod:`.common`.  Command-line only: writes files through the
``export`` package, which the add-on reaches through its own relative imports instead.
"""
from __future__ import annotations

import argparse
import os
import sys

from omninoise.backend.errors import SettingError
from omninoise.export.images import ImageError

from . import bake, hugepages, neural, solid, transfer, wave, zoo
from .common import Help

__all__ = ["main", "build_parser", "COMMANDS"]

#: subcommand name -> its module, in the order of ``omninoise --help``
COMMANDS = {"wave": wave, "bake": bake, "neural": neural, "solid": solid, "zoo": zoo, "transfer": transfer}


def _version_line() -> str:
    from omninoise.backend.version import __version__
    from omninoise.backend.wavenoise.fast import engine_path

    return f"omninoise {__version__} (wave noise: {engine_path()})"


class _Version(argparse.Action):
    """``--version``: the line of :func:`_version_line`, made only when asked for (finding the wave kernel loads
    the C library, which no other option needs at start-up)."""

    def __init__(self, option_strings, dest=argparse.SUPPRESS, default=argparse.SUPPRESS, help=None):
        super().__init__(option_strings, dest=dest, default=default, nargs=0, help=help)

    def __call__(self, parser, namespace, values, option_string=None):
        print(_version_line())      # on standard output, as argparse's own version action prints
        parser.exit()


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(
        prog="omninoise", formatter_class=Help,
        description="OmniNoise: wave noise, neural noise and solid textures from photos, as images, arrays and "
                    "volumes.",
        epilog="Run 'omninoise SUBCOMMAND --help' for each subcommand's options and examples. Exit status: 0 done, "
               "2 bad input (one line naming the option), 1 a failure while running, 130 interrupted.")
    ap.add_argument("--version", action=_Version, help="print the version and the wave kernel in use, then exit")
    ap.add_argument("--debug", action="store_true",
                    help="show the Python traceback of an internal error instead of one line")
    sub = ap.add_subparsers(dest="command", required=True, metavar="SUBCOMMAND")

    for module in COMMANDS.values():
        module.add_parser(sub)
    return ap


def main(argv: list[str] | None = None) -> int:
    ap = build_parser()
    a = ap.parse_args(argv)
    if argv is None and hugepages.wanted(a.command, getattr(a, "size", 0) or 0, os.environ):
        try:   # a large neural image: the same command again, with huge pages (cli/hugepages.py)
            hugepages.reexec()
        except OSError:
            pass
    try:
        return COMMANDS[a.command].run(a)
    except (SettingError, FileNotFoundError, PermissionError, IsADirectoryError, ImageError) as exc:
        print(f"omninoise {a.command}: error: {exc}", file=sys.stderr)
        return 2
    except Exception as exc:
        from omninoise.backend.grid import Cancelled
        from omninoise.backend.jobs import JobError

        if isinstance(exc, JobError):
            print(f"omninoise {a.command}: error: {exc}", file=sys.stderr)
            return 2
        if isinstance(exc, Cancelled):
            print(f"omninoise {a.command}: cancelled", file=sys.stderr)
            return 130
        if a.debug:
            raise
        what = str(exc).splitlines()[0] if str(exc) else ""
        print(f"omninoise {a.command}: internal error: {type(exc).__name__}{': ' + what if what else ''} "
              "(a bug: please report it with the command; --debug before the command shows the traceback)",
              file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print(f"\nomninoise {a.command}: interrupted; no partial file was left", file=sys.stderr)
        return 130
    return 1
