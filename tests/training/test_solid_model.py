"""Neural solid textures: training steps, ONNX export, and the torch-free runtime against torch."""

import json
import math

import numpy as np
import pytest

from omninoise.backend.grid import Cancelled

torch = pytest.importorskip("torch")

from omninoise.backend.errors import SettingError  # noqa: E402
from omninoise.backend.onnx_models import ModelError, fingerprint  # noqa: E402
from omninoise.backend.solid.model import SolidTextureModel, TextureCode  # noqa: E402
from omninoise.backend.solid.waves import wave_features as wave_features_np  # noqa: E402
from omninoise.training.solid import exemplars as ex  # noqa: E402
from omninoise.training.solid.export import export  # noqa: E402
from omninoise.training.solid.features import RandomFeatures, histogram_loss, style_loss  # noqa: E402
from omninoise.training.solid.value_noise import octave_seeds  # noqa: E402
from omninoise.training.solid.model import random_rotations, slice_points  # noqa: E402
from omninoise.training.solid.train import SolidConfig, build_model, train, training_images  # noqa: E402
from omninoise.training.solid.waves import photo_waves, wave_features, wave_share  # noqa: E402
from omninoise.backend.onnx_models import sealed


def _tiny(tmp_path, mode="single", dim=3, steps=4, **kw):
    cfg = dict(name=f"tiny_{mode}_{dim}d", mode=mode, dim=dim, crop=32, batch=2, steps=steps, width=32,
               log_every=2, checkpoint_every=2, threads=1, exemplars=["gravel"] if mode == "single" else ["gravel", "grass"])
    cfg.update(kw)
    run = tmp_path / f"run_{mode}_{dim}"
    state = train(SolidConfig.from_dict(cfg), str(run), log=lambda *_: None)
    return run, state


def test_config_errors_name_the_key():
    with pytest.raises(ValueError, match="unknown config key 'octave'"):
        SolidConfig.from_dict({"octave": 4})
    with pytest.raises(ValueError, match="exactly one exemplar"):
        SolidConfig.from_dict({"exemplars": ["wood", "rust"]})
    with pytest.raises(ValueError, match="dim must be 2 or 3"):
        SolidConfig.from_dict({"dim": 4})
    with pytest.raises(ValueError, match="cellular must be 0..8"):
        SolidConfig.from_dict({"cellular": 9})
    with pytest.raises(ValueError, match="bricks must be 0..4"):
        SolidConfig.from_dict({"bricks": 5, "octaves": 4})
    for bad in ({"waves": 4, "dim": 3}, {"waves": 4, "dim": 2, "mode": "space", "exemplars": ["gravel", "grass"]},
                {"waves": -1, "dim": 2}, {"waves": 2.5, "dim": 2}):
        with pytest.raises(ValueError, match="waves must be a whole number"):
            SolidConfig.from_dict(bad)


def test_photo_waves_find_the_photos_periodic_components_with_their_phases():
    H = W = 64
    r, c = torch.meshgrid(torch.arange(H, dtype=torch.float64), torch.arange(W, dtype=torch.float64), indexing="ij")
    g = 0.5 + 0.2 * torch.cos(2 * math.pi * (3 * c / W + 5 * r / H) + 0.7) \
        + 0.1 * torch.cos(2 * math.pi * (7 * c / W - 2 * r / H) - 1.1)
    w = photo_waves(g.expand(3, H, W).float(), 2, 128.0)
    # the stronger first; one of each conjugate pair (k_y > 0): (7, -2) comes back as (-7, 2)
    np.testing.assert_allclose(w[:, :2].numpy(), [[6.0, -10.0], [-14.0, -4.0]], atol=1e-5)
    np.testing.assert_allclose(w[:, 3].numpy(), [0.2, 0.1] / np.sqrt((0.2 ** 2 + 0.1 ** 2) / 2), rtol=0.02)
    # at the pixel centres of slice_points' plane the waves give the photo back, phases included (measured on
    # the periodic component, which differs from an image that tiles only by a faint smooth part)
    x = slice_points(1, H, 128.0, 2, 0.0, 0.0, torch.Generator().manual_seed(0))
    f = wave_features(x, w)[0]
    rec = 0.2 * f[:, 0] / w[0, 3] + 0.1 * f[:, 2] / w[1, 3]
    assert float((rec.view(H, W) - (g - 0.5).float()).abs().max()) < 0.01
    shifted = 0.2 * torch.cos(2 * math.pi * (3 * c / W + 5 * r / H) + 0.7 + 0.5)   # a phase error shows
    assert float((rec.view(H, W) - shifted.float()).abs().max()) > 0.05
    # the numpy twin the runtime reads
    np.testing.assert_allclose(wave_features_np(x[0].numpy() + 40.0, w.numpy()),
                               wave_features(x + 40.0, w)[0].numpy(), atol=1e-6)
    # a photo that is two waves is all waves; white noise has no period
    assert wave_share(g.expand(3, H, W).float(), 2) > 0.95
    noise = torch.rand(3, 64, 64, generator=torch.Generator().manual_seed(0))
    assert wave_share(noise, 4) < 0.05
    with pytest.raises(ValueError, match="fewer than 3 spectral peaks"):
        photo_waves(torch.full((3, 32, 32), 0.5), 3, 128.0)


