"""Benchmark scenarios: plain YAML files that describe a labelled simulated run.

A scenario names the true and the nominal robot, how they differ (model
error), the controller, the trajectory, the sensors, the contacts, the
duration and the seed. Shipped scenarios live in ``sensorless/data/scenarios``;
any other YAML file with the same keys works too: :mod:`sensorless.simulation.schema`
declares the format (and exports its JSON Schema), :func:`load_scenario` checks a
file against it before building anything.

Seeds: ``model_error.seed`` fixes the nominal model, so every run of a
scenario shares one robot and one model error (the situation of a user who
tunes on some runs and detects on others); the run seed drives sensor noise,
random trajectories and random contacts. :func:`generate` derives the seeds
of N collision-free and N collision runs from one master seed with
``numpy.random.SeedSequence``, so tuning and test data never share a seed.
"""

from __future__ import annotations

import copy
import importlib.resources
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from .._validation import check_dt, check_scalar
from .._version import __version__
from ..exceptions import InputValueError, MissingFileError, ModelError, UnknownNameError
from ..friction import Coulomb, CoulombViscous, FrictionModel, LuGre
from ..friction.drift import DriftingFriction
from ..io import write_log
from ..io.file_schema import read_yaml_mapping
from ..robots import load as load_robot
from ..robots.model import RobotModel
from ..trajectories import (
    FourierSeries,
    QuinticViaPoints,
    RandomPointToPoint,
    Trajectory,
    VelocitySweep,
)
from .collisions import Contact, ContactSet, HalfSine, Push, Recorded
from .controllers import ComputedTorque, JointPID
from .interaction_profiles import INTERACTION_PROFILES, interaction_profile
from .interactions import random_interactions
from .model_error import perturb, perturb_friction
from .payload import Payload, with_payload
from .plants import FlexiblePlant, Friction, RigidPlant, TorqueFeedback
from .schema import validate_scenario
from .sensors import SensorModel
from .simulator import SimulationResult, simulate

__all__ = ["Scenario", "available_scenarios", "generate", "load_scenario", "lugre_from"]


def _scenario_dir() -> Path:
    return Path(str(importlib.resources.files("sensorless") / "data" / "scenarios"))


def available_scenarios() -> list[str]:
    """Names of the scenarios shipped with the package."""
    return sorted(p.stem for p in _scenario_dir().glob("*.yaml"))


def lugre_from(
    friction: CoulombViscous,
    *,
    stiction_ratio: float = 1.5,
    stribeck_velocity: float = 0.01,
    presliding: float = 1e-4,
) -> LuGre:
    """A LuGre model with the steady state of a Coulomb + viscous model.

    F_c is the mean of |C₊| and |C₋|, F_s = ``stiction_ratio``·F_c, σ2 the
    viscous coefficient, σ0 = F_c / ``presliding`` (the presliding
    displacement [rad] at which the bristles carry F_c) and σ1 = √σ0, the
    ratio of Canudas de Wit et al. (1995, Table I: F_s/F_c = 1.5, σ1 = √σ0).
    These choices are ours (the thesis gives no LuGre numbers for the PUMA).
    """
    fc = 0.5 * (np.abs(friction.c_pos) + np.abs(friction.c_neg))
    sigma0 = fc / presliding
    return LuGre(
        sigma0=sigma0,
        sigma1=np.sqrt(sigma0),
        sigma2=friction.fv,
        fc=fc,
        fs=stiction_ratio * fc,
        vs=stribeck_velocity,
    )


