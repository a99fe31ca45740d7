"""The command line's progress bar: redrawn in place on a terminal, not more often than it can be read; a line per
tenth of the work in a log file or pipe; silent with --quiet."""
import sys

import pytest

from omninoise.cli import common
from omninoise.cli.common import Bar


def _feed(bar, n=1000):
    for i in range(n + 1):
        bar(i / n)


def test_a_log_gets_a_line_per_tenth_of_the_work(capsys):
    _feed(Bar(False, "fit "))
    err = capsys.readouterr().err
    lines = err.splitlines()
    assert "\r" not in err and err.endswith("\n") and len(lines) == 11
    assert lines[0].startswith("fit [....") and "  0.0%" in lines[0]
    assert lines[-1].startswith("fit [" + "#" * 30 + "] 100.0%")


def test_shares_that_add_up_to_one_within_rounding_end_the_bar(capsys):
    bar = Bar(False)
    for frac in (0.25, 0.5, 0.5 + 1 / 6, 0.5 + 2 / 6, 0.25 + 0.25 + 1 / 6 + 1 / 6 + 1 / 6):
        bar(frac)
    assert bar.done and capsys.readouterr().err.splitlines()[-1].startswith("[" + "#" * 30 + "] 100.0%")
    bar = Bar(False)
    bar(float("nan"))          # a fraction that is no number draws an empty bar, and ends nothing
    assert not bar.done and "  0.0%" in capsys.readouterr().err


def test_a_terminal_redraws_in_place_at_most_ten_times_a_second(capsys, monkeypatch):
    clock = [0.0]
    monkeypatch.setattr(common.time, "perf_counter", lambda: clock[0])
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)
    bar = Bar(False, "bake ")
    for i in range(1001):           # 1000 steps over 2 s
        clock[0] = i * 0.002
        bar(i / 1000)
    err = capsys.readouterr().err
    draws = err.split("\r")[1:]
    assert 20 <= len(draws) <= 22 and err.endswith("\n") and err.count("\n") == 1
    assert draws[0].startswith("bake [....") and draws[-1].startswith("bake [" + "#" * 30 + "] 100.0%")


@pytest.mark.parametrize("tty", [False, True])
def test_quiet_writes_nothing(capsys, monkeypatch, tty):
    monkeypatch.setattr(sys.stderr, "isatty", lambda: tty)
    _feed(Bar(True, "x"))
    assert capsys.readouterr().err == ""
