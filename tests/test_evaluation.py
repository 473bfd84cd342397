"""Tests of :mod:`sensorless.evaluation`.

The logs and events are built by hand so that every delay, count and rate
has a value written out here: a 10 s log sampled at 100 Hz with three
collision windows, [2.0, 2.5], [5.0, 5.3] and [8.0, 8.2] s. One false alarm
in 10 s of motion is 360 false alarms per hour.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sensorless.evaluation import (
    DEFAULT_MAX_DELAY,
    Evaluation,
    Window,
    collision_windows,
    comparison_table,
    efficiency_table,
    evaluate,
    summary_table,
)
from sensorless.exceptions import DimensionError, InputValueError, LogFormatError
from sensorless.io import Log
from sensorless.signals import Event

DT = 0.01
N_SAMPLES = 1001  # 0 .. 10 s
WINDOWS = {1: (2.0, 2.5), 2: (5.0, 5.3), 3: (8.0, 8.2)}
PEAKS = {1: 40.0, 2: 25.0, 3: 60.0}


def time_base() -> np.ndarray:
    return np.arange(N_SAMPLES) * DT


def make_log(*, with_labels: bool = True, with_metadata: bool = True, collisions=None) -> Log:
    t = time_base()
    labels = np.zeros(N_SAMPLES, dtype=np.int64)
    for ident, (start, end) in WINDOWS.items():
        labels[round(start / DT) : round(end / DT) + 1] = ident
    if collisions is None:
        collisions = [
            {"id": ident, "start": start, "end": end, "peak": PEAKS[ident], "link": 2}
            for ident, (start, end) in WINDOWS.items()
        ]
    metadata = {"collisions": collisions} if with_metadata else {}
    return Log(
        t=t,
        q=np.zeros((N_SAMPLES, 2)),
        collision_id=labels if with_labels else None,
        metadata=metadata,
    )


def event(start: float, end: float, joints=(2,), method: str = "time-variant") -> Event:
    return Event(start, end, tuple(joints), 1.0, 5.0, method)


# --------------------------------------------------------------------------- windows


def test_collision_windows_from_labels_with_peaks_from_metadata():
    windows = collision_windows(make_log())
    assert [w.id for w in windows] == [1, 2, 3]
    for window in windows:
        start, end = WINDOWS[window.id]
        assert window.start == pytest.approx(start)
        assert window.end == pytest.approx(end)
        assert window.peak_force == PEAKS[window.id]
        assert window.duration == pytest.approx(end - start)


def test_collision_windows_without_metadata_have_nan_peak():
    windows = collision_windows(make_log(with_metadata=False))
    assert [w.id for w in windows] == [1, 2, 3]
    assert all(math.isnan(w.peak_force) for w in windows)


def test_collision_windows_from_metadata_only():
    windows = collision_windows(make_log(with_labels=False))
    assert [(w.id, w.start, w.end, w.peak_force) for w in windows] == [
        (ident, *WINDOWS[ident], PEAKS[ident]) for ident in (1, 2, 3)
    ]


def test_collision_windows_empty_without_labels_or_metadata():
    assert collision_windows(make_log(with_labels=False, with_metadata=False)) == []


def test_labels_take_precedence_and_metadata_fills_unlabelled_contacts():
    collisions = [
        # The label says [2.0, 2.5]; the metadata's continuous times are not used.
        {"id": 1, "start": 1.995, "end": 2.503, "peak": 40.0},
        {"id": 2, "start": 5.0, "end": 5.3},
        {"id": 3, "start": 8.0, "end": 8.2, "peak": None},
        # Shorter than a sample period: no label, but a real contact.
        {"id": 4, "start": 9.501, "end": 9.505, "peak": 10.0},
        # Outside the log (e.g. a slice of a longer run): ignored.
        {"id": 5, "start": 12.0, "end": 12.5, "peak": 10.0},
    ]
    windows = collision_windows(make_log(collisions=collisions))
    assert [w.id for w in windows] == [1, 2, 3, 4]
    assert windows[0].start == pytest.approx(2.0)
    assert windows[0].end == pytest.approx(2.5)
    assert math.isnan(windows[1].peak_force)
    assert math.isnan(windows[2].peak_force)
    assert (windows[3].start, windows[3].end, windows[3].peak_force) == (9.501, 9.505, 10.0)


def test_label_interrupted_by_stronger_contact_is_one_window():
    t = time_base()
    labels = np.zeros(N_SAMPLES, dtype=np.int64)
    labels[100:300] = 1
    labels[150:200] = 2  # contact 2 dominates in the middle of contact 1
    log = Log(t=t, q=np.zeros((N_SAMPLES, 1)), collision_id=labels)
    windows = collision_windows(log)
    assert [(w.id, round(w.start, 9), round(w.end, 9)) for w in windows] == [
        (1, 1.0, 2.99),
        (2, 1.5, 1.99),
    ]


def test_windows_match_contact_set_labels():
    """Cross-check against the simulator's contact set (labels and metadata)."""
    from sensorless.simulation.collisions import Contact, ContactSet, HalfSine

    contacts = ContactSet(
        [
            Contact(1, 2, [0, 0, 0], [1, 0, 0], HalfSine(1.5, 0.3, 30.0)),
            Contact(2, 3, [0, 0, 0], [0, 1, 0], HalfSine(6.2, 0.2, 50.0)),
        ]
    )
    t = time_base()
    log = Log(
        t=t,
        q=np.zeros((N_SAMPLES, 3)),
        collision_id=contacts.active_id(t),
        metadata={"collisions": contacts.summaries()},
    )
    windows = collision_windows(log)
    assert [w.id for w in windows] == [ident for ident, _, _ in contacts.windows()]
    for window, (_, start, end) in zip(windows, contacts.windows(), strict=True):
        # The labels are sampled: the window lies within one sample period of the contact.
        assert start <= window.start < start + DT
        assert end - DT < window.end <= end
    assert [w.peak_force for w in windows] == [30.0, 50.0]


