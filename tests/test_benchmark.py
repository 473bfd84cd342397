"""The detection benchmark: the oracle, seeds, Dask = serial, counts, a killed worker.

One tiny configuration (panda-gaz cut to 3 s: one random contact per
collision run; two methods; N = M = K = 2) is run once in this process and
twice on a two-process Dask ``LocalCluster``; every check compares against
that serial run or against a recount from the record tables.
"""

from __future__ import annotations

import dataclasses
import io
import json
import logging
import os
import sys
from pathlib import Path

import cloudpickle
import numpy as np
import pandas as pd
import pytest

from sensorless.benchmark import (
    BenchmarkConfig,
    BenchmarkScenario,
    plan_runs,
    run_benchmark,
    wilson_interval,
)
from sensorless.exceptions import InputValueError, UnknownNameError
from sensorless.friction import Sigmoid
from sensorless.io import read_log
from sensorless.monitor import ObserverSettings
from sensorless.simulation.scenario import load_scenario

distributed = pytest.importorskip("distributed")

TINY = BenchmarkConfig(
    (BenchmarkScenario("panda-gaz", duration=3.0),),
    methods=("constant", "time-variant"),
    n_tuning=2,
    n_collision=2,
    n_free=2,
    master_seed=3,
)
KILLED = "panda-gaz/collision/001"  # the task whose worker is killed once
FAILING = "panda-gaz/tune/constant"  # the task that raises once


# ----------------------------------------------------------------------- oracle
def _friction_fields(friction: object) -> dict[str, object]:
    return {f.name: np.asarray(getattr(friction, f.name)) for f in dataclasses.fields(friction)}


@pytest.mark.parametrize("name", ["panda-gaz", "puma560-thesis", "lwr4-thesis"])
def test_the_oracle_has_the_true_parameters_and_friction(name) -> None:
    scenario = load_scenario(name)
    true, nominal = scenario.with_exact_model().robots()
    original_true, original_nominal = scenario.robots()
    np.testing.assert_allclose(
        nominal.parameter_vector(), true.parameter_vector(), rtol=0, atol=1e-12
    )
    assert type(nominal.friction) is type(true.friction)
    for key, value in _friction_fields(true.friction).items():
        np.testing.assert_array_equal(_friction_fields(nominal.friction)[key], value)
    # The true robot is untouched, and the scenario's own nominal model did differ.
    np.testing.assert_array_equal(original_true.parameter_vector(), true.parameter_vector())
    differs = not np.allclose(original_nominal.parameter_vector(), true.parameter_vector())
    assert differs or type(original_nominal.friction) is not type(true.friction)


def test_the_oracle_on_a_flexible_plant_gives_exact_models_per_kind() -> None:
    scenario = load_scenario("lwr4-thesis")
    oracle = scenario.with_exact_model()
    true, _ = oracle.robots()
    joint = oracle.nominal("joint")
    # Link-side model: the true links, no armature, the plant's link friction unperturbed.
    assert np.all(joint.standard_parameters()["Ia"] == 0.0)
    link = scenario.spec["plant"]["link_friction"]
    np.testing.assert_array_equal(joint.friction.c_pos, link["c_pos"])
    np.testing.assert_array_equal(scenario.nominal("joint").friction.c_pos != link["c_pos"], True)
    # Motor side: the true links with the torque loop's apparent motor inertia as armature.
    motor = oracle.nominal("motor")
    inertia = scenario.spec["plant"]["feedback"]["motor_inertia"]
    np.testing.assert_array_equal(motor.standard_parameters()["Ia"], inertia)
    params = true.standard_parameters()
    for key, value in motor.standard_parameters().items():
        if key != "Ia":
            np.testing.assert_allclose(value, params[key], rtol=0, atol=1e-12)


def test_the_oracle_keeps_a_drift_free_spec_and_is_idempotent() -> None:
    scenario = load_scenario("panda-gaz")
    oracle = scenario.with_exact_model()
    assert oracle.spec["nominal_robot"] == "panda_gaz" and "model_error" not in oracle.spec
    assert oracle.with_exact_model().spec == oracle.spec
    assert oracle.with_duration(2.0).robots()[1].name == "panda_gaz"  # survives with_*
    assert isinstance(oracle.robots()[1].friction, Sigmoid)


def test_the_oracle_residual_is_much_smaller_on_a_collision_free_run() -> None:
    # Franka Panda: the user's URDF model has no friction; the true arm has the sigmoid
    # friction of Gaz et al. and slightly other base-link parameters.
    scenario = load_scenario("panda-gaz").with_duration(4.0)
    log = scenario.run(seed=2, collisions=False).log
    settings = ObserverSettings()
    keep = log.t - log.t[0] >= settings.settle_time(log.dt)
    nominal = settings.observe(log, scenario.nominal()).residual[keep]
    exact = settings.observe(log, scenario.with_exact_model().nominal()).residual[keep]
    rms_nominal, rms_exact = np.sqrt((nominal**2).mean(axis=0)), np.sqrt((exact**2).mean(axis=0))
    # Measured on this run: RMS over all joints 0.22 N m (nominal) and 0.077 N m (exact);
    # per joint the exact one is 0.02-0.6 times the nominal one. What is left is the
    # encoder quantisation through the velocity estimate, largest on joints 1-4.
    assert np.sqrt((exact**2).mean()) < 0.5 * np.sqrt((nominal**2).mean())
    assert (rms_exact < 0.8 * rms_nominal).all()
    # The wrist (joints 5-7), where friction is most of the model error: peaks 0.17-0.26
    # N m with the nominal model, below 0.035 N m with the exact one.
    assert (np.abs(exact[:, 4:]).max(axis=0) < 0.25 * np.abs(nominal[:, 4:]).max(axis=0)).all()


