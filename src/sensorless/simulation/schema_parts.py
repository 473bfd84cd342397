"""The sections of a scenario file as pydantic models: friction, plant, control, motion, contacts.

:mod:`sensorless.simulation.schema` assembles them into the whole file,
:class:`~sensorless.simulation.schema.ScenarioFile`, and says what the
declarations mean (defaults equal to those of the builders in
:mod:`sensorless.simulation.scenario`, keys "absent by default"). Units SI and
radians; per-joint values are one number for every joint or a list of one
per joint, checked against the robot's joints.
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping
from typing import TYPE_CHECKING, Annotated, Any, Literal, TypeAlias

from pydantic import AfterValidator, Field, ValidationInfo, WithJsonSchema, model_validator
from pydantic_core import PydanticCustomError

from .. import robots
from ..io.file_schema import (
    Count,
    FileModel,
    Fraction,
    NonNegative,
    PerJoint,
    PerJointFraction,
    PerJointNonNegative,
    PerJointPositive,
    Positive,
    PositiveInt,
    Vector3,
    absent,
    context_n_dof,
    joint_list,
    known_name,
    one_of,
    per_joint,
)

__all__ = [
    "FRICTION_HELP",
    "CoulombFriction",
    "FlexiblePlantSpec",
    "LuGreFriction",
    "ModelErrorSpec",
    "PayloadSpec",
    "RandomCollisionsSpec",
    "RigidPlantSpec",
    "SensorsSpec",
]

# ----------------------------------------------------------------------------- values


def _link_within(link: int, info: ValidationInfo) -> int:
    n_dof = context_n_dof(info)
    if n_dof is not None and link > n_dof:
        raise PydanticCustomError(
            "link_range",
            "expected a link number in 1..{n_dof}; got {link}",
            {"n_dof": n_dof, "link": link},
        )
    return link


def _ordered(pair: list[float]) -> list[float]:
    if pair[0] > pair[1]:
        raise ValueError(f"expected [low, high] with low <= high; got {pair}")
    return pair


def _sweep(triple: list[float]) -> list[float]:
    low, high, step = triple
    if low > high or step <= 0:
        raise ValueError(f"expected [low, high, step] with low <= high and step > 0; got {triple}")
    return triple


def _nonzero(vector: list[float]) -> list[float]:
    if not any(vector):
        raise ValueError(f"expected a non-zero vector; got {vector}")
    return vector


RobotName = Annotated[
    str,
    AfterValidator(known_name("robot", robots.available)),
    WithJsonSchema({"type": "string", "enum": robots.available()}),
]
Link = Annotated[int, Field(ge=1), AfterValidator(_link_within)]
Seed = Annotated[int, Field(ge=0)]
PositiveRange = Annotated[
    list[Positive], Field(min_length=2, max_length=2), AfterValidator(_ordered)
]
NonNegativeRange = Annotated[
    list[NonNegative], Field(min_length=2, max_length=2), AfterValidator(_ordered)
]
Sweep = Annotated[list[float], Field(min_length=3, max_length=3), AfterValidator(_sweep)]

if TYPE_CHECKING:
    PerJointNonPositive: TypeAlias = float | list[float]
    PerJointGainError: TypeAlias = float | list[float]
    Friction: TypeAlias = "str | LuGreFriction | CoulombFriction"
    Plant: TypeAlias = "RigidPlantSpec | FlexiblePlantSpec"
    Controller: TypeAlias = "PIDSpec | ComputedTorqueSpec"
    Trajectory: TypeAlias = (
        "ViaPointsSpec | RandomPointToPointSpec | VelocitySweepSpec | FourierSpec"
    )
    Contact: TypeAlias = "HalfSineContact | PushContact | RecordedContact"
    JointNumbers: TypeAlias = int | list[int]
    JointSigns: TypeAlias = list[int]
    JointPositions: TypeAlias = list[float]
else:
    PerJointNonPositive = per_joint(Annotated[float, Field(le=0)], "per_joint_nonpositive")
    PerJointGainError = per_joint(Annotated[float, Field(gt=-1)], "per_joint_gain_error")
    JointSigns = joint_list(Literal[-1, 1])
    JointPositions = joint_list(float)


# ----------------------------------------------------------------------------- friction, error


class LuGreFriction(FileModel):
    """LuGre friction with the steady state of the robot's Coulomb + viscous model."""

    type: Literal["lugre"]
    stiction_ratio: Positive = Field(default=1.5, description="F_s / F_c [-].")
    stribeck_velocity: Positive = Field(default=0.01, description="Stribeck velocity v_s [rad/s].")
    presliding: Positive = Field(default=1e-4, description="Presliding displacement at F_c [rad].")


