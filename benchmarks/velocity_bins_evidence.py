"""False alarms and detections of the velocity family on lwr4-thesis, before and after pooling.

Issue 13, item 5. Two collision-free tuning runs leave many velocity bins of
the LWR nearly empty: the via-point motion passes through most velocities in
a few tens of milliseconds. A bin's L and U are the extremes of its few fit
errors, too tight for a new run. *before* is the old rule
(``min_bin_time=0``: every visited bin keeps its own extremes); *after* the
default (``min_bin_time=0.5`` s: a bin with less fit data takes the extremes
of the smallest window of neighbouring bins that holds 0.5 s).

The runs are those of :func:`sensorless.comparison.compare` with master seed
0 and two tuning runs, cut to ``--duration`` seconds; ``--start`` begins them
at a later via point of the trajectory (shifted to t = 0, at rest there, with
the contacts of that window): from 83 s on the LWR makes its fast moves
(±165° in 11-15 s), the first 40 s are slow. Seeds 0 and 1 of
``SeedSequence(0).spawn(4)`` tune, seed 2 is the collision run (the test run
of ``compare``), seed 3 a collision-free held-out run. Thresholds and margins
follow ``compare``: joints 1-3 monitored, margin 10 % of the constant β of the
residual, events with ``min_duration`` 5 ms and ``hold`` 50 ms. The velocity
family is shown on r̂_s (``joint``) and, for reference, on r̂ (``motor``):
``velocity`` is the single fit, ``velocity-combined`` the fit of both
residuals with one γ (eq. 4.47).

The LWR simulation takes about 3 s per simulated second (more on a loaded
machine); logs are cached in ``--cache`` and reused.

    .venv/bin/python benchmarks/velocity_bins_evidence.py [--duration 40] [--start 0] [--cache DIR]
"""

from __future__ import annotations

import argparse
import copy
import time
from pathlib import Path

import numpy as np

from sensorless.detection import Detector
from sensorless.evaluation import evaluate
from sensorless.io import Log, read_log, write_log
from sensorless.monitor import ObserverSettings
from sensorless.signals import ObserverSignals
from sensorless.simulation.scenario import Scenario, load_scenario
from sensorless.thresholds import (
    CombinedVelocityThreshold,
    ConstantThreshold,
    VelocityThreshold,
)
from sensorless.thresholds.velocity_bins import MIN_BIN_TIME

JOINTS = (1, 2, 3)
MARGIN = 0.1  # of the constant β, as compare()
MIN_DURATION, HOLD = 0.005, 0.05  # compare()'s event filtering [s]
RUNS = {"tuning 1": (0, False), "tuning 2": (1, False), "collision": (2, True), "free": (3, False)}


def segment(start: float, duration: float) -> Scenario:
    """lwr4-thesis from its via point at ``start`` [s] on, shifted to t = 0, ``duration`` [s] long.

    The run starts at rest at that via point; the contacts inside the window
    move along with it, the others are dropped.
    """
    base = load_scenario("lwr4-thesis")
    spec = copy.deepcopy(base.spec)
    points = [p for p in spec["trajectory"]["points"] if p[0] >= start]
    if not points or points[0][0] != start:
        times = [p[0] for p in spec["trajectory"]["points"]]
        raise SystemExit(f"--start must be the time of a via point, one of {times}; got {start}")
    spec["trajectory"]["points"] = [[p[0] - start, *p[1:]] for p in points]
    spec["collisions"] = [
        dict(c, start=c["start"] - start)
        for c in spec["collisions"]
        if start <= c["start"] < start + duration
    ]
    spec["duration"] = float(duration)
    return Scenario(base.name, spec)


def logs(scenario: Scenario, start: float, cache: Path) -> dict[str, Log]:
    """The four runs, simulated once and cached as Parquet."""
    seeds = [int(c.generate_state(1)[0]) for c in np.random.SeedSequence(0).spawn(4)]
    cache.mkdir(parents=True, exist_ok=True)
    out = {}
    for name, (index, collisions) in RUNS.items():
        stem = f"lwr4-{start:g}+{scenario.duration:g}s-seed{seeds[index]}-c{int(collisions)}"
        path = cache / f"{stem}.parquet"
        if not path.exists():
            clock = time.perf_counter()
            write_log(scenario.run(seed=seeds[index], collisions=collisions).log, path)
            print(f"simulated {name} ({path.name}) in {time.perf_counter() - clock:.0f} s")
        out[name] = read_log(path)
    return out


