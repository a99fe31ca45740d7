"""The upright Gaussian rest (backend/solid/upright.py): walls keep a photo's joint spectrum of horizontal and
vertical frequency where the isotropic rest turns it into blotches; the deprojection of horizontal frequencies,
the spectral orientation that gates it and turns diagonal photos level, the check choosing between the kinds, and
the kind stored with a code."""
import json
import os

import numpy as np
import pytest

import omninoise.backend.solid.upright as upright
from omninoise.backend.solid.model import SolidTextureModel, slice_points
from omninoise.backend.solid.pipeline import PhotoConfig, photo_code
from omninoise.backend.solid.gaussian_rest import (COUNT, MIXES, RENDER, GaussianRest, deproject, choose_mix, mix_rests, rest_field,
                                    rest_from_json, rest_to_json, rest_waves)
from omninoise.backend.solid.upright import UPRIGHT_GATE, candidates, circle_inside, orientation, upright_waves

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
PPU = 128.0


def layered_photo(n=128, seed=0, across=(6, 40), along=3, turn_deg=0.0):
    """A Gaussian texture (n, n, 3) of parallel layers: power where the frequency across the layers is in
    ``across`` and the one along them at most ``along`` (cycles per n px), the frequency across them pointing
    ``turn_deg`` degrees from the columns axis (0: vertical stripes, 90: horizontal layers), colours along one
    axis."""
    rng = np.random.default_rng(seed)
    fy, fx = np.meshgrid(np.fft.fftfreq(n), np.fft.fftfreq(n), indexing="ij")
    t = np.radians(turn_deg)
    a, b = (np.cos(t) * fx + np.sin(t) * fy) * n, (-np.sin(t) * fx + np.cos(t) * fy) * n
    keep = (np.abs(a) >= across[0]) & (np.abs(a) <= across[1]) & (np.abs(b) <= along)
    g = np.real(np.fft.ifft2(np.fft.fft2(rng.standard_normal((n, n))) * keep))
    return np.clip(0.45 + 0.08 * (g / g.std())[..., None] * np.array([1.0, 0.8, 0.5]), 0, 1)


def folded_power(img):
    """Power of an image (H, W, 3) (mean removed, summed over channels) and its |horizontal|, |vertical|
    frequencies in cycles per image side: three float64 (H W,)."""
    a = img - img.mean((0, 1))
    P = (np.abs(np.fft.fft2(a.transpose(2, 0, 1))) ** 2).sum(0).ravel()
    fy, fx = np.meshgrid(np.fft.fftfreq(a.shape[0]), np.fft.fftfreq(a.shape[1]), indexing="ij")
    return P, np.abs(fx.ravel()) * a.shape[1], np.abs(fy.ravel()) * a.shape[0]


def walls(waves, n=128):
    """x and y cuts (rows along z) of a rest's solid at full variance, two seeds each: (n, n, 3) float32 each."""
    r = GaussianRest(*waves, 1.0)
    return [rest_field(slice_points(n, PPU, ax, (0.3, 1.7, 2.9)), r, seed).reshape(n, n, 3)
            for ax in "xy" for seed in (1, 2)]


def mean_horizontal(imgs):
    """The power-weighted mean |horizontal frequency| of images, cycles per side."""
    P, h, _ = (np.concatenate(x) for x in zip(*(folded_power(i) for i in imgs)))
    return float((P * h).sum() / P.sum())


def vertical_share(imgs):
    """The share of power whose vertical frequency exceeds the horizontal one."""
    P, h, v = (np.concatenate(x) for x in zip(*(folded_power(i) for i in imgs)))
    return float(P[v > h].sum() / P.sum())


def test_the_circle_deprojection_inverts_its_kernel():
    """Horizontal frequencies of magnitude R on one bin show on walls spread below it (R |cos psi|);
    deproject with circle_inside gives them back, row by row of a 2D table."""
    edges = np.linspace(0, 10, 41)
    R = 0.5 * (edges[:-1] + edges[1:])[None, :]
    K = circle_inside(edges[:-1, None], R) - circle_inside(edges[1:, None], R)
    assert np.allclose(K.sum(0), 1.0)                          # every wave shows somewhere below its magnitude
    p3 = np.zeros((2, 40))
    p3[0, 30], p3[1, 12] = 1.0, 2.0
    p2 = p3 @ K.T
    assert p2[0, 30] < 0.5 and p2[0, :30].sum() > 0.5
    got = deproject(p2, edges, iterations=2000, inside=circle_inside)
    assert got[0].argmax() == 30 and got[0, 30] / got[0].sum() > 0.8
    assert got[1].argmax() == 12 and got[1, 12] / got[1].sum() > 0.8