class CoulombFriction(FileModel):
    """Coulomb friction: c_pos at positive, c_neg at negative velocity."""

    type: Literal["coulomb"]
    c_pos: PerJointNonNegative = Field(description="Torque at positive velocity [N m], >= 0.")
    c_neg: PerJointNonPositive = Field(
        description="Signed torque at negative velocity [N m], <= 0."
    )


def _friction_kind(value: Any) -> Any:
    if isinstance(value, str):
        return "name"
    return value.get("type") if isinstance(value, Mapping) else None


if not TYPE_CHECKING:
    Friction = one_of(
        "friction",
        {"name": Literal["robot", "none"], "lugre": LuGreFriction, "coulomb": CoulombFriction},
        key="type",
        pick=_friction_kind,
        expected="'robot', 'none', null or a mapping with type lugre or coulomb",
    )

FRICTION_HELP = "'robot' (the robot's own), 'none' or null (no friction), or a mapping with type"


class ModelErrorSpec(FileModel):
    """How the nominal model differs from the true robot (``perturb``)."""

    inertial: Fraction = Field(
        default=0.0, description="Relative band of the inertial parameters [-]."
    )
    friction: Fraction = absent("Relative band of the friction parameters [-] (absent: inertial).")
    seed: Seed = Field(default=0, description="Seed of the nominal model (shared by every run).")


class FrictionDrift(FileModel):
    """Warm-up and offset drift of the true friction (``DriftingFriction``); rigid plants only."""

    warmup: PerJointFraction = Field(default=0.3, description="Coulomb part lost once warm [-].")
    warmup_viscous: PerJointFraction | None = Field(
        default=None, description="Viscous part lost once warm [-] (null: warmup)."
    )
    time_constant: PerJointPositive = Field(default=900.0, description="Thermal time constant [s].")
    offset_rate: PerJointNonNegative = Field(
        default=0.0, description="Largest offset rate [N m/s]."
    )
    offset_periods: PositiveRange = Field(
        default=[600.0, 3600.0], description="Shortest and longest period of the offset [s]."
    )
    seed: Seed = Field(default=0, description="Seed of the offset's periods, phases and signs.")


# ----------------------------------------------------------------------------- plant


class RigidPlantSpec(FileModel):
    """Rigid joints (eq. 5.1)."""

    type: Literal["rigid"] = "rigid"
    friction_drift: FrictionDrift | None = Field(
        default=None, description="Drift of the true friction."
    )


class TorqueLoop(FileModel):
    """The joint-torque feedback loop of eq. 2.2."""

    motor_inertia: PerJointPositive = Field(description="Apparent motor inertia B_θ [kg m²].")
    damping: PerJointNonNegative = Field(description="Damping D_s [N m s/rad].")


class FlexiblePlantSpec(FileModel):
    """Flexible joints (eq. 2.1) with optional torque feedback (eq. 2.2)."""

    type: Literal["flexible"]
    stiffness: PerJointPositive = Field(description="Joint stiffness K [N m/rad].")
    damping: PerJointNonNegative = Field(default=0.0, description="Joint damping D [N m s/rad].")
    motor_inertia: PerJointPositive | None = Field(
        default=None, description="Motor inertia B [kg m²] (null: the robot's armature)."
    )
    motor_friction: Friction | None = Field(
        default="none", description=f"Motor-side friction: {FRICTION_HELP}."
    )
    link_friction: Friction | None = Field(
        default="robot", description=f"Link-side friction: {FRICTION_HELP}."
    )
    feedback: TorqueLoop | None = Field(default=None, description="Torque loop (null: none).")


if not TYPE_CHECKING:
    Plant = one_of(
        "plant",
        {"rigid": RigidPlantSpec, "flexible": FlexiblePlantSpec},
        key="type",
        default="rigid",
        expected="a mapping with type rigid (the default) or flexible",
    )


