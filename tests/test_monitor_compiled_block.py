"""The compiled batch by phases (``_compiled_block``) against the per-sample kernel: bit for bit."""

from __future__ import annotations

import copy

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sensorless.friction import Coulomb
from sensorless.monitor import CollisionMonitor, ObserverSettings, tune
from sensorless.monitor._codes import (
    FAULT_BOUNDS,
    FAULT_EARLY,
    FAULT_GAP,
    FAULT_OBSERVER,
    FAULT_Q,
    FAULT_TAU_M,
    FAULT_VELOCITY,
    SETTLING,
)
from sensorless.robots.recursion import numba_available
from sensorless.simulation.scenario import load_scenario

pytestmark = pytest.mark.skipif(not numba_available(), reason="numba is not installed")

FAMILIES = ("constant", "time-variant", "hysteretic", "velocity")


@pytest.fixture(scope="module")
def panda():
    """Test log, nominal robot and the four tuned families on the Panda."""
    scenario = load_scenario("panda-gaz").with_duration(3.0)
    free = [scenario.run(seed=s, collisions=False).log for s in (1, 2)]
    nominal = scenario.robots()[1]
    tuned = {m: tune(free, nominal, m, margin=0.05, folds=None) for m in FAMILIES}
    return scenario.run(seed=3).log, nominal, tuned


def _columns(log, measured=False):
    """(t, (q, qd, tau_m, tau_j)) of ``log`` as ``FusedStream.block`` takes them, copies."""
    q, tau = np.array(log.q), np.array(log.tau_m)
    qd = np.array(log.qd_true) if measured else np.empty((log.n_samples, 0))
    return np.array(log.t), [q, qd, tau, tau]


def _disturbed(log, measured=False):
    """Columns with, in this order: a NaN stretch, a torque breach, an early sample, a jump of
    q_2 (its velocity estimate beyond the limit), a gap the stream restarts after."""
    t, (q, qd, tau, _) = _columns(log, measured)
    dt = log.dt
    q[400:420, 2] = np.nan
    tau[700, 1] = 1e6
    t[900] = t[899] + 0.2 * dt
    q[1300, 1] += 0.5
    if measured:
        qd[1300, 1] = 1e3
    keep = np.r_[0:2400, 2500 : log.n_samples]  # after the collision (1.93-2.15 s)
    return t[keep], [c[keep] for c in (q, qd, tau, tau)]


def _both(monitor, t, sample, chunk):
    """``block`` of the phases (``chunk``) and of the per-sample kernel (chunk 0)."""
    fused = monitor._fused
    return (
        fused.block(t, tuple(np.ascontiguousarray(c) for c in sample), "m", chunk),
        fused.block(t, tuple(np.ascontiguousarray(c) for c in sample), "m", 0),
    )


def _assert_identical(got, expected) -> None:
    codes, series, events = got
    np.testing.assert_array_equal(codes, expected[0])
    np.testing.assert_array_equal(series, expected[1])  # NaN where NaN, else the same bits
    assert events == expected[2]


@pytest.mark.parametrize("chunk", [1, 5, 128])
@pytest.mark.parametrize("method", FAMILIES)
def test_phases_equal_the_per_sample_kernel(panda, method, chunk) -> None:
    log, nominal, tuned = panda
    monitor = CollisionMonitor(nominal, *tuned[method], backend="numba")
    for measured in (False, True):
        t, sample = _disturbed(log, measured)
        got, expected = _both(monitor, t, sample, chunk)
        _assert_identical(got, expected)
        status = got[0] & 15
        # Every disturbance is there (the phases stop before each), and events were found.
        for code, k in ((FAULT_Q, 400), (FAULT_TAU_M, 700), (FAULT_EARLY, 900)):
            assert status[k] == code
        assert FAULT_VELOCITY in status[1300:1310]
        assert status[2400] == FAULT_GAP and status[2401] == SETTLING
        assert got[2] and np.isfinite(got[1][0, 1000:1300]).all()