def test_walls_keep_the_photo_s_layers_where_the_isotropic_rest_loses_them():
    img = layered_photo(turn_deg=90.0)                         # level layers: vertical frequencies
    assert vertical_share([img]) > 0.95
    freq, amp = upright_waves(img, PPU)
    assert freq.shape == (COUNT, 3) and amp.shape == (COUNT, 3)
    up, iso = walls((freq, amp)), walls(rest_waves(img, PPU))
    assert vertical_share(up) > 0.85
    assert vertical_share(iso) < 0.7                           # the isotropic rest spreads it over directions
    var = np.mean([c.reshape(-1, 3).var(0).sum() for c in up])
    assert abs(var / img.reshape(-1, 3).var(0).sum() - 1.0) < 0.15
    cov = np.mean([np.cov(c.reshape(-1, 3).T) for c in up], axis=0)
    assert cov[0, 1] / np.sqrt(cov[0, 0] * cov[1, 1]) > 0.95   # the photo's colours


def test_horizontal_frequencies_are_deprojected_so_walls_show_the_photo_s(monkeypatch):
    img = layered_photo(turn_deg=0.0, seed=2, across=(2, 40))  # upright stripes: horizontal frequencies
    want = mean_horizontal([img])
    got = mean_horizontal(walls(upright_waves(img, PPU)))
    assert abs(got / want - 1.0) < 0.08                        # measured 0.94 (a cut's spectrum cannot dip)
    # without the deprojection walls show each frequency at R |cos psi|, 2 / pi R on average
    monkeypatch.setattr(upright, "deproject", lambda p2, edges, inside: p2)
    flat = mean_horizontal(walls(upright_waves(img, PPU)))
    assert flat / want < 0.75                                  # measured 0.6
    # a floor of the upright solid sees the horizontal frequencies in every direction: no layers
    r = GaussianRest(*upright_waves(img, PPU), 1.0)
    floor = rest_field(slice_points(128, PPU, "z", (0.3, 1.7, 2.9)), r, 1).reshape(128, 128, 3)
    assert orientation(floor)[0] < 0.3


def test_orientation_reads_layers_their_direction_and_isotropic_textures():
    c, a = orientation(layered_photo(turn_deg=90.0))
    assert c > 0.8 and abs(abs(np.degrees(a)) - 90.0) < 3.0
    c, a = orientation(layered_photo(turn_deg=30.0, seed=1))
    assert c > 0.8 and abs(np.degrees(a) - 30.0) < 3.0
    rng = np.random.default_rng(0)
    c, _ = orientation(rng.random((128, 128, 3)))
    assert c < 0.1
    assert orientation(np.full((32, 32, 3), 0.5)) == (0.0, 0.0)


def test_a_diagonal_photo_is_turned_level_before_its_spectrum_is_read():
    """Layers 30 degrees off the columns axis are drawn as upright stripes (turned by 30 degrees), not as a
    lattice of both diagonals (a wall cannot tell psi from psi + pi)."""
    img = layered_photo(turn_deg=30.0, seed=1)
    freq, amp = upright_waves(img, PPU)
    w = (np.abs(amp) ** 2).sum(1)
    h = np.hypot(freq[:, 0], freq[:, 1])
    assert (w * (h > 4 * np.abs(freq[:, 2]))).sum() / w.sum() > 0.8      # nearly all power horizontal
    assert vertical_share(walls((freq, amp))) < 0.1


def test_the_gate_offers_the_upright_rest_only_to_oriented_photos():
    rng = np.random.default_rng(1)
    assert set(candidates(layered_photo(turn_deg=90.0), PPU)) == {"isotropic", "upright"}
    speckle = rng.random((128, 128, 3))
    assert orientation(speckle)[0] < UPRIGHT_GATE and set(candidates(speckle, PPU)) == {"isotropic"}
    assert candidates(np.full((64, 64, 3), 0.3), PPU) == {}
    assert upright_waves(np.full((64, 64, 3), 0.3), PPU) is None
    a, b = upright_waves(layered_photo(), PPU), upright_waves(layered_photo(), PPU)
    assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])      # the same photo, the same waves


