"""Per-sample cost of p = M q̇, Cᵀq̇ and g: the O(n) recursion against Pinocchio (issue 22).

For the 6-dof PUMA 560 and the 7-dof Panda, prints the median over several
runs of the cost per sample [µs] of

- the three standard Pinocchio calls in a Python loop (``crba``,
  ``computeCoriolisMatrix``, ``computeGeneralizedGravity``): the floor of
  calling Pinocchio once per sample from Python;
- :meth:`MomentumTerms.terms` over a whole time series, numpy and numba;
- :meth:`MomentumTerms.terms_one` in a Python loop, numpy (Pinocchio calls)
  and numba;

with each cost divided by the floor's. One thread; compile time excluded.

    .venv/bin/python benchmarks/bench_kernel.py [--samples 200000] [--loop 20000] [--repeat 5]
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections.abc import Callable

import numpy as np
import pinocchio as pin

import sensorless as sl
from sensorless.robots.recursion import MomentumTerms, numba_available


def median_us(run: Callable[[], object], n_samples: int, repeat: int) -> float:
    """Median over ``repeat`` runs of the wall time per sample [µs]."""
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        run()
        times.append(time.perf_counter() - start)
    return statistics.median(times) / n_samples * 1e6


def one_sample_loop(
    terms: MomentumTerms, samples: list[tuple[np.ndarray, np.ndarray]]
) -> Callable[[], None]:
    """A loop of ``terms_one`` over (q, q̇) rows, compiled beforehand."""
    out = np.empty((3, terms.n_dof))
    terms.terms_one(samples[0][0], samples[0][1], out)

    def loop() -> None:
        for q, qd in samples:
            terms.terms_one(q, qd, out)

    return loop


def bench_robot(name: str, n_batch: int, n_loop: int, repeat: int) -> list[tuple[str, float]]:
    """Rows (label, µs per sample) for one robot, the Pinocchio floor first."""
    robot = sl.robots.load(name)
    model = robot.pinocchio_model
    data = model.createData()
    rng = np.random.default_rng(0)
    shape = (n_batch, robot.n_dof)
    q, qd = rng.uniform(-2, 2, shape), rng.uniform(-2, 2, shape)

    def pinocchio_loop() -> None:
        for k in range(n_loop):
            pin.crba(model, data, q[k])
            pin.computeCoriolisMatrix(model, data, q[k], qd[k])
            pin.computeGeneralizedGravity(model, data, q[k])

    floor = median_us(pinocchio_loop, n_loop, repeat)
    rows = [("Pinocchio crba + Coriolis + gravity, loop", floor)]
    backends = ["numpy", "numba"] if numba_available() else ["numpy"]
    for backend in backends:
        terms = MomentumTerms(model, backend=backend)
        terms.terms(q[:2], qd[:2])
        batch = median_us(lambda terms=terms: terms.terms(q, qd), n_batch, repeat)
        rows.append((f"MomentumTerms.terms, {backend}, {n_batch} samples", batch))
    samples = list(zip(q[:n_loop], qd[:n_loop], strict=True))
    for backend in backends:
        loop = one_sample_loop(MomentumTerms(model, backend=backend), samples)
        rows.append((f"MomentumTerms.terms_one, {backend}, loop", median_us(loop, n_loop, repeat)))
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=200_000, help="samples of the batch calls")
    parser.add_argument("--loop", type=int, default=20_000, help="samples of the Python loops")
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    if not numba_available():
        print("numba is not installed: numba rows left out (pip install numba)")
    print(f"median of {args.repeat} runs; cost per sample [µs]; ratio to the Pinocchio loop")
    for name in ("puma560", "panda"):
        rows = bench_robot(name, args.samples, args.loop, args.repeat)
        floor = rows[0][1]
        print(f"\n{name} ({sl.robots.load(name).n_dof} dof)")
        print(f"{'path':52s} {'µs/sample':>10s} {'ratio':>7s}")
        for label, cost in rows:
            print(f"{label:52s} {cost:10.3f} {cost / floor:7.3f}")


if __name__ == "__main__":
    main()
