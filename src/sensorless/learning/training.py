"""Training the learned family's network on simulated, labelled runs of a scenario (numpy only).

:func:`training_runs` simulates ``minutes`` of a scenario in runs of
``run_seconds``, each with its own randomised model error (inertial and
friction bands and seed of ``model_error``), sensor noise, motion speed,
payload and sample rate, from one master seed (``numpy.random.SeedSequence``,
one child per run; :func:`run_draws` recomputes what each run drew without
simulating); the observer gives r̂ and the threshold inputs,
:func:`sensorless.evaluation.collision_windows` the contacts. :func:`train`
fits the network of :mod:`sensorless.thresholds._cnn` by Adam on the
Gaussian negative log-likelihood of r̂ given the inputs, on every
free-motion sample: the samples of a contact and ``after_contact`` seconds
after it, and the observer's first ``settle`` seconds, get weight 0. The
gradient is the hand-written backward pass of :mod:`._backward` (checked
against finite differences in the tests), so training needs no framework and
the same seed gives the same weights.

Payload: a share ``payload_share`` of the runs carries a point mass of
U(``payload_mass``) [kg] at a centre of mass drawn in the box
``payload_com_low`` .. ``payload_com_high`` of the end-link frame [m], on the
*true* robot only (the scenario key ``payload``): the nominal model lacks it,
as a user's lacks what the arm picks up. The other runs carry none, so the
network still sees the nominal case. None of the network's inputs measures
the payload, so it learns a band wide enough for the whole range, not one
per payload: on an arm that carries none, that costs sensitivity. Measured
with ``benchmarks/learned_evidence.py`` on held-out Panda runs, half the runs
with up to 3 kg took the nominal arm from 24/24 contacts and no false alarm to
20/24 and 72/h, and a 2 kg arm from 15/24 to 20/24 (the time-variant
threshold: 21/24), so ``payload_share`` is 0 by default and in the shipped
weights; a user whose arm carries loads fits the level on runs with them.

Sample rate: each run is controlled, sampled and observed at the scenario's
rate times U(``rate_factor``) (:meth:`Scenario.with_sample_rate`). The
dilations count samples, so the network is trained for a band of periods,
dt/``rate_factor[1]`` .. dt/``rate_factor[0]``, which the weights file
records and :class:`~sensorless.thresholds.LearnedThreshold` enforces.
The network's inputs are the same four signals per joint; it is not told the
period.

The weights file records the recipe (ranges included) and, per run, the
scenario seed, sample rate [Hz] and payload drawn (``training.drawn``).
"""

from __future__ import annotations

import copy
import math
import time
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from .._validation import FloatArray, check_int, check_range, check_scalar
from .._version import __version__
from ..evaluation import collision_windows
from ..exceptions import InputValueError, UnknownNameError
from ..observers import observe
from ..signals import ObserverSignals
from ..simulation.scenario import Scenario, load_scenario
from ..thresholds import _cnn
from ..thresholds._learned_files import LearnedWeights
from ..thresholds.state import ThresholdInputs
from ._backward import gradients

__all__ = [
    "SCENARIOS",
    "TrainingRecipe",
    "TrainingRun",
    "random_network",
    "run_draws",
    "scenario_for",
    "train",
    "train_detector",
    "training_runs",
]


