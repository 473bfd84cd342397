"""Tests of :class:`sensorless.thresholds.CombinedVelocityThreshold`.

Paired runs are built from planted values: one γ shared by r̂ and r̂_s, and
per-bin offsets τ̂_fme and τ̂_sfe, filtered here with a plain Python loop of
the observer's zero-order-hold recursion (independent of
:func:`scipy.signal.lfilter`):

    r̂   = γ h   + K_I/(s+K_I)·τ̂_fme(q̇) + noise
    r̂_s = γ h_s - K_I/(s+K_I)·τ̂_sfe(q̇) + noise      (eq. 4.30, 4.31)
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

from sensorless.detection import Detector
from sensorless.exceptions import (
    DimensionError,
    FileFormatError,
    InputTypeError,
    InputValueError,
    ModelMismatchError,
    NotFittedError,
)
from sensorless.signals import ObserverSignals
from sensorless.thresholds import (
    METHODS,
    CombinedVelocityState,
    CombinedVelocityThreshold,
    ThresholdState,
    VelocityThreshold,
    load_threshold,
)

DT = 1e-3
GAIN = np.array([20.0, 25.0, 30.0])
N_DOF = 3
N = 3000
WIDTH = 0.06
GAMMA = np.array([0.02, -0.03, 0.05])
ROWS = ("model_torque", "friction", "sign", "velocity")

Pair = tuple[ObserverSignals, ObserverSignals]


def lowpass(x: np.ndarray, gain: np.ndarray = GAIN) -> np.ndarray:
    """K/(s+K) with zero-order hold, written as the recursion (y[0] = x[0])."""
    a = np.exp(-gain * DT)
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


def bins(velocity: np.ndarray, width: float = WIDTH) -> np.ndarray:
    """Bin k covers [k w, (k + 1) w)."""
    return np.floor(velocity / width).astype(int)


def planted_fme(k: np.ndarray, width: float = WIDTH) -> np.ndarray:
    """τ̂_fme per bin [N m]: Coulomb-like, viscous and a joint-dependent bias."""
    centre = (k + 0.5) * width
    return 0.3 * np.tanh(centre / 0.1) + 0.2 * centre + np.array([0.05, -0.1, 0.0])


def planted_sfe(k: np.ndarray, width: float = WIDTH) -> np.ndarray:
    """τ̂_sfe per bin [N m], shaped unlike τ̂_fme so that the two cannot be confused."""
    centre = (k + 0.5) * width
    return -0.1 * np.tanh(centre / 0.05) + 0.05 * centre**2 + np.array([0.2, 0.0, -0.15])


def pair(
    seed: int,
    n: int = N,
    *,
    width: float = WIDTH,
    noise_motor: float = 0.0,
    noise_joint: float = 0.0,
    gamma: np.ndarray = GAMMA,
) -> Pair:
    """(motor, joint) signals of one synthetic run; h_s differs from h by an inertia-like term."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * DT
    velocity = smooth(rng, t, 0.5)
    h = smooth(rng, t, 20.0)
    h_s = h - smooth(rng, t, 2.0)
    k = bins(velocity, width)
    common = {
        "t": t,
        "velocity": velocity,
        "friction": lowpass(0.5 * velocity),
        "sign": lowpass(np.sign(velocity)),
        "gain": GAIN,
        "robot": "synthetic",
    }
    r = gamma * h + lowpass(planted_fme(k, width)) + noise_motor * rng.standard_normal((n, N_DOF))
    r_s = (
        gamma * h_s - lowpass(planted_sfe(k, width)) + noise_joint * rng.standard_normal((n, N_DOF))
    )
    return (
        ObserverSignals(residual=r, model_torque=h, kind="motor", **common),
        ObserverSignals(residual=r_s, model_torque=h_s, kind="joint", **common),
    )


def bin_keys(th: CombinedVelocityThreshold) -> np.ndarray:
    """Bin number k of every row of the fitted tables, repeated per joint."""
    centres = (th.bin_edges_[:-1] + th.bin_edges_[1:]) / 2
    return np.repeat(bins(centres, float(th.bin_width))[:, None], N_DOF, axis=1)


def noisy_fit(**kwargs: object) -> tuple[CombinedVelocityThreshold, list[Pair]]:
    pairs = [pair(seed, noise_motor=0.02, noise_joint=0.03) for seed in (3, 4)]
    return CombinedVelocityThreshold(**kwargs).fit(pairs), pairs  # type: ignore[arg-type]


# --------------------------------------------------------------------------- fit


