"""The sampler contract (torch-free): schedules and timestep grids, and every sampler against an analytic model.

For data x₀ ~ N(0, s²) per pixel the exact ε-model is ε(x, t) = σ_t x / (α_t² s² + σ_t²), and the
probability-flow ODE keeps x_t / √(α_t² s² + σ_t²) constant, so the exact data prediction at t = 0 is

    x̂₀ = x_T · α₀ s² / (√(α₀² s² + σ₀²) √(α_T² s² + σ_T²)).

Golden values pin each sampler's output for one fixed input (as diffusers tests its schedulers); they were
computed by this implementation after the convergence tests below established that it solves the ODE.
"""
import numpy as np
import pytest

from omninoise.backend.errors import SettingError
from omninoise.backend.neural.generate import check_sampler
from omninoise.backend.neural.sampler import (DEFAULT_SAMPLER, DEFAULT_STEPS, SAMPLERS, ddim_sample, evaluations,
                                    initial_noise, sample, step_noise_rng)
from omninoise.backend.neural.schedule import (TRUNCATED_LAMBDA, alphas_from_config, cosine_alphas_cumprod, ddim_timesteps,
                                     timesteps)

AB = cosine_alphas_cumprod(1000)
S_DATA = 0.5


def gaussian_eps(x, t, cond):
    a = AB[int(t[0])]
    return (np.sqrt(1 - a) * x / (a * S_DATA ** 2 + 1 - a)).astype(np.float32)


def exact_x0(xT):
    a0, aT = AB[0], AB[-1]
    return xT * np.sqrt(a0) * S_DATA ** 2 / (np.sqrt(a0 * S_DATA ** 2 + 1 - a0) * np.sqrt(aT * S_DATA ** 2 + 1 - aT))


XT = initial_noise(0, (1, 1, 4, 4))
GOLDEN_TRUNCATED = [-0.19401, -0.47059, -0.29755, -0.29755, 0.35382, 0.64798]
GOLDEN_SDE = [0.19192, -0.31235, -0.12665, -0.24243, 0.55771, 0.581]


def err(name, steps, **kw):
    return float(np.abs(sample(name, gaussian_eps, XT, None, steps, clip=False, **kw) - exact_x0(XT)).max())


def test_every_sampler_converges_to_the_exact_ode_solution():
    for name in SAMPLERS:
        e = [err(name, n) for n in (10, 20, 40, 80)]
        assert e[0] > e[1] > e[2] > e[3], (name, e)
        assert e[3] < 0.025, (name, e)


def test_order_of_accuracy():
    """DDIM is first order (error halves as steps double); DPM-Solver++(2M) and Heun are second order."""
    d = [err("ddim", n) for n in (20, 40, 80)]
    assert 1.8 < d[0] / d[1] < 2.2 and 1.8 < d[1] / d[2] < 2.2
    h = [err("heun", n) for n in (10, 20, 40)]
    assert h[0] / h[1] > 3.0 and h[1] / h[2] > 3.0
    # at equal model evaluations the second-order solvers beat DDIM by far
    assert err("dpmpp_2m", 15) < err("ddim", 15) / 5
    assert err("heun", 8) < err("ddim", evaluations("heun", 8)) / 2


def test_golden_values():
    x = initial_noise(7, (1, 1, 2, 3))
    cases = {
        ("ddim", 10): [-0.16374, -0.39715, -0.25111, -0.25111, 0.2986, 0.54685],
        ("dpmpp_2m", 10): [-0.18253, -0.44273, -0.27993, -0.27993, 0.33287, 0.60961],
        ("heun", 6): [-0.20918, -0.50737, -0.3208, -0.32081, 0.38148, 0.69862],
        ("dpmpp_2m", 10, "truncated"): GOLDEN_TRUNCATED,
    }
    for (name, steps, *spacing), want in cases.items():
        got = sample(name, gaussian_eps, x, None, steps, clip=False, **dict(zip(["spacing"], spacing))).ravel()
        np.testing.assert_allclose(got, want, atol=2e-5, err_msg=name)
    exact = exact_x0(x).ravel()  # -0.2172 ... 0.7255: the second-order solvers are the nearer
    assert np.abs(cases[("ddim", 10)] - exact).max() > 2 * np.abs(cases[("dpmpp_2m", 10)] - exact).max()