@pytest.mark.parametrize(
    ("collisions", "match"),
    [
        ({"id": 1}, r"metadata\['collisions'\] must be a list"),
        (["contact"], r"\[0\] must be a dict"),
        ([{"id": 0, "start": 1.0, "end": 2.0}], r"positive integer 'id'; got 0"),
        ([{"id": True, "start": 1.0, "end": 2.0}], r"positive integer 'id'; got True"),
        ([{"id": 1, "end": 2.0}], r"numeric 'start' \[s\]; got None"),
        ([{"id": 1, "start": 1.0, "end": 2.0, "peak": "big"}], r"numeric 'peak' \[N\]"),
        ([{"id": 1, "start": 2.0, "end": 1.0}], r"start <= end; got start = 2.0 s"),
    ],
)
def test_collision_windows_reject_malformed_metadata(collisions, match):
    log = Log(t=time_base(), q=np.zeros((N_SAMPLES, 1)), metadata={"collisions": collisions})
    with pytest.raises(LogFormatError, match=match):
        collision_windows(log)


# --------------------------------------------------------------------------- evaluate


def test_detected_window_with_known_delays():
    result = evaluate([event(2.05, 2.6)], make_log(), method="tv")
    row = result.per_collision.loc[1]
    assert bool(row["detected"])
    assert row["start_delay"] == pytest.approx(0.05)
    assert row["end_delay"] == pytest.approx(0.1)
    assert row["n_events"] == 1
    assert row["joints"] == (2,)
    assert row["peak_force"] == 40.0
    assert result.method == "tv"
    assert result.detections == [event(2.05, 2.6)]


def test_missed_windows_have_nan_delays():
    result = evaluate([event(2.05, 2.6)], make_log())
    assert result.n_detected == 1
    assert result.n_missed == 2
    assert result.n_collisions == 3
    missed = result.per_collision.loc[[2, 3]]
    assert not missed["detected"].any()
    assert missed["start_delay"].isna().all()
    assert missed["end_delay"].isna().all()
    assert (missed["n_events"] == 0).all()
    assert list(missed["joints"]) == [(), ()]


