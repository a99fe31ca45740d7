"""Neural noise training parts: U-Net, schedule, sampler, loss, CutMix, resumable training."""
import json
import math
import os

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from omninoise.backend.neural.sampler import ddim_sample, ddim_step, initial_noise  # noqa: E402
from omninoise.backend.neural.schedule import cosine_alphas_cumprod, ddim_timesteps  # noqa: E402
from omninoise.training import zoo  # noqa: E402
from omninoise.training.cutmix import cutmix  # noqa: E402
from omninoise.training.diffusion import Diffusion  # noqa: E402
from omninoise.training.train import TrainConfig, train  # noqa: E402
from omninoise.training.unet import UNet, set_circular  # noqa: E402

TINY = dict(size=16, batch=4, widths=(8, 16, 16), emb_dim=8, log_every=1, checkpoint_every=2, sample_every=0,
            classes=("perlin", "spots", "cells_f1"))


def test_unet_size_and_shapes():
    m = UNet(len(zoo.CLASS_NAMES), len(zoo.PARAM_NAMES))
    n = sum(p.numel() for p in m.parameters())
    assert 4.5e6 < n < 5.6e6, n  # the paper's ~5.1M (Appendix C)
    small = UNet(3, 2, emb_dim=4, widths=(8, 16, 16))
    x = torch.randn(2, 1, 24, 40)
    cond = small.embed(torch.zeros(2, 24, 40, dtype=torch.long), torch.rand(2, 2, 24, 40))
    assert cond.shape == (2, 6, 24, 40)
    assert small(x, torch.tensor([3.0, 900.0]), cond).shape == (2, 1, 24, 40)


def test_circular_padding_makes_the_network_wrap():
    torch.manual_seed(0)
    m = set_circular(UNet(3, 2, emb_dim=4, widths=(8, 16, 16)).eval())
    x = torch.randn(1, 1, 32, 32)
    cond = m.embed(torch.ones(1, 32, 32, dtype=torch.long), torch.full((1, 2, 32, 32), 0.3))
    t = torch.tensor([100.0])
    with torch.no_grad():
        a = m(torch.roll(x, (8, 16), (2, 3)), t, cond)
        b = torch.roll(m(x, t, cond), (8, 16), (2, 3))
    assert torch.allclose(a, b, atol=1e-5)  # translation-equivariant on the torus: tiles seamlessly
    set_circular(m, False)
    with torch.no_grad():
        assert not torch.allclose(m(torch.roll(x, (8, 16), (2, 3)), t, cond), torch.roll(m(x, t, cond), (8, 16), (2, 3)),
                                  atol=1e-3)


def test_cosine_schedule_golden_values():
    ab = cosine_alphas_cumprod(1000)
    f = lambda t: math.cos((t / 1000 + 0.008) / 1.008 * math.pi / 2) ** 2  # noqa: E731
    for t in (0, 1, 250, 500, 900):
        assert ab[t] == pytest.approx(f(t + 1) / f(0), rel=1e-9)
    assert np.all(np.diff(ab) < 0) and ab[-1] < 1e-6
    np.testing.assert_array_equal(ddim_timesteps(5), [999, 749, 500, 250, 0])
    assert len(ddim_timesteps(30)) == 30 and ddim_timesteps(30)[0] == 999 and ddim_timesteps(30)[-1] == 0
    with pytest.raises(ValueError):
        ddim_timesteps(0)


