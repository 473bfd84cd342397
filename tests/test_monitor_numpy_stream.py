"""The numpy stream (no numba) against the Python stream and the compiled one.

:class:`~sensorless.monitor._numpy_stream.NumpyStream` runs the monitors built
with ``backend="numpy"``; the reference is the same monitor's Python path and,
where numba is installed, the compiled stream.
"""

from __future__ import annotations

import copy
import math
import pickle
import subprocess
import sys
import textwrap
from typing import Any

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from sensorless.friction import CoulombViscous, HystereticError, Stribeck, Viscous
from sensorless.monitor import (
    Adaptation,
    CollisionMonitor,
    ObserverSettings,
    StreamPolicy,
    tune,
)
from sensorless.monitor._numpy_stream import NumpyStream, unsupported
from sensorless.observers import MomentumObserver
from sensorless.robots.recursion import MomentumTerms, numba_available
from sensorless.simulation.scenario import load_scenario
from test_monitor_compiled import assert_goes_on, assert_same_event, assert_same_verdict

FAMILIES = ("constant", "time-variant", "hysteretic", "velocity")
TOLERANCE = 1e-9  # N m, residuals and bounds
# As in test_monitor_compiled: a subset of monitored joints, and the velocity bounds'
# widening outside the visited bins.
OPTIONS = {
    "constant": {},
    "time-variant": {},
    "hysteretic": {"joints": [1, 2, 4]},
    "velocity": {"extrapolation_margin": 0.1, "joints": [2, 3, 5, 6, 7]},
}
BACKENDS = ["python", pytest.param("numba", marks=pytest.mark.skipif(
    not numba_available(), reason="numba is not installed"))]  # fmt: skip


@pytest.fixture(scope="module")
def panda():
    """Collision run of the Panda (7 joints), nominal robot and the four tuned families."""
    scenario = load_scenario("panda-gaz").with_duration(2.0)
    free = [scenario.run(seed=s, collisions=False).log for s in (1, 2)]
    test = scenario.run(seed=3).log
    nominal = scenario.robots()[1]
    tuned = {m: tune(free, nominal, m, margin=0.05, folds=None, **OPTIONS[m]) for m in FAMILIES}
    return test, nominal, tuned


def _numpy_monitor(robot, tuned, **options) -> CollisionMonitor:
    """A monitor whose ``step`` runs the numpy stream."""
    threshold, observer_settings = tuned
    monitor = CollisionMonitor(robot, threshold, observer_settings, backend="numpy", **options)
    assert unsupported(monitor) == "" and monitor.backend == "numpy"
    return monitor


def _pair(robot, tuned, backend="python", **options):
    threshold, observer_settings = tuned
    if threshold.fingerprint_ not in ("", robot.fingerprint):
        # Bounds fitted with another friction model: these tests compare paths on one monitor.
        threshold = copy.copy(threshold)
        threshold.fingerprint_ = ""
    reference = CollisionMonitor(robot, threshold, observer_settings, backend=backend, **options)
    assert reference.backend == backend
    return _numpy_monitor(robot, (threshold, observer_settings), **options), reference


def _samples(log, stop=None):
    for k in range(log.n_samples if stop is None else stop):
        yield log.t[k], log.q[k], log.tau_m[k]


def _assert_close(got, expected) -> None:
    """Residuals and bounds of two lists of verdicts within TOLERANCE."""
    for name in ("residual", "lower", "upper"):
        np.testing.assert_allclose(
            np.array([getattr(v, name) for v in got]),
            np.array([getattr(v, name) for v in expected]),
            rtol=0.0,
            atol=TOLERANCE,
            err_msg=name,
        )


def _run_both(mine, reference, samples):
    """Feed both streams; their verdicts agree. Returns the statuses and the events."""
    statuses, events, got_all, expected_all = [], [], [], []
    for sample in samples:
        expected, got = reference.step(*sample), mine.step(*sample)
        assert_same_verdict(got, expected)
        got_all.append(got)
        expected_all.append(expected)
        statuses.append(expected.status)
        events += [] if expected.event is None else [expected.event]
    _assert_close(got_all, expected_all)
    assert_same_event(mine.finish(), reference.finish())
    assert mine.latched == reference.latched
    return statuses, events


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("method", FAMILIES)
def test_numpy_stream_equals_reference(panda, method, backend) -> None:
    test, nominal, tuned = panda
    mine, reference = _pair(nominal, tuned[method], backend)
    statuses, events = _run_both(mine, reference, _samples(test))
    assert "collision" in statuses  # the run exercises the detector and the latch
    assert events or reference.finish() is None


