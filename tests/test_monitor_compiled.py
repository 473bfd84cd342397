"""The compiled stream (numba) against the Python stream it fuses: same verdicts, same faults."""

from __future__ import annotations

import copy

import numpy as np
import pytest

from sensorless.exceptions import InputValueError, UnknownNameError
from sensorless.friction import (
    Coulomb,
    CoulombViscous,
    HystereticError,
    LuGre,
    Sigmoid,
    Stribeck,
    Viscous,
)
from sensorless.monitor import (
    Adaptation,
    CollisionMonitor,
    ObserverSettings,
    StreamPolicy,
    tune,
)
from sensorless.monitor import stream as stream_module
from sensorless.robots.recursion import numba_available
from sensorless.simulation.scenario import load_scenario

pytestmark = pytest.mark.skipif(not numba_available(), reason="numba is not installed")

COMPILED = ("constant", "time-variant", "hysteretic", "velocity")
TOLERANCE = 1e-9  # N m, residuals and bounds
# Beyond the margin: a subset of monitored joints (the others' bounds are ±inf) and the
# widening of velocity bounds outside the visited bins (panda joints 3, 5 and 7 leave them).
OPTIONS = {
    "constant": {},
    "time-variant": {},
    "hysteretic": {"joints": [1, 2, 4]},
    "velocity": {"extrapolation_margin": 0.1},
}


@pytest.fixture(scope="module")
def scenarios():
    """Per scenario: test log, nominal robot and the four tuned families."""
    out = {}
    for name in ("panda-gaz", "puma560-thesis"):
        scenario = load_scenario(name).with_duration(4.0)
        free = [scenario.run(seed=s, collisions=False).log for s in (1, 2)]
        test = scenario.run(seed=3).log
        nominal = scenario.robots()[1]
        tuned = {m: tune(free, nominal, m, margin=0.05, folds=None, **OPTIONS[m]) for m in COMPILED}
        out[name] = (test, nominal, tuned)
    return out


@pytest.fixture(scope="module")
def joint_torques():
    """The joint-torque observer (r̂_s) on the flexible-joint LWR: test log, robot, tuning."""
    scenario = load_scenario("lwr4-thesis").with_duration(4.0)
    free = [scenario.run(seed=1, collisions=False).log]
    test = scenario.run(seed=2).log
    robot = scenario.nominal("joint")
    tuned = tune(
        free, robot, "time-variant", ObserverSettings(kind="joint"), margin=0.05, folds=None
    )
    return test, robot, tuned


def _pair(robot, tuned, **options):
    threshold, settings = tuned
    if threshold.fingerprint_ not in ("", robot.fingerprint):
        # Bounds fitted with another friction model: these tests compare the two backends
        # on one monitor, not detection; without the fingerprint, the name decides.
        threshold = copy.copy(threshold)
        threshold.fingerprint_ = ""
    compiled = CollisionMonitor(robot, threshold, settings, backend="numba", **options)
    python = CollisionMonitor(robot, threshold, settings, backend="python", **options)
    assert (compiled.backend, python.backend) == ("numba", "python")
    return compiled, python


def _samples(log, stop=None, joint=False):
    for k in range(log.n_samples if stop is None else stop):
        yield (log.t[k], log.q[k], log.tau_m[k], log.tau_j[k] if joint else None)


def assert_same(got, expected) -> None:
    """Verdicts of two backends: equal statuses, joints, events and messages; rows within
    TOLERANCE (also used by ``test_monitor_numpy_stream``)."""
    assert_same_verdict(got, expected)
    for name in ("residual", "lower", "upper"):
        np.testing.assert_allclose(
            getattr(got, name), getattr(expected, name), rtol=0.0, atol=TOLERANCE, err_msg=name
        )


def assert_same_verdict(got, expected) -> None:
    """Equal statuses, times, joints, messages and events (peaks within TOLERANCE)."""
    assert (got.status, got.t, got.joints, got.message) == (
        expected.status,
        expected.t,
        expected.joints,
        expected.message,
    )
    assert_same_event(got.event, expected.event)


