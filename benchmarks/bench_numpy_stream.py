"""One stream step without numba: the numpy stream against the Python path and the Pinocchio floor.

Prints, per robot (panda-gaz, 7 joints; puma560-thesis, 6 joints) and per
threshold family, the median cost [µs] of one ``CollisionMonitor.step`` after
the settling window on a collision run, for the numpy stream
(:mod:`sensorless.monitor._numpy_stream`, ``backend="numpy"``) and for the
Python path, beside the Pinocchio floor of one sample: ``crba`` +
``computeCoriolisMatrix`` + ``computeGeneralizedGravity`` called from Python,
median over the samples. Issue 22's goal: the numpy stream at most 3× the floor.

The machine may be shared and noisy: the variants are interleaved sample by
sample (floor, numpy step, Python step of sample k, then sample k + 1), in an
order that rotates from repeat to repeat; each figure is the median over the
repeats of the median over the samples, and "(per run)" the median over the
repeats of the ratio numpy / floor within one repeat. The Python step between
them leaves the caches colder for both; "(no python)" is the same ratio from a
second pass per repeat that interleaves only the floor, the numpy step and
the issue's reference "the same calls + the observer update in numpy"
(:class:`BareObserver`), the stricter comparison; "bare/floor" is that
reference's ratio in the same pass. Run on one thread::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_numpy_stream.py
"""

from __future__ import annotations

import statistics
import sys
import time
from typing import Any

import numpy as np
import pinocchio as pin

from sensorless.monitor import CollisionMonitor, tune
from sensorless.simulation.scenario import load_scenario

SCENARIOS = ("panda-gaz", "puma560-thesis")
FAMILIES = ("constant", "time-variant", "hysteretic", "velocity")
REPEATS = 7
SAMPLES = 2000  # samples per run from the start of the log; the settling window is not timed


def interleaved(
    monitors: dict[str, Any], model: pin.Model, log_rows: tuple[np.ndarray, ...],
    order: list[str],
) -> dict[str, float]:  # fmt: skip
    """Median seconds per sample of each variant, timed sample by sample in ``order``.

    ``"floor"`` is the three standard Pinocchio calls on the sample; the others
    are ``step`` of the named monitor (a :class:`CollisionMonitor` first, or a
    :class:`BareObserver`), from a fresh stream. The settling window is not timed.
    """
    t, q, qd, tau = log_rows
    data = model.createData()
    for monitor in monitors.values():
        monitor.reset()
    costs: dict[str, list[float]] = {key: [] for key in order}
    clock = time.perf_counter
    for k in range(t.shape[0]):
        for key in order:
            if key == "floor":
                start = clock()
                pin.crba(model, data, q[k])
                pin.computeCoriolisMatrix(model, data, q[k], qd[k])
                pin.computeGeneralizedGravity(model, data, q[k])
            else:
                monitor = monitors[key]
                start = clock()
                monitor.step(t[k], q[k], tau[k])
            costs[key].append(clock() - start)
    any_monitor = next(iter(monitors.values()))
    settled = int(np.ceil(any_monitor.settle / any_monitor.dt))
    return {key: statistics.median(values[settled:]) for key, values in costs.items()}


