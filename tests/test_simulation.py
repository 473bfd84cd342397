"""Simulator: energy, momentum identity, tracking, reproducibility, contacts, flexible joints."""

from __future__ import annotations

import copy
import itertools

import numpy as np
import pinocchio as pin
import pytest

import sensorless as sl
from sensorless.exceptions import DimensionError, InputValueError
from sensorless.io import write_log
from sensorless.simulation.collisions import Contact, ContactSet, HalfSine, Push
from sensorless.simulation.controllers import JointPID
from sensorless.simulation.plants import FlexiblePlant, RigidPlant, TorqueFeedback
from sensorless.simulation.scenario import Scenario, load_scenario
from sensorless.simulation.simulator import simulate
from sensorless.trajectories import QuinticViaPoints

DT = 1e-3


def energy(robot: sl.RobotModel, q: np.ndarray, qd: np.ndarray) -> float:
    """Kinetic (armature included) plus potential energy [J], from Pinocchio directly."""
    model = robot.pinocchio_model
    data = model.createData()
    kinetic = 0.5 * qd @ robot.mass_matrix(q) @ qd
    return float(kinetic + pin.computePotentialEnergy(model, data, q))


def free_motion(plant: RigidPlant, q0: np.ndarray, steps: int, substeps: int, tau_c=None):
    state = plant.initial_state(q0)
    n = plant.n_dof
    zero = np.zeros(n)
    states = [state]
    for _ in range(steps):
        contact = zero if tau_c is None else tau_c(state.q)
        state = plant.advance(state, zero, contact, DT, substeps)
        states.append(state)
    return states


@pytest.mark.parametrize("name", ["planar2", "puma560"])
def test_frictionless_unactuated_arm_conserves_energy(name: str) -> None:
    robot = sl.robots.load(name)
    plant = RigidPlant(robot, friction=None)
    q0 = np.linspace(0.3, 1.1, robot.n_dof)
    states = free_motion(plant, q0, steps=10_000, substeps=4)
    energies = np.array([energy(robot, s.q, s.qd) for s in states])
    kinetic_peak = max(0.5 * s.qd @ robot.mass_matrix(s.q) @ s.qd for s in states[::100])
    assert kinetic_peak > 1.0  # the arm really falls and swings
    drift = np.abs(energies - energies[0]).max() / kinetic_peak
    assert drift < 1e-6


def test_constant_external_force_does_the_work_of_the_energy_change() -> None:
    robot = sl.robots.load("puma560")
    plant = RigidPlant(robot, friction=None)
    force = np.array([30.0, -20.0, 10.0])
    point = np.array([0.0, 0.0, 0.1])

    def tau_c(q: np.ndarray) -> np.ndarray:
        return robot.point_jacobian(q, 6, point)[:3].T @ force

    q0 = np.array([0.1, 0.8, -1.2, 0.3, 0.4, 0.2])
    states = free_motion(plant, q0, steps=3000, substeps=4, tau_c=tau_c)
    # The contact torque is held over each period, so its work there is exactly τ_c·Δq.
    work = sum(
        tau_c(before.q) @ (after.q - before.q) for before, after in itertools.pairwise(states)
    )
    change = energy(robot, states[-1].q, states[-1].qd) - energy(robot, states[0].q, states[0].qd)
    assert abs(work) > 1.0
    assert change == pytest.approx(work, rel=1e-6)
    # And it tends to the work of a constant force, F·Δx of the point (first order in dt).
    start = robot.forward_kinematics(states[0].q, 6, point)
    end = robot.forward_kinematics(states[-1].q, 6, point)
    assert change == pytest.approx(force @ (end - start), rel=0.05)


@pytest.fixture(scope="module")
def panda_run():
    """panda_gaz with its own (stateless) friction as both true and nominal robot."""
    scenario = load_scenario("panda-gaz")
    spec = copy.deepcopy(scenario.spec)
    spec.update(duration=6.0, nominal_robot="panda_gaz", sensors={})
    spec["random_collisions"] = {**spec["random_collisions"], "count": 2, "min_gap": 1.0}
    return Scenario("panda-exact", spec).run(seed=3)