def assert_goes_on(got, expected, bound="upper") -> None:
    """A stream that saw faults judges a good sample as one that never saw them: same
    status, joints, event, residual and ``bound`` (also used by the numpy-stream and fuzz
    tests)."""
    assert (got.status, got.joints, got.event) == (
        expected.status,
        expected.joints,
        expected.event,
    )
    np.testing.assert_array_equal(got.residual, expected.residual)
    np.testing.assert_array_equal(getattr(got, bound), getattr(expected, bound))


def assert_same_event(got, expected) -> None:
    if expected is None:
        assert got is None
        return
    assert (got.start, got.end, got.joints, got.method) == (
        expected.start,
        expected.end,
        expected.joints,
        expected.method,
    )
    assert got.peak == pytest.approx(expected.peak, rel=0.0, abs=TOLERANCE)
    assert got.peak_residual == pytest.approx(expected.peak_residual, rel=0.0, abs=TOLERANCE)


def _key(events):
    return [(e.start, e.end, e.joints) for e in events]


def _run_both(compiled, python, samples):
    """Feed both backends; their verdicts agree. Returns the statuses and fault messages."""
    statuses, messages = [], set()
    for sample in samples:
        expected = python.step(*sample)
        assert_same(compiled.step(*sample), expected)
        statuses.append(expected.status)
        messages.add(expected.message)
    assert_same_event(compiled.finish(), python.finish())
    assert compiled.latched == python.latched
    return statuses, messages


@pytest.mark.parametrize("scenario", ["panda-gaz", "puma560-thesis"])
@pytest.mark.parametrize("method", COMPILED)
def test_compiled_stream_equals_python(scenarios, scenario, method) -> None:
    test, nominal, tuned = scenarios[scenario]
    compiled, python = _pair(nominal, tuned[method])
    statuses, _ = _run_both(compiled, python, _samples(test))
    assert {"settling", "ok"} <= set(statuses)
    # Batch = stream on the compiled path too.
    events = []
    compiled.reset()
    for sample in _samples(test):
        verdict = compiled.step(*sample)
        events += [verdict.event] if verdict.event is not None else []
    last = compiled.finish()
    events += [last] if last is not None else []
    batch = compiled.run(test)[1]
    assert _key(events) == _key(batch)


def test_compiled_stream_of_joint_torques_equals_python(joint_torques) -> None:
    test, robot, tuned = joint_torques
    compiled, python = _pair(robot, tuned)
    statuses, _ = _run_both(compiled, python, _samples(test, joint=True))
    assert "collision" in statuses
    # Without tau_j the joint-torque observer refuses the sample, as the Python path does.
    for monitor in (compiled, python):
        assert monitor.step(10.0, test.q[0], test.tau_m[0]).message == (
            "the joint-torque observer needs tau_j"
        )


def test_chunked_equals_whole(scenarios) -> None:
    test, nominal, tuned = scenarios["panda-gaz"]
    whole, _ = _pair(nominal, tuned["time-variant"])
    chunked, _ = _pair(nominal, tuned["time-variant"])
    expected = [whole.step(*sample) for sample in _samples(test)]
    got = []
    for part in (test.slice(stop=1.7), test.slice(start=1.7)):
        got += [chunked.step(*sample) for sample in _samples(part)]
    assert len(got) == len(expected)
    for a, b in zip(got, expected, strict=True):
        assert (a.status, a.joints, a.event) == (b.status, b.joints, b.event)
        np.testing.assert_array_equal(a.residual, b.residual)
        np.testing.assert_array_equal(a.lower, b.lower)


FORMS = {
    "read-only rows": lambda t, q, tau: (t, q, tau),
    "writable copies": lambda t, q, tau: (float(t), q.copy(), tau.copy()),
    "lists": lambda t, q, tau: (int(t) if t == int(t) else t, q.tolist(), tau.tolist()),
    "strided views": lambda t, q, tau: (t, np.repeat(q, 2)[::2], np.repeat(tau, 2)[::2]),
    "0-d time, Fortran rows": lambda t, q, tau: (np.array(t), q[:, None].T[0], tau[None].T[:, 0]),
}