def row(
    single: VelocityThreshold, test: dict[str, ObserverSignals], logs: dict[str, Log]
) -> list[str]:
    """Pooled bins, band width, false alarms and detections of one fitted threshold."""
    joints = [j - 1 for j in JOINTS]
    visited = single.counts_[:, joints] > 0
    pooled = int((single.pooled_bins_[:, joints] & visited).sum())
    width = float((single.upper_ - single.lower_)[:, joints][visited].mean())
    detector = Detector(single, min_duration=MIN_DURATION, hold=HOLD)
    hit = evaluate(detector.detect(test["collision"]), logs["collision"])
    free = evaluate(detector.detect(test["free"]), logs["free"])
    n = hit.n_detected + hit.n_masked + hit.n_missed
    return [
        f"{pooled}/{int(visited.sum())}",
        f"{width:.3f}",
        str(len(free.false_alarms)),
        str(len(hit.false_alarms)),
        f"{hit.n_detected}/{n}",
        f"{1e3 * hit.mean_start_delay:.1f}",
    ]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=40.0, help="simulated time per run [s]")
    parser.add_argument(
        "--start", type=float, default=0.0, help="via point [s] of lwr4-thesis the runs start at"
    )
    parser.add_argument(
        "--margin-fraction",
        type=float,
        default=MARGIN,
        help="margin as a fraction of the constant β (compare(): 0.1)",
    )
    parser.add_argument(
        "--min-bin-time",
        type=float,
        nargs="+",
        default=[0.0, MIN_BIN_TIME],
        help="values of min_bin_time [s] to compare (0: the old rule)",
    )
    parser.add_argument("--residuals", nargs="+", default=["joint", "motor"])
    parser.add_argument("--cache", type=Path, default=Path("out/velocity_bins_evidence"))
    args = parser.parse_args()
    scenario = segment(args.start, args.duration)
    runs = logs(scenario, args.start, args.cache)
    signals: dict[str, dict[str, ObserverSignals]] = {}
    for kind in ("motor", "joint"):
        nominal = scenario.nominal(kind)
        settings = ObserverSettings(kind=kind)
        signals[kind] = {name: settings.observe(log, nominal) for name, log in runs.items()}
    tuning = {kind: [s["tuning 1"], s["tuning 2"]] for kind, s in signals.items()}
    margins = {
        kind: args.margin_fraction * ConstantThreshold(joints=JOINTS).fit(tuning[kind]).beta_
        for kind in signals
    }
    header = [
        "method",
        "residual",
        "min_bin_time [s]",
        "pooled bins",
        "mean width [N m]",
        f"FA free run ({args.duration:g} s)",
        "FA collision run",
        "detected",
        "mean delay [ms]",
    ]
    table = []
    for rule in args.min_bin_time:
        combined = CombinedVelocityThreshold(joints=JOINTS, min_bin_time=rule).fit(
            list(zip(tuning["motor"], tuning["joint"], strict=True))
        )
        for kind in args.residuals:
            single = VelocityThreshold(margin=margins[kind], joints=JOINTS, min_bin_time=rule)
            single.fit(tuning[kind])
            table.append(["velocity", kind, f"{rule:g}", *row(single, signals[kind], runs)])
            single = combined.for_kind(kind)
            # As compare(): fitted without margin, each residual gets that of its own β.
            single.lower_ = single.lower_ - margins[kind]
            single.upper_ = single.upper_ + margins[kind]
            row_cells = row(single, signals[kind], runs)
            table.append(["velocity-combined", kind, f"{rule:g}", *row_cells])
    widths = [max(len(str(r[i])) for r in [header, *table]) for i in range(len(header))]
    for line in [header, *table]:
        print("  ".join(str(c).ljust(w) for c, w in zip(line, widths, strict=True)))
    print(
        f"lwr4-thesis from {args.start:g} s, {args.duration:g} s runs; joints 1-3; margin "
        f"{args.margin_fraction:g} x constant beta. pooled bins: visited bins with less than "
        "min_bin_time of fit data (L and U from neighbouring bins); FA: false alarms"
    )


if __name__ == "__main__":
    main()
