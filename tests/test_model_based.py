"""Tests of :mod:`sensorless.thresholds.model_based` (thesis § 3.5, eq. 3.36/3.39).

The data are a shortened ``puma560-thesis`` run (6 s, one contact added at
3 s). τ̂_c (eq. 3.8/3.16) is computed here from the nominal model with a
5th-order Butterworth estimate of q̇ and q̈:
τ̂_c = M q̂̈ + C q̂̇ + g − τ_m + τ̂_fr.
"""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pytest

import sensorless as sl
from sensorless.exceptions import DimensionError, InputValueError, ModelError, NotFittedError
from sensorless.filters import Butterworth
from sensorless.io import Log
from sensorless.metric import parameter_bounds, q_vector
from sensorless.signals import ObserverSignals
from sensorless.simulation.scenario import Scenario, load_scenario
from sensorless.thresholds.base import load_threshold
from sensorless.thresholds.constant import ConstantThreshold
from sensorless.thresholds.model_based import ModelBasedThreshold

CONTACT_START = 3.0
CONTACT = {
    "id": 1, "link": 6, "point": [0, 0, 0.1], "direction": [1, 0, 0],
    "profile": "half_sine", "start": CONTACT_START, "duration": 0.2, "peak": 80,
}  # fmt: skip


def acceleration_signals(log: Log, nominal: sl.RobotModel) -> ObserverSignals:
    """τ̂_c of eq. 3.16 with Butterworth estimates of q̇, q̈ (no K_I: gain 1 is a placeholder)."""
    estimate, _ = Butterworth(log.dt, cutoff=20.0, order=5).filter(log.q)
    qd, qdd = estimate.velocity, estimate.acceleration
    assert log.tau_m is not None
    rigid = nominal.inverse_dynamics(log.q, qd, qdd)
    friction = nominal.friction_torque(qd)
    return ObserverSignals(
        t=log.t,
        residual=rigid - log.tau_m + friction,
        model_torque=rigid,
        friction=friction,
        sign=np.sign(qd),
        velocity=qd,
        gain=1.0,
        kind="acceleration",
        robot=nominal.name,
        position=log.q,
        acceleration=qdd,
    )


def segment(signals: ObserverSignals, start: int, stop: int, **changes: object) -> ObserverSignals:
    """Samples ``start:stop`` of a run, with some fields replaced."""
    rows = slice(start, stop)
    fields = {
        "t": signals.t[rows],
        "residual": signals.residual[rows],
        "model_torque": signals.model_torque[rows],
        "friction": signals.friction[rows],
        "sign": signals.sign[rows],
        "velocity": signals.velocity[rows],
        "gain": signals.gain,
        "kind": signals.kind,
        "robot": signals.robot,
        "position": None if signals.position is None else signals.position[rows],
        "acceleration": None if signals.acceleration is None else signals.acceleration[rows],
    }
    fields.update(changes)
    return ObserverSignals(**fields)  # type: ignore[arg-type]


def moving(signals: ObserverSignals, **changes: object) -> ObserverSignals:
    """0.6 s while the arm moves (it rests during the first 1.25 s)."""
    return segment(signals, 1500, 2100, **changes)


@pytest.fixture(scope="module")
def data() -> tuple[sl.RobotModel, ObserverSignals, ObserverSignals]:
    scenario = load_scenario("puma560-thesis")
    spec = copy.deepcopy(scenario.spec)
    spec["duration"] = 6.0
    spec["collisions"] = [CONTACT]
    short = Scenario(scenario.name, spec)
    _, nominal = short.robots()
    free = short.run(collisions=False).log
    hit = short.run(collisions=True).log
    return nominal, acceleration_signals(free, nominal), acceleration_signals(hit, nominal)


@pytest.fixture(scope="module")
def fitted(data: tuple[sl.RobotModel, ObserverSignals, ObserverSignals]) -> ModelBasedThreshold:
    nominal, free, _ = data
    return ModelBasedThreshold(nominal, btheta=0.02, margin=0.5).fit(free)


@pytest.fixture(scope="module")
def short_fit(data: tuple[sl.RobotModel, ObserverSignals, ObserverSignals]) -> ModelBasedThreshold:
    """A threshold fitted on 0.6 s of motion only (cheap to apply and refit)."""
    nominal, free, _ = data
    return ModelBasedThreshold(nominal, transient=0.05).fit(moving(free))


# ------------------------------------------------------------------------- fit and bounds


