"""Time one streaming step of the learned family's network for 7 joints (median of repeats).

Run: ``OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_learned.py``.
Prints, in µs per sample (wall clock, median and minimum, and process CPU
time, median, of 15 runs of 1000 samples), the network step
(``_cnn.step``), the threshold's public ``step`` (with its input checks)
and, for scale, the floor of calling Pinocchio from Python once per sample
(``crba`` + ``computeCoriolisMatrix`` + ``computeGeneralizedGravity`` for
the Panda, as in ``bench_kernel.py``), with the load average.
"""

from __future__ import annotations

import os
import statistics
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pinocchio as pin

import sensorless as sl
from sensorless.signals import ObserverSignals
from sensorless.thresholds import LearnedThreshold, LearnedWeights, _cnn, save_weights

N_DOF, N_STEPS, REPEATS = 7, 1000, 15


def _network() -> _cnn.Network:
    rng = np.random.default_rng(0)
    norm = {
        "input_mean": np.zeros((4, N_DOF)),
        "input_scale": np.ones((4, N_DOF)),
        "output_mean": np.zeros(N_DOF),
        "output_scale": np.ones(N_DOF),
    }
    return _cnn.random_network(rng, norm)


def _times(make: Callable[[], Callable[[], None]], clock: Callable[[], float]) -> list[float]:
    """µs per sample of REPEATS runs; ``make`` (untimed) gives a fresh run."""
    times = []
    for _ in range(REPEATS):
        run = make()
        start = clock()
        run()
        times.append((clock() - start) / N_STEPS * 1e6)
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

    def network_steps() -> Callable[[], None]:
        first = _cnn.initial_state(net, x[0])  # steps advance the state in place: a fresh one

        def run() -> None:
            state = first
            for row in x:
                _, _, state = _cnn.step(net, state, row)

        return run

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

        cases = (
            ("network step", network_steps),
            ("threshold.step", threshold_steps),
            ("Pinocchio floor", _pinocchio_floor),
        )
        for name, make in cases:
            wall = _times(make, time.perf_counter)
            cpu = statistics.median(_times(make, time.process_time))
            print(
                f"{name:16s} {statistics.median(wall):7.1f} µs wall (min {min(wall):5.1f})"
                f"  {cpu:7.1f} µs cpu  (7 joints, median of {REPEATS} x {N_STEPS} samples)"
            )
    print("Pinocchio floor: crba + computeCoriolisMatrix + computeGeneralizedGravity, Panda")
    print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores")


if __name__ == "__main__":
    main()