@dataclass(frozen=True)
class Scenario:
    """A parsed scenario; :meth:`run` simulates it.

    Attributes
    ----------
    name : str
    spec : dict
        The YAML content (validated).
    """

    name: str
    spec: dict[str, Any]

    @property
    def duration(self) -> float:
        """Simulated time [s]."""
        return float(self.spec["duration"])

    @property
    def dt(self) -> float:
        """Control period [s]."""
        return float(self.spec.get("dt", 1e-3))

    @property
    def seed(self) -> int:
        """Default run seed."""
        return int(self.spec.get("seed", 0))

    def with_duration(self, seconds: float) -> Scenario:
        """The same scenario cut (or extended) to ``seconds`` [s]; random contacts scale along."""
        seconds = check_dt(seconds, "duration")
        spec = copy.deepcopy(self.spec)
        spec["duration"] = seconds
        if "random_collisions" in spec:
            count = int(spec["random_collisions"]["count"])
            spec["random_collisions"]["count"] = max(1, round(count * seconds / self.duration))
        return Scenario(self.name, spec)

    def with_sample_rate(self, rate: float) -> Scenario:
        """The same scenario controlled, sampled and logged at ``rate`` [Hz] (key ``dt`` = 1/rate).

        The plant is still integrated with RK4 substeps fine enough for
        stability (:func:`simulate`); robots, trajectory, contacts, sensors and
        seeds are unchanged.
        """
        spec = copy.deepcopy(self.spec)
        spec["dt"] = 1.0 / check_scalar(rate, "rate", "Hz")
        return Scenario(self.name, spec)

    def robots(self) -> tuple[RobotModel, RobotModel]:
        """The true robot (with its true friction) and the nominal model the user has."""
        true = load_robot(self.spec["robot"])
        nominal = load_robot(self.spec.get("nominal_robot", self.spec["robot"]))
        if "nominal_friction" in self.spec:  # set by with_exact_model
            friction = _friction(self.spec["nominal_friction"], nominal)
            parameters = nominal.parameter_vector()
            nominal = nominal.with_standard_parameters(parameters, friction=friction)
        true_friction = _friction(self.spec.get("true_friction", "robot"), true)
        true = true.with_standard_parameters(true.parameter_vector(), friction=true_friction)
        if self.spec.get("payload") is not None:  # on the true robot only: the model lacks it
            true = with_payload(true, Payload.from_dict(self.spec["payload"]))
        error = self.spec.get("model_error")
        if error:
            nominal = perturb(
                nominal,
                relative=float(error.get("inertial", 0.0)),
                friction_relative=float(error.get("friction", error.get("inertial", 0.0))),
                seed=int(error.get("seed", 0)),
                name=f"{nominal.name} (nominal)",
            )
        return true, nominal

    def nominal(self, kind: str = "motor") -> RobotModel:
        """The nominal model an observer of ``kind`` uses.

        On a rigid plant it is the nominal robot for every kind. On a flexible
        plant, the motor-torque observer sees the links plus the apparent motor
        inertia (B_θ of the torque loop, else B) as armature and the friction of
        the nominal robot; the torque-sensor observer (``kind="joint"``, eq. 4.9)
        sees the links alone and the link-side friction of the plant, with the
        scenario's friction error applied to it too.

        Parameters
        ----------
        kind : {"motor", "joint", "acceleration"}
            Observer kind (see :func:`sensorless.observers.observe`).
        """
        if kind not in ("motor", "joint", "acceleration"):
            raise InputValueError(
                f"observer kind must be motor, joint or acceleration; got {kind!r}"
            )
        true, nominal = self.robots()
        plant = self.spec.get("plant", {"type": "rigid"})
        if plant.get("type", "rigid") != "flexible":
            return nominal
        params = nominal.standard_parameters()
        if kind == "joint":
            params["Ia"] = 0.0
            error = self.spec.get("model_error") or {}
            friction = perturb_friction(
                _friction(plant.get("link_friction", "robot"), true),
                float(error.get("friction", error.get("inertial", 0.0))),
                int(error.get("seed", 0)) + 1,
            )
            return nominal.with_standard_parameters(params, friction=friction)
        feedback = plant.get("feedback")
        inertia = plant.get("motor_inertia") if feedback is None else feedback["motor_inertia"]
        if inertia is not None:
            params["Ia"] = np.broadcast_to(np.asarray(inertia, dtype=float), (nominal.n_dof,))
        return nominal.with_standard_parameters(params)

    def build(self, seed: int | None = None, collisions: bool = True) -> dict[str, Any]:
        """Everything :func:`simulate` needs, as keyword arguments."""
        seed = self.seed if seed is None else seed
        rng = np.random.default_rng(seed)
        true, nominal = self.robots()
        plant = _plant(self.spec.get("plant", {"type": "rigid"}), true)
        trajectory = _trajectory(self.spec["trajectory"], true, self.duration, rng)
        controller = _controller(self.spec["controller"], nominal, trajectory)
        contacts = ContactSet([])
        if collisions:
            contacts = _contacts(self.spec, true, self.duration, rng, trajectory)
        return {
            "plant": plant,
            "controller": controller,
            "trajectory": trajectory,
            "duration": self.duration,
            "dt": self.dt,
            "sensors": SensorModel.from_dict(self.spec.get("sensors", {})),
            "contacts": contacts,
            "seed": seed,
            "metadata": {
                "scenario": self.name,
                "robot": true.name,
                "nominal_robot": nominal.name,
                "model_error": self.spec.get("model_error"),
                "collisions_enabled": collisions,
                "library_version": __version__,
            },
        }

    def run(
        self,
        seed: int | None = None,
        collisions: bool = True,
        progress: Callable[[int, int], None] | None = None,
    ) -> SimulationResult:
        """Simulate the scenario with a run seed (default: the scenario's)."""
        return simulate(**self.build(seed, collisions), progress=progress)

    def with_exact_model(self) -> Scenario:
        """The oracle: the same scenario with the nominal model equal to the true one.

        The spec is transformed, no behaviour is added: ``nominal_robot`` becomes
        ``robot``, ``model_error`` is dropped and a ``true_friction`` other than
        the robot's own is copied to ``nominal_friction``. So :meth:`robots`
        gives a nominal model with the true inertial parameters and the true
        friction, and :meth:`nominal` gives, on a flexible plant, the models of
        every observer kind without model error (the link friction of the
        plant for ``kind="joint"``, the apparent motor inertia for
        ``kind="motor"``). A ``payload`` stays on the true robot only: it is
        what the arm carries, not model error. What no rigid-body model holds
        stays unmodelled:
        joint elasticity seen by the motor-torque observer, the presliding
        state of LuGre friction (observers use its steady state), a drifting
        friction.

        The true robot, plant, trajectory, sensors, contacts and seeds are
        unchanged; the controller, though, is built on the nominal model, so a
        computed-torque or compensating controller makes slightly different
        runs. To judge the *same* runs with the exact model, observe the logs
        of this scenario with ``with_exact_model().nominal(kind)`` (what
        :mod:`sensorless.benchmark` does).

        Returns
        -------
        Scenario
            Same name, transformed spec.
        """
        spec = copy.deepcopy(self.spec)
        spec["nominal_robot"] = spec["robot"]
        spec.pop("model_error", None)
        spec.pop("nominal_friction", None)
        true_friction = spec.get("true_friction", "robot")
        if true_friction != "robot":
            spec["nominal_friction"] = copy.deepcopy(true_friction)
        return Scenario(self.name, spec)