@pytest.mark.parametrize("form", list(FORMS))
def test_every_form_of_a_sample_gives_the_same_stream(scenarios, form) -> None:
    """The compiled stream's common sample (the motor torques' dispatcher entry) and the
    conversion of other forms give identical verdicts; arrays of float64 take the entry."""
    test, nominal, tuned = scenarios["panda-gaz"]
    plain, python = _pair(nominal, tuned["time-variant"])
    given, _ = _pair(nominal, tuned["time-variant"])
    function, model, buffers, _ = given._compiled
    for q, tau in ((test.q[0], test.tau_m[0]), (test.q[0].copy(), test.tau_m[0].copy())):
        assert not q.flags.writeable or tau.flags.writeable  # read-only rows, then writable
        code = function(0.0, q, tau, tau, model, buffers, np.empty((3, 7)))
        assert code & 15 != stream_module.UNJUDGED
        given.reset()
    statuses = []
    for t, q, tau, _ in _samples(test, stop=1500):
        expected = plain.step(float(t), q.copy(), tau.copy())
        assert_same(expected, python.step(t, q, tau))
        got = given.step(*FORMS[form](t, q, tau))
        assert (got.status, got.t, got.joints, got.event, got.message) == (
            expected.status, expected.t, expected.joints, expected.event, expected.message,
        )  # fmt: skip
        for name in ("residual", "lower", "upper"):
            np.testing.assert_array_equal(getattr(got, name), getattr(expected, name))
        statuses.append(got.status)
    assert {"settling", "ok"} <= set(statuses)


@pytest.mark.parametrize("method", COMPILED)
def test_a_fault_changes_nothing(scenarios, method) -> None:
    test, nominal, tuned = scenarios["panda-gaz"]
    compiled, python = _pair(nominal, tuned[method])
    clean, _ = _pair(nominal, tuned[method])
    k = int(np.searchsorted(test.t, 0.3))  # past the settling window (0.25 s)
    q, tau = test.q[k], test.tau_m[k]
    q_far, jump, tau_big = q.copy(), q + 0.01, tau.copy()
    q_far[1], tau_big[4] = 3.0, 25.0
    last = test.t[k - 1]
    bad = [
        (np.nan, q, tau),
        (last, q, tau),  # repeated time stamp
        (last - 1.0, q, tau),  # back in time
        (last - 1.0, q[:3], tau),  # back in time and the wrong shape: the time is said first
        (last + 1e-12, q, tau),  # too early
        (last + 0.5, q, tau),  # a gap
        (test.t[k], np.full(7, np.nan), tau),
        (test.t[k], q[:6], tau),
        (test.t[k], q, "torque"),
        (test.t[k], q_far, tau),
        (test.t[k], q, tau_big),
        (test.t[k], q, tau + 1e308),
        (test.t[k], np.rad2deg(q), tau),
        (test.t[k], jump, tau),  # 10 rad/s in one millisecond
    ]
    from sensorless.monitor._compiled import PENDING  # needs numba

    for i, sample in enumerate(_samples(test, k + 200)):
        if i == k:
            for t, q_bad, tau_bad in bad:
                fused = compiled._fused  # committed rows: flags[0], state[0]; the rest is scratch
                before = fused._flags[0].copy(), fused._state[0].copy()
                got, reference = compiled.step(t, q_bad, tau_bad), python.step(t, q_bad, tau_bad)
                assert got.status == reference.status == "fault", (t, got)
                assert got.message == reference.message and got.message
                # The gap rule's memory is the one number a fault may set, as in Python.
                assert fused._flags[0, PENDING] == python._pending
                before[0][PENDING] = python._pending
                np.testing.assert_array_equal(fused._flags[0], before[0])
                np.testing.assert_array_equal(fused._state[0], before[1])
        expected = clean.step(*sample)
        got = compiled.step(*sample)
        assert_same(got, python.step(*sample))
        assert_goes_on(got, expected)  # as if the faults never came