@pytest.mark.filterwarnings("ignore:overflow encountered:RuntimeWarning")  # building the robot
def test_phases_stop_at_a_non_finite_observer_or_bound(panda) -> None:
    log, nominal, tuned = panda
    threshold, settings = tuned["time-variant"]
    # Friction that overflows the observer once a joint moves: its output becomes inf.
    huge = Coulomb(c_pos=np.full(7, 1e308), c_neg=np.full(7, -1e308))
    robot = nominal.with_standard_parameters(nominal.parameter_vector(), friction=huge)
    broken = copy.deepcopy(threshold)
    broken.alpha_ = broken.alpha_.copy()
    broken.alpha_[2] = np.nan  # every judged sample: a NaN bound
    for model, fitted, fault in (
        (robot, threshold, FAULT_OBSERVER),
        (nominal, broken, FAULT_BOUNDS),
    ):
        if fitted.fingerprint_ not in ("", model.fingerprint):
            fitted = copy.copy(fitted)
            fitted.fingerprint_ = ""
        monitor = CollisionMonitor(model, fitted, settings, backend="numba")
        t, sample = _columns(log)
        got, expected = _both(monitor, t, sample, 128)
        _assert_identical(got, expected)
        assert fault in got[0] & 15


def test_phases_of_joint_torques_equal_the_per_sample_kernel() -> None:
    scenario = load_scenario("lwr4-thesis").with_duration(2.0)
    free = [scenario.run(seed=1, collisions=False).log]
    log = scenario.run(seed=2).log
    robot = scenario.nominal("joint")
    settings = ObserverSettings(kind="joint")
    monitor = CollisionMonitor(
        robot, *tune(free, robot, "constant", settings, margin=0.05, folds=None), backend="numba"
    )
    t = np.array(log.t)
    tau_j = np.array(log.tau_j)
    tau_j[600, 3] = 1e7  # beyond its limit
    sample = [np.array(log.q), np.empty((log.n_samples, 0)), np.array(log.tau_m), tau_j]
    got, expected = _both(monitor, t, sample, 128)
    _assert_identical(got, expected)
    assert (got[0][600] & 15) > SETTLING


@pytest.mark.parametrize("method", ["time-variant", "velocity"])
def test_the_batch_is_the_live_stream_bit_for_bit(panda, method) -> None:
    """``process`` (phases) and ``step`` sample by sample: the same bits, codes and events."""
    log, nominal, tuned = panda
    monitor = CollisionMonitor(nominal, *tuned[method], backend="numba")
    run = monitor.process(log)
    events = []
    for k in range(log.n_samples):
        verdict = monitor.step(log.t[k], log.q[k], log.tau_m[k])
        assert (verdict.status == "settling") == run.settling[k]
        np.testing.assert_array_equal(verdict.residual, run.signals.residual[k])
        events += [] if verdict.event is None else [verdict.event]
    last = monitor.finish()
    assert events + ([] if last is None else [last]) == run.events
    assert run.events


_KINDS = ("nan_q", "torque", "early", "late", "jump", "speed", "gap", "repeat")


@settings(max_examples=30, deadline=None)
@given(
    disturbances=st.lists(
        st.tuples(st.sampled_from(_KINDS), st.integers(2, 1499), st.integers(1, 40)), max_size=6
    ),
    chunk=st.sampled_from([1, 2, 3, 17, 128, 1000]),
    method=st.sampled_from(FAMILIES),
    measured=st.booleans(),
)
def test_phases_equal_the_per_sample_kernel_on_any_disturbance(
    panda, disturbances, chunk, method, measured
) -> None:
    """Faults of every kind, anywhere, for any length: the phases give the kernel's bits."""
    log, nominal, tuned = panda
    monitor = CollisionMonitor(nominal, *tuned[method], backend="numba")
    t, (q, qd, tau, _) = _columns(log, measured)
    t, q, qd, tau = t[:1500], q[:1500], qd[:1500], tau[:1500]
    keep = np.ones(t.size, dtype=bool)
    for kind, k, width in disturbances:
        span = slice(k, min(k + width, t.size))
        if kind == "nan_q":
            q[span, 1] = np.nan
        elif kind == "torque":
            tau[span, 4] = 1e6
        elif kind == "early":
            t[k] = t[k - 1] + 0.3 * log.dt
        elif kind == "late":  # inside the gap rule: accepted
            t[k] = t[k - 1] + 1.4 * log.dt
        elif kind == "jump":
            q[span, 0] += 0.3
        elif kind == "speed" and measured:
            qd[span, 2] = 1e4
        elif kind == "gap":
            keep[span] = False
        elif kind == "repeat":
            t[k] = t[k - 1]
    t, sample = t[keep], [c[keep] for c in (q, qd, tau, tau)]
    got, expected = _both(monitor, t, sample, chunk)
    _assert_identical(got, expected)