def test_ddim_recovers_data_of_an_exact_model_and_calls_back():
    ab = cosine_alphas_cumprod()
    data = np.linspace(-0.8, 0.8, 64, dtype=np.float32).reshape(1, 1, 8, 8)

    def model(x, t, cond):  # the exact ε for a point-mass data distribution
        a = ab[int(t[0])]
        return (x - np.sqrt(a) * data) / np.sqrt(1 - a)

    seen = []
    out = ddim_sample(model, initial_noise(3, (1, 1, 8, 8)), None, steps=12, callback=lambda i, n, x0: seen.append(i))
    np.testing.assert_allclose(out, data, atol=1e-5)
    assert seen == list(range(12))
    np.testing.assert_array_equal(initial_noise(3, (2, 2)), initial_noise(3, (2, 2)))

    class Stop(Exception):
        pass

    def cancel(i, n, x0):
        if i == 2:
            raise Stop

    with pytest.raises(Stop):
        ddim_sample(model, initial_noise(3, (1, 1, 8, 8)), None, steps=12, callback=cancel)
    x, x0 = ddim_step(np.ones((1, 1, 2, 2), np.float32), np.zeros((1, 1, 2, 2), np.float32), 0.25, 1.0)
    np.testing.assert_allclose(x0, 1.0)  # clipped x̂₀ = 1 / √0.25 = 2 -> 1


def test_loss_parts():
    d = Diffusion()
    x0 = torch.zeros(64, 1, 8, 8)
    eps = d.noise_like(x0, torch.Generator().manual_seed(0))
    per_image = eps.mean(dim=(1, 2, 3))
    assert 0.05 < per_image.std() < 0.2  # offset noise: a shared shift of std 0.1 per image
    t = torch.full((64,), 999)
    assert d.q_sample(torch.ones(64, 1, 8, 8), t, torch.zeros_like(x0)).max() < 1e-3
    e = torch.randn(5, 32)
    e = e / e.norm(dim=1, keepdim=True) * math.sqrt(32)
    assert d.embedding_penalty(e) < 1e-10
    assert d.embedding_penalty(e * 2) == pytest.approx(0.02 * 32, rel=1e-4)


def test_min_snr_weights():
    """Hang et al. 2023, Eq. 8 (ε-prediction): w(t) = min(SNR, γ) / SNR; 1 where SNR <= γ; off at γ = 0."""
    from omninoise.backend.neural.schedule import cosine_alphas_cumprod

    ab = cosine_alphas_cumprod()
    snr = ab / (1 - ab)
    t = torch.tensor([0, 50, 200, 500, 999])
    w = Diffusion(min_snr_gamma=5.0).snr_weight(t).numpy()
    np.testing.assert_allclose(w, np.minimum(snr[t.numpy()], 5.0) / snr[t.numpy()], rtol=1e-3)  # float32 1 - ab
    assert w[0] < 0.01 and w[-1] == pytest.approx(1.0)  # the first steps are damped, the noisy ones are not
    assert torch.equal(Diffusion().snr_weight(t), torch.ones(5))
    with pytest.raises(ValueError, match="min_snr_gamma"):
        Diffusion(min_snr_gamma=-1.0)
    # the reported mse stays the unweighted one, the total carries the weights
    m = UNet(3, 2, emb_dim=4, widths=(8, 8, 8))
    x0 = torch.zeros(4, 1, 16, 16)
    cond = m.embed(torch.zeros(4, 16, 16, dtype=torch.long), torch.zeros(4, 2, 16, 16))
    plain = Diffusion(emb_lambda=0.0).loss(m, x0, cond, torch.Generator().manual_seed(3))
    snrw = Diffusion(emb_lambda=0.0, min_snr_gamma=5.0).loss(m, x0, cond, torch.Generator().manual_seed(3))
    assert float(plain[1]) == pytest.approx(float(snrw[1]))
    assert float(plain[0]) == pytest.approx(float(plain[1]))
    assert float(snrw[0]) < float(snrw[1])


