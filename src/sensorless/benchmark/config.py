"""What a benchmark runs: scenarios, methods, run counts, tuning rule, and the seed plan.

:class:`BenchmarkConfig` is declarative and picklable; :func:`plan_runs`
turns it into the list of :class:`RunSpec` (one simulated run each) with
seeds from one master seed: ``SeedSequence(master_seed).spawn(n_scenarios)``,
then per scenario ``spawn(3)`` for the tuning, collision and collision-free
test runs, then ``spawn(n)`` per role. A child of ``spawn`` depends only on
its position, so run k of a role keeps its seed when more runs are asked
for, and no seed depends on the order in which runs are scheduled. Units SI;
forces [N], times [s], rates per hour.
"""

from __future__ import annotations

import inspect
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .._validation import check_duration, check_int, check_scalar
from ..exceptions import InputTypeError, InputValueError, UnknownNameError
from ..monitor import METHOD_NAMES
from ..simulation.interactions import RANGES, draw_interactions
from ..simulation.scenario import Scenario, load_scenario

__all__ = [
    "DEFAULT_FORCE_BINS",
    "DEFAULT_METHODS",
    "ROLES",
    "BenchmarkConfig",
    "BenchmarkScenario",
    "Detection",
    "RunSpec",
    "full_config",
    "plan_runs",
    "quick_config",
]

ROLES = ("tuning", "collision", "free")
"""Run roles: collision-free tuning runs, collision test runs, collision-free test runs."""
DEFAULT_METHODS = ("constant", "time-variant", "hysteretic", "velocity")
"""Threshold families of the default benchmark (the model-based one is opt-in: slow fit)."""
DEFAULT_FORCE_BINS = (0.0, 10.0, 20.0, 30.0, 40.0, 60.0, math.inf)
"""Edges [N] of the peak-force bins of the detection rate."""
ORACLE = "oracle"
"""Label of the oracle: the ``oracle_method`` family on the residual of the exact model."""


@dataclass(frozen=True)
class BenchmarkScenario:
    """One scenario of a benchmark and how it is watched.

    Parameters
    ----------
    scenario : str, Path or Scenario
        A shipped scenario name, a scenario YAML file, or a :class:`Scenario`.
    duration : float, optional
        Simulated time of every run [s]; default the scenario's.
    joints : sequence of int, optional
        Monitored joints (1-based); default all.
    residuals : sequence of {"motor", "joint"}
        Residuals the momentum methods watch (``"joint"``: r̂_s of eq. 4.9,
        robots with joint torque sensors); one oracle per residual.
    interactions : int, optional
        Each collision run carries this many of the simulator's random
        interactions instead of the scenario's own contacts: guiding hands
        (intended), clamps and impacts (collisions), drawn and labelled by
        :func:`~sensorless.simulation.interactions.simulate_interactions` from
        the run's seed, so that the classification's confusion table has both
        classes. None (default): the scenario's own contacts, as without the option.
    """

    scenario: str | Path | Scenario
    duration: float | None = None
    joints: tuple[int, ...] | None = None
    residuals: tuple[str, ...] = ("motor",)
    interactions: int | None = None

    def load(self) -> Scenario:
        """The :class:`Scenario`, cut to :attr:`duration`.

        Raises
        ------
        InputValueError
            :attr:`interactions` contacts of the longest kind would not fit in a run.
        """
        scenario = (
            self.scenario if isinstance(self.scenario, Scenario) else load_scenario(self.scenario)
        )
        if self.duration is not None:
            scenario = scenario.with_duration(check_scalar(self.duration, "duration", "s"))
        if self.interactions is not None:
            _check_room(self.interactions, scenario)
        return scenario


@dataclass(frozen=True)
class Detection:
    """One detector the benchmark scores: a threshold family on one residual.

    Attributes
    ----------
    label : str
        Row name in the tables (``"velocity"``, ``"velocity (joint)"``, ``"oracle"``).
    method : str
        Threshold family (:data:`sensorless.monitor.METHOD_NAMES`).
    kind : {"motor", "joint", "acceleration"}
        Observer kind.
    oracle : bool
        Watches the residual of the exact model (:meth:`Scenario.with_exact_model`).
    """

    label: str
    method: str
    kind: str
    oracle: bool = False