@pytest.mark.parametrize(
    "friction",
    [
        CoulombViscous(c_pos=np.full(7, 0.3), c_neg=np.full(7, -0.2), fv=np.full(7, 0.5)),
        HystereticError(c=np.full(7, 0.2)),
        Stribeck(fc=np.full(7, 0.3), fs=0.5, vs=0.05, fv=0.4, delta=1.5),  # the model's own
    ],
    ids=lambda model: type(model).__name__,
)
def test_friction_models_agree(panda, friction) -> None:
    test, nominal, tuned = panda
    robot = nominal.with_standard_parameters(nominal.parameter_vector(), friction=friction)
    mine, reference = _pair(robot, tuned["hysteretic"])
    _run_both(mine, reference, _samples(test, 700))


def test_puma_armature_friction_filters_and_per_joint_gains() -> None:
    """6 joints, armature and Coulomb-viscous friction in the model; a Butterworth velocity
    filter (the cascade section by section) and one observer gain per joint."""
    scenario = load_scenario("puma560-thesis").with_duration(2.0)
    free = [scenario.run(seed=1, collisions=False).log]
    test = scenario.run(seed=3).log
    nominal = scenario.robots()[1]
    for observer_settings in (ObserverSettings(), ObserverSettings(filter="butterworth", order=3)):
        tuned = tune(free, nominal, "hysteretic", observer_settings, margin=0.05, folds=None)
        mine, reference = _pair(nominal, tuned)
        _run_both(mine, reference, _samples(test, 600))
    gains = np.linspace(15.0, 40.0, nominal.n_dof)
    mine, reference = _pair(nominal, tuned)
    for monitor in (mine, reference):  # per-joint gains: not a tuning option, set directly
        monitor._observer = MomentumObserver(nominal, monitor.dt, gains)
    mine._fused = NumpyStream(mine)  # rebuilt on the new observer
    mine._compiled = (*mine._fused.sample, mine._fused)
    _run_both(mine, reference, _samples(test, 600))


def test_constant_subset_and_per_joint_bin_filters(panda) -> None:
    """The constant bounds (±r̂ from the observer's product, L and U constant rows) with joints
    not monitored (bounds ∓∞); the velocity bins' filter of τ_fme with one gain per joint
    (the filter after the product instead of in it), on the Python path's verdicts."""
    test, nominal, tuned = panda
    free = [load_scenario("panda-gaz").with_duration(2.0).run(seed=1, collisions=False).log]
    constant = tune(free, nominal, "constant", margin=0.05, folds=None, joints=[1, 3, 4, 6])
    mine, reference = _pair(nominal, constant)
    assert mine._fused._constant and not mine._fused._bounds._whole
    statuses, _ = _run_both(mine, reference, _samples(test, 900))
    assert "collision" in statuses
    threshold, observer_settings = tuned["velocity"]
    threshold = copy.copy(threshold)
    gains = np.linspace(15.0, 40.0, nominal.n_dof)
    threshold.gain_ = gains  # per-joint gains: not a tuning option, set directly
    mine, reference = _pair(nominal, (threshold, observer_settings))
    for monitor in (mine, reference):
        monitor._observer = MomentumObserver(nominal, monitor.dt, gains)
    mine._fused = NumpyStream(mine)  # rebuilt on the new observer and threshold
    mine._compiled = (*mine._fused.sample, mine._fused)
    assert mine._fused._bin_gains is not None and mine._fused._gains is not None
    _run_both(mine, reference, _samples(test, 900))


