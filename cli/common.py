"""What the subcommands share: the help formatter, the progress bar, threads, and NAME=VALUE parsing."""
from __future__ import annotations

import argparse
import sys
import time

from omninoise.backend import limits
from omninoise.backend.errors import SettingError

__all__ = ["Help", "add_command", "class_args", "Bar", "set_threads", "param_items", "shown", "SHOWN"]

SHOWN = 400     #: at most this many characters of a message are printed


class Help(argparse.RawDescriptionHelpFormatter):
    """Each option's default after its help (unless it has none, is a switch, or the help names it already);
    descriptions and examples kept as written."""

    def _get_help_string(self, action):
        text = action.help or ""
        d = action.default
        if d is None or isinstance(d, bool) or d == [] or d is argparse.SUPPRESS or "default" in text:
            return text
        if action.option_strings or action.nargs in (argparse.OPTIONAL, argparse.ZERO_OR_MORE):
            return text + " (default: %(default)s)"
        return text


def add_command(sub, name: str, help: str, description: str, examples: str):
    return sub.add_parser(name, help=help, description=description, formatter_class=Help,
                          epilog="examples:\n" + "\n".join("  " + ln for ln in examples.strip().splitlines()))


def class_args(g) -> None:
    """The options of one noise class image, shared by ``neural`` and ``zoo``."""
    g.add_argument("--noise", help="class name (see --list)")
    g.add_argument("--param", action="append", default=[], metavar="NAME=VALUE", help="a class parameter (repeat)")
    g.add_argument("--size", type=int, default=256, help="output side in pixels")
    g.add_argument("--seed", type=int, default=0, help="another seed draws another image")
    g.add_argument("-o", "--out", help="output: .png, .exr or .npy")
    g.add_argument("--list", action="store_true", help="print the classes and their parameters")
    g.add_argument("--json", action="store_true", help="with --list: print it as JSON")


class Bar:
    """A progress bar on standard error: ``bar(fraction)``; silent with ``quiet``.  On a terminal it is redrawn in
    place at most every REDRAW_S seconds; written to a file or a pipe (a farm's or a CI's log) it is a line each time
    the work passes another tenth, not a line of carriage returns."""

    REDRAW_S = 0.1      #: the least time between two redraws on a terminal (and the first one is drawn at once)
    STEPS = 10          #: lines written to a file or pipe over the work (and one at its end)

    def __init__(self, quiet: bool, label: str = ""):
        self.quiet, self.t0, self.label, self.done = quiet, time.perf_counter(), label, False
        self.tty = sys.stderr.isatty()
        self.drawn_at, self.step = -float("inf"), -1

    def restart(self) -> None:
        """Start the clock again: a bar made before the stage it shows begins (the drawing after a fit)."""
        self.t0 = time.perf_counter()

    def __call__(self, frac: float, text: str | None = None) -> None:
        """Show ``frac`` of the work done, as the bar or as ``text``."""
        if self.quiet or self.done:
            return
        frac = min(max(float(frac), 0.0), 1.0) if frac == frac else 0.0
        if frac >= 1.0 - 1e-6:      # shares of the work added up reach 1 within rounding (0.25 + 0.25 + 3 x 1/6)
            frac = 1.0
        self.done = frac >= 1.0
        now = time.perf_counter()
        if self.tty:
            if not self.done and now - self.drawn_at < self.REDRAW_S:
                return
        else:
            step = int(frac * self.STEPS)
            if step <= self.step:
                return
            self.step = step
        self.drawn_at = now
        n = int(frac * 30)
        text = f"{self.label}[{'#' * n}{'.' * (30 - n)}] {frac * 100:5.1f}%  {now - self.t0:6.1f}s" \
            if text is None else text
        sys.stderr.write(f"\r{text}" + ("\n" if self.done else "") if self.tty else text.rstrip() + "\n")
        sys.stderr.flush()


def flag_image(flag: str, read, path: str):
    """``read(path)``, one of export's image readers, with an image it cannot use named by ``flag``."""
    from omninoise.export.images import ImageError

    try:
        return read(path)
    except ImageError as exc:
        raise SettingError(flag, str(exc)) from None


def set_threads(n: int, precision: str = "fp32") -> None:
    """The CLI's --threads and --precision as the defaults of every model the command loads."""
    from omninoise.backend.neural.precision import set_default_precision
    from omninoise.backend.onnx_models import set_default_threads

    set_default_threads(limits.threads("--threads", n))
    set_default_precision(precision)


def split_address(address: str) -> tuple:
    """A Dask scheduler's address ``tcp://HOST:PORT``, ``tls://HOST:PORT`` or ``HOST:PORT`` (tcp) -> (scheme, host,
    port) as written (the port a string, unchecked; an IPv6 host keeps its brackets)."""
    scheme, sep, rest = address.partition("://")
    if not sep:
        scheme, rest = "tcp", address
    host, _, port = rest.rpartition(":")
    return scheme, host, port


def param_items(items: list, flag: str) -> dict:
    out = {}
    for item in items:
        key, sep, val = item.partition("=")
        key = key.strip()
        if not sep or not key:
            raise SettingError(flag, f"expected NAME=VALUE, got {item!r}")
        if key in out:
            raise SettingError(flag, f"{key} is given twice")
        try:
            out[key] = float(val)
        except ValueError:
            raise SettingError(flag, f"expected NAME=VALUE with a number, got {item!r}") from None
    return out


def shown(text: str, limit: int = SHOWN) -> str:
    """``text`` as it is safe to print on a terminal: control characters (escape codes, line breaks, a job name's
    terminal title) written as escapes, and cut to ``limit`` characters."""
    out = "".join(c if c.isprintable() else ascii(c)[1:-1] for c in str(text))
    return out if len(out) <= limit else out[:limit - 1] + "…"
