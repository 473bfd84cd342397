"""Offset and friction of a nominal model identified from logs (identification/correction.py).

The logs are synthetic: the torque is the rigid-body torque of the robot's
own model along an analytic trajectory (exact q̇, q̈), plus a known
asymmetric Coulomb + viscous friction, a known constant offset and, where
stated, seeded noise. The fit must give back the generating parameters.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import sensorless as sl
from sensorless.exceptions import DimensionError, InputTypeError, InputValueError
from sensorless.friction import CoulombViscous
from sensorless.identification import NominalCorrection, identify_correction
from sensorless.identification.correction import model_error
from sensorless.io import Log

C_POS = np.array([6.0, 4.0, 2.5, 1.2, 0.8, 0.5])
C_NEG = np.array([-5.0, -6.0, -1.5, -1.0, -0.9, -0.3])
FV = np.array([12.0, 9.0, 4.0, 1.5, 1.0, 0.6])
OFFSET = np.array([-2.0, 1.5, 3.0, -0.4, 0.7, -0.2])
FRICTION = CoulombViscous(C_POS, C_NEG, FV)
POSE = np.array([0.3, -1.2, 1.0, -0.5, 0.4, 0.2])


@pytest.fixture(scope="module")
def robot() -> sl.RobotModel:
    return sl.robots.load("ur10")


def measured(
    robot: sl.RobotModel,
    t: np.ndarray,
    q: np.ndarray,
    qd: np.ndarray,
    qdd: np.ndarray,
    noise: float = 0.0,
    seed: int = 0,
) -> Log:
    """The log a real arm with FRICTION and OFFSET would record (noise [N m], seeded)."""
    tau = robot.inverse_dynamics(q, qd, qdd) + FRICTION.torque(qd) + OFFSET
    tau += noise * np.random.default_rng(seed).standard_normal(tau.shape)
    return Log(t, q, qd=qd, tau_m=tau)


def standing(robot: sl.RobotModel, seconds: float, dt: float = 0.01, **noise: float) -> Log:
    t = np.arange(0.0, seconds, dt)
    q = np.tile(POSE, (t.size, 1))
    zero = np.zeros_like(q)
    return measured(robot, t, q, zero, zero, **noise)


def swinging(robot: sl.RobotModel, seconds: float = 8.0, dt: float = 0.01, **noise: float) -> Log:
    """Every joint swings both ways: q = POSE + a sin(w t), with exact derivatives."""
    t = np.arange(0.0, seconds, dt)[:, None]
    amplitude = np.array([0.6, 0.4, 0.5, 0.8, 0.8, 1.0])
    omega = np.array([0.8, 1.0, 1.2, 1.5, 1.7, 2.0])
    q = POSE + amplitude * np.sin(omega * t)
    qd = amplitude * omega * np.cos(omega * t)
    qdd = -amplitude * omega**2 * np.sin(omega * t)
    return measured(robot, t[:, 0], q, qd, qdd, **noise)


def test_fit_recovers_the_generating_offset_and_friction(robot: sl.RobotModel) -> None:
    logs = [standing(robot, 2.0, noise=0.05, seed=1), swinging(robot, noise=0.05, seed=2)]
    correction = identify_correction(logs, robot)
    np.testing.assert_allclose(correction.offset, OFFSET, atol=0.02)
    np.testing.assert_allclose(correction.friction.c_pos, C_POS, rtol=0.03, atol=0.05)
    np.testing.assert_allclose(correction.friction.c_neg, C_NEG, rtol=0.03, atol=0.05)
    np.testing.assert_allclose(correction.friction.fv, FV, rtol=0.03, atol=0.05)


def test_without_rest_the_offset_shifts_both_coulomb_levels(robot: sl.RobotModel) -> None:
    # τ_fr + o = (C+ + o) at q̇ > 0 and (C− + o) at q̇ < 0: the fit can only see those sums,
    # where they keep the signs C+ >= 0, C− <= 0 demand (joint 3's C− + o > 0 does not).
    correction = identify_correction([swinging(robot)], robot)
    friction = correction.friction
    np.testing.assert_array_equal(correction.offset, 0.0)
    free = (C_POS + OFFSET >= 0) & (C_NEG + OFFSET <= 0)
    assert free.tolist() == [True, True, False, True, True, True]
    np.testing.assert_allclose(friction.c_pos[free], (C_POS + OFFSET)[free], atol=0.02)
    np.testing.assert_allclose(friction.c_neg[free], (C_NEG + OFFSET)[free], atol=0.02)
    np.testing.assert_allclose(friction.fv[free], FV[free], rtol=0.01)
    assert friction.c_neg[2] == pytest.approx(0.0, abs=1e-12)  # at its bound


def test_a_joint_seen_in_one_direction_gets_the_mirror_level(robot: sl.RobotModel) -> None:
    # Joint 6 turns at +0.3 rad/s only; joints 1-5 stand. A second log shows them all at rest.
    t = np.arange(0.0, 3.0, 0.01)
    q = np.tile(POSE, (t.size, 1))
    qd = np.zeros_like(q)
    qd[:, 5] = 0.3
    q[:, 5] += 0.3 * t
    logs = [standing(robot, 1.0), measured(robot, t, q, qd, np.zeros_like(q))]
    friction = identify_correction(logs, robot).friction
    assert friction.c_pos[5] + 0.3 * friction.fv[5] == pytest.approx(C_POS[5] + 0.3 * FV[5])
    assert friction.c_neg[5] == -friction.c_pos[5]
    # The joints that never moved get no friction.
    assert (friction.c_pos[:5] == 0).all() and (friction.c_neg[:5] == 0).all()
    assert (friction.fv[:5] == 0).all()


@pytest.mark.parametrize(("seconds", "expected"), [(0.6, OFFSET), (0.4, np.zeros(6))])
def test_an_offset_needs_min_time_at_rest_at_any_sample_rate(
    robot: sl.RobotModel, seconds: float, expected: np.ndarray
) -> None:
    # 1 kHz: the time at rest counts in seconds, not samples (the 0.1 s window's ends are cut).
    rest = standing(robot, seconds + 0.1, dt=0.001)
    correction = identify_correction([rest], robot, min_time=0.5)
    np.testing.assert_allclose(correction.offset, expected, atol=1e-9)


def test_model_error_is_the_generated_friction_and_offset(robot: sl.RobotModel) -> None:
    log = swinging(robot, seconds=3.0)
    error, velocity, period = model_error([log], robot, window=0.1)
    half = 5  # 11 samples in 0.1 s at 100 Hz: 5 dropped at each end
    assert error.shape == velocity.shape == (log.n_samples - 2 * half, 6)
    np.testing.assert_array_equal(velocity, log.qd[half:-half])
    np.testing.assert_allclose(period, 0.01)
    # Savitzky–Golay q̈ of a smooth swing is close to the exact one.
    expected = FRICTION.torque(velocity) + OFFSET
    np.testing.assert_allclose(error, expected, atol=0.05)


def test_the_correction_applies_to_the_model_and_the_log(robot: sl.RobotModel) -> None:
    correction = NominalCorrection(FRICTION, OFFSET)
    model = correction.model(robot)
    qd = np.linspace(-1.0, 1.0, 7)[:, None] * np.ones(6)
    np.testing.assert_allclose(model.friction_torque(qd), FRICTION.torque(qd))
    np.testing.assert_allclose(
        model.inverse_dynamics(POSE, qd[0], qd[0]), robot.inverse_dynamics(POSE, qd[0], qd[0])
    )
    log = standing(robot, 1.0)
    applied = correction.apply(log)
    np.testing.assert_allclose(applied.tau_m, log.tau_m - OFFSET)
    assert applied.metadata["tau_m_offset"] == pytest.approx(OFFSET.tolist())
    table = correction.to_pandas()
    assert list(table.index) == [1, 2, 3, 4, 5, 6]
    np.testing.assert_array_equal(table["offset [N m]"], OFFSET)


def test_bad_inputs_are_refused_with_what_was_expected(robot: sl.RobotModel) -> None:
    log = standing(robot, 1.0)
    with pytest.raises(InputValueError, match="non-empty sequence of Log"):
        identify_correction([], robot)
    with pytest.raises(InputValueError, match="non-empty sequence of Log"):
        identify_correction(log, robot)  # type: ignore[arg-type]
    with pytest.raises(InputTypeError, match="robot must be a RobotModel"):
        identify_correction([log], "ur10")  # type: ignore[arg-type]
    no_velocity = dataclasses.replace(log, qd=None)
    with pytest.raises(InputValueError, match=r"logs\[0\] must hold the measured velocity qd"):
        identify_correction([no_velocity], robot)
    with pytest.raises(DimensionError, match=r"logs\[0\] has 6 joints; robot 'planar2'"):
        identify_correction([log], sl.robots.load("planar2"))
    with pytest.raises(InputValueError, match=r"the 0\.5 s window needs more than"):
        identify_correction([log.slice(0.0, 0.3)], robot, window=0.5)
    with pytest.raises(InputValueError, match=r"resting must be a finite number > 0 \[rad/s\]"):
        identify_correction([log], robot, resting=0.0)
    with pytest.raises(InputValueError, match="min_time must be a finite number of seconds"):
        identify_correction([log], robot, min_time=-1.0)
    with pytest.raises(DimensionError, match=r"offset must be a scalar or have shape \(6,\)"):
        NominalCorrection(FRICTION, [1.0, 2.0])
    with pytest.raises(InputTypeError, match="friction must be a CoulombViscous"):
        NominalCorrection(None, OFFSET)  # type: ignore[arg-type]
    correction = NominalCorrection(FRICTION, OFFSET)
    with pytest.raises(InputValueError, match="no motor torques tau_m"):
        correction.apply(dataclasses.replace(log, tau_m=None))
    with pytest.raises(DimensionError, match="the correction has 6 joints; robot 'planar2'"):
        correction.model(sl.robots.load("planar2"))
