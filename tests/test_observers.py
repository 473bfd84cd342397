"""Tests of :mod:`sensorless.observers`.

Independent checks:

* a simulated PUMA 560 (true model = observer model, perfect sensors, smooth
  friction): r̂ equals the exact discrete K_I/(s+K_I) of the logged, held τ_c;
  a collision-free run stays in a band far below any contact;
* h equals K_I/(s+K_I) of M q̈ + C q̇ + g computed by RNEA at midpoints with
  q̈ from differences of the true velocity (a second method, no momentum);
* the filtered friction equals the filtered friction the plant logged;
* a constant external torque on a robot at rest gives the closed-form step
  response c (1 − exp(−K_I t)) per joint;
* the acceleration-based estimate recovers τ_c on a quintic trajectory, and
  with a Butterworth filter equals the model evaluated at delayed derivatives;
* step-by-step = batch, chunked = whole.
"""

from __future__ import annotations

import doctest
import importlib
from typing import Any

import numpy as np
import pytest
from scipy import signal

from sensorless import robots
from sensorless.exceptions import DimensionError, InputValueError, LogFormatError
from sensorless.filters import Butterworth, FiniteDifference, SavitzkyGolay
from sensorless.friction import LuGre, Sigmoid, Viscous
from sensorless.io import Log
from sensorless.observers import (
    AccelerationObserver,
    MomentumObserver,
    ObserverSample,
    ObserverState,
    default_estimator,
    observe,
)
from sensorless.signals import ObserverSignals
from sensorless.simulation import plants, simulator
from sensorless.simulation.scenario import Scenario, load_scenario

GAIN = 20.0  # K_I [1/s], thesis § 5.4


def _lowpass(x: np.ndarray, gain: Any, dt: float, y0: Any) -> np.ndarray:
    """y_k+1 = a y_k + (1 − a) x_k with a = exp(−K_I dt): exact K_I/(s+K_I) of a held x."""
    a = np.exp(-np.asarray(gain) * dt)
    y = np.empty((x.shape[0] + 1, x.shape[1]))
    y[0] = y0
    for k in range(x.shape[0]):
        y[k + 1] = a * y[k] + (1 - a) * x[k]
    return y


# --------------------------------------------------------------------------- simulated PUMA


@pytest.fixture(scope="module")
def puma() -> dict[str, Any]:
    """PUMA 560 thesis run, 10 s, perfect sensors, nominal = true, smooth friction.

    The friction is a sigmoid (Coulomb-like, but smooth): with a discontinuous
    Coulomb law the simulated stick-slip at rest is not a function of the
    sampled velocity, and no sampled observer can reproduce it.
    """
    base = load_scenario("puma560-thesis")
    spec = dict(base.spec)
    spec.update(duration=10.0, sensors={}, true_friction="robot")
    spec.pop("model_error")
    scenario = Scenario(base.name, spec)
    true, _ = scenario.robots()
    coulomb = 0.5 * (np.abs(true.friction.c_pos) + np.abs(true.friction.c_neg))
    friction = Sigmoid(phi1=2 * coulomb, phi2=20.0, phi3=0.0)
    robot = true.with_standard_parameters(true.parameter_vector(), friction=friction)
    runs = {}
    for collisions in (True, False):
        options = scenario.build(collisions=collisions)
        options["plant"] = plants.RigidPlant(robot)
        runs[collisions] = simulator.simulate(**options)
    return {"robot": robot, "hit": runs[True], "free": runs[False]}


def _observe_true(robot: Any, log: Log) -> ObserverSignals:
    observer = MomentumObserver(robot, log.dt, gain=GAIN)
    signals, _ = observer.run(log.t, log.q_true, log.qd_true, log.tau_m)
    return signals


def test_residual_is_filtered_contact_torque_with_exact_model(puma: dict[str, Any]) -> None:
    log = puma["hit"].log
    signals = _observe_true(puma["robot"], log)
    reference = _lowpass(log.tau_c[:-1], GAIN, log.dt, 0.0)
    peak = np.abs(reference).max()
    assert peak > 10.0  # the run has real contacts
    # Only the trapezoid rule on Cᵀq̇ − g − τ_fr separates the two: measured 7e-3 N m.
    np.testing.assert_allclose(signals.residual, reference, rtol=0, atol=2e-3 * peak)
    assert signals.residual[0].tolist() == [0.0] * 6


