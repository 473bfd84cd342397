"""Velocity and acceleration estimation from sampled joint positions.

Thesis § 3.4.1: the velocity and acceleration used by a model-based estimator
are filtered estimates, and a causal filter always delays and low-passes the
true signal. This module gives the usual estimators with their delay made
explicit.

Causal estimators (usable in a control loop)
    :class:`FiniteDifference`, :class:`DirtyDerivative`, :class:`Butterworth`.
Offline estimator (needs the whole record)
    :class:`SavitzkyGolay`.

Conventions
-----------
Units are SI and angles radians. Positions ``x`` have shape
``(n_samples, n_dof)`` (time along axis 0) or ``(n_dof,)`` for one sample;
results are :class:`Derivatives` ``(position, velocity, acceleration)`` in
[rad], [rad/s], [rad/s²].

Design is separate from application, as in :mod:`scipy.signal`: the
constructor designs, once, three cascades of second-order sections acting on
the raw position,

    position     = sosfilt(sos_position, x)
    velocity     = sosfilt(sos_velocity, x) / dt
    acceleration = sosfilt(sos_acceleration, x) / dt**2

where ``sos_velocity`` is one backward-difference section ``1 - z⁻¹`` followed
by the estimator's low-pass, and ``sos_acceleration`` two of them followed by
its low-pass. Putting the differences first, and on the raw position, makes a
robot at rest give a velocity and an acceleration of exactly zero, and makes
:class:`FiniteDifference` bit-for-bit ``np.diff(x, axis=0) / dt``.

The filter state is an explicit, immutable :class:`FilterState` holding the
``zi`` of :func:`scipy.signal.sosfilt` for the three cascades (shape
``(n_sections, 2, n_dof)`` each). :meth:`CausalEstimator.initial_state` gives
the state of a robot standing still at ``x0`` (no start-up transient);
:meth:`CausalEstimator.step` (one sample) and :meth:`CausalEstimator.filter`
(a whole array) run the same code, so a signal processed sample by sample or
in chunks, carrying the returned state, gives the same result as in one go.

Examples
--------
>>> import numpy as np
>>> from sensorless.filters import Butterworth
>>> dt = 1e-3
>>> t = np.arange(2000)[:, None] * dt
>>> q = np.hstack([np.sin(np.pi * t), 0.5 * t])          # two joints [rad]
>>> est = Butterworth(dt, cutoff=20.0)                    # 5th order, as in the thesis
>>> y, state = est.filter(q)
>>> y.velocity.shape
(2000, 2)
>>> bool(np.allclose(y.velocity[-1, 1], 0.5))            # ramp of 0.5 rad/s
True
>>> round(est.delay * 1e3, 1)                            # velocity delay [ms]
26.2
"""

from __future__ import annotations

import operator
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike
from scipy import signal

from ._validation import FloatArray, as_joint_array, check_dt
from .exceptions import DimensionError, InputTypeError, InputValueError

__all__ = [
    "Butterworth",
    "CausalEstimator",
    "Delays",
    "Derivatives",
    "DirtyDerivative",
    "FilterState",
    "FiniteDifference",
    "SavitzkyGolay",
]

# Backward difference 1 - z⁻¹ as one second-order section; the 1/dt gain is
# applied by division after filtering so that finite differences are exact.
_DIFFERENCE = np.array([[1.0, -1.0, 0.0, 1.0, 0.0, 0.0]])
_IDENTITY = np.array([[1.0, 0.0, 0.0, 1.0, 0.0, 0.0]])
_NO_SECTIONS = np.empty((0, 6))
_ALL_OUTPUTS = (True, True, True)


class Derivatives(NamedTuple):
    """Position and its first two time derivatives.

    Attributes
    ----------
    position : ndarray of shape (n_samples, n_dof) or (n_dof,)
        Joint positions [rad]: the filtered position where the estimator
        filters it, otherwise the input.
    velocity : ndarray of shape (n_samples, n_dof) or (n_dof,)
        Estimated joint velocities [rad/s].
    acceleration : ndarray of shape (n_samples, n_dof) or (n_dof,)
        Estimated joint accelerations [rad/s²].
    """

    position: FloatArray
    velocity: FloatArray
    acceleration: FloatArray