def test_momentum_identity_along_a_simulated_run(panda_run) -> None:
    """ṗ = τ_m + τ_c − τ_fr + Cᵀq̇ − g: the identity the momentum observer relies on."""
    log = panda_run.log
    robot = sl.robots.load("panda_gaz")
    q, qd = log.q_true, log.qd_true
    momentum = np.einsum("kij,kj->ki", robot.mass_matrix(q), qd)
    rest = robot.coriolis_transpose_velocity(q, qd) - robot.gravity(q) - panda_run.friction
    # τ_m and τ_c are held over [t_k, t_k+1); the state-dependent terms are integrated
    # by the trapezoid rule.
    increment = (log.tau_m[:-1] + log.tau_c[:-1]) * DT + 0.5 * (rest[:-1] + rest[1:]) * DT
    error = (np.diff(momentum, axis=0) - increment) / DT  # [N m]
    scale = np.abs(log.tau_m).max()
    assert np.abs(log.tau_c).max() > 5.0  # the run does contain contacts
    # What is left is the trapezoid rule's quadrature error (≈ 0.2 N m at worst) ...
    assert np.abs(error).max() < 5e-3 * scale
    assert np.median(np.abs(error)) < 5e-4 * scale
    # ... far below the size of the terms of the identity.
    assert np.abs(rest).max() > 50 * np.abs(error).max()


def test_puma_tracking_with_table_5_2_gains_stays_bounded() -> None:
    scenario = load_scenario("puma560-thesis")
    spec = copy.deepcopy(scenario.spec)
    spec["duration"] = 10.0
    result = Scenario("puma-short", spec).run(collisions=False)
    error = np.abs(result.desired - result.log.q_true).max(axis=0)
    assert np.all(np.isfinite(result.log.q_true))
    assert error.max() < 0.05  # rad, over two periods of Table 5.1
    assert result.substeps >= 1


def _short(name: str, duration: float) -> Scenario:
    scenario = load_scenario(name)
    spec = copy.deepcopy(scenario.spec)
    spec["duration"] = duration
    if "random_collisions" in spec:
        spec["random_collisions"] = {**spec["random_collisions"], "count": 1}
    return Scenario(scenario.name, spec)


def test_same_seed_same_bytes_and_different_seeds_differ(tmp_path) -> None:
    scenario = _short("panda-gaz", 3.0)
    paths = []
    for index, seed in enumerate((11, 11, 12)):
        for suffix in ("csv", "parquet"):
            path = tmp_path / f"run{index}.{suffix}"
            write_log(scenario.run(seed=seed).log, path)
            paths.append(path)
    csv0, parquet0, csv1, parquet1, csv2, _ = (p.read_bytes() for p in paths)
    assert csv0 == csv1
    assert parquet0 == parquet1
    assert csv0 != csv2


def test_logged_contact_torque_is_jacobian_transpose_force() -> None:
    scenario = _short("puma560-thesis", 10.0)
    result = scenario.run()
    log = result.log
    robot = sl.robots.load("puma560")
    contacts = log.metadata["collisions"]
    assert [c["id"] for c in contacts] == [1, 2, 3, 4, 5, 6, 7, 8, 9]
    first = contacts[0]
    profile = HalfSine(first["start"], first["end"] - first["start"], first["peak"])
    direction = np.asarray(first["direction"], dtype=float)
    inside = np.flatnonzero(log.collision_id == 1)
    assert inside.size > 50
    for k in inside[::25]:
        force = profile(log.t[k]) * direction / np.linalg.norm(direction)
        jac = robot.point_jacobian(log.q_true[k], first["link"], first["point"])
        np.testing.assert_allclose(log.tau_c[k], jac[:3].T @ force, atol=1e-9)
    outside = log.collision_id == 0
    assert np.all(log.tau_c[outside] == 0.0)