def test_low_snr_weights():
    """min(1/ᾱ_t, W): the ε error turned into the v error (1 + 1/SNR = 1/ᾱ), capped at W; about 1 on the clean
    steps, W on the noisiest; combined with min-SNR-γ by product; off at W = 1."""
    from omninoise.backend.neural.schedule import cosine_alphas_cumprod

    ab = cosine_alphas_cumprod()
    t = torch.tensor([0, 300, 700, 900, 999])
    w = Diffusion(low_snr_weight=10.0).snr_weight(t).numpy()
    np.testing.assert_allclose(w, np.minimum(1.0 / ab[t.numpy()], 10.0), rtol=1e-4)
    assert w[0] == pytest.approx(1.0, abs=1e-3) and w[-1] == pytest.approx(10.0) and 1.0 < w[2] < w[3] <= 10.0
    assert torch.equal(Diffusion(low_snr_weight=1.0).snr_weight(t), torch.ones(5))
    both = Diffusion(min_snr_gamma=5.0, low_snr_weight=10.0).snr_weight(t)
    assert torch.allclose(both, Diffusion(min_snr_gamma=5.0).snr_weight(t) * Diffusion(low_snr_weight=10.0).snr_weight(t))
    with pytest.raises(ValueError, match="low_snr_weight must be >= 1"):
        Diffusion(low_snr_weight=0.5)
    m = UNet(3, 2, emb_dim=4, widths=(8, 8, 8))
    x0 = torch.zeros(4, 1, 16, 16)
    cond = m.embed(torch.zeros(4, 16, 16, dtype=torch.long), torch.zeros(4, 2, 16, 16))
    plain = Diffusion(emb_lambda=0.0).loss(m, x0, cond, torch.Generator().manual_seed(3))
    low = Diffusion(emb_lambda=0.0, low_snr_weight=10.0).loss(m, x0, cond, torch.Generator().manual_seed(3))
    assert float(plain[1]) == pytest.approx(float(low[1])) and float(low[0]) > float(low[1])


def test_cutmix_pastes_other_classes_with_their_conditions():
    B, H = 6, 32
    imgs = torch.arange(B, dtype=torch.float32).view(B, 1, 1, 1).expand(B, 1, H, H).clone()
    ids = torch.tensor([0, 0, 1, 1, 2, 2]).view(B, 1, 1).expand(B, H, H).clone()
    params = (torch.arange(B, dtype=torch.float32) * 10).view(B, 1, 1, 1).expand(B, 2, H, H).clone()
    mi, mid, mp = cutmix(imgs, ids, params, np.random.default_rng(1), p=1.0)
    for b in range(B):
        donors = mi[b, 0].unique().long().tolist()
        assert len(donors) >= 2  # something was pasted
        for d in donors:
            m = mi[b, 0] == d
            assert torch.all(mid[b][m] == ids[d, 0, 0]) and torch.all(mp[b][:, m] == 10 * d)
            assert d == b or ids[d, 0, 0] != ids[b, 0, 0]  # donors are of another class
    same = cutmix(imgs, ids, params, np.random.default_rng(1), p=0.0)
    assert torch.equal(same[0], imgs) and torch.equal(same[1], ids)


def _cutmix_in_place(images, ids, params, rng, p):
    """The in-place form CutMix had before source maps (the reference for the equality below)."""
    from omninoise.training.cutmix import rotated_box_mask

    src = (images, ids, params)
    images, ids, params = images.clone(), ids.clone(), params.clone()
    B, _, H, W = images.shape
    base = ids[:, 0, 0].clone()
    for b in range(B):
        if rng.random() >= p:
            continue
        donors = np.nonzero((base != base[b]).numpy())[0]
        if len(donors) == 0:
            continue
        for _ in range(int(rng.integers(1, 5))):
            d = int(rng.choice(donors))
            w, h = float(rng.uniform(0.25, 0.75)) * W, float(rng.uniform(0.25, 0.75)) * H
            m = rotated_box_mask(H, W, float(rng.uniform(0, W)), float(rng.uniform(0, H)), w, h,
                                 float(rng.uniform(0, math.pi)))
            images[b, :, m] = src[0][d, :, m]
            ids[b, m] = src[1][d, m]
            params[b][:, m] = src[2][d][:, m]
    return images, ids, params


