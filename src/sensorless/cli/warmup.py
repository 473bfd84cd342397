"""``sensorless warm-up``: compile the numba kernels once, into numba's cache beside the sources.

The compiled paths (the simulator's sample loop and plant periods, the
observer's recursion, the fused stream and batch of the monitor) are compiled
on first use and cached on disk (``cache=True``). On a fresh clone that first
use is the demo or the test suite, where every worker process would compile
the same kernels. ``make`` runs this command once after installing, so later
runs load the kernels from the cache. Without numba it says so and does nothing.
"""

from __future__ import annotations

import time

from ..monitor import CollisionMonitor, tune
from ..robots.recursion import numba_available
from ..simulation.scenario import load_scenario
from ._common import console

__all__ = ["warm_up_command"]

# A rigid arm with LuGre friction, a rigid arm with a sigmoid model and computed torque,
# and a flexible arm: each compiles its own plant and loop kernels.
_SCENARIOS = ("puma560-thesis", "panda-gaz", "lwr4-thesis")
_SECONDS = 0.3  # long enough to pass the monitor's settling window


def warm_up_command() -> None:
    """Compile the simulator's and the monitor's numba kernels into numba's cache."""
    if not numba_available():
        console.print("numba is not installed: nothing to compile (the numpy paths run)")
        return
    for name in _SCENARIOS:
        start = time.perf_counter()
        scenario = load_scenario(name).with_duration(_SECONDS)
        result = scenario.run(seed=0, collisions=False)
        nominal = scenario.nominal("motor")
        threshold, settings = tune([result.log], nominal, "time-variant", folds=None)
        monitor = CollisionMonitor(nominal, threshold, settings)
        monitor.process(result.log)
        console.print(
            f"{name}: simulator {result.backend}, monitor {monitor.backend} "
            f"({time.perf_counter() - start:.1f} s)"
        )
