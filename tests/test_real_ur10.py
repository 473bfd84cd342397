"""The real-arm recipe (``sensorless.realarm``, ``examples/ur10_real_arm.py``) on the real UR10.

The recordings (``../shared/data/ur10-ext_observer``, see its README) are not
part of the repository; without them every test here is skipped. The tests run
the recipe's steps: import with the shipped spec (units checked against
the physics: the measured q̇ is the derivative of q in rad/s, torques are
within the UR10's ratings), the friction and offset identified on one half of
``link4.csv`` (it must predict the other half better than the bare URDF), the
observer residual of the standing arm (bounded), and the whole two-fold
cross-validation with its false-alarm table. They assert no false-alarm figure:
those are the example's output, not a property of the library.

Figures measured when these tests were written (fold models from a half of
``link4.csv``, the final model from all of it, apparent contacts left out):

- held-out RMS of τ_m − τ_model on joints 1–3 [N m]: URDF 15.2, 17.9, 9.0 and
  17.7, 15.6, 10.0; corrected 7.4, 12.6, 5.9 and 4.3, 4.6, 1.2 (folds 1, 2);
- largest |r̂| on ``ur-static.csv`` with the final model [N m]: 35.1, 29.1,
  43.6, 5.5, 3.5, 0.4 over the whole file (the apparent pushes of 15–40 N m
  included), 16.4, 14.5, 9.3, 3.8, 1.7, 0.4 between them.
"""

from __future__ import annotations

import importlib.util
import math
import sys
from pathlib import Path
from types import ModuleType

import numpy as np
import pytest

import sensorless as sl
from sensorless.exceptions import InputTypeError
from sensorless.identification import identify_correction
from sensorless.identification.correction import model_error
from sensorless.identification.logs import savgol_derivatives
from sensorless.plots import plot_held_out
from sensorless.realarm import (
    DEFAULT_FAMILIES,
    RealArmEvaluation,
    Recording,
    evaluate_folds,
    load_ur10,
    standing_residual,
    ur10_folds,
)

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "ur10-ext_observer"
EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "ur10_real_arm.py"

pytestmark = pytest.mark.skipif(
    not DATA.is_dir(), reason=f"the real UR10 recordings are absent (expected in {DATA})"
)

UR10_RATED_TORQUE = np.array([330.0, 330.0, 150.0, 56.0, 56.0, 56.0])
"""Rated joint torques of the UR10 [N m] (UR10 technical specifications)."""


@pytest.fixture(scope="module")
def example() -> ModuleType:
    spec = importlib.util.spec_from_file_location("ur10_real_arm", EXAMPLE)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up here
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def recordings() -> dict[str, Recording]:
    return load_ur10(DATA)


@pytest.fixture(scope="module")
def robot() -> sl.RobotModel:
    return sl.robots.load("ur10")


@pytest.fixture(scope="module")
def evaluation(recordings: dict, robot: sl.RobotModel) -> RealArmEvaluation:
    return evaluate_folds(ur10_folds(recordings), robot)


def test_import_gives_the_four_files_in_si_units(recordings: dict) -> None:
    assert list(recordings) == [
        "link4.csv",
        "ur-static.csv",
        "no_torque.csv",
        "3times.csv#1",
        "3times.csv#2",
    ]
    for name, recording in recordings.items():
        log = recording.log
        assert log.groups == ["q", "qd", "tau_m"], name
        assert np.allclose(np.diff(log.t), 0.01, rtol=0, atol=1e-9), name
        assert np.abs(log.q).max() <= 2 * math.pi, name
        assert np.abs(log.qd).max() < math.pi, name  # UR10 joints: at most 180 °/s
        assert (np.abs(log.tau_m).max(axis=0) < UR10_RATED_TORQUE).all(), name
        source = log.metadata["import"]
        assert source["source_units"] == {"t": "s", "q": "rad", "qd": "rad/s", "tau_m": "A"}
        assert source["conversions"]["tau_m"]["unit"] == "N m/A"
    # 3times.csv has a 1.1 s hole: two segments on the file's own clock, not one bridged log.
    first, second = recordings["3times.csv#1"].log, recordings["3times.csv#2"].log
    assert second.t[0] - first.t[-1] == pytest.approx(1.114, abs=0.01)


def test_measured_velocity_is_the_derivative_of_the_position(recordings: dict) -> None:
    # In rad/s, not deg/s or rad per sample: it matches dq/dt of the positions.
    for name in ("link4.csv", "no_torque.csv"):
        log = recordings[name].log
        qd, _ = savgol_derivatives(log.q, log.dt, 0.05)
        inner = slice(5, -5)
        error = np.sqrt(np.mean((qd[inner] - log.qd[inner]) ** 2, axis=0))
        assert (error < 0.01).all(), (name, error)
        assert np.abs(log.qd).max() > 0.1, name  # the arm moves in these two


