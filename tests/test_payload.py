"""Tests of the unknown payload: the simulator's payload, its estimation and the payload threshold.

Modules: :mod:`sensorless.simulation.payload`, :mod:`sensorless.identification.payload`
(with its regressor, ``_payload_regressor``) and :mod:`sensorless.thresholds.payload`.

Independent references: the observer itself run on the nominal model with
and without the payload (the difference is the payload's exact part of r̂,
computed by the full-model recursion, not by the end link's columns); the
gravity torque of a point mass through the point Jacobian; a bounded
least-squares solver (``scipy.optimize.lsq_linear``) for the m ≥ 0 fit; and
brute-force sampling of payload positions for the widening of the bounds.

The simulated runs: the shipped ``panda-gaz`` scenario with the exact model
(``Scenario.with_exact_model``, panda_gaz with its sigmoid friction, 1e-5 rad
encoders, 0.02 N m torque noise, random point-to-point motion up to 1.5 rad/s),
cut to 10 s, without contacts, observed with K_I = 20 and backward-difference
velocities (the defaults). Runs of 10 s (three) and 5 s (one): about 8 s of the test time.
"""

from __future__ import annotations

import copy
import dataclasses
import doctest
import importlib
import itertools

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.optimize import lsq_linear

import sensorless as sl
from sensorless.detection import Detector
from sensorless.exceptions import (
    DimensionError,
    FileFormatError,
    InputTypeError,
    InputValueError,
    ModelError,
    ModelMismatchError,
    NotFittedError,
)
from sensorless.identification._payload_regressor import PayloadRegressor
from sensorless.identification.payload import (
    PayloadEstimator,
    estimate_payload,
)
from sensorless.io import Log
from sensorless.monitor import CollisionMonitor, tune
from sensorless.observers import observe
from sensorless.signals import ObserverSignals
from sensorless.simulation.payload import Payload, with_payload
from sensorless.simulation.scenario import Scenario, load_scenario
from sensorless.simulation.schema import validate_scenario
from sensorless.thresholds import ConstantThreshold, TimeVariantThreshold, load_threshold
from sensorless.thresholds.payload import PayloadRange, PayloadThreshold, point_parameters

DURATION = 10.0  # s of motion: the "stated amount" of the estimation test
TUNING_SEED, SEED, OTHER_SEED = 1, 3, 5


def solid_sphere(mass: float, centre: tuple[float, float, float], radius: float) -> Payload:
    """A homogeneous ball: its matter lies within ``radius`` of its centre of mass."""
    return Payload(mass, centre, 0.4 * mass * radius**2 * np.eye(3))


PAYLOAD = solid_sphere(2.0, (0.02, -0.03, 0.10), 0.04)  # the 2 kg of the issue
HEAVIER = solid_sphere(2.5, (0.04, -0.04, 0.10), 0.03)  # m_max, at the edge of the ball
# Declared range: up to 2.5 kg inside the ball of radius 0.1 m about (0, 0, 0.08) m.
# Both payloads fit: |c − centre| + their radius = 0.081 m and 0.090 m.
MAX_MASS, CENTRE, RADIUS = 2.5, (0.0, 0.0, 0.08), 0.1
# Bound on the error of backward differences of 1e-5 rad encoder steps at 1 kHz [rad/s].
VELOCITY_ERROR = 1e-5 / 1e-3


@pytest.fixture(scope="module")
def scenario() -> Scenario:
    return load_scenario("panda-gaz").with_exact_model().with_duration(DURATION)


@pytest.fixture(scope="module")
def nominal(scenario: Scenario) -> sl.RobotModel:
    return scenario.robots()[1]


def as_spec(payload: Payload) -> dict[str, object]:
    """``payload`` as a scenario file's ``payload:`` entry."""
    i = payload.inertia
    inertia = [i[0, 0], i[0, 1], i[0, 2], i[1, 1], i[1, 2], i[2, 2]]
    return {"mass": payload.mass, "com": list(payload.com), "inertia": [float(v) for v in inertia]}


def run(scenario: Scenario, seed: int, payload: Payload | None) -> Log:
    """A collision-free run of ``scenario`` whose true robot carries ``payload``.

    The payload goes through the scenario's ``payload:`` entry, as in a file.
    """
    if payload is not None:
        scenario = Scenario(scenario.name, {**scenario.spec, "payload": as_spec(payload)})
    return scenario.run(seed=seed, collisions=False).log


@pytest.fixture(scope="module")
def loaded_log(scenario: Scenario) -> Log:
    return run(scenario, SEED, PAYLOAD)


@pytest.fixture(scope="module")
def loaded(loaded_log: Log, nominal: sl.RobotModel) -> ObserverSignals:
    return observe(loaded_log, nominal)