def test_gaps_restarts_and_latching_agree(scenarios) -> None:
    test, nominal, tuned = scenarios["panda-gaz"]
    gap, python = _pair(nominal, tuned["constant"], policy=StreamPolicy(settle=0.0035))
    regular = [(test.t[k], test.q[k], test.tau_m[k]) for k in range(300)]
    resumed = [(test.t[k], test.q[k], test.tau_m[k]) for k in range(810, 1400)]
    statuses, _ = _run_both(gap, python, regular + resumed)
    assert statuses[300] == "fault" and statuses[301:305] == ["settling"] * 4
    released, python = _pair(nominal, tuned["constant"], policy=StreamPolicy(release=0.1))
    statuses, _ = _run_both(released, python, _samples(test))
    assert "collision" in statuses
    latched, python = _pair(nominal, tuned["constant"])
    statuses, _ = _run_both(latched, python, _samples(test))
    assert statuses[-1] == "collision" and latched.latched
    latched.reset()
    assert not latched.latched
    assert latched.step(*regular[0]).status == "settling"


@pytest.mark.filterwarnings("ignore:overflow encountered:RuntimeWarning")  # the Python path's
def test_non_finite_observer_and_bounds_are_faults(scenarios) -> None:
    test, nominal, tuned = scenarios["panda-gaz"]
    threshold, settings = tuned["time-variant"]
    # Friction that overflows the observer's trapezoid once a joint moves: its output is inf.
    huge = Coulomb(c_pos=np.full(7, 1e308), c_neg=np.full(7, -1e308))
    robot = nominal.with_standard_parameters(nominal.parameter_vector(), friction=huge)
    compiled, python = _pair(robot, (threshold, settings))
    _, messages = _run_both(compiled, python, _samples(test, 600))
    assert "the observer's output is not finite for this sample" in messages
    # A threshold whose bounds are NaN on one joint: every judged sample is a fault.
    broken = copy.deepcopy(threshold)
    broken.alpha_ = broken.alpha_.copy()
    broken.alpha_[2] = np.nan
    compiled, python = _pair(nominal, (broken, settings))
    statuses, messages = _run_both(compiled, python, _samples(test, 400))
    assert set(statuses) == {"settling", "fault"}
    assert messages == {"", "the threshold's bounds are not finite for this sample"}


@pytest.mark.parametrize(
    "friction",
    [
        Coulomb(c_pos=np.full(7, 0.3), c_neg=np.full(7, -0.2)),
        Viscous(fv=np.linspace(0.1, 0.7, 7)),
        CoulombViscous(c_pos=np.full(7, 0.3), c_neg=np.full(7, -0.2), fv=np.full(7, 0.5)),
        Stribeck(fc=np.full(7, 0.3), fs=0.5, vs=0.05, fv=0.4, delta=1.5),
        Sigmoid(phi1=np.full(7, 0.5), phi2=5.0, phi3=0.04),
        HystereticError(c=np.full(7, 0.2)),
        LuGre(sigma0=np.full(7, 1e4), sigma1=10.0, sigma2=0.4, fc=0.3, fs=0.5, vs=0.05),
    ],
    ids=lambda model: type(model).__name__,
)
def test_every_friction_model_agrees(scenarios, friction) -> None:
    test, nominal, tuned = scenarios["panda-gaz"]
    robot = nominal.with_standard_parameters(nominal.parameter_vector(), friction=friction)
    compiled, python = _pair(robot, tuned["time-variant"])
    _run_both(compiled, python, _samples(test, 1200))


