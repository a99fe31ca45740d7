"""The photo set, the photo models' colour path and bounded transforms, the sliced Wasserstein loss and the
held-out photo evaluation."""
import dataclasses
import hashlib
import json
import os
import sys

import numpy as np
import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "tools"))

import build_photo_set as bps  # noqa: E402

torch = pytest.importorskip("torch")  # omninoise.training needs torch

from omninoise.training.solid import photo_eval as pe  # noqa: E402

PHOTOS = os.path.join(ROOT, "data", "photos")


def _manifest():
    with open(os.path.join(PHOTOS, "manifest.json"), encoding="utf-8") as fh:
        return json.load(fh)


def test_photo_set_manifest_matches_the_files():
    m = _manifest()
    photos = m["photos"]
    assert len(photos) >= 200
    on_disk = {f"{s}/{f}" for s in ("train", "val") for f in os.listdir(os.path.join(PHOTOS, s))}
    assert on_disk == {e["file"] for e in photos}
    for e in photos:
        with open(os.path.join(PHOTOS, e["file"]), "rb") as fh:
            assert hashlib.sha256(fh.read()).hexdigest() == e["sha256"], e["file"]
        assert e["licence"] in bps.LICENCES
        assert e["split"] == bps.split_of(e["path"]) and e["file"].startswith(e["split"] + "/")
        assert e["package"] in bps.PACKAGES and e["version"] != "unknown"
    # whole photos are held out: no source is in both splits, and each split has many categories
    src = {}
    for e in photos:
        src.setdefault(e["source_sha256"], set()).add(e["split"])
    assert all(len(v) == 1 for v in src.values())
    cats = {s: {e["category"] for e in photos if e["split"] == s} for s in ("train", "val")}
    assert len(cats["train"]) >= 10 and len(cats["val"]) >= 8
    with open(os.path.join(PHOTOS, "ATTRIBUTION.md"), encoding="utf-8") as fh:
        text = fh.read()
    assert all(e["file"] in text for e in photos)


def test_curation_helpers():
    rng = np.random.default_rng(0)
    assert bps.category("art/textures/terrain/types/alpine_arctic/gravel_dirt_01") == "gravel"
    assert bps.category("temp_grass_norm") is None and bps.category("portrait") is None
    assert bps.stationary(np.full((64, 64, 3), 0.5, np.float32)) == (False, "flat")
    ramp = np.repeat(np.linspace(0, 1, 64, dtype=np.float32)[None, :, None], 64, 0).repeat(3, 2)
    assert bps.stationary(ramp)[0] is False
    assert bps.stationary(rng.random((64, 64, 3)).astype(np.float32))[0] is True
    text = ("Files: a/b.png\n c/d.png\nCopyright:\n Someone\nLicense: CC0\n\n"
            "Files: e.png\nCopyright: X\nLicense: GPL-2\n")
    assert bps.parse_dep5(text) == {"a/b.png": ("CC0", "Someone"), "c/d.png": ("CC0", "Someone"),
                                    "e.png": ("GPL-2", "X")}


def test_patch_distance_sees_structure_and_colour():
    rng = np.random.default_rng(1)
    # a structured image: bright blobs on dark ground, two independent draws of it
    def blobs(seed):
        r = np.random.default_rng(seed)
        img = np.full((128, 128, 3), 0.2, np.float32)
        yy, xx = np.mgrid[0:128, 0:128]
        for cy, cx in r.integers(0, 128, (40, 2)):
            img[(yy - cy) ** 2 + (xx - cx) ** 2 < 16] = (0.9, 0.8, 0.6)
        return img

    a, b = blobs(0), blobs(1)
    same = pe.patch_swd(a, b)
    assert same < pe.patch_swd(pe.pixel_shuffle(b, 128, rng), b)      # same colours, no blobs
    assert same < pe.patch_swd(np.clip(a + 0.1, 0, 1), b)             # same blobs, wrong colour
    assert pe.mean_colour_error(a + 0.05, a) == pytest.approx(0.05, abs=1e-6)
    # the pyramid's levels add back up to the image
    pyr = pe.laplacian_pyramid(a, 3)
    assert [p.shape[0] for p in pyr] == [128, 64, 32]


def test_random_phase_keeps_colour_and_spectrum():
    rng = np.random.default_rng(2)
    photo = np.clip(rng.random((64, 64, 3)) * 0.3 + np.array([0.5, 0.3, 0.1]), 0, 1).astype(np.float32)
    out = pe.random_phase(photo, 64, rng)
    assert pe.mean_colour_error(out, photo) < 0.005
    P = lambda x: np.abs(np.fft.fft2(x[..., 0] - x[..., 0].mean()))   # noqa: E731
    np.testing.assert_allclose(P(out), P(photo), rtol=0.05, atol=0.05)
    assert np.abs(out - photo).mean() > 0.05                           # not the photo itself
    hist = pe.perlin_hist(photo, 32, rng)
    assert hist.shape == (32, 32, 3) and pe.mean_colour_error(hist, photo) < 0.02


def test_gaussian_noise_has_the_photo_spectrum_on_average_and_varies_per_draw():
    """Spot noise's power averaged over draws is the photo's periodic component's, band by band, its mean colour
    the photo's; one draw's amplitudes scatter around it (random phase noise keeps them exactly)."""
    from omninoise.backend.periodic import periodic_component

    rng = np.random.default_rng(3)
    g = np.cumsum(np.cumsum(rng.standard_normal((64, 64)), 0), 1)
    photo = np.clip(0.5 + 0.2 * (g - g.mean()) / g.std(), 0, 1)[..., None] * np.array([1.0, 0.8, 0.5])
    photo = photo.astype(np.float32)
    draws = [pe.gaussian_noise(photo, 64, rng) for _ in range(200)]
    assert max(pe.mean_colour_error(d, photo) for d in draws[:5]) < 0.05
    P = lambda x: np.abs(np.fft.fft2(x[..., 0] - x[..., 0].mean())) ** 2   # noqa: E731
    want = P(periodic_component(photo[None, ..., 0])[0][..., None])
    got = np.mean([P(d) for d in draws], 0)
    r = np.hypot(*np.meshgrid(np.fft.fftfreq(64), np.fft.fftfreq(64), indexing="ij"))
    for a, b in ((0.02, 0.06), (0.06, 0.15), (0.15, 0.5)):
        band = (r >= a) & (r < b)
        assert abs(got[band].sum() / want[band].sum() - 1.0) < 0.15, (a, got[band].sum() / want[band].sum())
    one = np.sqrt(P(draws[0])[r > 0.02] / want[r > 0.02])
    rp = np.sqrt(P(pe.random_phase(photo, 64, rng))[r > 0.02] / P(photo)[r > 0.02])
    assert np.median(np.abs(one - 1.0)) > 0.25 and np.median(np.abs(rp - 1.0)) < 0.15