@pytest.mark.parametrize("weighting", ["equal", "inverse_variance"])
@pytest.mark.parametrize("width", [0.06, 0.1])
def test_recovers_planted_gamma_and_offsets(width: float, weighting: str) -> None:
    th = CombinedVelocityThreshold(bin_width=width, weighting=weighting)
    th.fit([pair(1, width=width), pair(2, width=width)])
    np.testing.assert_allclose(th.gamma_, GAMMA, rtol=1e-9, atol=1e-12)
    visited = th.counts_ > 0
    assert visited.sum() > 20
    k = bin_keys(th)
    np.testing.assert_allclose(th.tau_fme_[visited], planted_fme(k, width)[visited], atol=1e-9)
    np.testing.assert_allclose(th.tau_sfe_[visited], planted_sfe(k, width)[visited], atol=1e-9)
    for name in ("lower_motor_", "upper_motor_", "lower_joint_", "upper_joint_"):
        np.testing.assert_allclose(getattr(th, name)[visited], 0.0, atol=1e-9)
    np.testing.assert_array_equal(th.counts_.sum(axis=0), [2 * N] * N_DOF)
    np.testing.assert_allclose(th.weights_, 0.5)
    assert th.kind_ == "motor+joint" and th.robot_ == "synthetic" and th.dt_ == pytest.approx(DT)


def test_recovers_planted_values_with_noise() -> None:
    th, _ = noisy_fit()
    np.testing.assert_allclose(th.gamma_, GAMMA, atol=2e-4)
    well_sampled = th.counts_ > 300
    assert well_sampled.sum() > 10
    k = bin_keys(th)
    np.testing.assert_allclose(th.tau_fme_[well_sampled], planted_fme(k)[well_sampled], atol=0.02)
    np.testing.assert_allclose(th.tau_sfe_[well_sampled], planted_sfe(k)[well_sampled], atol=0.02)
    visited = th.counts_ > 0
    assert np.all(th.lower_motor_[visited] < 0.0) and np.all(th.upper_motor_[visited] > 0.0)
    assert np.all(th.lower_joint_[visited] < 0.0) and np.all(th.upper_joint_[visited] > 0.0)
    # Gaussian noise of 0.02 / 0.03 N m: L and U are a few standard deviations.
    assert np.all(np.abs(th.lower_motor_) < 0.15) and np.all(np.abs(th.upper_joint_) < 0.2)


def test_transient_is_skipped_in_both_residuals() -> None:
    th = CombinedVelocityThreshold(transient=0.5).fit([pair(1), pair(2)])
    np.testing.assert_array_equal(th.counts_.sum(axis=0), [2 * (N - 500)] * N_DOF)


def gamma_errors(n_trials: int, noise_motor: float, noise_joint: float) -> dict[str, float]:
    """Mean |γ - planted γ| over seeded trials and joints, per way of fitting."""
    errors: dict[str, list[np.ndarray]] = {"motor": [], "joint": [], "equal": [], "inverse": []}
    for trial in range(n_trials):
        motor, joint = pair(500 + trial, n=1500, noise_motor=noise_motor, noise_joint=noise_joint)
        errors["motor"].append(VelocityThreshold().fit(motor).gamma_ - GAMMA)
        errors["joint"].append(VelocityThreshold().fit(joint).gamma_ - GAMMA)
        errors["equal"].append(CombinedVelocityThreshold().fit((motor, joint)).gamma_ - GAMMA)
        inverse = CombinedVelocityThreshold(weighting="inverse_variance").fit((motor, joint))
        errors["inverse"].append(inverse.gamma_ - GAMMA)
    return {name: float(np.mean(np.abs(values))) for name, values in errors.items()}


def test_shared_gamma_beats_the_noisy_residual_alone() -> None:
    error = gamma_errors(20, noise_motor=0.05, noise_joint=0.2)
    # Equal weights: about half the error of r̂_s alone (theory: sqrt(17/64)) ...
    assert error["equal"] < 0.7 * error["joint"]
    # ... but dragged by the noisy rows against the clean r̂ alone (theory: sqrt(17/4)).
    assert error["equal"] > 1.3 * error["motor"]
    # Inverse-variance weights beat r̂_s alone and lose nothing against r̂ alone.
    assert error["inverse"] < 0.45 * error["joint"]
    assert error["inverse"] < 1.1 * error["motor"]


