"""The procedural solids (backend/solid/procedural): each family's geometry, the ramp's colours, the photo's
estimates, the search, the field's JSON, and a fit that finds the family and sizes a photo was drawn with."""
import os

import numpy as np
import pytest

from omninoise.backend.errors import SettingError
from omninoise.backend.grid import Cancelled
from omninoise.backend.solid.model import slice_points
from omninoise.backend.solid.procedural.bonds import Bonds, herringbone
from omninoise.backend.solid.procedural.cells import NEIGHBOURS, Cells, _unique_cubes, cell_w, voronoi
from omninoise.backend.solid.procedural.estimate import GRID, Estimates, estimate, grid_repeat, repeat_length
from omninoise.backend.solid.procedural.family import MAX_PARAM, Param, axis_vector, dot3
from omninoise.backend.solid.procedural.field import DEFAULT_KINDS, FAMILIES, PX_PER_UNIT, ProceduralField
from omninoise.backend.solid.procedural.fit import (FIT_PLANES, STRUCTURE_MARGIN, STRUCTURE_SIDE, ProceduralConfig,
                                                   fit_procedural, kind_starts, oblique_points, pick, plane_group,
                                                   walls_structure)
from omninoise.backend.solid.procedural.structure import TOLERANCE, photo_structure
from omninoise.backend.solid.procedural.loss import SliceLoss
from omninoise.backend.solid.procedural.layers import Layers
from omninoise.backend.solid.procedural.ramp import Ramp, fit_ramp, luminance, photo_colours
from omninoise.backend.solid.procedural.rings import Rings
from omninoise.backend.solid.procedural.search import minimise
from omninoise.backend.solid.procedural.tint import FREQUENCIES, Tint, colour_axis, fit_tint

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CALM = dict(turbulence=0.0, turb_freq=1.0, detail=0.0)


def _points(n=4000, seed=0, extent=2.0):
    return np.random.default_rng(seed).uniform(-extent, extent, (n, 3))


def test_dot3_is_the_matrix_product():
    pts, v = _points(), axis_vector(0.7, 2.1)
    np.testing.assert_allclose(dot3(pts, v), pts @ v, rtol=0, atol=1e-14)
    assert dot3(pts.astype(np.float32), v).dtype == np.float64


def test_a_parameter_maps_to_the_unit_interval_and_back():
    lin, log = Param("a", -2.0, 6.0), Param("b", 0.01, 1.0, log=True)
    for q, v in ((lin, 1.5), (log, 0.1)):
        assert q.from_unit(q.to_unit(v)) == pytest.approx(v)
    assert log.to_unit(0.1) == pytest.approx(0.5)             # half way on the log axis
    assert lin.from_unit(-3.0) == -2.0 and lin.from_unit(7.0) == 6.0     # clipped


def test_the_ramp_reads_linearly_between_stops_and_holds_beyond():
    r = Ramp((0.0, 1.0, 3.0), ((0, 0, 0), (1, 0.5, 0), (1, 1, 1)))
    np.testing.assert_allclose(r(np.array([-1.0, 0.5, 2.0, 9.0])),
                               [[0, 0, 0], [0.5, 0.25, 0], [1, 0.75, 0.5], [1, 1, 1]], atol=1e-7)
    assert Ramp.from_dict(r.to_dict()) == r


def test_the_ramp_gives_the_photo_s_colours_in_the_photo_s_proportions():
    rng = np.random.default_rng(1)
    photo = np.concatenate([np.full((64, 32, 3), (0.1, 0.2, 0.6)), np.full((64, 32, 3), (0.9, 0.7, 0.2))], 1)
    photo += rng.normal(0, 0.02, photo.shape)
    values = rng.uniform(-3.0, 5.0, 20000)                    # any distribution of s
    out = fit_ramp(values, photo_colours(photo))(values)
    assert abs((luminance(out) > 0.5).mean() - 0.5) < 0.02   # half bright, half dark, as the photo
    np.testing.assert_allclose(out.mean(0), photo.reshape(-1, 3).mean(0), atol=0.02)
    flipped = fit_ramp(values, photo_colours(photo), flip=True)(values)
    assert np.corrcoef(luminance(out), values)[0, 1] > 0.8 > -0.8 > np.corrcoef(luminance(flipped), values)[0, 1]
    tied = fit_ramp(np.zeros(100), photo_colours(photo))       # one value everywhere: positions still increase
    assert np.all(np.diff(tied.positions) > 0)


def test_rings_are_circles_about_their_axis():
    p = dict(spacing=0.1, tilt=0.0, azimuth=0.0, centre_u=0.0, centre_v=0.0, grain=0.0, **CALM)
    rings, d = Rings(), None
    d, c = rings.geometry(p)
    np.testing.assert_allclose(d, (0, 0, 1), atol=1e-12)
    angles = np.linspace(0, 2 * np.pi, 50)
    for z in (-1.0, 0.7):         # points at one distance from the axis share one value, at any height
        pts = c + np.stack([0.234 * np.cos(angles), 0.234 * np.sin(angles), np.full(50, z)], 1)
        v = rings.values(p, pts, 0)
        np.testing.assert_allclose(v, v[0], atol=1e-9)
    assert rings.values(p, c[None] + [[0.234, 0, 0]], 0)[0] == pytest.approx(0.34)      # frac(0.234 / 0.1)


def test_layers_are_constant_on_planes_normal_to_theirs():
    p = dict(spacing=0.3, tilt=0.6, azimuth=1.1, profile="tri", **CALM)
    n = axis_vector(0.6, 1.1)
    u = np.cross(n, (0, 0, 1.0))
    pts = 0.17 * n + np.outer(np.linspace(-2, 2, 40), u)
    v = Layers().values(p, pts, 0)
    np.testing.assert_allclose(v, v[0], atol=1e-9)
    saw = Layers().values(dict(p, profile="saw"), _points(), 0)
    assert saw.min() >= 0 and saw.max() < 1