def test_backend_option(scenarios, monkeypatch) -> None:
    test, nominal, tuned = scenarios["panda-gaz"]
    threshold, settings = tuned["constant"]
    assert CollisionMonitor(nominal, threshold, settings).backend == "numba"
    model, model_settings = tune([test.slice(stop=2.0)], nominal, "model", margin=0.05, folds=None)
    assert CollisionMonitor(nominal, model, model_settings).backend == "python"
    with pytest.raises(InputValueError, match="backend 'numba' cannot run this monitor: the "):
        CollisionMonitor(nominal, model, model_settings, backend="numba")
    with pytest.raises(UnknownNameError, match="unknown backend 'fortran'"):
        CollisionMonitor(nominal, threshold, settings, backend="fortran")
    with pytest.raises(InputValueError, match="backend 'numpy' cannot run this monitor: the "):
        CollisionMonitor(nominal, model, model_settings, backend="numpy")
    # Without numba, "auto" is the numpy stream where it runs, else the Python path,
    # and "numba" says what is missing.
    monkeypatch.setattr(stream_module, "_fused", None)
    assert CollisionMonitor(nominal, threshold, settings).backend == "numpy"
    assert CollisionMonitor(nominal, model, model_settings).backend == "python"
    with pytest.raises(InputValueError, match=r"numba is not installed \(pip install sensorless"):
        CollisionMonitor(nominal, threshold, settings, backend="numba")


def _with_bad_stretch(log, rng):
    """``log`` with measured velocity (the truth plus noise), 50 NaN rows and a limit breach."""
    frame = log.to_pandas()
    n = log.n_dof
    measured = log.qd_true + rng.normal(0.0, 1e-3, log.qd_true.shape)
    for j in range(n):
        frame[f"qd_{j + 1}"] = measured[:, j]
    k = int(np.searchsorted(log.t, 1.5))
    frame.loc[k : k + 49, "q_3"] = np.nan
    frame.loc[k + 700, "tau_m_2"] = 1e6  # beyond the torque limit: one refused sample
    return type(log).from_pandas(frame, allow_missing=True)


def _assert_same_run(got, expected) -> None:
    """Two MonitorRuns of one log: same faults, settling, events; series within TOLERANCE."""
    assert got.faults == expected.faults
    np.testing.assert_array_equal(got.settling, expected.settling)
    assert _key(got.events) == _key(expected.events)
    for a, b in zip(got.events, expected.events, strict=True):
        assert_same_event(a, b)
    for name in ("residual", "model_torque", "friction", "sign", "velocity"):
        np.testing.assert_allclose(
            getattr(got.signals, name),
            getattr(expected.signals, name),
            rtol=0.0,
            atol=TOLERANCE,
            err_msg=name,
        )
    assert got.signals.metadata["observer"] == expected.signals.metadata["observer"]


@pytest.mark.parametrize("scenario", ["panda-gaz", "puma560-thesis"])
@pytest.mark.parametrize("method", COMPILED)
def test_compiled_batch_equals_python_batch(scenarios, scenario, method) -> None:
    """The kernel over a whole log (``fused_block``) = the Python path's array computation."""
    test, nominal, tuned = scenarios[scenario]
    compiled, python = _pair(nominal, tuned[method])
    for log in (test, _with_bad_stretch(test, np.random.default_rng(4))):
        got, expected = compiled.process(log), python.process(log)
        _assert_same_run(got, expected)
    # (puma560-thesis then leaves the position limits of joint 4 for 0.37 s)
    assert [f.n_samples for f in got.faults[:2]] == [50, 1]
    assert got.faults[1].reason.startswith("tau_m of joint 2 is 1e+06 N m")
    assert got.signals.metadata["observer"]["velocity"] == "measured"
    # The batch leaves the live stream alone.
    compiled.step(*next(_samples(test)))
    compiled.process(test)
    assert compiled.step(*list(_samples(test, 2))[1]).status == "settling"


def test_compiled_batch_of_joint_torques_equals_python(joint_torques) -> None:
    test, robot, tuned = joint_torques
    compiled, python = _pair(robot, tuned)
    _assert_same_run(compiled.process(test), python.process(test))


