"""Fast simulator paths against their references (issue 14).

The implicit spring step of flexible joints and the rewritten RK4 of rigid
joints are checked against RK4 at a much finer step; the unchecked inner-loop
paths (held friction, encoder reader) against the checked public ones.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import sensorless as sl
from sensorless.exceptions import InputValueError
from sensorless.friction import LuGre
from sensorless.simulation.controllers import JointPID
from sensorless.simulation.plants import FlexiblePlant, TorqueFeedback
from sensorless.simulation.scenario import load_scenario
from sensorless.simulation.sensors import SensorModel
from sensorless.simulation.simulator import simulate
from sensorless.trajectories import QuinticViaPoints


def _planar_flexible(feedback: TorqueFeedback | None, integrator: str) -> FlexiblePlant:
    planar = sl.robots.load("planar2")
    pi = planar.parameter_vector().reshape(2, 11)
    pi[:, 10] = [0.5, 0.3]
    robot = planar.with_standard_parameters(pi)
    return FlexiblePlant(
        robot, stiffness=3e5, damping=5.0, feedback=feedback, integrator=integrator
    )


def _planar_run(plant: FlexiblePlant, substeps: int) -> sl.io.Log:
    trajectory = QuinticViaPoints([0.0, 0.5, 1.0], np.array([[0.0, 0.0], [0.8, -1.0], [0.0, 0.0]]))
    controller = JointPID(kp=[400.0, 200.0], ki=0.0, kd=[40.0, 20.0], model=plant.robot)
    return simulate(plant, controller, trajectory, 1.0, substeps=substeps).log


@pytest.mark.parametrize("feedback", [None, TorqueFeedback([0.1, 0.05], [2.0, 1.0])])
def test_implicit_spring_step_converges_to_fine_rk4_at_second_order(feedback) -> None:
    reference = _planar_run(_planar_flexible(feedback, "rk4"), substeps=200)
    errors = []
    for substeps in (1, 2, 4):
        log = _planar_run(_planar_flexible(feedback, "rosenbrock"), substeps)
        errors.append(np.abs(log.q_true - reference.q_true).max())
        assert log.tau_j is not None and reference.tau_j is not None
        # Joint torque within 0.1 % of its range, positions within a microradian.
        scale = np.abs(reference.tau_j).max()
        assert np.abs(log.tau_j - reference.tau_j).max() < 1e-3 * scale
    assert errors[0] < 1e-6
    # Halving the step divides the error by about four: a second-order method.
    assert errors[0] / errors[1] > 3.0
    assert errors[1] / errors[2] > 3.0


def _lwr(duration: float, **plant: object) -> dict[str, object]:
    kwargs = load_scenario("lwr4-thesis").with_duration(duration).build()
    # Coulomb friction at rest chatters at the step of any explicit evaluation;
    # without it the two integrators solve the same smooth problem.
    changes = {"link_friction": None, "motor_friction": None, **plant}
    kwargs["plant"] = dataclasses.replace(kwargs["plant"], **changes)
    kwargs["sensors"] = SensorModel()
    return kwargs


def test_lwr_implicit_step_needs_few_substeps_and_matches_rk4() -> None:
    fast = simulate(**_lwr(0.4))
    reference = simulate(**_lwr(0.4, integrator="rk4"), substeps=40)
    assert fast.substeps <= 3 < reference.substeps
    assert fast.log.tau_j is not None and reference.log.tau_j is not None
    assert np.abs(fast.log.q_true - reference.log.q_true).max() < 1e-4
    scale = np.abs(reference.log.tau_j).max()
    assert np.abs(fast.log.tau_j - reference.log.tau_j).max() < 0.02 * scale


def test_rigid_lugre_run_matches_a_ten_times_finer_step() -> None:
    kwargs = load_scenario("puma560-thesis").with_duration(7.0).build()
    # Perfect sensors: the 1e-5 rad encoder steps would turn integration
    # differences into different feedback.
    kwargs["sensors"] = SensorModel()
    coarse = simulate(**kwargs)
    fine = simulate(**kwargs, substeps=10 * coarse.substeps)
    assert np.abs(coarse.log.tau_c).max() > 10.0  # contact 1 starts at 6.26 s
    # The bristle update after each substep is a first-order splitting: at
    # velocity reversals the LuGre torque of the two steps differs for a few
    # samples; elsewhere they agree.
    assert np.abs(coarse.log.q_true - fine.log.q_true).max() < 1e-4
    friction_gap = np.abs(coarse.friction - fine.friction)
    assert np.median(friction_gap) < 1e-3 * np.abs(fine.friction).max()
    assert np.percentile(friction_gap, 99) < 0.01 * np.abs(fine.friction).max()


def test_flexible_run_same_seed_same_bytes() -> None:
    scenario = load_scenario("lwr4-thesis").with_duration(0.3)
    first, second = scenario.run(seed=5).log, scenario.run(seed=5).log
    for name in ("q", "tau_m", "tau_j", "q_true", "qd_true", "tau_c"):
        assert getattr(first, name).tobytes() == getattr(second, name).tobytes()


def test_held_lugre_torque_and_bristle_update_equal_the_checked_ones() -> None:
    model = LuGre.canudas1995(3)
    rng = np.random.default_rng(1)
    z = rng.uniform(-1e-5, 1e-5, 3)
    for qd in (rng.normal(0.0, 0.01, 3), np.array([0.0, 1e-4, -2.0])):
        np.testing.assert_allclose(
            model.held(z)(qd), model.torque_from_state(qd, z), rtol=1e-12, atol=1e-12
        )
        np.testing.assert_allclose(
            model.advance_state(qd, 1e-3, z), model.step(qd, 1e-3, z)[1], rtol=1e-14, atol=0.0
        )


def test_position_reader_reads_what_measure_position_reads() -> None:
    sensors = SensorModel(encoder_resolution=[1e-3, 0.0, 2e-3], position_noise=1e-4)
    q = np.random.default_rng(2).normal(size=(20, 3))
    read = sensors.position_reader(3, np.random.default_rng(7))
    rng = np.random.default_rng(7)
    for row in q:
        assert read(row).tobytes() == sensors.measure_position(row, rng).tobytes()
    with pytest.raises(sl.exceptions.InputTypeError, match="Generator"):
        sensors.position_reader(3)


def test_unknown_integrator_is_rejected() -> None:
    robot = sl.robots.load("planar2")
    with pytest.raises(InputValueError, match="integrator must be one of"):
        FlexiblePlant(robot, stiffness=1e4, damping=1.0, motor_inertia=1.0, integrator="euler")
