"""``omninoise`` command line (also ``python -m omninoise``): the top parser and the dispatch.

Each subcommand is one module of this package with ``add_parser(sub)`` and ``run(args) -> int``
(:data:`COMMANDS`); what they share is in :mod:`.common`.  Command-line only: writes files through the
``export`` package, which the add-on reaches through its own relative imports instead.
"""
from __future__ import annotations

import argparse
import os
import re
import signal
import sys
import threading
import warnings

from omninoise.backend.errors import SettingError
from omninoise.export.atomic import OutputNameError
from omninoise.export.images import ImageError

from . import bake, hugepages, neural, solid, transfer, wave, zoo
from .common import Help, shown

__all__ = ["main", "build_parser", "COMMANDS", "Terminated", "STOP_SIGNALS"]

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


class Parser(argparse.ArgumentParser):
    """argparse with a bad flag reported as every other bad input is: one line naming it, exit 2 (not the usage
    first); the subcommands' parsers are of this class too. A negative number in any form Python reads (``-1e-3``,
    ``-.5``, ``-inf``) is a value, not an unknown flag (argparse takes only ``-1`` and ``-1.5`` so)."""

    NEGATIVE = re.compile(r"^-(\d+\.?\d*(e[+-]?\d+)?|\.\d+(e[+-]?\d+)?|inf(inity)?|nan)$", re.IGNORECASE)

    def __init__(self, *args, **kw):
        super().__init__(*args, **kw)
        self._negative_number_matcher = self.NEGATIVE

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message}; see '{self.prog} --help'\n")


def build_parser() -> argparse.ArgumentParser:
    ap = Parser(
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


class Terminated(KeyboardInterrupt):
    """SIGTERM or SIGHUP, raised where the command is (as Python raises KeyboardInterrupt for SIGINT), so that the
    write in progress removes its temporary on the way out."""

    def __init__(self, signum: int):
        super().__init__(signum)
        self.signum = signum


def _terminate(signum, frame):
    raise Terminated(signum)


#: the signals that stop a command as Ctrl+C does (exit status 128 + the signal's number)
STOP_SIGNALS = tuple(getattr(signal, n) for n in ("SIGTERM", "SIGHUP") if hasattr(signal, n))


def _reader_left() -> int:
    """The exit status of a command whose standard output's reader left (a pipe into ``head``): 128 + SIGPIPE, as
    a command that signal ended, without a traceback; the interpreter's flush at exit goes to /dev/null."""
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, sys.stdout.fileno())
    return 141


def main(argv: list[str] | None = None) -> int:
    ap = build_parser()
    if not (sys.argv[1:] if argv is None else argv):      # 'omninoise' alone: what it does and its subcommands
        try:
            ap.print_help()
        except BrokenPipeError:
            return _reader_left()
        return 0
    try:
        a = ap.parse_args(argv)
    except BrokenPipeError:             # --help or --version into a pipe whose reader left
        return _reader_left()
    if argv is None and hugepages.wanted(a.command, getattr(a, "size", 0) or 0, os.environ):
        try:   # a large neural image: the same command again, with huge pages (cli/hugepages.py)
            hugepages.reexec()
        except OSError:
            pass
    here = threading.current_thread() is threading.main_thread()
    before = {sig: signal.signal(sig, _terminate) for sig in STOP_SIGNALS} if here else {}
    try:
        return _run(a)
    finally:
        for sig, handler in before.items():
            signal.signal(sig, handler)


#: what each command's --list prints, and the options it reads beside it (the model it lists and how it loads it)
LISTS = {"neural": ("the classes and their parameters", ("model", "precision", "threads")),
         "solid": ("the shipped textures", ()), "zoo": ("the training classes", ())}
#: the flags of the settings not named --SETTING
FLAG_OF = {"out": "-o", **solid.FLAGS}


