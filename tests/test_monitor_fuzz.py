"""Fuzzing the live monitor: bad samples between good ones never raise and change nothing.

Between the good samples of a recorded run, hypothesis inserts samples that
are bad in one way or another: arbitrary floats (±1e308, subnormals, −0.0,
NaN, inf), arbitrary shapes, non-numbers, out-of-limit values, and time
stamps that repeat, go back, come too early or jump ahead. Every family must
answer each bad sample with a fault, never an exception, and give on the good
samples exactly the verdicts and residuals of a stream that never saw the bad ones.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from sensorless.monitor import CollisionMonitor, tune
from sensorless.robots.recursion import numba_available
from sensorless.simulation.scenario import load_scenario
from test_monitor_compiled import assert_goes_on

FAMILIES = ("constant", "time-variant", "hysteretic", "velocity", "model")
COMPILED = ("constant", "time-variant", "hysteretic", "velocity")  # the numba stream's families
needs_numba = pytest.mark.skipif(not numba_available(), reason="numba is not installed")
CASES = (
    [(m, "python") for m in FAMILIES]
    + [pytest.param(m, "numba", marks=needs_numba) for m in COMPILED]
    + [(m, "numpy") for m in COMPILED]  # the stream without numba: the same families
)
N_GOOD = 120  # good samples per example, after the settling window
DT = 1e-3

floats = st.floats(allow_nan=True, allow_infinity=True, allow_subnormal=True, width=64)
# Values no joint can have: each bad array holds at least one, among arbitrary floats
# (subnormals and −0.0 included) in the other entries.
impossible = st.sampled_from([1e308, -1e308, 1e200, np.nan, np.inf, -np.inf, 1e7, -1e7])


@pytest.fixture(scope="module")
def setup():
    scenario = load_scenario("panda-gaz").with_duration(3.0)
    free = [scenario.run(seed=s, collisions=False).log for s in (1, 2)]
    test = scenario.run(seed=3).log
    nominal = scenario.robots()[1]
    monitors = {m: tune(free, nominal, m, margin=0.05, folds=None) for m in FAMILIES}
    return test, nominal, monitors


def _bad_value(n: int) -> st.SearchStrategy[Any]:
    """A value for q or tau that no stream may accept."""
    wrong_shape = hnp.arrays(
        np.float64,
        st.one_of(st.tuples(st.integers(0, 9).filter(lambda k: k != n)), st.just((2, n))),
        elements=floats,
    )
    non_finite = st.tuples(
        hnp.arrays(np.float64, (n,), elements=floats), st.integers(0, n - 1), impossible
    ).map(lambda a: np.where(np.arange(n) == a[1], a[2], a[0]))
    return st.one_of(
        wrong_shape,
        non_finite,
        st.sampled_from(["q", None, object(), [1.0, "x"], {"a": 1}]),
    )


def _bad_time(last: float) -> st.SearchStrategy[float]:
    """A time stamp no stream may accept after ``last`` (values may be good)."""
    offsets = st.one_of(
        st.sampled_from([0.0, -DT, 1e-12, 0.4 * DT, 2.0 * DT, 0.5, 1000.0, -1000.0]),
        st.floats(min_value=1.6 * DT, max_value=1e6),
        st.floats(min_value=-1e6, max_value=0.49 * DT),
    )
    return st.one_of(
        offsets.map(lambda d: last + d), st.sampled_from([np.nan, np.inf, -np.inf, 1e308])
    )


@st.composite
def bad_sample(
    draw: Any, last: float, q: np.ndarray, tau: np.ndarray, first: bool
) -> tuple[Any, Any, Any]:
    """A sample the stream must refuse; only the first of a slot may have good values.

    (A second good-valued sample regular with the first would be a stream
    resumed after a gap: see :mod:`sensorless.monitor.policy`.)
    """
    n = q.shape[0]
    if first and draw(st.booleans()):
        return draw(_bad_time(last)), q, tau
    t = draw(st.one_of(st.just(last + DT), floats))
    if draw(st.booleans()):
        return t, draw(_bad_value(n)), tau
    return t, q, draw(_bad_value(n))


@pytest.mark.filterwarnings("ignore:overflow encountered:RuntimeWarning")  # numpy, q of 1e308
@pytest.mark.parametrize(("method", "backend"), CASES)
@settings(
    max_examples=25,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
@given(data=st.data())
def test_bad_samples_between_good_ones(setup, method, backend, data) -> None:
    test, nominal, tuned = setup
    threshold, observer_settings = tuned[method]
    clean = CollisionMonitor(nominal, threshold, observer_settings, backend=backend)
    fuzzed = CollisionMonitor(nominal, threshold, observer_settings, backend=backend)
    start = int(np.ceil(clean.settle / DT)) + 5
    first = data.draw(st.integers(0, test.n_samples - start - N_GOOD - 1), label="first")
    inserts = data.draw(
        st.lists(st.integers(start, start + N_GOOD - 1), max_size=25), label="positions"
    )
    for k in range(first, first + start + N_GOOD):
        i = k - first
        t, q, tau = test.t[k], test.q[k], test.tau_m[k]
        for j in range(inserts.count(i)):
            bad = data.draw(bad_sample(test.t[k - 1], q, tau, j == 0), label="bad sample")
            verdict = fuzzed.step(*bad)
            assert verdict.status == "fault", (bad, verdict)
        expected = clean.step(t, q, tau)
        got = fuzzed.step(t, q, tau)
        assert_goes_on(got, expected, "lower")