def test_rotations_and_slices():
    R = random_rotations(8, 3, seed=1)
    np.testing.assert_allclose((R @ R.transpose(1, 2)).numpy(), np.broadcast_to(np.eye(3), (8, 3, 3)), atol=1e-5)
    assert np.allclose(torch.det(R).numpy(), 1.0, atol=1e-5)
    g = torch.Generator().manual_seed(0)
    x = slice_points(4, 16, 16.0, 3, 0.0, 5.0, g)
    assert x.shape == (4, 256, 3)
    # axis-aligned slices: exactly one coordinate is constant over each slice, neighbours are 1/16 apart
    for b in range(4):
        assert int((x[b].std(0) < 1e-6).sum()) == 1
        assert np.isclose(float((x[b, 1] - x[b, 0]).norm()), 1 / 16, atol=1e-6)
    x2 = slice_points(2, 8, 8.0, 2, 0.5, 3.0, g)
    assert x2.shape == (2, 64, 2) and float(x2.abs().max()) < 4.0


def test_fixed_axis_slices_keep_the_photo_direction_on_one_axis():
    """fixed_axis 'columns': image columns step along +x in every slice, the plane turning about x (all angles
    seen); 'rows': image rows step down -z, the plane turning about z. Configs refuse it with rotated crops."""
    g = torch.Generator().manual_seed(3)
    size, ppu = 8, 8.0
    for axis, col_step, row_step_axis in (("columns", (1, 0, 0), 0), ("rows", None, 2)):
        x = slice_points(64, size, ppu, 3, 0.0, 5.0, g, fixed_axis=axis).view(64, size, size, 3)
        du = (x[:, 0, 1] - x[:, 0, 0]) * ppu          # one image column to the right
        dv = (x[:, 1, 0] - x[:, 0, 0]) * ppu          # one image row down
        np.testing.assert_allclose(du.norm(dim=1).numpy(), 1.0, atol=1e-5)
        np.testing.assert_allclose((du * dv).sum(1).numpy(), 0.0, atol=1e-5)   # orthonormal frames
        if col_step is not None:
            np.testing.assert_allclose(du.numpy(), np.broadcast_to(col_step, (64, 3)), atol=1e-5)
            angles = torch.atan2(dv[:, 2], dv[:, 1])
        else:
            np.testing.assert_allclose(dv.numpy(), np.broadcast_to((0, 0, -1), (64, 3)), atol=1e-5)
            angles = torch.atan2(du[:, 1], du[:, 0])
        # the plane turns all the way about the axis: every quadrant of angles is drawn
        assert len(set((torch.floor(angles / (np.pi / 2)) % 4).int().tolist())) == 4
    with pytest.raises(ValueError, match="fixed_axis"):
        slice_points(1, 4, 4.0, 3, 0.0, 1.0, g, fixed_axis="diagonal")
    with pytest.raises(ValueError, match="augment false"):
        SolidConfig.from_dict({"fixed_axis": "columns", "augment": True})
    with pytest.raises(ValueError, match="mode 'single'"):
        SolidConfig.from_dict({"fixed_axis": "rows", "dim": 2, "mode": "space", "exemplars": ["gravel", "grass"]})
    assert SolidConfig.from_dict({"fixed_axis": "rows", "dim": 2}).fixed_axis == "rows"


def test_features_see_structure_and_colour():
    f = RandomFeatures(seed=0)
    rng = torch.Generator().manual_seed(0)
    a = torch.rand(1, 3, 64, 64, generator=rng)
    # same marginal colour histogram, different structure: smooth vs white noise
    b = torch.nn.functional.avg_pool2d(torch.rand(1, 3, 72, 72, generator=rng), 9, 1)
    b = (b - b.mean()) / b.std() * a.std() + a.mean()
    assert float(style_loss(f, a, a)) < 1e-6
    assert float(style_loss(f, b, a, hist_weight=0.0)) > 0.1
    # channel-swapped colours keep each channel's histogram but not the joint one
    c = torch.rand(1, 3, 64, 64, generator=rng)
    c[:, 1] = 1.0 - c[:, 0]
    d = c.clone()
    d[:, 1] = c[:, 0]
    assert float(histogram_loss(c, d)) > 1e-3


def _fixed_loss(state, img):
    """Style loss of a model on fixed slices, seeds and crops (no batch-to-batch noise)."""
    from omninoise.training.solid.train import render
    cfg = SolidConfig.from_dict(state["config"])
    m = build_model(cfg)
    m.load_state_dict(state["model"])
    g = torch.Generator().manual_seed(123)
    ref = ex.random_crops(img, 4, cfg.crop, g)
    x = slice_points(4, cfg.crop, cfg.px_per_unit, cfg.dim, cfg.oblique, cfg.extent, g)
    with torch.no_grad():
        e, T = m.codes(batch=4)
        return float(style_loss(RandomFeatures(0), render(m, e, T, x, [1, 2, 3, 4], cfg.crop), ref))


def test_training_reduces_the_loss(tmp_path):
    cfg = dict(dim=2, crop=48, batch=2, lr=0.005, width=64, exemplars=["gravel"])
    _, s0 = _tiny(tmp_path / "a", steps=1, **cfg)
    _, s1 = _tiny(tmp_path / "b", steps=60, **cfg)
    img = ex.exemplar("gravel")
    before, after = _fixed_loss(s0, img), _fixed_loss(s1, img)
    assert after < 0.5 * before, (before, after)