@pytest.mark.parametrize("backend", ["python", "numba"])
def test_measured_velocity_in_the_stream_equals_the_batch(scenarios, backend) -> None:
    """``step(..., qd=)`` = ``process`` of a log with ``qd`` columns, sample by sample."""
    test, nominal, tuned = scenarios["panda-gaz"]
    threshold, settings = tuned["velocity"]
    log = _with_bad_stretch(test, np.random.default_rng(5))
    monitor = CollisionMonitor(nominal, threshold, settings, backend=backend)
    batch = monitor.process(log)
    residual = np.full((log.n_samples, log.n_dof), np.nan)
    events, statuses = [], []
    for k in range(log.n_samples):
        verdict = monitor.step(log.t[k], log.q[k], log.tau_m[k], qd=log.qd[k])
        statuses.append(verdict.status)
        if verdict.status != "fault":
            residual[k] = verdict.residual
        events += [verdict.event] if verdict.event is not None else []
    last = monitor.finish()
    events += [last] if last is not None else []
    np.testing.assert_allclose(residual, batch.signals.residual, rtol=0.0, atol=TOLERANCE)
    assert statuses.count("fault") == sum(f.n_samples for f in batch.faults) == 51
    assert _key(events) == _key(batch.events)
    # The measured velocity is what the observer used: it differs from the estimate's run.
    estimated = monitor.process(test).signals.residual
    assert np.nanmax(np.abs(estimated - batch.signals.residual)) > 1e-3
    # A bad measured velocity is a fault that changes nothing.
    monitor.reset()
    for k in range(400):
        monitor.step(log.t[k], log.q[k], log.tau_m[k], qd=log.qd[k])
    before = monitor.step(log.t[400], log.q[400], log.tau_m[400], qd=log.qd[400])
    for bad in (log.qd[401][:3], np.full(7, np.inf), log.qd[401] + 100.0, "fast"):
        verdict = monitor.step(log.t[401], log.q[401], log.tau_m[401], qd=bad)
        assert verdict.status == "fault" and "qd" in verdict.message
    assert before.status in ("ok", "collision")


def _drifted(log, rate, joint=2):
    """``log`` with a torque offset growing at ``rate`` [N m/s] on ``joint`` (1-based)."""
    frame = log.to_pandas()
    frame[f"tau_m_{joint}"] += rate * (log.t - log.t[0])
    return type(log).from_pandas(frame)


@pytest.mark.parametrize(
    "adaptation",
    [
        Adaptation(rate_limit=0.5, max_correction=10.0, guard=0.5),
        Adaptation(rate_limit=0.5, max_correction=10.0, guard=0.5, max_model_torque=50.0),
    ],
    ids=["friction", "with-model-torque"],
)
def test_drift_adaptation_compiled_equals_python(scenarios, adaptation) -> None:
    """The adapter inside the compiled step: the Python path's verdicts, faults and restarts."""
    test, nominal, tuned = scenarios["panda-gaz"]
    log = _drifted(test, 0.5)
    compiled, python = _pair(nominal, tuned["constant"], adaptation=adaptation)
    plain, _ = _pair(nominal, tuned["constant"])
    assert compiled.backend == "numba"
    k_bad, k_gap = int(np.searchsorted(log.t, 1.5)), int(np.searchsorted(log.t, 2.5))
    samples = list(_samples(log))
    bad = [
        (log.t[k_bad], q, log.tau_m[k_bad], None) for q in (np.full(7, np.nan), log.q[k_bad][:3])
    ]
    # Faults between good samples, then a gap the stream restarts after (learning kept).
    stream = samples[:k_bad] + bad + samples[k_bad:k_gap] + samples[k_gap + 200 :]
    statuses, _ = _run_both(compiled, python, stream)
    assert statuses.count("fault") >= 3 and "ok" in statuses
    # The correction acted: the residual of joint 2 differs from the plain monitor's.
    last = samples[k_gap - 1]
    plain.reset()
    for sample in samples[:k_gap]:
        reference = plain.step(*sample)
    compiled.reset()
    for sample in samples[:k_gap]:
        corrected = compiled.step(*sample)
    assert last[0] == corrected.t == reference.t
    assert abs(corrected.residual[1] - reference.residual[1]) > 0.01
    # Batch = the Python batch (its stepwise path).
    _assert_same_run(compiled.process(log), python.process(log))
