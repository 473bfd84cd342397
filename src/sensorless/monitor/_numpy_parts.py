"""Parts of the numpy stream (:mod:`._numpy_stream`): row layout, observer matrix, bounds, flags.

The rows of one observer block, the matrix of the observer's update over
them, the bounds of the constant, time-variant and velocity-bin thresholds on
them, and the stream's scalars (time rules, detector, latch). Needs no
numba. Units SI and radians.
"""

from __future__ import annotations

import math
from bisect import bisect_right
from typing import Any

import numpy as np

from .._validation import FloatArray
from ..friction.static import Coulomb, CoulombViscous, HystereticError, Viscous
from ..thresholds import ConstantThreshold, TimeVariantThreshold, VelocityThreshold
from ._codes import COLLISION, JOINTS_SHIFT, OK

__all__ = [
    "Bounds",
    "EventRules",
    "Flags",
    "block_views",
    "layout",
    "observer_matrix",
]

# Rows of the observer block (one block per buffer, and one for a (re)start): this sample's
# p + g (one rnea of the model), Cᵀq̇, g, sign, sign², q̇ and three friction rows whose sum is
# τ̂_fr (scratch); the state:
# q̇, q, τ_m, τ_J (the rows the limits check), the last sample's p, Cᵀq̇ − g, τ̂_fr and sign,
# the filters r̂, h, filtered τ̂_fr and filtered sign; a row of ones; the velocity bins' filter.
P1, C1, G1, S1, SS1, VV1, FA, FB, FC = range(9)
V, Q, TM, TJ, P, VG, FR, SG0, R, H, F, SG, ONE, BIN = range(9, 23)


def observer_matrix(dt: float, weight: float, pole: float, tau: int) -> FloatArray:
    """Rows P … SG of the new state from the rows P1 … SG of the observer block.

    ``MomentumObserver._step_checked`` as one product: the inputs of the four
    filters (increment of p over dt, trapezoid of Cᵀq̇ − g and τ̂_fr, held τ
    in the row ``tau``), then y′ = ``weight`` · input + ``pole`` · y. The row
    P1 holds p + g (p = P1 − G1).
    """
    w = np.zeros((SG - P + 1, SG + 1))
    for out, source in ((P, P1), (VG, C1), (SG0, S1)):
        w[out - P, source] = 1.0
    w[P - P, G1] = w[VG - P, G1] = -1.0
    w[FR - P, [FA, FB, FC]] = 1.0
    h_in = np.zeros(SG + 1)
    h_in[P1], h_in[P], h_in[C1], h_in[VG] = 1.0 / dt, -1.0 / dt, -0.5, -0.5
    h_in[G1] = 0.5 - 1.0 / dt
    f_in = np.zeros(SG + 1)
    f_in[[FA, FB, FC, FR]] = 0.5
    g_in = np.zeros(SG + 1)
    g_in[[S1, SG0]] = 0.5
    r_in = h_in + f_in
    r_in[tau] -= 1.0
    for row, inputs in ((R, r_in), (H, h_in), (F, f_in), (SG, g_in)):
        w[row - P] = weight * inputs
        w[row - P, row] += pole
    return w


def friction_basis(observer: Any) -> tuple[Any, str, FloatArray]:
    """How τ̂_fr(q̇) enters the observer block: its function, "none", "basis" or "model",
    and the basis coefficients (3, n_dof) of a·sign + b·sign² + f_v·q̇ [N m, N m, N m s/rad].

    Coulomb, viscous, Coulomb-viscous and hysteretic-error friction are sums of
    that basis; any other model's own function runs ("model").
    """
    friction, n = observer.friction_model, observer.n_dof
    basis = np.zeros((3, n))
    kind = type(friction)
    if kind in (Coulomb, CoulombViscous):
        c_pos, c_neg = (np.broadcast_to(x, (n,)) for x in (friction.c_pos, friction.c_neg))
        # c_pos where sign = 1, c_neg where −1, 0 at rest; halves first: no overflow
        basis[0], basis[1] = 0.5 * c_pos - 0.5 * c_neg, 0.5 * c_pos + 0.5 * c_neg
    if kind in (Viscous, CoulombViscous):
        basis[2] = np.broadcast_to(friction.fv, (n,))
    if kind is HystereticError:
        basis[0] = -np.broadcast_to(friction.c, (n,))
    if kind in (Coulomb, Viscous, CoulombViscous, HystereticError):
        return observer._friction, "basis", basis
    return observer._friction, "none" if friction is None else "model", basis