def load_scenario(name_or_path: str | Path) -> Scenario:
    """Load a shipped scenario by name, or a scenario YAML file by path.

    The file is checked against the declared format
    (:class:`~sensorless.simulation.schema.ScenarioFile`) before anything is built.

    Raises
    ------
    UnknownNameError
        A name that is not a shipped scenario.
    FileFormatError
        The file is not YAML text or does not follow the scenario format; the
        message names the file and lists every problem with its field path.
    """
    path = Path(name_or_path)
    if not path.suffix:
        path = _scenario_dir() / f"{name_or_path}.yaml"
        if not path.is_file():
            raise UnknownNameError(
                f"unknown scenario {name_or_path!r}; shipped scenarios: {available_scenarios()} "
                "(or give the path of a YAML file)"
            )
    if not path.is_file():
        raise MissingFileError(f"scenario file not found: {path}")
    spec = read_yaml_mapping(path, "scenario")
    validate_scenario(spec, f"scenario file {path}")
    return Scenario(str(spec.get("name", path.stem)), spec)


def generate(
    scenario: Scenario,
    n_runs: int,
    master_seed: int,
    out_dir: str | Path,
    *,
    file_format: str = "parquet",
    progress: Callable[[str], None] | None = None,
) -> list[Path]:
    """Write ``n_runs`` collision-free and ``n_runs`` collision logs of one scenario.

    Seeds come from ``SeedSequence(master_seed).spawn(2 n_runs)``: the first
    half for the collision-free (tuning) runs, the second for the collision
    (test) runs, so the two sets never share a seed.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    children = np.random.SeedSequence(master_seed).spawn(2 * n_runs)
    seeds = [int(child.generate_state(1)[0]) for child in children]
    paths = []
    for index, seed in enumerate(seeds):
        collisions = index >= n_runs
        kind = "collision" if collisions else "free"
        path = out / f"{scenario.name}-{kind}-{index % n_runs:03d}.{file_format}"
        result = scenario.run(seed=seed, collisions=collisions)
        paths.append(write_log(result.log, path))
        if progress is not None:
            progress(str(path))
    return paths


# ---------------------------------------------------------------- spec readers
def _friction(spec: Any, robot: RobotModel) -> FrictionModel | LuGre | None:
    if spec == "robot":
        return robot.friction
    if spec in (None, "none"):
        return None
    kind = spec.get("type")
    if kind == "lugre":
        base = robot.friction
        if not isinstance(base, CoulombViscous):
            raise ModelError(
                "lugre friction from the robot needs Coulomb + viscous friction; "
                f"{robot.name} has {base}"
            )
        options = {k: v for k, v in spec.items() if k != "type"}
        return lugre_from(base, **options)
    if kind == "coulomb":
        return Coulomb(spec["c_pos"], spec["c_neg"])
    raise ModelError(f"unknown friction type {kind!r}; options: robot, none, lugre, coulomb")


def _drift(spec: Mapping[str, Any], base: Friction) -> DriftingFriction:
    """The plant's ``friction_drift`` mapping: warm-up and offset drift of the true friction."""
    if not isinstance(base, FrictionModel):
        raise ModelError(
            "friction_drift needs a stateless true friction (Coulomb, viscous, Stribeck, "
            f"sigmoid); got {base!r}"
        )
    options = dict(spec)
    if "offset_periods" in options:
        options["offset_periods"] = tuple(options["offset_periods"])
    known = {"warmup", "warmup_viscous", "time_constant", "offset_rate", "offset_periods", "seed"}
    unknown = set(options) - known
    if unknown:
        raise ModelError(f"friction_drift: unknown keys {sorted(unknown)}; valid: {sorted(known)}")
    return DriftingFriction(base, **options)