def test_cells_take_one_value_each_and_gaps_take_the_lowest():
    p = dict(size=0.25, stretch=1.0, jitter=0.8, gap=0.0, **CALM)
    pts = _points(6000)
    _, _, cell = voronoi(pts / 0.25, 0.8, 0)
    v = Cells().values(p, pts, 0)
    keys = cell[:, 0].astype(np.int64) * 1000003 + cell[:, 1].astype(np.int64) * 1009 + cell[:, 2].astype(np.int64)
    for k in np.unique(keys)[:40]:
        np.testing.assert_allclose(v[keys == k], v[keys == k][0], atol=1e-12)
    gapped = Cells().values(dict(p, gap=0.2), pts, 0)
    assert gapped.min() == -1.0 and 0.05 < (gapped == -1.0).mean() < 0.9


@pytest.mark.parametrize("scale", [3.0, 1e7])
def test_cells_find_each_point_s_nearest_and_second_nearest_feature_point(scale):
    """Against every feature point of the 27 cubes around each point, one point at a time; 1e7 cubes apart, the
    cubes are told apart by rows, not by one key."""
    from omninoise.backend.wavenoise.wave import white_color4

    q = np.random.default_rng(4).uniform(-scale, scale, (300, 3)).astype(np.float32)
    f1, f2, cell = voronoi(q, 0.9, 5)
    for i in range(len(q)):
        base = np.floor(q[i])
        cubes = (base + NEIGHBOURS).astype(np.float32)
        h = np.stack([white_color4(cubes[:, 0], cubes[:, 1], cubes[:, 2], cell_w(5, 0), k) for k in range(3)], 1)
        d = np.linalg.norm(NEIGHBOURS + 0.9 * h - (q[i] - base), axis=1)     # from the point, within its cube
        order = np.argsort(d)
        assert f1[i] == pytest.approx(d[order[0]], abs=1e-5) and f2[i] == pytest.approx(d[order[1]], abs=1e-5)
        np.testing.assert_array_equal(cell[i], cubes[order[0]])


@pytest.mark.parametrize("spread,points", [(2.0, 20000), (40.0, 30000)])
def test_the_c_kernel_s_cells_are_numpy_s_bit_for_bit(spread, points):
    """voronoi's loop in the C kernel (where it is built, as for the extension) against numpy's: equal F1, F2 and
    cubes, in one batch of neighbours (few cubes) and in many (a cube per point or so)."""
    from omninoise.backend.wavenoise import ckernel

    if not ckernel.available():
        pytest.skip("the C kernel is not built here")
    q = np.random.default_rng(int(spread)).uniform(-spread, spread, (points, 3))
    got = voronoi(q, 0.85, 9)
    before = ckernel.set_enabled(False)
    try:
        want = voronoi(q, 0.85, 9)
    finally:
        ckernel.set_enabled(before)
    for g, w in zip(got, want):
        assert g.dtype == w.dtype == np.float32 and np.array_equal(g, w)


def test_cubes_are_found_once_each_as_numpy_finds_them():
    rng = np.random.default_rng(2)
    for base in (np.floor(rng.uniform(-40, 40, (5000, 3))), np.floor(rng.uniform(-2e6, 2e6, (5000, 3)))):
        base = base.astype(np.float32)
        cubes, back = _unique_cubes(base)
        want = np.unique(base, axis=0)
        assert len(cubes) == len(want)
        np.testing.assert_array_equal(cubes[np.lexsort(cubes.T[::-1])], want)
        np.testing.assert_array_equal(cubes[back], base)


def test_running_bond_courses_shift_by_half_a_unit_and_meet_at_the_corner():
    p = dict(length=0.4, height=0.1, offset=0.5, joint=0.2, **CALM)
    b = Bonds()
    x = np.linspace(0.0, 0.8, 801)
    for y in np.linspace(-1.0, 1.0, 9):                                          # at every depth
        row0 = b.values(p, np.stack([x, np.full_like(x, y), np.full_like(x, 0.0)], 1), 0)   # courses 0 and 1,
        row1 = b.values(p, np.stack([x, np.full_like(x, y), np.full_like(x, 0.1)], 1), 0)   # a quarter up
        assert (row0[np.min(np.abs(x[:, None] - [0.3, 0.7]), 1) < 0.0095] == -1.0).all()    # head joints, a
        assert (row1[np.min(np.abs(x[:, None] - [0.1, 0.5]), 1) < 0.0095] == -1.0).all()    # quarter unit on
    # the x wall and the y wall show their bed joints at the same heights (courses continue round a corner)
    front = b.values(p, slice_points(64, 128.0, "y", (0, 0.013, 0)), 0).reshape(64, 64)
    side = b.values(p, slice_points(64, 128.0, "x", (0.013, 0, 0)), 0).reshape(64, 64)
    np.testing.assert_array_equal((front == -1).all(1), (side == -1).all(1))
    assert (front == -1).all(1).sum() >= 4


@pytest.mark.parametrize("offset", [0.0, 0.5])
def test_a_cube_s_faces_at_round_coordinates_cut_units_not_a_bed_or_head_joint(offset):
    """Units 1/2 long and courses 1/4 high: the planes x, z = -1, 0, 1 (the default cube's faces, and cuts through
    the origin) lie on joints unless the courses' and units' phases move them off; each shows joint on a share
    of its area near the share of a cut anywhere, not most of it."""
    b = Bonds()
    p = dict(length=0.5, height=0.25, offset=offset, joint=0.15, **CALM)
    t = np.random.default_rng(2).uniform(-2.0, 2.0, (20000, 2))
    anywhere = (b.values(p, np.random.default_rng(0).uniform(-2.0, 2.0, (40000, 3)), 3) == -1.0).mean()
    for axis in (0, 2):
        for c in (-1.0, 0.0, 1.0):
            face = np.insert(t, axis, c, axis=1)
            share = (b.values(p, face, 3) == -1.0).mean()
            assert share < anywhere + 0.1, (axis, c, share, anywhere)


