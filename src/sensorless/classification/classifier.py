"""Intended contact or collision: four stated rules, an optional fit, batch and stream.

:class:`InteractionClassifier` calls an event *intended* when every rule
says so, and a *collision* otherwise:

=================  ==========================  =====================================
feature            intended when               stated cut-off (:class:`Cutoffs`)
=================  ==========================  =====================================
rise rate          at most ``rise_rate``       200 N m/s
duration           at least ``duration``       0.3 s
HF fraction        at most ``hf_fraction``     0.3
mean power         at least ``mean_power``     -5 W
=================  ==========================  =====================================

Why these: a hand builds up 10–40 N over 0.3–1 s, a raised-cosine slope of
at most π·40/(2·0.3) ≈ 210 N/s, about 200 N m/s in the joint torques of a
force at the tool of a 1 m arm (‖J_cᵀ d‖ ≲ 1 m); it pushes for a second or
more, while an impact (under 0.1 s) leaves a residual that decays within
~3/K_I = 0.15 s at the default gain K_I = 20 1/s, so its event is over
before 0.3 s; a hand's force has little content above 2–3 Hz, an impact
most of its energy above the 3 Hz high-pass; and a person guiding the arm
feeds it energy at low power, while an obstacle takes energy out (mean
τ̂_cᵀq̇ well below zero). A collision called intended
is the dangerous error, hence the conjunction: every feature must look like
a hand. The rise-rate and power cut-offs scale with the arm; :meth:`fit`
sets all four from labelled events.

:meth:`InteractionClassifier.fit` models the probability that an event is
intended as the product of one logistic factor per rule,
``Π_i σ(s_i (φ_i - c_i) / w_i)`` with ``φ`` = (log10 rise rate, log10
duration, HF fraction, mean power), ``s_i = ±1`` the sense of the rule, and
fits the cut-offs ``c_i`` and the widths ``w_i`` by maximum likelihood
(``scipy.optimize.minimize``, L-BFGS-B, from the stated cut-offs). The crisp
rules then use the fitted cut-offs; a cut-off pushed beyond all the data
switches its rule off.

The stream (:meth:`InteractionClassifier.step`) follows a
:class:`~sensorless.detection.Detector` sample by sample: it gives a
provisional class once an event has lasted ``window`` seconds (0.3 s by
default, the shortest intended contact, so the duration rule already holds)
and the final class when the detector closes the event; the final class and
features equal those of :func:`classify_events` on the recorded event, and
for an event that lasts at least ``window`` the provisional ones equal
``classify_events(..., provisional=True)``. (A stream may also give a
provisional class to a shorter event whose detector ``hold`` is still
running at ``window``: it cannot know yet that the event is over.)
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike
from scipy.optimize import minimize

from .._validation import FloatArray, Sign, check_dt, check_scalar, check_type
from ..detection import TIME_TOLERANCE, DetectorState, Verdict
from ..exceptions import DimensionError, InputValueError, NotFittedError, UnknownNameError
from ..signals import Event, ObserverSignals
from .features import (
    FEATURE_NAMES,
    EventFeatures,
    _Design,
    _design,
    _features,
    _open,
    _Sums,
    _update,
)

__all__ = [
    "KINDS",
    "Classification",
    "ClassifierState",
    "Cutoffs",
    "InteractionClassifier",
    "classifications_to_pandas",
    "classify_events",
]

#: The classes: a person's intended interaction, or an accidental collision.
KINDS: tuple[str, ...] = ("intended", "collision")

# +1: intended when the feature is at least the cut-off; -1: at most.
_SENSE = np.array([-1.0, 1.0, -1.0, 1.0])
_LOGGED = (True, True, False, False)  # rise rate and duration span decades: fitted in log10
_FLOOR = 1e-6


@dataclass(frozen=True)
class Cutoffs:
    """Cut-offs of the four rules; an event is intended when it passes all of them.

    Parameters
    ----------
    rise_rate : float, default 200.0
        Largest rise rate of an intended contact [N m/s], ``> 0``.
    duration : float, default 0.3
        Shortest intended contact [s], ``>= 0``.
    hf_fraction : float, default 0.3
        Largest high-frequency fraction of an intended contact [-], ``>= 0``.
    mean_power : float, default -5.0
        Lowest mean power τ̂_cᵀq̇ of an intended contact [W].
    """

    rise_rate: float = 200.0
    duration: float = 0.3
    hf_fraction: float = 0.3
    mean_power: float = -5.0

    def __post_init__(self) -> None:
        checks: tuple[tuple[str, str, Sign], ...] = (
            ("rise_rate", "N m/s", "positive"),
            ("duration", "s", "nonnegative"),
            ("hf_fraction", "-", "nonnegative"),
            ("mean_power", "W", "any"),
        )
        for name, unit, sign in checks:
            value = check_scalar(getattr(self, name), f"cut-off {name}", unit, sign)
            object.__setattr__(self, name, value)

    def failed(self, features: EventFeatures) -> tuple[str, ...]:
        """Names of the rules ``features`` fail (empty: intended)."""
        values = _row(features)
        limits = _row_of(self)
        # An event as long as the cut-off, in sample times, may fall short of it by rounding.
        limits[1] -= TIME_TOLERANCE
        return tuple(
            n
            for n, v, c, s in zip(FEATURE_NAMES, values, limits, _SENSE, strict=True)
            if not s * (v - c) >= 0.0
        )


@dataclass(frozen=True)
class Classification:
    """The class of one event and why.

    Attributes
    ----------
    kind : {"intended", "collision"}
    features : EventFeatures
        The features the rules saw.
    failed : tuple of str
        The rules that said "collision" (names in
        :data:`~sensorless.classification.FEATURE_NAMES`); empty for an
        intended event.
    provisional : bool
        True for the class a stream gives ``window`` seconds into an event.
    event : Event or None
        The detected event (None for a provisional class).
    """

    kind: str
    features: EventFeatures
    failed: tuple[str, ...]
    provisional: bool = False
    event: Event | None = None


@dataclass(frozen=True)
class ClassifierState:
    """What :meth:`InteractionClassifier.step` carries from one sample to the next.

    Attributes
    ----------
    dt : float
        Sample period of the stream [s].
    design : object
        The high-pass and the lag in samples at ``dt``.
    sums : object or None
        Running sums of the event in progress (None between events).
    snapshot : EventFeatures or None
        Features at the last sample outside the bounds (the event's end so far).
    told : bool
        Whether the provisional class of the event in progress was given.
    """

    dt: float
    design: _Design
    sums: _Sums | None = None
    snapshot: EventFeatures | None = None
    told: bool = False


def _row(features: EventFeatures) -> FloatArray:
    return np.array([getattr(features, name) for name in FEATURE_NAMES], dtype=float)


def _transform(rows: FloatArray) -> FloatArray:
    """φ: log10 of the rise rate and the duration (floored at 1e-6), the others as they are."""
    out = rows.copy()
    for j, logged in enumerate(_LOGGED):
        if logged:
            out[:, j] = np.log10(np.maximum(rows[:, j], _FLOOR))
    return out


class InteractionClassifier:
    """Tell intended contacts from collisions by four rules on the event's residual.

    Parameters
    ----------
    cutoffs : Cutoffs, optional
        Stated cut-offs (default :class:`Cutoffs`); :meth:`fit` learns others.
    window : float, default 0.3
        Time after an event's start at which a stream gives a provisional
        class [s], ``> 0``.
    highpass : float, default 3.0
        Corner of the high-pass behind the HF fraction [Hz], ``> 0``.
    lag : float, default 0.02
        Lag of the rise rate [s], ``> 0``.
    """

    def __init__(
        self,
        cutoffs: Cutoffs | None = None,
        *,
        window: float = 0.3,
        highpass: float = 3.0,
        lag: float = 0.02,
    ) -> None:
        self.cutoffs = Cutoffs() if cutoffs is None else check_type(cutoffs, Cutoffs, "cutoffs")
        self.window = check_scalar(window, "window", "s")
        self.highpass = check_scalar(highpass, "highpass", "Hz")
        self.lag = check_scalar(lag, "lag", "s")

    def __repr__(self) -> str:
        return (
            f"InteractionClassifier({self.cutoffs!r}, window={self.window!r}, "
            f"highpass={self.highpass!r}, lag={self.lag!r})"
        )

    @property
    def active_cutoffs(self) -> Cutoffs:
        """The cut-offs in use: ``cutoffs_`` after :meth:`fit`, else ``cutoffs``."""
        fitted: Cutoffs | None = getattr(self, "cutoffs_", None)
        return self.cutoffs if fitted is None else fitted

    # ----------------------------------------------------------------- batch

    def _design(self, dt: float) -> _Design:
        return _design(self.highpass, self.lag, dt)

    def features(
        self, events: Sequence[Event], signals: ObserverSignals, *, provisional: bool = False
    ) -> list[EventFeatures]:
        """Features of each event over its samples of ``signals``.

        Parameters
        ----------
        events : sequence of Event
            Events detected on ``signals`` (their times are sample times).
        signals : ObserverSignals
            Residual r̂ [N m] and velocity q̇ [rad/s] of the run.
        provisional : bool, default False
            Use only the samples up to the first one ``window`` seconds after
            the start (what a stream has seen when it gives its provisional
            class); an event shorter than that keeps all its samples.

        Returns
        -------
        list of EventFeatures
        """
        check_type(signals, ObserverSignals, "signals")
        chosen = list(events)
        for index, event in enumerate(chosen):
            check_type(event, Event, f"events[{index}]")
        design = self._design(check_dt(signals.dt, "signals.dt"))
        finite = np.isfinite(signals.residual).all(axis=1) & np.isfinite(signals.velocity).all(
            axis=1
        )
        found = []
        for event in chosen:
            last = event.end
            if provisional:
                due = signals.t >= event.start + self.window - TIME_TOLERANCE
                later = signals.t[due & (signals.t >= event.start)]
                last = min(last, float(later[0])) if later.size else last
            rows = np.flatnonzero((signals.t >= event.start) & (signals.t <= last) & finite)
            if rows.size == 0:
                raise InputValueError(
                    f"event [{event.start}, {event.end}] s has no finite sample in the signals "
                    f"(t from {signals.t[0]} to {signals.t[-1]} s)"
                )
            sums = _open(design, float(signals.t[rows[0]]), signals.residual[rows[0]])
            sums = _update(
                design, sums, signals.t[rows], signals.residual[rows], signals.velocity[rows]
            )
            found.append(_features(sums, design.lag))
        return found

    def decide(
        self, features: EventFeatures, *, provisional: bool = False, event: Event | None = None
    ) -> Classification:
        """The class of one event from its features (see the module's rules)."""
        failed = self.active_cutoffs.failed(check_type(features, EventFeatures, "features"))
        kind = "collision" if failed else "intended"
        return Classification(kind, features, failed, provisional, event)

    # ----------------------------------------------------------------- fit

    def fit(
        self, features: Sequence[EventFeatures], labels: Sequence[str]
    ) -> InteractionClassifier:
        """Learn the four cut-offs from labelled events (see the module docstring).

        Parameters
        ----------
        features : sequence of EventFeatures
            Features of labelled events.
        labels : sequence of str
            Their true classes, "intended" or "collision"; both must occur.

        Returns
        -------
        self
            With ``cutoffs_`` (:class:`Cutoffs`), ``widths_`` (ndarray of shape
            (4,), the logistic widths in φ units), ``converged_`` (bool) and
            ``n_events_`` (int).
        """
        rows = np.array([_row(check_type(f, EventFeatures, "features")) for f in features])
        names = list(labels)
        if len(names) != len(rows):
            raise DimensionError(f"got {len(rows)} feature sets and {len(names)} labels")
        unknown = sorted({str(n) for n in names} - set(KINDS))
        if unknown:
            raise UnknownNameError(f"unknown labels {unknown}; options: {list(KINDS)}")
        y = np.array([name == "intended" for name in names], dtype=float)
        if y.size == 0 or y.min() == y.max() or not np.isfinite(rows).all():
            raise InputValueError(
                "fit needs finite features of both intended and collision events; got "
                f"{int(y.sum())} intended and {int(y.size - y.sum())} collision events"
            )
        phi = _transform(rows)
        spread = phi.std(axis=0)
        spread[spread == 0.0] = 1.0
        start = _transform(_row_of(self.cutoffs)[None, :])[0]
        omega0 = np.log(0.2)

        def loss(w: FloatArray) -> float:
            z = _SENSE * (phi - w[:4]) / (np.exp(w[4:]) * spread)
            log_p = -np.logaddexp(0.0, -z).sum(axis=1)
            log_q = np.log(-np.expm1(np.minimum(log_p, -1e-12)))
            penalty = 1e-3 * float(np.sum((w[4:] - omega0) ** 2))
            return float(-np.mean(y * log_p + (1.0 - y) * log_q)) + penalty

        result = minimize(loss, np.concatenate([start, np.full(4, omega0)]), method="L-BFGS-B")
        cut = result.x[:4].copy()
        for j, logged in enumerate(_LOGGED):
            if logged:
                cut[j] = 10.0 ** cut[j]
        self.cutoffs_ = Cutoffs(
            rise_rate=max(float(cut[0]), _FLOOR),
            duration=max(float(cut[1]), 0.0),
            hf_fraction=max(float(cut[2]), 0.0),
            mean_power=float(cut[3]),
        )
        self.widths_ = np.exp(result.x[4:]) * spread
        self.converged_ = bool(result.success)
        self.n_events_ = int(y.size)
        return self

    def probability(self, features: Sequence[EventFeatures]) -> FloatArray:
        """Fitted probability that each event is intended, ``Π_i σ(s_i (φ_i - c_i) / w_i)``."""
        if not hasattr(self, "widths_"):
            raise NotFittedError("probability needs a fitted classifier; call fit first")
        phi = _transform(np.array([_row(f) for f in features]).reshape(-1, 4))
        cut = _transform(_row_of(self.cutoffs_)[None, :])[0]
        z = _SENSE * (phi - cut) / self.widths_
        return np.asarray(np.exp(-np.logaddexp(0.0, -z).sum(axis=1)))

    # ----------------------------------------------------------------- stream

    def initial_state(self, dt: float) -> ClassifierState:
        """State before the first sample of a stream sampled every ``dt`` [s]."""
        period = check_dt(dt)
        return ClassifierState(period, self._design(period))

    def step(
        self,
        state: ClassifierState,
        verdict: Verdict,
        detector_state: DetectorState,
        velocity: ArrayLike,
    ) -> tuple[Classification | None, ClassifierState]:
        """Follow the detector by one sample.

        Parameters
        ----------
        state : ClassifierState
            From :meth:`initial_state` or the previous call.
        verdict : Verdict
            What :meth:`Detector.step <sensorless.detection.Detector.step>` said about the sample.
        detector_state : DetectorState
            The detector's state after that sample (its ``open_event``).
        velocity : array-like of shape (n_dof,)
            Joint velocity of the sample, as given to the detector [rad/s].

        Returns
        -------
        classification : Classification or None
            The provisional class of the event in progress once it has lasted
            ``window`` seconds, or the final class of the event the detector
            closed at this sample (``verdict.event``); else None.
        state : ClassifierState
        """
        check_type(state, ClassifierState, "state", " from initial_state or step")
        if verdict.status == "fault":
            return None, state
        residual = np.asarray(verdict.residual, dtype=float)
        qd = np.asarray(velocity, dtype=float)
        if qd.shape != residual.shape:
            raise DimensionError(
                f"velocity must have the residual's shape {residual.shape}; got {qd.shape}"
            )
        design = state.design
        out: Classification | None = None
        sums, snapshot, told = state.sums, state.snapshot, state.told
        current = detector_state.open_event
        if sums is not None and (current is None or current.start != sums.start):
            ended = verdict.event
            if snapshot is not None and ended is not None and ended.start == sums.start:
                out = self.decide(snapshot, event=ended)
            sums, snapshot, told = None, None, False
        if current is not None:
            time = float(verdict.t)
            if sums is None:
                sums = _open(design, time, residual)
            sums = _update(design, sums, np.array([time]), residual[None, :], qd[None, :])
            if current.end == time:
                snapshot = _features(sums, design.lag)
            if out is None and not told and time - sums.start >= self.window - TIME_TOLERANCE:
                out = self.decide(_features(sums, design.lag), provisional=True)
                told = True
        return out, ClassifierState(state.dt, design, sums, snapshot, told)

    def finish(self, state: ClassifierState, event: Event | None) -> Classification | None:
        """Final class of the event still open at the end of a stream.

        ``event`` is what :meth:`Detector.finish <sensorless.detection.Detector.finish>`
        returned (None: nothing to classify).
        """
        check_type(state, ClassifierState, "state")
        if event is None or state.sums is None or state.snapshot is None:
            return None
        if event.start != state.sums.start:
            return None
        return self.decide(state.snapshot, event=event)


def _row_of(cutoffs: Cutoffs) -> FloatArray:
    return np.array([getattr(cutoffs, name) for name in FEATURE_NAMES], dtype=float)


def classify_events(
    events: Sequence[Event],
    signals: ObserverSignals,
    classifier: InteractionClassifier | None = None,
    *,
    provisional: bool = False,
) -> list[Classification]:
    """Class of each event: intended contact or collision, with the features used.

    Parameters
    ----------
    events : sequence of Event
        Events detected on ``signals``.
    signals : ObserverSignals
        The run's observer signals (residual [N m], velocity [rad/s]).
    classifier : InteractionClassifier, optional
        Default: the stated rules, :class:`InteractionClassifier()`.
    provisional : bool, default False
        Classify from the first ``window`` seconds of each event only (the
        class a stream gives before the event ends).

    Returns
    -------
    list of Classification
        One per event, in the order of ``events``.
    """
    chosen = InteractionClassifier() if classifier is None else classifier
    check_type(chosen, InteractionClassifier, "classifier")
    listed = list(events)
    found = chosen.features(listed, signals, provisional=provisional)
    return [
        chosen.decide(f, provisional=provisional, event=None if provisional else e)
        for f, e in zip(found, listed, strict=True)
    ]


def classifications_to_pandas(classifications: Sequence[Classification]) -> pd.DataFrame:
    """One row per classification: its class, failed rules, provisional flag and features."""
    rows: list[dict[str, Any]] = []
    for item in classifications:
        check_type(item, Classification, "classification")
        row: dict[str, Any] = {"kind": item.kind, "failed": ",".join(item.failed)}
        row["provisional"] = item.provisional
        row.update(item.features.as_dict())
        rows.append(row)
    columns = ["kind", "failed", "provisional", *EventFeatures.__dataclass_fields__]
    return pd.DataFrame(rows, columns=columns)
