"""The benchmark's isolation and classification of events (issue 12): counts, a known push.

Two tiny serial benchmarks. One on panda-gaz (its model error) whose
collision runs carry the simulator's random interactions (guiding hands,
clamps, impacts): its contact summary and confusion table must equal a
recount from the events table and from the ground truth of the logs the
benchmark wrote. One on a Panda held still with the true model and one push
at a known point: the isolation row must find the link, the point and the
force within the tolerances ``tests/test_isolation.py`` derives from the
observer's bandwidth (imported from there, not restated).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pandas as pd
import pytest

import sensorless as sl
from sensorless.benchmark import BenchmarkConfig, BenchmarkScenario, run_benchmark
from sensorless.benchmark.contacts import CONTACT_COLUMNS
from sensorless.benchmark.tables import COLUMNS
from sensorless.exceptions import InputValueError
from sensorless.io import read_log
from sensorless.isolation import Isolator
from sensorless.simulation.scenario import Scenario
from sensorless.simulation.schema import validate_scenario

# The push and the tolerances derived for it (pytest puts tests/ on sys.path).
from test_isolation import EPSILON, HOLD, PEAK, PLATEAU, POINT_TOLERANCE, RAMP, RAMP_START, RELEASE

DRAWN = BenchmarkConfig(
    (BenchmarkScenario("panda-gaz", duration=6.0, interactions=1),),
    methods=("constant",),
    n_tuning=1,
    n_collision=3,
    n_free=1,
    master_seed=5,
)


@pytest.fixture(scope="module")
def drawn(tmp_path_factory):
    logs = tmp_path_factory.mktemp("logs")
    return run_benchmark(DRAWN, scheduler="serial", log_dir=str(logs)), logs


def _kinds_written(logs, run: int) -> dict[int, tuple[str, float, float]]:
    """Contact id -> (kind, start, end) from the ground truth of a collision run's written log."""
    log = read_log(logs / "panda-gaz" / f"collision-{run:03d}.parquet")
    return {int(c["id"]): (c["kind"], c["start"], c["end"]) for c in log.metadata["collisions"]}


def test_the_contact_summary_and_confusion_equal_a_recount(drawn) -> None:
    result, logs = drawn
    events = result.tables["events"]
    assert list(events.columns) == list(COLUMNS["events"])  # the new columns are there
    collision_runs = events[events["role"] == "collision"]
    # Rows of collision-free runs carry no isolation; collision runs' rows all do.
    assert events.loc[events["role"] == "free", "contact"].isna().all()
    assert collision_runs["isolated_at"].notna().all()
    contacts = result.contacts().set_index("method")
    confusion = result.confusion()
    for method, row in contacts.iterrows():
        mine = collision_runs[collision_runs["method"] == method]
        # Recount the matches from the written ground truth: the earliest contact whose
        # window [start, end + max_delay] holds the event's start.
        truth = []
        for run, start in mine[["run", "start"]].itertuples(index=False):
            windows = sorted(_kinds_written(logs, run).items(), key=lambda item: item[1][1])
            inside = [(i, k) for i, (k, s, e) in windows if s <= start <= e + DRAWN.max_delay]
            truth.append(inside[0] if inside else (0, "none"))
        assert list(mine["contact"]) == [ident for ident, _ in truth]
        assert list(mine["true_kind"]) == [kind for _, kind in truth]
        scored = mine[mine["contact"] > 0]
        assert row["n_events"] == len(mine) and row["n_scored"] == len(scored)
        assert row["n_link_ok"] == int((scored["link"] == scored["link_true"]).sum())
        assert row["n_link_unseen"] == 0  # every Panda joint is monitored
        right = (scored["assigned_kind"] == scored["true_kind"]).sum()
        assert row["n_correct"] == right
        if len(scored):
            assert row["link_rate"] == row["n_link_ok"] / len(scored)
            assert row["accuracy"] == right / len(scored)
            errors = (scored["force_estimated"] - scored["force_true"]).abs()
            assert row["force_error_median"] == pytest.approx(float(np.nanmedian(errors)))
        table = confusion[confusion["method"] == method].set_index("true")
        assert int(table[["intended", "collision"]].to_numpy().sum()) == row["n_scored"]
        for true in ("intended", "collision"):
            assigned = scored.loc[scored["true_kind"] == true, "assigned_kind"]
            for kind in ("intended", "collision"):
                assert table.loc[true, kind] == int((assigned == kind).sum())
    # The seeded draws hold both classes, so the table is not trivially one-sided.
    kinds = {
        k for run in range(DRAWN.n_collision) for k, _, _ in _kinds_written(logs, run).values()
    }
    assert kinds == {"intended", "collision"}
    assert set(collision_runs.loc[collision_runs["contact"] > 0, "true_kind"]) == kinds