from omninoise.backend.solid.model import SolidTextureModel, colour_stats  # noqa: E402
from omninoise.backend.solid.pipeline import photo_code
from omninoise.backend.solid.refine import refine_code  # noqa: E402
from omninoise.training.solid import exemplars as ex  # noqa: E402
from omninoise.training.solid.export import export  # noqa: E402
from omninoise.training.solid.model import bounded_transform, colour_stats as colour_stats_t, random_rotations  # noqa: E402
from omninoise.training.solid.swd import SlicedFeatures, swd_loss  # noqa: E402
from omninoise.training.solid.train import SolidConfig, build_model, train  # noqa: E402
from omninoise.backend.onnx_models import sealed


def test_colour_stats_twins_agree_and_rebuild_the_covariance():
    img = torch.rand(1, 3, 40, 30) * torch.tensor([0.5, 0.2, 0.9]).view(1, 3, 1, 1)
    t = colour_stats_t(img)[0].numpy()
    n = colour_stats(img[0].permute(1, 2, 0).numpy())
    np.testing.assert_allclose(t, n, atol=1e-5)
    L = n[3:].reshape(3, 3)
    x = img[0].flatten(1).numpy()
    np.testing.assert_allclose(L @ L.T, np.cov(x, bias=True) + 1e-4 * np.eye(3), atol=1e-5)


def test_bounded_transforms_are_never_singular():
    R = random_rotations(8, 3).unsqueeze(0)
    for scale in (0.1, 10.0, 1000.0):
        T = bounded_transform(torch.randn(4, 8, 10) * scale, R)
        s = torch.linalg.svdvals(T)
        assert s.min() >= 0.4 * np.exp(-0.5) - 1e-5 and s.max() <= 1.6 * np.exp(0.5) + 1e-5


def test_a_translator_without_stretch_only_turns_and_scales_and_continues_a_stretching_one():
    R = random_rotations(8, 3).unsqueeze(0)
    raw = torch.randn(4, 8, 10) * 3.0
    assert torch.equal(bounded_transform(raw, R), bounded_transform(raw, R, max_stretch=0.6))   # the default
    s = torch.linalg.svdvals(bounded_transform(raw, R, max_stretch=0.0))
    np.testing.assert_allclose((s.amax(-1) / s.amin(-1)).numpy(), 1.0, atol=1e-5)       # no octave stretched
    assert (torch.linalg.svdvals(bounded_transform(raw, R)).amax(-1) / s.amax(-1)).max() > 1.2   # the default does
    root = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))), "configs",
                        "solid", "gpu")
    cfg = SolidConfig.from_dict({**json.load(open(os.path.join(root, "photo_space_gpu_nostretch_a.json"))),
                                 "device": "cpu", "init_onnx": "", "init_sha256": ""})
    assert cfg.max_stretch == 0.0 and cfg.spin == "octave"
    base = build_model(dataclasses.replace(cfg, max_stretch=0.6))
    model = build_model(cfg)
    model.load_state_dict(base.state_dict())          # the shipped weights continue into it unchanged
    z = torch.randn(3, cfg.z_dim)
    with torch.no_grad():
        _, T = model.translator(z)
    s = torch.linalg.svdvals(T)
    np.testing.assert_allclose((s.amax(-1) / s.amin(-1)).numpy(), 1.0, atol=1e-4)
    for bad, msg in (({"max_stretch": 1.0}, "max_stretch must be a number in"),
                     ({"max_stretch": -0.1}, "max_stretch must be a number in"),
                     ({"max_stretch": 0.0, "transform": "free"}, "max_stretch needs transform 'bounded'")):
        with pytest.raises(ValueError, match=msg):
            SolidConfig.from_dict({"mode": "space", "exemplars": ["gravel", "grass"], "transform": "bounded", **bad})