@pytest.fixture(scope="module")
def payload_part(loaded_log: Log, nominal: sl.RobotModel, loaded: ObserverSignals) -> np.ndarray:
    """The payload's exact part of r̂: the observer without minus with the payload in its model."""
    knowing = observe(loaded_log, with_payload(nominal, PAYLOAD))
    return loaded.residual - knowing.residual


@pytest.fixture(scope="module")
def free(scenario: Scenario, nominal: sl.RobotModel) -> ObserverSignals:
    """The same seed without the payload: the error the fit has to live with."""
    return observe(run(scenario, SEED, None), nominal)


@pytest.fixture(scope="module")
def tuning(scenario: Scenario, nominal: sl.RobotModel) -> ObserverSignals:
    return observe(run(scenario, TUNING_SEED, None), nominal)


@pytest.fixture(scope="module")
def heavier(scenario: Scenario, nominal: sl.RobotModel) -> ObserverSignals:
    return observe(run(scenario.with_duration(5.0), OTHER_SEED, HEAVIER), nominal)


def with_residual(signals: ObserverSignals, residual: np.ndarray) -> ObserverSignals:
    return dataclasses.replace(signals, residual=residual)


SERIES = ("t", "residual", "model_torque", "friction", "sign", "velocity", "position")


def rows_of(signals: ObserverSignals, rows: slice) -> ObserverSignals:
    return dataclasses.replace(signals, **{name: getattr(signals, name)[rows] for name in SERIES})


# ----------------------------------------------------------------------------- the simulator


def test_with_payload_adds_the_payload_to_the_end_link_only() -> None:
    robot = sl.robots.load("panda_gaz")
    loaded = with_payload(robot, PAYLOAD)
    grown = loaded.parameter_vector() - robot.parameter_vector()
    expected = np.zeros_like(grown)
    expected[-11:-1] = PAYLOAD.parameters()
    np.testing.assert_allclose(grown, expected, atol=1e-12)
    # The parameters are those of the body: parallel-axis theorem written out here.
    c, m = PAYLOAD.com, PAYLOAD.mass
    about_origin = PAYLOAD.inertia + m * (c @ c * np.eye(3) - np.outer(c, c))
    upper = about_origin[np.triu_indices(3)]  # xx, xy, xz, yy, yz, zz
    np.testing.assert_allclose(PAYLOAD.parameters(), [*upper, *(m * c), m], atol=1e-15)


def test_a_point_payload_adds_its_weight_through_the_point_jacobian() -> None:
    robot = sl.robots.load("panda_gaz")
    point = Payload(1.7, (0.03, 0.01, 0.12))
    q = np.random.default_rng(0).uniform(-1.0, 1.0, (5, robot.n_dof))
    added = with_payload(robot, point).gravity(q) - robot.gravity(q)
    for k in range(q.shape[0]):
        jacobian = robot.point_jacobian(q[k], robot.n_dof, point.com)[:3]
        weight = point.mass * robot.gravity_vector  # [N], in the base frame
        np.testing.assert_allclose(added[k], -jacobian.T @ weight, atol=1e-10)


def test_payload_checks_its_values() -> None:
    with pytest.raises(InputValueError, match="payload mass"):
        Payload(-1.0)
    with pytest.raises(DimensionError, match="com must have shape"):
        Payload(1.0, (0.0, 0.1))
    with pytest.raises(ModelError, match="triangle inequality"):
        Payload(1.0, inertia=np.diag([1.0, 0.1, 0.1]))
    with pytest.raises(DimensionError, match="3x3 tensor or its 6 entries"):
        Payload(1.0, inertia=[1.0, 2.0])
    with pytest.raises(InputValueError, match="unknown keys"):
        Payload.from_dict({"mass": 1.0, "centre": [0, 0, 0]})
    with pytest.raises(InputValueError, match="'mass'"):
        Payload.from_dict({"com": [0, 0, 0]})
    with pytest.raises(InputTypeError, match="payload must be a Payload"):
        with_payload(sl.robots.load("planar2"), {"mass": 1.0})  # type: ignore[arg-type]


