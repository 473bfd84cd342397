"""The compiled simulator against the reference: dynamics, one plant period, whole runs.

The reference is Pinocchio's ``aba``/``crba``, the plants' own ``advance`` and
``simulate(..., backend="numpy")``; every figure here is compared with it.
"""

from __future__ import annotations

import dataclasses
import doctest

import numpy as np
import pinocchio as pin
import pytest

import sensorless as sl
from sensorless.exceptions import DimensionError, InputValueError, UnknownNameError
from sensorless.friction import (
    Coulomb,
    CoulombViscous,
    DriftingFriction,
    HystereticError,
    LuGre,
    Sigmoid,
    Stribeck,
    Viscous,
)
from sensorless.robots import forward_dynamics
from sensorless.robots.forward_dynamics import ForwardDynamics
from sensorless.simulation.collisions import Contact, ContactSet, HalfSine, Push
from sensorless.simulation.compiled import compile_plant, numba_available, pack_friction
from sensorless.simulation.controllers import ComputedTorque, JointPID
from sensorless.simulation.plants import FlexiblePlant, PlantState, RigidPlant
from sensorless.simulation.scenario import load_scenario
from sensorless.simulation.sensors import SensorModel
from sensorless.simulation.simulator import simulate

pytestmark = pytest.mark.skipif(not numba_available(), reason="numba is not installed")

DT = 1e-3


def tree_model() -> pin.Model:
    """A branching tree with revolute, unaligned and prismatic joints, random inertias."""
    rng = np.random.default_rng(3)
    model = pin.Model()

    def body(parent: int, joint: object, name: str) -> int:
        placement = pin.SE3(pin.rpy.rpyToMatrix(*rng.uniform(-1, 1, 3)), rng.uniform(-0.3, 0.3, 3))
        jid = model.addJoint(parent, joint, placement, name)
        inertia = pin.Inertia(rng.uniform(0.5, 2.0), rng.uniform(-0.1, 0.1, 3),
                              np.diag(rng.uniform(0.01, 0.05, 3)))  # fmt: skip
        model.appendBodyToJoint(jid, inertia, pin.SE3.Identity())
        return int(jid)

    # Depth-first order (Pinocchio's algorithms expect each subtree contiguous).
    root = body(0, pin.JointModelRZ(), "j1")
    middle = body(root, pin.JointModelPX(), "j2")
    tip = body(middle, pin.JointModelRevoluteUnaligned(np.array([0.6, 0.0, 0.8])), "j3")
    body(tip, pin.JointModelPrismaticUnaligned(np.array([0.0, 0.6, 0.8])), "j4")
    body(root, pin.JointModelRY(), "j5")
    model.armature = rng.uniform(0.0, 0.2, model.nv)
    return model


MODELS = {
    "puma560": lambda: sl.robots.load("puma560").pinocchio_model,
    "panda": lambda: sl.robots.load("panda").pinocchio_model,
    "lwr4": lambda: sl.robots.load("lwr4").pinocchio_model,
    "tree": tree_model,
}


@pytest.mark.parametrize("name", sorted(MODELS))
def test_forward_dynamics_equals_pinocchio(name: str) -> None:
    model = MODELS[name]()
    data = model.createData()
    compiled = ForwardDynamics(model, backend="numba")
    rng = np.random.default_rng(0)
    for _ in range(10):
        q, qd, tau = rng.uniform(-2.0, 2.0, (3, model.nv))
        qdd = compiled.acceleration(q, qd, tau)
        reference = pin.aba(model, data, q, qd, tau)
        assert np.allclose(qdd, reference, rtol=1e-12, atol=1e-12)
        mass = compiled.mass_matrix(q)
        crba = pin.crba(model, data, q)
        assert np.allclose(mass, np.triu(crba) + np.triu(crba, 1).T, rtol=0, atol=1e-12)
        # M q̈ + C q̇ + g = τ, with C q̇ + g from the recursive Newton-Euler algorithm.
        bias = pin.rnea(model, data, q, qd, np.zeros(model.nv))
        assert np.allclose(mass @ qdd + bias, tau, rtol=0, atol=1e-10)
        # The compiled Newton-Euler inverts the compiled forward dynamics.
        assert np.allclose(compiled.inverse_dynamics(q, qd, qdd), tau, rtol=0, atol=1e-10)
        assert np.allclose(compiled.inverse_dynamics(q, qd, qdd), pin.rnea(model, data, q, qd, qdd),
                           rtol=0, atol=1e-10)  # fmt: skip


