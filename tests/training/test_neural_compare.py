"""python -m bench neural-compare: the card's candidate-against-model table from two evaluation JSONs, refused with one line
when the two were not made with one instrument."""
import json
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def evaluation(fds, classifier_steps=6000, n=32):
    classes = {c: dict(fd=fd, acc=0.5 + 0.1 * i, psd=0.05, psd_low=0.04 + 0.01 * i, param="scale")
               for i, (c, fd) in enumerate(fds.items())}
    return dict(classes=classes, size=64, classifier=dict(steps=classifier_steps, stages=3, threads=2),
                sampler=dict(name="dpmpp_2m", steps=10, spacing="truncated", eta=0.3), model=dict(n=n),
                locality=0.9, seam_tileable=1.03)


def run(tmp_path, a, b, *extra):
    pa, pb = tmp_path / "a.json", tmp_path / "b.json"
    pa.write_text(a if isinstance(a, str) else json.dumps(a))
    pb.write_text(b if isinstance(b, str) else json.dumps(b))
    return subprocess.run([sys.executable, "-m", "bench", "neural-compare", str(pa), str(pb), *extra],
                          capture_output=True, text=True, cwd=ROOT)


def test_the_table_has_the_medians_their_ratio_the_classes_lower_and_the_worst_class(tmp_path):
    before = evaluation({"cells_f1": 100.0, "perlin": 300.0, "gabor": 50.0})
    after = evaluation({"cells_f1": 40.0, "perlin": 90.0, "gabor": 60.0})
    r = run(tmp_path, before, after, "--labels", "old,new")
    assert r.returncode == 0, r.stderr
    out = r.stdout
    assert "| median per-class FD ↓ | 100.0 | **60.0** | 0.60 |" in out  # medians 100 and 60
    assert "**2 of 3**" in out and "worst ratio 1.20 (gabor 50 → 60)" in out
    assert "| perlin | 300.0 | 90.0 | 0.30 |" in out
    assert "| class | FD old | FD new |" in out


def test_two_instruments_are_refused_with_one_line(tmp_path):
    a = evaluation({"cells_f1": 1.0})
    for b, word in ((evaluation({"cells_f1": 1.0}, classifier_steps=600), "classifier"),
                    (evaluation({"cells_f1": 1.0}, n=8), "samples per class"),
                    (evaluation({"perlin": 1.0}), "classes differ")):
        r = run(tmp_path, a, b)
        assert r.returncode == 2 and r.stdout == ""
        lines = r.stderr.strip().splitlines()
        assert len(lines) == 1 and word in lines[0] and lines[0].startswith("neural_compare: error:"), r.stderr
    r = run(tmp_path, a, "{not json")
    assert r.returncode != 0 and "cannot read" in r.stderr and "Traceback" not in r.stderr
    r = run(tmp_path, a, json.dumps({"classes": {}}))
    assert r.returncode != 0 and "is not an evaluation" in r.stderr and "Traceback" not in r.stderr