def test_false_alarm_and_rate_per_hour():
    alarms = [event(0.5, 0.6), event(7.0, 7.1)]
    result = evaluate([event(2.05, 2.6), *alarms], make_log())
    assert result.false_alarms == alarms
    assert result.n_false_alarms == 2
    assert result.duration == pytest.approx(10.0)
    assert result.false_alarm_rate == pytest.approx(2 / (10.0 / 3600.0))  # 720 per hour
    assert result.n_detected == 1


def test_overlapping_events_give_first_start_and_last_end():
    events = [event(2.2, 2.7, joints=(1,)), event(2.05, 2.3, joints=(2, 3))]
    result = evaluate(events, make_log())
    row = result.per_collision.loc[1]
    assert row["start_delay"] == pytest.approx(0.05)
    assert row["end_delay"] == pytest.approx(0.2)
    assert row["n_events"] == 2
    assert row["joints"] == (1, 2, 3)
    assert result.n_false_alarms == 0
    # Events are kept sorted by start time.
    assert [e.start for e in result.events] == [2.05, 2.2]


def test_alarm_one_second_before_a_contact_is_a_false_alarm_and_masks_it():
    # Was: an event from 1.9 s "detected" window 1 (start 2.0 s) with a start
    # delay of -0.1 s. An alarm already on cannot tell of the contact (issue 18).
    alarm = event(1.0, 2.3)
    result = evaluate([alarm], make_log())
    row = result.per_collision.loc[1]
    assert result.false_alarms == [alarm]
    assert result.n_false_alarms == 1
    assert (result.n_detected, result.n_masked, result.n_missed) == (0, 1, 2)
    assert bool(row["masked"]) and not bool(row["detected"])
    assert math.isnan(row["start_delay"]) and math.isnan(row["end_delay"])
    assert result.detections == []
    assert math.isnan(result.mean_start_delay)
    assert result.summary()["n_masked"] == 1


def test_alarm_that_ends_before_the_contact_masks_nothing():
    result = evaluate([event(1.0, 1.99)], make_log())
    assert result.n_false_alarms == 1
    assert result.n_masked == 0
    assert result.n_missed == 3


def test_later_event_detects_a_masked_contact_with_a_positive_delay():
    early, late = event(1.9, 2.1), event(2.2, 2.4)
    result = evaluate([early, late], make_log())
    row = result.per_collision.loc[1]
    assert bool(row["detected"]) and not bool(row["masked"])
    assert row["start_delay"] == pytest.approx(0.2)
    assert result.false_alarms == [early]
    assert result.detections == [late]


def test_detection_running_into_the_next_contact_masks_it_and_stays_a_detection():
    long = event(2.1, 5.1)  # starts inside window 1, still on when window 2 starts
    result = evaluate([long], make_log(), max_delay=0.2)
    assert list(result.per_collision["detected"]) == [True, False, False]
    assert list(result.per_collision["masked"]) == [False, True, False]
    assert result.detections == [long]
    assert result.false_alarms == []


def test_event_after_the_end_detects_within_max_delay():
    late = [event(2.8, 2.9)]  # 0.3 s after the end of window 1
    assert DEFAULT_MAX_DELAY == 0.5
    detected = evaluate(late, make_log())
    assert detected.per_collision.loc[1, "start_delay"] == pytest.approx(0.8)
    assert detected.n_false_alarms == 0
    strict = evaluate(late, make_log(), max_delay=0.2)
    assert not strict.per_collision.loc[1, "detected"]
    assert strict.false_alarms == late
    assert strict.max_delay == 0.2


def test_tolerance_excuses_events_just_before_a_window():
    early = [event(1.8, 1.95)]
    strict = evaluate(early, make_log())
    assert strict.false_alarms == early
    tolerant = evaluate(early, make_log(), tolerance=0.1)
    assert tolerant.false_alarms == []
    assert tolerant.excused == early
    assert tolerant.n_detected == 0  # excused is not a detection