def test_resume_continues_from_checkpoint(tmp_path):
    cfg = SolidConfig.from_dict(dict(name="r", dim=2, crop=32, batch=1, steps=6, width=16, checkpoint_every=2,
                                     log_every=1, threads=1, exemplars=["gravel"]))
    train(cfg, str(tmp_path / "a"), max_steps=3, log=lambda *_: None)
    msgs = []
    state = train(cfg, str(tmp_path / "a"), log=msgs.append)
    assert msgs[0] == "resumed at step 3" and state["step"] == 6


def test_init_from_continues_a_finished_run_and_the_card_names_both_configs(tmp_path):
    import json

    from omninoise.training.solid.model_card import card

    base = dict(name="c", dim=2, crop=32, batch=1, steps=4, width=16, checkpoint_every=2, log_every=1, threads=1,
                exemplars=["gravel"])
    first = train(SolidConfig.from_dict(base), str(tmp_path / "runs" / "c"), log=lambda *_: None)
    long = dict(base, name="c_long", steps=7, init_from=str(tmp_path / "runs" / "c"))
    msgs = []
    state = train(SolidConfig.from_dict(long), str(tmp_path / "runs" / "c_long"), log=msgs.append)
    assert msgs[:2] == [f"continuing {tmp_path / 'runs' / 'c'}", "resumed at step 4"] and state["step"] == 7
    assert not torch.equal(state["model"]["decoder.net.0.weight"], first["model"]["decoder.net.0.weight"])
    steps = [json.loads(line)["step"] for line in open(tmp_path / "runs" / "c_long" / "log.jsonl")]
    assert steps == list(range(1, 8))  # the first run's log, then the continuation
    with pytest.raises(ValueError, match="init_from: no checkpoint"):
        train(SolidConfig.from_dict(dict(long, init_from=str(tmp_path / "none"))), str(tmp_path / "x"),
              log=lambda *_: None)
    # the card lists the config chain and reads the continued run's log
    cfgs = tmp_path / "configs"
    cfgs.mkdir()
    (cfgs / "c.json").write_text(json.dumps(base))
    (cfgs / "c_long.json").write_text(json.dumps(dict(long, init_from="runs/c")))
    export(str(tmp_path / "runs" / "c_long"), str(tmp_path / "models" / "c"))
    text = card(str(tmp_path / "models"), str(tmp_path / "runs"), None, str(cfgs))
    assert "| c | single | 2D | gravel | 1.0 | gram | `c.json` → `c_long.json` | 7 |" in text, text
    # a continued run that lost to the shipped model is listed beside it, marked as not shipped
    row = lambda v: {"gravel": {"ours_3d": dict(style=v, psd=0.1, diversity=1.0, success=0.5)}}  # noqa: E731
    for name, v in (("prev", 0.4), ("cand", 0.6), ("now", 0.4)):
        (tmp_path / f"{name}.json").write_text(json.dumps({"quality": row(v)}))
    text = card(str(tmp_path / "models"), str(tmp_path / "runs"), str(tmp_path / "now.json"), str(cfgs),
                str(tmp_path / "prev.json"), {"c": str(tmp_path / "cand.json")})
    assert ("| gravel | ours_3d: c continued, **not shipped** | 0.4 / 0.1 / 0.5 | 0.6 / 0.1 / 0.5 |" in text), text


@pytest.mark.parametrize("dim,cellular,bricks,waves,spin", [(2, 0, 0, 0, ""), (3, 0, 0, 0, ""), (2, 3, 0, 0, ""),
                                                           (3, 2, 2, 0, ""), (2, 0, 0, 6, ""), (3, 0, 0, 0, "lattice"),
                                                           (2, 2, 0, 0, "lattice"), (3, 2, 0, 0, "octave")])
def test_single_export_runtime_matches_torch(tmp_path, dim, cellular, bricks, waves, spin):
    run, state = _tiny(tmp_path, dim=dim, cellular=cellular, bricks=bricks, waves=waves, spin=spin)
    out = tmp_path / "model"
    doc = export(str(run), str(out))
    assert doc["spin"] == spin
    assert doc["mode"] == "single" and set(doc["files"]) == {"decoder.onnx"} and doc["cellular"] == cellular
    assert doc["bricks"] == bricks and len(doc.get("waves", [])) == waves
    if waves:   # measured from the exemplar, as training used them
        np.testing.assert_array_equal(np.asarray(doc["waves"], np.float32),
                                      photo_waves(training_images(SolidConfig.from_dict(state["config"]))[0],
                                                  waves, 128.0).numpy())
        # a run continued from the export keeps them (they are not measured again)
        cont = dict(state["config"], name="cont", steps=state["step"] + 1, init_onnx=str(out),
                    init_sha256=fingerprint(doc["files"]))
        s2 = train(SolidConfig.from_dict(cont), str(tmp_path / "cont"), log=lambda *_: None)
        np.testing.assert_array_equal(s2["model"]["waves"].numpy(), np.asarray(doc["waves"], np.float32))
    rt = SolidTextureModel(str(out))
    code = rt.default_code()
    assert code.e.shape == (64,) and code.T.shape == (8, dim, dim)
    m = build_model(SolidConfig.from_dict(state["config"]))
    m.load_state_dict(state["model"])
    rng = np.random.default_rng(0)
    x = rng.uniform(-3, 3, (1, 3000, dim)).astype(np.float32)
    with torch.no_grad():
        e, T = m.codes(batch=1)
        ref = m.sample(torch.from_numpy(x), e, T, octave_seeds([7], 8)).numpy()[0]
    got = rt.evaluate(x[0], code, seed=7, chunk=700)
    assert got.dtype == np.float32 and got.shape == (3000, 3) and rt.spin == spin
    if cellular or bricks:   # float32 positions in torch: a point within ~1e-4 of a Voronoi border may pick the other cell
        assert (np.abs(got - ref).max(axis=1) < 2e-4).mean() > 0.995
    else:
        np.testing.assert_allclose(got, ref, atol=2e-4)
    # chunking changes nothing; another seed gives another texture
    np.testing.assert_array_equal(rt.evaluate(x[0], code, 7, chunk=4096), got)
    assert np.abs(rt.evaluate(x[0], code, 8) - got).mean() > 1e-5


