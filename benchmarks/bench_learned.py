"""Time one streaming step of the learned family for 7 joints (median of repeats).

Run: ``OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_learned.py``.
Prints, in µs per sample (wall clock, median and minimum, and process CPU
time, median, of 15 runs of 1000 samples; the cases take turns, so that a
change of the machine's load falls on all of them), the network step
compiled (``_cnn.step``, numba) and in numpy (``_cnn.step_numpy``, the
fallback), the threshold's public ``step`` (with its input checks) and, for
scale, the floor of calling Pinocchio from Python once per sample (``crba``
+ ``computeCoriolisMatrix`` + ``computeGeneralizedGravity`` for the Panda,
as in ``bench_kernel.py``), the ratio of the threshold's step to that floor,
and the load average.
"""

from __future__ import annotations

import os
import statistics
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

import sensorless as sl
from sensorless.learning.training import random_network
from sensorless.signals import ObserverSignals
from sensorless.thresholds import (
    LearnedThreshold,
    LearnedWeights,
    _cnn,
    _cnn_kernel,
    save_weights,
)

N_DOF, N_STEPS, REPEATS = 7, 1000, 15


def _network() -> _cnn.Network:
    rng = np.random.default_rng(0)
    norm = {
        "input_mean": np.zeros((4, N_DOF)),
        "input_scale": np.ones((4, N_DOF)),
        "output_mean": np.zeros(N_DOF),
        "output_scale": np.ones(N_DOF),
    }
    return random_network(rng, norm)


def _times(
    cases: dict[str, Callable[[], Callable[[], None]]],
) -> dict[str, tuple[list[float], list[float]]]:
    """µs per sample (wall, cpu) of REPEATS runs of every case, in turns; ``make`` gives a run."""
    times: dict[str, tuple[list[float], list[float]]] = {name: ([], []) for name in cases}
    for _ in range(REPEATS):
        for name, make in cases.items():
            run = make()  # untimed: a fresh run
            wall, cpu = time.perf_counter(), time.process_time()
            run()
            times[name][0].append((time.perf_counter() - wall) / N_STEPS * 1e6)
            times[name][1].append((time.process_time() - cpu) / N_STEPS * 1e6)
    return times


def _pinocchio_floor() -> Callable[[], None]:
    model = sl.robots.load("panda").pinocchio_model
    data = model.createData()
    rng = np.random.default_rng(0)
    q, qd = rng.uniform(-2, 2, (2, N_STEPS, model.nv))

    def loop() -> None:
        for k in range(N_STEPS):
            pin.crba(model, data, q[k])
            pin.computeCoriolisMatrix(model, data, q[k], qd[k])
            pin.computeGeneralizedGravity(model, data, q[k])

    return loop


def main() -> None:
    net = _network()
    x = np.random.default_rng(1).normal(size=(N_STEPS, 4, N_DOF))

    def network_steps(step: Callable[..., Any]) -> Callable[[], Callable[[], None]]:
        def make() -> Callable[[], None]:
            first = _cnn.initial_state(net, x[0])  # steps advance the state in place: a fresh one

            def run() -> None:
                state = first
                for row in x:
                    _, _, state = step(net, state, row)

            return run

        return make

    with tempfile.TemporaryDirectory() as folder:
        path = save_weights(
            LearnedWeights(net, robot="bench", kind="motor", gain=20.0, dt=1e-3),
            Path(folder) / "bench",
        )
        t = np.arange(200) * 1e-3
        z = np.zeros((200, N_DOF))
        fit = ObserverSignals(t, z + 0.1, z, z, z, z, gain=20.0, robot="bench")
        threshold = LearnedThreshold(path).fit(fit)
        rows = [tuple(x[k, c] for c in range(4)) for k in range(N_STEPS)]

        def threshold_steps() -> Callable[[], None]:
            first = threshold.initial_state(*rows[0])

            def run() -> None:
                state = first
                for row in rows:
                    _, _, state = threshold.step(state, *row)

            return run

        cases = {
            "network step": network_steps(_cnn.step),
            "network (numpy)": network_steps(_cnn.step_numpy),
            "threshold.step": threshold_steps,
            "Pinocchio floor": _pinocchio_floor,
        }
        for make in cases.values():  # compile (or load numba's cache) before timing
            make()()
        times = _times(cases)
        for name, (wall, cpu) in times.items():
            print(
                f"{name:16s} {statistics.median(wall):7.1f} µs wall (min {min(wall):5.1f})"
                f"  {statistics.median(cpu):7.1f} µs cpu  "
                f"(7 joints, median of {REPEATS} x {N_STEPS} samples)"
            )
    ratio = statistics.median(times["threshold.step"][0]) / statistics.median(
        times["Pinocchio floor"][0]
    )
    print(f"network step compiled: {_cnn_kernel.available} (numba)")
    print(f"threshold.step / Pinocchio floor: {ratio:.2f} (wall medians)")
    print("Pinocchio floor: crba + computeCoriolisMatrix + computeGeneralizedGravity, Panda")
    print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores")


if __name__ == "__main__":
    main()