def _plant(spec: Mapping[str, Any], robot: RobotModel) -> RigidPlant | FlexiblePlant:
    kind = spec.get("type", "rigid")
    if kind == "rigid":
        if spec.get("friction_drift") is not None:
            return RigidPlant(robot, friction=_drift(spec["friction_drift"], robot.friction))
        return RigidPlant(robot)
    if spec.get("friction_drift") is not None:
        raise ModelError("friction_drift is supported on rigid plants only")
    if kind == "flexible":
        feedback = spec.get("feedback")
        return FlexiblePlant(
            robot,
            stiffness=spec["stiffness"],
            damping=spec.get("damping", 0.0),
            motor_inertia=spec.get("motor_inertia"),
            motor_friction=_friction(spec.get("motor_friction", "none"), robot),
            link_friction=_friction(spec.get("link_friction", "robot"), robot),
            feedback=None
            if feedback is None
            else TorqueFeedback(feedback["motor_inertia"], feedback["damping"]),
        )
    raise ModelError(f"unknown plant type {kind!r}; options: rigid, flexible")


def _trajectory(
    spec: Mapping[str, Any], robot: RobotModel, duration: float, rng: np.random.Generator
) -> Trajectory:
    kind = spec.get("type")
    if kind == "via_points":
        points = np.asarray(spec["points"], dtype=float)
        sign = np.asarray(spec.get("joint_sign", np.ones(robot.n_dof)), dtype=float)
        table = pd.DataFrame(
            points[:, 1:] * sign, columns=[f"q{j + 1}" for j in range(robot.n_dof)]
        )
        table.insert(0, "time", points[:, 0])
        repeat = max(1, int(np.ceil(duration / points[-1, 0])))
        return QuinticViaPoints.from_table(
            table, degrees=bool(spec.get("degrees", True)), repeat=repeat
        )
    if kind == "random_point_to_point":
        lower, upper = robot.position_limits
        margin = float(spec.get("limit_margin", 0.2))
        span = upper - lower
        return RandomPointToPoint(
            robot.n_dof,
            duration,
            lower + margin * span,
            upper - margin * span,
            float(spec["max_velocity"]),
            seed=int(rng.integers(2**31)),
            segment_time=tuple(spec.get("segment_time", (1.0, 3.0))),
            rest=tuple(spec.get("rest", (0.0, 0.5))),
        )
    if kind == "velocity_sweep":
        # Friction experiment of §2.4.1; home [rad] defaults to q = 0, travel checked
        # against the robot's joint limits.
        sweep = {"home": [0.0] * robot.n_dof, **spec}
        return VelocitySweep.from_dict(sweep, position_limits=robot.position_limits)
    if kind == "fourier":
        # The series `sensorless excite` optimised over one period, repeated to the duration.
        return FourierSeries.from_dict({**spec, "duration": duration})
    raise ModelError(
        f"unknown trajectory type {kind!r}; options: via_points, random_point_to_point, "
        "velocity_sweep, fourier"
    )


