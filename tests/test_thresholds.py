"""Tests of :mod:`sensorless.thresholds`.

The fits are checked on synthetic residuals built from planted values
(γ, ε_fr, C of Tables 5.3 and 5.7, per-bin friction offsets τ̂_fme): the
filtered signals are made here with a plain Python loop of the observer's
zero-order-hold recursion, independent of :func:`scipy.signal.lfilter`. The
streaming form is checked against the batch form, files against a round trip.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

from sensorless.exceptions import (
    DimensionError,
    FileFormatError,
    InputValueError,
    ModelMismatchError,
    NotFittedError,
)
from sensorless.signals import ObserverSignals
from sensorless.thresholds import (
    METHODS,
    ConstantThreshold,
    Threshold,
    ThresholdState,
    TimeVariantThreshold,
    VelocityThreshold,
    first_order,
    first_order_step,
    load_threshold,
)
from sensorless.thresholds.files import family_name

DT = 1e-3
GAIN = np.array([20.0, 25.0, 30.0])
N_DOF = 3
N = 3000
# Table 5.3 (simulated PUMA 560) and Table 5.7 (KUKA LWR), joints 1-3.
GAMMA_53 = np.array([-0.0456, -0.036, -0.078])
EPS_FR_53 = np.array([-1.74, 1.98, 0.29])
GAMMA_57 = np.array([0.0020, 5.0523e-4, 0.0521])
C_57 = np.array([0.2678, 0.5654, 0.4367])


def lowpass(x: np.ndarray, gain: np.ndarray, dt: float = DT) -> np.ndarray:
    """K/(s+K) with zero-order hold, written as the recursion (y[0] = x[0])."""
    a = np.exp(-gain * dt)
    y = np.empty_like(x)
    y[0] = x[0]
    for k in range(x.shape[0] - 1):
        y[k + 1] = a * y[k] + (1.0 - a) * x[k]
    return y


def smooth(rng: np.random.Generator, t: np.ndarray, scale: float) -> np.ndarray:
    """Sum of four random sinusoids per joint, shape (n_samples, N_DOF)."""
    freq = rng.uniform(0.2, 2.0, size=(4, N_DOF))
    phase = rng.uniform(0, 2 * np.pi, size=(4, N_DOF))
    amp = rng.uniform(0.3, 1.0, size=(4, N_DOF)) * scale
    return np.sum(amp * np.sin(2 * np.pi * freq * t[:, None, None] + phase), axis=1)


def parts(seed: int, n: int = N) -> dict[str, np.ndarray]:
    """t, h, filtered friction, filtered sign and velocity of a random smooth run."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * DT
    velocity = smooth(rng, t, 0.5)
    return {
        "t": t,
        "model_torque": smooth(rng, t, 20.0),
        "friction": lowpass(0.8 * np.sign(velocity) + 0.5 * velocity, GAIN),
        "sign": lowpass(np.sign(velocity), GAIN),
        "velocity": velocity,
    }


def signals(residual: np.ndarray, p: dict[str, np.ndarray], **kwargs: object) -> ObserverSignals:
    options: dict = {"gain": GAIN, "robot": "synthetic", "kind": "motor"} | kwargs
    return ObserverSignals(residual=residual, **p, **options)


def noise(seed: int, n: int = N, amplitude: float = 0.05) -> np.ndarray:
    return np.random.default_rng(seed).uniform(-amplitude, amplitude, size=(n, N_DOF))


def velocity_bins(velocity: np.ndarray, width: float) -> np.ndarray:
    """Bin k covers [k w, (k + 1) w)."""
    return np.floor(velocity / width).astype(int)


def planted_tau(k: np.ndarray, width: float) -> np.ndarray:
    """Per-bin friction offset [N m]: Coulomb-like, viscous and a joint-dependent bias."""
    centre = (k + 0.5) * width
    return 0.3 * np.tanh(centre / 0.1) + 0.2 * centre + np.array([0.05, -0.1, 0.0])[: k.shape[1]]