def test_a_scenario_file_carries_a_payload() -> None:
    spec = dict(load_scenario("panda-gaz").spec)
    inertia = [1e-3, 0, 0, 1e-3, 0, 1e-3]
    spec["payload"] = {"mass": 2.0, "com": [0.02, -0.03, 0.1], "inertia": inertia}
    validate_scenario(spec)
    payload = Payload.from_dict(spec["payload"])
    np.testing.assert_allclose(payload.inertia, 1e-3 * np.eye(3))
    # On the true robot only: the nominal model does not know it.
    true, nominal = Scenario("panda-gaz", spec).robots()
    plain_true, plain_nominal = load_scenario("panda-gaz").robots()
    np.testing.assert_allclose(
        true.parameter_vector(), with_payload(plain_true, payload).parameter_vector()
    )
    np.testing.assert_array_equal(nominal.parameter_vector(), plain_nominal.parameter_vector())
    for bad, message in (
        ({"mass": -2.0}, r"payload\.mass"),
        ({"mass": 2.0, "com": [0, 0]}, r"payload\.com"),
        ({"mass": 2.0, "masss": 1.0}, r"payload\.masss: unknown key"),
    ):
        with pytest.raises(FileFormatError, match=message):
            validate_scenario({**spec, "payload": bad})


# ----------------------------------------------------------------------------- estimation


def test_mass_columns_are_the_payloads_mass_matrix() -> None:
    robot = sl.robots.load("panda_gaz")
    tilted = Payload(1.5, (0.03, -0.02, 0.11), [2e-3, 3e-4, -2e-4, 1e-3, 1e-4, 1.5e-3])
    q = np.random.default_rng(4).uniform(-2.0, 2.0, (6, robot.n_dof))
    columns = PayloadRegressor(robot).mass_columns(q)
    added = with_payload(robot, tilted).mass_matrix(q) - robot.mass_matrix(q)  # by CRBA
    np.testing.assert_allclose(columns @ tilted.parameters(), added, atol=1e-12)


def test_the_regressor_is_the_observers_payload_part(
    loaded: ObserverSignals, nominal: sl.RobotModel, payload_part: np.ndarray
) -> None:
    psi = PayloadEstimator(nominal, loaded.dt, loaded.gain).regressor(
        loaded.position, loaded.velocity
    )
    scale = np.abs(payload_part).max()
    assert scale > 5.0  # the payload is felt: about 15 N m at joint 2
    np.testing.assert_allclose(psi @ PAYLOAD.parameters(), payload_part, atol=1e-10 * scale)


def test_noise_free_residuals_give_the_payload_exactly(
    loaded: ObserverSignals, nominal: sl.RobotModel, payload_part: np.ndarray
) -> None:
    estimate = estimate_payload(with_residual(loaded, payload_part), nominal, transient=0.0)
    assert estimate.rank == 10
    assert not estimate.mass_clipped
    np.testing.assert_allclose(estimate.parameters, PAYLOAD.parameters(), rtol=0, atol=1e-8)
    assert estimate.mass == pytest.approx(PAYLOAD.mass, abs=1e-8)
    np.testing.assert_allclose(estimate.com, PAYLOAD.com, atol=1e-8)
    assert estimate.rms < 1e-9
    assert estimate.n_samples == loaded.n_samples
    assert estimate.duration == pytest.approx(loaded.n_samples * loaded.dt)


def test_a_negative_mass_is_fitted_on_the_bound(
    loaded: ObserverSignals, nominal: sl.RobotModel
) -> None:
    estimator = PayloadEstimator(nominal, loaded.dt, loaded.gain, transient=0.0)
    psi = estimator.regressor(loaded.position[:3000], loaded.velocity[:3000])
    antibody = -PAYLOAD.parameters()  # the same data with every sign flipped: m < 0
    noise = 0.05 * np.random.default_rng(2).standard_normal((3000, nominal.n_dof))
    residual = psi @ antibody + noise
    signals = with_residual(rows_of(loaded, slice(0, 3000)), residual)
    estimate = estimate_payload(signals, nominal, transient=0.0)
    assert estimate.mass_clipped and estimate.mass == 0.0
    assert np.isnan(estimate.com).all()
    # The bounded least squares of another solver, on the stacked rows.
    lower = np.full(10, -np.inf)
    lower[9] = 0.0
    reference = lsq_linear(psi.reshape(-1, 10), residual.ravel(), bounds=(lower, np.inf), tol=1e-12)
    np.testing.assert_allclose(estimate.parameters, reference.x, atol=1e-6)


