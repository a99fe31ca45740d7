"""bench/solid_strokes.py: the diagonal-power ratio reads stripes' direction, and the bench runs on the shipped model."""
import os

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))




def test_diagonal_ratio_reads_the_stripes_direction(bench_script):
    mod = bench_script("solid_strokes")
    row, col = np.mgrid[0:128, 0:128].astype(np.float64)
    rising = np.repeat(np.sin(2 * np.pi * 0.15 * (col + row))[..., None], 3, axis=2)    # strokes rising to the right
    falling = np.repeat(np.sin(2 * np.pi * 0.15 * (col - row))[..., None], 3, axis=2)
    level = np.repeat(np.sin(2 * np.pi * 0.15 * row)[..., None], 3, axis=2)
    assert mod.diagonal_ratio(rising) > 100 and mod.diagonal_ratio(falling) < 0.01
    assert abs(np.log2(mod.diagonal_ratio(level))) < 0.1
    noise = np.random.default_rng(0).random((128, 128, 3))
    assert abs(np.log2(mod.diagonal_ratio(noise))) < 0.3


def test_bench_measures_and_draws_the_shipped_model(bench_script, tmp_path, capsys):
    mod = bench_script("solid_strokes")
    space = os.path.join(ROOT, "models", "solid", "space")
    out = tmp_path / "s.jpg"
    assert mod.main([space, "--every", "44", "--sheet", str(out), "--photos", "sand__desert"]) == 0
    said = capsys.readouterr().out
    assert "2 held-out photos" in said and "(spin octave)" in said and said.count("log2 diag") == 2
    assert out.stat().st_size > 5000
