"""A threshold that allows for a declared payload: a gripped object up to a mass is no collision.

An object gripped by the end link and missing from the nominal model moves
the momentum residual by its weight and inertia for as long as it is held;
every family fitted without it calls that a collision. :class:`PayloadThreshold`
wraps any threshold and widens its bounds, per joint and per sample, by the
largest residual that a payload within a declared range can produce at the
current state:

* **the range**: a mass of at most ``max_mass`` [kg] whose matter lies inside a
  ball (``radius`` [m]) or a box (``half_widths`` [m]) centred at ``center``
  in the end-link frame [m] (the frame of the last joint). Its centre of mass
  is then inside that region and its inertia is bounded by the region's size.
* **its residual**: in free motion a payload with standard parameters π_L
  (about the end-link origin) adds Ψ(q, q̂̇) π_L to r̂, with Ψ the end link's
  regressor filtered as the observer filters
  (:mod:`sensorless.identification._payload_regressor`: from q and the
  velocity the observer used, no q̈).
* **its range at a sample**: π_L of a body in the region is the mass-weighted
  sum of the parameters φ(p) of its points p, and Ψ_j φ(p) = pᵀA_j p + b_jᵀp + c_j
  is a quadratic in p. With p = center + u: its linear part over a ball is
  bounded exactly (±r|b'|) and its quadratic part by r²·λ_min/max(A_j) (over
  a box: Σ|b'_i|h_i and Σ|A_ik|h_i h_k). A mass μ in [0, max_mass] scales it, so
  joint j's residual moves by at most [m_max·min(0, q_min), m_max·max(0, q_max)]:
  the lower bound is lowered and the upper raised by those amounts. The
  widening is a true bound (never smaller than the payload's residual), tight
  in the gravity and first-moment terms that dominate.
* **start**: the bounds of a stream begin with the first sample held since
  forever (as every family), while the observer may have started with that
  sample and its payload part from zero. The difference, −λ a^k Ψ_0 π_L with
  a = exp(−K_I dt) and λ in [0, 1], is added as a start-up term that decays
  with the observer's own time constant; so the bounds hold for an observer
  started with the stream or earlier at rest.
* **the velocity estimate** (``velocity_error``, off by default): the
  observer's payload part is Ψ(q, q̇) π_L with the *true* velocity, the
  widening uses the estimate q̂̇. Through the momentum the difference is
  K_I s/(s+K_I)·M_L(q)(q̇ − q̂̇); with |q̂̇_i − q̇_i| ≤ δ_i it is at most
  K_I (B + K_I/(s+K_I)·B), B_j = Σ_i max|M_L(q)_ji| δ_i over the range (its
  part through Cᵀq̇ − g, of order |q̇|/K_I of this, is left out). Backward
  differences of encoder steps Δq give δ ≈ Δq/dt (0.01 rad/s for 1e-5 rad at
  1 kHz): a 2 kg payload then moves r̂ of the panda's joint 1 by 0.3 N m, a
  third of what the payload itself does there.

Fitting fits a copy of the wrapped threshold on the collision-free runs
(payload-free, as usual); :meth:`PayloadThreshold.from_fitted` wraps a
threshold fitted already. The payload threshold needs the joint positions in
its inputs (``ObserverSignals.position``, which observers record, and the
``position`` of ``step``).

It is not a family of its own (``tune(..., payload=...)`` wraps any family).
Its file (``method: payload``, :mod:`._payload_file`) holds the declared range
and the wrapped threshold, and names its nominal model, which the reader
takes from ``load_threshold(path, robot=...)`` or from the built-in robots.
"""

from __future__ import annotations

import copy
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike
from scipy import signal

from .._validation import (
    FloatArray,
    as_float_array,
    check_finite,
    check_scalar,
    check_type,
    per_joint,
)
from ..exceptions import DimensionError, InputTypeError, InputValueError, ModelMismatchError
from ..identification._payload_regressor import PayloadRegressor, filter_coefficients
from ..robots.model import RobotModel
from ..signals import ObserverSignals
from ._payload_file import PAYLOAD_METHOD, payload_to_dict, read_payload
from .base import StreamBounds, Threshold
from .checks import regular_period
from .files import READERS
from .fitting import BoolArray
from .state import ThresholdInputs, ThresholdState

if TYPE_CHECKING:
    from ..identification._payload_regressor import RegressorState