# ----------------------------------------------------------------------------- controller


class _Gains(FileModel):
    kp: PerJointNonNegative = absent("Proportional gain [N m/rad] (computed torque: [1/s²]).")
    ki: PerJointNonNegative = absent("Integral gain [N m/(rad s)] (computed torque: [1/s³]).")
    kd: PerJointNonNegative = absent("Derivative gain [N m s/rad] (computed torque: [1/s]).")
    friction_compensation: bool = Field(
        default=True, description="Add the nominal friction torque."
    )
    torque_limit: PerJointPositive | None = Field(
        default=None, description="Saturation [N m] (null: the model's effort limits)."
    )


class PIDSpec(_Gains):
    """Joint PID from the nominal model; gains given, or from a bandwidth (kp = J ω², kd = 2ζJω)."""

    type: Literal["pid"] = "pid"
    gravity_compensation: bool = Field(default=True, description="Add the nominal gravity torque.")
    bandwidth: Positive = absent(
        "Bandwidth ω [rad/s] for kp, kd, ki = 0 (absent: give kp, ki, kd)."
    )
    damping_ratio: NonNegative = Field(
        default=1.0, description="Damping ratio ζ [-] (with bandwidth)."
    )

    @model_validator(mode="after")
    def _gains_or_bandwidth(self) -> PIDSpec:
        if self.bandwidth is None:
            missing = [name for name in ("kp", "ki", "kd") if getattr(self, name) is None]
            if missing:
                raise PydanticCustomError(
                    "gains",
                    "required key is missing (kp, ki and kd, or bandwidth)",
                    {"field": missing[0]},
                )
            if "damping_ratio" in self.model_fields_set:
                raise PydanticCustomError(
                    "gains", "damping_ratio is used with bandwidth only", {"field": "damping_ratio"}
                )
        return self


class ComputedTorqueSpec(_Gains):
    """Computed torque with the nominal model; kp = ω², kd = 2ζω, ki = 0 unless given.

    No ``gravity_compensation``: the inverse dynamics holds ĝ already.
    """

    type: Literal["computed_torque"]
    bandwidth: Positive = Field(default=20.0, description="Bandwidth ω [rad/s].")
    damping_ratio: NonNegative = Field(default=1.0, description="Damping ratio ζ [-].")


if not TYPE_CHECKING:
    Controller = one_of(
        "controller",
        {"pid": PIDSpec, "computed_torque": ComputedTorqueSpec},
        key="type",
        default="pid",
        expected="a mapping with type pid (the default) or computed_torque",
    )


# ----------------------------------------------------------------------------- trajectory


def _via_points(points: list[list[float]], info: ValidationInfo) -> list[list[float]]:
    n_dof = context_n_dof(info)
    width = len(points[0]) if n_dof is None else n_dof + 1
    for k, row in enumerate(points):
        if len(row) != width or width < 2:
            raise ValueError(
                f"expected rows [time, q1, ..., q{width - 1}] of {width} numbers; "
                f"row {k} has {len(row)}"
            )
    times = [row[0] for row in points]
    if times[0] != 0 or any(b <= a for a, b in itertools.pairwise(times)):
        raise ValueError(f"expected times starting at 0 s and strictly increasing; got {times}")
    return points


class ViaPointsSpec(FileModel):
    """Quintic motion through via points (thesis Tables 5.1, 5.8), repeated to the duration."""

    type: Literal["via_points"]
    points: Annotated[list[list[float]], Field(min_length=2), AfterValidator(_via_points)] = Field(
        description="Rows [time [s], q1, ..., qn]; the last row equals the first to repeat."
    )
    degrees: bool = Field(default=True, description="Positions in degrees (false: radians).")
    joint_sign: JointSigns = absent("Sign per joint applied to the positions (absent: 1).")


class RandomPointToPointSpec(FileModel):
    """Random point-to-point quintic motion within the joint limits."""

    type: Literal["random_point_to_point"]
    max_velocity: Positive = Field(description="Largest joint velocity [rad/s].")
    limit_margin: Annotated[float, Field(ge=0, lt=0.5)] = Field(
        default=0.2, description="Fraction of each joint range kept away from its limits [-]."
    )
    segment_time: PositiveRange = Field(
        default=[1.0, 3.0], description="Range of segment times [s]."
    )
    rest: NonNegativeRange = Field(
        default=[0.0, 0.5], description="Range of rests between segments [s]."
    )