def test_bf16_decoder_draws_the_fp32_texture_and_is_recorded(tmp_path):
    """``precision`` "bf16": only the decoder's products run under bf16 autocast; the texture stays float32 and
    within bf16 rounding of fp32's, gradients reach every decoder weight, and the export (traced in fp32) says
    where and how the run trained.  Bad values get a one-line error."""
    from omninoise.training.precision import resolve
    from omninoise.training.solid.value_noise import octave_seeds
    from omninoise.training.solid.model import spectral_gains
    from omninoise.training.solid.train import hardware_here

    photos = ex.photo_set("train")[:2]
    cfg = dict(name="tiny_bf16", mode="space", dim=3, crop=64, batch=2, steps=2, width=16, log_every=1,
               checkpoint_every=2, threads=1, exemplars=photos, colour="affine", loss="swd", transform="bounded",
               swd_width=8, swd_levels=2, film=True, precision="bf16")
    c = SolidConfig.from_dict(cfg)
    model = build_model(c)
    assert model.precision == "fp32"                         # a model traces and exports in fp32 unless told
    ref = torch.stack([ex.load_image(p)[:, :64, :64] for p in photos])
    x = torch.from_numpy(np.random.default_rng(0).uniform(-3, 3, (2, 400, 3))).float()
    seeds = octave_seeds([3, 4], c.octaves)
    out = {}
    for prec in ("fp32", "bf16"):
        model.precision = prec
        model.zero_grad()
        e, T = model.codes(ref)
        rgb = model.sample(x, e, T, seeds, colour_stats_t(ref), spectral_gains(ref, c.octaves, c.px_per_unit))
        rgb.square().mean().backward()
        out[prec] = (rgb.detach(), [p.grad.clone() for p in model.decoder.parameters()])
    assert out["bf16"][0].dtype == torch.float32
    diff = (out["bf16"][0] - out["fp32"][0]).abs()
    assert 0 < diff.mean() < 2e-3, diff.mean()               # rounded, not a different texture
    for g16, g32 in zip(out["bf16"][1], out["fp32"][1]):
        if g32.abs().sum() > 0:
            assert torch.nn.functional.cosine_similarity(g16.flatten(), g32.flatten(), dim=0) > 0.98
    assert hardware_here(c, torch.device("cpu"), "bf16").endswith("1 threads, bf16 decoder, fp32 loss")
    assert hardware_here(c, torch.device("cpu"), "fp32").endswith("1 threads, fp32")
    lines = []
    train(c, str(tmp_path / "run"), log=lines.append)
    assert "precision: bf16 (the decoder under bf16 autocast)" in lines
    doc = export(str(tmp_path / "run"), str(tmp_path / "m"))
    assert doc["hardware"].endswith("bf16 decoder, fp32 loss")
    assert SolidConfig.from_dict({**cfg, "precision": "auto"}).precision == "auto"
    assert resolve("auto", torch.device("cpu")) in ("fp32", "bf16")
    with pytest.raises(ValueError, match="precision must be one of auto, fp32, bf16, got 'fp16'"):
        SolidConfig.from_dict({**cfg, "precision": "fp16"})


def test_swd_loss_prefers_the_texture_to_its_shuffle():
    g = torch.Generator().manual_seed(0)
    feats = SlicedFeatures(width=16, kernels=(3, 7), levels=3)
    img = ex.procedural("granite", 0, 96)[None]
    other = ex.procedural("granite", 1, 96)[None]
    shuffled = other.flatten(2)[:, :, torch.randperm(96 * 96, generator=g)].view_as(other)
    assert swd_loss(feats, other, img, generator=g) < 0.5 * swd_loss(feats, shuffled, img, generator=g)
    out = other.clone().requires_grad_()
    swd_loss(feats, out, img, per_sample=True, generator=g).backward()
    assert out.grad.abs().sum() > 0


def test_sliced_features_levels_and_wide_filters():
    """Each pyramid level gives the colour neighbourhoods and every filter that fits inside it: the default
    (3, 7) filters on 128 px crops keep their 4 levels x 3 taps; a 31 px filter stops at the 32 px level
    (needs k + 4) while the narrow taps go on."""
    img = torch.rand(1, 3, 128, 128)
    assert [t.shape[-1] for t in SlicedFeatures(width=4, kernels=(3, 7), levels=5)(img)] == \
        [124, 126, 122, 60, 62, 58, 28, 30, 26, 12, 14, 10]
    wide = SlicedFeatures(width=4, kernels=(3, 7, 31), levels=5)(img)
    assert [t.shape[-1] for t in wide] == [124, 126, 122, 98, 60, 62, 58, 34, 28, 30, 26, 12, 14, 10]


def test_photo_space_model_colour_path_export_and_refine(tmp_path):
    photos = ex.photo_set("train")[:2]
    cfg = dict(name="tiny_photo", mode="space", dim=3, crop=128, batch=2, steps=2, width=16, log_every=1,
               checkpoint_every=2, threads=1, exemplars=photos, colour="affine", loss="swd", transform="bounded",
               swd_width=8, swd_levels=2)
    state = train(SolidConfig.from_dict(cfg), str(tmp_path / "run"), log=lambda *_: None)
    doc = export(str(tmp_path / "run"), str(tmp_path / "m"))
    assert doc["colour_stats"] == 12 and len(next(iter(doc["codes"].values()))) == 8 + 12
    rt = SolidTextureModel(str(tmp_path / "m"))
    photo = ex.load_image(ex.photo_set("val")[0]).permute(1, 2, 0).numpy()
    z = rt.encode(photo)
    np.testing.assert_allclose(z[8:], colour_stats(photo), atol=1e-5)
    code = rt.translate(z)
    # the runtime's colour path equals torch's: mu + L d of the same decoder output
    m = build_model(SolidConfig.from_dict(state["config"]))
    m.load_state_dict(state["model"])
    pts = np.random.default_rng(0).uniform(-3, 3, (500, 3))
    from omninoise.training.solid.value_noise import octave_seeds
    with torch.no_grad():
        e, T = m.translator(torch.from_numpy(z[:8])[None])
        ref = m.sample(torch.from_numpy(pts).float()[None], e, T, octave_seeds([5], 8),
                       torch.from_numpy(z[8:])[None])[0].clamp(0, 1).numpy()
    np.testing.assert_allclose(rt.evaluate(pts, code, seed=5), ref, atol=2e-4)
    # the colour is the photo's by construction: moving mu moves the texture's mean colour by as much
    from dataclasses import replace
    base = rt.image(32, code, seed=1).reshape(-1, 3).mean(0)
    shifted = rt.image(32, replace(code, mu=code.mu - 0.05), seed=1).reshape(-1, 3).mean(0)
    assert np.all(np.abs((base - shifted) - 0.05) < 0.01)
    # refinement searches the latent only: the colour statistics are kept
    z2, hist = refine_code(rt, z, photo, steps=3)
    np.testing.assert_array_equal(z2[8:], z[8:])
    assert hist[-1] <= hist[0]