def test_forward_dynamics_backends_and_checks() -> None:
    robot = sl.robots.load("planar2")
    fast = ForwardDynamics.from_robot(robot)
    slow = ForwardDynamics.from_robot(robot, backend="numpy")
    assert (fast.backend, slow.backend) == ("numba", "numpy")
    q, qd, tau = np.array([0.3, -0.2]), np.array([0.5, 1.0]), np.array([1.0, -2.0])
    assert np.allclose(fast.acceleration(q, qd, tau), slow.acceleration(q, qd, tau), atol=1e-13)
    assert np.allclose(fast.mass_matrix(q), slow.mass_matrix(q), atol=1e-14)
    assert np.allclose(fast.inverse_dynamics(q, qd, tau), slow.inverse_dynamics(q, qd, tau))
    with pytest.raises(DimensionError, match=r"one sample of shape \(2,\)"):
        fast.acceleration(np.zeros((3, 2)), qd, tau)
    with pytest.raises(UnknownNameError, match="unknown backend 'fortran'"):
        ForwardDynamics.from_robot(robot, backend="fortran")


def _state(plant: RigidPlant | FlexiblePlant, rng: np.random.Generator) -> PlantState:
    n = plant.n_dof
    state = plant.initial_state(rng.uniform(-1.0, 1.0, n), rng.uniform(-1.0, 1.0, n))
    state = dataclasses.replace(state, t=200.0)
    if state.z is not None:
        state = dataclasses.replace(state, z=rng.uniform(-1e-4, 1e-4, n))
    if state.theta is not None:
        assert state.thetad is not None
        state = dataclasses.replace(
            state, theta=state.theta + rng.uniform(-1e-3, 1e-3, n),
            thetad=state.thetad + rng.uniform(-0.1, 0.1, n),
        )  # fmt: skip
    return state


def _same_period(plant: RigidPlant | FlexiblePlant, substeps: int | None = None) -> None:
    compiled = compile_plant(plant)
    assert compiled is not None
    rng = np.random.default_rng(5)
    state = _state(plant, rng)
    substeps = plant.substeps(DT, state.q) if substeps is None else substeps
    tau_m, tau_c = rng.uniform(-5.0, 5.0, (2, plant.n_dof))
    for _ in range(3):
        reference = plant.advance(state, tau_m, tau_c, DT, substeps)
        got = compiled.advance(state, tau_m, tau_c, DT, substeps)
        for name in ("q", "qd", "z", "theta", "thetad", "z_motor"):
            expected, value = getattr(reference, name), getattr(got, name)
            assert (expected is None) == (value is None), name
            if expected is not None:
                scale = 1e-12 * max(1.0, float(np.max(np.abs(expected))))
                assert np.allclose(value, expected, rtol=0, atol=scale), name
        assert got.t == reference.t
        state = reference


@pytest.mark.parametrize("scenario", ["puma560-thesis", "puma560-warmup", "lwr4-thesis"])
def test_period_equals_reference_on_shipped_plants(scenario: str) -> None:
    plant = load_scenario(scenario).with_duration(1.0).build()["plant"]
    _same_period(plant)


def test_period_equals_reference_flexible_without_feedback_with_lugre() -> None:
    plant = load_scenario("lwr4-thesis").with_duration(1.0).build()["plant"]
    lugre = LuGre(sigma0=1e3, sigma1=5.0, sigma2=0.1, fc=0.3, fs=0.5, vs=0.05, delta=1.5)
    lugre = LuGre(*(np.broadcast_to(getattr(lugre, f), 7) for f in
                    ("sigma0", "sigma1", "sigma2", "fc", "fs", "vs", "delta")))  # fmt: skip
    _same_period(dataclasses.replace(plant, feedback=None, link_friction=lugre))


STATIC = [
    Coulomb(c_pos=[0.5, 0.3], c_neg=[-0.4, -0.2]),
    Viscous(fv=[0.5, 1.0]),
    CoulombViscous(c_pos=0.5, c_neg=-0.4, fv=[0.2, 0.3]),
    Stribeck(fc=[0.5, 0.4], fs=0.8, vs=0.1, fv=0.2, delta=[2.0, 1.0]),
    Sigmoid(phi1=[0.5, 0.4], phi2=[5.0, 8.0], phi3=[0.04, -0.02]),
    HystereticError(c=[0.2, -0.1]),
    LuGre.canudas1995(2),
    DriftingFriction(
        CoulombViscous(c_pos=0.5, c_neg=-0.4, fv=[0.2, 0.1]), offset_rate=0.01, seed=3
    ),
    None,
]


@pytest.mark.parametrize("friction", STATIC, ids=lambda f: type(f).__name__)
def test_period_equals_reference_for_each_friction_model(friction: object) -> None:
    plant = RigidPlant(sl.robots.load("planar2"), friction=friction)  # type: ignore[arg-type]
    _same_period(plant, substeps=2)


def test_unsupported_parts_keep_the_reference() -> None:
    class Doubled(Coulomb):
        def evaluate(self, qd: np.ndarray) -> np.ndarray:
            return 2.0 * super().evaluate(qd)

    robot = sl.robots.load("planar2")
    assert pack_friction(Doubled(c_pos=[0.5, 0.5], c_neg=-0.5), 2) is None
    assert compile_plant(RigidPlant(robot, friction=Doubled(c_pos=[0.5, 0.5], c_neg=-0.5))) is None
    flexible = FlexiblePlant(robot, stiffness=1e3, damping=1.0, motor_inertia=0.1, integrator="rk4")
    assert compile_plant(flexible) is None


