"""The real-arm part of the demo: the UR10 recipe's result, or why it was skipped."""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pandas as pd

from ..plots import (
    plot_held_out,
)
from ..realarm import UR10_FOLDER, RealArmEvaluation, evaluate_ur10, missing_files


@dataclass(frozen=True)
class RealArm:
    """The real-arm part of the demo: the UR10 recipe's result, or why it was skipped.

    Attributes
    ----------
    folder : Path
        Where the recordings were looked for.
    evaluation : RealArmEvaluation or None
        :func:`sensorless.realarm.evaluate_ur10` on ``folder``; None if skipped.
    skipped : str
        Why it was skipped ("" if it ran).
    seconds : float
        Wall time of the recipe [s].
    plotted : (int, str)
        Fold and name of the held-out recording the report plots.
    """

    folder: Path
    evaluation: RealArmEvaluation | None
    skipped: str = ""
    seconds: float = 0.0
    plotted: tuple[int, str] = (1, "link4.csv second half")

    def summary(self) -> pd.DataFrame | None:
        """Per family: judged held-out seconds, false alarms, rate [1/h] with its 95 % interval."""
        if self.evaluation is None:
            return None
        columns = ["held-out [s]", "false alarms", "per hour", "95 % low", "95 % high"]
        return self.evaluation.summary()[[*columns, "at contacts"]]

    def report_items(self) -> list[Any]:
        """Text, table and plot of the report's section (only the reason if skipped)."""
        if self.evaluation is None:
            return [f"Skipped: {self.skipped}"]
        return [
            "Four recordings of a real UR10 (ext_observer, 100 Hz, measured velocity, motor "
            "currents × UR's gains), without labels. Per fold, a torque offset and Coulomb + "
            "viscous friction are identified on one half of link4.csv, each family is tuned "
            "on that half plus the first quarter of ur-static.csv (margin "
            f"{self.evaluation.margin_fraction:.0%} of the constant β per joint), and the "
            "monitor runs over everything else; both folds pooled. Spans that look like a "
            "hand on the arm are set apart: an alarm there counts under 'at contacts', not "
            "as a false alarm. Rates in false alarms per hour with the exact 95 % Poisson "
            f"interval. The recipe took {self.seconds:.1f} s "
            "(examples/ur10_real_arm.py explains it).",
            self.summary(),
            plot_held_out(self.evaluation.held_out(*self.plotted)),
        ]


def real_arm(folder: str | Path = UR10_FOLDER, **options: Any) -> RealArm:
    """The UR10 recipe on ``folder``, or a :class:`RealArm` that says why it was skipped.

    Parameters
    ----------
    folder : str or Path
        Folder of the UR10 recordings (:data:`sensorless.realarm.UR10_FOLDER`,
        relative to the current directory, by default).
    **options
        Keyword options of :func:`sensorless.realarm.evaluate_ur10`.
    """
    path = Path(folder)
    missing = missing_files(path)
    if missing:
        where = "is not a folder" if not path.is_dir() else f"lacks {missing}"
        reason = (
            f"{path} {where}: the real UR10 recordings (ext_observer) are not there. "
            "Give their folder with --real-data PATH."
        )
        return RealArm(path, None, reason)
    start = time.perf_counter()
    evaluation = evaluate_ur10(path, **options)
    return RealArm(path, evaluation, seconds=time.perf_counter() - start)