class Bounds:
    """The bounds of a fitted constant, time-variant or velocity-bin threshold, per sample.

    Constant and time-variant (forms "friction" and "hysteretic"): with the
    rows x = (r̂, h, filtered τ̂_fr, filtered sign, 1) of the observer block,
    [L, U, r̂ − U, L − r̂] = S @ (G ∘ x), G the per-joint gains (γ, ε_fr or −c,
    α or β). A joint not monitored has G = (0, 0, 0, 0, ∞): its bounds are ∓∞
    and a non-finite filter gives NaN (0 · ∞), as for the others.
    """

    def __init__(self, threshold: Any, dt: float, monitored: Any) -> None:
        n = monitored.size
        self.velocity = isinstance(threshold, VelocityThreshold)
        # [r̂, L, U, r̂ − U, L − r̂]; the row r̂ only when every joint is monitored (0 · ∞)
        sums = [[1, 0, 0, 0, 0], [0, 1, 1, 1, -1], [0, 1, 1, 1, 1], [1, -1, -1, -1, -1],
                [-1, 1, 1, 1, -1]]  # fmt: skip
        self._whole = bool(monitored.all())
        self._sums = np.array(sums if self._whole else sums[1:], dtype=np.float64)
        gains = np.zeros((5, n))
        gains[0] = 1.0
        if isinstance(threshold, ConstantThreshold):
            gains[4] = threshold.beta_
        elif isinstance(threshold, TimeVariantThreshold):
            gains[1], gains[4] = threshold.gamma_, threshold.alpha_
            hysteretic = threshold.form == "hysteretic"
            gains[3 if hysteretic else 2] = -threshold.c_ if hysteretic else threshold.eps_fr_
        gains[:, ~monitored] = 0.0
        gains[4, ~monitored] = np.inf
        self._gains, self._scaled = gains, np.empty((5, n))
        self._rows = np.empty((self._sums.shape[0], n))
        self._excursions = self._rows[-2:].reshape(-1)
        if self.velocity:
            self._read_bins(threshold, dt, monitored)

    def _read_bins(self, threshold: VelocityThreshold, dt: float, monitored: Any) -> None:
        """The bin table by r = searchsorted(edges, q̇, "right") (0 … n_edges), per joint.

        Entry r of joint j's list holds τ_fme, L and U [N m] of its bin clip(r − 1)
        (``bin_index``), L and U widened by the extrapolation margin where r says
        q̇ is outside the visited bins (``table_bounds``), and ∓∞ for a joint not
        monitored.
        """
        n = monitored.size
        edges = np.asarray(threshold.bin_edges_, dtype=np.float64)
        r = np.arange(edges.size + 1)[:, None]
        bins = np.clip(r - 1, 0, edges.size - 2) + np.zeros((1, n), dtype=np.int64)
        joint = np.arange(n)[None, :]
        visited = threshold.counts_ > 0
        first = np.argmax(visited, axis=0)
        last = visited.shape[0] - 1 - np.argmax(visited[::-1], axis=0)
        extra = float(threshold.extrapolation_margin)
        widen = extra * ((r <= first) | (r >= last + 2)) if extra > 0.0 else 0.0
        table = np.stack(
            [
                threshold.tau_fme_[bins, joint],
                threshold.lower_[bins, joint] - widen,
                threshold.upper_[bins, joint] + widen,
            ],
            axis=-1,
        )  # (n_edges + 1, n_dof, 3)
        table[:, ~monitored] = (0.0, -np.inf, np.inf)
        # Python floats: for a handful of joints, a loop over lists costs less than the
        # dozen small numpy calls of the same arithmetic (same operations, same order).
        self._edges = edges.tolist()
        step = np.broadcast_to(threshold.gain_, (n,)) * dt  # the filter of first_order
        gamma = np.where(monitored, threshold.gamma_, 0.0).tolist()
        rows = [[tuple(row) for row in table[:, j].tolist()] for j in range(n)]
        # per joint: the filter's pole and weight, γ, and (τ_fme, L, U) by r
        self._joints = list(
            zip(np.exp(-step).tolist(), (-np.expm1(-step)).tolist(), gamma, rows, strict=True)
        )

    def linear(self, s_block: FloatArray, s_rows: FloatArray, out: FloatArray) -> list[float]:
        """The constant or time-variant bounds: the residual and bounds into ``out`` [N m];
        returns r̂ − U, then L − r̂, per joint.

        ``s_block`` is the new observer block, ``s_rows`` its rows R … ONE.
        """
        _multiply(self._gains, s_rows, out=self._scaled)
        rows = self._rows
        _dot(self._sums, self._scaled, out=rows)
        if self._whole:
            out[...] = rows[:3]
        else:
            out[0] = s_block[R]
            out[1:] = rows[:2]
        return self._excursions.tolist()

    def bins(
        self, filters: list[float], s_block: FloatArray, c_block: FloatArray, start: bool,
        out: FloatArray,
    ) -> list[float]:  # fmt: skip
        """The velocity-bin threshold (``table_bounds``) on the new block, joint by joint:
        the residual and bounds into ``out`` [N m]; returns r̂ − U, then L − r̂, per joint.

        ``filters`` are the rows R … SG of ``s_block`` as one list, ``c_block`` the
        committed observer block. The bin is ``bisect_right(edges, q̇)``
        (``searchsorted(..., "right")``); the filter of τ_fme starts at ``start``
        (the first sample after the settling window).
        """
        n, edges = len(self._joints), self._edges
        residual = filters[:n]
        last = [None] * n if start else c_block[BIN].tolist()
        filtered, lower, upper, above, below = [], [], [], [], []
        for (pole, weight, gamma, rows), v, r, h, friction in zip(
            self._joints, s_block[V].tolist(), residual, filters[n : 2 * n], last, strict=True
        ):
            fme, low, high = rows[_bisect(edges, v)]
            if friction is None:
                friction = fme
            filtered.append(weight * fme + pole * friction)
            centre = gamma * h + friction
            low += centre
            high += centre
            lower.append(low)
            upper.append(high)
            above.append(r - high)  # no product: 0 · ∞ for a joint not monitored
            below.append(low - r)
        s_block[BIN] = filtered
        out[...] = (residual, lower, upper)
        above += below
        return above