def _check_list_alone(a: argparse.Namespace) -> None:
    """Refuse an option given beside ``--list`` that the listing does not read (``solid --list -o x.png`` wrote
    nothing and said nothing), as every option that would change nothing is refused."""
    if a.command not in LISTS:
        return
    if a.json and not a.list:
        raise SettingError("--json", "prints --list as JSON: give --list too")
    if not a.list:
        return
    what, reads = LISTS[a.command]
    defaults = vars(build_parser().parse_args([a.command]))
    for key, value in vars(a).items():
        if key not in ("command", "debug", "list", "json", "quiet") + reads and value != defaults.get(key):
            flag = FLAG_OF.get(key, "--" + key.replace("_", "-"))
            raise SettingError(flag, f"--list only prints {what}: leave out {flag}, which would change nothing")


def _check_outputs(a: argparse.Namespace) -> None:
    """The files a command will write (-o, --report), checked before any work: a missing or read-only folder, a
    name past the file system's limit (a frame pattern's '#' counted as the widest frame number), a folder in the
    file's place, or a file the command reads (a photo written over would be lost)."""
    from omninoise.backend.bake import check_not_read, check_one_file
    from omninoise.export.atomic import check_target

    outputs = (("-o", "out"), ("--report", "report"), ("--save-job", "save_job"))
    read = [(f"--{k.replace('_', '-')}" if k != "job" else "the job", v) for k, v in vars(a).items()
            if isinstance(v, str) and k not in ("command", "out", "report", "save_job")]     # the files given
    for flag, attr in outputs:
        path = getattr(a, attr, None)
        if isinstance(path, str) and path:
            if not (flag == "-o" and (getattr(a, "frames", None) or getattr(a, "keys", None))):  # neural animations
                check_one_file(path, flag)
            check_not_read(path, flag, read)
            try:
                check_target(re.sub(r"#+", lambda m: "0" * max(len(m.group()), 10), path))
                if os.path.isdir(path):
                    raise IsADirectoryError(f"output path is a folder, not a file: {path}")
            except OSError as exc:
                raise SettingError(flag, str(exc)) from None
    named = [(flag, getattr(a, k)) for flag, k in outputs if isinstance(getattr(a, k, None), str)]
    for i, (flag, path) in enumerate(named):
        twin = next((f for f, p in named[:i] if os.path.realpath(p) == os.path.realpath(path)), None)
        if twin is not None:
            raise SettingError(flag, f"{os.path.basename(path)} is also {twin}: write it to another file")


def _run(a: argparse.Namespace) -> int:
    """The subcommand, with every way it can end mapped to a one-line message and the documented exit status."""
    def say(what: str) -> None:
        print(f"omninoise {a.command}: {shown(what)}", file=sys.stderr)

    try:
        _check_list_alone(a)
        _check_outputs(a)
        with warnings.catch_warnings():     # numpy's overflow notes: a result they spoil is refused when written
            warnings.simplefilter("ignore", RuntimeWarning)
            return COMMANDS[a.command].run(a)
    except (SettingError, FileNotFoundError, PermissionError, IsADirectoryError, OutputNameError, ImageError) as exc:
        say(f"error: {exc}")
        return 2
    except BrokenPipeError:             # the reader of standard output left (`omninoise neural --list | head`)
        return _reader_left()
    except KeyboardInterrupt as exc:
        signum = getattr(exc, "signum", signal.SIGINT)
        print("", file=sys.stderr)
        say(f"{'interrupted' if signum == signal.SIGINT else 'terminated'}; no partial file was left")
        return 128 + int(signum)
    except Exception as exc:
        from omninoise.backend.grid import Cancelled
        from omninoise.backend.jobs import JobError
        from omninoise.export import NonFiniteError, WriteError

        if isinstance(exc, JobError):
            say(f"error: {exc}")
            return 2
        if isinstance(exc, Cancelled):
            say("cancelled")
            return 130
        if isinstance(exc, (NonFiniteError, WriteError)):     # the writers' last check, a full disk: nothing written
            say(f"error: {exc}")
            return 1
        if a.debug:
            raise
        what = str(exc).splitlines()[0] if str(exc) else ""
        say(f"internal error: {type(exc).__name__}{': ' + what if what else ''} (a bug: please report it with the "
            "command; --debug before the command shows the traceback)")
        return 1