def test_a_wall_cut_along_a_depth_joint_shows_scattered_units_not_a_face_of_mortar():
    """A stack bond of units 1/2 long cut along y at every depth through one unit: each row of units is moved
    into the wall by its own fraction, so no cut shows more than a few units' depth joints (a cut at y = 0, a
    cube's face at -1 or 1, showed nothing but joint when every unit's depth joints lay in one plane), and the
    cuts show joint on the same share of their area on average as cuts anywhere."""
    b = Bonds()
    p = dict(length=0.5, height=0.25, offset=0.0, joint=0.15, **CALM)
    xz = np.random.default_rng(1).uniform(-2.0, 2.0, (20000, 2))
    shares = []
    for y in np.linspace(0.0, 0.5, 101):
        wall = np.stack([xz[:, 0], np.full(len(xz), y), xz[:, 1]], 1)
        shares.append((b.values(p, wall, 3) == -1.0).mean())
    anywhere = (b.values(p, np.random.default_rng(0).uniform(-2.0, 2.0, (40000, 3)), 3) == -1.0).mean()
    assert max(shares) < 0.4, (max(shares), anywhere)
    assert np.mean(shares) == pytest.approx(anywhere, abs=0.02)


@pytest.mark.parametrize("family, params", [
    ("bonds", dict(length=0.4, height=0.1, offset=0.5, joint=0.2)),
    ("bonds", dict(length=0.3, height=0.1, offset=0.5, joint=0.2, pattern="herringbone45")),
    ("cells", dict(size=0.2, stretch=1.0, jitter=0.9, gap=0.1))])
def test_the_gap_mask_is_1_in_the_joints_0_inside_the_units_and_linear_between(family, params):
    """ProceduralField.gaps (the node group's Gap Mask): 1 where the value is the gap's -1, 0 where a unit or cell
    has its own value, and 1 - e between, e the value's share of the unit's own (turbulence and detail at 0)."""
    ramp = Ramp((-1.0, 2.0), ((0.0, 0.0, 0.0), (1.0, 1.0, 1.0)))
    f = ProceduralField(family, dict(params, **CALM), ramp, seed=2)
    pts = np.random.default_rng(3).uniform(-1.0, 1.0, (20000, 3))
    g, s = f.gaps(pts), f.values(pts)
    d, r = (FAMILIES[family].units if family == "bonds" else FAMILIES[family].cells)(f.params, pts, 2)
    np.testing.assert_allclose(s, (1.0 - g) * (1.0 + r) - 1.0, atol=1e-12)
    assert ((g == 1.0) == (s == -1.0)).all() and ((g == 0.0) == np.isclose(s, r)).all()
    assert 0.05 < (g == 1.0).mean() < 0.6 and 0.2 < (g == 0.0).mean() < 0.9 and ((g > 0) & (g < 1)).mean() > 0.02
    with pytest.raises(SettingError, match="layers have no gaps: a gap mask is drawn for cells, bonds"):
        ProceduralField("layers", dict(spacing=0.2, tilt=0.0, azimuth=0.0, profile="saw", **CALM), ramp).gaps(pts)


@pytest.mark.parametrize("n", [1.0, 2.0, 4.0])
def test_a_herringbone_tiles_the_plane_with_units_n_long_half_along_half_across(n):
    """Every point lies in its unit's rectangle (1 by n widths, along x or across it), one unit has one
    rectangle, and the units along and across cover the plane alike."""
    x, z = np.random.default_rng(0).uniform(-30.0, 30.0, (2, 40000))
    d, t, k, across = herringbone(x, z, n)
    lo_x, lo_z = t - n * k, t + across + n * k
    hi_x, hi_z = lo_x + 1.0 + (1.0 - across) * (n - 1.0), lo_z + 1.0 + across * (n - 1.0)
    assert ((x >= lo_x) & (x <= hi_x) & (z >= lo_z) & (z <= hi_z)).all()
    np.testing.assert_allclose(d, np.minimum.reduce([x - lo_x, hi_x - x, z - lo_z, hi_z - z]), atol=1e-12)
    _, unit = np.unique(np.stack([t, k, across], 1), axis=0, return_inverse=True)
    rect = np.stack([lo_x, lo_z, hi_x, hi_z], 1)
    first = np.full(unit.max() + 1, -1)
    first[unit.ravel()[::-1]] = np.arange(len(x))[::-1]
    np.testing.assert_array_equal(rect, rect[first[unit.ravel()]])
    assert abs(across.mean() - 0.5) < 0.02


def test_herringbone_bonds_zigzag_on_the_wall_and_refuse_an_unknown_pattern():
    """The 90-degree herringbone's wall holds as many units along x as across; the turned one's zigzag repeats
    along x every sqrt(2) widths; a field without a pattern is laid in courses."""
    b = Bonds()
    p = dict(length=0.2, height=0.1, offset=0.5, joint=0.2, **CALM)
    wall = slice_points(128, 128.0, "y", (0.013, 0.031, 0.017))
    flat = b.values(dict(p, pattern="herringbone"), wall, 0).reshape(128, 128)
    turned = b.values(dict(p, pattern="herringbone45"), wall, 0).reshape(128, 128)
    assert 0.15 < (flat == -1).mean() < 0.5 and 0.15 < (turned == -1).mean() < 0.5
    step = int(round(np.sqrt(2.0) * 0.1 * 128))                                  # 18 px: one repeat along x
    same = (turned[:, step:] == -1) == (turned[:, :-step] == -1)
    assert same.mean() > 0.95 and ((flat[:, step:] == -1) == (flat[:, :-step] == -1)).mean() < 0.85
    ramp = Ramp((-1.0, 2.0), ((0.0, 0.0, 0.0), (1.0, 1.0, 1.0)))
    np.testing.assert_array_equal(ProceduralField("bonds", p, ramp).values(wall), b.values(p, wall, 0))
    assert ProceduralField("bonds", p, ramp).params["pattern"] == "courses"
    with pytest.raises(SettingError, match="pattern must be one of courses, herringbone, herringbone45"):
        ProceduralField("bonds", dict(p, pattern="basket"), ramp)