def test_a_2_kg_payload_is_estimated_from_10_s_of_motion(
    loaded: ObserverSignals, free: ObserverSignals, nominal: sl.RobotModel
) -> None:
    """Mass within 5 %, centre of mass within 1 cm after 10 s of motion (9.75 s fitted).

    Why these tolerances. The fit's error is X⁺e, e the residual's error
    besides the payload's part, which has two sources:

    1. the exact model's own free-motion error (velocity by backward
       differences, encoder steps, torque noise), measured on the same motion
       without the payload: by Cauchy–Schwarz |δm| ≤ ‖X⁺_m‖‖e‖, computed
       below and ≤ 6 % of the mass (0.08–0.10 kg on seeds 3–5), the worst
       case of that error; its actual projection X⁺e is tiny (asserted
       below 0.05 % and 0.1 mm), since the error hardly correlates with the
       payload's columns;
    2. the payload's own torque seen through the velocity estimate (half a
       sample late): proportional to the payload, 0.03–0.25 % of the mass and
       at most 3.1 mm of the centre of mass on seeds 3–8 of this scenario
       (``benchmarks/payload_evidence.py``).

    5 % and 1 cm are the worst case of 1 for the mass and three times what
    2 shows for the centre of mass.
    """
    estimate = estimate_payload(loaded, nominal)
    assert estimate.duration == pytest.approx(DURATION - 0.25, abs=0.01)
    mass_error = estimate.mass - PAYLOAD.mass
    com_error = estimate.com - PAYLOAD.com
    assert abs(mass_error) <= 0.05 * PAYLOAD.mass
    assert np.abs(com_error).max() <= 0.01
    estimator = PayloadEstimator(nominal, loaded.dt, loaded.gain)
    used = loaded.t - loaded.t[0] >= estimator.transient
    psi = estimator.regressor(loaded.position, loaded.velocity)[used].reshape(-1, 10)
    inverse = np.linalg.pinv(psi)
    free_error = free.residual[used].ravel()
    assert abs(mass_error) <= np.linalg.norm(inverse[9]) * np.linalg.norm(free_error)
    assert np.linalg.norm(inverse[9]) * np.linalg.norm(free_error) <= 0.06 * PAYLOAD.mass
    projected = inverse @ free_error
    assert abs(projected[9]) <= 5e-4 * PAYLOAD.mass
    shift = (projected[6:9] - PAYLOAD.com * projected[9]) / PAYLOAD.mass
    assert np.abs(shift).max() <= 1e-4
    assert estimate.mass_std > 0 and (estimate.com_std > 0).all()
    table = estimate.to_pandas()
    assert table.loc["mass", "value"] == table.loc["m", "value"] == estimate.mass
    assert table.loc["com_z", "std"] == estimate.com_std[2]


def test_the_stream_equals_the_batch(loaded: ObserverSignals, nominal: sl.RobotModel) -> None:
    part = rows_of(loaded, slice(0, 4000))
    batch = estimate_payload(part, nominal, block=0.1)
    estimator = PayloadEstimator(nominal, loaded.dt, loaded.gain, block=0.1)
    q, qd, r = part.position, part.velocity, part.residual
    assert q is not None
    state = estimator.initial_state(q[0], qd[0])
    edges = [0, 1, 250, 251, 777, 2000, 3999, 4000]
    for a, b in itertools.pairwise(edges):
        if b - a == 1:
            state = estimator.step(state, q[a], qd[a], r[a])
        else:
            state = estimator.process(state, q[a:b], qd[a:b], r[a:b])
    stream = estimator.estimate(state)
    np.testing.assert_allclose(stream.parameters, batch.parameters, rtol=0, atol=1e-9)
    # Entries near zero carry the round-off of the whole matrix: absolute tolerance to its scale.
    scale = np.abs(batch.covariance).max()
    np.testing.assert_allclose(stream.covariance, batch.covariance, rtol=1e-9, atol=1e-10 * scale)
    assert (stream.n_samples, stream.n_blocks) == (batch.n_samples, batch.n_blocks) == (3750, 38)


def test_runs_are_pooled(loaded: ObserverSignals, nominal: sl.RobotModel) -> None:
    halves = [rows_of(loaded, slice(0, 5000)), rows_of(loaded, slice(5000, None))]
    pooled = estimate_payload(halves, nominal)
    # The same rows as one estimator that starts an observer at each half.
    estimator = PayloadEstimator(nominal, loaded.dt, loaded.gain)
    state = None
    for half in halves:
        assert half.position is not None
        state = estimator.initial_state(half.position[0], half.velocity[0], pooled=state)
        state = estimator.process(state, half.position, half.velocity, half.residual)
    assert state is not None
    np.testing.assert_allclose(pooled.parameters, estimator.estimate(state).parameters, atol=1e-9)
    assert pooled.n_samples == sum(half.n_samples - 250 for half in halves)