def velocity_residual(p: dict[str, np.ndarray], gamma: np.ndarray, width: float) -> np.ndarray:
    tau = planted_tau(velocity_bins(p["velocity"], width), width)
    return gamma * p["model_torque"] + lowpass(tau, GAIN)


def fitted(method: str, seed: int = 1) -> tuple[Threshold, ObserverSignals]:
    p = parts(seed)
    r = GAMMA_53 * p["model_torque"] + EPS_FR_53 * p["friction"] + noise(seed + 100)
    run = signals(r, p)
    threshold = {
        "constant": ConstantThreshold(margin=0.01),
        "time_variant": TimeVariantThreshold(margin=0.01),
        "hysteretic": TimeVariantThreshold(form="hysteretic"),
        "velocity": VelocityThreshold(bin_width=0.06, margin=0.01),
    }[method]
    return threshold.fit(run), run


FAMILIES = ["constant", "time_variant", "hysteretic", "velocity"]


# --------------------------------------------------------------------------- filter


def test_first_order_matches_recursion_chunks_and_step() -> None:
    x = np.random.default_rng(0).normal(size=(200, N_DOF))
    expected = lowpass(x, GAIN)
    y, zf = first_order(x, GAIN, DT)
    np.testing.assert_allclose(y, expected, rtol=0, atol=1e-13)
    y1, z1 = first_order(x[:77], GAIN, DT)
    y2, z2 = first_order(x[77:], GAIN, DT, zi=z1)
    np.testing.assert_allclose(np.vstack([y1, y2]), y, rtol=0, atol=1e-15)
    np.testing.assert_allclose(z2, zf, rtol=0, atol=1e-15)
    z = x[0]
    for k in range(x.shape[0]):
        out, z = first_order_step(x[k], GAIN, DT, z)
        np.testing.assert_allclose(out, y[k], rtol=0, atol=1e-15)
    np.testing.assert_allclose(z, zf, rtol=0, atol=1e-15)


def test_first_order_step_response_and_errors() -> None:
    y, _ = first_order(np.ones(50), 10.0, 0.01, zi=0.0)
    np.testing.assert_allclose(y, 1.0 - np.exp(-10.0 * 0.01 * np.arange(50)), atol=1e-15)
    with pytest.raises(InputValueError, match="gain K_I must be positive"):
        first_order(np.ones(3), -1.0, 0.01)
    with pytest.raises(InputValueError, match="dt must be a positive"):
        first_order(np.ones(3), 1.0, 0.0)
    with pytest.raises(DimensionError, match="pass zi"):
        first_order(np.zeros((0, 2)), 1.0, 0.01)
    with pytest.raises(DimensionError, match="gain must be a scalar or broadcast"):
        first_order(np.ones((3, 2)), [1.0, 2.0, 3.0], 0.01)


# --------------------------------------------------------------------------- fits


def test_constant_is_max_abs_residual_over_runs() -> None:
    p1, p2 = parts(1), parts(2)
    r1, r2 = noise(3, amplitude=1.0), noise(4, amplitude=2.0)
    margin = np.array([0.0, 0.1, 0.2])
    th = ConstantThreshold(margin=margin).fit([signals(r1, p1), signals(r2, p2)])
    expected = np.maximum(np.abs(r1).max(axis=0), np.abs(r2).max(axis=0)) + margin
    np.testing.assert_array_equal(th.beta_, expected)
    lower, upper = th.bounds(signals(r1, p1))
    np.testing.assert_array_equal(upper, np.broadcast_to(expected, (N, N_DOF)))
    np.testing.assert_array_equal(lower, -upper)


def test_transient_is_skipped_in_fit() -> None:
    p = parts(1)
    r = noise(3)
    r[:100] = 50.0
    th = ConstantThreshold(transient=100 * DT - 1e-9).fit(signals(r, p))
    np.testing.assert_array_equal(th.beta_, np.abs(r[100:]).max(axis=0))