@dataclass(frozen=True)
class TrainingRecipe:
    """Everything that decides the weights (written into the weights file).

    Parameters
    ----------
    scenario : str
        Shipped scenario name or scenario file.
    minutes : float
        Simulated time [min].
    seed : int
        Master seed of the runs, the initial weights and the crops.
    run_seconds : float
        Length of one run [s].
    inertial_error, friction_error : float
        Largest relative band of the random model error [-] (each run draws
        U(0, this) and its own ``model_error.seed``).
    noise_factor : (float, float)
        Range of the factor on the scenario's motor torque noise [-].
    velocity_factor : (float, float)
        Range of the factor on ``max_velocity`` of a random point-to-point trajectory [-].
    payload_share : float
        Share of the runs that carry a payload on the true robot [-], in [0, 1];
        0 (the default, and the shipped weights): none, see the module docstring.
    payload_mass : (float, float)
        Range of the payload mass [kg], >= 0 (a drawn 0 is no payload).
    payload_com_low, payload_com_high : (float, float, float)
        Corners of the box of the payload's centre of mass in the end-link frame [m]
        (z: out along the flange).
    rate_factor : (float, float)
        Range of the factor on the scenario's sample rate [-], > 0; (1, 1): the
        scenario's period only (the weights then hold that period exactly).
    gain : float
        Observer gain K_I [1/s].
    channels, steps, batch, crop : int
        Hidden channels, Adam steps, crops per step, samples per crop.
    learning_rate : float
        Adam step size (cosine decay to 10 % of it).
    settle, after_contact : float
        Times left out of the loss [s]: the start of a run, and after a contact.
    """

    scenario: str = "panda-gaz"
    minutes: float = 3.0
    seed: int = 0
    run_seconds: float = 10.0
    inertial_error: float = 0.2
    friction_error: float = 0.3
    noise_factor: tuple[float, float] = (0.5, 2.0)
    velocity_factor: tuple[float, float] = (0.6, 1.3)
    payload_share: float = 0.0
    payload_mass: tuple[float, float] = (0.0, 3.0)
    payload_com_low: tuple[float, float, float] = (-0.03, -0.03, 0.0)
    payload_com_high: tuple[float, float, float] = (0.03, 0.03, 0.15)
    rate_factor: tuple[float, float] = (0.8, 1.25)
    gain: float = 20.0
    channels: int = 16
    steps: int = 1500
    batch: int = 24
    crop: int = 200
    learning_rate: float = 3e-3
    settle: float = 0.3
    after_contact: float = 0.3


@dataclass(frozen=True, eq=False)
class TrainingRun:
    """One simulated run: inputs (n_samples, 4, n_dof), residual and loss weight (n_samples,).

    ``drawn``: its scenario seed, sample rate [Hz] and payload (:func:`run_draws`).
    """

    x: FloatArray
    residual: FloatArray
    weight: FloatArray
    signals: ObserverSignals
    drawn: dict[str, Any] = field(default_factory=dict)


def _randomised(
    scenario: Scenario, recipe: TrainingRecipe, rng: np.random.Generator
) -> tuple[Scenario, dict[str, Any]]:
    """The scenario of one run and what it drew (scenario seed, sample rate [Hz], payload).

    The order of the draws is part of the recipe: model error, noise, speed
    and scenario seed first (the draws of the weights trained before payload
    and rate were randomised, so their seeds recompute the same), then the
    payload (whether, mass, centre of mass: all drawn, used or not) and the
    rate factor.
    """
    spec = copy.deepcopy(scenario.spec)
    spec["model_error"] = {
        "inertial": float(rng.uniform(0.0, recipe.inertial_error)),
        "friction": float(rng.uniform(0.0, recipe.friction_error)),
        "seed": int(rng.integers(2**31)),
    }
    sensors = spec.setdefault("sensors", {})
    noise = np.asarray(sensors.get("motor_torque_noise", 0.0), dtype=float)
    sensors["motor_torque_noise"] = (noise * rng.uniform(*recipe.noise_factor)).tolist()
    trajectory = spec["trajectory"]
    if trajectory.get("type") == "random_point_to_point":
        trajectory["max_velocity"] = float(
            trajectory["max_velocity"] * rng.uniform(*recipe.velocity_factor)
        )
    seed = int(rng.integers(2**31))
    carries = bool(rng.random() < recipe.payload_share)
    mass = float(rng.uniform(*recipe.payload_mass))
    com = rng.uniform(recipe.payload_com_low, recipe.payload_com_high)
    rate = float(rng.uniform(*recipe.rate_factor)) / scenario.dt
    payload = {"mass": mass, "com": com.tolist()} if carries and mass > 0.0 else None
    if payload is not None:
        spec["payload"] = payload
    drawn = {"seed": seed, "sample_rate": rate, "payload": payload}
    run = Scenario(scenario.name, spec).with_duration(recipe.run_seconds)
    return run.with_sample_rate(rate), drawn


