"""The result of :func:`~sensorless.comparison.compare` for one scenario."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from .._validation import FloatArray
from ..evaluation import Evaluation, comparison_table, efficiency_table, summary_table
from ..io import Log
from ..report import (
    ScenarioSummary,
    band_widths,
    summarize,
)
from ..signals import Event, ObserverSignals
from ..thresholds import (
    Threshold,
    TimeVariantThreshold,
)


@dataclass
class Comparison:
    """Results of :func:`compare` for one scenario.

    Attributes
    ----------
    scenario : str
    joints : tuple of int or None
        Monitored joints (1-based), None for all.
    thresholds : dict
        Fitted threshold per method.
    evaluations : dict
        :class:`~sensorless.evaluation.Evaluation` per method on the test run.
    signals : dict
        Observer signals of the test run per observer kind ("motor", "joint", "acceleration").
    bounds : dict
        (lower, upper) of each method on the test run.
    events : dict
        Detected events per method.
    test_log : Log
        The collision run.
    seeds : dict
        Seeds of the tuning and test runs.
    kinds : dict
        Observer kind each method label watches ("motor", "joint", "acceleration").
    """

    scenario: str
    joints: tuple[int, ...] | None
    thresholds: dict[str, Threshold]
    evaluations: dict[str, Evaluation]
    signals: dict[str, ObserverSignals]
    bounds: dict[str, tuple[FloatArray, FloatArray]]
    events: dict[str, list[Event]]
    test_log: Log
    seeds: dict[str, Any] = field(default_factory=dict)
    kinds: dict[str, str] = field(default_factory=dict)

    def summary(self) -> pd.DataFrame:
        """One row per method: detected/total, false alarms, delays (Table 5.4 summary)."""
        return summary_table(self.evaluations)

    def overview(self) -> ScenarioSummary:
        """The report's summary: counts, rates, delays, band vs constant, and a sentence."""
        return summarize(self.scenario, self.evaluations, band_widths(self.bounds, self.joints))

    def per_collision(self) -> pd.DataFrame:
        """Start/end delay per collision and method (Tables 4.3, 5.4 style)."""
        return comparison_table(self.evaluations)

    def efficiency(self) -> pd.DataFrame | None:
        """α, γ, ε_fr, β and eff = α/β of the time-variant threshold (Table 5.7 style)."""
        threshold = self.thresholds.get("time-variant")
        if not isinstance(threshold, TimeVariantThreshold):
            return None
        joints = list(self.joints or range(1, threshold.n_dof_ + 1))
        index = np.asarray(joints) - 1
        table = efficiency_table(
            threshold.alpha_[index],
            threshold.beta_[index],
            extra={"gamma": threshold.gamma_[index], "eps_fr": threshold.eps_fr_[index]},
        )
        table.columns = [f"joint {j}" for j in joints]
        return table
