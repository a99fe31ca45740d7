"""backend/solid/procedural/structure.py: a photo's structure as which way it runs and whether it repeats as a grid,
and the structure error of a solid's walls, which the fit's check and auto (choose.py) hold the procedural solid to."""
import numpy as np

from omninoise.backend.solid.choose import PLANES, STRUCTURE_TOLERANCE, photo_structure, wall_structure
from omninoise.backend.solid.procedural.fit import plane_group
from omninoise.backend.solid.procedural.structure import lattice, orientation, photo_readings, structure_error

RNG = np.random.default_rng(11)


def grey(lum: np.ndarray) -> np.ndarray:
    return np.repeat(np.clip(lum, 0.0, 1.0)[..., None], 3, axis=2)


def tiles(side: int, tile: int, phase=(0, 0)) -> np.ndarray:
    """Square tiles ``tile`` px wide with dark joints 3 px wide and a little grain."""
    y, x = np.mgrid[0:side, 0:side]
    joint = (((x + phase[0]) % tile) < 3) | (((y + phase[1]) % tile) < 3)
    return grey(np.where(joint, 0.15, 0.7) + 0.04 * RNG.standard_normal((side, side)))


def planks(side: int, width: int, upright: bool) -> np.ndarray:
    """Boards ``width`` px wide with streaks along them, standing up (streaks along z) or lying."""
    streaks = np.cumsum(RNG.standard_normal((side, side)), axis=0) * 0.02
    lum = 0.5 + 0.2 * np.sin(2 * np.pi * np.arange(side) / width)[None, :] + streaks - streaks.mean(0)
    return grey(lum if upright else lum.T)


def stones(side: int, size: int) -> np.ndarray:
    """Irregular blotches about ``size`` px across: smoothed white noise."""
    f = np.fft.fftfreq(side)
    noise = np.real(np.fft.ifft2(np.fft.fft2(RNG.standard_normal((side, side)))
                                 * np.exp(-2 * (np.pi * size / 4) ** 2 * (f[:, None] ** 2 + f ** 2))))
    return grey(0.5 + 0.2 * noise / noise.std())


def test_orientation_reads_which_way_planks_run():
    up, lying, blotches = (orientation(planks(128, 20, True)), orientation(planks(128, 20, False)),
                           orientation(stones(128, 16)))
    assert np.linalg.norm(up) > 0.6 and np.linalg.norm(lying) > 0.6 and np.linalg.norm(blotches) < 0.2
    assert up[0] > 0.6 and lying[0] < -0.6        # gradients across upright boards run along x
    assert np.linalg.norm(up - lying) > 1.2


def test_lattice_reads_a_grid_at_its_repeats_and_not_stones():
    reading, lags = photo_readings(tiles(256, 40), 96)
    assert lags == (40.0, 40.0)
    assert reading[2] > 0.6 and np.linalg.norm(reading[:2]) < 0.1
    assert lattice(tiles(128, 40, (7, 19)), *lags) > 0.6           # a cut of two or three tiles reads the same
    assert lattice(stones(128, 24), *lags) < 0.2
    assert abs(lattice(tiles(128, 40), 200.0, 200.0)) <= 1.0        # lags past the cut are read at 3/4 of it
    assert photo_readings(planks(256, 120, True), 96)[1][0] == 96.0   # a photo's repeat past the cuts' reach


def test_a_grid_s_own_cuts_hold_its_structure_and_stones_or_stripes_do_not():
    photo = tiles(256, 40)
    reading, lags = photo_readings(photo, 96)
    own = structure_error([tiles(128, 40, (k, 3 * k)) for k in range(4)], reading, lags)
    blotches = structure_error([stones(128, 30) for _ in range(4)], reading, lags)
    stripes = structure_error([planks(128, 40, False) for _ in range(4)], reading, lags)
    assert own < 0.1 and blotches > 0.5 and stripes > 0.5
    assert blotches - own > STRUCTURE_TOLERANCE


def test_auto_reads_the_structure_of_the_walls_alone():
    """choose.wall_structure reads the cuts across x and across y of PLANES: a floor or oblique cut of any kind
    leaves it as it is."""
    photo = photo_structure(tiles(256, 40))
    walls = [tiles(128, 40, (5 * i, 2 * i)) for i in range(len(PLANES))]
    others = [stones(128, 30) if plane_group(n) not in ("x", "y") else w for w, (n, _) in zip(walls, PLANES)]
    assert wall_structure(walls, photo) == wall_structure(others, photo) < 0.1
    stony = [stones(128, 30) if plane_group(n) in ("x", "y") else w for w, (n, _) in zip(walls, PLANES)]
    assert wall_structure(stony, photo) > 0.5