class EventRules:
    """``Detector._step_checked`` and the latch on the stream's :class:`Flags`.

    ``monitored``: the joints watched (0-based); durations [s] already less
    the Detector's time tolerance; ``release`` NaN for a latch that holds.
    """

    def __init__(
        self, monitored: list[int], min_duration: float, hold: float, release: float
    ) -> None:
        self._monitored, self._min_duration, self._hold = monitored, min_duration, hold
        self._release = release

    def __call__(
        self, fl: Flags, time: float, excursions: list[float], out: FloatArray,
        closed: tuple[float, ...],
    ) -> tuple[int, tuple[float, ...]]:  # fmt: skip
        """``Detector._step_checked`` and the latch on the flags: (status | mask << 5, event).

        ``excursions`` are r̂ − U then L − r̂ per joint [N m].
        """
        n = len(excursions) // 2
        mask = 0
        if max(excursions) > 0.0:
            best, worst = -1, 0.0
            for j in self._monitored:
                above, below = excursions[j], excursions[n + j]
                excursion = above if above > below else below
                if excursion > 0.0:
                    mask |= 1 << j
                if best < 0 or excursion > worst:
                    best, worst = j, excursion
            residual = float(out[0, best])
            if fl.open and (fl.outside or time - fl.open_end < self._hold):
                fl.open_end = time
                fl.open_joints |= mask
                if not worst <= fl.open_peak:
                    fl.open_peak, fl.open_peak_residual = worst, residual
            else:
                closed = self.lasted(fl) or closed
                fl.open, fl.open_start, fl.open_end = True, time, time
                fl.open_joints, fl.open_peak, fl.open_peak_residual = mask, worst, residual
        elif fl.open and time - fl.open_end >= self._hold:
            closed = self.lasted(fl) or closed
            fl.open = False
        fl.outside = mask != 0
        if mask and fl.open and time - fl.open_start >= self._min_duration:
            fl.latched, fl.inside_since = True, math.nan
            return COLLISION | mask << JOINTS_SHIFT, closed
        if fl.latched and not math.isnan(self._release):
            if mask:
                fl.inside_since = math.nan
            elif math.isnan(fl.inside_since):
                fl.inside_since = time
            if time - fl.inside_since >= self._release:
                fl.latched, fl.inside_since = False, math.nan
        return (COLLISION if fl.latched else OK) | mask << JOINTS_SHIFT, closed

    def lasted(self, fl: Flags) -> tuple[float, ...]:
        """The open event's fields if it lasted ``min_duration``, else ()."""
        if fl.open and fl.open_end - fl.open_start >= self._min_duration:
            return (fl.open_start, fl.open_end, fl.open_joints, fl.open_peak, fl.open_peak_residual)
        return ()