def test_photo_card_reads_an_export_when_the_run_is_gone(tmp_path):
    """The card section is written from the shipped export's solid.json (config, steps, wall time) when the run
    folder is not kept, with the two evaluations side by side and the ledger rows as given."""
    from omninoise.training.solid import photo_card

    space = os.path.join(ROOT, "models", "solid", "space")
    with open(os.path.join(space, "solid.json"), encoding="utf-8") as fh:
        meta = json.load(fh)
    prev = dict(summary=dict(photos=87, median_swd=300.0, ratio_to_random_phase=2.5, beats_pixel_shuffle=70))
    new = dict(summary=dict(photos=87, median_swd=210.0, ratio_to_random_phase=1.9, beats_pixel_shuffle=77,
                            median_swd_axes=230.0))
    text = photo_card.section(space, prev, new, True, "older", (("a stage", 5, "1 min", 1.0, 2.0, "3", "4", "no"),))
    # a run evaluated before the per-axis distance existed shows a dash, not None
    assert "| median distance per axis (each slice axis alone) ↓ | — | 230.0 |" in text and "None" not in text
    last = "the last stage at " if meta["config"].get("init_onnx") or meta["config"].get("init_from") else ""
    assert f"**Run:** {meta['step']} steps, {last}batch {meta['config']['batch']}" in text
    hardware = meta.get("hardware") or "hardware not recorded"
    assert f"{meta['train_seconds'] / 60:.1f} min wall in all stages, on {hardware}" in text
    assert "| median patch distance (swd) ↓ | 300.0 | 210.0 |" in text
    assert "| measure | older | this model |" in text
    assert "| a stage | 5 | 1 min | 1.0 | 2.0 | 3 | 4 | no |" in text
    with pytest.raises(SystemExit, match="neither ckpt.pt"):
        photo_card.run_facts(str(tmp_path))


def test_photo_card_lists_every_stage_of_a_continued_run(tmp_path):
    """A model trained over stages (a later config continues the earlier run with init_from) gets one training
    command per stage in its card, oldest first, with the first stage's starting export."""
    from omninoise.training.solid import photo_card

    first = tmp_path / "a_3d.json"
    first.write_text(json.dumps({"name": "a", "init_onnx": "models/solid/space", "init_sha256": "ab" * 32}))
    second = tmp_path / "b_3d.json"
    second.write_text(json.dumps({"name": "b", "init_from": "runs/solid/a", "structure_weight": 0.2,
                                  "structure_net": "runs/net.pt"}))
    lines = photo_card.stage_commands([str(first), str(second), str(second)])
    assert lines == ["# starts from the export models/solid/space (sha256 abababababab...): the model this one replaced",
                     f"python -m omninoise.training.solid.train --config {first} --out runs/solid/a",
                     "# continues runs/solid/a (the stage above)",
                     "python -m omninoise.training.solid.structure_features --out runs/net.pt   # the structure term's network",
                     f"python -m omninoise.training.solid.train --config {second} --out runs/solid/b",
                     "# continues runs/solid/a (the stage above)",
                     f"python -m omninoise.training.solid.train --config {second} --out runs/solid/b"]
    space = os.path.join(ROOT, "models", "solid", "space")
    summary = dict(summary=dict(photos=87))
    third = tmp_path / "c_3d.json"
    third.write_text(json.dumps({"name": "c", "init_onnx": "models/solid/space", "init_sha256": "cd" * 32}))
    assert photo_card.stage_commands([str(first), str(third)])[2:] == [
        "python -m omninoise.training.solid.export runs/solid/a models/solid/space   # sha256 cdcdcdcdcdcd..., which the next "
        "stage starts from", f"python -m omninoise.training.solid.train --config {third} --out runs/solid/c"]
    text = photo_card.section(space, summary, summary, True, config=[str(first), str(second)])
    assert text.index("--out runs/solid/a") < text.index("--out runs/solid/b") < text.index("training.solid.export")


@pytest.mark.parametrize("film", [False, True])
def test_warm_start_from_an_export_rebuilds_the_trained_model(tmp_path, film):
    """A run continued from an export (init_onnx) starts from the very weights that were exported: the rebuilt
    torch model equals the trained one on every tensor the export holds, continues at the export's step, and a
    wrong fingerprint or a missing one is refused in one line.  With ``film`` (code-modulated decoder, encoder
    on standardised crops) the runtime's ONNX decoder and encoder also equal torch's."""
    from omninoise.backend.onnx_models import fingerprint
    from omninoise.training.solid.warm_start import exported_weights, warm_start

    photos = ex.photo_set("train")[:2]
    cfg = dict(name="tiny_photo", mode="space", dim=3, crop=64, batch=2, steps=4, width=16, log_every=1,
               checkpoint_every=2, threads=1, exemplars=photos, colour="affine", loss="swd", transform="bounded",
               swd_width=8, swd_levels=2, film=film, standardise=film, spectral=film)
    state = train(SolidConfig.from_dict(dict(cfg, steps=2)), str(tmp_path / "run"), log=lambda *_: None)
    doc = export(str(tmp_path / "run"), str(tmp_path / "m"))
    sha = fingerprint(doc["files"])
    m = build_model(SolidConfig.from_dict(cfg))
    warm_start(m, exported_weights(str(tmp_path / "m"), sha))
    got = m.state_dict()
    for name, ref in state["model"].items():
        if name.startswith("encoder.norms.4."):
            continue          # not in the export (its output is never read)
        np.testing.assert_allclose(got[name].numpy(), ref.numpy(), atol=1e-6, err_msg=name)
    if film:
        film_w = float(m.decoder.film.weight.abs().sum())
        assert np.isfinite(film_w) and film_w > 0, film_w          # trained away from its zero start
        rt = SolidTextureModel(str(tmp_path / "m"))
        photo = ex.load_image(ex.photo_set("val")[0]).permute(1, 2, 0).numpy()
        z = rt.encode(photo)
        crop = torch.from_numpy(np.ascontiguousarray(photo[:128, :128].transpose(2, 0, 1)))[None]
        with torch.no_grad():
            assert float(m.encoder(crop).abs().max()) > 0
            # standardised input: a crop's colour and contrast do not change its code
            np.testing.assert_allclose(m.encoder(crop * 0.5 + 0.2).numpy(), m.encoder(crop).numpy(), rtol=5e-3, atol=5e-3)
        pts = np.random.default_rng(0).uniform(-3, 3, (300, 3))
        from omninoise.training.solid.value_noise import octave_seeds
        assert z.shape == (8 + 12 + 8,) and rt.translate(z).gains.shape == (8,)
        with torch.no_grad():
            e, T = m.translator(torch.from_numpy(z[:8])[None])
            ref = m.sample(torch.from_numpy(pts).float()[None], e, T, octave_seeds([5], 8),
                           torch.from_numpy(z[8:20])[None], torch.from_numpy(z[20:])[None])[0].clamp(0, 1).numpy()
        np.testing.assert_allclose(rt.evaluate(pts, rt.translate(z), seed=5), ref, atol=2e-4)
    logs = []
    cont = train(SolidConfig.from_dict(dict(cfg, init_onnx=str(tmp_path / "m"), init_sha256=sha, warmup=2)),
                 str(tmp_path / "cont"), log=logs.append)
    assert any("at step 2" in line for line in logs) and cont["step"] == 4 and cont["first_step"] == 2
    with pytest.raises(ValueError, match="the config pins"):
        exported_weights(str(tmp_path / "m"), "0" * 64)
    with pytest.raises(ValueError, match="init_onnx needs init_sha256"):
        SolidConfig.from_dict(dict(cfg, init_onnx=str(tmp_path / "m")))
    # single mode: e and T come back from the JSON
    one = dict(cfg, mode="single", exemplars=photos[:1], steps=1, checkpoint_every=1, spectral=False)
    state1 = train(SolidConfig.from_dict(one), str(tmp_path / "run1"), log=lambda *_: None)
    doc1 = export(str(tmp_path / "run1"), str(tmp_path / "m1"))
    m1 = build_model(SolidConfig.from_dict(one))
    warm_start(m1, exported_weights(str(tmp_path / "m1"), fingerprint(doc1["files"])))
    for name, ref in state1["model"].items():
        np.testing.assert_allclose(m1.state_dict()[name].numpy(), ref.numpy(), atol=1e-6, err_msg=name)