def test_estimation_refuses_bad_input(loaded: ObserverSignals, nominal: sl.RobotModel) -> None:
    with pytest.raises(InputValueError, match="kind 'motor' or 'joint'"):
        estimate_payload(dataclasses.replace(loaded, kind="acceleration"), nominal)
    with pytest.raises(InputValueError, match="with positions"):
        estimate_payload(dataclasses.replace(loaded, position=None), nominal)
    with pytest.raises(ModelMismatchError, match="nominal model the observer used"):
        estimate_payload(loaded, with_payload(nominal, PAYLOAD))
    with pytest.raises(DimensionError, match="joints"):
        estimate_payload(loaded, sl.robots.load("puma560"))
    with pytest.raises(InputTypeError, match="signals must be an ObserverSignals"):
        estimate_payload([loaded.residual], nominal)  # type: ignore[list-item]
    with pytest.raises(InputValueError, match="at least one run"):
        estimate_payload([], nominal)
    with pytest.raises(InputValueError, match="joints must be"):
        PayloadEstimator(nominal, 1e-3, joints=[0, 8])
    with pytest.raises(InputValueError, match="block"):
        PayloadEstimator(nominal, 1e-3, block=0.0)
    with pytest.raises(InputValueError, match="transient"):
        PayloadEstimator(nominal, 1e-3, transient=-1.0)
    estimator = PayloadEstimator(nominal, 1e-3)
    state = estimator.initial_state(np.zeros(7))
    with pytest.raises(InputValueError, match="no sample is in the fit"):
        estimator.estimate(estimator.step(state, np.zeros(7), np.zeros(7), np.zeros(7)))
    with pytest.raises(DimensionError, match="step takes one sample"):
        estimator.step(state, np.zeros((2, 7)), np.zeros((2, 7)), np.zeros((2, 7)))
    with pytest.raises(DimensionError, match="same number of samples"):
        estimator.process(state, np.zeros((3, 7)), np.zeros((2, 7)), np.zeros((3, 7)))
    with pytest.raises(InputTypeError, match="state must be an EstimatorState"):
        estimator.estimate(None)  # type: ignore[arg-type]
    irregular = dataclasses.replace(loaded, t=loaded.t * (1 + 1e-3 * (loaded.t > 5)))
    with pytest.raises(InputValueError, match="not regularly sampled"):
        estimate_payload(irregular, nominal)


# ----------------------------------------------------------------------------- the threshold


def declared(threshold: sl.thresholds.Threshold, nominal: sl.RobotModel) -> PayloadThreshold:
    return PayloadThreshold(
        threshold,
        nominal,
        MAX_MASS,
        center=CENTRE,
        radius=RADIUS,
        velocity_error=VELOCITY_ERROR,
    )


def demo_margin(tuning: ObserverSignals) -> np.ndarray:
    """The margin of ``tune`` by default: 10 % of the constant band β of each joint."""
    return np.asarray(0.1 * ConstantThreshold(transient=0.25).fit(tuning).beta_)


@pytest.mark.parametrize(
    "region", [{"radius": RADIUS}, {"half_widths": (RADIUS, RADIUS, RADIUS)}], ids=["ball", "box"]
)
def test_the_widening_bounds_the_payloads_residual(
    tuning: ObserverSignals,
    loaded: ObserverSignals,
    nominal: sl.RobotModel,
    payload_part: np.ndarray,
    region: dict[str, object],
) -> None:
    plain = ConstantThreshold(margin=0.5).fit(tuning)
    widened = PayloadThreshold.from_fitted(plain, nominal, MAX_MASS, center=CENTRE, **region)
    lower0, upper0 = plain.bounds(loaded)
    lower, upper = widened.bounds(loaded)
    below, above = lower - lower0, upper - upper0
    assert (below <= payload_part + 1e-12).all() and (payload_part <= above + 1e-12).all()
    # How tight the widening is: test_torque_range_against_brute_force.


def test_the_velocity_term_covers_the_payload_seen_with_the_true_velocity(
    tuning: ObserverSignals, loaded_log: Log, loaded: ObserverSignals, nominal: sl.RobotModel
) -> None:
    """The observer's payload part is Ψ(q, q̇)π with the true q̇; the widening sees q̂̇.

    With δ the largest |q̂̇ − q̇| of the run per joint, the velocity term covers
    the difference: the widening holds the payload part of observers run on
    the true velocity (the simulator's ``qd_true``).
    """
    with_truth = [
        observe(loaded_log, model, velocity="true").residual
        for model in (nominal, with_payload(nominal, PAYLOAD))
    ]
    true_part = with_truth[0] - with_truth[1]
    error = np.abs(loaded.velocity - np.asarray(loaded_log.qd_true)).max(axis=0)
    assert 0.5 * VELOCITY_ERROR < error.max() < 2 * VELOCITY_ERROR
    plain = ConstantThreshold(margin=0.5).fit(tuning)
    lower0, upper0 = plain.bounds(loaded)
    for delta, covered in ((error, True), (0.0, False)):
        widened = PayloadThreshold.from_fitted(
            plain, nominal, MAX_MASS, center=CENTRE, radius=RADIUS, velocity_error=delta
        )
        lower, upper = widened.bounds(loaded)
        inside = (lower - lower0 <= true_part + 1e-12) & (true_part <= upper - upper0 + 1e-12)
        assert inside.all() == covered