def test_collision_free_residual_stays_far_below_every_contact(puma: dict[str, Any]) -> None:
    hit = puma["hit"].log
    reference = _lowpass(hit.tau_c[:-1], GAIN, hit.dt, 0.0)
    contact_peaks = [
        np.abs(reference[hit.collision_id == cid]).max() for cid in np.unique(hit.collision_id)[1:]
    ]
    assert len(contact_peaks) == 2
    free = _observe_true(puma["robot"], puma["free"].log)
    assert np.abs(free.residual).max() < 0.01 * min(contact_peaks)


def test_model_torque_equals_filtered_inverse_dynamics(puma: dict[str, Any]) -> None:
    robot, log = puma["robot"], puma["hit"].log
    signals = _observe_true(robot, log)
    q, qd, dt = log.q_true, log.qd_true, log.dt
    # Second method: RNEA with true states at mid-period and q̈ from velocity differences.
    rigid = robot.inverse_dynamics(
        0.5 * (q[1:] + q[:-1]), 0.5 * (qd[1:] + qd[:-1]), np.diff(qd, axis=0) / dt
    )
    reference = _lowpass(rigid, GAIN, dt, robot.gravity(q[0]))  # h_0 = g(q0) at rest
    peak = np.abs(reference).max()
    np.testing.assert_allclose(signals.model_torque, reference, rtol=0, atol=1e-5 * peak)


def test_filtered_friction_and_sign(puma: dict[str, Any]) -> None:
    log, run = puma["hit"].log, puma["hit"]
    signals = _observe_true(puma["robot"], log)
    # Friction the plant itself logged, trapezoid over each period.
    plant_friction = 0.5 * (run.friction[1:] + run.friction[:-1])
    reference = _lowpass(plant_friction, GAIN, log.dt, run.friction[0])
    np.testing.assert_allclose(signals.friction, reference, rtol=0, atol=1e-9)
    sign = np.sign(log.qd_true)
    np.testing.assert_allclose(
        signals.sign, _lowpass(0.5 * (sign[1:] + sign[:-1]), GAIN, log.dt, sign[0]), atol=1e-12
    )
    assert np.abs(signals.sign).max() <= 1.0


def test_residual_identity_with_filtered_torque(puma: dict[str, Any]) -> None:
    """r̂ = h − K_I/(s+K_I)·τ + K_I/(s+K_I)·τ̂_fr, with τ started at the balancing torque."""
    robot, log = puma["robot"], puma["hit"].log
    observer = MomentumObserver(robot, log.dt, gain=GAIN)
    state = observer.initial_state(log.q_true[0], log.qd_true[0])
    signals, _ = observer.run(log.t, log.q_true, log.qd_true, log.tau_m, state)
    torque = _lowpass(log.tau_m[:-1], GAIN, log.dt, state.torque)
    np.testing.assert_allclose(
        signals.residual, signals.model_torque - torque + signals.friction, rtol=0, atol=1e-9
    )


# --------------------------------------------------------------------------- closed forms