def test_measured_velocity_and_joint_torques(panda) -> None:
    test, nominal, tuned = panda
    mine, reference = _pair(nominal, tuned["time-variant"])
    rng = np.random.default_rng(4)
    qd = test.qd_true + rng.normal(0.0, 1e-3, test.q.shape)
    got, expected = [], []
    for k in range(700):
        sample = (test.t[k], test.q[k], test.tau_m[k])
        got.append(mine.step(*sample, qd=qd[k]))
        expected.append(reference.step(*sample, qd=qd[k]))
        assert_same_verdict(got[-1], expected[-1])
    _assert_close(got, expected)
    lwr = load_scenario("lwr4-thesis").with_duration(2.0)
    run = lwr.run(seed=2).log
    robot = lwr.nominal("joint")
    joint = ObserverSettings(kind="joint")
    threshold = tune([lwr.run(seed=1, collisions=False).log], robot, "constant", joint, folds=None)
    mine, reference = _pair(robot, threshold)
    samples = [(run.t[k], run.q[k], run.tau_m[k], run.tau_j[k]) for k in range(run.n_samples)]
    _run_both(mine, reference, samples)


def test_faults_match_and_change_nothing(panda) -> None:
    test, nominal, tuned = panda
    mine, reference = _pair(nominal, tuned["time-variant"])
    clean = _numpy_monitor(nominal, tuned["time-variant"])
    k = 400
    q, tau = test.q[k], test.tau_m[k]
    q_far, jump, tau_big = q.copy(), q + 0.01, tau.copy()
    q_far[1], tau_big[4] = 3.0, 25.0
    last = test.t[k - 1]
    bad = [
        (np.nan, q, tau),
        (last, q, tau),  # repeated time stamp
        (last - 1.0, q, tau),  # back in time
        (last + 1e-12, q, tau),  # too early
        (last + 0.5, q, tau),  # a gap
        (test.t[k], np.full(7, np.nan), tau),
        (test.t[k], q[:6], tau),
        (test.t[k], q, "torque"),
        (test.t[k], q_far, tau),  # outside the position limits
        (test.t[k], q, tau_big),
        (test.t[k], q, tau + 1e308),
        (test.t[k], jump, tau),  # 10 rad/s in one millisecond: a velocity fault
    ]
    stream = mine._fused
    for i, sample in enumerate(_samples(test, k + 150)):
        if i == k:
            for t, q_bad, tau_bad in bad:
                before = stream._save()
                got, expected = mine.step(t, q_bad, tau_bad), reference.step(t, q_bad, tau_bad)
                assert got.status == expected.status == "fault", (t, got)
                assert got.message == expected.message and got.message
                # The gap rule's memory is the one thing a fault may set, as in Python.
                assert stream._flags.pending == reference._pending
                after = stream._save()
                before[2].pending = after[2].pending
                np.testing.assert_equal(_fields(after[2]), _fields(before[2]))
                committed = 0 if before[1] else 1
                assert after[1] == before[1]
                np.testing.assert_array_equal(after[0][committed], before[0][committed])
        expected = clean.step(*sample)
        got = mine.step(*sample)
        assert_same_verdict(got, reference.step(*sample))
        assert_goes_on(got, expected)  # as if the faults never came


def test_gap_resume_release_and_reset(panda) -> None:
    test, nominal, tuned = panda
    mine, reference = _pair(nominal, tuned["constant"], policy=StreamPolicy(settle=0.0035))
    regular = [(test.t[k], test.q[k], test.tau_m[k]) for k in range(300)]
    resumed = [(test.t[k], test.q[k], test.tau_m[k]) for k in range(810, 1400)]
    statuses, _ = _run_both(mine, reference, regular + resumed)
    assert statuses[300] == "fault" and statuses[301:305] == ["settling"] * 4
    mine, reference = _pair(nominal, tuned["constant"], policy=StreamPolicy(release=0.1))
    statuses, _ = _run_both(mine, reference, _samples(test))
    assert "collision" in statuses
    mine.reset()
    assert not mine.latched and mine.step(*regular[0]).status == "settling"