class Flags:
    """The stream's scalars: time rules, detector and latch."""

    __slots__ = (
        "floor", "has_detector", "has_stream", "inside_since", "latched", "open", "open_end",
        "open_joints", "open_peak", "open_peak_residual", "open_start", "outside", "pending",
        "start", "t_last",
    )  # fmt: skip

    def __init__(self) -> None:
        self.has_stream = self.has_detector = self.latched = self.open = self.outside = False
        self.start = self.t_last = self.open_start = self.open_end = 0.0
        self.open_peak = self.open_peak_residual = 0.0
        self.floor = self.pending = -math.inf
        self.inside_since = math.nan
        self.open_joints = 0

    def __copy__(self) -> Flags:
        new = Flags.__new__(Flags)
        for name in self.__slots__:
            setattr(new, name, getattr(self, name))
        return new


def layout(buffer: FloatArray, m: int, check: int) -> tuple[Any, ...]:
    """Views of a buffer (section states, then the observer block), as :meth:`_step` reads them."""
    block = buffer[m:]
    return (
        buffer[:m], block[V], block[Q], block[TM], block[TJ], block[V : V + check],
        block[: SG + 1], block[P : SG + 1], block[R : ONE + 1], block[R : SG + 1].reshape(-1),
        block, block_views(block),
    )  # fmt: skip


def block_views(block: FloatArray) -> tuple[FloatArray, ...]:
    """Rows P1 … VV1, the sign rows S1 … VV1, the friction rows FA … FC, the row FA,
    the observer's input (P1 … SG) and the block itself."""
    return (
        block[P1], block[C1], block[G1], block[S1], block[SS1], block[VV1],
        block[S1 : VV1 + 1], block[FA : FC + 1], block[FA], block[: SG + 1], block,
    )  # fmt: skip


# Bound once: each module attribute lookup costs as much as a line of arithmetic.
_multiply, _dot, _bisect = np.multiply, np.dot, bisect_right
