"""Training the learned family's network on simulated, labelled runs of a scenario (numpy only).

:func:`training_runs` simulates ``minutes`` of a scenario in runs of
``run_seconds``, each with its own randomised model error (inertial and
friction bands and seed of ``model_error``), sensor noise and motion speed,
from one master seed (``numpy.random.SeedSequence``); the observer gives r̂
and the threshold inputs, :func:`sensorless.evaluation.collision_windows`
the contacts. :func:`train` fits the network of
:mod:`sensorless.thresholds._cnn` by Adam on the Gaussian negative
log-likelihood of r̂ given the inputs, on every free-motion sample: the
samples of a contact and ``after_contact`` seconds after it, and the
observer's first ``settle`` seconds, get weight 0. The gradient is the
hand-written backward pass of :mod:`._backward` (checked against finite
differences in the tests), so training needs no framework and the same seed
gives the same weights.

Not randomised: the sample period (the dilations count samples: the weights
hold the period they were trained at) and the payload.
"""

from __future__ import annotations

import copy
import math
import time
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from .._validation import FloatArray, check_int, check_scalar
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
    """One simulated run: inputs (n_samples, 4, n_dof), residual and loss weight (n_samples,)."""

    x: FloatArray
    residual: FloatArray
    weight: FloatArray
    signals: ObserverSignals


def _randomised(scenario: Scenario, recipe: TrainingRecipe, rng: np.random.Generator) -> Scenario:
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
    return Scenario(scenario.name, spec).with_duration(recipe.run_seconds)


def training_runs(recipe: TrainingRecipe) -> list[TrainingRun]:
    """Simulate and observe the runs of ``recipe`` (see the module docstring)."""
    scenario = load_scenario(recipe.scenario)
    n_runs = max(1, math.ceil(recipe.minutes * 60.0 / recipe.run_seconds))
    runs = []
    for child in np.random.SeedSequence(recipe.seed).spawn(n_runs):
        rng = np.random.default_rng(child)
        randomised = _randomised(scenario, recipe, rng)
        log = randomised.run(seed=int(rng.integers(2**31))).log
        signals = observe(log, randomised.nominal("motor"), kind="motor", gain=recipe.gain)
        t = signals.t - signals.t[0]
        weight = (t >= recipe.settle).astype(float)
        for window in collision_windows(log):
            during = (signals.t >= window.start) & (signals.t <= window.end + recipe.after_contact)
            weight[during] = 0.0
        inputs = ThresholdInputs.from_signals(signals)
        x = np.stack([getattr(inputs, name) for name in _cnn.CHANNELS], axis=1)
        runs.append(TrainingRun(x, signals.residual, weight, signals))
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
    }
    return LearnedWeights(
        network,
        robot=nominal.name.split(" (")[0],
        kind="motor",
        gain=float(recipe.gain),
        dt=float(np.round(runs[0].signals.dt, 12)),
        fingerprint=nominal.fingerprint,
        recipe=info,
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
