"""The built-in KUKA LWR IV+ against the thesis's tables (2.2-2.4, 2.7) and its scenario."""

from __future__ import annotations

import numpy as np
import pytest

import sensorless as sl
from sensorless.exceptions import InputValueError
from sensorless.identification import consistent_parameters
from sensorless.robots import lwr4 as lwr
from sensorless.simulation.model_error import is_physically_consistent
from sensorless.simulation.scenario import load_scenario


@pytest.fixture(scope="module")
def robot() -> sl.RobotModel:
    return sl.robots.load("lwr4")


@pytest.fixture(scope="module")
def base(robot: sl.RobotModel) -> sl.BaseParameters:
    return sl.base_parameters(robot, zero=lwr.ZERO)


def test_kinematics_of_table_2_4(robot: sl.RobotModel) -> None:
    """Upper arm 0.4 m and forearm 0.39 m: the wrist is 0.79 m above the shoulder at q = 0."""
    wrist = robot.link_pose(np.zeros(7), 7)[:3, 3]
    np.testing.assert_allclose(wrist, [0.0, 0.0, 0.79], atol=1e-12)
    elbow_bent = np.array([0.0, 0.0, 0.0, np.pi / 2, 0.0, 0.0, 0.0])
    elbow = robot.link_pose(elbow_bent, 4)[:3, 3]
    wrist = robot.link_pose(elbow_bent, 7)[:3, 3]
    np.testing.assert_allclose(elbow, [0.0, 0.0, 0.4], atol=1e-12)
    assert np.linalg.norm(wrist - elbow) == pytest.approx(0.39)
    assert abs(wrist[2] - 0.4) < 1e-12  # the forearm is horizontal


def test_friction_is_table_2_2_plus_table_2_3(robot: sl.RobotModel) -> None:
    assert robot.friction is not None
    up = robot.friction.torque(np.full(7, 0.5))
    down = robot.friction.torque(np.full(7, -0.5))
    np.testing.assert_allclose(up, lwr.MOTOR_COULOMB_POS + lwr.LINK_COULOMB)
    np.testing.assert_allclose(down, lwr.MOTOR_COULOMB_NEG - lwr.LINK_COULOMB)
    assert lwr.MOTOR_COULOMB_NEG[0] == -0.2591 and lwr.LINK_COULOMB[1] == 0.4561


def test_links_are_physically_consistent(robot: sl.RobotModel) -> None:
    assert is_physically_consistent(robot)
    assert (robot.standard_parameters()["m"] > 0).all()


def test_base_parameters_reproduce_table_2_7(base: sl.BaseParameters) -> None:
    """The classical parameters give the "Final Estimation" column of Table 2.7."""
    assert base.count == 25
    assert set(base.names) == set(lwr.TABLE_2_7_FINAL)
    values = dict(zip(base.names, base.values, strict=True))
    target = np.array([lwr.TABLE_2_7_FINAL[name] for name in base.names])
    got = np.array([values[name] for name in base.names])
    assert np.linalg.norm(got - target) / np.linalg.norm(target) < 1e-6
    # Largest absolute error well below the table's last printed digit (1e-4 kg m on θ1).
    assert np.max(np.abs(got - target)) < 1e-5


def test_declared_zeros_hold(robot: sl.RobotModel) -> None:
    values = dict(zip(robot.parameter_names(), robot.parameter_vector(), strict=True))
    for name in lwr.ZERO:
        assert values[name] == pytest.approx(0.0, abs=1e-9), name


def test_stored_parameters_are_the_retrieval(base: sl.BaseParameters) -> None:
    """Provenance: rerunning the retrieval from the prior gives the stored numbers."""
    prior = lwr.lwr4_prior()
    fit = consistent_parameters(
        sl.base_parameters(prior, zero=lwr.ZERO),
        [lwr.TABLE_2_7_FINAL[name] for name in base.names],
        prior=prior,
    )
    assert fit.success
    np.testing.assert_allclose(fit.parameters.to_numpy(), lwr.LINK_PARAMETERS, rtol=1e-6, atol=1e-9)


def test_scenario_nominal_models() -> None:
    """r̂ sees the links plus B_θ and the total friction; r̂_s the links and link friction."""
    scenario = load_scenario("lwr4-thesis")
    _, nominal = scenario.robots()
    motor = scenario.nominal("motor")
    joint = scenario.nominal("joint")
    feedback = np.asarray(scenario.spec["plant"]["feedback"]["motor_inertia"])
    np.testing.assert_allclose(motor.armature, feedback)
    np.testing.assert_allclose(joint.armature, 0.0)
    links = nominal.standard_parameters().drop(columns="Ia")
    for model in (motor, joint):
        np.testing.assert_allclose(model.standard_parameters().drop(columns="Ia"), links)
    assert motor.friction is not None and nominal.friction is not None
    np.testing.assert_array_equal(
        motor.friction.torque(np.ones(7)), nominal.friction.torque(np.ones(7))
    )
    # Link-side friction: Table 2.3 within the scenario's 15 % friction error, not the total.
    assert joint.friction is not None
    c_link = joint.friction.torque(np.ones(7))
    assert np.all(np.abs(c_link / lwr.LINK_COULOMB - 1) <= 0.15 + 1e-12)
    assert not np.allclose(c_link, lwr.LINK_COULOMB)
    with pytest.raises(InputValueError, match="observer kind must be motor, joint or"):
        scenario.nominal("torque")


def test_rigid_scenario_nominal_is_the_same_for_every_kind() -> None:
    scenario = load_scenario("puma560-thesis")
    nominal = scenario.robots()[1]
    for kind in ("motor", "joint", "acceleration"):
        np.testing.assert_array_equal(
            scenario.nominal(kind).parameter_vector(), nominal.parameter_vector()
        )