def test_a_declared_payload_raises_no_false_alarm(
    tuning: ObserverSignals,
    loaded: ObserverSignals,
    heavier: ObserverSignals,
    free: ObserverSignals,
    nominal: sl.RobotModel,
) -> None:
    """Tuned as ``tune`` tunes (margin 10 % of β, 0.25 s transient), on a payload-free run.

    The plain thresholds alarm on both payload runs (2 kg, and 2.5 kg at the
    edge of the declared ball for 5 s), the declared ones on neither. Without
    ``velocity_error`` the declared ones alarm on joint 1 (0.1-0.2 N m
    beyond): the payload's share of the velocity estimate's error
    (``test_the_velocity_term_covers_...``).
    """
    margin = demo_margin(tuning)
    for family in (
        ConstantThreshold(margin=margin, transient=0.25),
        TimeVariantThreshold(margin=margin, transient=0.25),
    ):
        plain = Detector(family.fit(tuning), min_duration=0.005, hold=0.05)
        widened = Detector(declared(family, nominal).fit(tuning), min_duration=0.005, hold=0.05)
        assert plain.detect(free) == []  # the plain threshold is sound without a payload
        for run in (loaded, heavier):
            assert len(plain.detect(run)) > 0
            assert widened.detect(run) == []


def test_threshold_stream_equals_batch(
    tuning: ObserverSignals, loaded: ObserverSignals, nominal: sl.RobotModel
) -> None:
    widened = declared(TimeVariantThreshold(margin=0.5), nominal).fit(tuning)
    lower, upper = widened.bounds(rows_of(loaded, slice(0, 1500)))
    p = loaded.position
    assert p is not None
    inputs = (loaded.model_torque, loaded.friction, loaded.sign, loaded.velocity)
    state = widened.initial_state(*(x[0] for x in inputs), position=p[0], dt=loaded.dt)
    rows: list[tuple[np.ndarray, np.ndarray]] = []
    for k in range(200):
        low, high, state = widened.step(state, *(x[k] for x in inputs), position=p[k])
        rows.append((low, high))
    chunk = slice(200, 1500)
    low, high, state = widened.process(state, *(x[chunk] for x in inputs), position=p[chunk])
    stream_lower = np.vstack([np.array([r[0] for r in rows]), low])
    stream_upper = np.vstack([np.array([r[1] for r in rows]), high])
    np.testing.assert_allclose(stream_lower, lower, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(stream_upper, upper, rtol=1e-12, atol=1e-12)


def test_torque_range_against_brute_force() -> None:
    rng = np.random.default_rng(7)
    psi = rng.normal(size=(40, 10)) * np.r_[np.full(6, 3.0), np.full(3, 10.0), 10.0]
    centre = np.array([0.01, -0.02, 0.08])
    unit = rng.normal(size=(4000, 3))
    unit /= np.linalg.norm(unit, axis=1, keepdims=True)
    ball = np.vstack([unit, unit * rng.uniform(0, 1, (4000, 1)) ** (1 / 3)]) * 0.1
    h = np.array([0.05, 0.03, 0.1])
    corners = np.array(np.meshgrid(*[[-1, 1]] * 3)).reshape(3, -1).T * h
    box = np.vstack([corners, rng.uniform(-1, 1, (4000, 3)) * h])
    for region, offsets, eigenvalues in (
        (PayloadRange(2.0, centre, radius=0.1), ball, True),
        (PayloadRange(2.0, centre, radius=0.1), ball, False),
        (PayloadRange(2.0, centre, half_widths=h), box, True),
    ):
        low, high = region.torque_range(psi, eigenvalues=eigenvalues)
        values = 2.0 * psi @ np.array([point_parameters(centre + u) for u in offsets]).T
        sampled_low = np.minimum(values.min(axis=1), 0.0)
        sampled_high = np.maximum(values.max(axis=1), 0.0)
        assert (low <= sampled_low + 1e-12).all() and (sampled_high <= high + 1e-12).all()
        # Loose only by the quadratic (inertial) part: at most 2 m_max Σ|A_ik| h_i h_k.
        # (Gershgorin's discs are within the same Σ|A_ik| of the spectrum.)
        quad_scale = 2.0 * np.abs(psi[:, :6]).sum(axis=1) * (0.1**2 if offsets is ball else h @ h)
        assert (sampled_low - low <= 2 * quad_scale + 1e-9).all()
        assert (high - sampled_high <= 2 * quad_scale + 1e-9).all()
    # Without inertial columns the ball bound is exact: the point centre ± r b/|b|.
    linear = psi.copy()
    linear[:, :6] = 0.0
    low, high = PayloadRange(2.0, centre, radius=0.1).torque_range(linear)
    slope = np.linalg.norm(linear[:, 6:9], axis=1)
    at_centre = linear[:, 6:9] @ centre + linear[:, 9]
    np.testing.assert_allclose(high, 2.0 * np.maximum(at_centre + 0.1 * slope, 0), atol=1e-12)
    np.testing.assert_allclose(low, 2.0 * np.minimum(at_centre - 0.1 * slope, 0), atol=1e-12)


def test_threshold_refuses_bad_input(
    tuning: ObserverSignals, loaded: ObserverSignals, nominal: sl.RobotModel
) -> None:
    base = ConstantThreshold(margin=0.5)
    with pytest.raises(NotFittedError, match="not fitted"):
        declared(base, nominal).bounds(loaded)
    with pytest.raises(NotFittedError, match="not fitted"):
        PayloadThreshold.from_fitted(base, nominal, 1.0)
    with pytest.raises(InputValueError, match=r"radius .* or half_widths"):
        PayloadThreshold(base, nominal, 1.0, radius=0.1, half_widths=(0.1, 0.1, 0.1)).fit(tuning)
    with pytest.raises(InputValueError, match="max_mass"):
        PayloadThreshold(base, nominal, -1.0).fit(tuning)
    with pytest.raises(DimensionError, match="center must have shape"):
        PayloadThreshold(base, nominal, 1.0, center=(0.0, 0.1)).fit(tuning)
    with pytest.raises(InputValueError, match="half_widths must be >= 0"):
        PayloadThreshold(base, nominal, 1.0, half_widths=(0.1, -0.1, 0.1)).fit(tuning)
    with pytest.raises(ModelMismatchError, match="observer's model"):
        PayloadThreshold(base, with_payload(nominal, PAYLOAD), 1.0).fit(tuning)
    with pytest.raises(InputTypeError, match="threshold must be a Threshold"):
        PayloadThreshold("constant", nominal, 1.0).fit(tuning)  # type: ignore[arg-type]
    widened = declared(base, nominal).fit(tuning)
    with pytest.raises(InputValueError, match="needs the joint positions"):
        widened.bounds(dataclasses.replace(loaded, position=None))
    assert widened.monitored_joints_ == tuple(range(1, 8))


# ----------------------------------------------------------------------------- the file


def test_a_saved_payload_threshold_gives_the_same_bounds(
    tuning: ObserverSignals, loaded: ObserverSignals, nominal: sl.RobotModel, tmp_path
) -> None:
    """A box range and a ball range survive the file: bounds equal bit for bit."""
    box = PayloadThreshold(
        TimeVariantThreshold(margin=0.5), nominal, MAX_MASS, center=CENTRE,
        half_widths=(0.05, 0.04, 0.1), velocity_error=VELOCITY_ERROR,
    ).fit(tuning)  # fmt: skip
    for widened in (declared(ConstantThreshold(margin=0.5), nominal).fit(tuning), box):
        path = widened.save(tmp_path / "payload.yaml")
        read = load_threshold(path, robot=nominal)
        assert isinstance(read, PayloadThreshold)
        assert read.to_dict() == widened.to_dict()
        for got, want in zip(read.bounds(loaded), widened.bounds(loaded), strict=True):
            np.testing.assert_array_equal(got, want)
        lower, upper = widened.threshold_.bounds(loaded)
        assert (read.bounds(loaded)[0] <= lower).all() and (read.bounds(loaded)[1] >= upper).all()


def test_a_payload_file_reads_its_nominal_model(
    tuning: ObserverSignals, loaded_log: Log, nominal: sl.RobotModel, tmp_path
) -> None:
    """The built-in model of the file's name and fingerprint, or the one given; no other."""
    path = declared(ConstantThreshold(margin=0.5), nominal).fit(tuning).save(tmp_path / "a.yaml")
    assert nominal.fingerprint == sl.robots.load(nominal.name).fingerprint  # the exact model
    read = load_threshold(path)
    assert isinstance(read, PayloadThreshold) and read.robot.fingerprint == nominal.fingerprint
    # A model with other parameters under the same name: not a built-in one.
    other = with_payload(nominal, HEAVIER)
    signals = observe(loaded_log.slice(0, 1.5), other)
    path = declared(ConstantThreshold(margin=0.5), other).fit(signals).save(tmp_path / "b.yaml")
    with pytest.raises(ModelMismatchError, match=r"not a built-in robot .* robot="):
        load_threshold(path)
    with pytest.raises(ModelMismatchError, match="fitted with the nominal model"):
        load_threshold(path, robot=nominal)
    read = load_threshold(path, robot=other)
    assert isinstance(read, PayloadThreshold) and read.robot is other


def test_a_broken_payload_file_lists_every_problem(
    tuning: ObserverSignals, nominal: sl.RobotModel
) -> None:
    data = declared(ConstantThreshold(margin=0.5), nominal).fit(tuning).to_dict()
    data["params"] = {**data["params"], "max_mass": -1.0, "center": [0.0, 0.1]}
    data["attributes"] = {"threshold": data["attributes"]["threshold_"]}
    with pytest.raises(FileFormatError) as info:
        PayloadThreshold.from_dict(data, robot=nominal)
    message = str(info.value)
    for path in ("params.max_mass", "params.center", "attributes.threshold:", "threshold_"):
        assert path in message, message
    wrapped = declared(ConstantThreshold(margin=0.5), nominal).fit(tuning).to_dict()
    wrapped["attributes"]["threshold_"]["n_dof"] = 6
    with pytest.raises(FileFormatError, match=r"attributes\.threshold_"):
        PayloadThreshold.from_dict(wrapped, robot=nominal)


def _paths(value: object, prefix: tuple = ()) -> list[tuple]:
    """Every key path (mappings and lists) of a file's content."""
    found = [prefix] if prefix else []
    if isinstance(value, dict):
        return found + [p for k, v in value.items() for p in _paths(v, (*prefix, k))]
    if isinstance(value, list):
        return found + [p for i, v in enumerate(value) for p in _paths(v, (*prefix, i))]
    return found


JUNK = st.sampled_from(["text", None, [], {}, -1.0, float("nan"), float("inf"), True, [1.0]])


@settings(
    max_examples=120, deadline=None, derandomize=True,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)  # fmt: skip
@given(data=st.data())
def test_a_mutated_payload_file_is_refused_clearly_or_read_whole(
    tuning: ObserverSignals, loaded: ObserverSignals, nominal: sl.RobotModel, data: st.DataObject
) -> None:
    """Fail-safe reading: one key dropped or replaced by junk gives a clear error, else a
    threshold whose bounds contain the wrapped threshold's (the widening is never negative)."""
    original = declared(ConstantThreshold(margin=0.5), nominal).fit(tuning).to_dict()
    mutated = copy.deepcopy(original)
    path = data.draw(st.sampled_from(_paths(original)))
    parent = mutated
    for key in path[:-1]:
        parent = parent[key]
    if data.draw(st.booleans()) and isinstance(parent, dict):
        del parent[path[-1]]
    else:
        parent[path[-1]] = data.draw(JUNK)
    try:
        read = PayloadThreshold.from_dict(mutated, robot=nominal)
    except ModelMismatchError:
        assert path[0] in ("robot", "fingerprint"), path  # another model: refused as such
        return
    except FileFormatError as error:  # the message names the field or an entry holding it
        names = [
            "".join(f"[{k}]" if isinstance(k, int) else f".{k}" for k in path[:n]).lstrip(".")
            for n in range(len(path), 0, -1)
        ]
        assert any(name in str(error) for name in names), (path, str(error))
        return
    part = rows_of(loaded, slice(0, 300))
    lower, upper = read.bounds(part)
    inner_lower, inner_upper = read.threshold_.bounds(part)
    assert (lower <= inner_lower).all() and (upper >= inner_upper).all()


@pytest.mark.parametrize(
    "module", ["simulation.payload", "identification.payload", "thresholds.payload"]
)
def test_doctests(module: str) -> None:
    result = doctest.testmod(importlib.import_module(f"sensorless.{module}"))
    assert result.attempted > 0 and result.failed == 0


def test_tune_with_a_declared_payload(scenario: Scenario, loaded_log: Log) -> None:
    """``tune(payload=...)``: the monitor raises no alarm on the 2 kg run; plain, it does."""
    free_log = run(scenario.with_duration(4.0), TUNING_SEED, None)
    nominal = scenario.robots()[1]
    declared = {"max_mass": MAX_MASS, "center": CENTRE, "radius": RADIUS}
    plain, settings = tune([free_log], nominal, "constant", folds=None)
    widened, _ = tune(
        [free_log], nominal, "constant", folds=None,
        payload={**declared, "velocity_error": VELOCITY_ERROR},
    )  # fmt: skip
    assert isinstance(widened, PayloadThreshold)
    assert CollisionMonitor(nominal, plain, settings).process(loaded_log).events
    assert CollisionMonitor(nominal, widened, settings).process(loaded_log).events == []
    with pytest.raises(InputValueError, match="not with false_alarm_rate"):
        tune([free_log], nominal, "constant", false_alarm_rate=1.0, payload=declared)