def test_estimates_read_a_stripe_photo_s_period_and_direction():
    H = W = 256
    r, c = np.mgrid[0:H, 0:W]
    for period, angle in ((24.0, 0.0), (16.0, np.pi / 2), (20.0, np.pi / 4)):
        # a wave whose vector points at ``angle`` (x right, z up = rows up)
        phase = (c * np.cos(angle) - r * np.sin(angle)) / period
        photo = np.repeat((0.5 + 0.4 * np.sin(2 * np.pi * phase))[..., None], 3, 2)
        e = estimate(photo, PX_PER_UNIT)
        assert e.spacing * PX_PER_UNIT == pytest.approx(period, abs=1.5), (period, angle)
        assert abs(np.sin(e.angle - angle)) < 0.05
    assert repeat_length(np.exp(-np.arange(100) / 10.0)) == pytest.approx(4 * 7, abs=1)   # no peak: 4 x half-fall
    # a lattice correlates again at two and three tiles, as high or a little higher: the repeat is one tile
    lags = np.arange(120)
    tiles = 1 - 0.1 * (lags >= 5) + sum(h * np.exp(-0.5 * ((lags - k) / 1.5) ** 2)
                                        for k, h in ((18, 0.8), (36, 0.85), (54, 0.84)))
    assert repeat_length(tiles) == pytest.approx(18, abs=1)
    tiles[18] = 0.2                                        # one tile's peak too low: it is no repeat, two tiles are
    tiles[17] = tiles[19] = 0.1
    assert repeat_length(tiles) == pytest.approx(36, abs=1)


def test_gaps_take_the_ramp_s_end_that_the_photo_s_grout_shows():
    """A grid of tiles with dark grout skews the photo's luminance dark, with pale mortar bright: the gapped
    families start with their gaps at that end of the ramp (flip off for dark), the others try both orders."""
    r, c = np.mgrid[0:128, 0:128]
    grout = ((r % 32) < 3) | ((c % 32) < 3)
    tiles = 0.55 + 0.1 * np.random.default_rng(0).standard_normal((128, 128))
    for colour, dark in ((0.1, True), (0.95, False)):
        photo = np.repeat(np.where(grout, colour, tiles)[..., None], 3, 2)
        est = estimate(photo, PX_PER_UNIT)
        assert est.dark_gaps is dark
        for starts in (Cells().starts(est), Bonds().starts(est), Bonds().herringbone_starts(est)):
            assert {s["flip"] for s in starts} == {not dark}
        assert {s["flip"] for s in Layers().starts(est)} == {False, True}
        assert {s["flip"] for s in Rings().starts(est)} == {False, True}


@pytest.mark.parametrize("spacing_z, stretches", [(0.156, {0.4073, 1.0}), (0.36, {0.9399}), (0.9, {2.3499, 1.0})])
def test_cells_start_round_as_well_where_the_photo_s_spacings_up_and_across_differ(spacing_z, stretches):
    """Stones' repeats up and across a photo are weak autocorrelation peaks (a photo of round stones read 0.156
    up, 0.383 across): cells start as tall as those say and round too, unless they nearly agree."""
    est = Estimates(spacing=0.383, angle=0.0, spacing_x=0.383, spacing_z=spacing_z, diagonals=(0.5, 0.5),
                    courses=(0.2, 0.0), dark_gaps=True)
    starts = Cells().starts(est)
    assert {round(s["stretch"], 4) for s in starts} == stretches
    assert len(starts) == 2 * len(stretches) * len({s["size"] for s in starts})


def test_nelder_mead_finds_a_bowl_s_bottom_within_its_budget():
    calls = []

    def f(x):
        calls.append(x)
        return float(np.sum((x - [0.3, 0.7, 0.55]) ** 2))

    x, fx = minimise(f, [0.5, 0.5, 0.5], 0.1, budget=120)
    assert fx < 1e-4 and len(calls) == 120
    assert minimise(f, [0.5, 0.5, 0.5], 0.1, budget=2)[1] < np.inf and len(calls) == 122    # stops inside the simplex
    x, _ = minimise(lambda x: float(np.sum((x - 2.0) ** 2)), [0.5, 0.5], 0.1, budget=60)   # the bottom outside
    np.testing.assert_allclose(x, [1.0, 1.0], atol=1e-3)