@dataclass(frozen=True)
class RunSpec:
    """One simulated run: scenario position and name, role, index in the role, seed."""

    scenario_index: int
    scenario: str
    role: str
    index: int
    seed: int

    @property
    def key(self) -> str:
        """A readable, unique task name: ``"panda-gaz/collision/003"``."""
        return f"{self.scenario}/{self.role}/{self.index:03d}"


@dataclass(frozen=True)
class BenchmarkConfig:
    """Everything a benchmark runs (hyper-parameters only; :func:`run_benchmark` runs it).

    Parameters
    ----------
    scenarios : sequence of BenchmarkScenario
        Scenarios, each with its duration, joints and residuals.
    methods : sequence of str
        Threshold families (:data:`sensorless.monitor.METHOD_NAMES`).
    n_tuning, n_collision, n_free : int
        Collision-free tuning runs (shared by every method), collision test
        runs, collision-free test runs (the false alarms per hour), per scenario.
    master_seed : int
        The one seed every run seed derives from (:func:`plan_runs`).
    margin_fraction : float
        Without ``false_alarm_rate``: every method's margin is this fraction
        of the constant β of the residual it watches (the rule of
        :func:`sensorless.comparison.compare`); the oracle's of its own β.
    false_alarm_rate : float, optional
        Stated false alarms per hour per robot [1/h]: every method and the
        oracle are tuned with ``tune(..., false_alarm_rate=...)`` instead.
    oracle_method : str or None
        Family of the oracle on the exact model's residual; None: no oracle.
    force_bins : sequence of float
        Increasing edges [N] of the peak-force bins (``inf`` allowed last).
    strong_force : float
        Contacts with a peak force at least this [N] make the "strong" rate.
    min_duration, hold : float
        Detector settings [s] of the monitor.
    isolation : bool
        Isolate (link, point, force) and classify (intended or collision)
        every event of the collision runs (:mod:`.contacts`): the contact
        columns of the events table, :meth:`BenchmarkResult.contacts` and
        :meth:`BenchmarkResult.confusion`. False: detection only, those
        columns empty.
    max_delay : float
        Time [s] after a contact during which an event still detects it
        (:func:`sensorless.evaluation.evaluate`).
    confidence : float
        Level of the Wilson and Poisson intervals.
    """

    scenarios: tuple[BenchmarkScenario, ...]
    methods: tuple[str, ...] = DEFAULT_METHODS
    n_tuning: int = 3
    n_collision: int = 5
    n_free: int = 3
    master_seed: int = 0
    margin_fraction: float = 0.1
    false_alarm_rate: float | None = None
    oracle_method: str | None = "constant"
    force_bins: tuple[float, ...] = DEFAULT_FORCE_BINS
    strong_force: float = 20.0
    min_duration: float = 0.005
    hold: float = 0.05
    isolation: bool = True
    max_delay: float = 0.5
    confidence: float = 0.95

    def __post_init__(self) -> None:
        if not self.scenarios or not all(isinstance(s, BenchmarkScenario) for s in self.scenarios):
            raise InputTypeError(
                "scenarios must be a non-empty sequence of BenchmarkScenario; got "
                f"{self.scenarios!r}"
            )
        unknown = [m for m in self.methods if m not in METHOD_NAMES]
        if not self.methods or unknown:
            raise UnknownNameError(
                f"unknown methods {unknown or '(none given)'}; options: {sorted(METHOD_NAMES)}"
            )
        if self.oracle_method is not None and self.oracle_method not in METHOD_NAMES:
            raise UnknownNameError(
                f"unknown oracle method {self.oracle_method!r}; options: {sorted(METHOD_NAMES)}"
            )
        check_int(self.n_tuning, "n_tuning", 1, "BenchmarkConfig")
        check_int(self.n_collision, "n_collision", 0, "BenchmarkConfig")
        check_int(self.n_free, "n_free", 0, "BenchmarkConfig")
        check_int(self.master_seed, "master_seed", 0, "BenchmarkConfig")
        check_scalar(self.margin_fraction, "margin_fraction", "-", "nonnegative")
        if self.false_alarm_rate is not None:
            check_scalar(self.false_alarm_rate, "false_alarm_rate", "1/h")
        edges = np.asarray(self.force_bins, dtype=float)
        if edges.size < 2 or np.isnan(edges).any() or not (np.diff(edges) > 0).all():
            raise InputValueError(
                f"force_bins must be at least two increasing edges [N]; got {self.force_bins!r}"
            )
        check_scalar(self.strong_force, "strong_force", "N", "nonnegative")
        check_duration(self.min_duration, "min_duration")
        check_duration(self.hold, "hold")
        check_duration(self.max_delay, "max_delay")
        if not 0.0 < float(self.confidence) < 1.0:
            raise InputValueError(f"confidence must be in (0, 1); got {self.confidence!r}")
        if not isinstance(self.isolation, bool):
            raise InputTypeError(f"isolation must be True or False; got {self.isolation!r}")
        for choice in self.scenarios:
            if not choice.residuals or set(choice.residuals) - {"motor", "joint"}:
                raise InputValueError(
                    "residuals must be a non-empty subset of ('motor', 'joint'); got "
                    f"{choice.residuals!r}"
                )
            if choice.interactions is not None:
                check_int(choice.interactions, "interactions", 1, "BenchmarkScenario")

    def detections(self, choice: BenchmarkScenario) -> list[Detection]:
        """The detectors scored on one scenario: every method on every residual, then oracles.

        Momentum methods watch each of ``choice.residuals`` (labelled
        ``"<method> (joint)"`` on r̂_s); the model-based one its own observer.
        """
        plan = []
        for method in self.methods:
            watched = METHOD_NAMES[method]
            for kind in choice.residuals if watched == "motor" else (watched,):
                label = f"{method} (joint)" if kind == "joint" else method
                plan.append(Detection(label, method, kind))
        if self.oracle_method is not None:
            watched = METHOD_NAMES[self.oracle_method]
            for kind in choice.residuals if watched == "motor" else (watched,):
                label = f"{ORACLE} (joint)" if kind == "joint" else ORACLE
                plan.append(Detection(label, self.oracle_method, kind, oracle=True))
        return plan