@pytest.mark.parametrize("method", ["constant", "velocity"])
@pytest.mark.parametrize("settle", [0.0, 0.0035])
def test_gap_resume_for_the_constant_and_bin_bounds(panda, method, settle) -> None:
    """A gap and a resume for the constant bounds (rows LC, UC) and the velocity bins (the
    filter of τ_fme restarts at τ_fme; with no settling window the second sample of a stream
    reads its block of a start); the Python path's verdicts."""
    test, nominal, tuned = panda
    mine, reference = _pair(nominal, tuned[method], policy=StreamPolicy(settle=settle))
    samples = [(test.t[k], test.q[k], test.tau_m[k]) for k in [*range(200), *range(810, 1100)]]
    statuses, _ = _run_both(mine, reference, samples)
    settling = statuses[201:].count("settling")  # after the gap, as at the start
    assert statuses[200] == "fault" and settling == statuses[:200].count("settling")
    assert settling == (0 if settle == 0.0 else 4) and set(statuses[210:]) <= {"ok", "collision"}


class _Exploding(Viscous):
    """A friction model of infinite torque beyond 1e-4 rad/s (the model's own function)."""

    def evaluate(self, qd):
        return np.where(np.abs(qd) > 1e-4, np.inf, 0.0)


def test_non_finite_observer_and_bounds_are_faults(panda) -> None:
    test, nominal, tuned = panda
    threshold, observer_settings = tuned["time-variant"]
    broken = copy.deepcopy(threshold)
    broken.alpha_ = broken.alpha_.copy()
    broken.alpha_[2] = np.nan
    mine, reference = _pair(nominal, (broken, observer_settings))
    statuses, _ = _run_both(mine, reference, _samples(test, 400))
    assert set(statuses) == {"settling", "fault"}
    # Friction that is infinite once a joint moves fast: the observer's output is not finite.
    robot = nominal.with_standard_parameters(
        nominal.parameter_vector(), friction=_Exploding(np.zeros(7))
    )
    mine, reference = _pair(robot, tuned["time-variant"])
    with np.errstate(invalid="ignore"):
        statuses, _ = _run_both(mine, reference, _samples(test, 600))
    assert "fault" in statuses and "settling" in statuses


def test_block_equals_step_by_step(panda) -> None:
    test, nominal, tuned = panda
    monitor = _numpy_monitor(nominal, tuned["hysteretic"])
    stream = monitor._fused
    n = 900
    t, q, tau = test.t[:n].copy(), test.q[:n].copy(), test.tau_m[:n].copy()
    q[500, 2], t[700] = np.nan, t[699] + 1e-9  # a value fault and a time fault
    for k in range(50):  # the live stream, which block leaves alone
        monitor.step(t[k], q[k], tau[k])
    live = stream._save()
    codes, series, events = stream.block(t, (q, np.empty((n, 0)), tau, tau), "hysteretic")
    after = stream._save()
    assert after[1] == live[1]  # the same committed buffer, the same contents and flags
    np.testing.assert_array_equal(after[0][0], live[0][0])
    np.testing.assert_array_equal(after[0][1], live[0][1])
    np.testing.assert_equal(_fields(after[2]), _fields(live[2]))
    fresh = NumpyStream(monitor)
    out = np.empty((3, 7))
    expected_events = []
    for k in range(n):
        status, joints, event = fresh.run(
            float(t[k]), (q[k], np.empty(0), tau[k], tau[k]), out, "h"
        )
        code = int(codes[k])
        if code & 15 >= NumpyStream.FAULT:
            assert stream.reason(code & 15) == status
            assert np.isnan(series[:6, k]).all()
            continue
        assert ("ok", "collision", "settling")[code & 15] == status
        assert joints == tuple(j + 1 for j in range(7) if code >> 5 >> j & 1)
        np.testing.assert_array_equal(series[:3, k], out)
        np.testing.assert_array_equal(series[3:, k], fresh.threshold_rows())
        expected_events += [] if event is None else [event]
    last = fresh.finish("h")
    expected_events += [] if last is None else [last]
    assert [(e.start, e.end, e.joints) for e in events] == [
        (e.start, e.end, e.joints) for e in expected_events
    ]
    assert {int(c) & 15 for c in codes} >= {2, NumpyStream.FAULT + 1, NumpyStream.FAULT + 4}
    # The batch monitor runs the stream's block: the same run as the Python path's arrays.
    reference = CollisionMonitor(nominal, *tuned["hysteretic"], backend="python")
    got, expected = monitor.process(test), reference.process(test)
    assert [(e.start, e.end, e.joints) for e in got.events] == [
        (e.start, e.end, e.joints) for e in expected.events
    ]
    np.testing.assert_allclose(got.signals.residual, expected.signals.residual, atol=TOLERANCE)