class Delays(NamedTuple):
    """Group delays at DC [s] of the three outputs of a causal estimator.

    For a polynomial input of degree ``m + 1`` the ``m``-th output equals the
    true derivative evaluated this long ago, once the start-up has died out.
    """

    position: float
    velocity: float
    acceleration: float


def _frozen(array: ArrayLike) -> FloatArray:
    out = np.array(array, dtype=np.float64)
    out.setflags(write=False)
    return out


@dataclass(frozen=True)
class FilterState:
    """State of a causal estimator, as ``zi``/``zf`` of :func:`scipy.signal.sosfilt`.

    Obtain it from :meth:`CausalEstimator.initial_state` or as the second
    value returned by :meth:`CausalEstimator.step` / :meth:`CausalEstimator.filter`;
    it is immutable, so an old state can be reused to replay a signal.

    Attributes
    ----------
    position, velocity, acceleration : ndarray of shape (n_sections, 2, n_dof)
        Section states of the three cascades ``sos_position``,
        ``sos_velocity`` and ``sos_acceleration`` (in the units of their
        input, [rad]).
    """

    position: FloatArray
    velocity: FloatArray
    acceleration: FloatArray

    def __post_init__(self) -> None:
        n_dof = None
        for name in ("position", "velocity", "acceleration"):
            value = _frozen(getattr(self, name))
            if value.ndim != 3 or value.shape[1] != 2:
                raise DimensionError(
                    f"FilterState.{name} must have shape (n_sections, 2, n_dof); "
                    f"got shape {value.shape}"
                )
            if n_dof is not None and value.shape[2] != n_dof:
                raise DimensionError(
                    f"FilterState.{name} is for {value.shape[2]} joints but "
                    f"FilterState.position is for {n_dof}"
                )
            n_dof = value.shape[2]
            object.__setattr__(self, name, value)

    @property
    def n_dof(self) -> int:
        """Number of joints the state is for."""
        return int(self.position.shape[2])


def _check_cutoff(cutoff: Any, dt: float, owner: str) -> float:
    nyquist = 0.5 / dt
    try:
        value = float(cutoff)
    except (TypeError, ValueError):
        raise InputValueError(
            f"{owner}: cutoff must be a frequency in Hz; got {cutoff!r}"
        ) from None
    if not np.isfinite(value) or value <= 0.0 or value >= nyquist:
        raise InputValueError(
            f"{owner}: cutoff must be a frequency in Hz with 0 < cutoff < Nyquist "
            f"frequency 1/(2 dt) = {nyquist:g} Hz (dt = {dt:g} s); got {cutoff!r}"
        )
    return value


def _check_int(value: Any, name: str, minimum: int, owner: str) -> int:
    if isinstance(value, (bool, np.bool_)):
        index = None
    else:
        try:
            index = operator.index(value)
        except TypeError:
            index = None
    if index is None or index < minimum:
        raise InputValueError(f"{owner}: {name} must be an integer >= {minimum}; got {value!r}")
    return index


def _n_dof_of(x: ArrayLike, name: str, ndim: int) -> int:
    shape = np.shape(x)
    expected = "(n_dof,)" if ndim == 1 else "(n_samples, n_dof)"
    if len(shape) != ndim or shape[-1] < 1:
        raise DimensionError(f"{name} must have shape {expected} with n_dof >= 1; got {shape}")
    return int(shape[-1])


def _dc_group_delay(sos: FloatArray) -> float:
    """Group delay at DC [samples] of a cascade of sections without zeros at z = 1."""
    return float(sum(signal.group_delay((sec[:3], sec[3:]), w=[0.0])[1][0] for sec in sos))


