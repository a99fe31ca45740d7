"""Run the Blender tests on every supported Blender's ``bpy``: ``python tools/blender_versions.py [--jobs N] VENV ...``.

Each VENV is a virtual environment with one ``bpy`` release and the runtime's
packages (``make test-blender`` builds them: bpy 4.2.0 and the latest 4.2 LTS,
4.3, 4.4, 4.5 LTS, 5.1, 5.2 and 5.3 beside the pinned 5.0 of ``.venv``).  The
tests that use ``bpy`` run there with pytest's JUnit report; the table printed at the end (bpy, Python, passed, skipped,
failed, exit status) is the README's support table.  The run fails when any
test fails or errs, or when a process ends badly, with one exception: the bpy
4.2 and 4.3 wheels crash at interpreter exit (signal 11) after a complete run
whenever a PropertyGroup with an update callback was registered, in code without
any OmniNoise (``tests/blender_scripts/bpy42_exit_crash.py``), and 4.3's exit may
instead wait forever (its draw manager's shader-compiler thread, joined by a
static destructor); that exit is reported, and accepted only when the JUnit
report is complete and green.  A process that has written its report and not
ended :data:`EXIT_GRACE` seconds later is ended.

The venvs' runs go :data:`JOBS` at a time (``--jobs``): one run keeps 1.3 of two cores busy (bpy builds node trees
on one; Cycles and llvmpipe render on both), so two at once end sooner on two cores.  Each run has its own
temporary folders; a line says when each ends.
"""
from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET
from concurrent.futures import ThreadPoolExecutor

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TESTS = ["tests/blender"]  # every test that uses bpy (tests/ mirrors the layers)
KNOWN_EXIT_CRASH = ("4.2.", "4.3.")  # bpy versions whose interpreter exit crashes or hangs (module docstring)
EXIT_GRACE = 120  #: seconds a test process may take to end once its JUnit report is written
JOBS = 2  #: the venvs whose tests run at once


def run(venv: str) -> dict:
    py = os.path.join(venv, "bin", "python")
    info = subprocess.run([py, "-c", "import bpy, sys; print(bpy.app.version_string.split()[0], "
                                     "'%d.%d' % sys.version_info[:2])"], capture_output=True, text=True)
    lines = info.stdout.strip().splitlines()       # bpy may print first ("Unable to initialise audio")
    if info.returncode != 0 or not lines or len(lines[-1].split()) != 2:
        return dict(venv=venv, bpy="?", python="?", ok=False, note="bpy does not import: " + info.stderr[-300:])
    version, python = lines[-1].split()
    with tempfile.TemporaryDirectory() as d:
        xml = os.path.join(d, "report.xml")
        r = _run_tests([py, "-m", "pytest", "-q", "-p", "no:warnings", "-p", "no:cacheprovider",
                        f"--junitxml={xml}", f"--basetemp={os.path.join(d, 'tmp')}", "-rfEs"] + TESTS, xml)
        row = dict(venv=venv, bpy=version, python=python, exit=r.returncode)
        if not os.path.isfile(xml):
            return dict(row, ok=False, note="no test report: " + (r.stdout + r.stderr)[-500:])
        suite = ET.parse(xml).getroot()
        suite = suite if suite.tag == "testsuite" else suite.find("testsuite")
        n, fail, err, skip = (int(suite.get(k, 0)) for k in ("tests", "failures", "errors", "skipped"))
    row.update(passed=n - fail - err - skip, skipped=skip, failed=fail + err)
    reasons = sorted({ln.split(": ", 1)[-1] for ln in r.stdout.splitlines() if ln.startswith("SKIPPED")})
    failed_tests = [ln for ln in r.stdout.splitlines() if ln.startswith(("FAILED", "ERROR"))]
    row["skip_reasons"] = reasons
    green = fail + err == 0 and n > 0
    if r.returncode == 0:
        row.update(ok=green, note="")
    elif r.returncode in (-11, 139, -9) and version.startswith(KNOWN_EXIT_CRASH) and green:
        how = "hangs" if r.returncode == -9 else "crashes"
        row.update(ok=True, note=f"{how} at interpreter exit after the run (bpy {version[:3]} wheel; see module "
                                 "docstring)")
    else:
        row.update(ok=False, note="\n".join(failed_tests) + "\n" + (r.stdout + r.stderr)[-1500:])
    return row


def _report_written(xml: str) -> bool:
    try:
        ET.parse(xml)
        return True
    except (OSError, ET.ParseError):
        return False


def _run_tests(cmd: list, xml: str) -> subprocess.CompletedProcess:
    """``cmd`` run in the repository root with its output captured; ended (exit -9) when it has not ended
    :data:`EXIT_GRACE` seconds after writing its complete JUnit report ``xml``."""
    p = subprocess.Popen(cmd, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    written = None
    while True:
        try:        # a call after a timeout goes on collecting: the output returned at the end is all of it
            out, err = p.communicate(timeout=10)
            return subprocess.CompletedProcess(cmd, p.returncode, out, err)
        except subprocess.TimeoutExpired:
            if written is None and _report_written(xml):
                written = time.monotonic()
            if written is not None and time.monotonic() - written > EXIT_GRACE:
                p.kill()


def _run_and_say(venv: str) -> dict:
    t0 = time.monotonic()
    row = run(venv)
    took = time.monotonic() - t0
    print(f"bpy {row['bpy']} ({venv}): {row.get('passed', 0)} passed, {row.get('failed', 0)} failed"
          f"{'' if row['ok'] else ', FAILED'}, in {took // 60:.0f} min {took % 60:.0f} s", flush=True)
    return row


def main(argv: list) -> int:
    jobs = JOBS
    if argv[:1] == ["--jobs"] and len(argv) > 1 and argv[1].isdigit() and int(argv[1]) > 0:
        jobs, argv = int(argv[1]), argv[2:]
    if not argv or argv[0].startswith("-"):
        print(__doc__)
        return 2
    # the last given (the newest Blender) starts first: its EEVEE compiles longest (bpy 5.3's run alone takes 10.4
    # min, 5.0's 5.9), and the last run to start ends alone; the rows keep the order given
    with ThreadPoolExecutor(max_workers=jobs) as pool:
        rows = list(pool.map(_run_and_say, argv[::-1]))[::-1]
    print("| bpy | Python | passed | skipped | failed | note |")
    print("|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['bpy']} | {r['python']} | {r.get('passed', '-')} | {r.get('skipped', '-')} | "
              f"{r.get('failed', '-')} | {r['note'].splitlines()[0] if r['note'] and r['ok'] else ''} |")
    for r in rows:
        for reason in r.get("skip_reasons", []):
            print(f"  bpy {r['bpy']} skipped: {reason}")
        if not r["ok"]:
            print(f"\nbpy {r['bpy']} ({r['venv']}) FAILED (exit {r.get('exit')}):\n{r['note']}", file=sys.stderr)
    passed = sum(r.get("passed", 0) for r in rows)
    failed = sum(r.get("failed", 0) + (0 if r["ok"] else 1) for r in rows)
    print(f"{passed} passed, {failed} failed")
    return 0 if all(r["ok"] for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