def test_cutmix_by_source_map_equals_pasting_in_place_and_keeps_the_data_stream():
    """Training now draws a source map and gathers on its device (no (B, P, H, W) maps built on the CPU): the same
    mixed batch, bit for bit, as pasting in place, and the same draws from the run's generator after it."""
    from omninoise.training.cutmix import cutmix_sources, mix_by_sources
    from omninoise.training.train import _conditions

    B, H, P = 12, 24, 3
    g = torch.Generator().manual_seed(0)
    imgs = torch.rand(B, 1, H, H, generator=g)
    ids = torch.tensor([0, 1, 2, 0, 1, 2, 3, 3, 0, 1, 2, 5])
    conds = torch.rand(B, P, generator=g)
    idm, pm = _conditions(ids, conds, H)
    ra, rb = np.random.default_rng(4), np.random.default_rng(4)
    want = _cutmix_in_place(imgs, idm, pm, ra, p=0.7)
    got = mix_by_sources(imgs, ids, conds, cutmix_sources(ids, H, H, rb, p=0.7))
    again = cutmix(imgs, idm, pm, np.random.default_rng(4), p=0.7)
    for w, x, y in zip(want, got, again):
        assert torch.equal(w, x) and torch.equal(w, y)
    assert not torch.equal(want[0], imgs)  # something was mixed
    assert ra.random() == rb.random()


def test_training_overfits_a_fixed_batch():
    torch.manual_seed(0)
    m = UNet(3, 2, emb_dim=4, widths=(8, 16, 16))
    d = Diffusion()
    x0 = zoo.generate("spots", zoo.default_params("spots"), torch.arange(4), 16).unsqueeze(1) * 2 - 1
    opt = torch.optim.AdamW(m.parameters(), lr=3e-3)
    losses = []
    for _ in range(60):
        _, mse = d.loss(m, x0, m.embed(torch.zeros(4, 16, 16, dtype=torch.long), torch.zeros(4, 2, 16, 16)),
                        torch.Generator().manual_seed(7))
        opt.zero_grad()
        mse.backward()
        opt.step()
        losses.append(float(mse.detach()))
    assert losses[-1] < 0.5 * losses[0], (losses[0], losses[-1])


def _stopped_and_resumed_equals_uninterrupted(cfg, tmp_path):
    """Train 2 of cfg's 4 steps into a/, resume to 4; train 4 at once into b/; the weights agree."""
    train(cfg, str(tmp_path / "a"), max_steps=2, log=lambda s: None)
    train(cfg, str(tmp_path / "a"), log=lambda s: None)
    train(cfg, str(tmp_path / "b"), log=lambda s: None)
    a = torch.load(tmp_path / "a" / "ckpt.pt", weights_only=False)
    b = torch.load(tmp_path / "b" / "ckpt.pt", weights_only=False)
    assert a["step"] == b["step"] == 4
    for k in a["model"]:
        assert torch.allclose(a["model"][k], b["model"][k], atol=1e-6), k


def test_training_runs_logs_and_resumes_identically(tmp_path):
    cfg = TrainConfig.from_dict(dict(TINY, steps=4))
    _stopped_and_resumed_equals_uninterrupted(cfg, tmp_path)
    log = [json.loads(line) for line in (tmp_path / "b" / "log.jsonl").read_text().splitlines()]
    assert [r["step"] for r in log] == [1, 2, 3, 4] and all(np.isfinite(r["mse"]) for r in log)