def _flat_layers(img):
    mean = img.mean((0, 1)).astype(np.float32)

    def layers(seed, axis, offset):
        pts = slice_points(RENDER, PPU, axis, offset)
        return np.broadcast_to(mean, (len(pts), 3)).copy(), np.zeros((len(pts), 3), np.float32), pts
    return layers


def _check_distances(img, offered):
    """The check's band distance of every (kind, t) for a decoder that draws nothing, computed here."""
    from omninoise.backend.solid.band_distance import band_distance
    from omninoise.backend.solid.gaussian_rest import CHECK_PLANES
    mean = img.mean((0, 1))
    out = {}
    for kind, waves in offered.items():
        r = GaussianRest(*waves, 1.0, kind)
        g = [rest_field(slice_points(RENDER, PPU, ax, off), r, s) for s, ax, off in CHECK_PLANES]
        for t in MIXES:
            out[kind, t] = band_distance([np.clip(mean + np.sqrt(t) * x, 0, 1).reshape(RENDER, RENDER, 3)
                                          for x in g], img)
    return out


@pytest.mark.long
@pytest.mark.parametrize("along, kind", [(3, "isotropic"), (20, "upright")])
def test_the_check_takes_the_kind_and_mix_that_come_closest(along, kind):
    """A decoder that draws nothing; the check weighs floors beside walls.  Thin level layers (along = 3): the
    upright rest's walls are far closer (band distance 86 against 211) but its floors, cut through single layers,
    far farther (687 against 198), and the check keeps the isotropic rest; layers with more horizontal detail
    (along = 20): walls 57 against 130, floors 272 against 135, pooled the upright rest."""
    img = layered_photo(256, turn_deg=90.0, across=(6, 30), along=along)
    offered = candidates(img, PPU)
    assert set(offered) == {"isotropic", "upright"}
    dist = _check_distances(img, offered)
    best = min(dist, key=dist.get)
    r = choose_mix(_flat_layers(img), img, offered)
    assert r is not None and (r.kind, r.mix) == best and r.kind == kind
    assert np.allclose(r.amp, offered[kind][1] * np.sqrt(r.mix))
    assert choose_mix(_flat_layers(img), img, {"isotropic": offered["isotropic"]}).kind == "isotropic"
    assert choose_mix(_flat_layers(img), img, {}) is None


def test_the_kind_is_stored_and_older_rests_read_as_isotropic():
    r = GaussianRest(*upright_waves(layered_photo(seed=4), PPU), 0.5, "upright")
    d = json.loads(json.dumps(rest_to_json(r)))
    assert d["kind"] == "upright" and rest_from_json(d).kind == "upright"
    del d["kind"]
    assert rest_from_json(d).kind == "isotropic"
    d["kind"] = "sideways"
    with pytest.raises(ValueError, match="kind 'sideways' is not one of isotropic, upright, mixed"):
        rest_from_json(d)
    iso = GaussianRest(*rest_waves(layered_photo(seed=4), PPU), 1.0)
    assert mix_rests(r, iso, 0.5).kind == "mixed" and mix_rests(r, None, 0.5).kind == "upright"
    assert mix_rests(r, r, 0.5).kind == "upright"


@pytest.mark.long
def test_an_artist_may_ask_for_a_kind_and_upright_is_checked_on_walls():
    """photo_code(rest=...): "upright" keeps the layers of a photo whose floors made the check (walls and floors)
    take the isotropic rest, because an artist asking for it is texturing walls; "isotropic" never offers the
    upright rest; anything else is named."""
    space = SolidTextureModel(os.path.join(ROOT, "models", "solid", "space"))
    img = layered_photo(256, turn_deg=90.0, across=(6, 30), along=3).astype(np.float32)
    assert set(candidates(img, PPU, "upright")) == {"upright"}
    assert set(candidates(img, PPU, "isotropic")) == {"isotropic"}
    up = photo_code(space, img, PhotoConfig(rest="upright")).rest
    assert up is not None and up.kind == "upright"
    iso = photo_code(space, img, PhotoConfig(rest="isotropic")).rest
    assert iso is None or iso.kind == "isotropic"
    with pytest.raises(ValueError, match="one of auto, isotropic, upright, not 'sideways'"):
        photo_code(space, img, PhotoConfig(rest="sideways"))
