"""Attitude filters: :class:`Mahony` (explicit complementary filter) and :class:`Madgwick`
(gradient descent), each 6D (gyro + accelerometer) or 9D (+ magnetometer, pass ``mag=``).

=====================  ===========================================================================
estimate               ``R_wb`` (body → world) as a scipy ``Rotation``, in ``world="ENU"`` (x east,
                       y north, z up) or ``"NED"`` (x north, y east, z down)
gyro                   body rate ω [rad/s]; step ``q ← q ⊗ Exp((ω − b̂ + ω_c) dt)`` (exact exponential)
accel                  specific force [m/s²]: at rest ``R_wbᵀ (0, 0, +g)`` (ENU) / ``R_wbᵀ (0, 0, −g)``
                       (NED), i.e. it points **up** (``docs/conventions.md`` row 7)
mag                    any unit; ``R_wbᵀ m_w``; north is +y (ENU) / +x (NED)
first sample           initialises: tilt from the accelerometer, heading from the magnetometer (9D),
                       else ZYX yaw 0; output as is
gyro_bias              the bias estimate after each sample [rad/s]
saturation             a clipped accelerometer sample (an axis at ±range, ``ImuData.accel_saturated``)
                       has ‖a‖ ≥ range, so the norm test of :class:`AccelRejection` skips it whenever
                       range > g + ``norm`` (±2 g sensors and up with the defaults), except during
                       the :class:`GainRamp`, when rejection is off; a clipped gyro sample is
                       integrated as read, its error then corrected like any other (heading only
                       in 9D)
=====================  ===========================================================================

Equations, rejection rules, the gain ramp and measured test numbers: ``docs/filters.md``.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike
from scipy.spatial.transform import Rotation

from imukit import _core
from imukit._arrays import (
    FloatArray,
    as_float_array,
    check_finite_rows,
    choice,
    real_scalar,
    rotation_from_unit_quat,
    vector3,
)
from imukit._errors import NonFiniteError, ParameterError, ShapeError
from imukit.imu import ImuData

__all__ = [
    "AccelRejection",
    "FilterResult",
    "FilterState",
    "GainRamp",
    "Madgwick",
    "MagRejection",
    "Mahony",
    "RestDetection",
]

WORLDS = ("ENU", "NED")


class GainRamp(NamedTuple):
    """Start-up ramp: for ``elapsed < duration_s`` the gain is
    ``nominal · (1 + (factor − 1)(1 − elapsed/duration_s))``, linear from ``factor × nominal`` to
    nominal; rejection is off and Mahony's integral term frozen meanwhile. A recovery restarts it."""

    duration_s: float = 3.0
    factor: float = 10.0


class AccelRejection(NamedTuple):
    """Skip the accelerometer correction when ``|‖a‖ − g| > norm`` [m/s²] or the angle between
    measured and predicted up exceeds ``angle_rad``; after ``recovery_s`` seconds of
    uninterrupted rejection, restart the :class:`GainRamp` (recovery). The defaults (4 m/s², 30°)
    were tuned on BROAD's handheld motion (docs/filters.md); (1.0, 10°) suits slow, smooth motion."""

    norm: float = 4.0
    angle_rad: float = math.radians(30.0)
    recovery_s: float = 5.0


class MagRejection(NamedTuple):
    """Skip the magnetometer correction when ``|‖m‖ − m₀| > norm_fraction · m₀`` or the dip angle
    differs from the reference ``δ₀`` by more than ``dip_rad`` (``m₀``, ``δ₀`` learned at the first
    magnetometer sample); after ``recovery_s`` seconds of rejection, re-learn them from the sample."""

    norm_fraction: float = 0.1
    dip_rad: float = math.radians(10.0)
    recovery_s: float = 10.0


class RestDetection(NamedTuple):
    """At rest once ``‖ω‖ < gyro`` [rad/s] and ``|‖a‖ − g| < accel`` [m/s²] held ``duration_s``;
    then ``b ← b + min(dt/tau_s, 1)(ω − b)``."""

    gyro: float = 0.05
    accel: float = 0.2
    duration_s: float = 1.0
    tau_s: float = 1.0


class FilterState:
    """A saved filter state: immutable, so "copy" is just keeping the object.

    ``values`` is the ``(16,)`` float64 layout ``[qx, qy, qz, qw, bx, by, bz, initialized,
    time, ramp_elapsed, accel_rejected_s, mag_rejected_s, rest_s, mag_norm_ref, sin δ₀, cos δ₀]``
    (``time`` is the absolute timestamp ``imu.t`` of the last sample of a ``run``, or the sum of the
    ``dt`` of ``update`` calls). Both filters share the layout.
    """

    __slots__ = ("values",)
    values: FloatArray

    def __init__(self, values: ArrayLike) -> None:
        v = np.array(as_float_array(values, "state"), dtype=np.float64)
        if v.shape != (16,):
            raise ShapeError(f"state: expected shape (16,), got {v.shape}")
        check_finite_rows(v, "state", "element")
        v.setflags(write=False)
        object.__setattr__(self, "values", v)

    def __setattr__(self, name: str, value: object) -> None:
        raise AttributeError("FilterState is immutable")

    def __repr__(self) -> str:
        return f"FilterState(values={self.values.tolist()!r})"

    @property
    def rotation(self) -> Rotation:
        """The attitude ``R_wb``."""
        return Rotation.from_quat(self.values[:4])

    @property
    def gyro_bias(self) -> FloatArray:
        """The gyro-bias estimate [rad/s]."""
        return self.values[4:7].copy()

    @property
    def initialized(self) -> bool:
        """Whether the attitude has been initialised."""
        return bool(self.values[7] != 0.0)

    @property
    def time(self) -> float:
        """Time of the last sample [s]."""
        return float(self.values[8])