def _contact(link: int, start: float) -> ContactSet:
    push = Push(start + 0.15, 0.1, 0.1, 0.1, 20.0)
    return ContactSet([
        Contact(1, link, [0.0, 0.05, 0.1], [1.0, 0.5, 0.0], HalfSine(start, 0.2, 40.0)),
        Contact(2, link - 1, [0.1, 0.0, 0.0], [0.0, 0.0, 1.0], push),
    ])  # fmt: skip


def _compare_runs(kwargs: dict, quantum: float) -> None:
    compiled = simulate(**kwargs)
    again = simulate(**kwargs)
    reference = simulate(**kwargs, backend="numpy")
    assert (compiled.backend, reference.backend) == ("numba", "numpy")
    one, two, ref = compiled.log, again.log, reference.log
    for name in ("q", "tau_m", "tau_j", "q_true", "qd_true", "tau_c", "collision_id"):
        if getattr(one, name) is not None:
            assert getattr(one, name).tobytes() == getattr(two, name).tobytes(), name
    assert np.array_equal(one.collision_id, ref.collision_id)
    assert np.any(one.tau_c != 0.0)
    for name, tol in (("q_true", 1e-9), ("qd_true", 1e-7), ("tau_c", 1e-8)):
        assert np.allclose(getattr(one, name), getattr(ref, name), rtol=0, atol=tol), name
    # A difference of 1e-15 rad can move the true position across an encoder
    # rounding boundary: the measured position may then differ by one quantum.
    differ = np.abs(one.q - ref.q)
    assert np.all((differ == 0.0) | np.isclose(differ, quantum, rtol=1e-6))
    assert np.count_nonzero(differ) <= 0.001 * differ.size
    assert np.allclose(compiled.friction, reference.friction, rtol=0, atol=1e-6)


def test_short_rigid_run_equals_reference() -> None:
    kwargs = load_scenario("puma560-thesis").with_duration(1.2).build()
    kwargs["contacts"] = _contact(6, 0.5)
    _compare_runs(kwargs, quantum=1e-5)


def test_short_flexible_run_equals_reference() -> None:
    kwargs = load_scenario("lwr4-thesis").with_duration(0.8).build()
    kwargs["contacts"] = _contact(3, 0.3)
    _compare_runs(kwargs, quantum=2e-5)


def test_position_noise_drawn_in_bulk_equals_per_sample() -> None:
    rng, bulk = np.random.default_rng(11), np.random.default_rng(11)
    rows = np.stack([rng.standard_normal(3) for _ in range(50)])
    assert rows.tobytes() == bulk.standard_normal((50, 3)).tobytes()
    kwargs = load_scenario("puma560-warmup").with_duration(0.3).build()
    kwargs["sensors"] = SensorModel(encoder_resolution=1e-5, position_noise=2e-5)
    compiled, reference = simulate(**kwargs), simulate(**kwargs, backend="numpy")
    assert compiled.backend == "numba"
    assert np.allclose(compiled.log.q, reference.log.q, rtol=0, atol=1e-12)


def test_computed_torque_run_equals_reference() -> None:
    kwargs = load_scenario("panda-gaz").with_duration(0.6).build(collisions=False)
    assert type(kwargs["controller"]) is ComputedTorque
    kwargs["contacts"] = _contact(5, 0.2)
    _compare_runs(kwargs, quantum=1e-5)


def test_backend_selection() -> None:
    class Custom(JointPID):
        """A controller the compiled loop does not know: the plant alone is compiled."""

    kwargs = load_scenario("puma560-thesis").with_duration(0.05).build(collisions=False)
    pid = kwargs["controller"]
    assert simulate(**kwargs).backend == "numba"
    assert simulate(**kwargs, backend="numpy").backend == "numpy"
    custom = Custom(kp=pid.kp, ki=pid.ki, kd=pid.kd, model=pid.model)
    mixed = simulate(**{**kwargs, "controller": custom})
    assert mixed.backend == "numba-plant"
    reference = simulate(**{**kwargs, "controller": custom}, backend="numpy")
    assert np.allclose(mixed.log.q_true, reference.log.q_true, rtol=0, atol=1e-12)
    with pytest.raises(UnknownNameError, match="unknown backend 'gpu'"):
        simulate(**kwargs, backend="gpu")
    with pytest.raises(InputValueError, match="duration"):
        simulate(**{**kwargs, "duration": -1.0})


def test_forward_dynamics_doctest_runs() -> None:
    results = doctest.testmod(forward_dynamics)
    assert results.attempted > 0 and results.failed == 0
