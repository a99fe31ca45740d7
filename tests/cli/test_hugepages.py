"""Huge pages for large neural images (cli/hugepages.py): when the tunable applies, how it is added to the
environment, which commands re-execute themselves, and a real re-execution of the command line."""
from __future__ import annotations

import os
import subprocess
import sys

import pytest

from omninoise.cli import hugepages as hp

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
HERE = dict(system="Linux", libc=("glibc", "2.36"), thp="always [madvise] never\n")


def test_supported_only_with_linux_glibc_235_and_thp():
    assert hp.supported(**HERE)
    assert hp.supported(**dict(HERE, libc=("glibc", "2.35")))
    assert not hp.supported(**dict(HERE, libc=("glibc", "2.34")))
    assert not hp.supported(**dict(HERE, libc=("", "")))                 # musl: platform.libc_ver() is empty
    assert not hp.supported(**dict(HERE, system="Darwin"))
    assert not hp.supported(**dict(HERE, thp="always madvise [never]\n"))
    assert hp.supported(**dict(HERE, thp="[always] madvise never\n"))


def test_environment_adds_the_tunable_once_and_respects_the_switch():
    assert hp.environment({"A": "1"}, **HERE) == {"A": "1", "GLIBC_TUNABLES": hp.TUNABLE}
    assert hp.environment({"GLIBC_TUNABLES": "glibc.malloc.arena_max=2"}, **HERE)["GLIBC_TUNABLES"] == \
        "glibc.malloc.arena_max=2:" + hp.TUNABLE
    mine = {"GLIBC_TUNABLES": "glibc.malloc.hugetlb=0"}                  # the user's own choice stays
    assert hp.environment(mine, **HERE) == mine
    assert hp.environment({hp.OFF_ENV: "0"}, **HERE) == {hp.OFF_ENV: "0"}
    assert hp.environment({"A": "1"}, **dict(HERE, system="Windows")) == {"A": "1"}
    env = {"A": "1"}
    hp.environment(env, **HERE)
    assert env == {"A": "1"}                                              # a copy, never the caller's


def test_only_large_neural_images_reexecute():
    assert hp.wanted("neural", 1024, {}, **HERE) and hp.wanted("neural", 512, {}, **HERE)
    assert not hp.wanted("neural", 256, {}, **HERE)
    assert not hp.wanted("wave", 4096, {}, **HERE)
    assert not hp.wanted("neural", 1024, {"GLIBC_TUNABLES": hp.TUNABLE}, **HERE)     # already re-executed
    assert not hp.wanted("neural", 1024, {hp.OFF_ENV: "0"}, **HERE)


def test_main_reexecutes_a_real_command_line_only(monkeypatch, tmp_path):
    from omninoise.cli import main as cli_main

    calls = []
    monkeypatch.setattr(hp, "wanted", lambda command, size, env: command == "neural" and size >= 512)
    monkeypatch.setattr(hp, "reexec", lambda: calls.append(1) or (_ for _ in ()).throw(OSError("no exec")))
    monkeypatch.setattr(sys, "argv", ["omninoise", "neural", "--size", "512", "--seed", "-1"])
    assert cli_main.main() == 2 and calls == [1]         # tried to re-execute; its failure is not fatal
    assert cli_main.main(["neural", "--size", "512", "--seed", "-1"]) == 2 and calls == [1]   # argv given: never


@pytest.mark.long
@pytest.mark.skipif(not hp.supported(), reason="needs Linux with glibc >= 2.35 and transparent huge pages")
def test_a_large_neural_command_runs_again_with_the_tunable(tmp_path):
    """The real thing: the command line (here ``python -c`` around cli.main) re-executes itself once with
    GLIBC_TUNABLES set and then makes the image; a 256² image does not re-execute."""
    code = ("import os, sys; open(sys.argv[1], 'a').write(os.environ.get('GLIBC_TUNABLES', '-') + '\\n'); "
            "sys.argv = ['omninoise'] + sys.argv[2:]; from omninoise.cli.main import main; sys.exit(main())")
    env = {k: v for k, v in os.environ.items() if k not in ("GLIBC_TUNABLES", hp.OFF_ENV)}
    for size, lines in ((512, ["-", hp.TUNABLE]), (256, ["-"])):
        log, out = tmp_path / f"env{size}.txt", tmp_path / f"n{size}.png"
        r = subprocess.run([sys.executable, "-c", code, str(log), "neural", "--noise", "perlin", "--size", str(size),
                            "--steps", "2", "--threads", "2", "-o", str(out)], cwd=ROOT, env=env,
                           capture_output=True, text=True, timeout=300)
        assert r.returncode == 0, r.stderr
        assert log.read_text().split() == lines and out.stat().st_size > 0