def _check_recipe(recipe: TrainingRecipe) -> None:
    """The payload and rate ranges of ``recipe`` (the other fields are checked where used)."""
    share = check_scalar(recipe.payload_share, "payload_share", "-", "nonnegative")
    if share > 1.0:
        raise InputValueError(f"payload_share must be in [0, 1] [-]; got {share}")
    check_range(recipe.payload_mass, "payload_mass", "kg", "nonnegative")
    check_range(recipe.rate_factor, "rate_factor", "-", "positive")
    corners = (recipe.payload_com_low, recipe.payload_com_high)
    if any(len(tuple(c)) != 3 for c in corners):
        raise InputValueError(
            "payload_com_low and payload_com_high must be 3 coordinates [m]; got "
            f"{corners[0]!r} and {corners[1]!r}"
        )
    for low, high in zip(*corners, strict=True):
        check_range((low, high), "payload_com_low .. payload_com_high", "m", "any")


def run_draws(recipe: TrainingRecipe) -> list[dict[str, Any]]:
    """What every run of ``recipe`` draws (as :func:`training_runs`), nothing simulated.

    Returns
    -------
    list of dict
        Per run: ``seed`` (the scenario run seed), ``sample_rate`` [Hz] and
        ``payload`` (``{"mass": kg, "com": [x, y, z] m}`` or None).
    """
    _check_recipe(recipe)
    scenario = load_scenario(recipe.scenario)
    return [_randomised(scenario, recipe, rng)[1] for rng in _run_rngs(recipe)]


def _run_rngs(recipe: TrainingRecipe) -> list[np.random.Generator]:
    n_runs = max(1, math.ceil(recipe.minutes * 60.0 / recipe.run_seconds))
    return [np.random.default_rng(c) for c in np.random.SeedSequence(recipe.seed).spawn(n_runs)]


def training_runs(recipe: TrainingRecipe) -> list[TrainingRun]:
    """Simulate and observe the runs of ``recipe`` (see the module docstring)."""
    _check_recipe(recipe)
    scenario = load_scenario(recipe.scenario)
    runs = []
    for rng in _run_rngs(recipe):
        randomised, drawn = _randomised(scenario, recipe, rng)
        log = randomised.run(seed=drawn["seed"]).log
        signals = observe(log, randomised.nominal("motor"), kind="motor", gain=recipe.gain)
        t = signals.t - signals.t[0]
        weight = (t >= recipe.settle).astype(float)
        for window in collision_windows(log):
            during = (signals.t >= window.start) & (signals.t <= window.end + recipe.after_contact)
            weight[during] = 0.0
        inputs = ThresholdInputs.from_signals(signals)
        x = np.stack([getattr(inputs, name) for name in _cnn.CHANNELS], axis=1)
        runs.append(TrainingRun(x, signals.residual, weight, signals, drawn))
    return runs


def _normalisation(runs: list[TrainingRun]) -> dict[str, FloatArray]:
    kept = [run.weight > 0 for run in runs]
    x = np.concatenate([run.x[k] for run, k in zip(runs, kept, strict=True)])
    r = np.concatenate([run.residual[k] for run, k in zip(runs, kept, strict=True)])
    return {
        "input_mean": x.mean(axis=0),
        "input_scale": np.maximum(x.std(axis=0), 1e-3),
        "output_mean": r.mean(axis=0),
        "output_scale": np.maximum(r.std(axis=0), 1e-3),
    }


def _crops(
    runs: list[TrainingRun], recipe: TrainingRecipe, field: int, rng: np.random.Generator
) -> tuple[FloatArray, FloatArray, FloatArray]:
    xs, targets, weights = [], [], []
    for _ in range(recipe.batch):
        run = runs[int(rng.integers(len(runs)))]
        start = int(rng.integers(0, run.x.shape[0] - recipe.crop + 1))
        stop = start + recipe.crop
        xs.append(run.x[start:stop])
        targets.append(run.residual[start + field - 1 : stop])
        weight = run.weight[start + field - 1 : stop]
        weights.append(np.broadcast_to(weight[:, None], targets[-1].shape))
    return np.stack(xs), np.stack(targets), np.stack(weights)


