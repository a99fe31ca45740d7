"""The command line's help: every subcommand has a description, examples and option groups, shows its defaults,
and names no source files."""
import re

import pytest

from omninoise.cli.main import build_parser

SUBCOMMANDS = ("wave", "bake", "neural", "solid", "zoo", "transfer")


def _help(name: str) -> str:
    ap = build_parser()
    sub = next(a for a in ap._actions if a.dest == "command")
    return sub.choices[name].format_help()


@pytest.mark.parametrize("name", SUBCOMMANDS)
def test_every_subcommand_has_a_description_and_runnable_looking_examples(name):
    text = _help(name)
    assert "examples:" in text
    examples = text.split("examples:", 1)[1].strip().splitlines()
    assert examples and all(line.strip().startswith(f"omninoise {name}") for line in examples), examples
    assert not re.search(r"\b[\w/]+\.py\b", text), "the help names a source file"


def test_defaults_are_shown_and_switches_carry_none():
    wave = _help("wave")
    assert re.search(r"--size SIZE\s+samples per axis \(default: 512\)", wave)
    assert "(default: gaussian)" in wave and "(default: 2.0)" in wave
    assert "(default: False)" not in wave and "(default: None)" not in wave
    solid = _help("solid")
    assert "(default: True)" not in solid


def test_options_are_grouped():
    for name, groups in (("wave", ("grid and output", "spectrum", "anisotropy")),
                         ("neural", ("blends", "animation", "inverse design", "sampling and speed")),
                         ("solid", ("photos (the texture-space model)",))):
        text = _help(name)
        for g in groups:
            assert f"\n{g}:\n" in text, (name, g)


def test_version(capsys):
    with pytest.raises(SystemExit) as e:
        build_parser().parse_args(["--version"])
    assert e.value.code == 0
    assert re.match(r"omninoise \d+\.\d+\.\d+ \(wave noise: (C row kernel|numba kernel|numpy)", capsys.readouterr().out)


@pytest.mark.parametrize("argv, first", [
    (["wave", "--dim", "5", "-o", "x.npy"], "omninoise wave: error: argument --dim: invalid choice: 5"),
    (["wave", "--size", "abc", "-o", "x.npy"], "omninoise wave: error: argument --size: invalid int value: 'abc'"),
    (["solid", "--families"], "omninoise solid: error: argument --families: expected one argument"),
    (["neural", "--corners", "perlin", "gabor"], "omninoise neural: error: argument --corners: expected 4"),
    (["wave"], "omninoise wave: error: the following arguments are required: -o/--out"),
    (["bogus"], "omninoise: error: argument SUBCOMMAND: invalid choice: 'bogus'"),
])
def test_a_flag_argparse_cannot_read_is_one_line_and_exit_2(argv, first, capsys):
    """As every other bad input: one line naming the flag (not the usage first), pointing at the help."""
    with pytest.raises(SystemExit) as e:
        build_parser().parse_args(argv)
    err = capsys.readouterr().err
    assert e.value.code == 2 and err.count("\n") == 1 and err.startswith(first), err
    assert err.rstrip().endswith("--help'")


def test_the_command_alone_prints_its_help(capsys):
    """``omninoise`` with nothing after it is a reader asking what it does: the help and its subcommands, exit 0."""
    from omninoise.cli.main import main
    assert main([]) == 0
    out = capsys.readouterr().out
    assert out.startswith("usage: omninoise") and all(name in out for name in SUBCOMMANDS)