def test_wall_time_budget_stops_with_a_checkpoint_and_resumes(tmp_path):
    """--max-seconds (a GPU machine's time limit): the run stops after its first step past the budget, checkpointed and
    logged, and resumes from there."""
    from omninoise.training.train import main

    cfg = TrainConfig.from_dict(dict(TINY, steps=50))
    last = train(cfg, str(tmp_path / "a"), log=lambda s: None, max_seconds=1e-9)
    state = torch.load(tmp_path / "a" / "ckpt.pt", weights_only=False)
    assert last["step"] == state["step"] == 1
    train(cfg, str(tmp_path / "a"), max_steps=2, log=lambda s: None)
    assert torch.load(tmp_path / "a" / "ckpt.pt", weights_only=False)["step"] == 3
    assert main(["--config", "x.json", "--out", str(tmp_path / "c"), "--max-seconds", "0"]) == 2


def _nan_batches(monkeypatch, bad_calls):
    """Make the zoo sampler's calls number ``bad_calls`` (0-based) return a NaN image first in the batch."""
    real = zoo.ZooSampler.batch
    calls = []

    def batch(self, b):
        imgs, ids, conds = real(self, b)
        if len(calls) in bad_calls:
            imgs[0] = float("nan")  # the whole image: CutMix may paste over part of it
        calls.append(1)
        return imgs, ids, conds

    monkeypatch.setattr(zoo.ZooSampler, "batch", batch)


def test_a_non_finite_batch_is_skipped_not_learned(monkeypatch, tmp_path):
    """One NaN pixel would turn every weight NaN through the clipped update: the update is skipped, counted in the
    log, and the weights stay finite."""
    _nan_batches(monkeypatch, {1})
    msgs = []
    cfg = TrainConfig.from_dict(dict(TINY, steps=3))
    last = train(cfg, str(tmp_path / "a"), log=msgs.append)
    state = torch.load(tmp_path / "a" / "ckpt.pt", weights_only=False)
    assert state["step"] == 3 and last["skipped"] == 1
    assert all(torch.isfinite(v).all() for k in ("model", "ema") for v in state[k].values() if v.is_floating_point())
    assert any("non-finite" in m and "update skipped" in m for m in msgs)


def test_a_run_that_keeps_diverging_stops_and_keeps_its_last_checkpoint(monkeypatch, tmp_path):
    from omninoise.training import train as train_mod

    cfg = TrainConfig.from_dict(dict(TINY, steps=10))
    train(cfg, str(tmp_path / "a"), max_steps=2, log=lambda s: None)
    before = torch.load(tmp_path / "a" / "ckpt.pt", weights_only=False)
    _nan_batches(monkeypatch, set(range(1000)))
    with pytest.raises(RuntimeError, match="diverged: 20 steps in a row"):
        train(cfg, str(tmp_path / "a"), log=lambda s: None)
    after = torch.load(tmp_path / "a" / "ckpt.pt", weights_only=False)
    assert after["step"] == before["step"] == 2 and train_mod.MAX_SKIPPED_IN_A_ROW == 20
    for k in before["model"]:
        assert torch.equal(before["model"][k], after["model"][k]), k


def test_worker_batches_depend_on_the_seed_and_step_alone_and_resume_identically(tmp_path):
    """workers > 0 (a GPU that outruns one core's zoo): batch k comes from default_rng([seed, k]) in a worker
    process, so one worker or two give the same batches in the same order, and a stopped run resumes exactly."""
    from omninoise.training.batches import batch_at, worker_batches, worker_loader

    cfg = TrainConfig.from_dict(dict(TINY, steps=4, workers=2))
    one = TrainConfig.from_dict(dict(TINY, steps=4, workers=1))
    a, b = list(worker_batches(cfg, 1, 4)), list(worker_batches(one, 1, 4))
    for k, (x, y) in enumerate(zip(a, b)):
        for u, v, w in zip(x, y, batch_at(cfg, k + 1)):
            assert torch.equal(u, v) and torch.equal(u, w)
    assert not torch.equal(a[0][0], a[1][0])
    # spawned, not forked (forked workers deadlocked on an H200 machine), and a stuck worker ends the run with an error
    loader = worker_loader(cfg, 0, 1)
    assert loader.multiprocessing_context.get_start_method() == "spawn" and 0 < loader.timeout <= 600
    _stopped_and_resumed_equals_uninterrupted(cfg, tmp_path)
    with pytest.raises(ValueError, match="workers must be an integer >= 0"):
        TrainConfig.from_dict(dict(TINY, workers=-1))


