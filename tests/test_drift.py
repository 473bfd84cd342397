"""Tests of :mod:`sensorless.friction.drift` and of drifting friction in the simulator.

Independent checks: the torque at t = 0 is the base model's; at any t it is
the closed form s_c(t)·Coulomb + s_v(t)·viscous written here from the base
model's own parameters; the offset's rate stays within its bound (finite
differences); the plant advanced at time t equals the plant with the frozen
model of time t; the logged friction of a simulated run is the model
evaluated at the logged times and true velocities.
"""

from __future__ import annotations

import doctest
import importlib

import numpy as np
import pytest

from sensorless import robots
from sensorless.exceptions import InputTypeError, InputValueError, ModelError
from sensorless.friction import CoulombViscous, LuGre, Sigmoid
from sensorless.friction.drift import DriftingFriction, FrictionAt
from sensorless.simulation.plants import PlantState, RigidPlant
from sensorless.simulation.scenario import _plant, available_scenarios, load_scenario

BASE = CoulombViscous(c_pos=[2.0, 0.5], c_neg=[-1.5, -0.7], fv=[0.8, 0.3])
QD = np.array([[-1.0, 0.4], [0.0, -0.01], [0.3, 2.0], [2.5, -1.2]])


@pytest.mark.parametrize(
    "base", [BASE, Sigmoid(phi1=[0.5, 0.9], phi2=[5.0, 9.0], phi3=[0.04, -0.03])]
)
def test_equals_base_model_at_time_zero(base: CoulombViscous | Sigmoid) -> None:
    model = DriftingFriction(base, warmup=0.3, time_constant=[600.0, 900.0], offset_rate=1e-3)
    np.testing.assert_allclose(model.torque(0.0, QD), base.torque(QD), rtol=1e-15, atol=1e-15)
    np.testing.assert_array_equal(model.offset(0.0), [0.0, 0.0])


def test_follows_the_declared_exponential() -> None:
    warm, warm_v, tau = np.array([0.3, 0.2]), np.array([0.4, 0.1]), np.array([600.0, 1500.0])
    model = DriftingFriction(BASE, warmup=warm, time_constant=tau, warmup_viscous=warm_v)
    coulomb = np.where(QD > 0, BASE.c_pos, np.where(QD < 0, BASE.c_neg, 0.0))
    for t in (0.0, 60.0, 600.0, 1800.0, 1e6):
        s_c = 1.0 - warm * (1.0 - np.exp(-t / tau))
        s_v = 1.0 - warm_v * (1.0 - np.exp(-t / tau))
        expected = s_c * coulomb + s_v * BASE.fv * QD
        np.testing.assert_allclose(model.torque(t, QD), expected, rtol=1e-13, atol=1e-15)
        np.testing.assert_allclose(model.scales(t)[0], s_c, rtol=1e-15)
    # One time per row equals row by row.
    times = np.array([0.0, 100.0, 900.0, 4000.0])
    rows = np.array([model.torque(t, qd) for t, qd in zip(times, QD, strict=True)])
    np.testing.assert_allclose(model.torque(times, QD), rows, rtol=1e-15)


def test_offset_rate_is_bounded_and_seeded() -> None:
    rate = np.array([2e-4, 5e-5])
    model = DriftingFriction(BASE, offset_rate=rate, offset_periods=(300.0, 3000.0), seed=4)
    t = np.linspace(0.0, 7200.0, 72001)
    offset = model.offset(t)
    slope = np.abs(np.diff(offset, axis=0)) / np.diff(t)[:, None]
    assert (slope <= rate * (1 + 1e-9)).all()
    assert (slope.max(axis=0) > 0.3 * rate).all()  # it does drift
    same = DriftingFriction(BASE, offset_rate=rate, offset_periods=(300.0, 3000.0), seed=4)
    np.testing.assert_array_equal(same.offset(t), offset)
    other = DriftingFriction(BASE, offset_rate=rate, offset_periods=(300.0, 3000.0), seed=5)
    assert not np.allclose(other.offset(t), offset)
    # The offset adds to the torque at every velocity.
    np.testing.assert_allclose(
        model.torque(1234.0, QD) - DriftingFriction(BASE).torque(1234.0, QD),
        np.broadcast_to(model.offset(1234.0), QD.shape),
        atol=1e-14,
    )


def test_frozen_model_equals_the_drifting_one() -> None:
    model = DriftingFriction(BASE, warmup=0.25, time_constant=700.0, offset_rate=1e-3, seed=2)
    frozen = model.at(950.0)
    assert isinstance(frozen, FrictionAt) and frozen.n_dof == 2
    np.testing.assert_array_equal(frozen.evaluate(QD), model.evaluate_at(950.0, QD))
    np.testing.assert_array_equal(frozen.torque(QD), model.torque(950.0, QD))
    assert "FrictionAt" in repr(frozen) and "DriftingFriction" in repr(model)