def test_event_spanning_two_windows_masks_both():
    # Was: detected both with a start delay of -0.1 s on window 2.
    result = evaluate([event(4.9, 8.1)], make_log())
    assert list(result.per_collision["detected"]) == [False, False, False]
    assert list(result.per_collision["masked"]) == [False, True, True]
    assert result.n_false_alarms == 1
    assert (result.n_detected, result.n_masked, result.n_missed) == (0, 2, 1)


def test_tolerance_excuses_an_alarm_starting_just_before_a_contact_which_is_masked():
    early = [event(1.95, 2.2)]
    strict = evaluate(early, make_log())
    assert strict.false_alarms == early
    assert strict.per_collision.loc[1, "masked"]
    tolerant = evaluate(early, make_log(), tolerance=0.1)
    assert tolerant.false_alarms == []
    assert tolerant.excused == early
    assert tolerant.per_collision.loc[1, "masked"]
    assert tolerant.n_detected == 0


def reference_outcome(events, windows, max_delay):
    """Per window "detected", "masked" or "missed", one rule at a time (a second method)."""
    outcome = {}
    for ident, (start, end) in windows.items():
        if any(start <= e.start <= end + max_delay for e in events):
            outcome[ident] = "detected"
        elif any(e.start < start <= e.end for e in events):
            outcome[ident] = "masked"
        else:
            outcome[ident] = "missed"
    return outcome


@given(
    st.lists(
        st.tuples(st.floats(0.0, 10.0), st.floats(0.0, 3.0)).map(
            lambda pair: (round(pair[0], 2), round(pair[0] + pair[1], 2))
        ),
        max_size=6,
    )
)
@settings(max_examples=200, deadline=None)
def test_outcomes_match_a_per_window_recount(intervals):
    events = [event(start, end) for start, end in intervals]
    result = evaluate(events, make_log())
    expected = reference_outcome(events, WINDOWS, DEFAULT_MAX_DELAY)
    table = result.per_collision
    got = {
        ident: "detected"
        if table.loc[ident, "detected"]
        else "masked"
        if table.loc[ident, "masked"]
        else "missed"
        for ident in WINDOWS
    }
    assert got == expected
    assert result.n_detected + result.n_masked + result.n_missed == result.n_collisions
    assert (table["start_delay"].dropna() >= 0.0).all()
    # An event detecting nothing is a false alarm (tolerance 0: nothing is excused).
    detecting = {
        i
        for i, e in enumerate(events)
        if any(s <= e.start <= w_end + DEFAULT_MAX_DELAY for s, w_end in WINDOWS.values())
    }
    assert result.n_false_alarms == len(events) - len(detecting)


def test_empty_events():
    result = evaluate([], make_log())
    assert result.n_detected == 0
    assert result.n_missed == 3
    assert result.false_alarms == []
    assert result.false_alarm_rate == 0.0
    assert math.isnan(result.mean_start_delay)
    assert math.isnan(result.mean_end_delay)
    assert math.isnan(result.max_start_delay)
    assert result.method == ""
    table = result.to_pandas()
    assert table.shape == (3, 9)
    assert table["detected"].dtype == bool


def test_log_without_windows_counts_every_event_as_false_alarm():
    log = make_log(with_labels=False, with_metadata=False)
    result = evaluate([event(2.05, 2.6)], log)
    assert result.n_collisions == 0
    assert result.n_false_alarms == 1
    assert result.false_alarm_rate == pytest.approx(360.0)
    assert result.per_collision.empty


def test_method_name_defaults_to_the_events_method():
    assert evaluate([event(2.05, 2.6, method="constant")], make_log()).method == "constant"
    mixed = [event(2.05, 2.6, method="a"), event(5.1, 5.2, method="b")]
    assert evaluate(mixed, make_log()).method == ""