def test_time_variant_recovers_planted_gamma_and_eps_fr() -> None:
    p = parts(5)
    exact = GAMMA_53 * p["model_torque"] + EPS_FR_53 * p["friction"]
    th = TimeVariantThreshold().fit(signals(exact, p))
    np.testing.assert_allclose(th.gamma_, GAMMA_53, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(th.eps_fr_, EPS_FR_53, rtol=1e-9, atol=1e-12)
    assert np.all(th.alpha_ < 1e-9)

    e = noise(6)
    th = TimeVariantThreshold().fit(signals(exact + e, p))
    np.testing.assert_allclose(th.gamma_, GAMMA_53, atol=2e-4)
    np.testing.assert_allclose(th.eps_fr_, EPS_FR_53, atol=2e-2)
    # α is the largest |r - γh - ε f| of the fitted γ, ε: within a few % of max|noise|
    remaining = exact + e - th.gamma_ * p["model_torque"] - th.eps_fr_ * p["friction"]
    np.testing.assert_allclose(th.alpha_, np.abs(remaining).max(axis=0), rtol=1e-9)
    np.testing.assert_allclose(th.alpha_, np.abs(e).max(axis=0), rtol=0.05)


def test_time_variant_ls_agrees_with_normal_equations() -> None:
    p = parts(7)
    r = GAMMA_53 * p["model_torque"] + EPS_FR_53 * p["friction"] + noise(8, amplitude=0.5)
    th = TimeVariantThreshold().fit(signals(r, p))
    for j in range(N_DOF):
        a = np.column_stack([p["model_torque"][:, j], p["friction"][:, j]])
        coef = np.linalg.solve(a.T @ a, a.T @ r[:, j])
        np.testing.assert_allclose([th.gamma_[j], th.eps_fr_[j]], coef, rtol=1e-8)


def test_hysteretic_form_recovers_c() -> None:
    p = parts(9)
    exact = GAMMA_57 * p["model_torque"] - C_57 * p["sign"]
    th = TimeVariantThreshold(form="hysteretic").fit(signals(exact, p))
    np.testing.assert_allclose(th.gamma_, GAMMA_57, rtol=1e-8, atol=1e-12)
    np.testing.assert_allclose(th.c_, C_57, rtol=1e-9)
    assert not hasattr(th, "eps_fr_")
    assert "c_" in th.to_dict()["attributes"]
    lower, upper = th.bounds(signals(exact, p))
    centre = GAMMA_57 * p["model_torque"] - C_57 * p["sign"]
    np.testing.assert_allclose((lower + upper) / 2, centre, atol=1e-9)


def test_efficiency_and_beta_match_constant_threshold() -> None:
    p = parts(10)
    r = GAMMA_53 * p["model_torque"] + EPS_FR_53 * p["friction"] + noise(11)
    run = signals(r, p)
    th = TimeVariantThreshold(margin=0.02).fit(run)
    np.testing.assert_array_equal(th.beta_, ConstantThreshold(margin=0.02).fit(run).beta_)
    np.testing.assert_allclose(th.efficiency_, th.alpha_ / th.beta_)
    assert np.all(th.efficiency_ < 0.2)  # the model part dominates this residual


@pytest.mark.parametrize("width", [0.06, 0.1])
def test_velocity_recovers_planted_offsets_and_gamma(width: float) -> None:
    p = parts(12)
    gamma = np.array([0.01, -0.02, 0.03])
    r = velocity_residual(p, gamma, width)
    th = VelocityThreshold(bin_width=width).fit(signals(r, p))
    np.testing.assert_allclose(th.gamma_, gamma, rtol=1e-7, atol=1e-10)
    centres = (th.bin_edges_[:-1] + th.bin_edges_[1:]) / 2
    k = np.floor(centres / width).astype(int)
    expected = planted_tau(np.repeat(k[:, None], N_DOF, axis=1), width)
    visited = th.counts_ > 0
    assert visited.sum() > 20
    np.testing.assert_allclose(th.tau_fme_[visited], expected[visited], atol=1e-6)
    np.testing.assert_allclose(th.lower_[visited], 0.0, atol=1e-7)
    np.testing.assert_allclose(th.upper_[visited], 0.0, atol=1e-7)
    np.testing.assert_array_equal(th.counts_.sum(axis=0), [N] * N_DOF)
    np.testing.assert_allclose(np.diff(th.bin_edges_), width, rtol=1e-9)


def test_velocity_bounds_bracket_noise_per_bin() -> None:
    p = parts(13)
    gamma = np.array([0.01, -0.02, 0.03])
    e = noise(14)
    th = VelocityThreshold(margin=0.0).fit(signals(velocity_residual(p, gamma, 0.06) + e, p))
    visited = th.counts_ > 0
    assert np.all(th.lower_[visited] <= 0.0) and np.all(th.upper_[visited] >= 0.0)
    assert np.all(th.lower_ >= -0.06) and np.all(th.upper_ <= 0.06)


def test_velocity_extrapolation_uses_edge_bin_and_margin() -> None:
    p = parts(15)
    r = velocity_residual(p, np.zeros(N_DOF), 0.06) + noise(16)
    run = signals(r, p)
    plain = VelocityThreshold().fit(run)
    wide = VelocityThreshold(extrapolation_margin=0.5).fit(run)
    fast = dict(p, velocity=p["velocity"] + 100.0)
    lo_plain, up_plain = plain.bounds(signals(r, fast))
    lo_wide, up_wide = wide.bounds(signals(r, fast))
    np.testing.assert_allclose(up_wide - up_plain, 0.5, atol=1e-12)
    np.testing.assert_allclose(lo_plain - lo_wide, 0.5, atol=1e-12)
    last = plain.counts_.shape[0] - 1 - np.argmax(plain.counts_[::-1] > 0, axis=0)
    edge_width = plain.upper_[last, range(N_DOF)] - plain.lower_[last, range(N_DOF)]
    np.testing.assert_allclose(up_plain - lo_plain, np.broadcast_to(edge_width, (N, N_DOF)))
    # inside the fitted range the extrapolation margin does nothing
    np.testing.assert_array_equal(wide.bounds(run)[1], plain.bounds(run)[1])


@pytest.mark.parametrize("method", FAMILIES)
def test_no_sample_outside_on_fit_data(method: str) -> None:
    th, run = fitted(method)
    lower, upper = th.bounds(run)
    assert np.all(lower <= run.residual) and np.all(run.residual <= upper)


@pytest.mark.parametrize("method", FAMILIES)
def test_unmonitored_joints_have_infinite_bounds(method: str) -> None:
    th, run = fitted(method)
    th.joints = [1, 3]
    lower, upper = th.bounds(run)
    assert np.all(lower[:, 1] == -np.inf) and np.all(upper[:, 1] == np.inf)
    assert np.all(np.isfinite(lower[:, [0, 2]]))
    assert th.monitored_joints_ == (1, 3)


# --------------------------------------------------------------------------- streaming


@pytest.mark.parametrize("method", FAMILIES)
def test_streaming_equals_batch(method: str) -> None:
    th, _ = fitted(method)
    p = parts(20, n=600)
    run = signals(noise(21, n=600), p)
    lower, upper = th.bounds(run)
    rows = [p[name] for name in ("model_torque", "friction", "sign", "velocity")]
    state = th.initial_state(*(x[0] for x in rows), dt=DT)
    for k in range(run.n_samples):
        lo, up, state = th.step(state, *(x[k] for x in rows))
        np.testing.assert_allclose(lo, lower[k], rtol=0, atol=1e-12)
        np.testing.assert_allclose(up, upper[k], rtol=0, atol=1e-12)
    state = th.initial_state(*(x[0] for x in rows), dt=DT)
    chunks = []
    for cut in np.array_split(np.arange(run.n_samples), [1, 5, 250, 251]):
        lo, up, state = th.process(state, *(x[cut] for x in rows))
        chunks.append((lo, up))
    np.testing.assert_allclose(np.vstack([c[0] for c in chunks]), lower, rtol=0, atol=1e-12)
    np.testing.assert_allclose(np.vstack([c[1] for c in chunks]), upper, rtol=0, atol=1e-12)
    assert isinstance(state, ThresholdState)


def test_velocity_stream_depends_on_filter_state() -> None:
    th, _ = fitted("velocity")
    p = parts(22, n=50)
    rows = [p[name][0] for name in ("model_torque", "friction", "sign", "velocity")]
    state = th.initial_state(*rows, dt=DT)
    assert state.zi.shape == (N_DOF,) and state.dt == DT
    jump = [*rows[:3], rows[3] + 0.5]
    _, _, moved = th.step(state, *jump)
    assert not np.allclose(moved.zi, state.zi)


# --------------------------------------------------------------------------- files


@pytest.mark.parametrize("method", FAMILIES)
def test_save_load_round_trip(method: str, tmp_path: Path) -> None:
    th, run = fitted(method)
    th.joints = [1, 2]
    path = th.save(tmp_path / f"{method}.yaml")
    text = path.read_text()
    data = yaml.safe_load(text)
    assert text.startswith("# sensorless fitted threshold")
    assert f"method: {family_name(th)}" in text
    for name in th.to_dict()["attributes"]:
        assert f"{name}:" in text
    assert data["robot"] == "synthetic" and data["n_dof"] == N_DOF and data["kind"] == "motor"
    assert data["gain"] == GAIN.tolist() and "library_version" in data
    loaded = load_threshold(path)
    assert type(loaded) is type(th) and loaded.get_params() == {
        k: (list(v) if isinstance(v, tuple | list) else v) for k, v in th.get_params().items()
    }
    for a, b in zip(loaded.bounds(run), th.bounds(run), strict=True):
        np.testing.assert_array_equal(a, b)
    same = type(th).from_dict(th.to_dict())
    np.testing.assert_array_equal(same.bounds(run)[0], th.bounds(run)[0])


def test_registry_and_repr() -> None:
    assert {"constant", "time-variant", "velocity"} <= set(METHODS)
    assert METHODS["velocity"] is VelocityThreshold
    assert repr(VelocityThreshold(bin_width=0.1)).startswith("VelocityThreshold(bin_width=0.1")


# --------------------------------------------------------------------------- errors


@pytest.mark.parametrize(
    "threshold", [ConstantThreshold(), TimeVariantThreshold(), VelocityThreshold()]
)
def test_unfitted_threshold_raises(threshold: Threshold, tmp_path: Path) -> None:
    run = signals(noise(1), parts(1))
    with pytest.raises(NotFittedError, match="call fit"):
        threshold.bounds(run)
    with pytest.raises(NotFittedError, match="not fitted yet"):
        threshold.initial_state(*np.zeros((4, N_DOF)))
    with pytest.raises(NotFittedError, match="call fit"):
        threshold.save(tmp_path / "x.yaml")


def test_signals_of_another_robot_kind_or_gain_are_rejected() -> None:
    th, run = fitted("constant")
    p = {k: (v if k == "t" else v[:, :2]) for k, v in parts(1).items()}
    other = ObserverSignals(residual=noise(1)[:, :2], **p, gain=GAIN[:2], robot="puma560")
    message = (
        r"thresholds fitted for synthetic \(3 joints\); signals come from puma560 \(2 joints\)"
    )
    with pytest.raises(DimensionError, match=message):
        th.bounds(other)
    renamed = signals(run.residual, parts(1), robot="panda")
    with pytest.raises(ModelMismatchError, match=r"signals come from panda \(3 joints\)"):
        th.bounds(renamed)
    with pytest.raises(
        InputValueError, match="fitted on 'motor' signals; these signals are 'joint'"
    ):
        th.bounds(signals(run.residual, parts(1), kind="joint"))
    with pytest.raises(InputValueError, match="observer gain K_I"):
        th.bounds(signals(run.residual, parts(1), gain=2 * GAIN))
    with pytest.raises(TypeError, match="ObserverSignals"):
        th.bounds(run.residual)  # type: ignore[arg-type]


def test_bad_hyper_parameters_are_rejected_at_fit() -> None:
    run = signals(noise(1), parts(1))
    with pytest.raises(InputValueError, match="margin must be finite and >= 0"):
        ConstantThreshold(margin=-0.1).fit(run)
    with pytest.raises(InputValueError, match="margin must be finite and >= 0"):
        TimeVariantThreshold(margin=[0.1, np.nan, 0.1]).fit(run)
    with pytest.raises(DimensionError, match=r"margin must be a scalar or have shape \(3,\)"):
        ConstantThreshold(margin=[0.1, 0.2]).fit(run)
    with pytest.raises(InputValueError, match="margin must be a number"):
        ConstantThreshold(margin="wide").fit(run)
    for width in (0.0, -0.06, np.inf, "fast"):
        with pytest.raises(InputValueError, match="bin_width must be a positive, finite number"):
            VelocityThreshold(bin_width=width).fit(run)  # type: ignore[arg-type]
    with pytest.raises(InputValueError, match="at most 10000 allowed"):
        VelocityThreshold(bin_width=1e-6).fit(run)
    with pytest.raises(InputValueError, match="extrapolation_margin must be"):
        VelocityThreshold(extrapolation_margin=-1.0).fit(run)
    with pytest.raises(InputValueError, match=r"form must be one of \['friction', 'hysteretic'\]"):
        TimeVariantThreshold(form="lugre").fit(run)
    with pytest.raises(InputValueError, match="transient must be a finite number of seconds"):
        ConstantThreshold(transient=-1.0).fit(run)
    with pytest.raises(InputValueError, match="no fit sample is left"):
        ConstantThreshold(transient=10.0).fit(run)
    for joints in ([0], [1, 1], [4], "all", []):
        with pytest.raises(InputValueError, match="joints must be distinct joint numbers"):
            ConstantThreshold(joints=joints).fit(run)


def test_bad_fit_data_is_rejected() -> None:
    p = parts(1)
    run = signals(noise(1), p)
    with pytest.raises(TypeError, match="sequence of ObserverSignals"):
        ConstantThreshold().fit(run.residual)  # type: ignore[arg-type]
    with pytest.raises(InputValueError, match="at least one collision-free run"):
        ConstantThreshold().fit([])
    with pytest.raises(InputValueError, match="one signal kind"):
        ConstantThreshold().fit([run, signals(noise(1), p, kind="joint")])
    with pytest.raises(ModelMismatchError, match="one robot"):
        ConstantThreshold().fit([run, signals(noise(1), p, robot="other")])
    with pytest.raises(InputValueError, match="one observer gain"):
        ConstantThreshold().fit([run, signals(noise(1), p, gain=1.0)])
    bad = noise(1)
    bad[10, 2] = np.nan
    with pytest.raises(InputValueError, match="residual of fit run 0 must be finite"):
        ConstantThreshold().fit(signals(bad, p))
    jittery = dict(p, t=p["t"] + np.where(np.arange(N) == 500, 3e-4, 0.0))
    with pytest.raises(InputValueError, match="not regularly sampled"):
        VelocityThreshold().fit(signals(noise(1), jittery))
    backwards = dict(p, t=p["t"][::-1].copy())
    with pytest.raises(InputValueError, match="strictly increasing"):
        ConstantThreshold().fit(signals(noise(1), backwards))


def test_bad_threshold_files_are_rejected(tmp_path: Path) -> None:
    # tests/test_file_schemas.py has the full table of bad files; these are the API's cases.
    th, _ = fitted("constant")
    data = th.to_dict()
    with pytest.raises(FileFormatError, match="unknown threshold method 'magic'; valid methods"):
        Threshold.from_dict(dict(data, method="magic"))
    path = tmp_path / "t.yaml"
    path.write_text(yaml.safe_dump(dict(data, method="magic")))
    with pytest.raises(FileFormatError, match=r"t\.yaml: method: unknown threshold method 'magic'"):
        load_threshold(path)
    with pytest.raises(FileFormatError, match="attributes: required key is missing"):
        Threshold.from_dict({k: v for k, v in data.items() if k != "attributes"})
    with pytest.raises(InputValueError, match="holds a 'constant' threshold, not 'velocity'"):
        VelocityThreshold.from_dict(data)
    with pytest.raises(FileFormatError, match=r"attributes.alpha_: unknown key.*beta_: required"):
        Threshold.from_dict(dict(data, attributes={"alpha_": [1.0, 2.0, 3.0]}))
    with pytest.raises(
        FileFormatError, match=r"beta_: expected shape \(n_dof,\) = \(3,\); got \(2,\)"
    ):
        Threshold.from_dict(dict(data, attributes={"beta_": [1.0, 2.0]}))
    with pytest.raises(FileFormatError, match=r"params\.speed: unknown key"):
        Threshold.from_dict(dict(data, params={"margin": 0.0, "speed": 1.0}))
    path.write_text("method: [unclosed")
    with pytest.raises(FileFormatError, match="is not valid YAML"):
        load_threshold(path)
    path.write_text("- just a list")
    with pytest.raises(FileFormatError, match="holds a YAML mapping"):
        load_threshold(path)


def test_stream_input_errors() -> None:
    th, _ = fitted("velocity")
    rows = list(np.zeros((4, N_DOF)))
    state = th.initial_state(*rows)
    assert state.dt == pytest.approx(DT)
    with pytest.raises(DimensionError, match="step takes one sample"):
        th.step(state, *np.zeros((4, 2, N_DOF)))
    with pytest.raises(DimensionError, match="initial_state takes one sample"):
        th.initial_state(*np.zeros((4, 2, N_DOF)))
    with pytest.raises(DimensionError, match=r"shape \(3,\) or \(n_samples, 3\)"):
        th.step(state, *np.zeros((4, 2)))
    with pytest.raises(TypeError, match="ThresholdState"):
        th.step("state", *rows)  # type: ignore[arg-type]
    with pytest.raises(InputValueError, match="must be finite"):
        th.step(state, rows[0], rows[1], rows[2], np.full(N_DOF, np.nan))
    assert th.initial_state(*rows, kind="motor").dt == state.dt
    with pytest.raises(InputValueError, match="fitted on 'motor' signals; these signals are"):
        th.initial_state(*rows, kind="joint")


def test_minimax_fit_gives_the_narrowest_band() -> None:
    """The L∞ fit recovers planted γ, ε_fr and never has a wider band than LS or β."""
    rng = np.random.default_rng(4)
    t = np.arange(4000) * 1e-3
    h = np.column_stack([np.sin(3 * t), np.cos(2 * t)]) * 10
    f = np.column_stack([np.cos(5 * t), np.sin(7 * t)]) * 2
    noise = rng.uniform(-0.3, 0.3, h.shape) + 0.2 * np.sign(np.sin(11 * t))[:, None]
    r = np.array([0.05, -0.1]) * h + np.array([0.4, 0.8]) * f + noise
    zeros = np.zeros_like(r)
    run = ObserverSignals(t, r, h, f, zeros, zeros, gain=20.0, robot="demo")
    exact = TimeVariantThreshold(fit_method="minimax").fit(
        ObserverSignals(t, r - noise, h, f, zeros, zeros, gain=20.0, robot="demo")
    )
    np.testing.assert_allclose(exact.gamma_, [0.05, -0.1], atol=1e-7)
    np.testing.assert_allclose(exact.eps_fr_, [0.4, 0.8], atol=1e-7)
    minimax = TimeVariantThreshold(fit_method="minimax").fit(run)
    least = TimeVariantThreshold().fit(run)
    assert np.all(minimax.alpha_ <= least.alpha_ + 1e-9)
    assert np.all(minimax.alpha_ <= minimax.beta_)
    # The planted coefficients are feasible with α = max|noise|: the optimum is no wider.
    assert np.all(minimax.alpha_ <= np.abs(noise).max(axis=0) + 1e-9)
    with pytest.raises(InputValueError, match="fit_method must be one of"):
        TimeVariantThreshold(fit_method="l1").fit(run)