def test_ddim_eta_zero_is_deterministic_and_eta_one_adds_seeded_noise():
    a = ddim_sample(gaussian_eps, XT, None, 10, clip=False)
    np.testing.assert_array_equal(a, ddim_sample(gaussian_eps, XT, None, 10, clip=False, eta=0.0))
    b = ddim_sample(gaussian_eps, XT, None, 10, clip=False, eta=1.0, rng=step_noise_rng(3))
    c = ddim_sample(gaussian_eps, XT, None, 10, clip=False, eta=1.0, rng=step_noise_rng(3))
    np.testing.assert_array_equal(b, c)
    assert np.abs(a - b).max() > 1e-3
    with pytest.raises(ValueError, match="needs an rng"):
        ddim_sample(gaussian_eps, XT, None, 10, eta=0.5)
    # η = 1 over every timestep is DDPM's ancestral sampler: it reproduces the data's spread s (up to the
    # shrinkage of the final prediction, α₀ s² / √(α₀² s² + σ₀²) = 0.49996); with 50 steps it is 7% low
    many = initial_noise(11, (1, 1, 128, 128))
    out = ddim_sample(gaussian_eps, many, None, 1000, clip=False, eta=1.0, rng=step_noise_rng(1))
    assert abs(out.std() - S_DATA) < 0.008


def test_callback_counts_model_evaluations_and_may_cancel():
    for name in SAMPLERS:
        seen, calls = [], []

        def model(x, t, c):
            calls.append(int(t[0]))
            return gaussian_eps(x, t, c)

        sample(name, model, XT, None, 7, callback=lambda i, n, x0: seen.append((i, n)))
        n = evaluations(name, 7)
        assert len(calls) == n and seen == [(i, n) for i in range(n)], name
        assert calls[0] == 999 and calls[-1] == 0

    def stop(i, n, x0):
        if i == 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        sample(DEFAULT_SAMPLER, gaussian_eps, XT, None, 10, callback=stop)


def test_timestep_grids():
    np.testing.assert_array_equal(timesteps(10, AB, "uniform"), ddim_timesteps(10))
    for spacing in ("uniform", "logsnr", "karras"):
        ts = timesteps(12, AB, spacing)
        assert ts[0] == 999 and ts[-1] == 0 and np.all(np.diff(ts) < 0) and len(ts) <= 12
    lam = 0.5 * np.log(AB / (1 - AB))
    dl = np.diff(lam[timesteps(20, AB, "logsnr")])
    # even steps in λ away from t = T - 1, where whole timesteps are λ-steps of ~0.7 and the first targets round apart
    assert np.abs(dl[4:] / dl[4:].mean() - 1).max() < 0.1
    with pytest.raises(ValueError, match="unknown spacing"):
        timesteps(5, AB, "geometric")
    with pytest.raises(ValueError, match="steps must lie"):
        timesteps(0, AB, "logsnr")


def test_truncated_grid_spends_every_evaluation_between_its_lambda_bounds():
    """T-1, then steps - 1 distinct timesteps even in λ from -3.5 to 3.5; the λ grids from T-1 merge targets."""
    lam = 0.5 * np.log(AB / (1 - AB))
    for n in (2, 5, 10, 30):
        ts = timesteps(n, AB, "truncated")
        assert len(ts) == n and ts[0] == 999 and np.all(np.diff(ts) < 0), n
        assert abs(lam[ts[1]] - TRUNCATED_LAMBDA[0]) < 0.05
        if n > 2:
            assert abs(lam[ts[-1]] - TRUNCATED_LAMBDA[1]) < 0.05
            dl = np.diff(lam[ts[1:]])
            assert np.abs(dl / dl.mean() - 1).max() < 0.15, n  # timesteps are whole: λ rounds
    assert len(timesteps(15, AB, "logsnr")) == 13  # what the truncated grid avoids
    assert evaluations("dpmpp_2m", 15, "logsnr") == 13 and evaluations("dpmpp_2m", 10, "truncated") == 10
    assert evaluations("heun", 10, "truncated") == 18
    # on Gaussian data it converges to the exact solution up to its ends' bias (the data prediction at
    # λ = 3.5 instead of t = 0, and one step across λ < -3.5), and at 10 evaluations it is nearer than DDIM 30
    e = [err("dpmpp_2m", n, spacing="truncated") for n in (5, 10, 40)]
    assert e[0] > e[1] > e[2] and e[2] < 2e-3, e
    assert e[1] < err("ddim", 30), e