def test_summary_and_to_pandas():
    events = [event(2.05, 2.6), event(5.1, 5.5), event(7.0, 7.1)]
    result = evaluate(events, make_log(), method="tv")
    summary = result.summary()
    assert summary["method"] == "tv"
    assert summary["n_collisions"] == 3
    assert summary["n_detected"] == 2
    assert summary["n_missed"] == 1
    assert summary["detected"] == "2/3"
    assert summary["n_false_alarms"] == 1
    assert summary["false_alarm_rate"] == pytest.approx(360.0)
    assert summary["mean_start_delay"] == pytest.approx((0.05 + 0.1) / 2)
    assert summary["mean_end_delay"] == pytest.approx((0.1 + 0.2) / 2)
    assert summary["max_start_delay"] == pytest.approx(0.1)
    assert summary["duration"] == pytest.approx(10.0)
    table = result.to_pandas()
    assert list(table.columns) == [
        "start",
        "end",
        "peak_force",
        "detected",
        "masked",
        "start_delay",
        "end_delay",
        "n_events",
        "joints",
    ]
    assert table.index.name == "id"
    table.loc[1, "start"] = -1.0
    assert result.per_collision.loc[1, "start"] == pytest.approx(2.0)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"tolerance": -0.1}, r"tolerance must be a finite, non-negative number .* got -0.1"),
        ({"tolerance": "a"}, r"tolerance must be a non-negative number of seconds; got 'a'"),
        ({"max_delay": math.nan}, r"max_delay must be a finite, non-negative .* got nan"),
        ({"max_delay": math.inf}, r"max_delay must be a finite"),
    ],
)
def test_evaluate_rejects_bad_settings(kwargs, match):
    with pytest.raises(InputValueError, match=match):
        evaluate([], make_log(), **kwargs)


def test_evaluate_rejects_bad_events():
    with pytest.raises(TypeError, match=r"Event objects; item 1 is a tuple"):
        evaluate([event(1.0, 1.1), (1.0, 2.0)], make_log())
    with pytest.raises(InputValueError, match=r"event 0 ends before it starts"):
        evaluate([event(2.0, 1.0)], make_log())
    with pytest.raises(InputValueError, match=r"event 0 must have finite start and end"):
        evaluate([event(2.0, math.inf)], make_log())


def test_evaluate_rejects_unknown_keyword():
    with pytest.raises(TypeError, match="unexpected keyword"):
        evaluate([], make_log(), delay=0.1)  # type: ignore[call-arg]


# --------------------------------------------------------------------------- tables


def two_methods() -> dict[str, Evaluation]:
    log = make_log()
    time_variant = [event(2.05, 2.6), event(5.04, 5.4), event(8.03, 8.3)]
    constant = [event(2.31, 2.55), event(6.5, 6.6)]
    return {
        "time-variant": evaluate(time_variant, log),
        "constant": evaluate(constant, log),
    }


def test_comparison_table_in_the_style_of_table_5_4():
    table = comparison_table(two_methods(), missed="Does not Detect")
    assert table.shape == (3, 3 + 2 * 2)
    assert list(table.index) == [1, 2, 3]
    assert table.index.name == "collision"
    assert list(table.columns) == [
        ("window", "start"),
        ("window", "end"),
        ("window", "peak_force"),
        ("time-variant", "start_delay"),
        ("time-variant", "end_delay"),
        ("constant", "start_delay"),
        ("constant", "end_delay"),
    ]
    assert table[("window", "start")].tolist() == pytest.approx([2.0, 5.0, 8.0])
    assert table[("window", "peak_force")].tolist() == [40.0, 25.0, 60.0]
    assert table[("time-variant", "start_delay")].tolist() == pytest.approx([0.05, 0.04, 0.03])
    assert table[("time-variant", "end_delay")].tolist() == pytest.approx([0.1, 0.1, 0.1])
    assert table.loc[1, ("constant", "start_delay")] == pytest.approx(0.31)
    assert table.loc[1, ("constant", "end_delay")] == pytest.approx(0.05)
    assert table.loc[2, ("constant", "start_delay")] == "Does not Detect"
    assert table.loc[3, ("constant", "end_delay")] == "Does not Detect"


def test_comparison_table_names_masked_collisions():
    log = make_log()
    evaluations = {"a": evaluate([event(4.9, 5.2)], log), "b": evaluate([event(5.1, 5.2)], log)}
    table = comparison_table(evaluations)
    assert table.loc[2, ("a", "start_delay")] == "masked"
    assert table.loc[2, ("b", "start_delay")] == pytest.approx(0.1)
    assert table.loc[1, ("a", "start_delay")] == "missed"