@pytest.mark.parametrize("scenario", ["panda-gaz", "puma560-thesis"])
def test_terms_equal_pinocchio(scenario) -> None:
    """p + g (p = M q̇, crba with the upper triangle mirrored), Cᵀq̇ and g of the stream's rows,
    and p as the difference of the first and third rows, on random states."""
    robot = load_scenario(scenario).robots()[1]
    model = robot.pinocchio_model
    free = [load_scenario(scenario).with_duration(0.6).run(seed=1, collisions=False).log]
    monitor = _numpy_monitor(robot, tune(free, robot, "constant", folds=None))
    stream = monitor._fused
    data, rng = model.createData(), np.random.default_rng(7)
    rows = np.zeros_like(stream._start)
    recursion = MomentumTerms(model, backend="numpy")
    for _ in range(20):
        q = rng.uniform(-np.pi, np.pi, model.nq)
        qd = rng.uniform(-3.0, 3.0, model.nv)
        stream._terms(q, qd, _views(rows))
        mass = pin.crba(model, data, q)
        mass = np.triu(mass) + np.triu(mass, 1).T
        p = mass @ qd
        coriolis = pin.computeCoriolisMatrix(model, data, q, qd).T @ qd
        gravity = pin.computeGeneralizedGravity(model, data, q)
        for got, expected in (
            (rows[0], p + gravity), (rows[0] - rows[2], p), (rows[1], coriolis), (rows[2], gravity)
        ):  # fmt: skip
            np.testing.assert_allclose(
                got, expected, rtol=1e-10, atol=1e-10 * np.abs(expected).max()
            )
        p_r, c_r, g_r = recursion.terms(q[None], qd[None])
        np.testing.assert_allclose(
            [rows[0] - rows[2], rows[1], rows[2]], np.stack([p_r[0], c_r[0], g_r[0]]),
            rtol=1e-10, atol=1e-9,
        )  # fmt: skip


def _fields(flags) -> list[Any]:
    """The stream's scalars (NaN compares equal in ``np.testing.assert_equal``)."""
    return [getattr(flags, name) for name in flags.__slots__]


def _views(block):
    from sensorless.monitor._numpy_parts import block_views

    return block_views(block)


def test_unsupported_monitors(panda) -> None:
    test, nominal, tuned = panda
    threshold, observer_settings = tuned["constant"]
    model = tune([test.slice(stop=1.5)], nominal, "model", margin=0.05, folds=None)
    adapted = CollisionMonitor(
        nominal, threshold, observer_settings, backend="python", adaptation=Adaptation()
    )
    assert "drift adaptation" in unsupported(adapted)
    # The model-based family watches the acceleration-based estimate.
    assert "'acceleration' observer" in unsupported(CollisionMonitor(nominal, *model))


_NO_NUMBA = """
import pickle, sys
from importlib.abc import MetaPathFinder

class NoNumba(MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if name == "numba" or name.startswith("numba."):
            raise ImportError("numba is blocked")
        return None

sys.meta_path.insert(0, NoNumba())
from sensorless.monitor import CollisionMonitor
from sensorless.monitor._numpy_stream import NumpyStream
robot, threshold, settings, samples, expected = pickle.load(open(sys.argv[1], "rb"))
monitor = CollisionMonitor(robot, threshold, settings, backend="python")
monitor._fused = NumpyStream(monitor)
monitor.reset()
got = [monitor.step(*sample).status for sample in samples]
assert got == expected, (got, expected)
assert not any(name == "numba" or name.startswith("numba.") for name in sys.modules)
print("ok", got.count("ok") + got.count("collision"))
"""


