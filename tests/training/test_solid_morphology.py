"""The level-set morphology measure: exact functionals on known shapes, and it ranks shapes by the eye."""
import numpy as np
import pytest

torch = pytest.importorskip("torch")  # omninoise.training needs torch

from omninoise.training.solid.morphology import _functionals, minkowski_curves, morphology_distance
from omninoise.training.solid.photo_eval import pixel_shuffle, random_phase


def _discs(seed, r=10, n=60, S=192):
    g = np.random.default_rng(seed)
    yy, xx = np.mgrid[:S, :S]
    im = np.full((S, S), 0.2)
    for _ in range(n):
        cy, cx = g.uniform(0, S, 2)
        im[(yy - cy) ** 2 + (xx - cx) ** 2 < r * r] = 0.8
    return np.repeat(im[..., None], 3, 2) + g.normal(0, 0.02, (S, S, 3))


def test_functionals_of_known_shapes():
    b = np.zeros((20, 20), bool)
    b[3:7, 3:9] = True                          # one 4 x 6 rectangle: perimeter 20, one component
    assert _functionals(b) == (20 / 400, 1 / 400)
    b[12:18, 10:18] = True
    b[14:16, 12:15] = False                     # a second rectangle with a hole: chi 1 + 1 - 1
    p, chi = _functionals(b)
    assert chi == 1 / 400 and p == (20 + 28 + 10) / 400
    b[:] = False
    b[5, 5] = b[6, 6] = True                    # diagonal neighbours are one 8-connected component
    assert _functionals(b)[1] == 1 / 400


def test_curves_shape_and_ranking():
    a = _discs(1)
    assert minkowski_curves(a).shape == (3, 2, 9)
    rng = np.random.default_rng(0)
    same = morphology_distance(_discs(2), a)
    # another draw of the same process is near; other sizes, random phase and a pixel shuffle are far
    others = [morphology_distance(_discs(3, r=25, n=12), a), morphology_distance(_discs(3, r=4, n=400), a),
              morphology_distance(random_phase(a, 192, rng), a), morphology_distance(pixel_shuffle(a, 192, rng), a)]
    assert same < 0.25 and min(others) > 2 * same, (same, others)
    assert morphology_distance(pixel_shuffle(a, 192, rng), a) == pytest.approx(max(others), rel=0.3)
    # a brightness or contrast change is not a change of shape
    assert morphology_distance(0.5 * a + 0.1, a) < 1e-9