class BareObserver:
    """Issue 22's reference row "the same calls + the observer update in numpy".

    The three standard calls and nothing but a first-order momentum observer
    (p = M q̇, β = g − Cᵀq̇, explicit Euler, K_I = 50/s) with q̇ by backward
    differences and a constant band per joint: no limits, faults, settling,
    velocity filter, friction, bounds of a family or detector. Units SI.
    """

    def __init__(self, model: pin.Model, dt: float, band: float = 5.0) -> None:
        self.model, self.data, self.dt = model, model.createData(), dt
        self.gain, self.band = 50.0, np.full(model.nv, band)
        self.reset()

    def reset(self) -> None:
        self.q_last: np.ndarray | None = None
        self.p0, self.integral, self.r = (np.zeros(self.model.nv) for _ in range(3))

    def step(self, t: float, q: np.ndarray, tau: np.ndarray) -> bool:
        """One sample at time ``t`` [s]; whether a joint's residual leaves the band."""
        model, data = self.model, self.data
        v = np.zeros_like(q) if self.q_last is None else (q - self.q_last) / self.dt
        m = pin.crba(model, data, q)
        c = pin.computeCoriolisMatrix(model, data, q, v)
        g = pin.computeGeneralizedGravity(model, data, q)
        p = m.dot(v)
        if self.q_last is None:
            self.p0 = p
        self.q_last = q.copy()
        self.integral = self.integral + (tau + c.T.dot(v) - g + self.r) * self.dt
        self.r = self.gain * (p - self.p0 - self.integral)
        return bool((np.abs(self.r) > self.band).any())


def numpy_monitor(robot: Any, threshold: Any, settings: Any) -> CollisionMonitor:
    """A monitor whose ``step`` runs the numpy stream."""
    monitor = CollisionMonitor(robot, threshold, settings, backend="numpy")
    return monitor


def main() -> None:
    print(f"median of {REPEATS} runs (each the median over ~{SAMPLES - 250} steps), µs per sample")
    print(
        f"{'robot':<16}{'family':<14}{'floor':>8}{'numpy':>9}{'python':>9}"
        f"{'numpy/floor':>13}{'(per run)':>13}{'(no python)':>13}{'bare/floor':>12}"
        f"{'python/floor':>14}"
    )
    for name in SCENARIOS:
        scenario = load_scenario(name).with_duration(8.0)  # as benchmarks/bench_monitor.py
        free = [scenario.run(seed=s, collisions=False).log for s in (1, 2)]
        log = scenario.run(seed=3).log
        nominal = scenario.robots()[1]
        n = min(SAMPLES, log.n_samples)
        t, q, tau = log.t[:n], log.q[:n], log.tau_m[:n]
        qd = np.gradient(log.q, log.dt, axis=0)[:n]
        for method in FAMILIES:
            threshold, settings = tune(free, nominal, method, margin=0.05, folds=None)
            monitors = {
                "numpy": numpy_monitor(nominal, threshold, settings),
                "python": CollisionMonitor(nominal, threshold, settings, backend="python"),
            }
            names = ["floor", "numpy", "python"]
            medians: dict[str, list[float]] = {key: [] for key in names}
            ratios, strict, bare = [], [], []
            # the stricter pass: the floor, the numpy stream and the bare observer update only
            numpy_only = {
                "numpy": monitors["numpy"],
                "bare": BareObserver(nominal.pinocchio_model, log.dt),
            }
            three = ["floor", "bare", "numpy"]
            for repeat in range(REPEATS):
                order = names[repeat % 3 :] + names[: repeat % 3]  # rotated each repeat
                run = interleaved(monitors, nominal.pinocchio_model, (t, q, qd, tau), order)
                for key in names:
                    medians[key].append(run[key])
                ratios.append(run["numpy"] / run["floor"])
                order = three[repeat % 3 :] + three[: repeat % 3]
                run = interleaved(numpy_only, nominal.pinocchio_model, (t, q, qd, tau), order)
                strict.append(run["numpy"] / run["floor"])
                bare.append(run["bare"] / run["floor"])
            floor, fast, slow = (1e6 * statistics.median(medians[key]) for key in names)
            ratio = statistics.median(ratios)
            print(
                f"{name:<16}{method:<14}{floor:>8.2f}{fast:>9.2f}{slow:>9.2f}"
                f"{fast / floor:>13.2f}{ratio:>13.2f}{statistics.median(strict):>13.2f}"
                f"{statistics.median(bare):>12.2f}{slow / floor:>14.2f}"
            )
            sys.stdout.flush()


if __name__ == "__main__":
    main()