def test_no_alarm_on_fit_data(
    data: tuple[sl.RobotModel, ObserverSignals, ObserverSignals], fitted: ModelBasedThreshold
) -> None:
    _, free, _ = data
    lower, upper = fitted.bounds(free)
    assert lower.shape == upper.shape == free.residual.shape
    np.testing.assert_array_equal(lower, -upper)
    assert np.all(free.residual <= upper) and np.all(free.residual >= lower)
    # margin 0.5 N m: the closest sample is 0.5 N m inside the bound
    slack = np.min(upper - np.abs(free.residual), axis=0)
    np.testing.assert_allclose(slack, 0.5, atol=1e-6)
    # the bound follows the motion: it is not a constant
    assert np.all(np.ptp(upper, axis=0) > 0)


def test_fitted_attributes(
    data: tuple[sl.RobotModel, ObserverSignals, ObserverSignals], fitted: ModelBasedThreshold
) -> None:
    nominal, free, _ = data
    base = sl.base_parameters(nominal)
    np.testing.assert_array_equal(fitted.independent_, base.independent)
    np.testing.assert_allclose(fitted.theta_, base.values, rtol=1e-12)
    np.testing.assert_allclose(fitted.btheta_, parameter_bounds(0.02, base.values))
    assert fitted.bq_.shape == (28,) and fitted.bq_[-1] == 0.0
    assert np.all(fitted.bq_[:-1] > 0)
    assert np.all(fitted.b_fr_ >= 0.5)
    np.testing.assert_array_equal(fitted.b_d_, np.zeros(6))
    assert fitted.robot_ == nominal.name and fitted.kind_ == "acceleration"
    # the bound is the three terms of eq. 3.36 plus the constants
    piece = segment(free, 1500, 1700)
    terms = fitted.bound_terms(piece)
    _, upper = fitted.bounds(piece)
    np.testing.assert_allclose(
        upper, terms.q_error + terms.cross + terms.parameter_error + fitted.b_fr_, rtol=1e-12
    )


def test_detects_the_contact(
    data: tuple[sl.RobotModel, ObserverSignals, ObserverSignals], fitted: ModelBasedThreshold
) -> None:
    _, free, hit = data
    lower, upper = fitted.bounds(hit)
    alarm = np.any((hit.residual > upper) | (hit.residual < lower), axis=1)
    before = hit.t < CONTACT_START
    # before the contact the run is the fit run itself
    np.testing.assert_array_equal(hit.residual[before], free.residual[before])
    assert not alarm[before].any()
    during = (hit.t >= CONTACT_START) & (hit.t <= CONTACT_START + 0.3)
    assert alarm[during].any()


def test_without_error_bounds_it_is_the_constant_threshold(
    data: tuple[sl.RobotModel, ObserverSignals, ObserverSignals],
) -> None:
    """B_Q̃ = 0 and B_Θ̃ = 0 leave B_c = B_fr = max |τ̂_c|, the constant threshold of eq. 5.32."""
    nominal, free, _ = data
    part = segment(free, 1500, 1800)
    threshold = ModelBasedThreshold(nominal, btheta=0.0, bq=np.zeros(28)).fit(part)
    beta = ConstantThreshold().fit(part).beta_
    _, upper = threshold.bounds(part)
    np.testing.assert_allclose(upper, np.broadcast_to(beta, upper.shape), rtol=1e-10)


def test_disturbance_and_parameter_bounds_widen_the_threshold(
    data: tuple[sl.RobotModel, ObserverSignals, ObserverSignals], short_fit: ModelBasedThreshold
) -> None:
    nominal, free, _ = data
    part = moving(free)
    _, upper = short_fit.bounds(part)
    bigger = ModelBasedThreshold(nominal, btheta=0.1, disturbance=[1, 2, 3, 4, 5, 6], transient=0.1)
    bigger.fit(part)
    _, upper_big = bigger.bounds(part)
    # the learned B_fr absorbs what the model part does not cover, so compare model parts
    model = upper - short_fit.b_fr_
    model_big = upper_big - bigger.b_fr_ - bigger.b_d_
    assert np.all(model_big >= model)
    np.testing.assert_array_equal(bigger.b_d_, [1, 2, 3, 4, 5, 6])
    np.testing.assert_array_equal(short_fit.bq_, bigger.bq_)