__all__ = ["PayloadRange", "PayloadThreshold", "PayloadThresholdState", "point_parameters"]


def _vector3(value: ArrayLike, name: str) -> FloatArray:
    arr = as_float_array(value, name, "(3,)")
    if arr.shape != (3,):
        raise DimensionError(f"{name} must have shape (3,) [m]; got shape {arr.shape}")
    check_finite(arr, name)
    return arr


def point_parameters(point: FloatArray) -> FloatArray:
    """Standard parameters φ(p) of a 1-kg point mass at ``point`` [m], shape (10,).

    (y²+z², −xy, −xz, x²+z², −yz, x²+y²) [kg m²], (x, y, z) [kg m], 1 [kg]: the
    order of :data:`~sensorless.identification.payload.PAYLOAD_PARAMETER_NAMES`.
    """
    x, y, z = point
    return np.array(
        [y * y + z * z, -x * y, -x * z, x * x + z * z, -y * z, x * x + y * y, x, y, z, 1.0]
    )


def _check_threshold(threshold: object) -> None:
    if not isinstance(threshold, Threshold):
        raise InputTypeError(
            "threshold must be a Threshold (a family to widen, e.g. ConstantThreshold); got "
            f"{type(threshold).__name__}"
        )


@dataclass(frozen=True, eq=False)
class PayloadRange:
    """Payloads of at most ``max_mass`` whose matter lies in a ball or a box of the end-link frame.

    Parameters
    ----------
    max_mass : float
        Largest payload mass [kg], >= 0.
    center : array-like of shape (3,)
        Centre of the region in the end-link frame [m].
    radius : float, optional
        Radius of the ball [m], >= 0.
    half_widths : array-like of shape (3,), optional
        Half-widths of the box along the end-link axes [m], >= 0. Give
        ``radius`` or ``half_widths``; neither means a point (radius 0).
    """

    max_mass: float
    center: FloatArray
    radius: float | None = None
    half_widths: FloatArray | None = None

    def __post_init__(self) -> None:
        object.__setattr__(
            self, "max_mass", check_scalar(self.max_mass, "max_mass", "kg", "nonnegative")
        )
        object.__setattr__(self, "center", _vector3(self.center, "center"))
        if self.radius is not None and self.half_widths is not None:
            raise InputValueError(
                f"give radius (a ball) or half_widths (a box), not both; got radius="
                f"{self.radius!r}, half_widths={self.half_widths!r}"
            )
        if self.half_widths is None:
            radius = 0.0 if self.radius is None else self.radius
            object.__setattr__(self, "radius", check_scalar(radius, "radius", "m", "nonnegative"))
        else:
            widths = _vector3(self.half_widths, "half_widths")
            if (widths < 0).any():
                raise InputValueError(f"half_widths must be >= 0 [m]; got {widths.tolist()}")
            object.__setattr__(self, "half_widths", widths)

    def torque_range(
        self, psi: FloatArray, *, eigenvalues: bool = True
    ) -> tuple[FloatArray, FloatArray]:
        """Range of Ψ π_L over the payloads of the range, per row of ``psi``.

        The linear part is exact, the quadratic (inertial) part an outer
        bound (module docstring).

        Parameters
        ----------
        psi : ndarray of shape (..., 10)
            Rows of the payload regressor (standard parameters about the
            end-link origin, :data:`~sensorless.identification.payload.PAYLOAD_PARAMETER_NAMES`).
        eigenvalues : bool
            Bound the quadratic part over a ball by the eigenvalues of A (True)
            or, cheaper and wider, by Gershgorin's discs.

        Returns
        -------
        low, high : ndarray of shape (...)
            Bounds of Ψ π_L [N m]; ``low <= 0 <= high`` (no payload is in the range).

        Examples
        --------
        >>> box = PayloadRange(2.0, center=(0.0, 0.0, 0.1), half_widths=(0.05, 0.05, 0.0))
        >>> psi = np.zeros(10)
        >>> psi[9], psi[6] = -9.81, 9.81       # per kg at p: 9.81 (x − 1), x within ±0.05 m
        >>> low, high = box.torque_range(psi)   # 2 kg · 9.81 · (−1.05) ... 0 (no payload)
        >>> print(f"{float(low):.4f} {float(high):.4f}")
        -20.6010 0.0000
        """
        f = np.moveaxis(psi, -1, 0)
        # A of Ψφ(p) = pᵀA p + bᵀp + c, by its distinct entries (diagonal, then xy, xz, yz).
        diagonal = np.stack([f[3] + f[5], f[0] + f[5], f[0] + f[3]])
        off = -0.5 * np.stack([f[1], f[2], f[4]])
        c = self.center
        at_center = psi @ point_parameters(c)
        slope = f[6:9] + 2.0 * np.stack(
            [
                diagonal[0] * c[0] + off[0] * c[1] + off[1] * c[2],
                off[0] * c[0] + diagonal[1] * c[1] + off[2] * c[2],
                off[1] * c[0] + off[2] * c[1] + diagonal[2] * c[2],
            ]
        )
        # Σ_k≠i |A_ik| per row i (Gershgorin), and Σ_i≠k |A_ik| h_i h_k (the box).
        size = np.abs(off)
        row_reach = np.stack([size[0] + size[1], size[0] + size[2], size[1] + size[2]])
        if self.half_widths is None:
            radius = float(self.radius or 0.0)
            linear = radius * np.sqrt((slope**2).sum(axis=0))
            if eigenvalues:
                quad = np.empty((*psi.shape[:-1], 3, 3))
                for i in range(3):
                    quad[..., i, i] = diagonal[i]
                for value, (i, k) in zip(off, ((0, 1), (0, 2), (1, 2)), strict=True):
                    quad[..., i, k] = quad[..., k, i] = value
                spectrum = np.linalg.eigvalsh(quad)
                smallest, largest = spectrum[..., 0], spectrum[..., -1]
            else:
                smallest = (diagonal - row_reach).min(axis=0)
                largest = (diagonal + row_reach).max(axis=0)
            curve_low = radius**2 * np.minimum(smallest, 0.0)
            curve_high = radius**2 * np.maximum(largest, 0.0)
        else:
            h = self.half_widths
            linear = np.tensordot(h, np.abs(slope), 1)
            weights = np.array([h[0] * h[1], h[0] * h[2], h[1] * h[2]])
            cross = 2.0 * np.tensordot(weights, size, 1)
            scaled = diagonal * (h**2)[(slice(None),) + (None,) * (diagonal.ndim - 1)]
            curve_low = np.minimum(scaled, 0.0).sum(axis=0) - cross
            curve_high = np.maximum(scaled, 0.0).sum(axis=0) + cross
        low = at_center - linear + curve_low
        high = at_center + linear + curve_high
        mass = self.max_mass
        return mass * np.minimum(low, 0.0), mass * np.maximum(high, 0.0)