class CausalEstimator:
    """Causal velocity/acceleration estimator: shared streaming and batch code.

    Subclasses only design the low-pass filters; the public constructors are
    :class:`FiniteDifference`, :class:`DirtyDerivative` and
    :class:`Butterworth`.

    Parameters
    ----------
    dt : float
        Sample period [s].
    lowpass : tuple of three ndarrays of shape (n_sections, 6)
        Unit-DC-gain low-pass applied to the position, after the single
        backward difference (velocity) and after the double one
        (acceleration); zero sections mean no filtering.
    """

    __slots__ = ("_coefficients", "_delays", "_dt", "_scale", "_sos", "_zi_unit")

    def __init__(self, dt: float, lowpass: tuple[FloatArray, FloatArray, FloatArray]) -> None:
        self._dt = dt
        self._scale = (1.0, dt, dt * dt)
        sos = []
        delays = []
        for order, filt in enumerate(lowpass):
            cascade = np.vstack([_DIFFERENCE] * order + [filt])
            # writable (sosfilt refuses a read-only sos); the properties hand out copies
            sos.append(np.array(cascade if cascade.shape[0] else _IDENTITY))
            delays.append(dt * (0.5 * order + _dc_group_delay(filt)))
        self._sos: tuple[FloatArray, ...] = tuple(sos)
        # The same coefficients as Python floats, for the per-sample recursion.
        self._coefficients = tuple(_sections(s) for s in self._sos)
        # sosfilt_zi scales each section by the DC gain of those before it, so
        # the sections after a difference start at exactly zero.
        self._zi_unit = tuple(_frozen(signal.sosfilt_zi(s)) for s in self._sos)
        self._delays = Delays(*delays)

    @property
    def dt(self) -> float:
        """Sample period [s]."""
        return self._dt

    @property
    def sos_position(self) -> FloatArray:
        """Sections such that ``position = sosfilt(sos_position, x, axis=0)``."""
        return self._sos[0].copy()

    @property
    def sos_velocity(self) -> FloatArray:
        """Sections such that ``velocity = sosfilt(sos_velocity, x, axis=0) / dt``."""
        return self._sos[1].copy()

    @property
    def sos_acceleration(self) -> FloatArray:
        """Sections such that ``acceleration = sosfilt(sos_acceleration, x, axis=0) / dt**2``."""
        return self._sos[2].copy()

    @property
    def delays(self) -> Delays:
        """Group delays at DC [s] of position, velocity and acceleration.

        Each backward difference adds ``dt / 2``; the low-pass part comes from
        :func:`scipy.signal.group_delay` at zero frequency.
        """
        return self._delays

    @property
    def delay(self) -> float:
        """Group delay at DC of the velocity estimate [s] (``delays.velocity``)."""
        return self._delays.velocity

    def initial_state(self, x0: ArrayLike) -> FilterState:
        """State of a robot standing still at ``x0``.

        Parameters
        ----------
        x0 : array-like of shape (n_dof,)
            Joint positions [rad] held since forever.

        Returns
        -------
        FilterState
            Feeding ``x0`` again from this state gives position ``x0`` and
            exactly zero velocity and acceleration.
        """
        n_dof = _n_dof_of(x0, "x0", ndim=1)
        arr, _ = as_joint_array(x0, n_dof, "x0")
        rest = arr[0]
        return FilterState(*(zi[:, :, None] * rest for zi in self._zi_unit))

    def step(self, x: ArrayLike, state: FilterState) -> tuple[Derivatives, FilterState]:
        """Process one sample.

        Parameters
        ----------
        x : array-like of shape (n_dof,)
            Joint positions [rad] at this sample.
        state : FilterState
            State after the previous sample (or :meth:`initial_state`).

        Returns
        -------
        y : Derivatives
            Position [rad], velocity [rad/s], acceleration [rad/s²], each of
            shape (n_dof,).
        state : FilterState
            State to pass with the next sample.
        """
        state = self._check_state(state)
        arr, single = as_joint_array(x, state.n_dof, "x")
        if not single:
            raise DimensionError(
                f"step takes one sample x of shape ({state.n_dof},); got shape {np.shape(x)}; "
                "use filter for a whole array"
            )
        zis = (state.position, state.velocity, state.acceleration)
        outputs, final = self._step_outputs(arr[0], zis, _ALL_OUTPUTS)
        return Derivatives(*outputs), FilterState(*final)  # type: ignore[arg-type]

    def _step_outputs(
        self,
        x: FloatArray,
        zis: tuple[FloatArray, FloatArray, FloatArray],
        which: tuple[bool, bool, bool],
    ) -> tuple[
        tuple[FloatArray | None, FloatArray | None, FloatArray | None],
        tuple[FloatArray, FloatArray, FloatArray],
    ]:
        """One checked sample through the cascades selected by ``which``; the core of :meth:`step`.

        ``x`` has shape (n_dof,) and ``zis`` are the (position, velocity,
        acceleration) section states. Returns the outputs (None where not
        selected) and the new states; the state of a cascade that is not
        selected is returned unchanged, so it is only meaningful to callers
        that never select that cascade.
        """
        outputs: list[FloatArray | None] = [None, None, None]
        final = list(zis)
        for k in range(3):
            if which[k]:
                y, final[k] = _sos_sample(self._coefficients[k], x, zis[k])
                outputs[k] = y / self._scale[k]
        return (outputs[0], outputs[1], outputs[2]), (final[0], final[1], final[2])

    def filter(
        self, x: ArrayLike, state: FilterState | None = None
    ) -> tuple[Derivatives, FilterState]:
        """Process a whole array of samples.

        Parameters
        ----------
        x : array-like of shape (n_samples, n_dof)
            Joint positions [rad], time along axis 0.
        state : FilterState, optional
            State before ``x[0]``; by default the robot at rest at ``x[0]``
            (:meth:`initial_state`).

        Returns
        -------
        y : Derivatives
            Position [rad], velocity [rad/s], acceleration [rad/s²], each of
            shape (n_samples, n_dof).
        state : FilterState
            State after the last sample, to continue with the next chunk.
        """
        if state is None:
            n_dof = _n_dof_of(x, "x", ndim=2)
            arr, _ = as_joint_array(x, n_dof, "x")
            if arr.shape[0] == 0:
                raise DimensionError(
                    "x has no samples; pass a state to filter an empty chunk, or at least "
                    "one sample to start at rest at x[0]"
                )
            state = self.initial_state(arr[0])
        else:
            state = self._check_state(state)
            arr, single = as_joint_array(x, state.n_dof, "x")
            if single:
                raise DimensionError(
                    f"filter takes x of shape (n_samples, {state.n_dof}); got shape "
                    f"{np.shape(x)}; use step for one sample"
                )
        return self._run(arr, state)

    def _check_state(self, state: Any) -> FilterState:
        if not isinstance(state, FilterState):
            raise InputTypeError(
                f"state must be a FilterState from initial_state, step or filter; "
                f"got {type(state).__name__}"
            )
        for name, sos in zip(("position", "velocity", "acceleration"), self._sos, strict=True):
            zi = getattr(state, name)
            if zi.shape[0] != sos.shape[0]:
                raise DimensionError(
                    f"state.{name} has {zi.shape[0]} sections but {self!r} has "
                    f"{sos.shape[0]}; was the state made by another estimator?"
                )
        return state

    def _run(self, x: FloatArray, state: FilterState) -> tuple[Derivatives, FilterState]:
        if x.shape[0] == 0:  # sosfilt cannot reshape an empty signal
            return Derivatives(x.copy(), x.copy(), x.copy()), state
        outputs = []
        final = []
        zis = (state.position, state.velocity, state.acceleration)
        for sos, zi, scale in zip(self._sos, zis, self._scale, strict=True):
            y, zf = signal.sosfilt(sos, x, axis=0, zi=zi)
            outputs.append(y / scale)
            final.append(zf)
        return Derivatives(*outputs), FilterState(*final)

    def _params(self) -> str:
        return f"dt={self._dt!r}"

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self._params()})"