def test_space_export_encode_translate_interpolate(tmp_path):
    run, state = _tiny(tmp_path, mode="space", dim=3, crop=128, batch=2, steps=2)
    out = tmp_path / "space"
    doc = export(str(run), str(out))
    assert set(doc["files"]) == {"decoder.onnx", "encoder.onnx", "translator.onnx"}
    assert set(doc["codes"]) == {"gravel", "grass"}
    rt = SolidTextureModel(str(out))
    m = build_model(SolidConfig.from_dict(state["config"]))
    m.load_state_dict(state["model"])
    m.eval()
    img = ex.procedural("wood", 3, 160).permute(1, 2, 0).numpy()
    z = rt.encode(img)
    with torch.no_grad():
        crops = torch.stack([torch.from_numpy(img[a:a + 128, b:b + 128]).permute(2, 0, 1)
                             for a in (0, 32) for b in (0, 32)])
        zt = m.encoder(crops).mean(0).numpy()
        e_t, T_t = m.translator(torch.from_numpy(zt)[None])
    np.testing.assert_allclose(z, zt, atol=1e-4)
    code = rt.translate(z)
    np.testing.assert_allclose(code.e, e_t[0].numpy(), atol=1e-4)
    np.testing.assert_allclose(code.T, T_t[0].numpy(), atol=1e-4)
    # interpolation in z: the ends are the two exemplars' codes
    z1, z2 = rt.codes["gravel"], rt.codes["grass"]
    np.testing.assert_allclose(rt.translate(1.0 * z1 + 0.0 * z2).e, rt.code("gravel").e, atol=1e-6)
    # a small grey image is upsampled to the encoder's size
    assert rt.encode(np.full((40, 50), 0.5, np.float32)).shape == (8,)
    with pytest.raises(SettingError, match="knows no exemplar 'marble'"):
        rt.code("marble")


def test_runtime_refuses_altered_and_bad_input(tmp_path):
    run, _ = _tiny(tmp_path, dim=2, steps=2)
    out = tmp_path / "m"
    export(str(run), str(out))
    rt = SolidTextureModel(str(out))
    with pytest.raises(SettingError, match="2D and cannot be evaluated at 3D points"):
        rt.evaluate(np.zeros((4, 3)), rt.default_code())
    with pytest.raises(SettingError, match="transforms have shape"):
        rt.evaluate(np.zeros((4, 2)), TextureCode(np.zeros(64, np.float32), np.zeros((8, 3, 3), np.float32)))
    with pytest.raises(SettingError, match="cannot encode images"):
        rt.encode(np.zeros((128, 128, 3)))
    with pytest.raises(Cancelled):
        rt.evaluate(np.zeros((10, 2)), rt.default_code(), cancel=lambda: True)
    doc = json.loads((out / "solid.json").read_text())
    (out / "solid.json").write_text(json.dumps(sealed(dict(doc, spin="world"))))
    with pytest.raises(ModelError, match="spin must be one of .* got 'world'"):
        SolidTextureModel(str(out))
    (out / "solid.json").write_text(json.dumps(sealed(doc)))
    with open(out / "decoder.onnx", "ab") as fh:
        fh.write(b"x")
    with pytest.raises(ModelError, match="sha256 does not match"):
        SolidTextureModel(str(out))
    with pytest.raises(ModelError, match="no solid.json"):
        SolidTextureModel(str(tmp_path))


def test_exemplars_split_and_crops():
    img = ex.exemplar("gravel")
    assert img.shape == (3, 512, 512) and float(img.min()) >= 0 and float(img.max()) <= 1
    assert ex.train_region(img, "gravel").shape[2] == 384
    assert ex.heldout_region("gravel").shape[2] == 128
    for name in ex.PROCEDURAL:
        a, b = ex.procedural(name, 0, 64), ex.procedural(name, 1, 64)
        assert a.shape == (3, 64, 64) and float((a - b).abs().mean()) > 0.01, name
    g = torch.Generator().manual_seed(0)
    c = ex.random_crops(img, 3, 64, g, augment=True)
    assert c.shape == (3, 3, 64, 64)
    with pytest.raises(ValueError, match="smaller than the 600 px"):
        ex.random_crops(img, 1, 600, g)
    with pytest.raises(ValueError, match="unknown exemplar 'cork'"):
        ex.exemplar("cork")