def test_spectral_gains_twins_agree_and_follow_the_grain():
    """The per-octave gains (training.solid.model.spectral_gains and its numpy twin) agree; a fine-grained image
    raises the fine octaves' gains, a smooth one the coarse octaves'; a flat image gives 1 everywhere."""
    from omninoise.backend.solid.model import spectral_gains as gains_np
    from omninoise.training.solid.model import spectral_gains as gains_t

    rng = np.random.default_rng(0)
    fine = rng.random((128, 128, 3)).astype(np.float32)                 # pixel noise: detail at 1-2 px
    coarse = np.kron(rng.random((8, 8, 3)), np.ones((16, 16, 1))).astype(np.float32)   # 16 px blocks
    for img in (fine, coarse, ex.load_image(ex.photo_set("val")[3]).permute(1, 2, 0).numpy()[:128, :128]):
        t = gains_t(torch.from_numpy(np.ascontiguousarray(img.transpose(2, 0, 1)))[None])[0].numpy()
        np.testing.assert_allclose(gains_np(img), t, rtol=1e-4, atol=1e-5)
    gf, gc = gains_np(fine), gains_np(coarse)
    assert gf[7] > 2 * gf[2] and gc[3] > 2 * gc[7]                      # octave 7: 1 px lattice; octave 3: 16 px
    np.testing.assert_allclose(gains_np(np.full((64, 64, 3), 0.3, np.float32)), 1.0, atol=1e-4)
    with pytest.raises(ValueError, match="spectral gains"):
        SolidConfig.from_dict(dict(mode="single", exemplars=["gravel"], spectral=True))


def test_features_added_to_an_export_start_as_the_export(tmp_path):
    """Cellular and brick features added to a model trained without them (init_onnx with new ``cellular``
    and ``bricks``): their first-layer columns start at zero, so the grown model draws the export's texture
    exactly, and the continued run trains them; features are not added to an export that has some."""
    from omninoise.backend.onnx_models import fingerprint
    from omninoise.training.solid.value_noise import octave_seeds
    from omninoise.training.solid.warm_start import exported_weights, warm_start

    photos = ex.photo_set("train")[:2]
    cfg = dict(name="tiny_grow", mode="space", dim=3, crop=64, batch=2, steps=2, width=16, log_every=1,
               checkpoint_every=2, threads=1, exemplars=photos, colour="affine", loss="swd", transform="bounded",
               swd_width=8, swd_levels=2, film=True, standardise=True, spectral=True)
    state = train(SolidConfig.from_dict(cfg), str(tmp_path / "run"), log=lambda *_: None)
    doc = export(str(tmp_path / "run"), str(tmp_path / "m"))
    sha = fingerprint(doc["files"])
    old = build_model(SolidConfig.from_dict(cfg))
    old.load_state_dict(state["model"])
    grown = build_model(SolidConfig.from_dict(dict(cfg, cellular=2, bricks=1)))
    warm_start(grown, exported_weights(str(tmp_path / "m"), sha), new_features=9)
    pts = torch.from_numpy(np.random.default_rng(0).uniform(-3, 3, (1, 400, 3))).float()
    z = torch.randn(1, 8)
    stats, gains = torch.rand(1, 12), torch.rand(1, 8) + 0.5
    with torch.no_grad():
        e, T = old.translator(z)
        a = old.sample(pts, e, T, octave_seeds([3], 8), stats, gains)
        b = grown.sample(pts, e, T, octave_seeds([3], 8), stats, gains)
    np.testing.assert_allclose(b.numpy(), a.numpy(), atol=1e-6)
    grow = dict(cfg, cellular=2, bricks=1, steps=4, init_onnx=str(tmp_path / "m"), init_sha256=sha)
    cont = train(SolidConfig.from_dict(grow), str(tmp_path / "cont"), log=lambda *_: None)
    w = cont["model"]["decoder.net.0.weight"]
    assert w.shape[1] == 8 * 3 + 9 + 64 and float(w[:, 24:33].abs().sum()) > 0     # the new columns trained
    doc2 = export(str(tmp_path / "cont"), str(tmp_path / "m2"))
    with pytest.raises(ValueError, match="features can be added only"):
        train(SolidConfig.from_dict(dict(grow, cellular=3, init_onnx=str(tmp_path / "m2"),
                                         init_sha256=fingerprint(doc2["files"]))), str(tmp_path / "c2"),
              log=lambda *_: None)