def test_a_field_reads_back_from_json_and_refuses_bad_parameters():
    p = dict(length=0.4, height=0.1, offset=0.5, joint=0.2, turbulence=0.3, turb_freq=2.0, detail=0.2, flip=True)
    ramp = Ramp((-1.0, 0.0, 2.0), ((0.2, 0.1, 0.1), (0.5, 0.3, 0.2), (0.8, 0.6, 0.5)))
    f = ProceduralField("bonds", p, ramp, seed=3)
    g = ProceduralField.from_dict(f.to_dict())
    pts = _points(3000)
    a = f.evaluate(pts)
    np.testing.assert_array_equal(a, g.evaluate(pts))
    assert a.dtype == np.float32 and np.isfinite(a).all() and a.min() >= 0 and a.max() <= 1
    np.testing.assert_array_equal(f.evaluate(pts[:, :2]), f.evaluate(np.c_[pts[:, :2], np.zeros(3000)]))
    with pytest.raises(SettingError, match="unknown procedural family 'tiles'"):
        ProceduralField("tiles", p, ramp)
    with pytest.raises(SettingError, match="height must be a finite number, got nan"):
        ProceduralField("bonds", dict(p, height=float("nan")), ramp)
    with pytest.raises(SettingError, match=r"height must be at least 0.01, got 0.0"):
        ProceduralField("bonds", dict(p, height=0.0), ramp)
    with pytest.raises(SettingError, match=r"joint must be in \[0.0, 0.5\], got 0.6"):
        ProceduralField("bonds", dict(p, joint=0.6), ramp)
    edited = ProceduralField("bonds", dict(p, length=3.0, turbulence=4.0), ramp)    # beyond the search, drawn
    assert edited.params["length"] == 3.0 and np.isfinite(edited.evaluate(pts)).all()
    with pytest.raises(SettingError, match="profile must be one of saw, tri"):
        ProceduralField("layers", dict(spacing=0.2, tilt=0.0, azimuth=0.0, **CALM), ramp)
    with pytest.raises(Cancelled):
        f.evaluate(pts, chunk=100, cancel=lambda: True)
    tint = Tint(2.0, (-0.3, 0.0, 0.3), (-0.1, 0.0, 0.2), (0.6, -0.8, 0.0))
    t = ProceduralField("bonds", p, ramp, seed=3, tint=tint)
    assert ProceduralField.from_dict(t.to_dict()).tint == tint and "tint" not in f.to_dict()
    np.testing.assert_allclose(t.evaluate(pts), np.clip(a + tint(pts, 3), 0, 1), atol=1e-6)
    with pytest.raises(SettingError, match="the tint's frequency must be a positive number"):
        ProceduralField("bonds", p, ramp, tint=Tint(0.0, (0.0, 1.0), (0.0, 0.1), (1.0, 0.0, 0.0)))


@pytest.mark.parametrize("family", sorted(FAMILIES))
def test_every_parameter_is_drawn_finite_up_to_its_limit_and_refused_past_it(family):
    """A saved solid edited by hand (or a node group's inputs) may take any parameter up to +-MAX_PARAM, each drawn
    finite; past it the parameter is refused, naming it (a rings centre of 1e300 drew NaN, a turbulence frequency
    of 1e300 infinite points)."""
    ramp = Ramp((-1.0, 0.0, 2.0), ((0.2, 0.1, 0.1), (0.5, 0.3, 0.2), (0.8, 0.6, 0.5)))
    params = FAMILIES[family].params()
    base = {q.name: q.lo for q in params} | {"layers": {"profile": "tri"}}.get(family, {})
    pts = _points(500)
    for q in params:
        for sign in (1, -1):
            v = sign * MAX_PARAM
            if (q.floor and v < q.lo) or (q.cap and v > q.hi):
                continue                # outside what the parameter takes anyway
            drawn = ProceduralField(family, dict(base, **{q.name: v}), ramp).evaluate(pts)
            assert np.isfinite(drawn).all(), (q.name, v)
            with pytest.raises(SettingError, match=f"{q.name} must lie within"):
                ProceduralField(family, dict(base, **{q.name: 10 * v}), ramp)


def test_oblique_planes_are_square_grids_of_photo_pixels():
    pts = oblique_points(8, 128.0, (0.6, 0.5, 0.62), (1.0, 2.0, 3.0)).reshape(8, 8, 3)
    n = np.array([0.6, 0.5, 0.62]) / np.linalg.norm([0.6, 0.5, 0.62])
    np.testing.assert_allclose((pts - [1.0, 2.0, 3.0]) @ n, 0.0, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(pts[0, 1] - pts[0, 0]), 1 / 128.0)
    np.testing.assert_allclose(np.linalg.norm(pts[1, 0] - pts[0, 0]), 1 / 128.0)
    np.testing.assert_allclose(oblique_points(8, 128.0, (0, 1, 0), (0, 0.5, 0)),
                               slice_points(8, 128.0, "y", (0, 0.5, 0)))


def test_the_loss_weighs_each_group_of_cuts_alike():
    """Walls that match and a floor that does not: pooled, the floor is one cut in three; grouped by axis, it is half
    the loss.  The same slices always score the same (the draws are fixed)."""
    rng = np.random.default_rng(3)
    photo = np.clip(0.5 + 0.2 * rng.standard_normal((128, 128, 3)), 0, 1)
    crops = [photo[:48, :48], photo[60:108, 70:118]]
    flat = np.full((48, 48, 3), 0.5)
    grouped, pooled = SliceLoss(photo, 48, ["x", "y", "z"]), SliceLoss(photo, 48, ["x", "x", "x"])
    walls_only = grouped(crops + [crops[0]])
    assert grouped(crops + [flat]) > pooled(crops + [flat]) > walls_only
    assert grouped(crops + [flat]) == grouped(crops + [flat])
    assert [plane_group(n) for n, _ in FIT_PLANES] == ["x", "x", "y", "y", "z", "z", "oblique", "oblique"]
    with pytest.raises(ValueError, match="expected 3 slices"):
        grouped(crops)


