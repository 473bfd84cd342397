"""The SLSQP runs of :func:`~sensorless.metric.optimize_trajectory`: stages, rounds, B_Q̃.

:func:`solve` runs SLSQP through the ε continuation of eq. 3.30; after each
run the limits are checked on a dense grid and the lag model
(:mod:`sensorless.metric._lag`) on every sample, and what exceeds joins the
constraints for another run (at most :data:`REFINEMENT_ROUNDS`).
:class:`Table31` is B_Q̃ by the method of thesis Table 3.1 over several
noise draws.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt
import scipy.optimize
from numpy.typing import ArrayLike

from .._validation import FloatArray
from ..filters import CausalEstimator
from ._checks import per_joint_nonnegative
from ._constraints import constraints
from ._plan import IntArray
from ._transcription import Problem
from .bounds import q_error_bounds

__all__ = ["REFINEMENT_ROUNDS", "Run", "Table31", "solve"]

#: SLSQP runs at most this often per stage, each time with what exceeded added.
REFINEMENT_ROUNDS = 4
#: Relative tightening of every limit inside the problem (against solver tolerance).
_BACKOFF = 1e-3
#: Peaks of a lag error above this fraction of its largest are constrained from the start,
#: at most this many per entry of Q (the highest), and as many more per refinement round.
_NEAR_PEAK = 0.8
_LAG_PEAKS = 3


class Table31:
    """B_Q̃ by the method of thesis Table 3.1 (:func:`q_error_bounds`), the largest over
    ``n_draws`` noise draws whose seeds come from ``seed``."""

    def __init__(
        self,
        estimator: CausalEstimator,
        dt: float,
        noise_std: float | ArrayLike,
        seed: int,
        n_draws: int,
    ) -> None:
        self.estimator, self.dt, self.noise_std = estimator, dt, noise_std
        children = np.random.SeedSequence(seed).spawn(n_draws)
        self.seeds = [int(child.generate_state(1)[0]) for child in children]

    def __call__(self, q: FloatArray, qd: FloatArray, qdd: FloatArray) -> FloatArray:
        bounds = []
        for seed in self.seeds:
            bound = q_error_bounds(
                q, self.dt, self.estimator, noise_std=self.noise_std, seed=seed,
                reference=(qd, qdd),
            )  # fmt: skip
            bounds.append(bound)
        return np.asarray(np.max(bounds, axis=0))

    def noise(self, shape: tuple[int, int]) -> FloatArray:
        """The position noise [rad] of every draw, as :func:`q_error_bounds` adds it:
        shape (n_draws, *shape)."""
        std = per_joint_nonnegative(self.noise_std, shape[1], "noise_std", "rad")
        return np.array([np.random.default_rng(s).standard_normal(shape) * std for s in self.seeds])


class Run:
    """One SLSQP start through its refinement rounds."""

    def __init__(self, x: FloatArray, objective: float, violation: float, info: dict[str, Any]):
        self.x, self.objective, self.violation, self.info = x, objective, violation, info

    @property
    def feasible(self) -> bool:
        return self.violation <= 0.0


def solve(
    problem: Problem,
    x: FloatArray,
    dense: FloatArray,
    first_times: FloatArray,
    schedule: list[float],
    iterations: int,
    ftol: float,
) -> Run:
    """SLSQP from ``x`` through the ε of ``schedule`` (each stage from the last optimum).

    After each solve the limits are checked on ``dense`` and the lag model on
    every sample; times and samples that exceed join the constraints and the
    stage is solved again (at most :data:`REFINEMENT_ROUNDS` times).
    """
    maps = problem.affine(dense)
    times = first_times
    pairs = lag_pairs(problem, x, start=True)
    # s_k >= 0: a bound on B_Q̃'s lag part holds even where no constraint row reaches yet.
    bounds = [(None, None)] * problem.n_z + [(0.0, None)] * problem.n_s
    n_iterations, messages, success = 0, [], True
    violation = np.inf
    for epsilon in schedule:
        problem.set_epsilon(epsilon)
        problem.scale = 1.0
        problem.scale = max(float(np.abs(problem.gradient(x)).max()), np.finfo(float).tiny)
        for _ in range(REFINEMENT_ROUNDS):
            if problem.lag is not None:
                # Start each round feasible for the lag model: s_k at least the largest |e_k|.
                largest = problem.largest_lag(x)
                x = np.concatenate([x[: problem.n_z], np.maximum(x[problem.n_z :], largest)])
            solution = scipy.optimize.minimize(
                problem.objective, x, jac=problem.gradient, method="SLSQP", bounds=bounds,
                constraints=constraints(problem, times, pairs, _BACKOFF),
                options={"maxiter": iterations, "ftol": ftol},
            )  # fmt: skip
            x = np.asarray(solution.x)
            n_iterations += int(solution.nit)
            messages.append(f"ε = {epsilon:g}: {solution.message}")
            success = bool(solution.success)
            excess = problem.limits.violation(problem.robot, *problem.states(x, maps))
            violation = float(excess.max())
            lagging = lag_pairs(problem, x, start=False)
            if violation <= 0.0 and lagging.size == 0:
                break
            times = np.union1d(times, dense[peaks(excess[:, None])[:, 0]])
            pairs = np.unique(np.vstack([pairs, lagging]), axis=0)
    info = {"iterations": n_iterations, "message": "; ".join(messages), "success": success}
    return Run(x, problem.raw_objective(x), violation, info)


def lag_pairs(problem: Problem, x: FloatArray, start: bool) -> IntArray:
    """(draw, sample, entry k) triples, shape (m, 3), where |e_k(t)| peaks: near its largest
    at the ``start``, else above s_k (beyond 0.1 %); the :data:`_LAG_PEAKS` highest per entry."""
    if problem.lag is None:
        return np.zeros((0, 3), dtype=np.intp)
    errors = np.abs(problem.lag.errors(x[: problem.n_z]))
    if start:
        # Peaks near their entry's largest (noise makes many small ones); round-off is none.
        largest = errors.max(axis=(0, 1))
        level = np.maximum(_NEAR_PEAK * largest, 1e-9 * max(float(largest.max()), 1e-300))
    else:
        level = x[problem.n_z :] * (1.0 + _BACKOFF) + 1e-12
    excess = errors - level
    found = []
    for k in range(errors.shape[2]):
        hits = np.argwhere(peaks(excess[:, :, k].T).T)  # (draw, sample) of each peak
        highest = np.argsort(-excess[hits[:, 0], hits[:, 1], k], kind="stable")[:_LAG_PEAKS]
        found.append(np.column_stack([hits[highest], np.full(highest.size, k)]))
    return np.vstack(found).astype(np.intp)


def peaks(excess: FloatArray) -> npt.NDArray[np.bool_]:
    """Where a column of ``excess`` (n_points, n_columns) is > 0 and a local maximum."""
    padded = np.pad(excess, ((1, 1), (0, 0)), constant_values=-np.inf)
    middle = padded[1:-1]
    return np.asarray((middle > 0.0) & (middle >= padded[:-2]) & (middle >= padded[2:]))