def test_refinement_never_worsens_and_moves_a_wrong_start(tmp_path, monkeypatch):
    import omninoise.backend.solid.refine as rf
    from omninoise.backend.grid import Cancelled
    from omninoise.backend.solid.refine import refine_code, sliced_distance, sliced_target
    run, _ = _tiny(tmp_path, mode="space", dim=3, crop=128, batch=2, steps=2)
    export(str(run), str(tmp_path / "space"))
    rt = SolidTextureModel(str(tmp_path / "space"))
    img = ex.procedural("rust", 1, 160).permute(1, 2, 0).numpy()
    z0 = rt.codes["grass"]
    monkeypatch.setattr(rf, "RENDER_SIZE", 48)          # a tiny model: small renders keep the test quick
    z, hist = refine_code(rt, z0, img, steps=12, seed=1)
    assert len(hist) == 13 and all(b <= a for a, b in zip(hist, hist[1:]))
    assert z.dtype == np.float32 and z.shape == (8,)
    assert not np.array_equal(z, z0) and hist[-1] < hist[0]   # a grass code refined towards rust
    z_same, h0 = refine_code(rt, z0, img, steps=0)
    np.testing.assert_array_equal(z_same, z0)
    assert h0 == hist[:1]
    with pytest.raises(Cancelled):
        refine_code(rt, z0, img, steps=3, cancel=lambda: True)
    # the final check: a code the search found is dropped when it is not closer on the fresh planes
    final = []
    real = rf.sliced_distance

    def fresh_planes_prefer_the_start(images, target, seed=1):
        if len(images) != len(rf.FINAL_PLANES):
            return real(images, target, seed)
        final.append(1)                                 # the refined code is measured first, then the start
        return 1.0 if len(final) % 2 else 0.0
    monkeypatch.setattr(rf, "sliced_distance", fresh_planes_prefer_the_start)
    z2, hist2 = refine_code(rt, z0, img, steps=12, seed=1)
    assert min(hist2) < hist2[0]                         # the search moved from the wrong start ...
    np.testing.assert_array_equal(z2, z0)                # ... and the final check undid it
    assert hist2[-1] == hist2[0]
    monkeypatch.setattr(rf, "sliced_distance", real)
    # the distance sees colour, scale and orientation, and is 0 for the same image
    base = np.tile(np.sin(np.arange(64) * 0.8)[None, :, None] * 0.3 + 0.5, (64, 1, 3))
    t = sliced_target([base])
    assert sliced_distance([base.transpose(1, 0, 2)], t) > 0.05                      # rotated stripes
    assert sliced_distance([base * 0.5], t) > 0.05                                    # darker
    fine = np.tile(np.sin(np.arange(64) * 2.4)[None, :, None] * 0.3 + 0.5, (64, 1, 3))
    assert sliced_distance([fine], t) > 0.05                                          # finer
    assert sliced_distance([base.copy()], t) < 0.02
    rng = np.random.default_rng(0)
    noise = rng.random((64, 64, 3))
    assert sliced_distance([rng.random((64, 64, 3))], sliced_target([noise])) < 0.02   # another draw, same process


def test_spectral_aspect_and_the_initial_stretch_follow_the_grain():
    """Stripes that run horizontally (grain along the rows) have aspect < 1, standing ones > 1, a noise about 1;
    init_stretch lengthens features along the fixed axis by it, never shortens them, and starts the run so."""
    from omninoise.training.solid.model import spectral_aspect
    from omninoise.training.solid.train import initial_stretch

    g = torch.Generator().manual_seed(0)
    noise = torch.rand(1, 64, 64, generator=g)
    blur = torch.nn.functional.avg_pool2d(noise[None], (1, 9), stride=1, padding=(0, 4))[0]   # smeared along rows
    lying = blur.expand(3, -1, -1)
    standing = lying.transpose(1, 2)
    assert spectral_aspect(lying) < 0.5 < 2.0 < spectral_aspect(standing)
    assert 0.8 < spectral_aspect(noise.expand(3, -1, -1)) < 1.25
    assert initial_stretch(lying, "columns") == pytest.approx(spectral_aspect(lying))
    assert initial_stretch(lying, "rows") == 1.0 and initial_stretch(standing, "columns") == 1.0
    with pytest.raises(ValueError, match="init_stretch"):
        SolidConfig.from_dict({"init_stretch": True})


def test_fixed_axis_models_start_with_lattices_along_the_axis(tmp_path):
    """axis_rotations keep the fixed axis on the lattice's second (brick-row) axis and are rotations; a fresh
    single model with fixed_axis starts from them, its column of the axis scaled by the initial stretch."""
    from omninoise.training.solid.model import axis_rotations
    from omninoise.training.solid import exemplars as ex

    for axis, k in (("columns", 0), ("rows", 2)):
        T = axis_rotations(8, axis, seed=2)
        e = torch.zeros(3)
        e[k] = 1.0
        np.testing.assert_allclose((T @ e).numpy(), np.broadcast_to([0.0, 1.0, 0.0], (8, 3)), atol=1e-6)
        np.testing.assert_allclose((T @ T.transpose(1, 2)).numpy(), np.broadcast_to(np.eye(3), (8, 3, 3)), atol=1e-6)
        np.testing.assert_allclose(torch.det(T).numpy(), 1.0, atol=1e-5)
        assert len({round(float(t[0, (k + 1) % 3]), 4) for t in T}) == 8     # each octave turned its own way
    # 2D: the plane is the photo's; "rows" keeps the lattices' rows on its rows (p_1 = y), "columns" on its
    # columns (p_1 = x), every octave alike
    for axis, k in (("rows", 1), ("columns", 0)):
        T = axis_rotations(8, axis, seed=2, dim=2)
        e = torch.zeros(2)
        e[k] = 1.0
        np.testing.assert_allclose((T @ e).numpy(), np.broadcast_to([0.0, 1.0], (8, 2)), atol=1e-7)
        np.testing.assert_allclose(torch.det(T).numpy(), 1.0, atol=1e-6)
    photo = ex.photo_set("train")[0]
    cfg = dict(name="tiny_axis", mode="single", dim=3, crop=32, batch=1, steps=0, width=8, threads=1,
               exemplars=[photo], colour="affine", loss="swd", swd_width=4, swd_levels=1, augment=False,
               fixed_axis="rows", init_stretch=True, checkpoint_every=1)
    from omninoise.training.solid.train import initial_stretch, training_images
    c = SolidConfig.from_dict(cfg)
    logs = []
    train(SolidConfig.from_dict(dict(cfg, steps=1, lr=0.0, lr_min=0.0)), str(tmp_path / "run"), log=logs.append)
    state = torch.load(tmp_path / "run" / "ckpt.pt", weights_only=False)
    want = axis_rotations(8, "rows", 0)
    want[:, :, 2] *= initial_stretch(training_images(c)[0], "rows")
    np.testing.assert_allclose(state["model"]["T"].numpy(), want.numpy(), atol=1e-6)   # lr 0: the start itself
    assert any("stretched along the rows axis" in s for s in logs)
    train(SolidConfig.from_dict(dict(cfg, dim=2, steps=1, lr=0.0, lr_min=0.0)), str(tmp_path / "run2"),
          log=lambda *_: None)
    T2 = torch.load(tmp_path / "run2" / "ckpt.pt", weights_only=False)["model"]["T"]
    want2 = torch.eye(2).expand(8, 2, 2).clone()
    want2[:, :, 1] *= initial_stretch(training_images(c)[0], "rows")   # the photo's vertical is y in 2D
    np.testing.assert_allclose(T2.numpy(), want2.numpy(), atol=1e-6)