# ------------------------------------------------------------------------ seeds
def test_seeds_are_stable_distinct_and_per_role() -> None:
    runs = plan_runs(TINY)
    assert [s.key for s in runs] == [
        "panda-gaz/tuning/000", "panda-gaz/tuning/001", "panda-gaz/collision/000",
        "panda-gaz/collision/001", "panda-gaz/free/000", "panda-gaz/free/001",
    ]  # fmt: skip
    assert len({s.seed for s in runs}) == len(runs)
    bigger = BenchmarkConfig(TINY.scenarios, n_tuning=5, n_collision=4, n_free=1, master_seed=3)
    seeds = {s.key: s.seed for s in plan_runs(bigger)}
    assert all(seeds[s.key] == s.seed for s in runs if s.key in seeds)
    other = BenchmarkConfig(TINY.scenarios, n_tuning=2, n_collision=2, n_free=2, master_seed=4)
    assert not {s.seed for s in plan_runs(other)} & {s.seed for s in runs}


def test_wilson_interval_matches_its_closed_form() -> None:
    k, n, z = 7, 19, 1.959963984540054
    p = k / n
    centre = (p + z**2 / (2 * n)) / (1 + z**2 / n)
    half = z / (1 + z**2 / n) * np.sqrt(p * (1 - p) / n + z**2 / (4 * n**2))
    np.testing.assert_allclose(wilson_interval(k, n), (centre - half, centre + half), rtol=1e-9)
    assert all(np.isnan(wilson_interval(0, 0)))


def test_bad_configurations_are_refused() -> None:
    with pytest.raises(UnknownNameError, match="unknown methods"):
        BenchmarkConfig(TINY.scenarios, methods=("bogus",))
    with pytest.raises(InputValueError, match="force_bins"):
        BenchmarkConfig(TINY.scenarios, force_bins=(10.0, 5.0))
    with pytest.raises(InputValueError, match="n_tuning"):
        BenchmarkConfig(TINY.scenarios, n_tuning=0)
    with pytest.raises(InputValueError, match="residuals"):
        BenchmarkConfig((BenchmarkScenario("panda-gaz", residuals=("torque",)),))
    with pytest.raises(InputValueError, match="scheduler must be"):
        run_benchmark(TINY, scheduler="cluster")


# -------------------------------------------------------------------- the runs
@pytest.fixture(scope="module")
def serial(tmp_path_factory):
    logs = tmp_path_factory.mktemp("logs")
    return run_benchmark(TINY, scheduler="serial", log_dir=f"file://{logs}"), logs


@pytest.fixture(scope="module")
def client():
    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
            silence_logs=logging.ERROR,
        ) as cluster,
        distributed.Client(cluster) as connected,
    ):  # fmt: skip
        yield connected


def _parquet(table: pd.DataFrame) -> bytes:
    buffer = io.BytesIO()
    table.to_parquet(buffer, index=False)
    return buffer.getvalue()


def _assert_same(result, reference) -> None:
    for name, table in reference.tables.items():
        pd.testing.assert_frame_equal(result.tables[name], table, check_exact=True)
        assert _parquet(result.tables[name]) == _parquet(table), name
    assert _parquet(result.summary()) == _parquet(reference.summary())
    assert _parquet(result.by_force()) == _parquet(reference.by_force())
    # The events table holds the isolation and classification columns; their summaries:
    assert _parquet(result.contacts()) == _parquet(reference.contacts())
    assert _parquet(result.confusion()) == _parquet(reference.confusion())


def test_dask_equals_serial_byte_for_byte(serial, client) -> None:
    reference, _ = serial
    result = run_benchmark(TINY, scheduler=client.scheduler.address)  # "tcp://127.0.0.1:port"
    assert os.getpid() not in set(result.timings["pid"])  # the tasks ran in the workers
    _assert_same(result, reference)


class _Faults:
    """Kills the worker of one task and makes another raise, the first time each runs."""

    def __init__(self, folder: Path) -> None:
        self.folder = folder

    def __call__(self, name: str) -> None:
        if name not in (KILLED, FAILING):
            return
        slug = name.replace("/", "_")
        with open(self.folder / f"{slug}.attempts", "a") as attempts:
            attempts.write(f"{os.getpid()}\n")
        marker = self.folder / f"{slug}.done"
        if marker.exists():
            return
        marker.touch()
        if name == KILLED:
            os._exit(1)  # the worker process dies mid-task; its nanny starts a new one
        raise RuntimeError("a transient failure")


