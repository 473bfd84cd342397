"""Time-variant thresholds b_2H, b_2L of eq. (5.33) and their hysteretic form, eq. (5.39).

With h(t) = K_I/(s+K_I)·(M q̈ + C q̇ + g) of the nominal model (eq. 5.30) and
the filtered nominal friction f(t) = K_I/(s+K_I)·τ̂_fr, eq. (5.33) bounds the
residual of joint j by

    b_2L,j(t) = -α_j + γ_j h_j(t) + ε_fr,j f_j(t)
    b_2H,j(t) = +α_j + γ_j h_j(t) + ε_fr,j f_j(t).

On a robot whose friction error is hysteretic rather than proportional to
the nominal friction (eq. 5.38, KUKA LWR), the friction term becomes
-C_j·K_I/(s+K_I)·sign(q̇_j) (eq. 5.39, ``form="hysteretic"``).

Fit (section 5.3.3, "tuned experimentally by having the robot follow few
different trajectories"): for every joint, γ and ε_fr (or C) are the least
squares solution of r̂ ≈ γ h + ε_fr f (or r̂ ≈ γ h - C·sign) over the samples
of all fit runs, and α is the largest remaining |r̂ - γ h - ε_fr f|, plus
``margin``. Since α, not the squared error, is the width of the band,
``fit_method="minimax"`` goes past the thesis: γ, ε_fr and α solve the
Chebyshev (L∞) problem min α s.t. |r̂ - γ h - ε_fr f| ≤ α as a linear program
(scipy.optimize.linprog, HiGHS) on at most ``max_lp_samples`` evenly spaced
samples per joint; α is then recomputed on every sample. γ = ε_fr = 0 is
feasible, so on the fitted samples the minimax α never exceeds β.
``beta_`` is the constant threshold of eq. (5.32) on the same samples, so that
``efficiency_ = alpha_ / beta_`` is the eff of Table 5.7
(smaller is better).

Examples
--------
>>> import numpy as np
>>> from sensorless.signals import ObserverSignals
>>> t = np.arange(200) * 1e-3
>>> h = np.sin(7 * t)[:, None]
>>> f = np.cos(3 * t)[:, None]
>>> r = -0.05 * h + 0.3 * f + 0.01 * np.sign(np.sin(50 * t))[:, None]
>>> z = np.zeros_like(r)
>>> run = ObserverSignals(t, r, h, f, z, z, gain=20.0, robot="demo")
>>> th = TimeVariantThreshold().fit(run)
>>> bool(th.alpha_[0] < th.beta_[0])
True
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy.optimize import linprog

from .._validation import FloatArray, check_int
from ..exceptions import InputValueError
from ..signals import ObserverSignals
from .base import StreamBounds, Threshold
from .fitting import BoolArray, rounding_guard, stack
from .state import ThresholdInputs, ThresholdState

__all__ = ["FORMS", "TimeVariantThreshold"]

FIT_METHODS = ("least_squares", "minimax")
FORMS = ("friction", "hysteretic")
"""Forms of the friction term: ε_fr·filtered friction (eq. 5.33), -C·filtered sign (eq. 5.39)."""
_COEFFICIENTS = {"friction": "eps_fr_", "hysteretic": "c_"}


class TimeVariantThreshold(Threshold):
    """Bounds ±α + γ h + ε_fr·K_I/(s+K_I)τ̂_fr (eq. 5.33) or ±α + γ h - C·K_I/(s+K_I)sign q̇ (5.39).

    Parameters
    ----------
    margin : float or array-like of shape (n_dof,)
        Added to α (and to β) [N m], >= 0.
    form : {"friction", "hysteretic"}
        Friction term of eq. (5.33) or of eq. (5.39).
    joints, transient
        As for every family, see :class:`~sensorless.thresholds.base.Threshold`.
    fit_method : {"least_squares", "minimax"}
        How γ and ε_fr (or C) are fitted (see the module docstring).
    max_lp_samples : int
        Samples per joint the minimax linear program uses at most.

    Attributes
    ----------
    alpha_ : ndarray of shape (n_dof,)
        Constant half-width α [N m] (includes ``margin``).
    gamma_ : ndarray of shape (n_dof,)
        Coefficient γ of h [-].
    eps_fr_ : ndarray of shape (n_dof,)
        Coefficient ε_fr of the filtered friction [-] (``form="friction"``).
    c_ : ndarray of shape (n_dof,)
        Coefficient C of the filtered sign [N m] (``form="hysteretic"``).
    beta_ : ndarray of shape (n_dof,)
        Constant threshold β of eq. (5.32) on the same samples [N m] (includes ``margin``).
    """

    name = "time-variant"

    alpha_: FloatArray
    gamma_: FloatArray
    eps_fr_: FloatArray
    c_: FloatArray
    beta_: FloatArray

    def __init__(
        self,
        margin: Any = 0.0,
        form: str = "friction",
        *,
        joints: Any = None,
        transient: float = 0.0,
        fit_method: str = "least_squares",
        max_lp_samples: int = 20_000,
    ) -> None:
        super().__init__(margin, joints=joints, transient=transient)
        self.form = form
        self.fit_method = fit_method
        self.max_lp_samples = max_lp_samples

    @property
    def efficiency_(self) -> FloatArray:
        """eff = α/β per joint (Table 5.7) [-]; smaller means a tighter threshold."""
        self._check_fitted()
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.asarray(self.alpha_ / self.beta_)

    def _check_form(self) -> str:
        if self.form not in FORMS:
            raise InputValueError(f"form must be one of {list(FORMS)}; got {self.form!r}")
        return str(self.form)

    def _coefficient_name(self) -> str:
        return _COEFFICIENTS[self._check_form()]

    def _attribute_names(self) -> tuple[str, ...]:
        return ("alpha_", "gamma_", self._coefficient_name(), "beta_")

    def _centre(
        self, gamma: FloatArray, coefficient: FloatArray, inputs: ThresholdInputs
    ) -> FloatArray:
        """b_2V(t) = γ h + ε_fr f (eq. 5.29) or γ h - C·sign (eq. 5.39); ``form`` is checked."""
        if self.form == "friction":
            return gamma * inputs.model_torque + coefficient * inputs.friction
        return gamma * inputs.model_torque - coefficient * inputs.sign

    def _fit(self, runs: list[ObserverSignals], keep: list[BoolArray], margin: FloatArray) -> None:
        form = self._check_form()
        if self.fit_method not in FIT_METHODS:
            raise InputValueError(
                f"fit_method must be one of {list(FIT_METHODS)}; got {self.fit_method!r}"
            )
        # Two coefficients per joint: the linear program needs more samples than that.
        max_samples = check_int(self.max_lp_samples, "max_lp_samples", 3, "TimeVariantThreshold")
        residual = stack(runs, keep, "residual")
        inputs = ThresholdInputs(*(stack(runs, keep, name) for name in ThresholdInputs._fields[:4]))
        # The hysteretic term enters with a minus sign: regress on -sign to get C directly.
        second = inputs.friction if form == "friction" else -inputs.sign
        n_dof = residual.shape[1]
        gamma = np.empty(n_dof)
        coefficient = np.empty(n_dof)
        for j in range(n_dof):
            design = np.column_stack([inputs.model_torque[:, j], second[:, j]])
            if self.fit_method == "minimax":
                gamma[j], coefficient[j] = _chebyshev(design, residual[:, j], max_samples)
            else:
                solution = np.linalg.lstsq(design, residual[:, j], rcond=None)[0]
                gamma[j], coefficient[j] = solution
        centre = self._centre(gamma, coefficient, inputs)
        error = residual - centre
        self.gamma_ = gamma
        setattr(self, _COEFFICIENTS[form], coefficient)
        self.alpha_ = np.max(np.abs(error), axis=0) + margin + rounding_guard(residual, centre)
        self.beta_ = np.max(np.abs(residual), axis=0) + margin

    def _run(self, state: ThresholdState, inputs: ThresholdInputs) -> StreamBounds:
        # form was checked by fit or from_dict (through _attribute_names)
        centre = self._centre(self.gamma_, getattr(self, _COEFFICIENTS[self.form]), inputs)
        return centre - self.alpha_, centre + self.alpha_, state


def _chebyshev(design: FloatArray, target: FloatArray, max_samples: int) -> FloatArray:
    """Coefficients x minimising max |target - design x| (L∞ fit) by linear programming.

    ``max_samples`` (> the number of columns of ``design``) evenly spaced rows are used at most.
    """
    step = max(1, int(np.ceil(design.shape[0] / max_samples)))
    a, b = design[::step], target[::step]
    ones = np.ones((a.shape[0], 1))
    # Variables (x, α): minimise α subject to ±(b - a x) ≤ α.
    a_ub = np.vstack([np.hstack([-a, -ones]), np.hstack([a, -ones])])
    b_ub = np.concatenate([-b, b])
    cost = np.zeros(a.shape[1] + 1)
    cost[-1] = 1.0
    bounds = [(None, None)] * a.shape[1] + [(0.0, None)]
    result = linprog(cost, A_ub=a_ub, b_ub=b_ub, bounds=bounds, method="highs")
    if not result.success:
        raise InputValueError(f"minimax fit failed: {result.message}")
    return np.asarray(result.x[:-1])