def test_noise_ramp_lets_the_shape_features_draw_first(tmp_path, monkeypatch):
    """noise_ramp: the value noise enters single-mode training with a gain (step + 1) / ramp, capped at 1, so the
    first steps' images are a function of the shape features alone; bad settings are named."""
    import omninoise.training.solid.train as tr

    with pytest.raises(ValueError, match="noise_ramp needs shape features"):
        SolidConfig.from_dict({"noise_ramp": 5, "steps": 10})
    with pytest.raises(ValueError, match="noise_ramp must be a whole number"):
        SolidConfig.from_dict({"noise_ramp": 10, "steps": 10, "bricks": 1})
    cfg = SolidConfig.from_dict({"noise_ramp": 4, "steps": 10, "bricks": 1})
    assert [tr.noise_gain(cfg, s) for s in range(5)] == [0.25, 0.5, 0.75, 1.0, 1.0]
    assert tr.noise_gain(SolidConfig.from_dict({}), 0) == 1.0

    seen, render = [], tr.render

    def spy(model, e, T, x, seeds, size, stats=None, gains=None):
        seen.append(None if gains is None else gains.unique().tolist())
        if gains is not None and len(seen) == 1:   # at gain 0 the decoder's value-noise weights no longer matter
            w = model.decoder.net[0].weight
            n_value = model.octaves * model.channels
            with torch.no_grad():
                for g in (0.0, 1.0):
                    before = render(model, e, T, x, seeds, size, stats, gains * 0.0 + g)
                    w[:, :n_value] += 0.5
                    after = render(model, e, T, x, seeds, size, stats, gains * 0.0 + g)
                    w[:, :n_value] -= 0.5
                    assert torch.allclose(before, after) == (g == 0.0), g
        return render(model, e, T, x, seeds, size, stats, gains)

    monkeypatch.setattr(tr, "render", spy)
    _tiny(tmp_path, steps=5, bricks=1, noise_ramp=3)
    assert seen[2:] == [None, None, None]
    np.testing.assert_allclose([g[0] for g in seen[:2]], [1 / 3, 2 / 3], rtol=1e-6)
    assert all(len(g) == 1 for g in seen[:2])


def test_noise_ramp_in_space_mode_scales_the_spectral_gains(tmp_path, monkeypatch):
    """A space model's ramp multiplies each photo's measured spectral gains (model.spectral_gains) by the ramp's
    gain, so the ratios between octaves stay the photo's while the noise fades in."""
    import omninoise.training.solid.train as tr
    from omninoise.training.solid.model import spectral_gains

    seen, render = [], tr.render

    def spy(model, e, T, x, seeds, size, stats=None, gains=None):
        seen.append(gains.clone())
        return render(model, e, T, x, seeds, size, stats, gains)

    measured, real = [], spectral_gains

    def spy_gains(img, octaves=8, px_per_unit=128.0):
        measured.append(real(img, octaves, px_per_unit))
        return measured[-1]

    monkeypatch.setattr(tr, "render", spy)
    monkeypatch.setattr(tr, "spectral_gains", spy_gains)
    _tiny(tmp_path, mode="space", steps=4, crop=64, cellular=1, noise_ramp=2, colour="affine", spectral=True)
    assert len(seen) == len(measured) == 4
    for step, (g, m) in enumerate(zip(seen, measured)):
        torch.testing.assert_close(g, m * min(1.0, (step + 1) / 2))