class FilterResult(NamedTuple):
    """Output of ``run``: ``rotation`` (length N, ``R_wb``), ``gyro_bias`` (N, 3) after each sample,
    and ``state`` after the last sample (pass it as ``initial=`` to continue)."""

    rotation: Rotation
    gyro_bias: FloatArray
    state: FilterState


def _positive(x: float, name: str, *, zero: bool = False) -> float:
    what = f"a {'non-negative' if zero else 'positive'} finite number"
    return real_scalar(x, name, what=what, accept=lambda v: math.isfinite(v) and (v >= 0.0 if zero else v > 0.0))


def _numbers(option: tuple[float, ...] | None, name: str) -> list[float] | None:
    """The fields of an options NamedTuple as floats (their ranges are checked in the core)."""
    if option is None:
        return None
    fields = getattr(option, "_fields", [str(k) for k in range(len(option))])
    return [real_scalar(v, f"{name}.{f}", what="a number", accept=lambda x: True) for f, v in zip(fields, option)]


def _check_mag_norms(mags: FloatArray) -> FloatArray:
    """``mags`` (N, 3), refusing finite samples whose norm overflows: the filter keeps the first
    norm as its reference, which must stay finite."""
    with np.errstate(over="ignore", invalid="ignore"):
        norms = np.linalg.norm(mags, axis=1)
    # NaN and inf themselves are the core's to report (naming the sample); here finite overflow.
    big = np.flatnonzero(np.isinf(norms) & np.isfinite(mags).all(axis=1))
    if big.size:
        raise NonFiniteError(f"mag: sample {int(big[0])} is too large: its norm overflows float64")
    return mags


def _vec3(x: ArrayLike, name: str) -> list[float]:
    return [float(e) for e in vector3(x, name)]


class _Filter:
    """Common front of both filters: options, the state and the three ways of running."""

    _core_filter: _core.AttitudeFilter
    _state: FilterState
    world: str

    def _setup(
        self,
        algorithm: str,
        gains: list[float],
        world: str,
        gravity: float,
        gain_ramp: GainRamp | None,
        acc_rejection: AccelRejection | None,
        mag_rejection: MagRejection | None,
        rest_detection: RestDetection | None,
    ) -> None:
        self.world = choice(world, "world", WORLDS)
        ramp = _numbers(gain_ramp, "gain_ramp") or [0.0, 1.0]
        self._core_filter = _core.AttitudeFilter(
            algorithm,
            gains,
            self.world,
            float(gravity),
            ramp,
            _numbers(acc_rejection, "acc_rejection"),
            _numbers(mag_rejection, "mag_rejection"),
            _numbers(rest_detection, "rest_detection"),
        )
        self.reset()

    def reset(self, initial: Rotation | None = None) -> None:
        """Forget the state; the next :meth:`update` initialises (or starts at ``initial``)."""
        self._state = FilterState(self._core_filter.initial_state(_initial_quat(initial)))

    def get_state(self) -> FilterState:
        """The current streaming state (immutable; keep it to restore later)."""
        return self._state

    def set_state(self, state: FilterState) -> None:
        """Restore a state from :meth:`get_state` or ``run(...).state``."""
        if not isinstance(state, FilterState):
            raise ParameterError(f"state: expected a FilterState, got {type(state).__name__}")
        self._state = state

    def update(self, gyro: ArrayLike, accel: ArrayLike, dt: float, mag: ArrayLike | None = None) -> Rotation:
        """One streaming sample (``dt`` [s] since the previous one; ignored on the first, which
        initialises); returns the current attitude ``R_wb``."""
        values = self._core_filter.update(
            self._state.values,
            _vec3(gyro, "gyro"),
            _vec3(accel, "accel"),
            real_scalar(dt, "dt", what="a step in seconds", accept=lambda x: True),
            None if mag is None else _check_mag_norms(np.array([_vec3(mag, "mag")]))[0].tolist(),
        )
        self._state = FilterState(values)
        return rotation_from_unit_quat(values[:4].copy())

    def run(
        self, imu: ImuData, *, mag: ArrayLike | None = None, initial: Rotation | FilterState | None = None
    ) -> FilterResult:
        """Filter a whole recording in one native call (GIL released); the streaming state is not
        touched.

        Parameters
        ----------
        imu
            The gyro and accelerometer samples.
        mag
            ``(N, 3)`` magnetometer samples (9D), or None (6D).
        initial
            None: the first sample initialises. A ``Rotation``: the attitude at ``imu.t[0]`` (zero
            bias). A :class:`FilterState` (e.g. ``run(...).state`` of the previous chunk): continue
            from it, the first sample being a step of ``imu.t[0] − state.time``.
        """
        if not isinstance(imu, ImuData):
            raise ParameterError(f"imu: expected an imukit.ImuData, got {type(imu).__name__}")
        n = len(imu.t)
        mags = None
        if mag is not None:
            mags = np.ascontiguousarray(as_float_array(mag, "mag"))
            if mags.shape != (n, 3):
                raise ShapeError(f"mag: expected shape (N, 3) with N = len(imu.t) = {n}, got {mags.shape}")
            _check_mag_norms(mags)
        continued = isinstance(initial, FilterState)
        if isinstance(initial, FilterState):
            start = initial.values.copy()
            start[8] = initial.time - float(imu.t[0])  # the core's clock is imu.seconds
        else:
            start = self._core_filter.initial_state(_initial_quat(initial))
        q, bias, final = self._core_filter.run(imu.seconds, imu.gyro, imu.accel, mags, start, continued)
        final[8] = float(imu.t[-1])
        return FilterResult(rotation_from_unit_quat(q), bias, FilterState(final))