def test_contact_on_a_link_leaves_later_joints_untouched() -> None:
    robot = sl.robots.load("panda_gaz")
    contact = Contact(1, 3, (0.05, 0.0, 0.02), (1.0, 0.5, -0.2), Push(0.2, 0.1, 0.3, 0.1, 40.0))
    trajectory = QuinticViaPoints(
        [0.0, 1.0], np.tile([0.0, -0.5, 0.0, -2.0, 0.0, 1.5, 0.7], (2, 1))
    )
    controller = JointPID(kp=np.full(7, 200.0), ki=0.0, kd=np.full(7, 5.0), model=robot)
    result = simulate(
        RigidPlant(robot), controller, trajectory, 1.0, contacts=ContactSet([contact])
    )
    assert np.abs(result.log.tau_c[:, :3]).max() > 1.0
    assert np.all(result.log.tau_c[:, 3:] == 0.0)


def test_stiff_flexible_arm_approaches_the_rigid_arm() -> None:
    planar = sl.robots.load("planar2")
    pi = planar.parameter_vector().reshape(2, 11)
    pi[:, 10] = [0.5, 0.3]  # motor inertia (armature) of the rigid arm = B of the flexible one
    robot = planar.with_standard_parameters(pi)
    trajectory = QuinticViaPoints([0.0, 1.0, 2.0], np.array([[0.0, 0.0], [0.8, -1.0], [0.0, 0.0]]))
    controller = JointPID(kp=[400.0, 200.0], ki=0.0, kd=[40.0, 20.0], model=robot)
    rigid = simulate(RigidPlant(robot, friction=None), controller, trajectory, 2.0)

    def gap(stiffness: float) -> tuple[float, int]:
        plant = FlexiblePlant(robot, stiffness=stiffness, damping=0.01 * np.sqrt(stiffness))
        run = simulate(plant, controller, trajectory, 2.0)
        assert run.log.tau_j is not None
        return float(np.abs(run.log.q_true - rigid.log.q_true).max()), run.substeps

    stiff, substeps = gap(1e7)
    soft, _ = gap(3e4)
    assert substeps > 1  # the stiff joints force RK4 substeps
    assert stiff < 1e-4
    assert soft > 100 * stiff


def test_torque_feedback_loop_runs_and_reads_joint_torque() -> None:
    robot = sl.robots.load("panda_gaz")
    plant = FlexiblePlant(
        robot,
        stiffness=5000.0,
        damping=5.0,
        motor_inertia=0.3,
        link_friction=robot.friction,
        feedback=TorqueFeedback(motor_inertia=0.05, damping=1.0),
    )
    q0 = np.array([0.0, -0.5, 0.0, -2.0, 0.0, 1.5, 0.7])
    trajectory = QuinticViaPoints([0.0, 1.0], np.tile(q0, (2, 1)))
    controller = JointPID(kp=np.full(7, 100.0), ki=0.0, kd=np.full(7, 5.0), model=robot)
    result = simulate(plant, controller, trajectory, 1.0)
    # Standing still under gravity, the torque sensors carry the gravity torque.
    np.testing.assert_allclose(
        result.log.tau_j[-1], robot.gravity(result.log.q_true[-1]), atol=0.05
    )


def test_bad_simulation_inputs_are_rejected() -> None:
    robot = sl.robots.load("planar2")
    trajectory = QuinticViaPoints([0.0, 1.0], np.zeros((2, 2)))
    controller = JointPID(kp=[10.0, 10.0], ki=0.0, kd=[1.0, 1.0], model=robot)
    with pytest.raises(InputValueError, match="duration"):
        simulate(RigidPlant(robot), controller, trajectory, -1.0)
    with pytest.raises(InputValueError, match="dt"):
        simulate(RigidPlant(robot), controller, trajectory, 1.0, dt=0.0)
    other = JointPID(kp=np.ones(6), ki=0.0, kd=np.ones(6), model=sl.robots.load("puma560"))
    with pytest.raises(DimensionError, match="plant has 2 joints"):
        simulate(RigidPlant(robot), other, trajectory, 1.0)
    with pytest.raises(InputValueError, match="substeps"):
        simulate(RigidPlant(robot), controller, trajectory, 1.0, substeps=0)
    with pytest.raises(InputValueError, match="stiffness"):
        FlexiblePlant(robot, stiffness=-1.0, damping=0.0, motor_inertia=1.0)
    with pytest.raises(DimensionError, match="kp must have 2 entries"):
        JointPID(kp=[1.0, 2.0, 3.0], ki=0.0, kd=[1.0, 1.0], model=robot)
