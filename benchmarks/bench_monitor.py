"""Live-monitor cost on the 7-joint Panda: one stream step per family, and the batch path.

Prints, in one process:

* the Pinocchio floor of one observer step: ``crba`` + ``computeCoriolisMatrix``
  + ``computeGeneralizedGravity`` on one sample, median over the samples;
* per threshold family, the median and p99 [µs] of ``CollisionMonitor.step``
  and its ratio to the floor, side by side for the Python path, the numpy
  stream (``backend="numpy"``) and the compiled one (``backend="numba"``),
  where the family has them;
* batch ``CollisionMonitor.run`` in samples/s, Python path (arrays) and
  compiled path (the stream's kernel over the log), beside the bare loop of
  the three Pinocchio calls over the same samples.

Every figure is the median of ``REPEATS`` runs. Run with
``.venv/bin/python benchmarks/bench_monitor.py``.
"""

from __future__ import annotations

import statistics
import time

import numpy as np
import pinocchio as pin

from sensorless.monitor import CollisionMonitor, tune
from sensorless.robots.recursion import numba_available
from sensorless.simulation.scenario import load_scenario

FAMILIES = ("constant", "time-variant", "hysteretic", "velocity", "model")
COMPILED = ("constant", "time-variant", "hysteretic", "velocity")
REPEATS = 5
STREAM_SAMPLES = 3000


def pinocchio_floor(model: pin.Model, q: np.ndarray, qd: np.ndarray) -> list[float]:
    """Seconds per sample of the three standard calls, one timing per sample."""
    data = model.createData()
    out = []
    for k in range(q.shape[0]):
        start = time.perf_counter()
        pin.crba(model, data, q[k])
        pin.computeCoriolisMatrix(model, data, q[k], qd[k])
        pin.computeGeneralizedGravity(model, data, q[k])
        out.append(time.perf_counter() - start)
    return out


def stream_costs(monitor: CollisionMonitor, t, q, tau) -> list[float]:
    """Seconds of each ``step`` after the settling window."""
    monitor.reset()
    out = []
    for k in range(t.shape[0]):
        start = time.perf_counter()
        monitor.step(t[k], q[k], tau[k])
        out.append(time.perf_counter() - start)
    return out


def step_cost(monitor: CollisionMonitor, t, q, tau) -> tuple[float, float]:
    """Median and p99 [s] of one ``step`` after the settling window, median over the repeats."""
    runs = [stream_costs(monitor, t, q, tau) for _ in range(REPEATS)]
    settled = int(np.ceil(monitor.settle / monitor.dt))
    median = statistics.median(statistics.median(r[settled:]) for r in runs)
    p99 = statistics.median(float(np.percentile(r[settled:], 99)) for r in runs)
    return median, p99


def main() -> None:
    scenario = load_scenario("panda-gaz").with_duration(8.0)
    free = [scenario.run(seed=s, collisions=False).log for s in (1, 2)]
    log = scenario.run(seed=3).log
    nominal = scenario.robots()[1]
    model = nominal.pinocchio_model
    qd = np.gradient(log.q, log.dt, axis=0)
    n = STREAM_SAMPLES
    floors = [statistics.median(pinocchio_floor(model, log.q[:n], qd[:n])) for _ in range(REPEATS)]
    floor = statistics.median(floors)
    print(f"Panda (7 joints), {n} samples, median of {REPEATS} runs")
    print(f"Pinocchio floor (crba + Coriolis + gravity, one sample): {1e6 * floor:.2f} µs")
    columns = f"{'median µs':>11}{'p99 µs':>9}{'× floor':>9}"
    print(f"{'':<14}" + "   ".join(f"{b:^29}" for b in ("python", "numpy", "numba")))
    print(f"{'family':<14}" + "   ".join([columns] * 3))
    for method in FAMILIES:
        threshold, settings = tune(free, nominal, method, margin=0.05, folds=None)
        cells = []
        for backend in ("python", "numpy", "numba"):
            if backend != "python" and (
                method not in COMPILED or (backend == "numba" and not numba_available())
            ):
                cells.append(f"{'(Python path only)':^29}")
                continue
            monitor = CollisionMonitor(nominal, threshold, settings, backend=backend)
            median, p99 = step_cost(monitor, log.t[:n], log.q[:n], log.tau_m[:n])
            cells.append(f"{1e6 * median:>11.2f}{1e6 * p99:>9.2f}{median / floor:>9.2f}")
        print(f"{method:<14}" + "   ".join(cells))

    threshold, settings = tune(free, nominal, "time-variant", margin=0.05, folds=None)
    rates = {}
    for backend in ("python", "numba") if numba_available() else ("python",):
        monitor = CollisionMonitor(nominal, threshold, settings, backend=backend)
        monitor.run(log)  # warm: the compiled path loads from numba's cache once
        batch = []
        for _ in range(REPEATS):
            start = time.perf_counter()
            monitor.run(log)
            batch.append(time.perf_counter() - start)
        rates[backend] = log.n_samples / statistics.median(batch)
    bare = []
    data = model.createData()
    for _ in range(REPEATS):
        start = time.perf_counter()
        for k in range(log.n_samples):
            pin.crba(model, data, log.q[k])
            pin.computeCoriolisMatrix(model, data, log.q[k], qd[k])
            pin.computeGeneralizedGravity(model, data, log.q[k])
        bare.append(time.perf_counter() - start)
    bare_rate = log.n_samples / statistics.median(bare)
    print(
        f"bare loop of the three Pinocchio calls, {log.n_samples} samples: "
        f"{bare_rate:,.0f} samples/s"
    )
    for backend, rate in rates.items():
        print(
            f"batch run (time-variant), {backend:<6}: {rate:>11,.0f} samples/s, "
            f"{bare_rate / rate:.2f}× the Pinocchio per-sample cost"
        )


if __name__ == "__main__":
    main()