def random_network(
    rng: np.random.Generator,
    normalisation: dict[str, Any],
    *,
    channels: int = 16,
    dilations: tuple[int, ...] = _cnn.DILATIONS,
    floor: float = 0.05,
) -> _cnn.Network:
    """A network with Glorot-uniform weights from ``rng`` and zero biases (training start)."""
    n_dof = int(np.shape(normalisation["output_scale"])[0])
    kernels, biases = [], []
    c_in = len(_cnn.CHANNELS)
    for k in range(len(dilations)):
        limit = np.sqrt(6.0 / (3 * c_in + channels))
        kernels.append(rng.uniform(-limit, limit, (channels, 3 * c_in)))
        biases.append(np.zeros((channels, n_dof if k == 0 else 1)))
        c_in = channels
    limit = np.sqrt(6.0 / (channels + 2))
    return _cnn.Network(
        tuple(kernels),
        tuple(biases),
        rng.uniform(-limit, limit, (2, channels)),
        np.zeros((2, 1)),
        tuple(int(d) for d in dilations),
        np.asarray(normalisation["input_mean"], dtype=float),
        np.asarray(normalisation["input_scale"], dtype=float),
        np.asarray(normalisation["output_mean"], dtype=float),
        np.asarray(normalisation["output_scale"], dtype=float),
        float(floor),
    )


def train(runs: list[TrainingRun], recipe: TrainingRecipe) -> tuple[_cnn.Network, list[float]]:
    """Fit the network on ``runs`` by Adam; the network and the loss of every step."""
    steps = check_int(recipe.steps, "steps", 1, "TrainingRecipe")
    rate = check_scalar(recipe.learning_rate, "learning_rate", "-")
    rng = np.random.default_rng([recipe.seed, 1])  # not the runs' SeedSequence(seed)
    net = random_network(rng, _normalisation(runs), channels=recipe.channels)
    field = net.receptive_field
    if min(run.x.shape[0] for run in runs) < max(recipe.crop, field):
        raise InputValueError(f"every run needs at least crop = {recipe.crop} samples")
    params = net.parameters()
    first = [np.zeros_like(p) for p in params]
    second = [np.zeros_like(p) for p in params]
    losses = []
    for k in range(1, steps + 1):
        x, target, weight = _crops(runs, recipe, field, rng)
        loss, grads = gradients(net.with_parameters(params), x, target, weight)
        losses.append(loss)
        step_size = rate * (0.1 + 0.9 * 0.5 * (1.0 + math.cos(math.pi * k / steps)))
        for p, g, m, v in zip(params, grads, first, second, strict=True):
            m *= 0.9
            m += 0.1 * g
            v *= 0.999
            v += 0.001 * g * g
            p -= step_size * (m / (1.0 - 0.9**k)) / (np.sqrt(v / (1.0 - 0.999**k)) + 1e-8)
    return net.with_parameters(params), losses


def train_detector(recipe: TrainingRecipe) -> LearnedWeights:
    """Simulate, train and return the weights with their recipe (``sensorless train-detector``)."""
    started = time.perf_counter()
    runs = training_runs(recipe)
    simulated = time.perf_counter() - started
    network, losses = train(runs, recipe)
    scenario = load_scenario(recipe.scenario)
    nominal = scenario.nominal("motor")
    tail = losses[-max(1, len(losses) // 10) :]
    info: dict[str, Any] = asdict(recipe)
    info |= {
        "method": "Adam on the Gaussian negative log-likelihood of r̂ (numpy, manual gradients)",
        "runs": len(runs),
        "final_loss": float(np.mean(tail)),
        "seconds_simulating": round(simulated, 1),
        "seconds_total": round(time.perf_counter() - started, 1),
        "library_version": __version__,
        "drawn": [run.drawn for run in runs],
    }
    low, high = recipe.rate_factor
    dt = scenario.dt if low < high else scenario.dt / low
    return LearnedWeights(
        network,
        robot=nominal.name.split(" (")[0],
        kind="motor",
        gain=float(recipe.gain),
        dt=float(np.round(dt, 12)),
        fingerprint=nominal.fingerprint,
        recipe=info,
        period_range=(
            (float(np.round(scenario.dt / high, 12)), float(np.round(scenario.dt / low, 12)))
            if low < high
            else None
        ),
    )


SCENARIOS = {"panda": "panda-gaz", "puma560": "puma560-thesis", "lwr4": "lwr4-thesis"}
"""The shipped scenario each robot's network is trained on by default."""


def scenario_for(robot: str) -> str:
    """The shipped training scenario of a built-in robot (:data:`SCENARIOS`)."""
    if robot not in SCENARIOS:
        raise UnknownNameError(
            f"no training scenario for robot {robot!r}; known: {sorted(SCENARIOS)} "
            "(or pass a scenario)"
        )
    return SCENARIOS[robot]
