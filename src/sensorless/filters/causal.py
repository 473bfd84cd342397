"""Causal velocity and acceleration estimators, usable in a control loop.

:class:`FiniteDifference`, :class:`DirtyDerivative` and :class:`Butterworth`
share the streaming and batch code of :class:`CausalEstimator`; their state
is an explicit, immutable :class:`FilterState`. Design and conventions:
:mod:`sensorless.filters`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike
from scipy import signal

from .._validation import FloatArray, as_joint_array, check_dt, check_int, check_type
from ..exceptions import DimensionError, InputValueError
from ._derivatives import Derivatives, n_dof_of
from ._sos import DIFFERENCE, IDENTITY, NO_SECTIONS, dc_group_delay, sections, sos_sample

__all__ = [
    "Butterworth",
    "CausalEstimator",
    "Delays",
    "DirtyDerivative",
    "FilterState",
    "FiniteDifference",
]

_ALL_OUTPUTS = (True, True, True)


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
            cascade = np.vstack([DIFFERENCE] * order + [filt])
            # writable (sosfilt refuses a read-only sos); the properties hand out copies
            sos.append(np.array(cascade if cascade.shape[0] else IDENTITY))
            delays.append(dt * (0.5 * order + dc_group_delay(filt)))
        self._sos: tuple[FloatArray, ...] = tuple(sos)
        # The same coefficients as Python floats, for the per-sample recursion.
        self._coefficients = tuple(sections(s) for s in self._sos)
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
        n_dof = n_dof_of(x0, "x0", ndim=1)
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
                y, final[k] = sos_sample(self._coefficients[k], x, zis[k])
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
            n_dof = n_dof_of(x, "x", ndim=2)
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
        check_type(state, FilterState, "state", " from initial_state, step or filter")
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
        super().__init__(check_dt(dt), (NO_SECTIONS, NO_SECTIONS, NO_SECTIONS))


class DirtyDerivative(CausalEstimator):
    """Dirty derivative ``s / (τ s + 1)``, ``τ = 1 / (2π cutoff)``, discretised by Tustin.

    The velocity is the bilinear (Tustin) transform of ``s / (τ s + 1)``
    (:func:`scipy.signal.cont2discrete`); the acceleration applies the same
    filter to the velocity. ``position`` is the input. Tustin rather than
    zero-order hold because it keeps unit gain on a ramp (ZOH assumes a
    staircase position and is off by ``O(dt/τ)``) and maps ``s = 0`` to
    ``z = 1`` exactly: the numerator is ``b0 (1 - z⁻¹)``, kept as an exact
    backward difference followed by the first-order section ``b0 dt / (1 + a1 z⁻¹)``.
    The delays are ``τ`` (velocity) and ``2 τ`` (acceleration) at every rate.
    The bilinear transform warps frequency: the low-pass's digital -3 dB point
    is ``atan(π dt cutoff) / (π dt)`` [Hz], close to ``cutoff`` only when it is
    well below the Nyquist frequency (20 Hz gives 19.97 Hz at 1 kHz, 17.86 Hz
    at 100 Hz).

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
        super().__init__(dt, (NO_SECTIONS, section, np.vstack([section, section])))

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
    ``B`` at DC, ``1 / (ω_a sin(π / (2 order)))`` with the prewarped
    ``ω_a = (2 / dt) tan(π cutoff dt)`` (the analog prototype's DC delay; the
    bilinear transform keeps it): close to ``1 / (2π cutoff sin(π / (2 order)))``
    when ``cutoff`` is well below the Nyquist frequency, shorter at low rates
    (20 Hz, 5th order: 25.7 ms at 1 kHz, 22.3 ms at 100 Hz).

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
        self._order = check_int(order, "order", 1, "Butterworth")
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