def test_a_photo_drawn_by_a_family_is_fitted_by_that_family():
    """Stones drawn with known sizes (cells: every cut of the solid, straight or oblique, shows stones like the
    photo's, so the fit's loss, which weighs every group of cuts alike, can find its family): the fit picks cells
    of the photo's scale.  Within +-25 % of the true size the loss of one draw does not tell sizes apart (160 at
    the size drawn, 158 at 1.25 times it, 118 to 177 over two seeds), so the size is asked within 50 %."""
    truth = ProceduralField("cells", dict(size=0.2, stretch=1.0, jitter=0.9, gap=0.12, turbulence=0.1,
                                          turb_freq=2.0, detail=0.1, flip=False),
                            Ramp((-1.0, 0.0, 2.0), ((0.1, 0.1, 0.1), (0.55, 0.25, 0.2), (0.75, 0.4, 0.3))), seed=5)
    photo = truth.image(192, offset=(0.0, 0.1, 0.0))
    fit = fit_procedural(photo, ProceduralConfig(budget=24, finalists=2, seed=1))
    assert fit.field.family == "cells", (fit.scores, fit.structure)
    assert fit.field.params["size"] == pytest.approx(0.2, rel=0.5)
    assert set(fit.structure) == set(fit.scores) and fit.field.family == pick(fit.scores, fit.structure)
    starts = sum(len(f.starts(estimate(photo, PX_PER_UNIT))) for f in FAMILIES.values())
    assert fit.tried == 2 * starts + 2 * 24 + 2 * (len(FREQUENCIES) + 1)


def test_the_check_keeps_the_closest_finalist_unless_a_near_one_holds_the_structure_better():
    """Stage 7's pick: the closest by the check's distance, unless another within STRUCTURE_MARGIN of it has a
    structure error lower by more than the tolerance."""
    near, far = 1.0 + 0.5 * STRUCTURE_MARGIN, 1.0 + 2.0 * STRUCTURE_MARGIN
    assert pick({"layers": 100.0, "bonds": 120.0}, {}) == "layers"
    assert pick({"layers": 100.0, "bonds": 100.0 * near}, {"layers": 1.2, "bonds": 0.4}) == "bonds"
    assert pick({"layers": 100.0, "bonds": 100.0 * far}, {"layers": 1.2, "bonds": 0.4}) == "layers"
    assert pick({"layers": 100.0, "bonds": 100.0 * near}, {"layers": 0.5, "bonds": 0.5 - 0.5 * TOLERANCE}) == "layers"
    assert pick({"layers": 100.0 * near, "bonds": 100.0}, {"layers": 0.3, "bonds": 1.2}) == "layers"
    assert pick({"cells": 101.0, "rings": 100.0, "layers": 100.0 * near},
                {"cells": 0.2, "rings": 0.9, "layers": 0.1}) == "layers"


def test_a_wall_in_courses_holds_a_brick_photo_s_structure_and_blotches_do_not():
    """What stage 7 reads: a running bond's walls hold the structure of a photo drawn by it (the cuts across x show
    the units' depth, courses too); layers of blotches with the photo's colours (a brick wall's closest finalist by
    patch statistics on one of the held-out photos) are farther by more than the tolerance."""
    ramp = Ramp((-1.0, 0.0, 2.0), ((0.9, 0.9, 0.85), (0.45, 0.2, 0.15), (0.6, 0.3, 0.2)))
    truth = ProceduralField("bonds", dict(length=0.5, height=0.25, offset=0.5, joint=0.12, turbulence=0.05,
                                          turb_freq=2.0, detail=0.05, flip=True), ramp, seed=3)
    blotches = ProceduralField("layers", dict(spacing=0.3, tilt=0.0, azimuth=0.0, profile="tri", turbulence=0.6,
                                              turb_freq=3.0, detail=0.2, flip=False), ramp, seed=3)
    photo = truth.image(256, offset=(0.0, 0.0, 0.0))
    readings = photo_structure(photo, STRUCTURE_SIDE)
    courses, blotched = (walls_structure(f, PX_PER_UNIT, readings) for f in (truth, blotches))
    assert courses < 0.3 and blotched - courses > TOLERANCE, (courses, blotched)
    assert pick({"layers": 150.0, "bonds": 150.0 * (1.0 + 0.5 * STRUCTURE_MARGIN)},
                {"layers": blotched, "bonds": courses}) == "bonds"


@pytest.mark.parametrize("length, height, offset", [(0.5, 0.25, 0.5), (0.3, 0.3, 0.0), (0.4, 0.2, 0.25),
                                                    (0.36, 0.18, 1 / 3)])
def test_a_wall_s_courses_are_read_off_the_photo_and_kept_by_the_fit(length, height, offset):
    """A wall drawn in courses (a running bond, a stack bond of square tiles, bonds shifted by a quarter and a
    third of a unit): the estimate reads the units' length, and the courses' height and shift, and a fit asked for
    bonds keeps them (the fit's loss does not see which way a lattice's units line up)."""
    ramp = Ramp((-1.0, 0.0, 2.0), ((0.9, 0.9, 0.85), (0.45, 0.2, 0.15), (0.6, 0.3, 0.2)))
    truth = ProceduralField("bonds", dict(length=length, height=height, offset=offset, joint=0.12, turbulence=0.05,
                                          turb_freq=2.0, detail=0.05, flip=True), ramp, seed=3)
    photo = truth.image(256, offset=(0.0, 0.0, 0.0))
    est = estimate(photo, PX_PER_UNIT)
    assert est.spacing_x == pytest.approx(length, abs=1.5 / PX_PER_UNIT)
    assert est.courses[0] == pytest.approx(height, abs=1.5 / PX_PER_UNIT)
    assert min(abs(est.courses[1] - offset), 1 - abs(est.courses[1] - offset)) < 0.03, est.courses
    fit = fit_procedural(photo, ProceduralConfig(side=64, budget=8, families=("bonds",))).field
    assert (fit.params["length"], fit.params["height"], fit.params["offset"]) == (
        Bonds().starts(est)[0]["length"], est.courses[0], est.courses[1])