def test_a_stuck_data_worker_ends_the_run_with_a_one_line_error(monkeypatch, tmp_path):
    """The loader's timeout turns a worker that makes nothing (a GPU machine's time limit running out on a hang) into an
    error naming the workers and the way out, with nothing written as if it had trained."""
    from omninoise.training import batches as B
    from omninoise.training import train as T

    def stuck(cfg, start, end, pin=False):  # what DataLoader raises when no batch comes within its timeout
        raise RuntimeError(f"DataLoader timed out after {B.BATCH_TIMEOUT_S} seconds")

    monkeypatch.setattr(B, "worker_loader", stuck)
    cfg = TrainConfig.from_dict(dict(TINY, steps=2, workers=2))
    with pytest.raises(RuntimeError,
                       match=r"data workers made no batch in \d+ s at step 1 \(workers=2\); set workers to 0"):
        T.train(cfg, str(tmp_path / "r"), log=lambda s: None)
    assert not (tmp_path / "r" / "ckpt.pt").exists()


def test_mirrors_contradict_oriented_conditioning_so_training_does_not_mirror(monkeypatch, tmp_path):
    """A left-right mirror turns a gabor of orientation θ into one of π - θ while its conditioning still says θ
    (and damascus's fixed bands into their reflection): the model then learns 'θ or its mirror' and draws both in
    patches.  So training does not mirror unless a config asks for it (the stages that did say so)."""
    from omninoise.training import train as T
    from omninoise.training.evaluate import gradient_direction

    p = dict(zoo.default_params("gabor"), orientation=math.radians(30), bandwidth=0.02)
    img = zoo.generate("gabor", p, torch.arange(1), 128)
    assert abs(gradient_direction(img.numpy())[0] - 30) < 8
    mirrored, _, _ = T.random_mirror(img[:, None], torch.zeros(1, 128, 128), torch.zeros(1, 2, 128, 128),
                                     type("R", (), {"random": staticmethod(iter([0.0, 0.9]).__next__)})())
    assert abs(gradient_direction(mirrored[:, 0].numpy())[0] - 150) < 8  # the conditioning would still say 30°

    assert TrainConfig().flips is False
    calls = []
    monkeypatch.setattr(T, "random_mirror", lambda *a: calls.append(1) or a[:3])
    train(TrainConfig.from_dict(dict(TINY, steps=2)), str(tmp_path / "a"), log=lambda s: None)
    assert calls == []
    train(TrainConfig.from_dict(dict(TINY, steps=2, flips=True)), str(tmp_path / "b"), log=lambda s: None)
    assert len(calls) == 2


def test_config_errors():
    with pytest.raises(ValueError, match="unknown config key 'lr_rate'"):
        TrainConfig.from_dict({"lr_rate": 1})
    with pytest.raises(ValueError, match="unknown class 'lava'"):
        TrainConfig.from_dict({"classes": ["lava"]})
    with pytest.raises(ValueError, match="multiple of 8"):
        TrainConfig.from_dict({"size": 30})


def test_checkpoints_of_a_smaller_zoo_still_load():
    """The zoo is append-only: a model made before classes were added uses the first ids and slots."""
    from omninoise.training.train import build_model, model_names

    cfg = TrainConfig.from_dict(dict(TINY))
    old = UNet(len(zoo.CLASS_NAMES) - 1, len(zoo.PARAM_NAMES) - 3, emb_dim=8, widths=(8, 16, 16))
    again = build_model(cfg, old.state_dict())
    again.load_state_dict(old.state_dict())
    classes, params = model_names(again)
    assert classes == list(zoo.CLASS_NAMES[:-1]) and params == list(zoo.PARAM_NAMES[:-3])