def test_runs_without_numba(panda, tmp_path) -> None:
    test, nominal, tuned = panda
    threshold, observer_settings = tuned["time-variant"]
    samples = [(float(t), q, tau) for t, q, tau in _samples(test, 320)]
    reference = CollisionMonitor(nominal, threshold, observer_settings, backend="python")
    expected = [reference.step(*sample).status for sample in samples]
    path = tmp_path / "case.pickle"
    path.write_bytes(pickle.dumps((nominal, threshold, observer_settings, samples, expected)))
    script = tmp_path / "no_numba.py"
    script.write_text(textwrap.dedent(_NO_NUMBA))
    result = subprocess.run(
        [sys.executable, str(script), str(path)], capture_output=True, text=True, check=False
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.startswith("ok ")


_floats = st.floats(allow_nan=True, allow_infinity=True, allow_subnormal=True, width=64)


@st.composite
def _garbage(draw: Any, last: float, q: np.ndarray, tau: np.ndarray) -> tuple[Any, Any, Any]:
    """A sample the stream must refuse: a bad time, or a value no joint can have."""
    n = q.shape[0]
    impossible = draw(st.sampled_from([1e308, -1e308, np.nan, np.inf, -np.inf, 1e7]))
    values = draw(st.lists(_floats, min_size=n, max_size=n))
    bad = np.where(np.arange(n) == draw(st.integers(0, n - 1)), impossible, values)
    kind = draw(st.sampled_from(["time", "q", "tau", "shape", "type"]))
    if kind == "time":
        offset = draw(st.sampled_from([0.0, -1e-3, 1e-12, 4e-4, 0.5, -1000.0, np.nan, np.inf]))
        return last + offset, q, tau
    t = draw(st.one_of(st.just(last + 1e-3), _floats))
    if kind == "q":
        return t, bad, tau
    if kind == "tau":
        return t, q, bad
    if kind == "shape":
        return t, np.resize(q, draw(st.sampled_from([(0,), (n + 1,), (2, n)]))), tau
    return t, draw(st.sampled_from(["q", None, object(), [1.0, "x"]])), tau


def test_sample_entry_point(panda) -> None:
    """``sample`` (the compiled stream's entry of the common sample): the codes of ``_step``
    for float64 samples of the right shape and a finite time, unpickled ones included;
    UNJUDGED, nothing changed, else."""
    test, nominal, tuned = panda
    entry = _numpy_monitor(nominal, tuned["time-variant"])._fused
    reference = _numpy_monitor(nominal, tuned["time-variant"])._fused
    function, model, buffers = entry.sample
    out, expected_out = np.empty((3, 7)), np.empty((3, 7))
    for k in range(400):
        t, q, tau = float(test.t[k]), test.q[k], test.tau_m[k]
        if k == 300:
            for bad in ((t, q.tolist(), tau), (t, q[:6], tau), (t, q.astype(np.float32), tau),
                        (math.nan, q, tau), (t, q, np.repeat(tau, 2)[::2])):  # fmt: skip
                before = entry._save()
                assert function(*bad, bad[2], model, buffers, out) == NumpyStream.UNJUDGED
                np.testing.assert_equal(_fields(entry._save()[2]), _fields(before[2]))
        if k % 2:  # an unpickled array's dtype equals float64 without being the same object
            q, tau = pickle.loads(pickle.dumps(q)), pickle.loads(pickle.dumps(tau))
        code = function(t, q, tau, tau, model, buffers, out)
        assert code != NumpyStream.UNJUDGED
        assert code == reference._step(t, q, np.empty(0), tau, tau, expected_out)
        np.testing.assert_array_equal(out, expected_out)


@pytest.mark.filterwarnings("ignore:overflow encountered:RuntimeWarning")  # q of 1e308 rad
@settings(
    max_examples=20,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
@given(data=st.data())
def test_garbage_never_raises_nor_poisons(panda, data) -> None:
    test, nominal, tuned = panda
    method = data.draw(st.sampled_from(FAMILIES), label="family")
    clean = _numpy_monitor(nominal, tuned[method])
    fuzzed = _numpy_monitor(nominal, tuned[method])
    start = int(np.ceil(clean.settle / 1e-3)) + 5
    inserts = data.draw(st.lists(st.integers(start, start + 59), max_size=12), label="positions")
    for k in range(start + 60):
        sample = (test.t[k], test.q[k], test.tau_m[k])
        for _ in range(inserts.count(k)):
            bad = data.draw(_garbage(test.t[k - 1], test.q[k], test.tau_m[k]), label="bad")
            verdict = fuzzed.step(*bad)
            assert verdict.status == "fault" and verdict.message, (bad, verdict)
        expected, got = clean.step(*sample), fuzzed.step(*sample)
        assert_goes_on(got, expected, "lower")