@pytest.mark.parametrize("photo, length, height, offset", [
    ("photos/val/brick__tex_trak_trak4_brick2a.jpg", 64, 32, 0.5),     # a running bond of 64 x 32 px bricks
    ("structured/tile__tile01.jpg", 64, 64, 0.0),                      # grids of square tiles
    ("structured/tile__tile02.jpg", 37, 37, 0.0),
    ("structured/tile__tile03.jpg", 43, 43, 0.0)])
def test_held_out_walls_are_read_as_they_are_laid(photo, length, height, offset):
    """The courses of photos the evaluation holds out (their sizes counted by eye in px): a running bond, and tile
    grids as stack bonds, not running bonds of half-height units."""
    from omninoise.export import read_rgb

    est = estimate(read_rgb(os.path.join(ROOT, "data", photo)), PX_PER_UNIT)
    assert est.spacing_x * PX_PER_UNIT == pytest.approx(length, abs=2)
    assert est.courses[0] * PX_PER_UNIT == pytest.approx(height, abs=2)
    assert min(abs(est.courses[1] - offset), 1 - abs(est.courses[1] - offset)) < 0.05, est.courses


@pytest.mark.parametrize("photo, grid", [
    ("photos/val/brick__tex_trak_trak4_brick2a.jpg", True), ("structured/tile__tile01.jpg", True),
    ("structured/tile__tile03.jpg", True), ("photos/val/paving__forestfloor_pine.jpg", False),
    ("structured/wood__wood17.jpg", False), ("structured/marble__marble02b.jpg", False)])
def test_photos_that_repeat_as_a_grid_are_told_apart(photo, grid):
    """Brick and tile walls repeat as grids, a forest floor, planks and marble do not; a drawn stack bond does, its
    own noise alone does not; and the request asks it only of procedural fits that try kinds besides bonds."""
    from omninoise.backend.solid.request import SolidRequest
    from omninoise.export import read_rgb

    path = os.path.join(ROOT, "data", photo)
    assert (grid_repeat(read_rgb(path)) >= GRID) == grid
    assert SolidRequest(exemplar=path, method="procedural").check().repeats_as_grid() == grid
    assert not SolidRequest(exemplar=path, method="procedural", families=("bonds",)).check().repeats_as_grid()
    assert not SolidRequest(exemplar=path, method="spectral").check().repeats_as_grid()


def test_a_drawn_grid_repeats_as_one_and_its_noise_does_not():
    ramp = Ramp((-1.0, 0.0, 2.0), ((0.9, 0.9, 0.85), (0.45, 0.2, 0.15), (0.6, 0.3, 0.2)))
    wall = ProceduralField("bonds", dict(length=0.3, height=0.3, offset=0.0, joint=0.12, turbulence=0.05,
                                         turb_freq=2.0, detail=0.05, flip=True), ramp, seed=3).image(256)
    assert grid_repeat(wall) >= GRID
    noise = np.random.default_rng(0).random((256, 256, 1)).repeat(3, 2)
    assert grid_repeat(noise) < 0.2


@pytest.mark.parametrize("pattern, n", [("herringbone", 2), ("herringbone", 3), ("herringbone45", 2),
                                        ("herringbone45", 3)])
def test_a_herringbone_photo_asked_for_herringbones_is_fitted_by_its_own(pattern, n):
    """A wall drawn as a herringbone of units n widths long, fitted with families=("herringbone",): the fit finds
    the herringbone's turn, the units' n (read off the wall's repeats: sqrt(2) n widths against sqrt(2), along
    the diagonals for the straight one, along z and x for the turned one) and the units' width within 30 %."""
    ramp = Ramp((-1.0, 0.0, 2.0), ((0.25, 0.25, 0.25), (0.55, 0.25, 0.2), (0.8, 0.45, 0.3)))
    width = 0.1067
    truth = ProceduralField("bonds", dict(length=n * width, height=width, offset=0.5, joint=0.15, turbulence=0.1,
                                          turb_freq=2.0, detail=0.1, pattern=pattern), ramp, seed=5)
    photo = truth.image(160, offset=(0.0, 0.1, 0.0))
    fit = fit_procedural(photo, ProceduralConfig(side=64, budget=16, families=("herringbone",))).field
    assert (fit.family, fit.params["pattern"]) == ("bonds", pattern), fit.params
    assert fit.params["length"] == pytest.approx(n * fit.params["height"]), fit.params
    assert fit.params["height"] == pytest.approx(width, rel=0.3), fit.params
    with pytest.raises(SettingError, match="families"):
        ProceduralConfig(families=("tiles",))
    with pytest.raises(SettingError, match="families"):
        ProceduralConfig(families=())


def test_a_flat_or_tiny_photo():
    """A photo of one colour is drawn by the first kind's first start, not searched: every kind draws it alike."""
    flat = fit_procedural(np.full((64, 64, 3), 0.4, np.float32), ProceduralConfig(side=32, budget=6))
    img = flat.field.image(32)
    assert np.isfinite(img).all() and np.abs(img - 0.4).max() < 1e-5
    starts = kind_starts(DEFAULT_KINDS[0], estimate(np.full((64, 64, 3), 0.4), PX_PER_UNIT))
    assert flat.field.family == DEFAULT_KINDS[0] and flat.tried == len(starts) + len(FREQUENCIES) + 1, flat
    with pytest.raises(SettingError, match="at least 16 x 16 px, got 12 x 40"):
        fit_procedural(np.zeros((40, 12, 3)))


@pytest.mark.parametrize("photo, message", [
    (np.where(np.eye(64)[..., None] > 0, np.nan, 0.5) * np.ones(3), "NaN or infinite"),
    (np.full((64, 64, 3), np.inf), "NaN or infinite"),
    (np.zeros((0, 64, 3)), "got \\(0, 64, 3\\)"),
    ("photo.jpg", "got str"),
])
def test_pixels_that_are_not_a_photo_are_refused_before_the_fit(photo, message):
    """The fit's own entry refuses, naming the exemplar, what the request refuses (a NaN pixel stopped the fit in
    its estimate with a bare ValueError)."""
    with pytest.raises(SettingError, match=message):
        fit_procedural(photo)


