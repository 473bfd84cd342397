"""Collision monitoring on a real arm: the UR10 recordings of ext_observer.

Run from the repository (about 5 s, 10 s with the plots; ``--help`` for the options)::

    .venv/bin/python examples/ur10_real_arm.py --output out/ur10

The data are four recordings of a Universal Robots UR10 (MIT-licensed project
ext_observer, kept in ``../shared/data/ur10-ext_observer``; see its README):
100 Hz with jittery time stamps, joint positions, the velocities the
controller measures, and motor currents that become torques through UR's
current-to-torque gains. They carry no collision labels.

The recipe
----------
1. **Import** every file with the column-mapping CSV importer and its shipped
   spec, ``sensorless.io.import_log("csv", path, spec="ur10_ext_observer")``:
   the jitter is resampled onto a 10 ms grid, and the 1.1 s gap of
   ``3times.csv`` splits it into two segments instead of being bridged.
2. **A better nominal model from** ``link4.csv`` **only.** The built-in
   ``ur10`` (the URDF of ``example-robot-data``) has no friction; on the real
   arm the torque it predicts misses by 9–27 N m RMS on joints 1–3 in motion. The
   library's inertial identification
   (:func:`~sensorless.identification.identify_from_logs`, then
   :func:`~sensorless.identification.consistent_parameters`) needs rich
   excitation: ten seconds of ``link4.csv`` (a few constant-velocity moves)
   leave its 40 base parameters ill-conditioned (condition number 5·10⁴), and
   its model misses the held-out half by over 100 N m RMS on joint 2. So the
   URDF's rigid-body model stays, and what it lacks is identified joint by
   joint from its error e = τ_m − τ_model(q, q̇, q̈), with q̇ the measured
   velocity (the one the observer uses) and q̈ from a zero-phase
   Savitzky–Golay fit (:func:`~sensorless.identification.logs.savgol_derivatives`):

   - a **torque offset** o_j: the median of e_j while joint j rests
     (|q̇_j| < 5 mrad/s for at least 0.5 s of the data; else 0). The library's
     friction models give 0 at rest, so an offset cannot live in them; it is
     taken off the measured torque instead, ``tau_m − o``
     (:meth:`NominalCorrection.apply`), before the observer sees it, and a
     live monitor would take it off the stream the same way;
   - **asymmetric Coulomb and viscous friction** (C+ ≥ 0, C− ≤ 0, F_v ≥ 0) by
     bounded least squares (:func:`scipy.optimize.lsq_linear`) on the moving
     samples of e_j − o_j, attached to the model as a
     :class:`~sensorless.friction.CoulombViscous` through
     :meth:`~sensorless.robots.RobotModel.with_standard_parameters`. C+ ≠ −C−
     carries the offset of a moving joint. A direction in which the joint moved
     for less than 0.5 s gets the mirror of the other one; a joint that never
     moved (joint 6 here) gets no friction.
3. **Two-fold cross-validation.** ``link4.csv`` is cut into two halves in
   time. For each fold, the correction is identified on the training half
   only, and each threshold family (constant, time-variant with the demo's
   minimax fit, velocity) is tuned with :func:`sensorless.monitor.tune` on the
   training half plus the first quarter of ``ur-static.csv``, with the demo's
   margin: 10 % of the constant β of the same tuning data, per joint. The
   :class:`~sensorless.monitor.CollisionMonitor` then runs on everything held
   out: the other half of ``link4.csv``, the remaining three quarters of
   ``ur-static.csv``, ``no_torque.csv`` and both segments of ``3times.csv``.
4. **The table**: per family, the held-out collision-free seconds the monitor
   judged (the 0.25 s settling after each start is not judged), the false
   alarms, the rate per hour with the exact 95 % Poisson interval (both folds
   pooled; the files held out in both folds count twice and their two counts
   are not independent, so the interval is too narrow), the alarms at
   apparent contacts (below), the rate that ``tune``'s own cross-validation
   of each fold's tuning data expects, and the mean band width (upper − lower
   bound) per joint.
5. **Plots** (``--output``): the residual of every held-out recording
   against the three families' bounds, apparent contacts shaded
   (:func:`sensorless.plots.plot_residuals`).

What the recordings show
------------------------
The source calls them collision-free, but ext_observer is a library of
*external-torque* observers, and two files look like its test cases:

- in ``ur-static.csv`` the arm holds its pose (|q − q₀| < 0.1 mrad) while the
  torque of joints 1–3 steps by 15–40 N m four times, stays there for 2.5–5 s
  and steps back; at each release the arm springs out by ~2 mrad and the
  controller pulls it back, as when a hand lets go of the arm;
- in ``link4.csv`` the residual of every model tried shows two 0.6 s pulses
  of 15–23 N m on joints 1–3 together (at 3.5 s and 9.6 s) in
  constant-velocity motion, and joint 1's velocity dips at the first.

These six spans are :data:`APPARENT_CONTACTS`, read off the residuals by eye
and generously; they are not ground truth. By default they are left out of
the identification and tuning data, an alarm at one of them is counted
apart, not as a false alarm, and the held-out time excludes them.
``--every-alarm-false`` drops the list: everything is tuned on, every alarm
is false.

What a run says (the figures are printed, not promised): 15–20 s of
tuning data give held-out false-alarm rates of 750–950 per hour (1100–1500
with ``--every-alarm-false``), from under a minute of held-out data per
fold. The alarms come from what the tuning data did not show: the hard stop
at the end of ``link4.csv`` and ``no_torque.csv`` (the residual rings by
±25 N m), the faster motion of ``no_torque.csv`` (1 rad/s against 0.3 in
``link4.csv``, so F_v is extrapolated) and the other poses of ``3times.csv``
(one alarm in each 0.1 s judged). The offset found at ``link4.csv``'s poses
does not carry over to the standing pose of ``ur-static.csv``: there the
corrected model's residual between contacts is larger than the URDF's
(the URDF's gravity is off by a pose-dependent amount, which no constant
mends). And the Coulomb term switches at any nonzero velocity, also at the
10⁻⁶–10⁻⁴ rad/s the controller reports now and then for a standing arm (4 %
of the samples of ``ur-static.csv``): each such sample kicks the residual by C±.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import NDArray
from scipy.optimize import lsq_linear

import sensorless as sl
from sensorless.evaluation import evaluate
from sensorless.friction import CoulombViscous
from sensorless.identification.logs import savgol_derivatives, window_samples
from sensorless.io import Log, import_log
from sensorless.monitor import (
    CollisionMonitor,
    MonitorRun,
    ObserverSettings,
    calibration_of,
    poisson_interval,
    tune,
)
from sensorless.plots import plot_residuals
from sensorless.robots import RobotModel
from sensorless.signals import Event
from sensorless.thresholds import ConstantThreshold, Threshold

FloatArray = NDArray[np.float64]

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "ur10-ext_observer"
"""Default folder of the recordings: ``shared/data/ur10-ext_observer`` beside the repository."""
FILES = ("link4.csv", "ur-static.csv", "no_torque.csv", "3times.csv")
SPEC = "ur10_ext_observer"
"""Import spec shipped with the library for these files."""
FAMILIES = ("constant", "time-variant", "velocity")
MARGIN_FRACTION = 0.1
"""Margin of every family as a fraction of the constant β per joint (the demo's recipe)."""
SAVGOL_WINDOW = 0.1
"""Savitzky–Golay window [s] for q̈ in the identification."""
RESTING = 0.005
"""Speed [rad/s] below which a joint counts as resting."""
MIN_TIME = 0.5
"""Data [s] a joint needs at rest (offset) or in a direction (Coulomb level) to identify it."""
STATIC_TUNING = 0.25
"""Fraction of ``ur-static.csv`` (from its start) used for tuning; the rest is held out."""
MIN_PIECE = 1.0
"""Shortest piece [s] of tuning data kept between two apparent contacts."""
APPARENT_CONTACTS: dict[str, tuple[tuple[float, float], ...]] = {
    "link4.csv": ((3.4, 4.3), (9.4, 10.2)),
    "ur-static.csv": ((3.0, 6.6), (11.5, 16.6), (25.2, 31.6), (37.8, 44.0)),
}
"""Spans [s] (time from the file's first sample) that look like a hand on the arm."""

Windows = tuple[tuple[float, float], ...]
Bounds = tuple[FloatArray, FloatArray]


@dataclass(frozen=True)
class Recording:
    """One imported segment of a file and the apparent contacts in it.

    Attributes
    ----------
    name : str
        File name, with ``#k`` for the k-th segment of a file cut at a gap.
    log : Log
        The segment (time [s] from the file's first sample).
    contacts : tuple of (float, float)
        Apparent contacts [s] inside the segment.
    """

    name: str
    log: Log
    contacts: Windows = ()

    def part(self, start: float | None, stop: float | None, suffix: str) -> Recording:
        """The samples with ``start <= t < stop`` [s] (None: unbounded)."""
        log = self.log.slice(start, stop)
        lo, hi = float(log.t[0]), float(log.t[-1])
        inside = tuple((a, b) for a, b in self.contacts if b >= lo and a <= hi)
        return Recording(f"{self.name} {suffix}", log, inside)

    def clean_pieces(self) -> list[Log]:
        """The stretches between apparent contacts that last at least :data:`MIN_PIECE`."""
        edges = [float(self.log.t[0]), *[v for span in self.contacts for v in span]]
        edges.append(float(self.log.t[-1]) + self.log.dt)
        pieces = []
        for start, stop in zip(edges[::2], edges[1::2], strict=True):
            if stop - start >= MIN_PIECE:
                pieces.append(self.log.slice(start, stop))
        return pieces

    def labelled(self) -> Log:
        """The log with its apparent contacts as collision windows (for scoring and plots)."""
        collisions = [{"id": k + 1, "start": a, "end": b} for k, (a, b) in enumerate(self.contacts)]
        return dataclasses.replace(
            self.log, metadata={**self.log.metadata, "collisions": collisions}
        )


def load_recordings(
    folder: Path, contacts: Mapping[str, Windows] = APPARENT_CONTACTS
) -> dict[str, Recording]:
    """Import the four files of ``folder``: one :class:`Recording` per segment, by name."""
    recordings: dict[str, Recording] = {}
    for name in FILES:
        segments = import_log("csv", folder / name, spec=SPEC)
        for k, log in enumerate(segments):
            label = name if len(segments) == 1 else f"{name}#{k + 1}"
            recordings[label] = Recording(label, log, tuple(contacts.get(name, ())))
    return recordings


@dataclass(frozen=True)
class NominalCorrection:
    """What the recordings add to the URDF model: friction and a torque offset.

    Attributes
    ----------
    friction : CoulombViscous
        Joint friction (C+ [N m], C− [N m], F_v [N m s/rad]).
    offset : ndarray of shape (n_dof,)
        Offset of the measured motor torque [N m], taken off ``tau_m``.
    """

    friction: CoulombViscous
    offset: FloatArray

    def model(self, robot: RobotModel) -> RobotModel:
        """``robot`` with this friction (rigid-body parameters unchanged)."""
        return robot.with_standard_parameters(
            robot.standard_parameters(), friction=self.friction, name=f"{robot.name}+friction"
        )

    def apply(self, log: Log) -> Log:
        """``log`` with the offset taken off its motor torques."""
        if log.tau_m is None:
            raise ValueError("the log has no motor torques tau_m")
        metadata = {**log.metadata, "tau_m_offset": [float(v) for v in self.offset]}
        return dataclasses.replace(log, tau_m=log.tau_m - self.offset, metadata=metadata)

    def to_pandas(self) -> pd.DataFrame:
        """One row per joint: C+, C− [N m], F_v [N m s/rad], offset [N m]."""
        return pd.DataFrame(
            {
                "C+ [N m]": self.friction.c_pos,
                "C- [N m]": self.friction.c_neg,
                "Fv [N m s/rad]": self.friction.fv,
                "offset [N m]": self.offset,
            },
            index=pd.Index(range(1, self.offset.size + 1), name="joint"),
        )


def model_error(logs: Sequence[Log], robot: RobotModel) -> tuple[FloatArray, FloatArray]:
    """τ_m − τ_model(q, q̇, q̈) [N m] and the measured q̇ [rad/s] of the logs, stacked.

    q̈ comes from a Savitzky–Golay fit of q over :data:`SAVGOL_WINDOW`; half a
    window at each end of every log is dropped (the fit extrapolates there).
    """
    errors, velocities = [], []
    for log in logs:
        if log.qd is None or log.tau_m is None:
            raise ValueError("identification needs the measured velocity qd and the torque tau_m")
        _, qdd = savgol_derivatives(log.q, log.dt, SAVGOL_WINDOW)
        half = window_samples(log.dt, SAVGOL_WINDOW) // 2
        keep = slice(half, log.n_samples - half)
        tau = robot.inverse_dynamics(log.q[keep], log.qd[keep], qdd[keep])
        errors.append(log.tau_m[keep] - tau)
        velocities.append(np.asarray(log.qd[keep]))
    return np.concatenate(errors), np.concatenate(velocities)


def identify_correction(logs: Sequence[Log], robot: RobotModel) -> NominalCorrection:
    """Torque offset and Coulomb + viscous friction per joint (recipe step 2)."""
    error, velocity = model_error(logs, robot)
    dt = logs[0].dt
    n_dof = robot.n_dof
    c_pos, c_neg, fv, offset = (np.zeros(n_dof) for _ in range(4))
    for j in range(n_dof):
        e, v = error[:, j], velocity[:, j]
        resting = np.abs(v) < RESTING
        if resting.sum() * dt >= MIN_TIME:
            offset[j] = np.median(e[resting])
        # The directions (+1, -1) the joint moved in long enough to show their Coulomb level.
        seen = {sign: sign * v >= RESTING for sign in (1, -1)}
        seen = {sign: mask for sign, mask in seen.items() if mask.sum() * dt >= MIN_TIME}
        if not seen:
            continue
        moving = np.abs(v) >= RESTING
        design = np.column_stack([*(mask[moving] for mask in seen.values()), v[moving]])
        lower = [0.0 if sign > 0 else -np.inf for sign in seen] + [0.0]
        upper = [np.inf if sign > 0 else 0.0 for sign in seen] + [np.inf]
        fit = lsq_linear(design.astype(float), e[moving] - offset[j], bounds=(lower, upper))
        level = dict(zip(seen, fit.x[:-1], strict=True))
        c_pos[j] = level.get(1, -level.get(-1, 0.0))
        c_neg[j] = level.get(-1, -c_pos[j])
        fv[j] = fit.x[-1]
    return NominalCorrection(CoulombViscous(c_pos, c_neg, fv), offset)


@dataclass(frozen=True)
class HeldOut:
    """One family's verdicts on one held-out recording in one fold.

    Attributes
    ----------
    fold : int
        Fold number (1 or 2).
    family : str
        Threshold family.
    name : str
        Held-out recording.
    seconds : float
        Judged collision-free time [s]: not settling, not in an apparent contact.
    false_alarms : list of Event
        Events away from any apparent contact.
    at_contacts : int
        Events at an apparent contact.
    band_sum : ndarray of shape (n_dof,)
        Sum over the judged samples of upper − lower bound [N m].
    n_band : int
        Number of those samples.
    """

    fold: int
    family: str
    name: str
    seconds: float
    false_alarms: list[Event]
    at_contacts: int
    band_sum: FloatArray
    n_band: int


@dataclass(frozen=True)
class Tuned:
    """A family tuned in one fold: threshold, settings and the rate ``tune`` expects [1/h]."""

    family: str
    threshold: Threshold
    settings: ObserverSettings
    expected_rate: float


def tune_families(logs: Sequence[Log], robot: RobotModel) -> list[Tuned]:
    """Every family of :data:`FAMILIES` tuned on ``logs`` with the demo's margin."""
    base, _ = tune(logs, robot, "constant", folds=None)
    assert isinstance(base, ConstantThreshold)
    margin = MARGIN_FRACTION * base.beta_
    tuned = []
    for family in FAMILIES:
        # The demo's time-variant fit (minimax), as in sensorless.comparison.
        options: dict[str, Any] = {"fit_method": "minimax"} if family == "time-variant" else {}
        threshold, settings = tune(logs, robot, family, margin=margin, **options)
        calibration = calibration_of(threshold)
        rate = math.nan if calibration is None else calibration.rate
        tuned.append(Tuned(family, threshold, settings, rate))
    return tuned


def judge(
    fold: int, tuned: Tuned, robot: RobotModel, recording: Recording
) -> tuple[HeldOut, MonitorRun, Bounds]:
    """Run the monitor of ``tuned`` over a held-out recording (offset already applied).

    An event that meets an apparent contact, or starts within
    :data:`~sensorless.evaluation.DEFAULT_MAX_DELAY` after it, is "at the
    contact" (:func:`~sensorless.evaluation.evaluate`); the same spans are
    left out of the judged time.
    """
    monitor = CollisionMonitor(robot, tuned.threshold, tuned.settings)
    run = monitor.process(recording.log)
    if run.faults:
        raise RuntimeError(f"{recording.name}: the monitor refused samples: {run.faults}")
    scoring = evaluate(run.events, recording.labelled(), method=tuned.family)
    lower, upper = tuned.threshold.bounds(run.signals)
    t = run.signals.t
    judged = ~run.settling
    for start, stop in recording.contacts:
        judged &= (t < start) | (t > stop + scoring.max_delay)
    result = HeldOut(
        fold=fold,
        family=tuned.family,
        name=recording.name,
        seconds=float(judged.sum() * recording.log.dt),
        false_alarms=list(scoring.false_alarms),
        at_contacts=len(run.events) - len(scoring.false_alarms),
        band_sum=np.sum((upper - lower)[judged], axis=0),
        n_band=int(judged.sum()),
    )
    return result, run, (lower, upper)


@dataclass(frozen=True)
class FoldReport:
    """What one fold produced: its correction, its tuned families and their verdicts."""

    fold: int
    correction: NominalCorrection
    tuned: list[Tuned]
    results: list[HeldOut]


def run_fold(
    fold: int,
    train: Recording,
    static_tuning: Recording,
    held_out: Sequence[Recording],
    robot: RobotModel,
    output: Path | None = None,
) -> FoldReport:
    """Identify, tune and judge one fold (recipe steps 2–3, and 5 with ``output``)."""
    correction = identify_correction(train.clean_pieces(), robot)
    model = correction.model(robot)
    pieces = [*train.clean_pieces(), *static_tuning.clean_pieces()]
    tuning = [correction.apply(log) for log in pieces]
    tuned = tune_families(tuning, model)
    results: list[HeldOut] = []
    for recording in held_out:
        corrected = dataclasses.replace(recording, log=correction.apply(recording.log))
        bounds: dict[str, Bounds] = {}
        events: dict[str, list[Event]] = {}
        for family in tuned:
            result, run, bounds[family.family] = judge(fold, family, model, corrected)
            results.append(result)
            events[family.family] = run.events
        if output is not None:
            # Every family watches the same residual (motor observer, K_I = 20/s).
            figure = plot_residuals(
                run.signals,
                bounds,
                corrected.labelled(),
                events,
                title=f"fold {fold}: {recording.name} (shaded: apparent contacts)",
            )
            stem = recording.name.replace(".csv", "").replace("#", "-").replace(" ", "_")
            figure.savefig(output / f"fold{fold}_{stem}.png", dpi=80)
    return FoldReport(fold, correction, tuned, results)


Fold = tuple[Recording, Recording, list[Recording]]
"""Training half of ``link4.csv``, tuning part of ``ur-static.csv``, held-out recordings."""


def split(recordings: Mapping[str, Recording]) -> list[Fold]:
    """The two folds of recipe step 3."""
    link4 = recordings["link4.csv"]
    middle = float(link4.log.t[0]) + link4.log.duration / 2.0
    halves = [link4.part(None, middle, "first half"), link4.part(middle, None, "second half")]
    static = recordings["ur-static.csv"]
    cut = float(static.log.t[0]) + STATIC_TUNING * static.log.duration
    static_tuning, static_rest = static.part(None, cut, "start"), static.part(cut, None, "rest")
    others = [r for name, r in recordings.items() if name not in ("link4.csv", "ur-static.csv")]
    return [
        (halves[0], static_tuning, [halves[1], static_rest, *others]),
        (halves[1], static_tuning, [halves[0], static_rest, *others]),
    ]


def summary(reports: Sequence[FoldReport], n_dof: int) -> pd.DataFrame:
    """The table of recipe step 4: one row per family, both folds pooled."""
    rows = []
    for family in FAMILIES:
        results = [r for report in reports for r in report.results if r.family == family]
        seconds = sum(r.seconds for r in results)
        alarms = sum(len(r.false_alarms) for r in results)
        hours = seconds / 3600.0
        low, high = poisson_interval(alarms, hours)
        band = np.sum([r.band_sum for r in results], axis=0) / sum(r.n_band for r in results)
        expected = [
            t.expected_rate for report in reports for t in report.tuned if t.family == family
        ]
        row: dict[str, object] = {
            "family": family,
            "held-out [s]": round(seconds, 1),
            "false alarms": alarms,
            "per hour": round(alarms / hours),
            "95 % interval": f"{low:.0f}-{high:.0f}",
            "at contacts": sum(r.at_contacts for r in results),
            "tune expects [1/h]": " / ".join(f"{v:.0f}" for v in expected),
        }
        for j in range(n_dof):
            row[f"band {j + 1}"] = round(float(band[j]), 1)
        rows.append(row)
    return pd.DataFrame(rows).set_index("family")


def details(reports: Sequence[FoldReport]) -> pd.DataFrame:
    """False alarms per fold, held-out recording and family (alarms at contacts in brackets)."""
    rows: dict[tuple[int, str], dict[str, object]] = {}
    for report in reports:
        for r in report.results:
            row = rows.setdefault((r.fold, r.name), {"fold": r.fold, "held out": r.name})
            row["judged [s]"] = round(r.seconds, 1)
            row[r.family] = f"{len(r.false_alarms)} ({r.at_contacts})"
    return pd.DataFrame(list(rows.values())).set_index(["fold", "held out"])


def cross_validate(
    recordings: Mapping[str, Recording], robot: RobotModel, output: Path | None = None
) -> list[FoldReport]:
    """Both folds of recipe step 3 (and the plots of step 5 into ``output``)."""
    return [
        run_fold(fold, train, static_tuning, held_out, robot, output)
        for fold, (train, static_tuning, held_out) in enumerate(split(recordings), start=1)
    ]


def standing_residual(
    recordings: Mapping[str, Recording], robot: RobotModel, correction: NominalCorrection
) -> pd.DataFrame:
    """Largest |r̂| [N m] per joint on the standing arm, URDF model vs corrected model.

    Over all of ``ur-static.csv`` and over its stretches between apparent
    contacts; the observer starts on the first sample of each (K_I = 20/s,
    measured velocity).
    """
    static = recordings["ur-static.csv"]
    settings = ObserverSettings()
    corrected = correction.model(robot)
    rows = {}
    for label, logs in (("whole file", [static.log]), ("between contacts", static.clean_pieces())):
        for name, model, apply in (("URDF", robot, False), ("corrected", corrected, True)):
            peak = np.zeros(robot.n_dof)
            for log in logs:
                used = correction.apply(log) if apply else log
                residual = settings.observe(used, model).residual
                peak = np.maximum(peak, np.abs(residual).max(axis=0))
            rows[f"{name}, {label}"] = peak.round(1)
    columns = [f"joint {j}" for j in range(1, robot.n_dof + 1)]
    return pd.DataFrame.from_dict(rows, orient="index", columns=columns)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the recipe and print its tables."""
    parser = argparse.ArgumentParser(description=(__doc__ or "").split("\n\n")[0])
    parser.add_argument("--data", type=Path, default=DATA, help="folder of the four CSV files")
    parser.add_argument("--output", type=Path, help="folder for the residual plots (PNG)")
    parser.add_argument(
        "--every-alarm-false",
        action="store_true",
        help="ignore the apparent contacts: tune on everything, every alarm is false",
    )
    args = parser.parse_args(argv)
    if not args.data.is_dir():
        parser.error(f"{args.data} is not a folder; give the recordings' folder with --data")
    if args.output is not None:
        args.output.mkdir(parents=True, exist_ok=True)
    recordings = load_recordings(args.data, {} if args.every_alarm_false else APPARENT_CONTACTS)
    robot = sl.robots.load("ur10")
    pd.set_option("display.width", 200)

    print("Imported (time from each file's first sample):")
    for name, recording in recordings.items():
        log = recording.log
        spans = ", ".join(f"{a:g}-{b:g} s" for a, b in recording.contacts) or "none"
        print(
            f"  {name:14s} {log.n_samples:5d} samples, {log.duration:5.2f} s, "
            f"dt = {log.dt * 1e3:.1f} ms; apparent contacts: {spans}"
        )
    reports = cross_validate(recordings, robot, args.output)
    for report in reports:
        print(f"\nFold {report.fold}: friction and offset from link4.csv's training half")
        print(report.correction.to_pandas().round(2).to_string())
    final = identify_correction(recordings["link4.csv"].clean_pieces(), robot)
    print("\nFrom all of link4.csv (the model a user would keep):")
    print(final.to_pandas().round(2).to_string())
    print("\nLargest |r̂| [N m] on the standing arm (ur-static.csv), URDF vs this model:")
    print(standing_residual(recordings, robot, final).to_string())
    print("\nFalse alarms per fold and held-out recording (alarms at apparent contacts):")
    print(details(reports).to_string())
    print(
        f"\nHeld-out false alarms, both folds pooled. Margin {MARGIN_FRACTION:.0%} of the "
        "constant β per joint; 95 % exact Poisson interval; at contacts: alarms at an "
        "apparent contact; tune expects: the rate tune's own cross-validation of each "
        "fold's tuning data states [1/h]; band: mean upper − lower bound per joint [N m]."
    )
    print(summary(reports, robot.n_dof).to_string())
    if args.output is not None:
        print(f"\nResidual plots written to {args.output}/")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