def _longest_interaction() -> float:
    """Longest window [s] :func:`draw_interactions` can draw, from its ranges (:data:`RANGES`)."""
    guiding, clamp, impact = RANGES["guiding"], RANGES["clamp"], RANGES["impact"]
    build = clamp["peak"][1] / (clamp["stiffness"][0] * clamp["speed"][0])
    return max(
        sum(guiding[key][1] for key in ("ramp", "hold", "release")),
        build + clamp["hold"][1] + clamp["release"][1],
        impact["duration"][1],
    )


def _check_room(count: int, scenario: Scenario) -> None:
    """``count`` interactions of the longest kind fit in a run, with the draw's gaps and margins."""
    defaults = inspect.signature(draw_interactions).parameters
    gap, margin = defaults["min_gap"].default, defaults["margin"].default
    needed = count * _longest_interaction() + (count - 1) * gap + 2 * margin
    if needed > scenario.duration:
        raise InputValueError(
            f"interactions: {count} random interactions may need {needed:g} s (longest "
            f"{_longest_interaction():g} s each, {gap:g} s apart, {margin:g} s margins) but "
            f"{scenario.name!r} runs {scenario.duration:g} s; lower interactions or raise duration"
        )


def _seeds(sequence: np.random.SeedSequence, count: int) -> list[int]:
    return [int(child.generate_state(1)[0]) for child in sequence.spawn(count)]