@pytest.mark.parametrize("shape", [(20, 4000), (4000, 20), (3000, 40)])
def test_a_strip_is_read_as_a_central_window_that_keeps_its_shorter_side(shape):
    """A photo whose sides differ more than 16 times: resized whole to the fit's 256 px it would be a line of pixels
    (a 20 x 4000 strip: 1 x 256); its central window keeps 16 px across, its frequencies in texture units
    unchanged."""
    from omninoise.backend.solid.pixels import MIN_SIDE, at_most

    strip = np.random.default_rng(1).random((*shape, 3)).astype(np.float32)
    img, ppu = at_most(strip, PX_PER_UNIT, 256)
    short, window = min(shape), min(shape) * 256 // MIN_SIDE
    assert max(img.shape[:2]) == 256 and min(img.shape[:2]) == MIN_SIDE
    assert ppu == pytest.approx(PX_PER_UNIT * MIN_SIDE / short)
    start = (max(shape) - window) // 2
    centre = strip[start:start + window] if shape[0] > shape[1] else strip[:, start:start + window]
    np.testing.assert_array_equal(img, at_most(centre, PX_PER_UNIT, 256)[0])
    photo, same = at_most(np.full((256, 200, 3), 0.5, np.float32), PX_PER_UNIT, 256)    # a photo is left whole
    assert photo.shape == (256, 200, 3) and same == PX_PER_UNIT
    field = fit_procedural(strip, ProceduralConfig(side=32, budget=4, finalists=1, textured=False)).field
    assert np.isfinite(field.image(16)).all()


def test_auto_s_check_gives_the_evaluation_s_two_figures():
    """choose.check_figures: ``axes``, the mean band distance of the groups of PLANES across x, y and z, and
    ``oblique``, that of the oblique cuts."""
    from omninoise.backend.solid.band_distance import band_distance
    from omninoise.backend.solid.choose import PLANES, check_figures

    rng = np.random.default_rng(4)
    photo = np.clip(0.5 + 0.2 * rng.standard_normal((96, 96, 3)), 0, 1)
    images = [np.clip(0.5 + (0.2 if plane_group(n) != "z" else 0.02) * rng.standard_normal((32, 32, 3)), 0, 1)
              for n, _ in PLANES]
    groups = {g: [im for im, (n, _) in zip(images, PLANES) if plane_group(n) == g] for g in ("x", "y", "z", "oblique")}
    assert [len(groups[g]) for g in ("x", "y", "z", "oblique")] == [2, 2, 2, 6]
    f = check_figures(images, photo)
    assert f["axes"] == pytest.approx(np.mean([band_distance(groups[g], photo) for g in "xyz"]), abs=0.01)
    assert f["oblique"] == pytest.approx(band_distance(groups["oblique"], photo), abs=0.01)
    assert band_distance(groups["z"], photo) > 2 * band_distance(groups["x"], photo)      # the faint floor counts


def _blur(x: np.ndarray, sigma: float) -> np.ndarray:
    """A periodic Gaussian blur of a square image (H, H) by sigma px."""
    f = np.fft.fftfreq(x.shape[0])
    return np.real(np.fft.ifft2(np.fft.fft2(x) * np.exp(-2 * (np.pi * sigma) ** 2 * (f[:, None] ** 2 + f ** 2))))


def test_the_tint_draws_the_hues_that_luminance_does_not_tell_apart():
    """Green moss and red leaves of one luminance, in patches: a ramp by luminance gives both one olive.  The tint's
    axis is the green-red one, the fit keeps a tint, and the solid's front is green and red in the photo's
    proportions, spread along that axis almost as far as the photo."""
    rng = np.random.default_rng(4)
    moss = _blur(rng.standard_normal((192, 192)), 10) > 0
    lum = 0.45 + 0.15 * np.tanh(20 * _blur(rng.standard_normal((192, 192)), 3))
    green, red = np.array([0.1, 0.55, 0.1]), np.array([0.75, 0.35, 0.25])      # luminance 0.42 and 0.43
    colour = np.where(moss[..., None], green, red)
    photo = np.clip(colour * (lum / luminance(colour))[..., None], 0, 1)
    axis = (green - red) / np.linalg.norm(green - red)
    a, levels = colour_axis(photo)
    assert abs(a @ axis) > 0.99 and np.all(np.diff(levels) > 0)
    assert levels[0] < -0.3 and levels[-1] > 0.3                 # two hues, not a spread about one
    along = (photo.reshape(-1, 3) - photo.reshape(-1, 3).mean(0)) @ axis
    fitted = fit_procedural(photo, ProceduralConfig(budget=12, seed=1, side=48)).field
    assert fitted.tint is not None and fitted.tint.frequency in FREQUENCIES
    front = fitted.image(128).reshape(-1, 3)
    drawn = (front - front.mean(0)) @ axis
    assert abs((drawn > 0).mean() - moss.mean()) < 0.1 and drawn.std() > 0.7 * along.std()
    plain = ProceduralField(fitted.family, fitted.params, fitted.ramp, fitted.seed).image(128).reshape(-1, 3)
    assert ((plain - plain.mean(0)) @ axis).std() < 0.5 * along.std()        # the ramp alone: near one hue
    t = fit_tint(photo, 4.0, 1)                                  # its stops hold at every frequency: u's quantiles
    u = t.amount(_points(20000, extent=3.0), 1)
    assert abs(np.median(u) - np.median(levels)) < 0.1 and abs((u > 0).mean() - (levels > 0).mean()) < 0.1