def test_plant_passes_time_to_the_friction() -> None:
    robot = robots.load("planar2")
    model = DriftingFriction(
        CoulombViscous(c_pos=0.8, c_neg=-0.8, fv=[0.5, 0.2]), warmup=0.5, time_constant=100.0,
        offset_rate=1e-2, seed=1,
    )  # fmt: skip
    drifting = RigidPlant(robot, friction=model)
    q0, qd0 = np.array([0.3, -0.4]), np.array([1.0, -0.5])
    state = PlantState(q0, qd0, t=250.0)
    after = drifting.advance(state, np.zeros(2), np.zeros(2), 1e-3, 2)
    frozen = RigidPlant(robot, friction=model.at(250.0))
    reference = frozen.advance(PlantState(q0, qd0), np.zeros(2), np.zeros(2), 1e-3, 2)
    np.testing.assert_array_equal(after.qd, reference.qd)
    assert after.t == 250.0 + 1e-3
    cold = RigidPlant(robot, friction=model.base).advance(
        PlantState(q0, qd0), np.zeros(2), np.zeros(2), 1e-3, 2
    )
    assert not np.allclose(after.qd, cold.qd)  # warm joints lose less speed to friction
    np.testing.assert_array_equal(drifting.joint_friction(state), model.torque(250.0, qd0))
    assert drifting.substeps(1e-3, q0) == RigidPlant(robot, friction=model.base).substeps(1e-3, q0)


def test_warmup_scenario_runs_and_logs_the_drifting_friction() -> None:
    assert "puma560-warmup" in available_scenarios()
    scenario = load_scenario("puma560-warmup")
    assert scenario.duration >= 1800.0
    pushes = [c for c in scenario.spec["collisions"] if c["profile"] == "push"]
    impacts = [c for c in scenario.spec["collisions"] if c["profile"] == "half_sine"]
    assert pushes and impacts and all(c["ramp"] == 2.0 for c in pushes)
    assert min(c["start"] for c in scenario.spec["collisions"]) >= 300.0
    short = scenario.with_duration(0.5)
    parts = short.build()
    model = parts["plant"].friction
    assert isinstance(model, DriftingFriction)
    result = short.run()
    log = result.log
    assert np.isfinite(log.tau_m).all() and np.isfinite(log.q).all()
    np.testing.assert_allclose(result.friction, model.torque(log.t, log.qd_true), atol=1e-12)


def test_scenario_builder_keys() -> None:
    planar = robots.load("planar2")
    friction = CoulombViscous([0.5, 0.5], [-0.5, -0.5], [0.1, 0.1])
    robot = planar.with_standard_parameters(planar.parameter_vector(), friction=friction)
    spec = {
        "type": "rigid",
        "friction_drift": {
            "warmup": [0.2, 0.3], "warmup_viscous": 0.5, "time_constant": [300, 600],
            "offset_rate": 1e-4, "offset_periods": [100, 200], "seed": 3,
        },
    }  # fmt: skip
    plant = _plant(spec, robot)
    assert isinstance(plant.friction, DriftingFriction)
    np.testing.assert_array_equal(plant.friction.warmup, [0.2, 0.3])
    np.testing.assert_array_equal(plant.friction.time_constant, [300.0, 600.0])
    with pytest.raises(ModelError, match="unknown keys"):
        _plant({"type": "rigid", "friction_drift": {"warm": 0.2}}, robot)
    with pytest.raises(ModelError, match="rigid plants only"):
        _plant({"type": "flexible", "stiffness": 1e4, "friction_drift": {}}, robot)
    lugre = robot.with_standard_parameters(robot.parameter_vector(), friction=None)
    with pytest.raises(ModelError, match="stateless"):
        _plant({"type": "rigid", "friction_drift": {}}, lugre)


def test_validation() -> None:
    with pytest.raises(InputTypeError, match="base must be a stateless FrictionModel"):
        DriftingFriction(LuGre(1e4, 100.0, 0.1, 1.0, 1.5, 0.01))  # type: ignore[arg-type]
    with pytest.raises(InputValueError, match=r"warmup must be a fraction in \[0, 1\)"):
        DriftingFriction(BASE, warmup=1.0)
    with pytest.raises(InputValueError, match="warmup must be"):
        DriftingFriction(BASE, warmup=-0.1)
    with pytest.raises(InputValueError, match="time_constant must be"):
        DriftingFriction(BASE, time_constant=0.0)
    with pytest.raises(InputValueError, match="offset_rate must be"):
        DriftingFriction(BASE, offset_rate=-1.0)
    with pytest.raises(InputValueError, match="offset_periods must satisfy"):
        DriftingFriction(BASE, offset_periods=(100.0, 10.0))
    with pytest.raises(InputValueError, match="offset_periods must be two"):
        DriftingFriction(BASE, offset_periods=(100.0,))  # type: ignore[arg-type]
    with pytest.raises(InputValueError, match="seed must be"):
        DriftingFriction(BASE, seed=-1)
    model = DriftingFriction(BASE)
    with pytest.raises(InputValueError, match="t must be a finite time >= 0"):
        model.torque(-1.0, QD)
    with pytest.raises(InputValueError, match="one time per row"):
        model.torque([0.0, 1.0], QD)
    with pytest.raises(InputValueError, match="t must be one time"):
        model.at([0.0, 1.0])  # type: ignore[arg-type]


def test_doctests() -> None:
    module = importlib.import_module("sensorless.friction.drift")
    assert doctest.testmod(module).failed == 0
