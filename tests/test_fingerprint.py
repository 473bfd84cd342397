"""The model fingerprint: a payload or other parameters under the same name is another model."""

from __future__ import annotations

import numpy as np
import pytest

from sensorless import robots
from sensorless.exceptions import ModelMismatchError
from sensorless.friction import CoulombViscous
from sensorless.monitor import CollisionMonitor, ObserverSettings
from sensorless.observers import MomentumObserver
from sensorless.signals import ObserverSignals
from sensorless.thresholds import ConstantThreshold, VelocityThreshold

DT = 1e-3


def with_payload(robot: robots.RobotModel, mass: float, offset: float) -> robots.RobotModel:
    """The same robot, same name, with a point mass [kg] at ``offset`` [m] along z of the last link.

    Standard parameters about the link frame: m += mass, mZ += mass·d, XX and YY += mass·d²
    (parallel-axis theorem for a point mass on the z axis).
    """
    table = robot.standard_parameters()
    last = table.index[-1]
    table.loc[last, "m"] += mass
    table.loc[last, "mZ"] += mass * offset
    table.loc[last, "XX"] += mass * offset**2
    table.loc[last, "YY"] += mass * offset**2
    return robot.with_standard_parameters(table.to_numpy())


def observed(robot: robots.RobotModel, seed: int = 0) -> ObserverSignals:
    """2 s of a slow sine on every joint through the nominal model ``robot``, with noise."""
    rng = np.random.default_rng(seed)
    t = np.arange(2001) * DT
    phase = np.linspace(0.0, 1.0, robot.n_dof)
    q = 0.3 * np.sin(2.0 * t[:, None] + phase)
    qd = 0.6 * np.cos(2.0 * t[:, None] + phase)
    qdd = -1.2 * np.sin(2.0 * t[:, None] + phase)
    tau = robot.inverse_dynamics(q, qd, qdd) + 0.01 * rng.standard_normal(q.shape)
    signals, _ = MomentumObserver(robot, DT, gain=20.0, friction=None).run(t, q, qd, tau)
    return signals


@pytest.mark.parametrize("name", robots.available())
def test_the_fingerprint_is_stable_and_survives_a_parameter_round_trip(name: str) -> None:
    robot = robots.load(name)
    assert robot.fingerprint == robots.load(name).fingerprint
    assert len(robot.fingerprint) == 16
    int(robot.fingerprint, 16)
    rebuilt = robot.with_standard_parameters(robot.parameter_vector())
    assert rebuilt.fingerprint == robot.fingerprint


def test_a_payload_friction_or_gravity_change_changes_the_fingerprint() -> None:
    robot = robots.load("panda")
    heavy = with_payload(robot, 1.0, 0.1)
    assert heavy.name == robot.name
    assert heavy.fingerprint != robot.fingerprint
    # The payload is a real change of the dynamics: gravity on joint 2 differs.
    q = np.array([0.0, 0.5, 0.0, -1.5, 0.0, 1.0, 0.0])
    assert abs(heavy.gravity(q)[1] - robot.gravity(q)[1]) > 0.5
    rubbing = robot.with_standard_parameters(
        robot.parameter_vector(), friction=CoulombViscous(c_pos=[0.5] * 7, c_neg=-0.5, fv=0.1)
    )
    assert rubbing.fingerprint != robot.fingerprint
    stickier = robot.with_standard_parameters(
        robot.parameter_vector(),
        friction=CoulombViscous(c_pos=[0.6] + [0.5] * 6, c_neg=-0.5, fv=0.1),
    )
    assert stickier.fingerprint not in (robot.fingerprint, rubbing.fingerprint)
    # Names and descriptions are not dynamics.
    renamed = robot.with_standard_parameters(robot.parameter_vector(), name="my panda")
    assert renamed.fingerprint == robot.fingerprint


def test_signals_and_thresholds_carry_the_fingerprint_and_a_payload_is_refused() -> None:
    robot = robots.load("planar2")
    heavy = with_payload(robot, 2.0, 0.05)
    base, other = observed(robot), observed(heavy, seed=1)
    assert base.fingerprint == robot.fingerprint
    assert other.fingerprint == heavy.fingerprint
    threshold = ConstantThreshold(margin=0.05).fit(base)
    assert threshold.fingerprint_ == robot.fingerprint
    threshold.bounds(base)
    with pytest.raises(ModelMismatchError, match="dynamic parameters differ"):
        threshold.bounds(other)
    with pytest.raises(ModelMismatchError, match="dynamic parameters differ"):
        VelocityThreshold().fit([base, other])
    settings = ObserverSettings(kind="motor", gain=20.0)
    CollisionMonitor(robot, threshold, settings)
    with pytest.raises(ModelMismatchError, match=heavy.fingerprint):
        CollisionMonitor(heavy, threshold, settings)


def test_without_a_fingerprint_the_name_decides() -> None:
    """Signals built by hand and thresholds from files of earlier versions have none."""
    robot = robots.load("planar2")
    base = observed(robot)
    anonymous = ObserverSignals(
        base.t,
        base.residual,
        base.model_torque,
        base.friction,
        base.sign,
        base.velocity,
        gain=base.gain,
        robot=base.robot,
    )
    assert anonymous.fingerprint == ""
    threshold = ConstantThreshold(margin=0.05).fit(anonymous)
    assert threshold.fingerprint_ == ""
    threshold.bounds(base)
    heavy = with_payload(robot, 2.0, 0.05)
    CollisionMonitor(heavy, threshold, ObserverSettings(kind="motor", gain=20.0))


def test_threshold_files_keep_the_fingerprint(tmp_path) -> None:
    import yaml

    from sensorless.exceptions import FileFormatError
    from sensorless.thresholds import load_threshold

    robot = robots.load("planar2")
    threshold = ConstantThreshold(margin=0.05).fit(observed(robot))
    path = threshold.save(tmp_path / "constant.yaml")
    assert f"fingerprint: {robot.fingerprint}" in path.read_text()
    loaded = load_threshold(path)
    assert loaded.fingerprint_ == robot.fingerprint
    settings = ObserverSettings(kind="motor", gain=20.0)
    with pytest.raises(ModelMismatchError, match="dynamic parameters differ"):
        CollisionMonitor(with_payload(robot, 2.0, 0.05), loaded, settings)
    # A file of an earlier version, without the key: the name decides.
    data = yaml.safe_load(path.read_text())
    del data["fingerprint"]
    old = tmp_path / "old.yaml"
    old.write_text(yaml.safe_dump(data))
    assert load_threshold(old).fingerprint_ == ""
    data["fingerprint"] = "not a fingerprint"
    old.write_text(yaml.safe_dump(data))
    with pytest.raises(FileFormatError, match="fingerprint"):
        load_threshold(old)