def test_interactions_replace_the_contacts_of_the_collision_runs_only(drawn) -> None:
    result, logs = drawn
    runs = result.tables["runs"].set_index("role")
    count = DRAWN.scenarios[0].interactions
    assert (runs.loc["collision", "n_contacts"] == count).all()
    assert (runs.loc[["tuning", "free"], "n_contacts"] == 0).all()
    profiles = {"GuidingHand": "intended", "Clamp": "collision", "Impact": "collision"}
    for run in range(DRAWN.n_collision):
        log = read_log(logs / "panda-gaz" / f"collision-{run:03d}.parquet")
        for contact in log.metadata["collisions"]:
            assert profiles[contact["profile"]] == contact["kind"]


def test_interactions_that_cannot_fit_are_refused() -> None:
    with pytest.raises(InputValueError, match="interactions must be an integer"):
        BenchmarkConfig((BenchmarkScenario("panda-gaz", interactions=0),))
    with pytest.raises(InputValueError, match="random interactions may need"):
        BenchmarkScenario("panda-gaz", duration=6.0, interactions=2).load()


# --------------------------------------------------------------- a known push
def _push_scenario() -> Scenario:
    """A Panda held still at q0 by a stiff loop, pushed once on link 7 at a capsule point.

    The push of ``tests/test_isolation.py`` (its profile constants), as a
    scenario with the true model as the nominal one and ideal sensors.
    """
    robot = sl.robots.load("panda")
    surface = Isolator(robot).surfaces[7]
    q0 = np.array([0.2, -0.4, 0.3, -1.8, 0.4, 1.6, 0.5])
    point, normal = surface.points[60], surface.normals[60]
    side = np.cross([0.0, 0.0, 1.0], normal)  # tilted about the link axis: joint 7 feels it
    rotation = robot.link_pose(q0, 7)[:3, :3]
    direction = rotation @ (-math.cos(0.5) * normal + math.sin(0.5) * side)
    end = PLATEAU + HOLD + RELEASE + 0.2
    spec = {
        "name": "panda-push", "duration": end, "dt": 0.001, "seed": 1,
        "robot": "panda", "nominal_robot": "panda", "plant": {"type": "rigid"},
        "controller": {
            "type": "computed_torque", "bandwidth": 80.0, "damping_ratio": 1.0,
            "friction_compensation": False,
        },
        "trajectory": {"type": "via_points", "degrees": False, "points": [[0.0, *q0], [end, *q0]]},
        "collisions": [
            {
                "id": 1, "link": 7, "point": point.tolist(), "direction": direction.tolist(),
                "profile": "push", "start": RAMP_START, "ramp": RAMP, "hold": HOLD,
                "release": RELEASE, "peak": PEAK,
            }
        ],
    }  # fmt: skip
    validate_scenario(spec, "the push scenario")
    return Scenario("panda-push", spec)


def test_a_known_push_with_the_true_model_is_isolated() -> None:
    """Link, point and force within the bounds of ``test_true_model_push_is_isolated``.

    There: |F̂(t) − F| / F0 <= exp(−K_I (t − t_p)) + ε on the plateau (t >= t_p)
    and the point within POINT_TOLERANCE; here K_I is the gain the benchmark
    tuned, and the benchmark picks the sample (the event's peak).
    """
    config = BenchmarkConfig(
        (BenchmarkScenario(_push_scenario()),), methods=("constant",), oracle_method=None,
        n_tuning=1, n_collision=1, n_free=0,
    )  # fmt: skip
    result = run_benchmark(config, scheduler="serial")
    (row,) = result.tables["events"].itertuples(index=False)
    gain = result.tuned[("panda-push", "constant")].settings.gain
    assert row.contact == 1 and row.link_true == 7 and row.link == 7 and row.link_ok
    assert PLATEAU <= row.isolated_at <= PLATEAU + HOLD + RELEASE
    lag = math.exp(-gain * (row.isolated_at - PLATEAU))
    # ||F̂| − |F|| <= |F̂ − F|: the magnitude obeys the same bound.
    assert abs(row.force_error) <= (lag + EPSILON) * PEAK
    assert row.point_error <= POINT_TOLERANCE
    summary = result.contacts().iloc[0]
    assert summary["n_scored"] == 1 and summary["link_rate"] == 1.0
    assert summary["force_error_median"] == abs(row.force_error)


def test_without_isolation_the_new_columns_are_empty_and_the_rest_unchanged(drawn) -> None:
    result, _ = drawn
    off = run_benchmark(
        dataclasses.replace(DRAWN, isolation=False, n_collision=1, n_free=0), scheduler="serial"
    )
    events = off.tables["events"]
    assert events[list(CONTACT_COLUMNS)].isna().all().all()
    old = [c for c in COLUMNS["events"] if c not in CONTACT_COLUMNS]
    mine = result.tables["events"]
    first = mine[(mine["role"] == "collision") & (mine["run"] == 0)][old].reset_index(drop=True)
    pd.testing.assert_frame_equal(events[old].reset_index(drop=True), first, check_exact=True)
    assert off.contacts()["n_scored"].sum() == 0