def test_held_out_photo_evaluation_reports_patch_and_morphology_measures(tmp_path, bench_script):
    """python -m bench solid-photos on a tiny space model and two held-out photos: every measure per photo, the
    summary's medians, and the photo's own crop nearer to the photo than the pixel shuffle (patches) and random phase (morphology)."""
    import json

    mod = bench_script("eval_solid_photos")
    cfg = dict(name="tiny_eval", mode="space", dim=3, crop=64, batch=2, steps=1, width=16, log_every=1,
               checkpoint_every=1, threads=1, exemplars=ex.photo_set("train")[:2], colour="affine", loss="swd",
               transform="bounded", swd_width=8, swd_levels=2, cellular=1, bricks=1)
    train(SolidConfig.from_dict(cfg), str(tmp_path / "run"), log=lambda *_: None)
    export(str(tmp_path / "run"), str(tmp_path / "m"))
    out = tmp_path / "eval.json"
    counts = []
    real_levels = mod.pe.level_distances       # every patch distance goes through it

    def counting_levels(images, reference, *a, **k):
        counts.append(1 if isinstance(images, np.ndarray) else len(images))
        return real_levels(images, reference, *a, **k)

    mod.pe.level_distances = counting_levels
    try:
        assert mod.main(["--model", str(tmp_path / "m"), "--limit", "2", "-o", str(out)]) == 0
    finally:
        mod.pe.level_distances = real_levels
    # every baseline meets the photo as often as the model's slices do: pooled six (model, 4 baselines), walls
    # four (model, random phase, the photo's crops), single axes two; nothing scored from another count; the six
    # oblique cuts meet random phase noise's six pooled draws
    assert sorted(set(counts)) == [2, 4, 6]
    assert counts.count(6) == 2 * 6 and counts.count(4) == 2 * 3 and counts.count(2) == 2 * 3 * 3
    doc = json.loads(out.read_text())
    assert doc["summary"]["photos"] == 2 and doc["summary"]["median_morph"] > 0
    for r in doc["photos"].values():
        assert r["photo_crop"] < r["pixel_shuffle"] and r["morph_photo_crop"] < r["morph_random_phase"]
        assert set(r) >= {"swd", "morph", "morph_random_phase", "colour", "random_phase", "axis_spread", "spectrum",
                          "spectrum_random_phase"}
        assert r["spectrum"] > 0 and r["spectrum_random_phase"] > 0
        assert r["swd_axes"] == pytest.approx((r["x"] + r["y"] + r["z"]) / 3, abs=0.06)
        assert r["photo_crop_axes"] < r["random_phase_axes"] or r["photo_crop_walls"] < r["random_phase_walls"]
        assert r["photo_crop_band"] < r["band"] and r["photo_crop_band"] < r["pixel_shuffle"]
        assert r["band_axes"] == pytest.approx((r["x_band"] + r["y_band"] + r["z_band"]) / 3, abs=0.06)
        assert 0 < r["oblique_band"] < r["oblique"] < r["pixel_shuffle"]
        assert (r["random_phase_oblique"], r["random_phase_oblique_band"]) == (r["random_phase"],
                                                                              r["random_phase_band"])
    assert doc["summary"]["median_spectrum"] > 0
    assert doc["summary"]["beats_random_phase_oblique"] == sum(r["oblique"] < r["random_phase"]
                                                               for r in doc["photos"].values())
    assert 0 <= doc["summary"]["beats_random_phase_axes"] <= 6


def test_grouped_patch_distance_pools_like_the_model_and_counts_matter():
    """photo_eval.grouped_swd: each axis alone, their mean, the walls (x and y) and all pooled, each the patch
    distance of those images; and why the evaluation groups baselines so: the photo's own crops pooled six at a
    time lie closer to it than two at a time, so a comparison at unequal counts favours the larger."""
    photo = ex.load_image([p for p in ex.photo_set("val") if "rock1" in p][0]).permute(1, 2, 0).numpy()
    rng = np.random.default_rng(3)
    groups = {ax: [pe.photo_crop(photo, 128, rng) for _ in range(2)] for ax in "xyz"}
    d = pe.grouped_swd(groups, photo)
    for ax in "xyz":
        assert d[ax] == round(pe.patch_swd(groups[ax], photo), 1)
    assert d["axes"] == pytest.approx(np.mean([d[ax] for ax in "xyz"]), abs=0.06)
    assert d["walls"] == round(pe.patch_swd(groups["x"] + groups["y"], photo), 1)
    assert d["pooled"] == round(pe.patch_swd([im for v in groups.values() for im in v], photo), 1)
    assert d["pooled"] < 0.85 * d["axes"]
    lv = pe.level_distances(groups["x"], photo)
    assert d["x_band"] == round(pe.band_swd(lv), 1) and d["x"] == round(1000 * sum(lv) / 4, 1)
    assert d["pooled_band"] < d["pooled"]      # the residue is the level where crops lie farthest
    assert pe.photo_crop(photo[:100, :90], 128, rng).shape == (100, 90, 3)     # a small photo: itself