if not TYPE_CHECKING:
    JointNumbers = one_of(
        "joint_numbers",
        {"number": Link, "list": Annotated[list[Link], Field(min_length=1)]},
        pick=lambda v: "list" if isinstance(v, list) else "number",
        expected="a joint number or a list of joint numbers",
    )


class VelocitySweepSpec(FileModel):
    """Constant-velocity friction experiment, one joint at a time (thesis §2.4.1)."""

    type: Literal["velocity_sweep"]
    home: JointPositions = absent("Pose between runs [rad] (absent: 0 for every joint).")
    joints: JointNumbers | None = Field(
        default=None, description="Joints to sweep, 1-based (null: all)."
    )
    velocities: Annotated[list[float], Field(min_length=1)] | None = Field(
        default=None,
        description="Velocities [rad/s] in pairs +v, -v (null: the sweeps fast and slow).",
    )
    fast: Sweep = Field(
        default=[-2.0, 2.0, 0.16], description="Wide sweep [low, high, step] [rad/s]."
    )
    slow: Sweep | None = Field(
        default=[-0.11, 0.11, 0.01],
        description="Slow sweep [low, high, step] [rad/s] (null: none).",
    )
    hold: Positive = Field(default=1.0, description="Time at each velocity [s].")
    ramp: Positive = Field(default=0.5, description="Time of each velocity change [s].")

    @model_validator(mode="after")
    def _velocities_or_sweeps(self) -> VelocitySweepSpec:
        if self.velocities is not None and {"fast", "slow"} & self.model_fields_set:
            raise PydanticCustomError(
                "sweep",
                "give velocities or the sweeps fast/slow, not both",
                {"field": "velocities"},
            )
        return self


def _harmonics(rows: list[list[float]], info: ValidationInfo) -> list[list[float]]:
    n_dof = context_n_dof(info)
    width = len(rows[0]) if n_dof is None else n_dof
    for k, row in enumerate(rows):
        if len(row) != width:
            raise ValueError(
                f"expected one row of {width} numbers (one per joint) per harmonic; "
                f"row {k} has {len(row)}"
            )
    return rows


Harmonics = Annotated[list[list[float]], Field(min_length=1), AfterValidator(_harmonics)]


class FourierSpec(FileModel):
    """A finite Fourier series (thesis §2.4.3): the ``trajectory`` ``sensorless excite`` writes.

    q_j(t) = offset_j + Σ_l a_lj/(ω l) sin(ω l t) − b_lj/(ω l) cos(ω l t),
    ω = 2π base_frequency; periodic, it runs for the scenario's duration.
    """

    type: Literal["fourier"]
    base_frequency: Positive = Field(description="Fundamental frequency [Hz].")
    offset: JointPositions = Field(description="Offset q0 per joint [rad].")
    a: Harmonics = Field(description="Sine coefficients [rad/s], one row per harmonic.")
    b: Harmonics = Field(description="Cosine coefficients [rad/s], one row per harmonic.")
    duration: Positive = absent(
        "Period the series was optimised over [s]; the scenario's duration is simulated."
    )

    @model_validator(mode="after")
    def _same_harmonics(self) -> FourierSpec:
        if len(self.a) != len(self.b) or len(self.a[0]) != len(self.b[0]):
            raise PydanticCustomError(
                "harmonics",
                "expected a and b of the same shape (harmonics, joints); got {a} and {b}",
                {
                    "field": "b",
                    "a": f"{len(self.a)} x {len(self.a[0])}",
                    "b": f"{len(self.b)} x {len(self.b[0])}",
                },
            )
        return self


if not TYPE_CHECKING:
    Trajectory = one_of(
        "trajectory",
        {
            "via_points": ViaPointsSpec,
            "random_point_to_point": RandomPointToPointSpec,
            "velocity_sweep": VelocitySweepSpec,
            "fourier": FourierSpec,
        },
        key="type",
        expected="a mapping with type via_points, random_point_to_point, velocity_sweep or fourier",
    )


# ----------------------------------------------------------------------------- sensors, contacts