def test_budget_fits_the_schedule_to_the_time_there_is(tmp_path, monkeypatch):
    """--budget-seconds: after steps 10 to 40 of a stretch the run's steps become what the rest of the budget holds
    at the measured rate, the noise ramp keeps its share of the schedule, and the checkpoint records both."""
    import omninoise.training.solid.train as tr

    cfg = SolidConfig.from_dict({"steps": 1000, "noise_ramp": 200, "bricks": 1})
    fitted = tr.fit_schedule(cfg, 40, 0.5, 100.0)
    assert (fitted.steps, fitted.noise_ramp) == (240, 48)
    assert tr.fit_schedule(cfg, 40, 0.5, -3.0).steps == 41          # past the budget: one more step
    assert tr.fit_schedule(SolidConfig.from_dict({"steps": 10}), 0, 0.1, 100.0).noise_ramp == 0
    with pytest.raises(ValueError, match="seconds per step must be a positive number"):
        tr.fit_schedule(cfg, 40, 0.0, 100.0)

    clock, render = [0.0], tr.render

    def step_of_two_seconds(*args, **kw):                # a clock that moves 2 s per rendered step
        clock[0] += 2.0
        return render(*args, **kw)

    monkeypatch.setattr(tr, "render", step_of_two_seconds)
    monkeypatch.setattr(tr.time, "time", lambda: clock[0])
    run = tmp_path / "budget"
    cfg = SolidConfig.from_dict(dict(crop=16, batch=1, steps=1000, width=16, log_every=1000, checkpoint_every=1000,
                                     threads=1, exemplars=["gravel"], dim=2, bricks=1, noise_ramp=500))
    state = train(cfg, str(run), log=lambda *_: None, budget_seconds=1000.0)
    # at step 40, 80 s gone at 2 s per step: the 920 s left hold 460 steps
    assert state["step"] == state["config"]["steps"] == 500
    assert state["config"]["noise_ramp"] == 250
    with pytest.raises(ValueError, match="budget_seconds must be a positive number"):
        train(cfg, str(run), budget_seconds=0.0)


def test_device_is_checked(tmp_path, capsys):
    import omninoise.training.solid.train as tr

    with pytest.raises(ValueError, match="device must be 'cpu', 'cuda' or 'cuda:N', got 'gpu'"):
        SolidConfig.from_dict({"device": "gpu"})
    SolidConfig.from_dict({"device": "cuda:1"})
    if not torch.cuda.is_available():
        assert tr.main(["--config", "configs/solid/gravel_3d.json", "--out", str(tmp_path / "r"),
                        "--set", 'device="cuda"', "--set", "steps=2"]) == 2
        assert "torch sees no CUDA device here" in capsys.readouterr().err


def test_average_of_checkpoints_is_their_mean_and_exports(tmp_path):
    """training.solid.average (stochastic weight averaging): every float tensor is the mean of the runs' tensors,
    the last run gives config and step, the sources are named, a run of another shape is refused in one line, and
    the average exports and is read by the card (no loss log of its own)."""
    from omninoise.training.solid import average, photo_card

    run_a, state_a = _tiny(tmp_path, steps=2)
    run_b = tmp_path / "run_b"
    state_b = train(SolidConfig.from_dict(dict(state_a["config"], steps=4, init_from=str(run_a))), str(run_b),
                    log=lambda *_: None)
    assert state_b["step"] == 4
    out = tmp_path / "avg"
    assert average.main(["--out", str(out), str(run_a), str(run_b)]) == 0
    avg = torch.load(out / "ckpt.pt", map_location="cpu", weights_only=False)
    for k, v in avg["model"].items():
        if v.is_floating_point():
            torch.testing.assert_close(v, (state_a["model"][k] + state_b["model"][k]) / 2)
    assert not torch.equal(state_a["model"]["decoder.net.0.weight"], state_b["model"]["decoder.net.0.weight"])
    assert avg["step"] == 4 and "opt" not in avg
    assert avg["averaged_from"] == [dict(run=str(run_a), step=2), dict(run=str(run_b), step=4)]
    facts = photo_card.run_facts(str(out))
    assert facts["averaged"] == [2, 4] and facts["loss"] is None
    export(str(out), str(tmp_path / "avg_export"))
    m = SolidTextureModel(str(tmp_path / "avg_export"))
    assert m.config["step"] == 4

    other, _ = _tiny(tmp_path, dim=2, steps=1)
    with pytest.raises(ValueError, match="is not the architecture of"):
        average.average_checkpoints([str(run_a), str(other)])
    with pytest.raises(ValueError, match="at least two run folders or snapshots"):
        average.average_checkpoints([str(run_a)])
    assert average.main(["--out", str(tmp_path / "x"), str(run_a), str(tmp_path / "missing")]) == 2


def test_gpu_campaign_script_trains_configs_side_by_side(tmp_path):
    """tools/gpu_solid_campaign.sh, rehearsed on the CPU (EXTRA_SET): each config trains to the schedule fitted to
    the budget and comes back as NAME.pt without the optimiser's moments, the logs as one archive; a config that
    fails makes the script fail and is named."""
    import json
    import os
    import subprocess
    import sys
    import tarfile

    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    cfg = dict(name="camp_a", crop=16, batch=1, steps=100000, width=16, log_every=100000, checkpoint_every=100000,
               exemplars=["gravel"], dim=2, device="cuda", snapshot_every=10)
    (tmp_path / "camp_a.json").write_text(json.dumps(cfg))
    (tmp_path / "camp_bad.json").write_text(json.dumps(dict(cfg, name="camp_bad", octave=3)))
    env = dict(os.environ, PYTHON=sys.executable, POLL="1", EXTRA_SET='device="cpu";threads=1', SWA_FROM="20",
               PYTHONPATH=root + os.pathsep + os.environ.get("PYTHONPATH", ""))
    r = subprocess.run(["bash", os.path.join(root, "tools", "gpu_solid_campaign.sh"), "3", "out", "camp_a.json",
                        "camp_bad.json"], cwd=tmp_path, env=env, capture_output=True, text=True, timeout=600)
    assert r.returncode == 1, r.stdout + r.stderr
    assert "camp_bad failed:" in r.stdout and "unknown config key 'octave'" in r.stdout
    state = torch.load(tmp_path / "out" / "camp_a.pt", map_location="cpu", weights_only=False)
    assert "opt" not in state and 40 < state["step"] == state["config"]["steps"] < 100000
    assert state["config"]["device"] == "cpu"
    swa = torch.load(tmp_path / "out" / "camp_a_swa.pt", map_location="cpu", weights_only=False)
    assert swa["step"] == state["step"] and swa["averaged_from"][0]["step"] == 20
    assert not (tmp_path / "out" / "camp_bad_swa.pt").exists()
    with tarfile.open(tmp_path / "out" / "logs.tar.gz") as tar:
        names = set(tar.getnames())
    assert {"runs/solid/camp_a.log", "runs/solid/camp_a/log.jsonl", "runs/solid/camp_bad.log"} <= names