def test_bounds_equal_the_split_regressor_formula(
    data: tuple[sl.RobotModel, ObserverSignals, ObserverSignals], short_fit: ModelBasedThreshold
) -> None:
    """B_c of eq. 3.36 written out with RobotModel.regressor_terms, in batch and stream."""
    nominal, free, _ = data
    part = segment(free, 1500, 1530)
    assert part.position is not None and part.acceleration is not None
    split = nominal.regressor_terms(part.position)[..., short_fit.independent_]  # (t, l, n, p)
    full = np.einsum("tl,tlnp->tnp", q_vector(part.velocity, part.acceleration), split)
    expected = (
        np.einsum("tln,l->tn", np.abs(split @ short_fit.theta_), short_fit.bq_)
        + np.einsum("tlnp,p,l->tn", np.abs(split), short_fit.btheta_, short_fit.bq_)
        + np.abs(full) @ short_fit.btheta_
        + short_fit.b_fr_
        + short_fit.b_d_
    )
    np.testing.assert_allclose(short_fit.bounds(part)[1], expected, rtol=1e-10, atol=0)
    state = short_fit.initial_state(
        part.model_torque[0], part.friction[0], part.sign[0], part.velocity[0],
        position=part.position[0], acceleration=part.acceleration[0],
    )  # fmt: skip
    for k in range(3):
        _, upper, state = short_fit.step(
            state, part.model_torque[k], part.friction[k], part.sign[k], part.velocity[k],
            position=part.position[k], acceleration=part.acceleration[k],
        )  # fmt: skip
        np.testing.assert_allclose(upper, expected[k], rtol=1e-10, atol=0)


# ------------------------------------------------------------------------- streaming


def test_step_and_process_match_bounds(
    data: tuple[sl.RobotModel, ObserverSignals, ObserverSignals], short_fit: ModelBasedThreshold
) -> None:
    _, free, _ = data
    part = segment(free, 1500, 1540)
    lower, upper = short_fit.bounds(part)
    state = short_fit.initial_state(
        part.model_torque[0], part.friction[0], part.sign[0], part.velocity[0],
        position=part.position[0], acceleration=part.acceleration[0],  # type: ignore[index]
    )  # fmt: skip
    streamed = []
    for k in range(10):
        low, up, state = short_fit.step(
            state, part.model_torque[k], part.friction[k], part.sign[k], part.velocity[k],
            position=part.position[k], acceleration=part.acceleration[k],  # type: ignore[index]
        )  # fmt: skip
        streamed.append((low, up))
    np.testing.assert_allclose(np.array([s[1] for s in streamed]), upper[:10], rtol=1e-13)
    np.testing.assert_allclose(np.array([s[0] for s in streamed]), lower[:10], rtol=1e-13)
    chunks = [slice(0, 7), slice(7, 25), slice(25, 40)]
    pieces = []
    for chunk in chunks:
        _, up, state = short_fit.process(
            state, part.model_torque[chunk], part.friction[chunk], part.sign[chunk],
            part.velocity[chunk], position=part.position[chunk],  # type: ignore[index]
            acceleration=part.acceleration[chunk],  # type: ignore[index]
        )  # fmt: skip
        pieces.append(up)
    np.testing.assert_allclose(np.vstack(pieces), upper, rtol=1e-13)


def test_chunk_size_does_not_change_bounds(
    data: tuple[sl.RobotModel, ObserverSignals, ObserverSignals], short_fit: ModelBasedThreshold
) -> None:
    _, free, _ = data
    part = segment(free, 1500, 1550)
    _, upper = short_fit.bounds(part)
    small = ModelBasedThreshold(**{**short_fit.get_params(), "chunk_size": 7})
    small.fit(moving(free))
    np.testing.assert_allclose(small.bounds(part)[1], upper, rtol=1e-12)


# ------------------------------------------------------------------------- files


def test_save_load_round_trip(
    data: tuple[sl.RobotModel, ObserverSignals, ObserverSignals],
    short_fit: ModelBasedThreshold,
    tmp_path: Path,
) -> None:
    nominal, free, _ = data
    path = short_fit.save(tmp_path / "model_based.yaml")
    text = path.read_text(encoding="utf-8")
    assert "method: model" in text and "b_fr_" in text and "standard_parameters" in text
    loaded = load_threshold(path)
    assert isinstance(loaded, ModelBasedThreshold)
    for name in ("bq_", "theta_", "independent_", "btheta_", "b_fr_", "b_d_"):
        np.testing.assert_array_equal(getattr(loaded, name), getattr(short_fit, name))
    assert loaded.independent_.dtype == np.int64
    part = segment(free, 1500, 1600)
    np.testing.assert_allclose(loaded.bounds(part)[1], short_fit.bounds(part)[1], rtol=1e-12)
    # the rebuilt robot has the same dynamics as the nominal one
    rebuilt = loaded.robot_model()
    rng = np.random.default_rng(0)
    q, qd, qdd = rng.standard_normal((3, 4, 6))
    np.testing.assert_allclose(
        rebuilt.inverse_dynamics(q, qd, qdd), nominal.inverse_dynamics(q, qd, qdd), atol=1e-9
    )
    # and it can be saved again and refitted
    again = load_threshold(loaded.save(tmp_path / "again.yaml"))
    np.testing.assert_array_equal(again.b_fr_, short_fit.b_fr_)  # type: ignore[attr-defined]
    refit = loaded.fit(moving(free))
    np.testing.assert_allclose(refit.b_fr_, short_fit.b_fr_, rtol=1e-9)  # type: ignore[attr-defined]