def plan_runs(config: BenchmarkConfig) -> list[RunSpec]:
    """Every run of a benchmark with its seed, in (scenario, role, index) order.

    Examples
    --------
    >>> config = BenchmarkConfig((BenchmarkScenario("panda-gaz"),), n_tuning=2, n_collision=1,
    ...                          n_free=1, master_seed=7)
    >>> [(spec.role, spec.index) for spec in plan_runs(config)]
    [('tuning', 0), ('tuning', 1), ('collision', 0), ('free', 0)]
    >>> more = BenchmarkConfig((BenchmarkScenario("panda-gaz"),), n_tuning=3, n_collision=1,
    ...                        n_free=1, master_seed=7)
    >>> plan_runs(config)[1].seed == plan_runs(more)[1].seed  # run 1 keeps its seed
    True
    """
    runs = []
    root = np.random.SeedSequence(config.master_seed)
    counts = (config.n_tuning, config.n_collision, config.n_free)
    for position, (choice, branch) in enumerate(
        zip(config.scenarios, root.spawn(len(config.scenarios)), strict=True)
    ):
        name = _scenario_name(choice)
        for role, count, sequence in zip(ROLES, counts, branch.spawn(len(ROLES)), strict=True):
            for index, seed in enumerate(_seeds(sequence, count)):
                runs.append(RunSpec(position, name, role, index, seed))
    return runs


def _scenario_name(choice: BenchmarkScenario) -> str:
    scenario = choice.scenario
    return scenario.name if isinstance(scenario, Scenario) else load_scenario(scenario).name


def quick_config(master_seed: int = 0, **overrides: Any) -> BenchmarkConfig:
    """The ``--quick`` benchmark, sized for at most 5 min on 2 cores.

    panda-gaz (10 s runs, one random contact each) and puma560-thesis (20 s
    runs, the first four contacts of the thesis's list, joints 1-3), the four
    fast families, 3 tuning, 10 collision and 5 collision-free test runs each.
    """
    settings: dict[str, Any] = {
        "scenarios": (
            BenchmarkScenario("panda-gaz", duration=10.0),
            BenchmarkScenario("puma560-thesis", duration=20.0, joints=(1, 2, 3)),
        ),
        "n_tuning": 3,
        "n_collision": 10,
        "n_free": 5,
        "master_seed": master_seed,
    }
    settings.update(overrides)
    return BenchmarkConfig(**settings)


def full_config(master_seed: int = 0, **overrides: Any) -> BenchmarkConfig:
    """The full benchmark: the demo's three scenarios at their length, 5/20/10 runs each.

    panda-gaz (60 s), puma560-thesis (60 s, joints 1-3), lwr4-thesis (100 s,
    joints 1-3, r̂ and r̂_s); 5 tuning, 20 collision and 10 collision-free
    test runs per scenario.
    """
    settings: dict[str, Any] = {
        "scenarios": (
            BenchmarkScenario("panda-gaz"),
            BenchmarkScenario("puma560-thesis", joints=(1, 2, 3)),
            BenchmarkScenario(
                "lwr4-thesis", duration=100.0, joints=(1, 2, 3), residuals=("motor", "joint")
            ),
        ),
        "n_tuning": 5,
        "n_collision": 20,
        "n_free": 10,
        "master_seed": master_seed,
    }
    settings.update(overrides)
    return BenchmarkConfig(**settings)


def check_config(config: Any) -> BenchmarkConfig:
    """``config`` if it is a :class:`BenchmarkConfig`."""
    if not isinstance(config, BenchmarkConfig):
        raise InputTypeError(f"config must be a BenchmarkConfig; got {type(config).__name__}")
    return config


def labels_of(config: BenchmarkConfig, choices: Sequence[BenchmarkScenario]) -> list[str]:
    """Every detector label, in first-seen order over the scenarios."""
    seen: dict[str, None] = {}
    for choice in choices:
        for detection in config.detections(choice):
            seen.setdefault(detection.label, None)
    return list(seen)