def test_friction_and_offset_predict_the_held_out_half_better(
    recordings: dict, robot: sl.RobotModel
) -> None:
    for fold in ur10_folds(recordings):
        (train,), held_out = fold.identification, fold.held_out
        assert train.name.startswith("link4.csv") and held_out[0].name.startswith("link4.csv")
        correction = identify_correction(train.clean_pieces(), robot)
        friction = correction.friction
        assert (friction.c_pos >= 0).all() and (friction.c_neg <= 0).all()
        assert (friction.fv >= 0).all()
        # Joint 6 never moves in link4.csv: no friction is invented for it.
        assert friction.c_pos[5] == friction.c_neg[5] == friction.fv[5] == 0.0
        test = [correction.apply(log) for log in held_out[0].clean_pieces()]
        error, velocity, _ = model_error(test, robot)
        corrected = error - correction.model(robot).friction_torque(velocity)
        bare, _, _ = model_error(held_out[0].clean_pieces(), robot)
        rms_corrected = np.sqrt(np.mean(corrected**2, axis=0))
        rms_bare = np.sqrt(np.mean(bare**2, axis=0))
        assert (rms_corrected[:3] < 0.8 * rms_bare[:3]).all(), (rms_corrected, rms_bare)


def test_standing_arm_residual_stays_bounded(recordings: dict, robot: sl.RobotModel) -> None:
    correction = identify_correction(recordings["link4.csv"].clean_pieces(), robot)
    peaks = standing_residual(recordings, robot, correction)
    assert np.isfinite(peaks.to_numpy()).all()
    whole = peaks.loc["corrected, whole file"].to_numpy()
    between = peaks.loc["corrected, between contacts"].to_numpy()
    # Measured 35.1, 29.1, 43.6, 5.5, 3.5, 0.4 and 16.4, 14.5, 9.3, 3.8, 1.7, 0.4 N m.
    assert (whole <= [60.0, 60.0, 60.0, 10.0, 10.0, 10.0]).all(), whole
    assert (between <= [25.0, 25.0, 25.0, 6.0, 6.0, 6.0]).all(), between


def test_cross_validation_reports_a_finite_false_alarm_rate_per_family(
    evaluation: RealArmEvaluation, robot: sl.RobotModel
) -> None:
    assert [fold.fold for fold in evaluation.folds] == [1, 2]
    for fold in evaluation.folds:
        held_out = {run.name for run in fold.held_out}
        assert len(held_out) == 5 and any(name.startswith("link4.csv") for name in held_out)
        for run in fold.held_out:
            assert run.signals.residual.shape == (run.log.n_samples, robot.n_dof)
            for lower, upper in run.bounds.values():
                assert lower.shape == upper.shape == run.signals.residual.shape
    table = evaluation.summary()
    assert list(table.index) == list(DEFAULT_FAMILIES)
    for family, row in table.iterrows():
        # Both link4 halves (~17 s), twice 15 s standing, twice 5.4 s of no_torque.csv, ...
        assert row["held-out [s]"] > 50.0, family
        alarms, rate = int(row["false alarms"]), float(row["per hour"])
        assert alarms >= 0 and math.isfinite(rate), family
        assert rate == pytest.approx(alarms / (row["held-out [s]"] / 3600.0))
        assert row["95 % low"] <= rate <= row["95 % high"], family
        bands = row[[f"band {j}" for j in range(1, robot.n_dof + 1)]].to_numpy(dtype=float)
        assert (np.isfinite(bands) & (bands > 0)).all(), family
    # The rounded table for a person says the same.
    readable = evaluation.summary(readable=True)
    for family, row in readable.iterrows():
        low, high = (float(v) for v in row["95 % interval"].split("-"))
        assert low == pytest.approx(table.loc[family, "95 % low"], abs=0.5)
        assert high == pytest.approx(table.loc[family, "95 % high"], abs=0.5)
        assert row["per hour"] == pytest.approx(table.loc[family, "per hour"], abs=0.5)
        assert len(row["tune expects [1/h]"].split(" / ")) == 2
    # The per-recording table adds up to the pooled one.
    details = evaluation.details()
    for family in DEFAULT_FAMILIES:
        counts = details[family].str.extract(r"(\d+) \((\d+)\)").astype(int)
        assert counts[0].sum() == table.loc[family, "false alarms"]
        assert counts[1].sum() == table.loc[family, "at contacts"]