def test_shared_gamma_beats_both_residuals_alone_at_equal_noise() -> None:
    error = gamma_errors(20, noise_motor=0.05, noise_joint=0.05)
    # Twice the rows: theory sqrt(1/2) of either error.
    assert error["equal"] < 0.9 * min(error["motor"], error["joint"])
    assert error["inverse"] < 0.9 * min(error["motor"], error["joint"])


def test_inverse_variance_weights_favour_the_cleaner_residual() -> None:
    pairs = [pair(seed, noise_motor=0.01, noise_joint=0.1) for seed in (5, 6)]
    equal = CombinedVelocityThreshold().fit(pairs)
    inverse = CombinedVelocityThreshold(weighting="inverse_variance").fit(pairs)
    np.testing.assert_allclose(equal.weights_, 0.5)
    np.testing.assert_allclose(inverse.weights_.sum(axis=0), 1.0)
    # Weights are the inverse mean square errors: about (0.1 / 0.01)^2 = 100 to 1.
    assert np.all(inverse.weights_[0] > 0.98)
    # Bounds of each residual come from its own errors, whatever the weighting.
    assert np.all(inverse.upper_joint_ - inverse.lower_joint_ > 0.3)
    assert np.all(inverse.upper_motor_ - inverse.lower_motor_ < 0.15)


def test_offset_sum_is_eq_4_21_the_fit_of_the_residual_difference() -> None:
    motor, joint = pair(7)
    th = CombinedVelocityThreshold().fit((motor, joint))
    difference = ObserverSignals(
        t=motor.t,
        residual=motor.residual - joint.residual,
        model_torque=motor.model_torque - joint.model_torque,
        friction=motor.friction,
        sign=motor.sign,
        velocity=motor.velocity,
        gain=GAIN,
        robot="synthetic",
    )
    single = VelocityThreshold().fit(difference)
    visited = th.counts_ > 0
    np.testing.assert_allclose(single.gamma_, th.gamma_, rtol=1e-9)
    np.testing.assert_allclose(
        single.tau_fme_[visited], (th.tau_fme_ + th.tau_sfe_)[visited], atol=1e-9
    )


# --------------------------------------------------------------------------- apply


def test_bounds_contain_the_fit_runs() -> None:
    th, pairs = noisy_fit()
    for run in (r for p in pairs for r in p):
        lower, upper = th.bounds(run)
        assert np.all(lower <= run.residual) and np.all(run.residual <= upper)


@pytest.mark.parametrize("kind", ["motor", "joint"])
def test_bounds_follow_eq_4_35_and_4_38(kind: str) -> None:
    th, _ = noisy_fit(margin=0.01)
    run = pair(8, n=800)[kind == "joint"]
    lower, upper = th.bounds(run)
    index = np.clip(np.searchsorted(th.bin_edges_, run.velocity, side="right") - 1, 0, None)
    joints = np.arange(N_DOF)
    tau = th.tau_fme_ if kind == "motor" else -th.tau_sfe_
    centre = th.gamma_ * run.model_torque + lowpass(tau[index, joints])
    low, up = getattr(th, f"lower_{kind}_"), getattr(th, f"upper_{kind}_")
    np.testing.assert_allclose(lower, centre + low[index, joints], rtol=0, atol=1e-12)
    np.testing.assert_allclose(upper, centre + up[index, joints], rtol=0, atol=1e-12)


@pytest.mark.parametrize("kind", ["motor", "joint"])
def test_for_kind_is_the_plain_velocity_threshold(kind: str, tmp_path: Path) -> None:
    th, pairs = noisy_fit(extrapolation_margin=0.2)
    single = th.for_kind(kind)
    assert type(single) is VelocityThreshold and single.kind_ == kind
    expected = th.tau_fme_ if kind == "motor" else -th.tau_sfe_
    np.testing.assert_array_equal(single.tau_fme_, expected)
    run = pairs[0][kind == "joint"]
    fast = ObserverSignals(
        t=run.t,
        residual=run.residual,
        model_torque=run.model_torque,
        friction=run.friction,
        sign=run.sign,
        velocity=3.0 * run.velocity,
        gain=GAIN,
        kind=kind,
        robot="synthetic",
    )
    for signals in (run, fast):
        for a, b in zip(single.bounds(signals), th.bounds(signals), strict=True):
            np.testing.assert_array_equal(a, b)
    loaded = load_threshold(single.save(tmp_path / "single.yaml"))
    assert loaded.name == "velocity"
    np.testing.assert_array_equal(loaded.bounds(run)[1], th.bounds(run)[1])