def test_schedule_is_read_from_the_model_json():
    np.testing.assert_array_equal(alphas_from_config(dict(kind="cosine", T=1000, s=0.008)), AB)
    assert len(alphas_from_config(dict(kind="cosine", T=250))) == 250
    with pytest.raises(ValueError, match="unsupported noise schedule 'linear'"):
        alphas_from_config(dict(kind="linear"))


def test_sampler_settings_are_checked_in_one_place():
    check_sampler(DEFAULT_SAMPLER, DEFAULT_STEPS)
    for args, msg in [(("euler_a", 10), "unknown sampler 'euler_a'"), (("ddim", 0), "steps"),
                      (("ddim", 2.5), "steps"), (("heun", 1), "at least 2"), (("ddim", 10, "zigzag"), "spacing"),
                      (("ddim", 10, "uniform", float("nan")), "eta"), (("heun", 10, "uniform", 0.5), "DPM-Solver")]:
        with pytest.raises(SettingError, match=msg):
            check_sampler(*args)
    with pytest.raises(ValueError, match="unknown sampler"):
        sample("euler_a", gaussian_eps, XT, None, 4)


def test_dpmpp_2m_sde_eta_zero_is_the_ode_solver_and_eta_one_samples_the_data_distribution():
    from omninoise.backend.neural.sampler import dpmpp_2m_sample

    ode = dpmpp_2m_sample(gaussian_eps, XT, None, 10, clip=False, spacing="truncated")
    np.testing.assert_array_equal(ode, dpmpp_2m_sample(gaussian_eps, XT, None, 10, clip=False, spacing="truncated",
                                                       eta=0.0, rng=step_noise_rng(1)))
    a = dpmpp_2m_sample(gaussian_eps, XT, None, 10, clip=False, spacing="truncated", eta=1.0, rng=step_noise_rng(3))
    b = dpmpp_2m_sample(gaussian_eps, XT, None, 10, clip=False, spacing="truncated", eta=1.0, rng=step_noise_rng(3))
    np.testing.assert_array_equal(a, b)
    assert np.abs(a - ode).max() > 1e-3
    with pytest.raises(ValueError, match="needs an rng"):
        dpmpp_2m_sample(gaussian_eps, XT, None, 10, eta=0.5)
    # golden values (one fixed input and step noise), computed after the distribution check below passed
    x = initial_noise(7, (1, 1, 2, 3))
    got = sample("dpmpp_2m", gaussian_eps, x, None, 10, clip=False, spacing="truncated", eta=1.0,
                 rng=step_noise_rng(5)).ravel()
    np.testing.assert_allclose(got, GOLDEN_SDE, atol=2e-5)
    # the SDE forgets x_T and draws from the data: N(0, s²) per pixel, shrunk by the last prediction
    # (α₀ s² / √(α₀² s² + σ₀²) at the grid's last λ); x_T's correlation with the output falls far below the ODE's 1
    many = initial_noise(11, (1, 1, 128, 128))
    for steps in (10, 50):
        out = dpmpp_2m_sample(gaussian_eps, many, None, steps, clip=False, spacing="truncated", eta=1.0,
                              rng=step_noise_rng(2))
        assert abs(out.std() - S_DATA) < 0.02, (steps, out.std())
        assert abs(np.corrcoef(out.ravel(), many.ravel())[0, 1]) < 0.5
    assert check_sampler("dpmpp_2m", 10, eta=1.0) is None
    with pytest.raises(SettingError, match="eta"):
        check_sampler("heun", 10, eta=0.5)


def test_requests_name_the_step_noise_they_are_made_with():
    from omninoise.backend.neural.request import NeuralRequest
    from omninoise.backend.neural.sampler import DEFAULT_ETA

    assert DEFAULT_ETA == {"ddim": 0.0, "dpmpp_2m": 0.3, "heun": 0.0} and set(DEFAULT_ETA) == set(SAMPLERS)
    r = NeuralRequest("uniform", [("perlin", {})], 16, 16)
    assert r.eta is None and r.key()["eta"] == 0.3
    assert NeuralRequest("uniform", [("perlin", {})], 16, 16, sampler="ddim").key()["eta"] == 0.0
    assert NeuralRequest("uniform", [("perlin", {})], 16, 16, eta=0.0).key()["eta"] == 0.0