def test_a_killed_worker_and_a_failing_task_are_retried_with_the_same_result(
    serial, client, tmp_path
) -> None:
    reference, _ = serial
    cloudpickle.register_pickle_by_value(sys.modules[__name__])  # workers cannot import tests
    try:
        result = run_benchmark(TINY, scheduler=client, retries=2, before_task=_Faults(tmp_path))
    finally:
        cloudpickle.unregister_pickle_by_value(sys.modules[__name__])
    killed = (tmp_path / f"{KILLED.replace('/', '_')}.attempts").read_text().split()
    failed = (tmp_path / f"{FAILING.replace('/', '_')}.attempts").read_text().split()
    # Run again in another process; a task whose result the dead worker held runs
    # once more (the scheduler recomputes lost results), hence "at least".
    assert len(killed) >= 2 and len(set(killed)) >= 2
    assert len(failed) >= 2
    _assert_same(result, reference)


# ---------------------------------------------------------------- the numbers
def test_the_summary_counts_equal_a_recount_from_the_event_table(serial) -> None:
    result, _ = serial
    events, tables = result.tables["events"], result.tables
    summary = result.summary().set_index("method")
    collisions = tables["collisions"]
    for method, row in summary.iterrows():
        mine = events[events["method"] == method]
        alarms = mine[(mine["outcome"] == "false_alarm") & (mine["role"] == "free")]
        assert row["n_false_alarms"] == len(alarms)
        # Detected contacts: the (run, id) pairs some detection event names.
        hits = {
            (run, int(ident))
            for run, names in mine.loc[
                mine["outcome"] == "detection", ["run", "collisions"]
            ].itertuples(index=False)
            for ident in names.split(",")
        }
        assert row["n_detected"] == len(hits)
        assert row["n_collisions"] == (collisions["method"] == method).sum() == TINY.n_collision
        strong = collisions[(collisions["method"] == method) & (collisions["peak_force"] >= 20.0)]
        assert row["n_strong"] == len(strong)
        hours = result.tables["results"].query("method == @method and role == 'free'")
        assert row["free_hours"] == pytest.approx(hours["judged_seconds"].sum() / 3600)
    by_force = result.by_force()
    for method, group in by_force.groupby("method"):
        assert group["n"].sum() == summary.loc[method, "n_collisions"]
        assert group["n_detected"].sum() == summary.loc[method, "n_detected"]


def test_the_oracle_is_never_later_than_a_method_beyond_the_filter_delay(serial) -> None:
    result, _ = serial
    collisions = result.tables["collisions"].set_index(["run", "collision"])
    settings = ObserverSettings()
    dt = 1e-3
    # Both watch the same contact through the same K_I/(s+K_I) observer: a method whose
    # model error happens to add to the contact can cross its bound sooner, by at most
    # the time the oracle's residual needs to rise through its band, 1/K_I for a
    # contact above it; plus two samples for the event's first and second sample.
    tolerance = 1.0 / settings.gain + 2 * dt
    oracle = collisions[collisions["method"] == "oracle"]
    compared = 0
    for method in TINY.methods:
        mine = collisions[collisions["method"] == method]
        both = mine["detected"] & oracle["detected"].reindex(mine.index)
        excess = oracle["start_delay"][both] - mine["start_delay"][both]
        assert (excess <= tolerance).all(), (method, excess.max())
        compared += int(both.sum())
    assert compared >= 2


def test_without_interactions_the_collision_runs_are_the_scenarios_own(serial) -> None:
    result, logs = serial
    assert TINY.scenarios[0].interactions is None
    spec = next(s for s in plan_runs(TINY) if s.role == "collision")
    written = read_log(logs / "panda-gaz" / f"collision-{spec.index:03d}.parquet")
    again = TINY.scenarios[0].load().run(seed=spec.seed, collisions=True).log
    assert written.metadata["collisions"] == json.loads(json.dumps(again.metadata["collisions"]))
    np.testing.assert_array_equal(written.tau_m, again.tau_m)
    runs = result.tables["runs"].set_index(["role", "run"])
    assert runs.loc[("collision", spec.index), "n_contacts"] == len(again.metadata["collisions"])


def test_the_logs_go_through_fsspec_and_the_outputs_are_written(serial, tmp_path) -> None:
    result, logs = serial
    written = sorted(p.relative_to(logs).as_posix() for p in logs.rglob("*.parquet"))
    assert written == sorted(f"panda-gaz/{s.role}-{s.index:03d}.parquet" for s in plan_runs(TINY))
    paths = result.write(tmp_path / "out")
    summary = pd.read_csv(paths["summary_csv"])
    assert list(summary["method"]) == ["constant", "time-variant", "oracle"]
    assert pd.read_parquet(paths["events"]).equals(result.tables["events"])
    for name in ("detection_vs_force", "delays", "false_alarms", "force_estimates"):
        assert paths[name].read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    page = paths["index"].read_text(encoding="utf-8")
    names = ("summary", "events", "delays", "contacts", "confusion", "force_estimates")
    assert all(paths[name].name in page for name in names)
    assert pd.read_csv(paths["confusion_csv"]).equals(result.confusion())