@dataclass(frozen=True, eq=False)
class PayloadThresholdState(ThresholdState):
    """Streaming state of a :class:`PayloadThreshold`.

    Attributes
    ----------
    base : ThresholdState
        State of the wrapped threshold.
    regressor : RegressorState
        Filter state of the payload regressor Ψ.
    startup : ndarray of shape (2, n_dof)
        Start-up widening of the lower and the upper bound at the next
        sample [N m], >= 0; it decays by a = exp(−K_I dt) per sample.

    ``zi`` holds K_I/(s+K_I)·B of the velocity term at the last sample [N m·s].
    """

    base: ThresholdState
    regressor: RegressorState
    startup: FloatArray


class PayloadThreshold(Threshold):
    """Any threshold, widened for payloads within a declared range (module docstring).

    Parameters
    ----------
    threshold : Threshold
        The family to widen (fitted by :meth:`fit` on a copy).
    robot : RobotModel
        The nominal model of the observer (without the payload).
    max_mass : float
        Largest payload mass [kg], >= 0.
    center : array-like of shape (3,)
        Centre of the payload's region in the end-link frame [m].
    radius : float, optional
        Radius of a ball holding the payload's matter [m].
    half_widths : array-like of shape (3,), optional
        Half-widths of a box holding it instead [m].
    velocity_error : float or array-like of shape (n_dof,)
        Bound δ on the error of the velocity the observer uses [rad/s], >= 0
        (module docstring); 0 leaves that term out.

    Attributes (after :meth:`fit`)
    ------------------------------
    threshold_ : Threshold
        The fitted wrapped threshold.
    range_ : PayloadRange
        The declared range, checked.
    velocity_error_ : ndarray of shape (n_dof,)
        δ per joint [rad/s].
    (and the common attributes of :class:`~sensorless.thresholds.base.Threshold`)

    Examples
    --------
    >>> import sensorless as sl
    >>> from sensorless.thresholds import ConstantThreshold
    >>> robot = sl.robots.load("panda")
    >>> widened = PayloadThreshold(ConstantThreshold(margin=0.5), robot, max_mass=2.5,
    ...                            center=(0.0, 0.0, 0.1), radius=0.1)
    >>> widened  # doctest: +ELLIPSIS
    PayloadThreshold(threshold=ConstantThreshold(...), robot=RobotModel(name='panda', ...), ...)
    """

    _state_type = PayloadThresholdState

    threshold_: Threshold
    range_: PayloadRange
    velocity_error_: FloatArray
    _regressor: PayloadRegressor

    def __init__(
        self,
        threshold: Threshold,
        robot: RobotModel,
        max_mass: float,
        *,
        center: ArrayLike = (0.0, 0.0, 0.0),
        radius: float | None = None,
        half_widths: ArrayLike | None = None,
        velocity_error: ArrayLike = 0.0,
    ) -> None:
        super().__init__()
        self.threshold = threshold
        self.robot = robot
        self.max_mass = max_mass
        self.center = center
        self.radius = radius
        self.half_widths = half_widths
        self.velocity_error = velocity_error

    # ----------------------------------------------------------------- fit

    def _check_hyper_parameters(self, n_dof: int, robot_name: str, fingerprint: str) -> None:
        _check_threshold(self.threshold)
        check_type(self.robot, RobotModel, "robot", " (the nominal model of the observer)")
        if self.robot.n_dof != n_dof:
            raise DimensionError(
                f"robot {self.robot.name!r} has {self.robot.n_dof} joints; the signals {n_dof}"
            )
        if (robot_name and robot_name != self.robot.name) or (
            fingerprint and fingerprint != self.robot.fingerprint
        ):
            raise ModelMismatchError(
                f"the signals come from the nominal model {robot_name!r}; robot is "
                f"{self.robot.name!r} with other parameters: pass the observer's model"
            )
        widths = None if self.half_widths is None else _vector3(self.half_widths, "half_widths")
        self.range_ = PayloadRange(
            self.max_mass, _vector3(self.center, "center"), self.radius, widths
        )
        self.velocity_error_ = per_joint(
            self.velocity_error, n_dof, "velocity_error", "rad/s", "nonnegative"
        )
        self._regressor = PayloadRegressor(self.robot)

    def _fit(self, runs: list[ObserverSignals], keep: list[BoolArray], margin: FloatArray) -> None:
        first = runs[0]
        self._check_hyper_parameters(first.n_dof, first.robot, first.fingerprint)
        self.threshold_ = copy.deepcopy(self.threshold).fit(runs)

    @classmethod
    def from_fitted(
        cls,
        threshold: Threshold,
        robot: RobotModel,
        max_mass: float,
        *,
        center: ArrayLike = (0.0, 0.0, 0.0),
        radius: float | None = None,
        half_widths: ArrayLike | None = None,
        velocity_error: ArrayLike = 0.0,
    ) -> PayloadThreshold:
        """Wrap a threshold fitted already (no refit); parameters as for the class."""
        out = cls(
            threshold,
            robot,
            max_mass,
            center=center,
            radius=radius,
            half_widths=half_widths,
            velocity_error=velocity_error,
        )
        _check_threshold(threshold)
        threshold._check_fitted()
        out._check_hyper_parameters(threshold.n_dof_, threshold.robot_, threshold.fingerprint_)
        out.threshold_ = copy.deepcopy(threshold)
        for name in ("robot_", "fingerprint_", "kind_", "n_dof_", "gain_", "dt_"):
            setattr(out, name, copy.deepcopy(getattr(threshold, name)))
        return out

    def _attribute_names(self) -> tuple[str, ...]:
        return ()

    def to_dict(self) -> dict[str, Any]:
        """The fitted threshold as plain values: the declared range and the wrapped threshold."""
        self._check_fitted()
        return payload_to_dict(self)

    @classmethod
    def from_dict(
        cls,
        data: Mapping[str, Any],
        *,
        robot: RobotModel | None = None,
        source: str = "threshold description",
    ) -> PayloadThreshold:
        """Rebuild a fitted payload threshold from :meth:`to_dict` output.

        ``robot`` is the nominal model it was fitted with; without it, the
        built-in robot of the file's name and fingerprint (:mod:`._payload_file`).

        Raises
        ------
        FileFormatError
            The description does not follow the format (every problem with the
            path of its field).
        ModelMismatchError
            ``robot`` is another model, or none was given and no built-in is the file's.
        """
        return _read(data, source, robot)

    # ----------------------------------------------------------------- delegation

    @property
    def monitored_joints_(self) -> tuple[int, ...]:
        """Monitored joints of the wrapped threshold, 1-based."""
        self._check_fitted()
        return self.threshold_.monitored_joints_

    def model_fingerprint(self, kind: str) -> str:
        """Fingerprint of the wrapped threshold's fit runs of signal ``kind``."""
        return self.threshold_.model_fingerprint(kind)

    def _check_kind(self, kind: str | None) -> None:
        self.threshold_._check_kind(kind)

    def _period(self, t: FloatArray, what: str) -> float:
        # The regressor filter needs a regular period, whatever the wrapped family does.
        self.threshold_._period(t, what)
        return regular_period(t, what)

    # ----------------------------------------------------------------- bounds

    def _initial_state_checked(
        self, inputs: ThresholdInputs, dt: float, kind: str | None = None
    ) -> ThresholdState:
        if inputs.position is None:
            raise InputValueError(
                "a PayloadThreshold needs the joint positions: signals with position (as "
                "observers record them) or position= in initial_state and step"
            )
        base = self.threshold_._initial_state_checked(inputs, dt, kind)
        q0, qd0 = inputs.position[:1], inputs.velocity[:1]
        regressor = self._regressor.initial_state(q0, qd0, held=True)
        low, high = self.range_.torque_range(regressor.filtered)
        startup = np.stack([high, -low])
        noise = self._velocity_bound(inputs.position[:1])[0]
        return PayloadThresholdState(dt, noise, base, regressor, startup)

    def _velocity_bound(self, q: FloatArray) -> FloatArray:
        """B_j = Σ_i max|M_L(q)_ji| δ_i over the range, shape (n_samples, n_dof) [N m s]."""
        if not self.velocity_error_.any():
            return np.zeros_like(q)
        columns = self._regressor.mass_columns(q)
        low, high = self.range_.torque_range(columns, eigenvalues=False)
        return np.asarray(np.maximum(-low, high) @ self.velocity_error_)

    def _run(self, state: ThresholdState, inputs: ThresholdInputs) -> StreamBounds:
        assert isinstance(state, PayloadThresholdState)  # checked by the public entry points
        if inputs.position is None:
            raise InputValueError("a PayloadThreshold needs position at every sample")
        lower, upper, base = self.threshold_._process_checked(state.base, inputs)
        psi, regressor = self._regressor.filter(
            state.regressor, inputs.position, inputs.velocity, self.gain_, state.dt
        )
        low, high = self.range_.torque_range(psi)
        pole, _ = filter_coefficients(self.gain_, state.dt)
        decay = pole[None, :] ** np.arange(psi.shape[0])[:, None]
        lower = lower + low - state.startup[0] * decay
        upper = upper + high + state.startup[1] * decay
        zi = state.zi
        if self.velocity_error_.any():
            noise = self._velocity_bound(inputs.position)
            filtered = _filter_held(noise, pole, state.zi)
            velocity = self.gain_ * (noise + filtered)
            lower -= velocity
            upper += velocity
            zi = filtered[-1]
        startup = state.startup * pole ** psi.shape[0]
        return lower, upper, PayloadThresholdState(state.dt, zi, base, regressor, startup)


def _read(data: Mapping[str, Any], source: str, robot: RobotModel | None) -> PayloadThreshold:
    """The reader of ``payload`` descriptions (:data:`~sensorless.thresholds.files.READERS`)."""
    threshold = read_payload(data, source, robot, PayloadThreshold.from_fitted)
    assert isinstance(threshold, PayloadThreshold)  # what from_fitted builds
    return threshold


READERS[PAYLOAD_METHOD] = _read


def _filter_held(x: FloatArray, pole: FloatArray, last: FloatArray) -> FloatArray:
    """y_k = a y_k−1 + (1 − a) x_k per column, y_−1 = ``last`` (the observer's form)."""
    out = np.empty_like(x)
    for j in range(x.shape[1]):
        zi = [pole[j] * last[j]]
        out[:, j] = signal.lfilter([1.0 - pole[j]], [1.0, -pole[j]], x[:, j], zi=zi)[0]
    return out