def test_a_plain_fit_on_r_s_finds_minus_tau_sfe() -> None:
    motor, joint = pair(9)
    th = CombinedVelocityThreshold().fit((motor, joint))
    single = VelocityThreshold().fit(joint)
    visited = th.counts_ > 0
    np.testing.assert_allclose(single.tau_fme_[visited], -th.tau_sfe_[visited], atol=1e-9)


@pytest.mark.parametrize("kind", ["motor", "joint"])
def test_streaming_equals_batch(kind: str) -> None:
    th, _ = noisy_fit(extrapolation_margin=0.1)
    th.joints = [1, 3]
    run = pair(10, n=600)[kind == "joint"]
    lower, upper = th.bounds(run)
    assert np.all(upper[:, 1] == np.inf) and np.all(np.isfinite(upper[:, [0, 2]]))
    rows = [getattr(run, name) for name in ROWS]
    state = th.initial_state(*(x[0] for x in rows), dt=DT, kind=kind)
    assert isinstance(state, CombinedVelocityState) and state.kind == kind
    assert state.zi.shape == (N_DOF,)
    for k in range(run.n_samples):
        lo, up, state = th.step(state, *(x[k] for x in rows))
        np.testing.assert_allclose(lo, lower[k], rtol=0, atol=1e-12)
        np.testing.assert_allclose(up, upper[k], rtol=0, atol=1e-12)
    state = th.initial_state(*(x[0] for x in rows), dt=DT, kind=kind)
    chunks = []
    for cut in np.array_split(np.arange(run.n_samples), [1, 5, 250, 251]):
        lo, up, state = th.process(state, *(x[cut] for x in rows))
        chunks.append((lo, up))
    np.testing.assert_allclose(np.vstack([c[0] for c in chunks]), lower, rtol=0, atol=1e-12)
    np.testing.assert_allclose(np.vstack([c[1] for c in chunks]), upper, rtol=0, atol=1e-12)
    assert isinstance(state, CombinedVelocityState) and state.kind == kind


def test_the_stream_kind_selects_the_residual() -> None:
    th, _ = noisy_fit()
    run = pair(11, n=50)[0]
    first = [getattr(run, name)[0] for name in ROWS]
    motor = th.initial_state(*first, kind="motor")
    joint = th.initial_state(*first, kind="joint")
    assert not np.allclose(motor.zi, joint.zi)
    lo_m, _, _ = th.step(motor, *first)
    lo_s, _, _ = th.step(joint, *first)
    assert not np.allclose(lo_m, lo_s)


def test_detect_uses_the_residual_of_the_signals() -> None:
    th, pairs = noisy_fit()
    assert Detector(th.for_kind(pairs[0][1].kind)).detect(pairs[0][1]) == []
    _, joint = pair(3, noise_motor=0.02, noise_joint=0.03)
    bumped = joint.residual.copy()
    bumped[1000:1100, 1] += 2.0
    hit = ObserverSignals(
        t=joint.t,
        residual=bumped,
        model_torque=joint.model_torque,
        friction=joint.friction,
        sign=joint.sign,
        velocity=joint.velocity,
        gain=GAIN,
        kind="joint",
        robot="synthetic",
    )
    events = Detector(th.for_kind(hit.kind)).detect(hit)
    assert len(events) == 1 and events[0].joints == (2,)
    assert events[0].start == pytest.approx(1.0)


def test_the_detector_takes_the_threshold_of_one_residual() -> None:
    th, pairs = noisy_fit()
    motor = pairs[0][0]
    result = Detector(th.for_kind("motor")).run(motor)
    np.testing.assert_array_equal(result.lower, th.bounds(motor)[0])
    np.testing.assert_array_equal(result.upper, th.bounds(motor)[1])
    assert result.method == "velocity"
    hint = r"got kind None; pass kind='motor' or kind='joint', or stream for_kind\(kind\)"
    with pytest.raises(InputValueError, match=hint):
        Detector(th).run(motor)
    detector = Detector(th)
    first = [getattr(motor, name)[0] for name in ROWS]
    with pytest.raises(InputValueError, match=hint):
        detector.step(detector.initial_state(), motor.residual[0], *first, motor.t[0])


# --------------------------------------------------------------------------- files