def test_summary_table_shape_and_values():
    table = summary_table(two_methods())
    assert list(table.index) == ["time-variant", "constant"]
    assert table.index.name == "method"
    assert "method" not in table.columns
    assert table.loc["time-variant", "detected"] == "3/3"
    assert table.loc["constant", "detected"] == "1/3"
    assert table.loc["time-variant", "n_false_alarms"] == 0
    assert table.loc["constant", "n_false_alarms"] == 1
    assert table.loc["constant", "false_alarm_rate"] == pytest.approx(360.0)
    assert table.loc["time-variant", "mean_start_delay"] == pytest.approx(0.04)
    assert table.loc["constant", "mean_start_delay"] == pytest.approx(0.31)
    assert table.shape == (2, 12)


def test_tables_reject_bad_input():
    evaluations = two_methods()
    with pytest.raises(InputValueError, match="at least one"):
        comparison_table({})
    with pytest.raises(InputValueError, match="at least one"):
        summary_table({})
    with pytest.raises(TypeError, match=r"evaluations\['x'\] must be an Evaluation; got dict"):
        summary_table({"x": {}})  # type: ignore[dict-item]
    with pytest.raises(TypeError, match="must be a mapping"):
        comparison_table(list(evaluations.values()))  # type: ignore[arg-type]
    with pytest.raises(InputValueError, match="may not be named 'window'"):
        comparison_table({"window": evaluations["constant"]})
    other_log = make_log(with_labels=False, collisions=[{"id": 1, "start": 2.0, "end": 2.4}])
    other = evaluate([], other_log)
    with pytest.raises(InputValueError, match="same collision windows; 'other' has windows"):
        comparison_table({"tv": evaluations["time-variant"], "other": other})


def test_efficiency_table_reproduces_table_5_7():
    table = efficiency_table(
        [2.0137, 1.8727, 2.3715],
        [2.5662, 2.4758, 2.8413],
        extra={"gamma": [0.0020, 5.0523e-4, 0.0521], "C": [0.2678, 0.5654, 0.4367]},
    )
    assert list(table.index) == ["alpha", "gamma", "C", "beta", "eff"]
    assert list(table.columns) == [1, 2, 3]
    assert table.columns.name == "joint"
    assert table.loc["eff"].round(4).tolist() == [0.7847, 0.7564, 0.8347]
    assert table.loc["gamma", 2] == 5.0523e-4


def test_efficiency_table_rejects_bad_input():
    with pytest.raises(InputValueError, match=r"beta must be positive .* got \[1.0, 0.0\]"):
        efficiency_table([1.0, 1.0], [1.0, 0.0])
    with pytest.raises(DimensionError, match=r"beta must have the shape of alpha, \(2,\)"):
        efficiency_table([1.0, 1.0], [1.0, 2.0, 3.0])
    with pytest.raises(DimensionError, match=r"alpha must have shape \(n_dof,\)"):
        efficiency_table([[1.0]], [1.0])
    with pytest.raises(DimensionError, match=r"extra\['C'\] must have the shape of alpha"):
        efficiency_table([1.0], [1.0], extra={"C": [1.0, 2.0]})
    with pytest.raises(InputValueError, match=r"alpha must be finite"):
        efficiency_table([math.nan], [1.0])
    with pytest.raises(DimensionError, match=r"alpha must be a numeric array"):
        efficiency_table(["a"], [1.0])
    with pytest.raises(InputValueError, match=r"may not be named .* got \['eff'\]"):
        efficiency_table([1.0], [1.0], extra={"eff": [1.0]})


def test_window_fields():
    window = Window(3, 1.0, 1.25, 7.0)
    assert (window.id, window.start, window.end, window.peak_force) == (3, 1.0, 1.25, 7.0)
    assert window.duration == 0.25
    assert math.isnan(Window(1, 0.0, 1.0).peak_force)