def test_min_spacing_caps_every_octave_lattice_in_training_and_in_the_export(tmp_path):
    """``min_spacing``: no octave's lattice is finer than that many exemplar pixels, whatever the translator
    asks for (largest singular value of T_i <= (px_per_unit / 2^i) / min_spacing), in torch and in the
    exported translator the runtime reads; octaves coarse enough are not touched; bad values are refused."""
    from omninoise.backend.onnx_models import fingerprint
    from omninoise.training.solid.model import bounded_transform, max_scales, random_rotations
    from omninoise.training.solid.warm_start import exported_weights, warm_start

    np.testing.assert_allclose(max_scales(4, 16.0, 2.0).numpy(), [8.0, 4.0, 2.0, 1.0])
    R = random_rotations(4, 3)
    raw = torch.randn(64, 4, 10) * 5.0                      # every stretch and scale pushed to its bound
    free = torch.linalg.svdvals(bounded_transform(raw, R)).amax(-1)
    capped = torch.linalg.svdvals(bounded_transform(raw, R, max_scales(4, 16.0, 8.0))).amax(-1)   # caps 2, 1, .5, .25
    assert float(free.max()) > 2.0                                                                # the bound alone
    assert bool((capped <= torch.tensor([2.0, 1.0, 0.5, 0.25]) + 1e-5).all())
    np.testing.assert_allclose(capped[:, 0].numpy(), torch.minimum(free[:, 0], torch.tensor(2.0)).numpy(), rtol=0.35)
    loose = torch.linalg.svdvals(bounded_transform(raw, R, max_scales(4, 16.0, 0.1))).amax(-1)     # caps >= 20
    np.testing.assert_allclose(loose.numpy(), free.numpy(), rtol=1e-6)

    photos = ex.photo_set("train")[:2]
    cfg = dict(name="tiny_spacing", mode="space", dim=3, crop=64, batch=2, steps=2, width=16, log_every=1,
               checkpoint_every=2, threads=1, exemplars=photos, colour="affine", loss="swd", transform="bounded",
               swd_width=8, swd_levels=2, px_per_unit=32.0, octaves=4, min_spacing=8.0)
    train(SolidConfig.from_dict(cfg), str(tmp_path / "run"), log=lambda *_: None)
    doc = export(str(tmp_path / "run"), str(tmp_path / "m"))
    rt = SolidTextureModel(str(tmp_path / "m"))
    for path in photos:
        T = np.asarray(rt.translate(rt.encode(ex.load_image(path).permute(1, 2, 0).numpy())).T)
        top = np.linalg.svd(T, compute_uv=False).max(-1)
        assert (top <= np.array([4.0, 2.0, 1.0, 0.5]) + 1e-5).all() and top[3] > 0.45, top
    # an export made without the cap continues with it (the cap is config, not a weight)
    plain = dict(cfg, min_spacing=0.0, name="tiny_plain")
    train(SolidConfig.from_dict(plain), str(tmp_path / "run0"), log=lambda *_: None)
    doc0 = export(str(tmp_path / "run0"), str(tmp_path / "m0"))
    m = build_model(SolidConfig.from_dict(cfg))
    warm_start(m, exported_weights(str(tmp_path / "m0"), fingerprint(doc0["files"])))
    assert "translator.max_scale" not in m.state_dict()
    for bad, msg in ((-1.0, "min_spacing must be"), (float("nan"), "min_spacing must be")):
        with pytest.raises(ValueError, match=msg):
            SolidConfig.from_dict(dict(cfg, min_spacing=bad))
    with pytest.raises(ValueError, match="needs mode 'space' and transform 'bounded'"):
        SolidConfig.from_dict(dict(cfg, transform="free"))
    assert doc["config"]["min_spacing"] == 8.0


def test_single_photo_model_holds_out_a_quarter_and_ships_its_colour(tmp_path, bench_script):
    """A single-exemplar photo model (``hold_out``): training crops only the left three quarters, the export
    carries the photo's colour (mu, L) so the runtime draws in it without an encoder, and
    python -m bench solid-singles measures it on the right quarter beside random phase, the shuffle and a space model."""
    photo_path = os.path.relpath(ex.photo_set("train")[0], ROOT)
    img = ex.exemplar(os.path.join(ROOT, photo_path))
    cfg = dict(name="tiny_single", mode="single", dim=3, crop=64, batch=2, steps=2, width=16, log_every=1,
               checkpoint_every=2, threads=1, exemplars=[os.path.join(ROOT, photo_path)], colour="affine",
               loss="swd", swd_width=8, swd_levels=2, hold_out=True)
    c = SolidConfig.from_dict(cfg)
    from omninoise.training.solid.train import training_images
    (region,) = training_images(c)
    assert region.shape[2] == img.shape[2] * 3 // 4          # the right quarter never reaches training
    assert training_images(SolidConfig.from_dict({**cfg, "hold_out": False}))[0].shape[2] == img.shape[2]
    with pytest.raises(ValueError, match="hold_out"):
        SolidConfig.from_dict({**cfg, "mode": "space", "exemplars": ex.photo_set("train")[:2]})
    train(c, str(tmp_path / "run"), log=lambda *_: None)
    doc = export(str(tmp_path / "run"), str(tmp_path / "models" / "tiny_single"))
    np.testing.assert_allclose(doc["colour_code"], colour_stats(region.permute(1, 2, 0).numpy()), atol=1e-5)
    from omninoise.training.precision import resolve            # precision "auto": bf16 where this CPU computes it natively
    prec = "fp32" if resolve("auto", torch.device("cpu")) == "fp32" else "bf16 decoder, fp32 loss"
    assert doc["hardware"].endswith(f"1 threads, {prec}")    # where it trained travels with the export
    rt = SolidTextureModel(str(tmp_path / "models" / "tiny_single"))
    code = rt.default_code()
    np.testing.assert_allclose(code.mu, doc["colour_code"][:3], atol=1e-6)
    pic = rt.image(32, code, seed=0, axis="x")
    assert pic.shape == (32, 32, 3) and 0.0 <= pic.min() and pic.max() <= 1.0
    assert rt.exemplar_label == os.path.basename(photo_path).split("__")[0]
    # an export without the colour it draws in is refused when loaded, with a one-line reason
    broken = dict(json.loads((tmp_path / "models" / "tiny_single" / "solid.json").read_text()))
    del broken["colour_code"]
    (tmp_path / "models" / "tiny_single" / "solid.json").write_text(json.dumps(sealed(broken)))
    from omninoise.backend.onnx_models import ModelError
    with pytest.raises(ModelError, match="colour_code"):
        SolidTextureModel(str(tmp_path / "models" / "tiny_single"))
    (tmp_path / "models" / "tiny_single" / "solid.json").write_text(json.dumps(sealed(doc)))
    # the held-out evaluation: every measure, against the shipped space model given the same training pixels
    mod = bench_script("eval_solid_singles")
    out = tmp_path / "singles.json"
    assert mod.main(["--models", str(tmp_path / "models"), "--space", os.path.join(ROOT, "models", "solid", "space"),
                     "--prev", str(tmp_path / "models"), "-o", str(out), "--sheet", str(tmp_path / "s.png")]) == 0
    r = json.loads(out.read_text())["rows"]["tiny_single"]
    assert set(r) >= {"swd", "space", "random_phase", "pixel_shuffle", "photo_crop", "colour", "morph", "previous"}
    assert r["previous"] == r["swd"]          # the "previous" model here is the model itself: the same figures
    assert r["photo_crop"] < r["pixel_shuffle"] and r["photo_crop"] < r["swd"]   # a 2-step model is far from the photo
    assert (tmp_path / "s.png").stat().st_size > 1000