def test_save_load_round_trip(tmp_path: Path) -> None:
    th, pairs = noisy_fit(margin=[0.01, 0.02, 0.0], weighting="inverse_variance")
    th.joints = [1, 2]
    path = th.save(tmp_path / "combined.yaml")
    text = path.read_text()
    data = yaml.safe_load(text)
    assert "method: velocity-combined" in text
    assert data["kind"] == "motor+joint" and data["n_dof"] == N_DOF
    assert data["params"]["weighting"] == "inverse_variance"
    for name in th.to_dict()["attributes"]:
        assert f"{name}:" in text
    loaded = load_threshold(path)
    assert type(loaded) is CombinedVelocityThreshold
    assert loaded.get_params() == {
        k: (list(v) if isinstance(v, tuple | list) else v) for k, v in th.get_params().items()
    }
    for run in pairs[0]:
        for a, b in zip(loaded.bounds(run), th.bounds(run), strict=True):
            np.testing.assert_array_equal(a, b)
    same = CombinedVelocityThreshold.from_dict(th.to_dict())
    np.testing.assert_array_equal(same.bounds(pairs[1][1])[0], th.bounds(pairs[1][1])[0])


def test_registry_and_repr() -> None:
    assert METHODS["velocity-combined"] is CombinedVelocityThreshold
    assert METHODS["velocity"] is VelocityThreshold
    text = repr(CombinedVelocityThreshold(bin_width=0.1))
    assert text.startswith("CombinedVelocityThreshold(bin_width=0.1")
    assert "weighting='equal'" in text


# --------------------------------------------------------------------------- errors


def test_unfitted_threshold_raises(tmp_path: Path) -> None:
    th = CombinedVelocityThreshold()
    motor, _ = pair(1, n=10)
    with pytest.raises(NotFittedError, match="call fit"):
        th.bounds(motor)
    with pytest.raises(NotFittedError, match="not fitted yet"):
        th.initial_state(*np.zeros((4, N_DOF)), kind="motor")
    with pytest.raises(NotFittedError, match="call fit"):
        th.for_kind("motor")
    with pytest.raises(NotFittedError, match="call fit"):
        Detector(th.for_kind(motor.kind)).detect(motor)
    with pytest.raises(NotFittedError, match="call fit"):
        th.save(tmp_path / "x.yaml")


def replace(run: ObserverSignals, **changes: object) -> ObserverSignals:
    fields = {
        "t": run.t,
        "residual": run.residual,
        "model_torque": run.model_torque,
        "friction": run.friction,
        "sign": run.sign,
        "velocity": run.velocity,
        "gain": run.gain,
        "kind": run.kind,
        "robot": run.robot,
    }
    return ObserverSignals(**(fields | changes))  # type: ignore[arg-type]


def test_bad_pairs_are_rejected() -> None:
    motor, joint = pair(1, n=200)
    th = CombinedVelocityThreshold()
    with pytest.raises(InputTypeError, match=r"paired runs.*one ObserverSignals of kind 'motor'"):
        th.fit(motor)  # type: ignore[arg-type]
    with pytest.raises(InputTypeError, match=r"paired runs.*got dict"):
        th.fit({"motor": motor})  # type: ignore[arg-type]
    with pytest.raises(InputValueError, match=r"paired runs.*an empty sequence"):
        th.fit([])
    with pytest.raises(InputTypeError, match="got 4 items as pair 0"):
        th.fit([motor, joint, motor, joint])
    with pytest.raises(InputTypeError, match="got 1 items as pair 1"):
        th.fit([(motor, joint), (motor,)])
    with pytest.raises(
        InputValueError, match=r"pair 0 must be \(motor, joint\).*\('joint', 'motor'\)"
    ):
        th.fit((joint, motor))
    with pytest.raises(InputValueError, match=r"pair 1 must be.*\('motor', 'motor'\)"):
        th.fit([(motor, joint), (motor, motor)])


def test_pairs_must_come_from_one_run() -> None:
    motor, joint = pair(1, n=200)
    th = CombinedVelocityThreshold()
    with pytest.raises(
        DimensionError, match="pair 0: the motor signals have 200 samples, the joint signals 150"
    ):
        th.fit(
            (
                motor,
                replace(joint, **{k: getattr(joint, k)[:150] for k in ("t", "residual", *ROWS)}),
            )
        )
    shifted = replace(joint, t=joint.t + 1e-3)
    with pytest.raises(
        InputValueError, match=r"pair 0: t of the joint signals differs .* sample 0"
    ):
        th.fit((motor, shifted))
    other = joint.velocity.copy()
    other[7, 2] += 1e-3
    with pytest.raises(
        InputValueError, match=r"velocity of the joint signals differs .* sample 7, joint 3"
    ):
        th.fit([pair(2, n=200), (motor, replace(joint, velocity=other))])
    with pytest.raises(ModelMismatchError, match=r"one robot.*'synthetic'.*'lwr4'"):
        th.fit((motor, replace(joint, robot="lwr4")))
    with pytest.raises(InputValueError, match="one observer gain K_I"):
        th.fit((motor, replace(joint, gain=2 * GAIN)))
    two = {k: getattr(joint, k)[:, :2] for k in ("residual", *ROWS)}
    with pytest.raises(DimensionError, match=r"one robot.*\(3 joints\).*\(2 joints\)"):
        th.fit((motor, replace(joint, **two, gain=GAIN[:2])))
    bad = joint.residual.copy()
    bad[3, 0] = np.nan
    with pytest.raises(InputValueError, match="residual of fit run 0 must be finite"):
        th.fit((motor, replace(joint, residual=bad)))


