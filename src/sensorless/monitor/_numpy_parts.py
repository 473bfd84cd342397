"""Parts of the numpy stream (:mod:`._numpy_stream`): row layout, observer matrix, bounds.

The rows of one observer block, the matrix of the observer's update over
them and the bounds of the constant, time-variant and velocity-bin
thresholds on them (the detector and the latch: :mod:`._numpy_rules`).
Needs no numba. Units SI and radians.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._validation import FloatArray
from ..friction.static import Coulomb, CoulombViscous, HystereticError, Viscous
from ..thresholds import ConstantThreshold, TimeVariantThreshold, VelocityThreshold

__all__ = [
    "Bounds",
    "block_views",
    "layout",
    "limits_check",
    "observer_matrix",
    "start_rows",
]

# Rows of the observer block (one block per buffer, and one for a (re)start): this sample's
# p + g (one rnea of the model), Cᵀq̇, g, sign, sign², q̇ and three friction rows whose sum is
# τ̂_fr (scratch); the state:
# q̇, q, τ_m, τ_J (the rows the limits check), the last sample's p, Cᵀq̇ − g, τ̂_fr and sign,
# the filters r̂, h, filtered τ̂_fr and filtered sign; a row of ones; for the velocity bins: the
# filter of τ_fme before this sample (a copy of the last BIN, or τ_fme at its start), this
# sample's bin entries (L and U less the centre, τ_fme), the filter of τ_fme. For the
# constant bounds instead: −r̂ and r̂ (copies the product writes), then L and U (constant rows).
P1, C1, G1, S1, SS1, VV1, FA, FB, FC = range(9)
V, Q, TM, TJ, P, VG, FR, SG0, R, H, F, SG, ONE, BP, LO, HI, FME, BIN = range(9, 27)
NR, RR, LC, UC = range(BP, BP + 4)


def observer_matrix(
    dt: float, weight: float, pole: float, tau: int, bins: tuple[float, float] | None = None,
    constant: bool = False,
) -> FloatArray:  # fmt: skip
    """Rows P … SG of the new state from the rows P1 … SG of the observer block.

    ``MomentumObserver._step_checked`` as one product: the inputs of the four
    filters (increment of p over dt, trapezoid of Cᵀq̇ − g and τ̂_fr, held τ
    in the row ``tau``), then y′ = ``weight`` · input + ``pole`` · y. The row
    P1 holds p + g (p = P1 − G1). With ``bins`` (the weight and pole of the
    velocity bins' filter of τ_fme, the same for every joint): rows P … BIN
    from the rows P1 … BIN, the rows ONE, LO, HI and FME copied, BP a copy of BIN
    and BIN′ = weight · FME + pole · BIN. With ``constant``: rows P … RR from
    the rows P1 … ONE, ONE copied, NR = −r̂′ and RR = r̂′.
    """
    if constant:
        w = np.zeros((RR - P + 1, ONE + 1))
        w[: SG - P + 1, : SG + 1] = observer_matrix(dt, weight, pole, tau)
        w[ONE - P, ONE] = 1.0
        w[NR - P], w[RR - P] = -w[R - P], w[R - P]
        return w
    if bins is not None:
        w = np.zeros((BIN - P + 1, BIN + 1))
        w[: SG - P + 1, : SG + 1] = observer_matrix(dt, weight, pole, tau)
        for row, source in ((ONE, ONE), (LO, LO), (HI, HI), (FME, FME), (BP, BIN)):
            w[row - P, source] = 1.0
        w[BIN - P, FME], w[BIN - P, BIN] = bins
        return w
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

    Time-variant (forms "friction" and "hysteretic"): with the rows x = (r̂, h,
    filtered τ̂_fr, filtered sign, 1) of the observer block, [L, U, r̂ − U,
    L − r̂] = S @ (G ∘ x), G the per-joint gains (γ, ε_fr or −c, α). A joint
    not monitored has G = (0, 0, 0, 0, ∞): its bounds are ∓∞ and a non-finite
    filter gives NaN (0 · ∞), as for the others. Velocity bins: x = (r̂, h,
    filtered τ̂_fr, filtered sign, 1, τ_fme filtered up to the last sample,
    L − c, U − c) with c the bin's centre (this sample's bin entries, by
    ``lookup_parts``; the observer's product copies them), G = (1, γ, 0, 0, 0,
    1, 1, 1), (0, …, 0, ∞, 0, 0, 0) for a joint not monitored. The stream reads
    ``parts``: G, a buffer for G ∘ x, S, the rows S @ (G ∘ x), those of them
    the verdict's rows L and U (r̂, L, U when every joint is monitored), whether
    every joint is, and the excursions r̂ − U, L − r̂ as one row. Constant: L
    and U are constant rows ``low_up`` (−β, β; ∓∞ for a joint not monitored)
    and the observer's product gives −r̂ and r̂; ``constant_parts``: [−L, U],
    the excursions [L − r̂, r̂ − U] ([−r̂, r̂] − [−L, U]) and them as one row.
    ``pair``: the two rows of excursions, for the detector.
    """

    def __init__(self, threshold: Any, dt: float, monitored: Any) -> None:
        n = monitored.size
        self.velocity = isinstance(threshold, VelocityThreshold)
        self.bins: tuple[float, float] | None = None
        self.bin_gains: tuple[FloatArray, FloatArray] | None = None
        # [r̂, L, U, r̂ − U, L − r̂]; the row r̂ only when every joint is monitored (0 · ∞)
        if self.velocity:  # columns r̂, h, F, SG, 1, last filtered τ_fme, L − c, U − c
            sums = [[1, 0, 0, 0, 0, 0, 0, 0], [0, 1, 0, 0, -1, 1, 1, 0], [0, 1, 0, 0, 1, 1, 0, 1],
                    [1, -1, 0, 0, -1, -1, 0, -1], [-1, 1, 0, 0, -1, 1, 1, 0]]  # fmt: skip
        else:
            sums = [[1, 0, 0, 0, 0], [0, 1, 1, 1, -1], [0, 1, 1, 1, 1], [1, -1, -1, -1, -1],
                    [-1, 1, 1, 1, -1]]  # fmt: skip
        self._whole = bool(monitored.all())
        self._sums = np.array(sums if self._whole else sums[1:], dtype=np.float64)
        gains = np.zeros((len(sums[0]), n))
        gains[0] = 1.0
        if isinstance(threshold, ConstantThreshold):
            gains[4] = threshold.beta_
        elif isinstance(threshold, TimeVariantThreshold):
            gains[1], gains[4] = threshold.gamma_, threshold.alpha_
            hysteretic = threshold.form == "hysteretic"
            gains[3 if hysteretic else 2] = -threshold.c_ if hysteretic else threshold.eps_fr_
        else:
            gains[1], gains[5:] = threshold.gamma_, 1.0
            self._read_bins(threshold, dt, monitored)
        gains[:, ~monitored] = 0.0
        gains[4, ~monitored] = np.inf
        self._gains, self._scaled = gains, np.empty(gains.shape)
        self._rows = np.empty((self._sums.shape[0], n))
        self._excursions = self._rows[-2:].reshape(-1)
        self.constant = isinstance(threshold, ConstantThreshold)
        self.low_up = np.stack([-gains[4], gains[4]])  # the rows LC and UC of the buffers
        if self.constant:  # [L − r̂, r̂ − U]
            self._rows = np.empty((2, n))
            self._excursions = self._rows.reshape(-1)
        negated = np.stack([-self.low_up[0], self.low_up[1]])
        self.constant_parts = (negated, self._rows, self._excursions)
        self.pair = self._rows[-2:]
        self.parts = (
            self._gains, self._scaled, self._sums, self._rows,
            self._rows[:3] if self._whole else self._rows[:2], self._whole, self._excursions,
        )  # fmt: skip

    def _read_bins(self, threshold: VelocityThreshold, dt: float, monitored: Any) -> None:
        """The bin table by r = searchsorted(edges, q̇, "right") (0 … n_edges), per joint,
        and the filter of τ_fme (``first_order``).

        Entry r of joint j holds L and U less the centre, and τ_fme [N m], of its bin
        clip(r − 1) (``bin_index``), L and U widened by the extrapolation margin where r
        says q̇ is outside the visited bins (``table_bounds``); zeros for a joint not
        monitored (its gains make the bounds ∓∞). ``bins``: the filter's weight and pole in
        the observer's product (1, 0 when the joints' differ: then ``bin_gains``, per joint,
        after it).
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
                threshold.lower_[bins, joint] - widen,
                threshold.upper_[bins, joint] + widen,
                threshold.tau_fme_[bins, joint],
            ]
        )  # (3, n_edges + 1, n_dof): the rows LO, HI, FME
        table[:, :, ~monitored] = 0.0
        self._edges = edges
        # column j · (n_edges + 1) + r: the entries of joint j at r (one index for three rows)
        self._table = np.ascontiguousarray(table.transpose(0, 2, 1)).reshape(3, -1)
        self._base = np.arange(n) * (edges.size + 1)
        self._index = np.empty(n, dtype=np.int64)
        step = np.broadcast_to(threshold.gain_, (n,)) * dt  # the filter of first_order
        weight, pole = -np.expm1(-step), np.exp(-step)
        uniform = bool(np.all(step == step[0]))
        self.bins = (float(weight[0]), float(pole[0])) if uniform else (1.0, 0.0)
        self.bin_gains = None if uniform else (weight, pole)
        self.lookup_parts = (edges, self._base, self._index, self._table)
        """This sample's bin entries at the velocity v into the rows LO … FME of a block:
        ``add(edges.searchsorted(v, "right"), base, index)``, then
        ``table.take(index, 1, rows, "clip")``."""


def limits_check(limits: Any, check: int) -> tuple[FloatArray, tuple[Any, ...]]:
    """The centres of the rows q̇, q, τ_m (, τ_J) and their check against ``limits``.

    [−limit, x − centre, limit]: |x − centre| <= limit is one comparison of
    the first two blocks with the last two (exact: negation is), NaN failing
    both; all inside when the comparisons' bytes are those of all True
    (cheaper than a count). Returns the centres (check, n_dof) and (x − centre,
    first blocks, last blocks, bytes of all True, comparisons).
    """
    n = limits.centre.shape[0]
    centre = np.zeros((check, n))
    centre[1] = limits.centre
    limit = np.stack([limits.velocity, limits.half_range, *[limits.torque] * (check - 2)])
    between = np.stack([-limit, np.zeros_like(limit), limit])
    inside = np.empty((2, check, n), dtype=bool)
    return centre, (between[1], between[:2], between[1:], np.ones_like(inside).tobytes(), inside)


def start_rows(terms: FloatArray, block: FloatArray, tau: int) -> None:
    """``MomentumObserver.initial_state`` from the rows P1 … FC of ``terms`` into ``block``
    (the held torque into the row ``tau``)."""
    p, vg, sign = terms[P1] - terms[G1], terms[C1] - terms[G1], terms[S1].copy()
    friction = terms[FA] + terms[FB] + terms[FC]
    block[P], block[VG], block[FR], block[SG0] = p, vg, friction, sign
    block[tau], block[R], block[H] = friction - vg, 0.0, -vg
    block[F], block[SG] = friction, sign


def layout(buffer: FloatArray, m: int, check: int, kind: str) -> tuple[Any, ...]:
    """Views of a buffer (section states, then the observer block), as :meth:`_step` reads them.

    ``kind`` "velocity": the observer's product also writes the rows ONE … BIN, the bounds
    read R … HI; "constant": the product writes ONE … RR, the bounds read NR … RR and the
    verdict's rows are RR … UC; else the product writes P … SG, the bounds read R … ONE.
    """
    block = buffer[m:]
    last, rows = {"velocity": (BIN, (R, HI)), "constant": (RR, (NR, RR))}.get(kind, (SG, (R, ONE)))
    views = (
        buffer[:m], block[V], block[Q], block[TM], block[TJ], block[V : V + check],
        block[RR : UC + 1], block[P : last + 1], block[rows[0] : rows[1] + 1],
        block[R : SG + 1].reshape(-1), block, block_views(block, kind),
    )  # fmt: skip
    return (*views, views[1:11])  # the last: the ten a sample unpacks, as one tuple


def block_views(block: FloatArray, kind: str = "") -> tuple[FloatArray, ...]:
    """Rows P1 … VV1, the sign rows S1 … VV1, the friction rows FA … FC, the row FA,
    the bin entries LO … FME, the observer's input (P1 … SG; P1 … BIN for ``kind``
    "velocity", P1 … ONE for "constant") and the block itself."""
    last = {"velocity": BIN, "constant": ONE}.get(kind, SG)
    return (
        block[P1], block[C1], block[G1], block[S1], block[SS1], block[VV1],
        block[S1 : VV1 + 1], block[FA : FC + 1], block[FA], block[LO : FME + 1],
        block[: last + 1], block,
    )  # fmt: skip