def _controller(spec: Mapping[str, Any], nominal: RobotModel, trajectory: Trajectory) -> JointPID:
    options = {k: v for k, v in spec.items() if k not in ("type", "bandwidth", "damping_ratio")}
    kind = spec.get("type", "pid")
    if kind == "computed_torque":
        omega = float(spec.get("bandwidth", 20.0))
        zeta = float(spec.get("damping_ratio", 1.0))
        options.setdefault("kp", omega**2)
        options.setdefault("kd", 2 * zeta * omega)
        options.setdefault("ki", 0.0)
        return ComputedTorque(model=nominal, **options)
    if kind != "pid":
        raise ModelError(f"unknown controller type {kind!r}; options: pid, computed_torque")
    if "bandwidth" in spec:
        # Gains from the nominal inertia at the start pose: kp = J ω², kd = 2 ζ J ω.
        q0 = trajectory.evaluate(0.0)[0]
        inertia = np.diag(nominal.mass_matrix(q0))
        omega = float(spec["bandwidth"])
        zeta = float(spec.get("damping_ratio", 1.0))
        options.setdefault("kp", inertia * omega**2)
        options.setdefault("kd", 2 * zeta * inertia * omega)
        options.setdefault("ki", 0.0)
    return JointPID(model=nominal, **options)


def _profile(spec: Mapping[str, Any]) -> Any:
    kind = spec["profile"]
    if kind == "half_sine":
        return HalfSine(spec["start"], spec["duration"], spec["peak"])
    if kind == "push":
        return Push(spec["start"], spec["ramp"], spec["hold"], spec["release"], spec["peak"])
    if kind == "recorded":
        return Recorded.from_csv(
            spec["file"], start=spec.get("start", 0.0), scale=spec.get("scale", 1.0)
        )
    if kind in INTERACTION_PROFILES:
        return interaction_profile(spec)
    raise ModelError(
        f"unknown force profile {kind!r}; options: half_sine, push, recorded, guiding, clamp, "
        "impact"
    )


def _contacts(
    spec: Mapping[str, Any],
    robot: RobotModel,
    duration: float,
    rng: np.random.Generator,
    trajectory: Trajectory,
) -> ContactSet:
    if "random_interactions" in spec:
        return random_interactions(spec["random_interactions"], robot, trajectory, duration, rng)
    if "random_collisions" in spec:
        options = dict(spec["random_collisions"])
        count = int(options.pop("count"))
        for key in ("peak_range", "duration_range"):
            if key in options:
                options[key] = tuple(options[key])
        return ContactSet.random(robot, count, duration, rng, **options)
    contacts = [
        Contact(c["id"], c["link"], c.get("point", (0.0, 0.0, 0.0)), c["direction"], _profile(c))
        for c in spec.get("collisions", [])
    ]
    return ContactSet(contacts)