def _initial_quat(initial: Rotation | None) -> list[float] | None:
    if initial is None:
        return None
    if isinstance(initial, Rotation) and initial.single:
        return [float(v) for v in initial.as_quat()]
    raise ParameterError(f"initial: expected a single scipy Rotation, a FilterState or None, got {initial!r}")


class Mahony(_Filter):
    """Mahony's explicit complementary filter (Mahony, Hamel & Pflimlin, IEEE TAC 2008):
    ``Ṙ̂ = R̂ [ω − b̂ + k_P ω_mes]×``, ``ḃ̂ = −k_I ω_mes``, ``ω_mes = Σ v_i × v̂_i``.

    Parameters
    ----------
    kp
        Proportional gain [1/s] (default 0.5, tuned on BROAD: docs/filters.md).
    ki
        Integral gain [1/s²] of the gyro-bias estimate (default 0.01; 0 disables it).
    world
        ``"ENU"`` or ``"NED"``.
    gravity
        Gravity magnitude [m/s²] for the rejection and rest tests (default 9.81).
    gain_ramp
        :class:`GainRamp` (default 3 s from 10×), or None for none.
    acc_rejection, mag_rejection
        :class:`AccelRejection` / :class:`MagRejection` (defaults on), or None to use every sample.
    rest_detection
        :class:`RestDetection`, or None (default) for none.
    """

    def __init__(
        self,
        *,
        kp: float = 0.5,
        ki: float = 0.01,
        world: str = "ENU",
        gravity: float = 9.81,
        gain_ramp: GainRamp | None = GainRamp(),  # noqa: B008 - immutable NamedTuple
        acc_rejection: AccelRejection | None = AccelRejection(),  # noqa: B008
        mag_rejection: MagRejection | None = MagRejection(),  # noqa: B008
        rest_detection: RestDetection | None = None,
    ) -> None:
        self.kp = _positive(kp, "kp", zero=True)
        self.ki = _positive(ki, "ki", zero=True)
        self._setup(
            "mahony",
            [self.kp, self.ki],
            world,
            _positive(gravity, "gravity"),
            gain_ramp,
            acc_rejection,
            mag_rejection,
            rest_detection,
        )


class Madgwick(_Filter):
    """Madgwick's gradient-descent filter (Madgwick 2010; Madgwick, Harrison & Vaidyanathan, ICORR
    2011): ``q̇ = ½ q ⊗ (ω − b̂) − β ∇f/‖∇f‖``.

    Parameters
    ----------
    beta
        ``β`` [1/s], the norm of the correction's quaternion rate (default 0.07, tuned on BROAD:
        docs/filters.md). The bias estimate changes only through ``rest_detection``.
    world, gravity, gain_ramp, acc_rejection, mag_rejection, rest_detection
        As for :class:`Mahony`.
    """

    def __init__(
        self,
        *,
        beta: float = 0.07,
        world: str = "ENU",
        gravity: float = 9.81,
        gain_ramp: GainRamp | None = GainRamp(),  # noqa: B008 - immutable NamedTuple
        acc_rejection: AccelRejection | None = AccelRejection(),  # noqa: B008
        mag_rejection: MagRejection | None = MagRejection(),  # noqa: B008
        rest_detection: RestDetection | None = None,
    ) -> None:
        self.beta = _positive(beta, "beta", zero=True)
        self._setup(
            "madgwick",
            [self.beta, 0.0],
            world,
            _positive(gravity, "gravity"),
            gain_ramp,
            acc_rejection,
            mag_rejection,
            rest_detection,
        )