def test_cpu_threads_limits_torch_and_numba_and_restores_them():
    """One training thread must also mean one numba worker (the zoo's wave classes run numba kernels)."""
    numba = pytest.importorskip("numba")
    from omninoise.training.threads import cpu_threads

    before = torch.get_num_threads(), numba.get_num_threads()
    with cpu_threads(1):
        assert torch.get_num_threads() == 1 and numba.get_num_threads() == 1
    assert (torch.get_num_threads(), numba.get_num_threads()) == before
    with cpu_threads(0):
        assert (torch.get_num_threads(), numba.get_num_threads()) == before


def test_every_shipped_config_parses_and_the_gpu_config_trains_a_step(tmp_path):
    """configs/: each file loads; the production (GPU) config runs one step at its resolution on the CPU."""
    import glob

    from omninoise.training.solid.train import load_config as load_solid
    from omninoise.training.train import load_config

    root = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))), "configs")
    neural = sorted(glob.glob(os.path.join(root, "*.json")))
    solid = sorted(glob.glob(os.path.join(root, "solid", "*.json")))
    assert len(neural) >= 4 and len(solid) >= 14
    for path in neural:
        load_config(path)
    for path in solid:
        load_solid(path)
    with open(os.path.join(root, "neural_noise_gpu.json"), encoding="utf-8") as fh:
        gpu = json.load(fh)
    assert gpu["size"] >= 128 and "classes" not in gpu  # the full zoo
    cfg = TrainConfig.from_dict(dict(gpu, batch=2, steps=1, device="cpu", sample_every=0))
    last = train(cfg, str(tmp_path / "gpu"), log=lambda s: None)
    assert last["step"] == 1 and np.isfinite(last["mse"])


def test_precision_is_bf16_only_where_the_cpu_computes_it():
    from omninoise.training.precision import autocast, cpu_bf16_native, resolve

    assert cpu_bf16_native("processor : 0\nflags : fpu avx2 avx512f amx_bf16 amx_tile\n")
    assert cpu_bf16_native("flags : fpu avx2 avx512_bf16\n")
    assert not cpu_bf16_native("flags : fpu avx2 fma\n") and not cpu_bf16_native("no flags here")
    cpu = torch.device("cpu")
    assert resolve("fp32", cpu) == "fp32" and resolve("bf16", cpu) == "bf16"
    assert resolve("auto", cpu) == ("bf16" if cpu_bf16_native() else "fp32")
    with pytest.raises(ValueError, match="precision must be one of"):
        resolve("fp16", cpu)
    with pytest.raises(ValueError, match="precision must be one of"):
        TrainConfig.from_dict(dict(precision="int8"))
    with autocast("bf16", cpu):
        assert (torch.ones(2, 2) @ torch.ones(2, 2)).dtype == torch.bfloat16
    with autocast("fp32", cpu):
        assert (torch.ones(2, 2) @ torch.ones(2, 2)).dtype == torch.float32


def test_bf16_training_steps_follow_the_fp32_loss(tmp_path):
    """A short bf16 + channels_last run tracks the fp32 run's loss (same data, same seed)."""
    base = dict(size=16, batch=4, steps=6, widths=(8, 16, 16), emb_dim=8, log_every=6, checkpoint_every=100,
                sample_every=0, classes=("perlin", "spots"), lr=1e-3)
    logs = {}
    for prec, cl in (("fp32", False), ("bf16", True)):
        rec = []
        train(TrainConfig.from_dict(dict(base, precision=prec, channels_last=cl)), str(tmp_path / prec),
              log=lambda s, rec=rec: rec.append(s))
        logs[prec] = json.loads(rec[-1])
        assert logs[prec]["precision"] == prec
    assert abs(logs["bf16"]["mse"] - logs["fp32"]["mse"]) < 0.1 * logs["fp32"]["mse"]
