"""Every field that is read at points (wave noise, cellular wave noise, the solid textures of each method) refuses
points that are not (P, D) finite coordinates with one line naming the points, before any work, and reads no point
as no value."""
import numpy as np
import pytest

from omninoise.backend import Spectrum, WaveSettings, compile_noise
from omninoise.backend.errors import SettingError
from omninoise.backend.solid.model import SolidTextureModel
from omninoise.backend.solid.procedural.field import ProceduralField
from omninoise.backend.solid.procedural.ramp import fit_ramp
from omninoise.backend.solid.spectral_solid import SplineField
from omninoise.backend.solid.synthesis import TileField
from omninoise.backend.paths import solid_models

RNG = np.random.default_rng(0)
CELLS = ProceduralField("cells", dict(size=0.2, stretch=1.0, jitter=0.8, gap=0.1, turbulence=0.2, turb_freq=2.0,
                                      detail=0.1, flip=False),
                        fit_ramp(np.linspace(-1, 1, 8), RNG.uniform(0, 1, (16, 3))), seed=1)


def _fields():
    """{name: (a function of points, the coordinates it reads)}."""
    wave = compile_noise(WaveSettings(dim=3, spectrum=Spectrum("bandpass", 2, 6), directions=8))
    cells = compile_noise(WaveSettings(dim=2, spectrum=Spectrum("bandpass", 2, 6), directions=8, cellular="polytope"))
    model = SolidTextureModel(f"{solid_models()}/gravel_3d")
    return {
        "wave": (wave.evaluate, 3),
        "wave cellular": (lambda p: cells.evaluate(p).distance, 2),
        "procedural": (CELLS.evaluate, 3),
        "procedural gaps": (CELLS.gaps, 3),
        "spectral": (SplineField(RNG.uniform(0, 1, (8, 8, 8, 3)), (0.5, 0.5, 0.5)).evaluate, 3),
        "synthesis": (TileField(RNG.uniform(0, 1, (8, 8, 8, 3)).astype(np.float32), 4.0).evaluate, 3),
        "neural": (lambda p: model.evaluate(p, model.default_code()), 3),
    }


FIELDS = _fields()


@pytest.mark.parametrize("name", list(FIELDS))
@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_a_point_that_is_not_finite_is_refused(name, bad):
    f, dim = FIELDS[name]
    pts = RNG.uniform(-1, 1, (50, dim))
    assert np.isfinite(f(pts)).all()
    pts[7, dim - 1] = bad
    with pytest.raises(SettingError, match="^points: .*NaN or infinite"):
        f(pts)


@pytest.mark.parametrize("name", list(FIELDS))
def test_no_point_no_value(name):
    f, dim = FIELDS[name]
    assert len(f(np.zeros((0, dim)))) == 0


@pytest.mark.parametrize("name", list(FIELDS))
def test_points_of_another_shape_are_refused(name):
    f, dim = FIELDS[name]
    for shape in ((50,), (50, 4), (2, 50, dim)):
        with pytest.raises(SettingError, match="^points: "):
            f(np.zeros(shape))


def test_a_time_that_is_not_finite_is_refused():
    noise = compile_noise(WaveSettings(dim=3, spectrum=Spectrum("bandpass", 2, 6), directions=8, speed=1.0))
    pts = RNG.uniform(-1, 1, (50, 3))
    for time in (np.nan, np.full(50, np.inf)):
        with pytest.raises(SettingError, match="^time: "):
            noise.evaluate(pts, time)