def test_bad_hyper_parameters_are_rejected_at_fit() -> None:
    pairs = pair(1, n=200)
    with pytest.raises(
        InputValueError, match=r"weighting must be one of \['equal', 'inverse_variance'\]"
    ):
        CombinedVelocityThreshold(weighting="robust").fit(pairs)
    with pytest.raises(InputValueError, match="bin_width must be a positive"):
        CombinedVelocityThreshold(bin_width=0.0).fit(pairs)
    with pytest.raises(InputValueError, match="extrapolation_margin must be"):
        CombinedVelocityThreshold(extrapolation_margin=-1.0).fit(pairs)
    with pytest.raises(InputValueError, match="no fit sample is left"):
        CombinedVelocityThreshold(transient=10.0).fit(pairs)
    with pytest.raises(InputValueError, match="margin must be finite and >= 0"):
        CombinedVelocityThreshold(margin=-0.1).fit(pairs)


def test_signals_and_states_of_another_kind_are_rejected() -> None:
    th, pairs = noisy_fit()
    motor = pairs[0][0]
    acceleration = replace(motor, kind="acceleration")
    with pytest.raises(
        InputValueError,
        match=r"bounds 'motor' \(r̂\) and 'joint' \(r̂_s\) signals; got kind 'acceleration'",
    ):
        th.bounds(acceleration)
    with pytest.raises(InputValueError, match="got kind 'acceleration'"):
        Detector(th.for_kind(acceleration.kind)).detect(acceleration)
    with pytest.raises(InputTypeError, match="signals must be an ObserverSignals"):
        th.bounds(motor.residual)  # type: ignore[arg-type]
    with pytest.raises(ModelMismatchError, match=r"fitted for synthetic.*come from puma"):
        th.bounds(replace(motor, robot="puma"))
    with pytest.raises(InputValueError, match="observer gain"):
        th.bounds(replace(motor, gain=GAIN + 1.0))
    first = [getattr(motor, name)[0] for name in ROWS]
    with pytest.raises(InputValueError, match="got kind None; pass kind='motor' or kind='joint'"):
        th.initial_state(*first)
    with pytest.raises(InputValueError, match="got kind 'acceleration'"):
        th.for_kind("acceleration")
    plain = ThresholdState(DT, np.zeros(N_DOF))
    with pytest.raises(
        InputTypeError, match=r"CombinedVelocityState from initial_state.*ThresholdState"
    ):
        th.step(plain, *first)


def test_bad_threshold_files_are_rejected() -> None:
    th, _ = noisy_fit()
    data = th.to_dict()
    with pytest.raises(FileFormatError, match="has kind 'motor\\+joint'; got 'motor'"):
        CombinedVelocityThreshold.from_dict(data | {"kind": "motor"})
    weights = dict(data["attributes"], weights_=[[0.5, 0.5, 0.5]])
    with pytest.raises(FileFormatError, match=r"weights_: expected shape \(2, n_dof\) = \(2, 3\)"):
        CombinedVelocityThreshold.from_dict(data | {"attributes": weights})
    short = dict(data["attributes"], tau_sfe_=data["attributes"]["tau_sfe_"][:-1])
    with pytest.raises(FileFormatError, match="tau_sfe_: expected shape"):
        CombinedVelocityThreshold.from_dict(data | {"attributes": short})
    missing = {k: v for k, v in data["attributes"].items() if k != "lower_joint_"}
    with pytest.raises(FileFormatError, match="lower_joint_: required key is missing"):
        CombinedVelocityThreshold.from_dict(data | {"attributes": missing})
    with pytest.raises(
        InputValueError, match="holds a 'velocity-combined' threshold, not 'velocity'"
    ):
        VelocityThreshold.from_dict(data)
