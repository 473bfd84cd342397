"""The benchmark's entry point and its result: :func:`run_benchmark` → :class:`BenchmarkResult`.

Summary columns (one row per scenario and detector; rates with intervals at
``config.confidence``):

* ``n_collisions``, ``n_detected``, ``detection_rate`` with its Wilson
  interval ``detection_low``/``detection_high``, over the collision runs;
* ``n_strong``, ``n_strong_detected``, ``strong_rate`` (``strong_low``,
  ``strong_high``): contacts with a peak force ≥ ``config.strong_force`` [N];
* ``free_hours``, ``n_false_alarms``, ``false_alarms_per_hour`` with its
  exact Poisson interval, over the judged time of the collision-free test
  runs; ``n_false_alarms_collision_runs`` for the collision runs;
* ``delay_median``, ``delay_p95``: start delay [s] over detected contacts;
  ``oracle_delay_median``, ``delay_ratio`` (median / the oracle's median on
  the same runs) and ``delay_excess`` (median over contacts both detect of
  the detector's delay minus the oracle's) [s];
* ``eff`` (mean over the monitored joints) and ``eff_joints``: eff = α/β of
  the time-variant families (Table 5.7), NaN elsewhere.

With ``config.isolation`` (the default), :meth:`BenchmarkResult.contacts`
gives the isolation and classification of the events of the collision runs
per scenario and detector (link rate with its Wilson interval, point and
force errors, accuracy: :func:`~.tables.contact_summary`) and
:meth:`BenchmarkResult.confusion` the confusion table
(:func:`~.tables.confusion_table`); the per-event values are columns of the
events table (:mod:`.contacts`).
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import pandas as pd

from .config import BenchmarkConfig, check_config
from .engine import Progress, execute
from .tables import (
    confusion_table,
    contact_summary,
    detection_by_force,
    record_tables,
    summary_table,
)
from .tasks import BeforeTask, Tuned, tuning_record

__all__ = ["BenchmarkResult", "run_benchmark"]


@dataclass(eq=False)
class BenchmarkResult:
    """What :func:`run_benchmark` measured.

    Attributes
    ----------
    config : BenchmarkConfig
    tables : dict of str to DataFrame
        ``runs``, ``results``, ``collisions``, ``events`` (:mod:`.tables`).
    tuned : dict
        ``{(scenario, label): Tuned}``: every tuned detector.
    timings : DataFrame
        One row per task: name, seconds, pid (not part of the results: it
        changes from run to run).
    workers : int
        Processes that ran tasks.
    """

    config: BenchmarkConfig
    tables: dict[str, pd.DataFrame]
    tuned: dict[tuple[str, str], Tuned]
    timings: pd.DataFrame
    workers: int

    def summary(self) -> pd.DataFrame:
        """One row per scenario and detector (columns: module docstring)."""
        return summary_table(self.tables, self.tuned, self.config)

    def by_force(self) -> pd.DataFrame:
        """Detection rate per peak-force bin with Wilson intervals (:func:`detection_by_force`)."""
        return detection_by_force(self.tables, self.config)

    def contacts(self) -> pd.DataFrame:
        """Isolation and classification per scenario and detector.

        See :func:`~.tables.contact_summary`; no scored events (NaN rates)
        with ``config.isolation`` False.
        """
        return contact_summary(self.tables, self.tuned, self.config)

    def confusion(self) -> pd.DataFrame:
        """True class × assigned class of the scored events (:func:`~.tables.confusion_table`)."""
        return confusion_table(self.tables, self.tuned)

    def write(self, out_dir: str | Path) -> dict[str, Path]:
        """Write every table (Parquet; summaries also CSV), the figures and ``index.html``.

        Returns
        -------
        dict of str to Path
            What was written, by name.
        """
        from .figures import write_figures
        from .index import write_index

        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        written: dict[str, Path] = {}
        for name, table in self.tables.items():
            written[name] = _parquet(table, out / f"{name}.parquet")
        summary, by_force = self.summary(), self.by_force()
        outputs = [("summary", summary), ("by_force", by_force)]
        contacts = confusion = None
        if self.config.isolation:
            contacts, confusion = self.contacts(), self.confusion()
            outputs += [("contacts", contacts), ("confusion", confusion)]
        for name, table in outputs:
            written[name] = _parquet(table, out / f"{name}.parquet")
            table.to_csv(out / f"{name}.csv", index=False)
            written[f"{name}_csv"] = out / f"{name}.csv"
        self.timings.to_csv(out / "tasks.csv", index=False)
        written["tasks"] = out / "tasks.csv"
        (out / "config.json").write_text(
            json.dumps(_config_dict(self.config), indent=2, default=str), encoding="utf-8"
        )
        written["config"] = out / "config.json"
        written.update(write_figures(summary, by_force, self.tables, out, contacts is not None))
        written["index"] = write_index(
            out, summary, by_force, written, self.config, contacts, confusion
        )
        return written


def _parquet(table: pd.DataFrame, path: Path) -> Path:
    table.to_parquet(path, index=False)
    return path


def _config_dict(config: BenchmarkConfig) -> dict[str, Any]:
    data = asdict(config)
    data["scenarios"] = [
        {**asdict(choice), "scenario": getattr(choice.scenario, "name", str(choice.scenario))}
        for choice in config.scenarios
    ]
    return data


def run_benchmark(
    config: BenchmarkConfig,
    *,
    scheduler: Any = "local",
    n_workers: int | None = None,
    retries: int = 2,
    log_dir: str | None = None,
    before_task: BeforeTask = None,
    progress: Progress | None = None,
) -> BenchmarkResult:
    """Run a detection benchmark: tune on N runs, judge on M collision and K collision-free runs.

    For every scenario of ``config``: ``n_tuning`` collision-free runs tune
    every detector (every method on every residual, and the oracle: the
    ``oracle_method`` family on the residual of the exact model,
    :meth:`~sensorless.simulation.scenario.Scenario.with_exact_model`, of the
    *same* runs); every detector then judges each of ``n_collision`` collision
    runs and ``n_free`` collision-free runs through
    :class:`~sensorless.monitor.CollisionMonitor` (settling window, compiled
    stream), scored by :func:`sensorless.evaluation.evaluate`. Every seed
    comes from ``config.master_seed`` (:func:`~sensorless.benchmark.plan_runs`).

    Parameters
    ----------
    config : BenchmarkConfig
    scheduler : "serial", "local", str or distributed.Client
        ``"serial"``: in this process; ``"local"``: a Dask ``LocalCluster`` of
        ``n_workers`` processes with one thread each; ``"tcp://host:port"``:
        that Dask scheduler; or a ``distributed.Client``. The results are the
        same for every scheduler.
    n_workers : int, optional
        Processes of the local cluster; default the CPU count.
    retries : int
        Times a failed task is run again (a killed worker's task is moved to
        another worker by the scheduler as well).
    log_dir : str, optional
        fsspec URL every simulated run's log (Parquet + sidecar) is written to.
    before_task : callable(str), optional
        Called with each task's name before it runs (instrumentation).
    progress : callable(done, total, name), optional
        Told each time a task finishes.

    Returns
    -------
    BenchmarkResult

    Notes
    -----
    The local cluster starts worker processes by spawning: a script that calls
    this with ``scheduler="local"`` needs the usual ``if __name__ == "__main__":``
    guard. Tasks are coarse (seconds each), so Dask's overhead per task (about a
    millisecond) does not matter; a tuning task holds all ``n_tuning`` logs of its
    scenario in memory.
    """
    raw = execute(
        check_config(config), scheduler=scheduler, n_workers=n_workers, retries=retries,
        log_dir=log_dir, before_task=before_task, progress=progress,
    )  # fmt: skip
    tables = record_tables([(s, tuning_record(s, log)) for s, log in raw.tuning], raw.records)
    timings = pd.DataFrame(
        [(t.name, t.name.split("/")[1], t.seconds, t.pid) for t in raw.timings],
        columns=["task", "kind", "seconds", "pid"],
    )
    return BenchmarkResult(config, tables, raw.tuned, timings, raw.workers)