class FiniteDifference(CausalEstimator):
    """Backward differences: no filtering, the shortest delay, the most noise.

    ``velocity[k] = (x[k] - x[k-1]) / dt`` and ``acceleration[k] =
    (velocity[k] - velocity[k-1]) / dt``; ``position`` is the input. The
    delays are ``dt / 2`` (velocity) and ``dt`` (acceleration).

    Parameters
    ----------
    dt : float
        Sample period [s].

    Examples
    --------
    >>> import numpy as np
    >>> est = FiniteDifference(0.5)
    >>> y, _ = est.filter([[0.0], [1.0], [3.0]])
    >>> y.velocity.ravel().tolist(), y.acceleration.ravel().tolist()
    ([0.0, 2.0, 4.0], [0.0, 4.0, 4.0])
    """

    __slots__ = ()

    def __init__(self, dt: float) -> None:
        super().__init__(check_dt(dt), (_NO_SECTIONS, _NO_SECTIONS, _NO_SECTIONS))


class DirtyDerivative(CausalEstimator):
    """Dirty derivative ``s / (τ s + 1)``, ``τ = 1 / (2π cutoff)``, discretised by Tustin.

    The velocity is the bilinear (Tustin) transform of ``s / (τ s + 1)``
    (:func:`scipy.signal.cont2discrete`); the acceleration applies the same
    filter to the velocity. ``position`` is the input. Tustin rather than
    zero-order hold because it keeps unit gain on a ramp (ZOH assumes a
    staircase position and is off by ``O(dt/τ)``) and maps ``s = 0`` to
    ``z = 1`` exactly: the numerator is ``b0 (1 - z⁻¹)``, kept as an exact
    backward difference followed by the first-order section ``b0 dt / (1 + a1 z⁻¹)``.
    The delays are ``τ`` (velocity) and ``2 τ`` (acceleration).

    Parameters
    ----------
    dt : float
        Sample period [s].
    cutoff : float
        Bandwidth ``1 / (2π τ)`` [Hz]; ``0 < cutoff < 1 / (2 dt)``.

    Examples
    --------
    >>> est = DirtyDerivative(1e-3, cutoff=50.0)
    >>> round(est.tau, 6), round(est.delay, 6)
    (0.003183, 0.003183)
    """

    __slots__ = ("_cutoff",)

    def __init__(self, dt: float, cutoff: float) -> None:
        dt = check_dt(dt)
        self._cutoff = _check_cutoff(cutoff, dt, "DirtyDerivative")
        tau = 1.0 / (2.0 * np.pi * self._cutoff)
        num, den, _ = signal.cont2discrete(([1.0, 0.0], [tau, 1.0]), dt, method="bilinear")
        section = np.array([[num[0, 0] * dt, 0.0, 0.0, 1.0, den[1], 0.0]])
        super().__init__(dt, (_NO_SECTIONS, section, np.vstack([section, section])))

    @property
    def cutoff(self) -> float:
        """Bandwidth of the dirty derivative [Hz]."""
        return self._cutoff

    @property
    def tau(self) -> float:
        """Time constant ``τ = 1 / (2π cutoff)`` [s]."""
        return 1.0 / (2.0 * np.pi * self._cutoff)

    def _params(self) -> str:
        return f"dt={self._dt!r}, cutoff={self._cutoff!r}"