class SensorsSpec(FileModel):
    """Measurement model (``SensorModel``); every effect off by default."""

    encoder_resolution: PerJointNonNegative = Field(default=0.0, description="Encoder step [rad].")
    position_noise: PerJointNonNegative = Field(
        default=0.0, description="Position noise std [rad]."
    )
    motor_torque_noise: PerJointNonNegative = Field(
        default=0.0, description="Motor torque noise std [N m]."
    )
    motor_torque_gain_error: PerJointGainError = Field(
        default=0.0, description="Relative gain error of the motor torque [-], > -1."
    )
    torque_sensor_noise: PerJointNonNegative = Field(
        default=0.0, description="Torque sensor noise std [N m]."
    )
    torque_sensor_bias: PerJoint = Field(default=0.0, description="Torque sensor offset [N m].")
    torque_sensor_hysteresis: PerJointNonNegative = Field(
        default=0.0, description="Play half-width of the torque sensor [N m]."
    )


class _ContactSpec(FileModel):
    id: PositiveInt = Field(description="Label of the contact in logs (>= 1, unique).")
    link: Link = Field(description="Link the force acts on, 1-based.")
    point: Vector3 = Field(default=[0.0, 0.0, 0.0], description="Point in the link frame [m].")
    direction: Annotated[Vector3, AfterValidator(_nonzero)] = Field(
        description="Direction of the force in the base frame (normalised)."
    )


class HalfSineContact(_ContactSpec):
    """Impact: half a sine of the force."""

    profile: Literal["half_sine"]
    start: NonNegative = Field(description="Start [s].")
    duration: Positive = Field(description="Length [s].")
    peak: NonNegative = Field(description="Largest force [N].")


class PushContact(_ContactSpec):
    """Push: ramp up, hold, ramp down."""

    profile: Literal["push"]
    start: NonNegative = Field(description="Start [s].")
    ramp: Positive = Field(description="Rise time [s].")
    hold: NonNegative = Field(description="Time at the peak [s].")
    release: Positive = Field(description="Fall time [s].")
    peak: NonNegative = Field(description="Force held [N].")


class RecordedContact(_ContactSpec):
    """A recorded force from a CSV file with columns t [s] and f [N]."""

    profile: Literal["recorded"]
    file: str = Field(description="CSV file of the force.")
    start: NonNegative = Field(default=0.0, description="Time of the first sample [s].")
    scale: float = Field(default=1.0, description="Factor on the force [-].")


if not TYPE_CHECKING:
    Contact = one_of(
        "contact",
        {"half_sine": HalfSineContact, "push": PushContact, "recorded": RecordedContact},
        key="profile",
        expected="a mapping with profile half_sine, push or recorded",
    )


class RandomCollisionsSpec(FileModel):
    """Contacts drawn at random from the run seed (``ContactSet.random``)."""

    count: Count = Field(description="Number of contacts in the run.")
    links: Annotated[list[Link], Field(min_length=1)] | None = Field(
        default=None, description="Links to choose from (null: 2..n)."
    )
    kinds: Annotated[list[Literal["half_sine", "push"]], Field(min_length=1)] = Field(
        default=["half_sine", "push"], description="Profiles to choose from."
    )
    peak_range: PositiveRange = Field(default=[20.0, 80.0], description="Range of peak forces [N].")
    duration_range: PositiveRange = Field(
        default=[0.1, 0.5], description="Range of contact lengths [s]."
    )
    min_gap: NonNegative = Field(default=1.0, description="Least time between contacts [s].")
    margin: NonNegative = Field(default=0.5, description="Contact-free time at both ends [s].")
    point_range: NonNegative = Field(
        default=0.05, description="Half-width of the cube of points [m]."
    )


class PayloadSpec(FileModel):
    """A payload on the true robot's end link, unknown to the nominal model (``Payload``)."""

    mass: Positive = Field(description="Mass [kg].")
    com: Vector3 = Field(
        default=[0.0, 0.0, 0.0], description="Centre of mass in the end-link frame [m]."
    )
    inertia: Annotated[list[float], Field(min_length=6, max_length=6)] = absent(
        "Inertia about the centre of mass, entries xx, xy, xz, yy, yz, zz in end-link axes "
        "[kg m²] (absent: a point mass)."
    )