def test_harmonic_rest_trains_on_photos_less_their_part_as_the_runtime_encodes_them(tmp_path):
    """``harmonic_rest``: training crops each photo's rest (its harmonic part removed as the runtime removes it),
    the export says so, and the exported model encodes a photo's rest when the part rides along; the option
    needs a space photo model."""
    from omninoise.backend.solid.harmonic import photo_harmonics, remove_harmonics
    from omninoise.training.solid.train import training_images

    brick = [p for p in ex.photo_set("train") if "brick2b" in p]
    cfg = dict(name="tiny_rest", mode="space", dim=3, crop=128, batch=2, steps=2, width=16, log_every=1,
               checkpoint_every=2, threads=1, exemplars=brick + ex.photo_set("train")[:1], colour="affine",
               loss="swd", transform="bounded", swd_width=8, swd_levels=2, harmonic_rest=True)
    rests = training_images(SolidConfig.from_dict(cfg))
    fulls = training_images(SolidConfig.from_dict(dict(cfg, harmonic_rest=False)))
    full = fulls[0].permute(1, 2, 0).numpy()
    h = photo_harmonics(full, 128.0)
    assert h.share > 0.5
    np.testing.assert_allclose(rests[0].permute(1, 2, 0).numpy(), remove_harmonics(full, h, 128.0), atol=1e-6)
    assert rests[0].var() < 0.6 * fulls[0].var()
    train(SolidConfig.from_dict(cfg), str(tmp_path / "run"), log=lambda *_: None)
    doc = export(str(tmp_path / "run"), str(tmp_path / "m"))
    assert doc["harmonic_rest"] is True
    rt = SolidTextureModel(str(tmp_path / "m"))
    photo = ex.load_image(brick[0]).permute(1, 2, 0).numpy()
    part = rt.harmonics(photo)
    z = rt.encode(photo, part)
    np.testing.assert_allclose(z[8:20], colour_stats(remove_harmonics(photo, part, rt.px_per_unit)), atol=1e-5)
    np.testing.assert_allclose(rt.encode(photo)[8:20], colour_stats(photo), atol=1e-5)
    # the name "brick" keeps its photo's part, measured from the photo, not its rest: the name draws the photo's
    # code as encoding the photo would
    assert set(doc["code_harmonics"]) == {"brick"} and rt.code_harmonics["brick"].share > 0.5
    named, encoded = rt.code("brick"), photo_code(rt, photo).code
    np.testing.assert_allclose(named.e, encoded.e, atol=1e-4)
    np.testing.assert_array_equal(named.harmonics.freq, encoded.harmonics.freq)
    # and its Gaussian rest where the check keeps one for the photo (written by the export from the photo)
    assert (named.rest is None) == (encoded.rest is None) == ("brick" not in doc.get("code_rests", {}))
    if named.rest is not None:
        assert named.rest.mix == encoded.rest.mix
        np.testing.assert_allclose(named.rest.freq, encoded.rest.freq, rtol=1e-5)
    for bad in (dict(cfg, mode="single", exemplars=brick), dict(cfg, colour="sigmoid")):
        with pytest.raises(ValueError, match="harmonic_rest"):
            SolidConfig.from_dict(bad)


def test_axis_imbalance_tells_oriented_photos_from_isotropic_ones_and_bounds_what_a_solid_can_show():
    n = 128
    y, x = np.mgrid[:n, :n] / n
    grey = lambda a: np.repeat(a[..., None], 3, 2)          # noqa: E731
    planks = grey(0.5 + 0.4 * np.sin(2 * np.pi * 12 * x))    # stripes across the columns only
    assert pe.axis_imbalance(planks) == pytest.approx(1.0, abs=1e-3)
    assert pe.axis_imbalance(planks.transpose(1, 0, 2)) == pytest.approx(1.0, abs=1e-3)   # and across the rows
    assert pe.axis_imbalance(grey(0.5 + 0.2 * np.sin(2 * np.pi * 12 * x) + 0.2 * np.sin(2 * np.pi * 12 * y))) < 1e-3
    noise = np.random.default_rng(0).random((n, n, 3))
    assert pe.axis_imbalance(noise) < 0.1
    # symmetric: a turned photo is as oriented; a flat one is 0
    assert pe.axis_imbalance(planks[:, :100]) == pytest.approx(pe.axis_imbalance(planks[:, :100].transpose(1, 0, 2)))
    assert pe.axis_imbalance(np.full((32, 48, 3), 0.3)) == 0.0
    # a solid whose walls (slices normal to x and y, rows along z) both show the planks: sin(2 pi 12 (x + y));
    # its floor (normal to z) then has the walls' column spectrum on both axes, so it is not oriented at all
    f = lambda X, Y, Z: grey(0.5 + 0.4 * np.sin(2 * np.pi * 12 * (X + Y)))     # noqa: E731
    wall_x, wall_y, floor = f(0.3, x, y), f(x, 0.7, y), f(x, y, 0.1)
    assert pe.axis_imbalance(wall_x) == pytest.approx(1.0, abs=1e-3) and pe.axis_imbalance(wall_y) > 0.999
    assert pe.axis_imbalance(floor) < 1e-3