def test_constant_external_torque_gives_first_order_step_response() -> None:
    robot = robots.load("planar2")
    gain = np.array([10.0, 40.0])
    dt, n = 1e-3, 400
    q0 = np.array([0.3, -0.5])
    contact = np.array([2.0, -1.5])
    q = np.tile(q0, (n, 1))
    tau = np.tile(robot.gravity(q0) - contact, (n, 1))  # held at rest by τ + τ_c = g
    t = np.arange(n) * dt
    signals, _ = MomentumObserver(robot, dt, gain=gain, friction=None).run(t, q, 0 * q, tau)
    expected = contact * (1 - np.exp(-gain * t[:, None]))
    np.testing.assert_allclose(signals.residual, expected, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(signals.model_torque, np.tile(robot.gravity(q0), (n, 1)))


def test_initial_sample_handles_p0() -> None:
    robot = robots.load("panda_gaz")
    observer = MomentumObserver(robot, 1e-3)
    q0 = np.linspace(-0.5, 0.5, 7)
    sample, _ = observer.step(observer.initial_state(q0), q0, np.zeros(7), np.ones(7))
    assert sample.residual.tolist() == [0.0] * 7
    np.testing.assert_allclose(sample.model_torque, robot.gravity(q0), rtol=1e-12, atol=1e-12)
    qd0 = np.linspace(0.3, -0.3, 7)
    sample, state = observer.step(observer.initial_state(q0, qd0), q0, qd0, np.ones(7))
    assert sample.residual.tolist() == [0.0] * 7
    expected_h = robot.gravity(q0) - robot.coriolis_transpose_velocity(q0, qd0)
    np.testing.assert_allclose(sample.model_torque, expected_h, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(sample.friction, robot.friction.torque(qd0), rtol=1e-12)
    np.testing.assert_array_equal(sample.sign, np.sign(qd0))
    np.testing.assert_array_equal(state.torque, np.ones(7))  # kept for the next step
    np.testing.assert_allclose(state.momentum, robot.mass_matrix(q0) @ qd0, rtol=1e-12)


def test_lugre_friction_enters_through_its_steady_state() -> None:
    robot = robots.load("planar2")
    lugre = LuGre.canudas1995(2)
    observer = MomentumObserver(robot, 1e-3, friction=lugre)
    qd = np.array([[-0.01, 0.002], [0.5, -3.0], [0.0, 0.0]])
    np.testing.assert_allclose(
        observer.friction_model.evaluate(qd), lugre.steady_state(qd), rtol=1e-14, atol=1e-14
    )


# --------------------------------------------------------------------------- streaming


def _random_run(n_samples: int, seed: int = 0) -> tuple[np.ndarray, ...]:
    rng = np.random.default_rng(seed)
    t = np.arange(n_samples) * 1e-3
    q = 0.5 * np.sin(np.outer(t, rng.uniform(0.5, 2.0, 7)) + rng.uniform(0, 3, 7))
    qd = np.gradient(q, t, axis=0) + 0.01 * rng.standard_normal(q.shape)
    tau = 5.0 * rng.standard_normal(q.shape)
    return t, q, qd, tau


def test_step_loop_equals_run_and_chunks_equal_whole() -> None:
    robot = robots.load("panda_gaz")
    observer = MomentumObserver(robot, 1e-3, gain=np.linspace(5.0, 50.0, 7))
    n = 9000  # more than one internal block of run
    t, q, qd, tau = _random_run(n)
    whole, final = observer.run(t, q, qd, tau)

    state = observer.initial_state(q[0], qd[0])
    stepped = np.empty((4, n, 7))
    for k in range(n):
        sample, state = observer.step(state, q[k], qd[k], tau[k])
        stepped[:, k] = sample
    for index, name in enumerate(("residual", "model_torque", "friction", "sign")):
        np.testing.assert_allclose(stepped[index], getattr(whole, name), rtol=0, atol=1e-10)
    np.testing.assert_allclose(state.filtered, final.filtered, rtol=0, atol=1e-10)

    state = None
    parts = []
    for chunk in np.split(np.arange(n), [1, 2, 700, 5000, 8999]):
        part, state = observer.run(t[chunk], q[chunk], qd[chunk], tau[chunk], state)
        parts.append(part.residual)
    np.testing.assert_allclose(np.vstack(parts), whole.residual, rtol=0, atol=1e-10)
    empty, same = observer.run(t[:0], q[:0], qd[:0], tau[:0], state)
    assert empty.n_samples == 0 and same is state


def test_run_returns_signals_with_metadata() -> None:
    robot = robots.load("planar2")
    t, q, qd, tau = (x[:, :2] if x.ndim == 2 else x for x in _random_run(50))
    signals, state = MomentumObserver(robot, 1e-3, gain=[3.0, 4.0], torque="joint").run(
        t, q, qd, tau
    )
    assert isinstance(signals, ObserverSignals) and isinstance(state, ObserverState)
    assert signals.kind == "joint" and signals.robot == robot.name
    np.testing.assert_array_equal(signals.gain, [3.0, 4.0])
    np.testing.assert_array_equal(signals.position, q)
    np.testing.assert_array_equal(signals.velocity, qd)
    assert signals.metadata["gain"] == [3.0, 4.0] and signals.metadata["torque"] == "joint"
    with pytest.raises(ValueError, match="read-only"):
        state.filtered[0, 0] = 1.0


# --------------------------------------------------------------------------- acceleration


def _quintic(t: np.ndarray, start: np.ndarray, end: np.ndarray, duration: float) -> tuple:
    s = np.clip(t / duration, 0, 1)[:, None]
    span = (end - start)[None, :]
    q = start + span * (10 * s**3 - 15 * s**4 + 6 * s**5)
    qd = span * (30 * s**2 - 60 * s**3 + 30 * s**4) / duration
    qdd = span * (60 * s - 180 * s**2 + 120 * s**3) / duration**2
    return q, qd, qdd


@pytest.fixture(scope="module")
def quintic() -> dict[str, Any]:
    """Panda on a 1-s quintic at 10 kHz with a half-sine external torque."""
    robot = robots.load("panda_gaz")
    dt = 1e-4
    t = np.arange(10001) * dt
    q, qd, qdd = _quintic(t, np.zeros(7), np.linspace(0.8, -0.6, 7), 1.0)
    window = (t > 0.3) & (t < 0.6)
    tau_c = np.where(window[:, None], 5.0 * np.sin(np.pi * (t[:, None] - 0.3) / 0.3), 0.0)
    tau_c = tau_c * np.linspace(1.0, 0.4, 7)
    tau = robot.inverse_dynamics(q, qd, qdd) + robot.friction.torque(qd) - tau_c
    return {"robot": robot, "dt": dt, "t": t, "q": q, "tau": tau, "tau_c": tau_c, "qdd": qdd}


def test_acceleration_observer_recovers_contact_torque(quintic: dict[str, Any]) -> None:
    d = quintic
    observer = AccelerationObserver(d["robot"], FiniteDifference(d["dt"]))
    signals, _ = observer.run(d["t"], d["q"], d["tau"])
    # Backward differences lag by dt/2 (velocity) and dt (acceleration): O(dt) error.
    error = np.abs(signals.residual - d["tau_c"]).max()
    assert error < 1e-2 * np.abs(d["tau_c"]).max()
    assert signals.kind == "acceleration" and np.isnan(signals.gain).all()
    # The double backward difference is centred on the previous sample.
    np.testing.assert_allclose(signals.acceleration[2:], d["qdd"][1:-1], rtol=0, atol=1e-4)
    np.testing.assert_allclose(
        signals.model_torque - d["tau"] + signals.friction, signals.residual, atol=1e-9
    )


def test_acceleration_observer_lags_by_the_filter_delays(quintic: dict[str, Any]) -> None:
    """With a Butterworth filter τ̂_c is the model at derivatives delayed by ``delays``."""
    d = quintic
    estimator = Butterworth(d["dt"], cutoff=20.0, order=5)
    signals, _ = AccelerationObserver(d["robot"], estimator).run(d["t"], d["q"], d["tau"])
    robot, t = d["robot"], d["t"]
    lag_v, lag_a = estimator.delays.velocity, estimator.delays.acceleration
    qd_lag = _quintic(t - lag_v, np.zeros(7), np.linspace(0.8, -0.6, 7), 1.0)[1]
    qdd_lag = _quintic(t - lag_a, np.zeros(7), np.linspace(0.8, -0.6, 7), 1.0)[2]
    delayed = (
        robot.inverse_dynamics(d["q"], qd_lag, qdd_lag) + robot.friction.torque(qd_lag) - d["tau"]
    )
    lagged_error = np.abs(signals.residual - delayed)[t > 0.2].max()
    contact_error = np.abs(signals.residual - d["tau_c"]).max()
    assert lagged_error < 0.01 * contact_error  # the delay explains the error


def test_acceleration_step_equals_run_and_chunks(quintic: dict[str, Any]) -> None:
    d = quintic
    observer = AccelerationObserver(d["robot"], Butterworth(d["dt"], cutoff=50.0, order=2))
    n = 600
    t, q, tau = d["t"][:n], d["q"][:n] + 1e-3, d["tau"][:n]
    whole, final = observer.run(t, q, tau)
    state = observer.initial_state(q[0])
    for k in range(n):
        sample, state = observer.step(state, q[k], tau[k])
        assert isinstance(sample, ObserverSample)
        np.testing.assert_allclose(sample.residual, whole.residual[k], rtol=0, atol=1e-10)
    first, state = observer.run(t[:250], q[:250], tau[:250])
    second, state = observer.run(t[250:], q[250:], tau[250:], state)
    np.testing.assert_allclose(
        np.vstack([first.residual, second.residual]), whole.residual, rtol=0, atol=1e-10
    )
    np.testing.assert_allclose(state.velocity, final.velocity, rtol=0, atol=1e-12)


# --------------------------------------------------------------------------- observe()


def test_observe_true_velocity_equals_observer_run(puma: dict[str, Any]) -> None:
    robot, log = puma["robot"], puma["hit"].log
    signals = observe(log, robot, velocity="true")
    direct, _ = MomentumObserver(robot, log.dt).run(log.t, log.q, log.qd_true, log.tau_m)
    np.testing.assert_array_equal(signals.residual, direct.residual)
    np.testing.assert_array_equal(signals.position, log.q)
    assert signals.metadata["scenario"] == "puma560-thesis"
    assert signals.metadata["observer"]["velocity"] == "true"
    assert signals.metadata["observer"]["gain"] == [GAIN] * 6


def test_observe_filter_and_acceleration_kinds(puma: dict[str, Any]) -> None:
    robot, log = puma["robot"], puma["hit"].log.slice(0.0, 3.0)
    estimated = observe(log, robot)  # backward differences of q by default
    assert estimated.metadata["observer"]["estimator"].startswith("FiniteDifference")
    np.testing.assert_allclose(estimated.velocity[1:], np.diff(log.q, axis=0) / log.dt)
    accel = observe(log, robot, kind="acceleration")
    assert accel.kind == "acceleration" and accel.acceleration is not None
    assert accel.metadata["observer"]["estimator"].startswith("Butterworth")
    joint_log = Log(t=log.t, q=log.q, tau_j=log.tau_m, qd_true=log.qd_true)
    joint = observe(joint_log, robot, kind="joint", velocity="true", gain=[5.0] * 6)
    motor = observe(log, robot, kind="motor", velocity="true", gain=5.0)
    assert joint.kind == "joint"
    np.testing.assert_array_equal(joint.residual, motor.residual)


def test_observe_uses_a_measured_velocity_when_the_log_has_one(puma: dict[str, Any]) -> None:
    robot, log = puma["robot"], puma["hit"].log.slice(0.0, 2.0)
    measured = Log(t=log.t, q=log.q, qd=log.qd_true, tau_m=log.tau_m, metadata=log.metadata)
    auto = observe(measured, robot)
    assert auto.metadata["observer"]["velocity"] == "measured"
    np.testing.assert_array_equal(auto.velocity, log.qd_true)
    truth = observe(log, robot, velocity="true")
    np.testing.assert_array_equal(auto.residual, truth.residual)
    estimated = observe(measured, robot, velocity="filter")
    assert estimated.metadata["observer"]["velocity"] == "filter"
    assert observe(log, robot).metadata["observer"]["velocity"] == "filter"  # no qd: estimate
    with pytest.raises(LogFormatError, match="velocity='measured' needs the measured"):
        observe(log, robot, velocity="measured")
    with pytest.raises(InputValueError, match="velocity='measured' applies to the momentum"):
        observe(measured, robot, kind="acceleration", velocity="measured")


def test_default_estimator() -> None:
    assert isinstance(default_estimator(1e-3), FiniteDifference)
    slow = default_estimator(0.05, "acceleration")
    assert isinstance(slow, Butterworth) and slow.order == 5 and slow.cutoff == 5.0
    with pytest.raises(InputValueError, match="kind must be one of"):
        default_estimator(1e-3, "momentum")


def _log(n_dof: int, **columns: Any) -> Log:
    t = np.arange(20) * 1e-3
    arrays = {name: value * np.ones((20, n_dof)) for name, value in columns.items()}
    return Log(t=t, q=np.zeros((20, n_dof)), **arrays)


def test_observe_errors() -> None:
    puma, panda = robots.load("puma560"), robots.load("panda")
    with pytest.raises(DimensionError, match="robot has 6 joints, log has 7"):
        observe(_log(7, tau_m=1.0), puma)
    with pytest.raises(LogFormatError, match=r"tau_j_1\.\.tau_j_7"):
        observe(_log(7, tau_m=1.0), panda, kind="joint")
    with pytest.raises(LogFormatError, match="tau_m"):
        observe(_log(7, tau_j=1.0), panda)
    with pytest.raises(LogFormatError, match="qd_true"):
        observe(_log(7, tau_m=1.0), panda, velocity="true")
    with pytest.raises(InputValueError, match=r"\['motor', 'joint', 'acceleration'\]"):
        observe(_log(7, tau_m=1.0), panda, kind="torque")
    with pytest.raises(InputValueError, match=r"\['auto', 'measured', 'filter', 'true'\]"):
        observe(_log(7, tau_m=1.0), panda, velocity="sensor")
    with pytest.raises(InputValueError, match="velocity='filter'"):
        observe(_log(7, tau_m=1.0, qd_true=0.0), panda, kind="acceleration", velocity="true")
    with pytest.raises(InputValueError, match=r"estimator has dt = 0\.002"):
        observe(_log(7, tau_m=1.0), panda, estimator=FiniteDifference(2e-3))
    with pytest.raises(TypeError, match="causal estimator"):
        observe(_log(7, tau_m=1.0), panda, estimator=SavitzkyGolay(1e-3, 5))  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="Log"):
        observe({"t": [0.0]}, panda)  # type: ignore[arg-type]


# --------------------------------------------------------------------------- validation


def test_momentum_observer_constructor_errors() -> None:
    robot = robots.load("planar2")
    for dt in (0.0, -1e-3, float("nan")):
        with pytest.raises(InputValueError, match="dt must be a positive"):
            MomentumObserver(robot, dt)
    for gain in (0.0, -5.0, [1.0, float("inf")]):
        with pytest.raises(InputValueError, match="gain K_I must be positive"):
            MomentumObserver(robot, 1e-3, gain=gain)
    with pytest.raises(DimensionError, match=r"gain K_I must be a scalar or have shape \(2,\)"):
        MomentumObserver(robot, 1e-3, gain=[1.0, 2.0, 3.0])
    with pytest.raises(InputValueError, match="gain K_I must be a positive number"):
        MomentumObserver(robot, 1e-3, gain="fast")
    with pytest.raises(InputValueError, match=r"torque must be one of \['motor', 'joint'\]"):
        MomentumObserver(robot, 1e-3, torque="link")
    with pytest.raises(InputValueError, match="friction must be 'model'"):
        MomentumObserver(robot, 1e-3, friction="coulomb")
    with pytest.raises(TypeError, match="friction must be"):
        MomentumObserver(robot, 1e-3, friction=3.0)
    with pytest.raises(DimensionError, match="friction model has 3 joints; the robot has 2"):
        MomentumObserver(robot, 1e-3, friction=Viscous([1.0, 2.0, 3.0]))
    with pytest.raises(TypeError, match="RobotModel"):
        MomentumObserver("planar2", 1e-3)  # type: ignore[arg-type]
    MomentumObserver(robot, 1e-3, friction=Viscous(0.5))  # one value for every joint is fine


def test_momentum_observer_run_and_step_errors() -> None:
    robot = robots.load("planar2")
    observer = MomentumObserver(robot, 1e-3)
    t = np.arange(10) * 1e-3
    q, qd, tau = np.zeros((10, 2)), np.zeros((10, 2)), np.ones((10, 2))
    with pytest.raises(DimensionError, match="use step"):
        observer.run(t[:1], q[0], qd[0], tau[0])
    with pytest.raises(DimensionError, match=r"qd must have shape \(2,\) or \(n_samples, 2\)"):
        observer.run(t, q, np.zeros((10, 3)), tau)
    with pytest.raises(DimensionError, match="tau must have 10 samples"):
        observer.run(t, q, qd, tau[:9])
    bad = qd.copy()
    bad[3, 1] = np.nan
    with pytest.raises(InputValueError, match="qd must be finite; found nan at sample 3, joint 1"):
        observer.run(t, q, bad, tau)
    with pytest.raises(DimensionError, match="t must have shape"):
        observer.run(t[:9], q, qd, tau)
    with pytest.raises(InputValueError, match=r"sampled every dt = 0\.001 s.*sample 4 to 5"):
        observer.run(np.r_[t[:5], t[5:] + 1e-4], q, qd, tau)
    with pytest.raises(DimensionError, match="q has no samples"):
        observer.run(t[:0], q[:0], qd[:0], tau[:0])
    with pytest.raises(TypeError, match="ObserverState"):
        observer.run(t, q, qd, tau, state=np.zeros(2))  # type: ignore[arg-type]
    other = MomentumObserver(robots.load("puma560"), 1e-3).initial_state(np.zeros(6))
    with pytest.raises(DimensionError, match="state is for 6 joints"):
        observer.run(t, q, qd, tau, state=other)
    with pytest.raises(DimensionError, match=r"q0 must be one sample of shape \(2,\)"):
        observer.initial_state(q)

    state = observer.initial_state(q[0])
    with pytest.raises(DimensionError, match=r"qd must be one sample of shape \(2,\)"):
        observer.step(state, q[0], qd, tau[0])
    with pytest.raises(DimensionError, match="tau must be a numeric array"):
        observer.step(state, q[0], qd[0], ["a", "b"])
    with pytest.raises(InputValueError, match="tau must be finite; found inf at joint 0"):
        observer.step(state, q[0], qd[0], [np.inf, 0.0])
    with pytest.raises(TypeError, match="ObserverState"):
        observer.step(None, q[0], qd[0], tau[0])  # type: ignore[arg-type]


def test_acceleration_observer_errors() -> None:
    robot = robots.load("planar2")
    with pytest.raises(TypeError, match="causal estimator"):
        AccelerationObserver(robot, SavitzkyGolay(1e-3, 5))  # type: ignore[arg-type]
    observer = AccelerationObserver(robot, FiniteDifference(1e-3), torque="joint")
    t = np.arange(10) * 2e-3
    with pytest.raises(InputValueError, match=r"sampled every dt = 0\.001 s"):
        observer.run(t, np.zeros((10, 2)), np.zeros((10, 2)))
    state = observer.initial_state(np.zeros(2))
    with pytest.raises(InputValueError, match="q must be finite"):
        observer.step(state, [np.nan, 0.0], np.zeros(2))
    with pytest.raises(TypeError, match="FilterState"):
        observer.step(object(), np.zeros(2), np.zeros(2))  # type: ignore[arg-type]
    with pytest.raises(InputValueError, match="torque must be one of"):
        AccelerationObserver(robot, FiniteDifference(1e-3), torque="sensor")


@pytest.mark.parametrize("name", ["", ".momentum", ".acceleration", ".observe"])
def test_module_examples(name: str) -> None:
    module = importlib.import_module(f"sensorless.observers{name}")
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0


def test_lfilter_recursion_is_the_reference_recursion() -> None:
    """The reference ``_lowpass`` used above is K_I/(s+K_I) discretised with a held input."""
    gain, dt = 7.0, 1e-2
    x = np.random.default_rng(1).standard_normal((300, 1))
    a = np.exp(-gain * dt)
    expected = signal.lfilter([0.0, 1 - a], [1.0, -a], x[:, 0])
    np.testing.assert_allclose(_lowpass(x, gain, dt, 0.0)[:-1, 0], expected, atol=1e-14)
    numerator, denominator, _ = signal.cont2discrete(([gain], [1.0, gain]), dt, method="zoh")
    np.testing.assert_allclose(numerator[0], [0.0, 1 - a], rtol=1e-12)
    np.testing.assert_allclose(denominator, [1.0, -a], rtol=1e-12)