def test_a_held_out_run_plots_its_residual_against_every_family(
    evaluation: RealArmEvaluation,
) -> None:
    run = evaluation.held_out(1, "ur-static.csv rest")
    figure = plot_held_out(run, joints=(1, 2))
    assert len(figure.axes) == 2
    first = figure.axes[0]
    # 3408 samples: r̂ is drawn as its min/max envelope over buckets (a filled band) that
    # reaches the residual's extremes, each family's bounds as upper and lower lines.
    band = np.vstack([path.vertices for path in first.collections[0].get_paths()])
    residual = run.signals.residual[:, 0]
    assert band[:, 1].min() == residual.min() and band[:, 1].max() == residual.max()
    assert len(first.lines) == 2 * len(DEFAULT_FAMILIES)
    assert len(first.patches) == len(run.log.metadata["collisions"]) == 3  # apparent contacts
    assert "fold 1: ur-static.csv rest" in figure.get_suptitle()
    with pytest.raises(InputTypeError, match="run must be a HeldOutRun"):
        plot_held_out(run.signals)  # type: ignore[arg-type]
    with pytest.raises(KeyError, match="no held-out run"):
        evaluation.held_out(3, "link4.csv")


def test_the_script_runs_end_to_end_and_writes_its_plots(
    example: ModuleType, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert example.main(["--data", str(DATA), "--output", str(tmp_path)]) == 0
    printed = capsys.readouterr().out
    assert "Held-out false alarms, both folds pooled" in printed
    for family in DEFAULT_FAMILIES:
        assert f"\n{family} " in printed
    plots = sorted(path.name for path in tmp_path.glob("*.png"))
    assert len(plots) == 10 and "fold1_link4_second_half.png" in plots


def test_every_backend_and_a_compiled_loop_judge_the_real_arm_alike(
    recordings: dict, robot: sl.RobotModel
) -> None:
    """On ``ur-static.csv`` (4544 samples at 100 Hz, four apparent pushes): the stream on
    the numba, numpy and Python backends and the step in a user's numba loop give the same
    statuses and residuals (numpy to 1e-9 N m); the batches the same events and residuals.

    Measured: numba = Python = the loop bit for bit, numpy within 7.3e-13 N m; four events.
    """
    pytest.importorskip("numba")
    from numba import njit

    tuned = sl.tune(recordings["link4.csv"].clean_pieces(), robot, "time-variant", folds=None)
    log = recordings["ur-static.csv"].labelled()
    backends = ("numba", "numpy", "python")
    monitors = {b: sl.CollisionMonitor(robot, *tuned, backend=b) for b in backends}
    t, q, tau = (np.ascontiguousarray(a) for a in (log.t, log.q, log.tau_m))
    streams = {}
    for backend, monitor in monitors.items():
        verdicts = [monitor.step(t[k], q[k], tau[k]) for k in range(t.size)]
        streams[backend] = ([v.status for v in verdicts], np.array([v.residual for v in verdicts]))

    @njit
    def loop(function, model, buffers, t, q, tau, codes, residuals):  # type: ignore[no-untyped-def]
        out = np.empty((3, q.shape[1]))
        for k in range(t.shape[0]):
            codes[k] = function(t[k], q[k], tau[k], tau[k], model, buffers, out)
            residuals[k] = out[0]

    numba = monitors["numba"]
    numba.reset()
    codes, residuals = np.zeros(t.size, dtype=np.int64), np.zeros_like(q)
    loop(*numba.compiled_step(), t, q, tau, codes, residuals)
    statuses = streams["numba"][0]
    assert {"settling", "ok", "collision"} <= set(statuses)
    assert statuses == streams["numpy"][0] == streams["python"][0]
    assert [sl.monitor.CompiledStep.reason(int(code)) for code in codes] == statuses
    np.testing.assert_array_equal(residuals, streams["numba"][1])
    np.testing.assert_array_equal(streams["python"][1], streams["numba"][1])
    np.testing.assert_allclose(streams["numpy"][1], streams["numba"][1], rtol=0.0, atol=1e-9)
    runs = {backend: monitor.process(log) for backend, monitor in monitors.items()}
    keys = {b: [(e.start, e.end, e.joints) for e in run.events] for b, run in runs.items()}
    assert keys["numba"] == keys["numpy"] == keys["python"] and len(keys["numba"]) >= 1
    for backend in ("numpy", "python"):
        np.testing.assert_allclose(
            runs[backend].signals.residual, runs["numba"].signals.residual, rtol=0.0, atol=1e-9
        )