def test_robot_by_name() -> None:
    threshold = ModelBasedThreshold("planar2")
    assert threshold.robot_model().name == "planar2"
    assert threshold.robot_model() is threshold.robot_model()


# ------------------------------------------------------------------------- errors


def test_errors_before_fit(data: tuple[sl.RobotModel, ObserverSignals, ObserverSignals]) -> None:
    nominal, free, _ = data
    threshold = ModelBasedThreshold(nominal)
    with pytest.raises(NotFittedError, match="not fitted yet"):
        threshold.bounds(segment(free, 1500, 1510))
    with pytest.raises(NotFittedError, match="not fitted yet"):
        threshold.to_dict()


def test_missing_acceleration(
    data: tuple[sl.RobotModel, ObserverSignals, ObserverSignals], short_fit: ModelBasedThreshold
) -> None:
    nominal, free, _ = data
    no_acceleration = segment(free, 1500, 1600, acceleration=None)
    with pytest.raises(InputValueError, match="lack acceleration"):
        ModelBasedThreshold(nominal).fit(no_acceleration)
    with pytest.raises(InputValueError, match="lack acceleration"):
        short_fit.bounds(no_acceleration)
    with pytest.raises(InputValueError, match="lack position and acceleration"):
        short_fit.bounds(segment(free, 1500, 1600, acceleration=None, position=None))
    state = short_fit.initial_state(
        free.model_torque[0], free.friction[0], free.sign[0], free.velocity[0]
    )
    with pytest.raises(InputValueError, match="lack position and acceleration"):
        short_fit.step(
            state, free.model_torque[0], free.friction[0], free.sign[0], free.velocity[0]
        )


def test_wrong_joint_count(
    data: tuple[sl.RobotModel, ObserverSignals, ObserverSignals], short_fit: ModelBasedThreshold
) -> None:
    _, free, _ = data
    with pytest.raises(DimensionError, match="the nominal robot has 2 joints; fit run 0 has 6"):
        ModelBasedThreshold(sl.robots.load("planar2")).fit(segment(free, 1500, 1600))
    two = segment(
        free, 0, 100, **{name: getattr(free, name)[:100, :2] for name in (
            "residual", "model_torque", "friction", "sign", "velocity", "position", "acceleration"
        )}, gain=1.0,
    )  # fmt: skip
    with pytest.raises(DimensionError, match=r"\(6 joints\); signals come from .* \(2 joints\)"):
        short_fit.bounds(two)


def test_wrong_kind(data: tuple[sl.RobotModel, ObserverSignals, ObserverSignals]) -> None:
    nominal, free, _ = data
    with pytest.raises(InputValueError, match="must be of kind 'acceleration'; got 'motor'"):
        ModelBasedThreshold(nominal).fit(segment(free, 1500, 1600, kind="motor"))


def test_hyper_parameter_errors(
    data: tuple[sl.RobotModel, ObserverSignals, ObserverSignals],
) -> None:
    nominal, free, _ = data
    part = segment(free, 1500, 1600)
    with pytest.raises(DimensionError, match=r"bq must have shape \(28,\)"):
        ModelBasedThreshold(nominal, bq=np.zeros(3)).fit(part)
    with pytest.raises(InputValueError, match="disturbance must be finite and >= 0"):
        ModelBasedThreshold(nominal, disturbance=-1.0).fit(part)
    with pytest.raises(DimensionError, match=r"disturbance must be a scalar or have shape \(6,\)"):
        ModelBasedThreshold(nominal, disturbance=[1.0, 2.0]).fit(part)
    with pytest.raises(InputValueError, match="relative bound must be a finite number >= 0"):
        ModelBasedThreshold(nominal, btheta=-0.02).fit(part)
    with pytest.raises(InputValueError, match="reference_window must be a time"):
        ModelBasedThreshold(nominal, reference_window=0.002).fit(part)
    with pytest.raises(InputValueError, match="margin must be finite and >= 0"):
        ModelBasedThreshold(nominal, margin=-1.0).fit(part)
    with pytest.raises(TypeError, match="robot must be a RobotModel"):
        ModelBasedThreshold(3.0).fit(part)  # type: ignore[arg-type]
    with pytest.raises(ModelError, match="missing"):
        ModelBasedThreshold({"name": "x"}).robot_model()
    with pytest.raises(ModelError, match="valid types"):
        ModelBasedThreshold(
            {
                "name": "x", "gravity": [0, 0, -9.81], "standard_parameters": [0.0] * 11,
                "joints": [{"name": "j", "type": "JointModelPX", "parent": 0,
                            "rotation": np.eye(3).tolist(), "translation": [0, 0, 0]}],
            }
        ).robot_model()  # fmt: skip