class Butterworth(CausalEstimator):
    """Causal Butterworth low-pass with backward differences (thesis § 3.4.1: 5th order).

    One digital Butterworth low-pass ``B`` (:func:`scipy.signal.butter`,
    ``output='sos'``) filters the position, the backward difference of the
    position and its double backward difference:

        position = B x,   velocity = B (1 - z⁻¹) x / dt,   acceleration = B (1 - z⁻¹)² x / dt²

    which equals differencing the filtered position, but starts from an
    exactly zero velocity for a robot at rest. The three outputs are therefore
    mutually consistent (velocity is the backward difference of position).
    Delays: ``d``, ``d + dt/2`` and ``d + dt`` with ``d`` the group delay of
    ``B`` at DC, close to ``1 / (2π cutoff sin(π / (2 order)))``.

    Parameters
    ----------
    dt : float
        Sample period [s].
    cutoff : float
        -3 dB frequency of the low-pass [Hz]; ``0 < cutoff < 1 / (2 dt)``.
    order : int
        Filter order, >= 1. Default 5, as in the thesis.

    Examples
    --------
    >>> est = Butterworth(1e-3, cutoff=20.0, order=5)
    >>> est.sos_position.shape, est.sos_velocity.shape
    ((3, 6), (4, 6))
    """

    __slots__ = ("_cutoff", "_order")

    def __init__(self, dt: float, cutoff: float, order: int = 5) -> None:
        dt = check_dt(dt)
        self._cutoff = _check_cutoff(cutoff, dt, "Butterworth")
        self._order = _check_int(order, "order", 1, "Butterworth")
        lowpass = signal.butter(self._order, self._cutoff, btype="low", output="sos", fs=1.0 / dt)
        super().__init__(dt, (lowpass, lowpass, lowpass))

    @property
    def cutoff(self) -> float:
        """-3 dB frequency of the low-pass [Hz]."""
        return self._cutoff

    @property
    def order(self) -> int:
        """Order of the Butterworth low-pass."""
        return self._order

    def _params(self) -> str:
        return f"dt={self._dt!r}, cutoff={self._cutoff!r}, order={self._order}"


