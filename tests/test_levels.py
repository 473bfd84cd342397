"""Two reaction levels (issue 12, item 2): phased bands, contact/collision events, monitor, CLI.

Closed forms: ramps of slope s cross a band ±β at t0 + β/s; a constant
acceleration a0 through the phase's first-order smoothing gives
q̈̂ = a0 (1 − aⁿ) after n samples and decays as aᵐ after it, so the phase
switches at samples found from logarithms.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from sensorless.cli import app
from sensorless.detection import LevelledDetector, LevelledEvent
from sensorless.exceptions import (
    DimensionError,
    FileFormatError,
    InputTypeError,
    InputValueError,
    NotFittedError,
)
from sensorless.io import write_log
from sensorless.monitor import CollisionMonitor, LevelledMonitor, save_tuned, tune, tune_levels
from sensorless.report import levels_section, write_report
from sensorless.robots.recursion import numba_available
from sensorless.signals import ObserverSignals
from sensorless.simulation.scenario import load_scenario
from sensorless.thresholds import (
    ConstantThreshold,
    PhasedThreshold,
    TimeVariantThreshold,
    VelocityThreshold,
    load_threshold,
)

DT = 1e-3


def _signals(residual: np.ndarray, velocity: np.ndarray | None = None, **series) -> ObserverSignals:
    n = residual.shape[0]
    zero = np.zeros_like(residual)
    return ObserverSignals(
        np.arange(n) * DT,
        residual,
        series.get("model_torque", zero),
        series.get("friction", zero),
        series.get("sign", zero),
        zero if velocity is None else velocity,
        gain=20.0,
        robot="synthetic",
    )


def _quiet(n_dof: int = 1) -> ObserverSignals:
    """A fit run whose largest |r| is 0.1 N m on every joint."""
    return _signals(0.1 * np.cos(np.pi * np.arange(20))[:, None] * np.ones(n_dof))


def _first_after(t: float) -> int:
    """Index of the first sample strictly after time t [s] (t not on the grid)."""
    return math.floor(t / DT) + 1


def _last_before(t: float) -> int:
    return math.ceil(t / DT) - 1


# ----------------------------------------------------------------------------- levels


def test_ramps_have_the_level_of_the_bands_they_cross() -> None:
    contact = ConstantThreshold(margin=0.4).fit(_quiet())
    collision = ConstantThreshold(margin=0.9).fit(_quiet())
    b_c, b_x = float(contact.beta_[0]), float(collision.beta_[0])
    slope = 7.3  # N m/s
    ramps = {"contact": (0.1, 0.11), "collision": (0.5, 0.2)}  # start, rise time [s]
    t = np.arange(1000) * DT
    r = np.zeros_like(t)
    for t0, rise in ramps.values():
        up = (t >= t0) & (t <= t0 + rise)
        down = (t > t0 + rise) & (t <= t0 + 2 * rise)
        r[up] = slope * (t[up] - t0)
        r[down] = slope * (t0 + 2 * rise - t[down])
    events = LevelledDetector(contact, collision).detect(_signals(r[:, None]))
    assert [e.level for e in events] == ["contact", "collision"]
    for event, (t0, rise) in zip(events, ramps.values(), strict=True):
        assert event.start == pytest.approx(_first_after(t0 + b_c / slope) * DT)
        assert event.end == pytest.approx(_last_before(t0 + 2 * rise - b_c / slope) * DT)
        assert event.event.peak == pytest.approx(slope * rise - b_c)
    hit = events[1].collisions
    t0, rise = ramps["collision"]
    assert len(hit) == 1
    assert hit[0].start == pytest.approx(_first_after(t0 + b_x / slope) * DT)
    assert hit[0].end == pytest.approx(_last_before(t0 + 2 * rise - b_x / slope) * DT)
    assert hit[0].peak == pytest.approx(slope * rise - b_x)
    assert math.isnan(events[0].collision_start)


def test_a_crossing_contact_band_is_clipped_and_marked() -> None:
    # A time-variant contact band 0.5 h ± 0.1 and a constant collision band ±1.02: where
    # h = 2 the contact band [0.9, 1.1] reaches beyond the collision band.
    n = 400
    h = np.where((np.arange(n) >= 100) & (np.arange(n) < 200), 2.0, 0.0)[:, None]
    alternating = 0.1 * np.cos(np.pi * np.arange(n))[:, None]
    contact = TimeVariantThreshold().fit(_signals(0.5 * h + alternating, model_torque=h))
    collision = ConstantThreshold(margin=0.92).fit(_quiet())
    r = 0.5 * h
    r[150:160] = 1.06  # beyond the collision band, inside the contact band as fitted
    run = _signals(r, model_torque=h)
    result = LevelledDetector(contact, collision).run(run)
    lower, upper = contact.bounds(run)
    beta = collision.beta_[0]
    expected = (upper[:, 0] > beta) | (lower[:, 0] < -beta)
    np.testing.assert_array_equal(result.crossed[:, 0], expected)
    np.testing.assert_array_equal(np.flatnonzero(expected), np.arange(100, 200))
    assert (r[150:160, 0] < upper[150:160, 0]).all()  # unclipped, no contact event at all
    assert [e.level for e in result.events] == ["collision"]
    assert (result.events[0].start, result.events[0].end) == pytest.approx((0.150, 0.159))
    np.testing.assert_array_less(result.contact.upper[:, 0], beta + 1e-12)


def test_levels_batch_equals_stream() -> None:
    rng = np.random.default_rng(5)
    n, n_dof = 1500, 2
    t = np.arange(n) * DT
    velocity = np.column_stack([np.sin(3 * t), np.cos(2 * t)])
    friction = 0.3 * np.tanh(velocity / 0.05)
    h = 3 * np.column_stack([np.cos(5 * t), np.sin(4 * t)])
    fit = _signals(
        0.05 * h + 0.2 * friction + rng.uniform(-0.05, 0.05, (n, n_dof)),
        velocity,
        model_torque=h,
        friction=friction,
        sign=np.tanh(velocity / 0.01),
    )
    contact = TimeVariantThreshold().fit(fit)
    collision = VelocityThreshold(bin_width=0.25, margin=0.3).fit(fit)
    bumps = np.zeros((n, n_dof))
    bumps[300:340, 0] = 0.25
    bumps[700:800, 1] = np.linspace(0, 1.5, 100)
    bumps[1100:1110, 0] = -2.0
    run = _signals(fit.residual + bumps, velocity, model_torque=h, friction=friction, sign=fit.sign)
    detector = LevelledDetector(contact, collision, min_duration=0.005, hold=0.02)
    batch = detector.run(run)
    state = detector.initial_state(DT)
    streamed: list[LevelledEvent] = []
    lower = np.empty((n, n_dof))
    for k in range(n):
        verdict, state = detector.step(
            state, run.residual[k], h[k], friction[k], run.sign[k], velocity[k], t[k]
        )
        lower[k] = verdict.contact.lower
        if verdict.event is not None:
            streamed.append(verdict.event)
    last, _ = detector.finish(state)
    streamed += [] if last is None else [last]
    assert len(batch.events) >= 3
    assert batch.counts()["collision"] >= 1 and batch.counts()["contact"] >= 1
    assert streamed == batch.events
    np.testing.assert_allclose(lower, batch.contact.lower, rtol=1e-12, atol=1e-12)


# ----------------------------------------------------------------------------- phases


def _ramp_velocity(n: int, k1: int, k2: int, accelerations: list[float]) -> np.ndarray:
    """q̇ = 0 up to k1, then constant accelerations over equal parts of (k1, k2], then held."""
    qdd = np.zeros(n)
    parts = np.array_split(np.arange(k1 + 1, k2 + 1), len(accelerations))
    for part, value in zip(parts, accelerations, strict=True):
        qdd[part] = value
    return np.cumsum(qdd * DT)[:, None]


def _phased(**options) -> PhasedThreshold:
    quiet = _signals(np.full((40, 1), 0.1), _ramp_velocity(40, 5, 25, [5.0]))
    return PhasedThreshold(ConstantThreshold(), ConstantThreshold(), **options).fit(quiet)


def test_phase_enters_and_leaves_where_the_closed_form_says() -> None:
    level, hysteresis, hold, smoothing, a0 = 1.0, 0.5, 0.03, 0.02, 2.0
    n, k1, k2 = 700, 100, 400
    phased = _phased(level=level, hysteresis=hysteresis, hold=hold, smoothing=smoothing)
    velocity = _ramp_velocity(n, k1, k2, [a0])
    phases = phased.phases(_signals(np.zeros((n, 1)), velocity))
    pole = math.exp(-DT / smoothing)
    # q̈̂ = a0 (1 − aⁿ) n samples into the ramp: above the level from n_in on.
    n_in = math.floor(math.log(1 - level / a0) / math.log(pole)) + 1
    peak = a0 * (1 - pole ** (k2 - k1))
    # After it, peak·aᵐ: above the exit level up to m_busy, then hold seconds of quiet.
    m_busy = math.ceil(math.log((1 - hysteresis) * level / peak) / math.log(pole)) - 1
    k_out = k2 + m_busy + round(hold / DT)
    expected = np.zeros(n, dtype=bool)
    expected[k1 + n_in : k_out] = True
    np.testing.assert_array_equal(phases.accelerating, expected)
    np.testing.assert_allclose(phases.acceleration[k2, 0], peak, rtol=1e-9)


def test_hysteresis_keeps_the_phase_between_the_levels() -> None:
    n, k1, k2 = 900, 100, 700
    # 2 rad/s² (above the level 1), then 0.8 rad/s² (between the exit level 0.5 and 1).
    velocity = _ramp_velocity(n, k1, k2, [2.0, 0.8])
    run = _signals(np.zeros((n, 1)), velocity)
    with_hysteresis = _phased(level=1.0, hysteresis=0.5, hold=0.0, smoothing=0.0)
    without = _phased(level=1.0, hysteresis=0.0, hold=0.0, smoothing=0.0)
    middle = k1 + (k2 - k1) // 2  # the first sample at 0.8 rad/s²
    on = with_hysteresis.phases(run).accelerating
    off = without.phases(run).accelerating
    np.testing.assert_array_equal(np.flatnonzero(on), np.arange(k1 + 1, k2 + 1))
    np.testing.assert_array_equal(np.flatnonzero(off), np.arange(k1 + 1, middle + 1))
    # 0.8 rad/s² from rest never enters.
    calm = _signals(np.zeros((n, 1)), _ramp_velocity(n, k1, k2, [0.8]))
    assert not with_hysteresis.phases(calm).accelerating.any()


def test_phased_bounds_batch_equal_stream_and_chunks() -> None:
    rng = np.random.default_rng(11)
    n = 2000
    t = np.arange(n) * DT
    qd = np.column_stack([np.sin(2 * np.pi * 0.7 * t), 0.5 * np.sin(2 * np.pi * 1.3 * t)])
    friction = 0.3 * np.tanh(qd / 0.05)
    h = 2 * np.cos(2 * np.pi * t)[:, None] * np.ones(2)
    residual = 0.05 * h + rng.uniform(-0.05, 0.05, (n, 2))
    run = _signals(residual, qd, model_torque=h, friction=friction, sign=np.tanh(qd / 0.01))
    phased = PhasedThreshold(
        TimeVariantThreshold(), VelocityThreshold(bin_width=0.2), level=4.0, hysteresis=0.2
    ).fit(run)
    assert 0.1 < phased.accelerating_fraction_ < 0.9
    lower, upper = phased.bounds(run)
    args = (run.model_torque, run.friction, run.sign, run.velocity)
    state = phased.initial_state(*(a[0] for a in args), dt=DT)
    stepped = np.empty((n, 2))
    for k in range(n):
        _, stepped[k], state = phased.step(state, *(a[k] for a in args))
    state = phased.initial_state(*(a[0] for a in args), dt=DT)
    chunks = []
    for rows in np.array_split(np.arange(n), [7, 8, 500, 1333]):
        low, _, state = phased.process(state, *(a[rows] for a in args))
        chunks.append(low)
    np.testing.assert_allclose(stepped, upper, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(np.concatenate(chunks), lower, rtol=1e-12, atol=1e-12)
    active = phased.phases(run).accelerating
    a_low, _ = phased.accelerating_.bounds(run)
    s_low, _ = phased.steady_.bounds(run)
    np.testing.assert_array_equal(lower, np.where(active[:, None], a_low, s_low))


def test_phased_threshold_round_trips_through_its_file(tmp_path: Path) -> None:
    phased = _phased(level=[1.5], hold=0.02)
    loaded = load_threshold(phased.save(tmp_path / "phased.yaml"))
    assert isinstance(loaded, PhasedThreshold)
    run = _signals(np.zeros((200, 1)), _ramp_velocity(200, 20, 120, [4.0]))
    for a, b in zip(loaded.bounds(run), phased.bounds(run), strict=True):
        np.testing.assert_array_equal(a, b)
    text = (tmp_path / "phased.yaml").read_text(encoding="utf-8")
    (tmp_path / "bad.yaml").write_text(text.replace("level: [1.5]", "level: [-1.5]"))
    with pytest.raises(FileFormatError, match=r"params\.level"):
        load_threshold(tmp_path / "bad.yaml")
    (tmp_path / "gone.yaml").write_text(text.replace("steady_:", "stationary_:"))
    with pytest.raises(FileFormatError, match=r"attributes\.steady_: required key is missing"):
        load_threshold(tmp_path / "gone.yaml")


# ----------------------------------------------------------------------------- bad input


def test_bad_inputs_give_clear_errors() -> None:
    fitted = ConstantThreshold(margin=0.4).fit(_quiet())
    with pytest.raises(NotFittedError, match="not fitted"):
        LevelledDetector(ConstantThreshold(), fitted)
    with pytest.raises(NotFittedError, match="not fitted"):
        PhasedThreshold.from_fitted(fitted, ConstantThreshold())
    with pytest.raises(InputTypeError, match="collision must be a fitted threshold"):
        LevelledDetector(fitted, "constant")  # type: ignore[arg-type]
    narrow = ConstantThreshold(margin=0.1).fit(_quiet())
    with pytest.raises(InputValueError, match=r"collision band must be at least as wide.*joint 1"):
        LevelledDetector(fitted, narrow)
    with pytest.raises(DimensionError, match="3 joints, the collision threshold for 1"):
        LevelledDetector(ConstantThreshold().fit(_quiet(3)), fitted)
    detector = LevelledDetector(narrow, fitted)
    with pytest.raises(DimensionError, match=r"\(1,\).*got shape \(2,\)"):
        detector.step(detector.initial_state(), [0.0, 0.0], [0], [0], [0], [0], 0.0)
    phased = _phased()
    with pytest.raises(DimensionError, match="1 joints"):
        phased.bounds(_signals(np.zeros((10, 2))))
    with pytest.raises(InputValueError, match="level must be finite and > 0"):
        _phased(level=0.0)
    with pytest.raises(InputValueError, match=r"hysteresis must be in \[0, 1\)"):
        _phased(hysteresis=1.0)
    with pytest.raises(InputValueError, match=r"no stretch .* in the accelerating phase"):
        PhasedThreshold(ConstantThreshold(), ConstantThreshold()).fit(_quiet())


# ----------------------------------------------------------------------------- monitor


@pytest.fixture(scope="module")
def panda() -> dict:
    scenario = load_scenario("panda-gaz").with_duration(4.0)
    free = [scenario.run(seed=s, collisions=False).log for s in (1, 2)]
    hit = scenario.run(seed=4, collisions=True).log
    return {"nominal": scenario.robots()[1], "free": free, "hit": hit}


def _streamed(monitor: LevelledMonitor, log) -> list[LevelledEvent]:
    monitor.reset()
    events = []
    for k in range(log.n_samples):
        verdict = monitor.step(log.t[k], log.q[k], log.tau_m[k])
        if verdict.event is not None:
            events.append(verdict.event)
    last = monitor.finish()
    return events + ([] if last is None else [last])


def _close(a: list[LevelledEvent], b: list[LevelledEvent]) -> None:
    assert [(e.level, e.joints) for e in a] == [(e.level, e.joints) for e in b]
    np.testing.assert_allclose([(e.start, e.end) for e in a], [(e.start, e.end) for e in b])


def test_scenario_end_to_end(panda) -> None:
    levels = tune_levels(panda["free"], panda["nominal"], contact="constant", folds=None)
    result = levels.process(panda["hit"])
    contact, collision = result.counts()["contact"], result.counts()["collision"]
    assert collision >= 1 and contact >= 1
    # Every collision the monitor found lies inside exactly one collision-level event.
    assert len(result.run.events) == len(result.collisions)
    for found in result.run.events:
        holders = [e for e in result.events if e.start <= found.start and found.end <= e.end]
        assert len(holders) == 1 and holders[0].level == "collision"
        assert any(c.start == found.start and c.end == found.end for c in holders[0].collisions)
    assert len(result.events) >= collision
    _close(_streamed(levels, panda["hit"]), result.events)


def test_monitor_stream_reads_the_observer_signals(panda) -> None:
    nominal, free = panda["nominal"], panda["free"]
    contact, settings = tune(free, nominal, "time-variant", margin_fraction=0.0, folds=None)
    collision, _ = tune(free, nominal, "time-variant", settings, folds=None)
    part = panda["hit"].slice(3.3, 4.0)  # the contact of seed 4 and the time before it
    # Both stream backends hand the contact level the sample's observer signals: the
    # compiled one from its committed state, the Python one from its record.
    for backend in ("python", "numba") if numba_available() else ("python",):
        monitor = CollisionMonitor(nominal, collision, settings, backend=backend)
        levels = LevelledMonitor(monitor, contact)
        batch = levels.process(part)
        assert batch.events and levels.monitor.backend == backend
        _close(_streamed(levels, part), batch.events)


def test_tune_levels_with_a_phased_contact_band(panda) -> None:
    phased = PhasedThreshold(ConstantThreshold(), ConstantThreshold(), level=2.0, transient=0.25)
    levels = tune_levels(
        panda["free"], panda["nominal"], contact=phased, collision="constant", folds=None
    )
    fitted = levels.contact
    assert isinstance(fitted, PhasedThreshold)
    assert (fitted.accelerating_.beta_ >= fitted.steady_.beta_).sum() >= 4
    result = levels.process(panda["hit"])
    assert result.counts()["collision"] == len(result.run.events)
    part = panda["hit"].slice(3.3, 4.0)  # the phase reads the velocity: streamed on any backend
    _close(_streamed(levels, part), levels.process(part).events)
    with pytest.raises(InputValueError, match="name the family with 'method'"):
        tune_levels(panda["free"], panda["nominal"], contact={"margin": 0.0}, folds=None)
    with pytest.raises(InputTypeError, match="contact must be a family name"):
        tune_levels(panda["free"], panda["nominal"], contact=3, folds=None)  # type: ignore[arg-type]


def test_cli_and_report_show_both_levels(panda, tmp_path: Path) -> None:
    nominal, free = panda["nominal"], panda["free"]
    contact, settings = tune(free, nominal, "constant", margin_fraction=0.0, folds=None)
    collision, _ = tune(free, nominal, "constant", settings, folds=None)
    paths = [save_tuned(tmp_path / f"{n}.yaml", th, settings) for n, th in
             (("contact", contact), ("collision", collision))]  # fmt: skip
    log_path = write_log(panda["hit"], tmp_path / "hit.parquet")
    result = LevelledMonitor(CollisionMonitor(nominal, collision, settings), contact).process(
        panda["hit"]
    )
    counts = result.counts()
    out = CliRunner().invoke(
        app,
        ["detect", str(log_path), "--thresholds", str(paths[1]), "--contact-threshold",
         str(paths[0])],
    )  # fmt: skip
    assert out.exit_code == 0, out.output
    assert f"{counts['contact']} contact, {counts['collision']} collision" in out.output
    assert out.output.count(" collision ") >= counts["collision"]
    heading, items = levels_section(result.events, log=panda["hit"])
    page = write_report(tmp_path / "r.html", title="levels", sections=[(heading, items)])
    html = page.read_text(encoding="utf-8")
    assert "Events per level" in html and "Events with their level" in html
    table = items[1].frame  # type: ignore[union-attr]
    assert table.loc["contact band (every event)", "events"] == len(result.events)
    assert table.loc["collision band", "events"] == len(result.collisions)
    # `sensorless report --contact-threshold` adds the same section to the comparison report.
    report = tmp_path / "report.html"
    out = CliRunner().invoke(
        app,
        ["report", str(log_path), "--thresholds", str(paths[1]), "--contact-threshold",
         str(paths[0]), "-o", str(report)],
    )  # fmt: skip
    assert out.exit_code == 0, out.output
    html = report.read_text(encoding="utf-8")
    assert "Events by reaction level" in html and "Events per level" in html