def test_snapshots_are_kept_and_averaged(tmp_path):
    """snapshot_every keeps the weights every N steps and at the end in RUN/snapshots; average --snapshots RUN
    --from STEP is the mean of those from STEP on, with the run's config; bad settings are named."""
    import os

    from omninoise.training.solid import average
    from omninoise.training.solid.train import snapshot_path

    with pytest.raises(ValueError, match="snapshot_every must be a whole number"):
        SolidConfig.from_dict({"snapshot_every": -1})
    run, state = _tiny(tmp_path, steps=5, snapshot_every=2)
    snaps = sorted(os.listdir(run / "snapshots"))
    assert snaps == ["step_0000002.pt", "step_0000004.pt", "step_0000005.pt"]
    last = torch.load(snapshot_path(str(run), 5), map_location="cpu", weights_only=False)
    for k, v in state["model"].items():
        torch.testing.assert_close(last["model"][k], v)
    out = tmp_path / "swa"
    assert average.main(["--out", str(out), "--snapshots", str(run), "--from", "3"]) == 0
    avg = torch.load(out / "ckpt.pt", map_location="cpu", weights_only=False)
    s4 = torch.load(snapshot_path(str(run), 4), map_location="cpu", weights_only=False)
    w = "decoder.net.0.weight"
    torch.testing.assert_close(avg["model"][w], (s4["model"][w] + last["model"][w]) / 2)
    assert avg["step"] == 5 and avg["config"] == state["config"]
    assert [a["step"] for a in avg["averaged_from"]] == [4, 5]
    with pytest.raises(ValueError, match="no weight snapshots from step 9 on"):
        average.snapshots(str(run), 9)
    with pytest.raises(ValueError, match="snapshots alone hold no config"):
        average.average_checkpoints([snapshot_path(str(run), 4), snapshot_path(str(run), 5)])


def test_training_with_waves_warns_when_the_photo_has_no_period(tmp_path):
    msgs = []
    cfg = SolidConfig.from_dict(dict(name="w", dim=2, crop=32, batch=1, steps=1, width=16, threads=1, waves=4,
                                     exemplars=["gravel"]))
    train(cfg, str(tmp_path / "w"), log=msgs.append)
    said = [m for m in msgs if m.startswith("waves:")]
    assert len(said) == 1 and "under 10 %" in said[0], msgs


def test_isotropy_penalty_charges_the_stretch_alone():
    """isotropy_weight's penalty: 0 for any rotation times a scale, ~0.43 for a 1.45 : 1 stretch, blind to
    rotations before and after (spun lattices), and its gradient shrinks the stretch; configs check the weight."""
    from omninoise.training.solid.model import random_rotations
    from omninoise.training.solid.train import isotropy_penalty
    R = random_rotations(8, 3, 1)
    assert isotropy_penalty(R * 3.0).item() < 1e-10
    S = R @ torch.diag(torch.tensor([1.45, 1.0, 1.0]))
    p = isotropy_penalty(S).item()
    assert 0.4 < p < 0.47
    Q = random_rotations(8, 3, 2)
    assert abs(isotropy_penalty(Q @ S @ R.transpose(-1, -2)).item() - p) < 1e-5
    T = S.clone().requires_grad_(True)
    isotropy_penalty(T).backward()
    with torch.no_grad():
        s = torch.linalg.svdvals(T - 0.1 * T.grad)
    assert (s[:, 0] / s[:, 2]).max() < 1.45 - 0.01
    with pytest.raises(ValueError, match="isotropy_weight"):
        SolidConfig.from_dict({"isotropy_weight": -1.0})


def test_a_run_from_a_spun_export_must_name_its_spin(tmp_path):
    """Continuing an export that turns its octaves with a config that does not would draw another texture from the
    same weights: refused, with the spin named; naming it continues."""
    run, state = _tiny(tmp_path, dim=3, spin="octave")
    doc = export(str(run), str(tmp_path / "m"))
    cont = dict(state["config"], name="cont", steps=state["step"] + 1, init_onnx=str(tmp_path / "m"),
                init_sha256=fingerprint(doc["files"]), spin="")
    with pytest.raises(ValueError, match="draws with spin 'octave'; set spin in the config"):
        train(SolidConfig.from_dict(cont), str(tmp_path / "c1"), log=lambda *_: None)
    s2 = train(SolidConfig.from_dict(dict(cont, spin="octave")), str(tmp_path / "c2"), log=lambda *_: None)
    assert s2["step"] == state["step"] + 1