class SavitzkyGolay:
    """Savitzky–Golay smoothing and differentiation: non-causal, OFFLINE only.

    Fits a polynomial of degree ``polyorder`` to each window of ``window``
    samples centred on the sample (:func:`scipy.signal.savgol_filter`,
    ``mode='interp'``: the first and last half-windows use the fit of the
    first and last full window). It has no delay and is exact for polynomials
    up to ``polyorder``, but it needs future samples: there is no
    ``initial_state``/``step``, and it is not a :class:`CausalEstimator`.
    Use it to make reference derivatives from a recorded log.

    Parameters
    ----------
    dt : float
        Sample period [s].
    window : int
        Window length [samples]; odd and > ``polyorder``.
    polyorder : int
        Degree of the fitted polynomial, >= 2 (the acceleration of a lower
        degree fit is identically zero). Default 3.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(50)[:, None] * 0.01
    >>> y = SavitzkyGolay(0.01, window=11).filter(t**3)
    >>> bool(np.allclose(y.velocity, 3 * t**2)), bool(np.allclose(y.acceleration, 6 * t))
    (True, True)
    """

    __slots__ = ("_dt", "_polyorder", "_window")

    def __init__(self, dt: float, window: int, polyorder: int = 3) -> None:
        self._dt = check_dt(dt)
        self._polyorder = _check_int(polyorder, "polyorder", 2, "SavitzkyGolay")
        self._window = _check_int(window, "window", self._polyorder + 1, "SavitzkyGolay")
        if self._window % 2 == 0:
            raise InputValueError(
                f"SavitzkyGolay: window must be an odd number of samples > polyorder "
                f"({self._polyorder}); got {window!r}"
            )

    @property
    def dt(self) -> float:
        """Sample period [s]."""
        return self._dt

    @property
    def window(self) -> int:
        """Window length [samples]."""
        return self._window

    @property
    def polyorder(self) -> int:
        """Degree of the fitted polynomial."""
        return self._polyorder

    def filter(self, x: ArrayLike) -> Derivatives:
        """Smooth and differentiate a whole record.

        Parameters
        ----------
        x : array-like of shape (n_samples, n_dof)
            Joint positions [rad], time along axis 0, ``n_samples >= window``.

        Returns
        -------
        Derivatives
            Smoothed position [rad], velocity [rad/s], acceleration [rad/s²],
            each of shape (n_samples, n_dof).
        """
        n_dof = _n_dof_of(x, "x", ndim=2)
        arr, _ = as_joint_array(x, n_dof, "x")
        if arr.shape[0] < self._window:
            raise DimensionError(
                f"SavitzkyGolay(window={self._window}) needs at least {self._window} samples; "
                f"x has {arr.shape[0]}"
            )
        return Derivatives(
            *(
                signal.savgol_filter(
                    arr,
                    self._window,
                    self._polyorder,
                    deriv=deriv,
                    delta=self._dt,
                    axis=0,
                    mode="interp",
                )
                for deriv in range(3)
            )
        )

    def __repr__(self) -> str:
        return f"SavitzkyGolay(dt={self._dt!r}, window={self._window}, polyorder={self._polyorder})"


_Section = tuple[float, float, float, float, float, float]


def _sections(sos: FloatArray) -> tuple[_Section, ...]:
    """Rows of ``sos`` as tuples of Python floats (same values, cheaper to unpack)."""
    return tuple(
        (float(b0), float(b1), float(b2), float(a0), float(a1), float(a2))
        for b0, b1, b2, a0, a1, a2 in sos
    )


def _sos_sample(
    sos: tuple[_Section, ...], x: FloatArray, zi: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """One sample through second-order sections, transposed direct form II.

    The recursion :func:`scipy.signal.sosfilt` runs, written out for a single
    sample: calling sosfilt on one row costs far more than the arithmetic
    (axis handling and validation), and a live detector calls this at 1 kHz.
    ``sos`` holds the sections as float tuples (see :func:`_sections`);
    ``zi`` has shape (n_sections, 2, n_dof); a new state array is returned.
    """
    zf = np.empty_like(zi)
    y = x
    for k, (b0, b1, b2, _, a1, a2) in enumerate(sos):
        out = b0 * y + zi[k, 0]
        zf[k, 0] = b1 * y - a1 * out + zi[k, 1]
        zf[k, 1] = b2 * y - a2 * out
        y = out
    return y, zf
