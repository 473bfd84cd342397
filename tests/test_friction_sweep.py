"""Constant-velocity friction sweeps: the VelocitySweep trajectory and identify_friction.

The end-to-end tests simulate the experiment of thesis §2.4.1-2.4.2 on a
robot with planted friction and check that the identification gives the
planted parameters back.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml
from matplotlib.figure import Figure
from scipy.integrate import cumulative_trapezoid

from sensorless.exceptions import DimensionError, InputTypeError, InputValueError
from sensorless.friction import Coulomb, CoulombViscous
from sensorless.identification.friction import (
    FrictionFit,
    FrictionIdentification,
    identify_friction,
    sweep_velocities,
)
from sensorless.io import Log
from sensorless.robots import load
from sensorless.robots.model import RobotModel
from sensorless.simulation.controllers import JointPID
from sensorless.simulation.plants import FlexiblePlant, RigidPlant
from sensorless.simulation.scenario import load_scenario
from sensorless.simulation.simulator import SimulationResult, simulate
from sensorless.trajectories import VelocitySweep

DT = 1e-3
HOME = np.array([0.3, -0.4])
SPEEDS = [-1.0, -0.4, -0.1, 0.1, 0.4, 1.0]
# Planted rigid-arm friction [N m], [N m s/rad].
C_POS, C_NEG, FV = np.array([0.8, 0.5]), np.array([-0.6, -0.4]), np.array([0.5, 0.3])


def _small_sweep(**options: object) -> VelocitySweep:
    kwargs: dict[str, object] = {
        "joints": [3, 1],
        "velocities": [-0.5, -0.2, 0.2, 0.5],
        "hold": 0.4,
        "ramp": 0.3,
    }
    kwargs.update(options)
    return VelocitySweep([0.1, -0.2, 0.3], **kwargs)


# ------------------------------------------------------------------ VelocitySweep
def test_sweep_derivatives_are_finite_differences() -> None:
    sweep = _small_sweep()
    h = 1e-4
    t = np.arange(0.0, sweep.duration, h)
    q, qd, qdd = sweep.evaluate(t)
    # Central differences: O(h²) in the interior of segments; the jerk jumps at
    # ramp ends cost at most h · |jerk| = h · π² |Δv| / (2 ramp²) on qdd.
    np.testing.assert_allclose(np.gradient(q, h, axis=0)[1:-1], qd[1:-1], atol=1e-7)
    jerk = np.pi**2 * 1.0 / (2 * 0.3**2)
    np.testing.assert_allclose(np.gradient(qd, h, axis=0)[1:-1], qdd[1:-1], atol=h * jerk)
    assert np.abs(qdd).max() == pytest.approx(np.pi * 1.0 / (2 * 0.3), rel=1e-6)


def test_position_is_the_integral_of_velocity_and_returns_home() -> None:
    sweep = _small_sweep()
    t = np.linspace(0.0, sweep.duration, 200_001)
    q, qd, _ = sweep.evaluate(t)
    integral = cumulative_trapezoid(qd, t, axis=0, initial=0.0)
    np.testing.assert_allclose(q - q[0], integral, atol=1e-8)
    np.testing.assert_allclose(q[0], sweep.home)
    np.testing.assert_allclose(q[-1], sweep.home, atol=1e-12)
    np.testing.assert_array_equal(qd[[0, -1]], 0.0)


def test_plateaus_have_exactly_the_requested_velocities() -> None:
    sweep = _small_sweep()
    schedule = sweep.schedule()
    assert list(schedule.columns) == ["joint", "velocity", "start", "end"]
    assert list(schedule["joint"].unique()) == [3, 1]  # the order given
    for _, row in schedule.iterrows():
        t = np.linspace(row.start, row.end, 51)
        q, qd, qdd = sweep.evaluate(t)
        j = int(row.joint) - 1
        others = [k for k in range(3) if k != j]
        np.testing.assert_array_equal(qd[:, j], row.velocity)
        np.testing.assert_array_equal(qdd[:, j], 0.0)
        np.testing.assert_array_equal(qd[:, others], 0.0)
        np.testing.assert_array_equal(q[:, others], np.broadcast_to(sweep.home[others], (51, 2)))
    for joint in (3, 1):
        mine = schedule[schedule["joint"] == joint]
        assert sorted(mine["velocity"]) == [-0.5, -0.2, 0.2, 0.5]
        # Pairs +v, -v of equal duration, in increasing speed.
        np.testing.assert_array_equal(np.abs(mine["velocity"]), [0.2, 0.2, 0.5, 0.5])
        np.testing.assert_array_equal(mine["velocity"].to_numpy()[::2], [0.2, 0.5])


def test_schedule_timing_is_consistent() -> None:
    sweep = _small_sweep()
    schedule = sweep.schedule()
    np.testing.assert_allclose(schedule["end"] - schedule["start"], 0.4)
    gaps = schedule["start"].to_numpy()[1:] - schedule["end"].to_numpy()[:-1]
    # One ramp between plateaus of a joint, two (down to rest, up again) between joints.
    np.testing.assert_allclose(gaps, [0.3, 0.3, 0.3, 0.6, 0.3, 0.3, 0.3])
    assert schedule["start"].iloc[0] == pytest.approx(0.3)
    assert sweep.duration == pytest.approx(schedule["end"].iloc[-1] + 0.3)
    n = len(schedule)
    assert sweep.duration == pytest.approx(n * 0.4 + (n + 2) * 0.3)


def test_default_velocities_are_the_thesis_sweeps() -> None:
    sweep = VelocitySweep([0.0])
    np.testing.assert_array_equal(sweep.velocities, sweep_velocities())
    assert sweep.hold == 1.0 and sweep.ramp == 0.5
    n = sweep_velocities().size
    assert sweep.duration == pytest.approx(n * 1.0 + (n + 1) * 0.5)


def test_travel_check_is_exact() -> None:
    sweep = _small_sweep(joints=[1])
    t = np.linspace(0.0, sweep.duration, 400_001)
    q = sweep.evaluate(t)[0][:, 0]
    low, high = q.min(), q.max()
    # Room above home: the excursions go up; the dense maximum is the limit.
    assert low == pytest.approx(0.1, abs=1e-9) and high > 0.3
    # Less room below (0.1 rad) than above, so the excursions stay upwards.
    _small_sweep(joints=[1], position_limits=([0.0, -1.0, -1.0], [high + 1e-7, 1.0, 1.0]))
    with pytest.raises(InputValueError, match=r"joint 1 would travel over \[0.1, "):
        _small_sweep(joints=[1], position_limits=([0.0, -1.0, -1.0], [high - 1e-4, 1.0, 1.0]))


def test_excursion_goes_to_the_side_with_more_room() -> None:
    limits = ([-2.0, -2.0, -2.0], [0.5, 2.0, 2.0])
    sweep = _small_sweep(joints=[1], position_limits=limits)
    t = np.linspace(0.0, sweep.duration, 20_001)
    q = sweep.evaluate(t)[0][:, 0]
    assert q.max() == pytest.approx(0.1, abs=1e-9) and q.min() < -0.2
    assert sweep.schedule()["velocity"].iloc[0] == -0.2
    assert (q >= -2.0).all() and (q <= 0.5).all()


def test_dict_round_trip() -> None:
    sweep = _small_sweep()
    spec = yaml.safe_load(yaml.safe_dump(sweep.to_dict()))
    again = VelocitySweep.from_dict(spec)
    t = np.linspace(0.0, sweep.duration, 1001)
    for a, b in zip(sweep.evaluate(t), again.evaluate(t), strict=True):
        np.testing.assert_array_equal(a, b)
    fast_only = VelocitySweep.from_dict({"home": [0.0], "fast": [-1.0, 1.0, 0.5], "slow": None})
    np.testing.assert_array_equal(fast_only.velocities, [-1.0, -0.5, 0.5, 1.0])


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"joints": [0]}, InputValueError, "joint numbers from 1 to n_dof = 3"),
        ({"joints": [4]}, InputValueError, "joint numbers from 1 to n_dof = 3"),
        ({"joints": [True]}, InputValueError, "joint numbers"),
        ({"joints": [1, 1]}, InputValueError, "distinct"),
        ({"velocities": [-0.2, 0.0, 0.2]}, InputValueError, "nonzero"),
        ({"velocities": [-0.2, 0.2, 0.5]}, InputValueError, r"no opposite for \[0.5\]"),
        ({"velocities": [[0.2, -0.2]]}, DimensionError, "shape"),
        ({"hold": 0.0}, InputValueError, r"hold must be a positive"),
        ({"ramp": -1.0}, InputValueError, r"ramp must be a positive"),
        ({"position_limits": (0.2, 1.0)}, InputValueError, "joint 1 has home = 0.1"),
        ({"position_limits": (1.0, -1.0)}, InputValueError, "lower < upper"),
        ({"position_limits": ([0.0, 0.0], 1.0)}, DimensionError, r"shape \(3,\)"),
        ({"position_limits": ([-1, -1, 0], [1, 1, 0.5])}, InputValueError, "joint 3 would travel"),
    ],
)
def test_sweep_rejects_bad_input(kwargs: dict[str, object], error: type, match: str) -> None:
    with pytest.raises(error, match=match):
        _small_sweep(**kwargs)


def test_sweep_rejects_bad_home_and_specifications() -> None:
    with pytest.raises(InputValueError, match="radians"):
        VelocitySweep([90.0])
    with pytest.raises(DimensionError, match=r"home must have shape \(n_dof,\)"):
        VelocitySweep([[0.0]])
    with pytest.raises(InputTypeError, match=r"unknown keys \['speed'\]"):
        VelocitySweep.from_dict({"home": [0.0], "speed": 1.0})
    with pytest.raises(InputValueError, match="needs the key 'home'"):
        VelocitySweep.from_dict({"velocities": [-1.0, 1.0]})
    with pytest.raises(InputValueError, match="not both"):
        VelocitySweep.from_dict({"home": [0.0], "velocities": [-1.0, 1.0], "fast": [-1, 1, 1]})
    with pytest.raises(InputValueError, match="must be 'velocity_sweep'"):
        VelocitySweep.from_dict({"home": [0.0], "type": "fourier"})
    with pytest.raises(InputTypeError, match="must be a mapping"):
        VelocitySweep.from_dict([0.0])


# ------------------------------------------------------------------ scenario
def _write_scenario(tmp_path: Path, robot: str, trajectory: dict[str, object]) -> Path:
    spec = {
        "name": "friction-sweep",
        "duration": 1.0,
        "robot": robot,
        "controller": {
            "type": "pid",
            "kp": 100.0,
            "ki": 0.0,
            "kd": 10.0,
            "friction_compensation": False,
        },
        "trajectory": trajectory,
    }
    path = tmp_path / "sweep.yaml"
    path.write_text(yaml.safe_dump(spec))
    return path


def test_scenario_velocity_sweep_round_trip(tmp_path: Path) -> None:
    trajectory = {
        "type": "velocity_sweep",
        "joints": [2],
        "fast": [-1.0, 1.0, 0.5],
        "slow": [-0.1, 0.1, 0.1],
        "hold": 0.5,
        "ramp": 0.2,
        "home": [0.1, -0.2],
    }
    built = load_scenario(_write_scenario(tmp_path, "planar2", trajectory)).build()["trajectory"]
    assert isinstance(built, VelocitySweep)
    np.testing.assert_array_equal(built.velocities, [-1.0, -0.5, -0.1, 0.1, 0.5, 1.0])
    assert built.joints == (2,) and built.hold == 0.5 and built.ramp == 0.2
    np.testing.assert_array_equal(built.home, [0.1, -0.2])
    again = VelocitySweep.from_dict(built.to_dict())
    np.testing.assert_array_equal(again.schedule(), built.schedule())
    # home defaults to q = 0 and every joint is swept.
    default = load_scenario(_write_scenario(tmp_path, "planar2", {"type": "velocity_sweep"}))
    sweep = default.build()["trajectory"]
    np.testing.assert_array_equal(sweep.home, [0.0, 0.0])
    assert sweep.joints == (1, 2)


def test_scenario_checks_the_sweep_against_the_robot_limits(tmp_path: Path) -> None:
    # LWR joint 2 is limited to ±120°: 2 rad/s held 1 s from q = 0 leaves it.
    path = _write_scenario(tmp_path, "lwr4", {"type": "velocity_sweep", "joints": [2]})
    with pytest.raises(InputValueError, match=r"joint 2 would travel .* position_limits"):
        load_scenario(path).build()


# ------------------------------------------------------------------ identification
def _planar2_with_friction() -> RobotModel:
    base = load("planar2")
    friction = CoulombViscous(c_pos=C_POS, c_neg=C_NEG, fv=FV)
    return base.with_standard_parameters(base.parameter_vector(), friction=friction)


def _stiff_pid(robot: RobotModel) -> JointPID:
    # Stiff enough that the resting joint stays below rest_velocity while the other
    # accelerates (M_11 ≈ 2.6 kg m², M_22 ≈ 0.33 kg m²); friction NOT compensated,
    # so it appears in the commanded torque.
    return JointPID(
        kp=[2500.0, 800.0], ki=0.0, kd=[150.0, 30.0], model=robot, friction_compensation=False
    )


@pytest.fixture(scope="module")
def rigid_run() -> SimulationResult:
    robot = _planar2_with_friction()
    sweep = VelocitySweep(HOME, velocities=SPEEDS, hold=1.5, ramp=0.5)
    return simulate(RigidPlant(robot), _stiff_pid(robot), sweep, sweep.duration, dt=DT)


@pytest.fixture(scope="module")
def rigid_identification(rigid_run: SimulationResult) -> FrictionIdentification:
    return identify_friction(rigid_run.log, _planar2_with_friction())


def _zoh_bias_bound(robot: RobotModel) -> np.ndarray:
    """dt/2 · max |∂g_j/∂q_j| [N m s/rad], the zero-order-hold bias of the viscous slope.

    The command (with ĝ(q_k)) is held over a period while the joint moves on by
    v·dt, so the gravity actually met is g(q_k + v dt/2) on average: a torque
    error ∂g/∂q · v · dt/2 that flips sign with v and tilts the map.
    """
    grid = np.stack(np.meshgrid(*[np.linspace(-np.pi, np.pi, 41)] * 2), -1).reshape(-1, 2)
    h = 1e-6
    slopes = [
        (robot.gravity(grid + h * np.eye(2)[j]) - robot.gravity(grid - h * np.eye(2)[j]))[:, j]
        / (2 * h)
        for j in range(2)
    ]
    return DT / 2 * np.abs(np.array(slopes)).max(axis=1)


def test_identify_friction_recovers_planted_coulomb_viscous(
    rigid_identification: FrictionIdentification,
) -> None:
    result = rigid_identification
    assert result.joints == (1, 2)
    bound = _zoh_bias_bound(_planar2_with_friction())  # ≈ [0.0098, 0.0025]
    for j in (1, 2):
        fit = result.fits[j]["coulomb_viscous"]
        assert isinstance(fit, FrictionFit) and isinstance(fit.model, CoulombViscous)
        p = fit.parameters
        # The viscous slope carries the ZOH bias (halving dt halves it); the
        # Coulomb levels at |v| <= 1 rad/s at most that bias times 1 rad/s.
        assert abs(p["fv"] - FV[j - 1]) <= bound[j - 1]
        assert abs(p["c_pos"] - C_POS[j - 1]) <= bound[j - 1]
        assert abs(p["c_neg"] - C_NEG[j - 1]) <= bound[j - 1]
        assert fit.rms < 2e-3
        # The plain Coulomb fit averages C± + fv v over the plateaus (eq. 2.7 read
        # on a viscous joint): C+ + fv · mean(v > 0).
        mean_v = np.mean([0.1, 0.4, 1.0])
        coulomb = result.fits[j]["coulomb"].parameters
        assert coulomb["c_pos"] == pytest.approx(C_POS[j - 1] + FV[j - 1] * mean_v, abs=0.01)
        assert coulomb["c_neg"] == pytest.approx(C_NEG[j - 1] - FV[j - 1] * mean_v, abs=0.01)


def test_maps_hold_only_the_joints_own_plateaus(
    rigid_run: SimulationResult, rigid_identification: FrictionIdentification
) -> None:
    for j in (1, 2):
        table = rigid_identification.joint_map(j)
        # One row per planted plateau: the other joint's sweep adds nothing.
        np.testing.assert_allclose(table["velocity"], SPEEDS, atol=1e-3)
        planted = CoulombViscous(C_POS[j - 1], C_NEG[j - 1], FV[j - 1])
        truth = planted.torque(np.array(SPEEDS)[:, None])[:, 0]
        # Within the ZOH gravity bias of the fastest plateau (0.0098 N m on joint 1);
        # the slow points carry smaller coupling errors of the resting joint.
        bound = _zoh_bias_bound(_planar2_with_friction()).max()
        np.testing.assert_allclose(table["torque"], truth, atol=bound)
        assert (table["n_samples"] > 500).all()
    only_two = identify_friction(rigid_run.log, _planar2_with_friction(), joints=[2])
    assert only_two.joints == (2,)
    pd.testing.assert_frame_equal(only_two.joint_map(2), rigid_identification.joint_map(2))


def test_result_tables_dict_and_plot(rigid_identification: FrictionIdentification) -> None:
    result = rigid_identification
    table = result.to_pandas()
    assert len(table) == 2 * 3
    assert list(table.columns[:2]) == ["joint", "model"]
    assert {"c_pos", "c_neg", "fv", "fc", "fs", "vs", "rms", "n_plateaus"} <= set(table.columns)
    row = table[(table["joint"] == 2) & (table["model"] == "coulomb_viscous")].iloc[0]
    assert row["fv"] == result.fits[2]["coulomb_viscous"].parameters["fv"]
    assert np.isnan(row["fs"])
    assert set(result.maps.columns) >= {"joint", "velocity", "torque", "torque_std"}

    spec = result.to_dict()
    assert yaml.safe_load(yaml.safe_dump(spec)) == spec
    assert spec["units"]["fv"] == "N m s/rad" and spec["units"]["c_pos"] == "N m"
    assert spec["torque"] == "motor"
    joint_2 = spec["joints"][1]
    assert joint_2["joint"] == 2
    assert joint_2["models"]["coulomb_viscous"]["c_pos"] == pytest.approx(C_POS[1], abs=0.01)
    assert joint_2["map"]["velocity"] == list(result.joint_map(2)["velocity"])

    figure = result.plot()
    assert isinstance(figure, Figure)
    assert len(figure.axes) == 2
    assert figure.axes[1].get_title().startswith("joint 2")
    assert len(figure.axes[0].get_lines()) >= 3  # one curve per model


def test_flexible_joints_link_side_and_total_friction() -> None:
    """torque="joint" gives the link-side friction (eq. 2.10), "motor" link + motor."""
    robot = load("planar2")
    link = CoulombViscous(c_pos=[0.5, 0.4], c_neg=[-0.5, -0.3], fv=[0.3, 0.2])
    motor = Coulomb([0.3, 0.2], [-0.3, -0.25])
    plant = FlexiblePlant(
        robot,
        stiffness=[3000.0, 3000.0],
        damping=[5.0, 5.0],
        motor_inertia=[1.0, 1.0],
        motor_friction=motor,
        link_friction=link,
    )
    sweep = VelocitySweep(HOME, joints=[2], velocities=SPEEDS, hold=1.5, ramp=0.5)
    controller = JointPID(
        kp=[1500.0, 800.0], ki=0.0, kd=[80.0, 40.0], model=robot, friction_compensation=False
    )
    log = simulate(plant, controller, sweep, sweep.duration, dt=DT).log
    link_side = identify_friction(log, robot, torque="joint", models="coulomb_viscous")
    total = identify_friction(log, robot, torque="motor", models="coulomb_viscous")
    assert link_side.joints == total.joints == (2,)
    # Tolerance: 4x the ZOH bound of joint 2 (0.0025 N m s/rad): the spring-motor
    # ripple (torque_std ≈ 0.09 N m) is not fully averaged over 1.5 s plateaus.
    expected = {
        "link": (0.4, -0.3, 0.2, link_side),
        "link + motor": (0.4 + 0.2, -0.3 - 0.25, 0.2, total),
    }
    for c_pos, c_neg, fv, result in expected.values():
        p = result.fits[2]["coulomb_viscous"].parameters
        assert p["c_pos"] == pytest.approx(c_pos, abs=0.01)
        assert p["c_neg"] == pytest.approx(c_neg, abs=0.01)
        assert p["fv"] == pytest.approx(fv, abs=0.01)


# ------------------------------------------------------------------ errors
def _synthetic_log(velocity: np.ndarray, n_dof: int = 2) -> Log:
    """Joint 1 moving at ``velocity`` [rad/s] (others at rest), tau_m = g(q) + 0.3 sign(v)."""
    q = np.zeros((velocity.shape[0], n_dof))
    q[:, 0] = np.cumsum(velocity) * DT
    tau = np.zeros_like(q)
    tau[:, 0] = 0.3 * np.sign(velocity)
    if n_dof == 2:
        tau += load("planar2").gravity(q)
    return Log(t=np.arange(velocity.shape[0]) * DT, q=q, tau_m=tau)


T_SYNTHETIC = np.arange(0.0, 4.0, DT)
BACK_AND_FORTH = np.where(T_SYNTHETIC < 2.0, 0.5, -0.5)


def test_identify_friction_errors(rigid_run: SimulationResult) -> None:
    robot = _planar2_with_friction()
    with pytest.raises(InputValueError, match=r"torque='joint' needs the columns tau_j_1"):
        identify_friction(rigid_run.log, robot, torque="joint")
    with pytest.raises(InputValueError, match=r"torque must be one of \['joint', 'motor'\]"):
        identify_friction(rigid_run.log, robot, torque="link")
    with pytest.raises(DimensionError, match=r"the log has 3 joints .* has 2"):
        identify_friction(_synthetic_log(BACK_AND_FORTH, n_dof=3), robot)
    with pytest.raises(InputValueError, match="the robot stands still"):
        identify_friction(_synthetic_log(0.0 * T_SYNTHETIC), robot)
    # Both joints swing together: motion, but never one joint alone.
    swing = 0.3 * np.sin(np.pi * T_SYNTHETIC)[:, None] * np.ones((1, 2))
    together = Log(t=T_SYNTHETIC, q=swing, tau_m=np.zeros_like(swing))
    with pytest.raises(InputValueError, match="no constant-velocity plateau found"):
        identify_friction(together, robot)
    with pytest.raises(InputValueError, match="joint 2 has no constant-velocity plateau"):
        identify_friction(_synthetic_log(BACK_AND_FORTH), robot, joints=[2])
    with pytest.raises(InputValueError, match="models must be a non-empty sequence"):
        identify_friction(rigid_run.log, robot, models=("lugre",))
    with pytest.raises(InputValueError, match="joints must be distinct joint numbers"):
        identify_friction(rigid_run.log, robot, joints=[3])
    with pytest.raises(InputValueError, match=r"settle must be a finite number >= 0"):
        identify_friction(rigid_run.log, robot, settle=-1.0)
    with pytest.raises(InputValueError, match=r"max_acceleration must be a finite number > 0"):
        identify_friction(rigid_run.log, robot, max_acceleration=0.0)
    with pytest.raises(InputTypeError, match=r"log must be a sensorless\.io\.Log"):
        identify_friction(rigid_run, robot)
    with pytest.raises(InputTypeError, match="robot must be a RobotModel"):
        identify_friction(rigid_run.log, "planar2")
    # A fit that cannot run names the joint and the model: positive velocities only.
    forward = np.where(T_SYNTHETIC < 2.0, 0.5, 0.2)
    with pytest.raises(InputValueError, match=r"joint 1, model 'coulomb': .*1 positive and 1 neg"):
        identify_friction(_synthetic_log(forward), robot)


def test_synthetic_log_gives_exact_coulomb_and_unknown_joint_error() -> None:
    result = identify_friction(_synthetic_log(BACK_AND_FORTH), load("planar2"), models="coulomb")
    assert result.joints == (1,)
    assert result.fits[1]["coulomb"].parameters == pytest.approx({"c_pos": 0.3, "c_neg": -0.3})
    with pytest.raises(
        InputValueError, match=r"joint 2 was not identified; identified joints: \[1\]"
    ):
        result.joint_map(2)
