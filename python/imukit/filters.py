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
                       has ‖a‖ ≥ range, so the raw norm test of :class:`AccelRejection` skips its
                       correction whenever range > g + ``norm`` (±2 g sensors and up with the
                       defaults), except during the :class:`GainRamp`; with :class:`AccelLowPass`
                       (default) it still enters the low-passed vector, as every sample does; a
                       clipped gyro sample is integrated as read, its error then corrected like any
                       other (heading only in 9D)
=====================  ===========================================================================

Options are the core's value classes (``imukit._core``): :class:`GainRamp`, :class:`AccelLowPass`,
:class:`AccelRejection`,
:class:`MagRejection`, :class:`RestDetection`, frozen, compared by value and picklable; a field left out
(or None) takes the Rust ``Default``, the one place every default number is written. The filters'
keyword defaults (gains, ``world``, ``gravity``, which options are on) are read from the core too.
:class:`FilterState` is the core's state with named fields; it pickles and deep-copies exactly.

Equations, rejection rules, the gain ramp, the ``Law`` seam and measured test numbers:
``docs/filters.md``.
"""

from __future__ import annotations

import inspect
import math
import threading
from typing import Any, NamedTuple, TypeVar

import numpy as np
from numpy.typing import ArrayLike
from scipy.spatial.transform import Rotation

from imukit import _core, quat
from imukit._arrays import FloatArray, as_float_array, real_scalar, rotation_from_unit_quat, vector3
from imukit._deprecation import deprecated
from imukit._errors import NonFiniteError, ParameterError, ShapeError
from imukit._extrinsics import sensor_pose
from imukit._names import canonical
from imukit.imu import ImuBias, ImuData

__all__ = [
    "AccelLowPass",
    "AccelRejection",
    "FilterResult",
    "FilterState",
    "GainRamp",
    "Madgwick",
    "MagRejection",
    "Mahony",
    "RestDetection",
    "Robust",
    "RobustResult",
    "RobustState",
    "in_world",
]

GainRamp = _core.GainRamp
AccelLowPass = _core.AccelLowPass
AccelRejection = _core.AccelRejection
MagRejection = _core.MagRejection
RestDetection = _core.RestDetection

_OPTIONS = _core.FilterOptions.default()
WORLDS: tuple[str, ...] = _core.FILTER_WORLDS
# ENU (x east, y north, z up) to NED (x north, y east, z down): x and y swapped, z flipped, a half turn
# about (1, 1, 0)/√2 (xyzw), its own inverse.
_NED_FROM_ENU = np.array([math.sqrt(0.5), math.sqrt(0.5), 0.0, 0.0])


def in_world(attitude: Rotation | ArrayLike, world: str) -> Rotation | FloatArray:
    """An attitude ``R_wb`` with a z-up (ENU) world, as a filter run with ``world`` estimates it: itself
    for ``"ENU"``, ``C R_wb`` for ``"NED"`` (``C`` swaps x and y and flips z; the body axes stay). A
    ground truth (motion capture, EuRoC, BROAD: z up) is scored against a NED filter's estimate so.
    ``attitude``: a scipy ``Rotation`` (one back) or ``(..., 4)`` ``xyzw`` rows (rows back; a NaN row,
    no truth there, stays NaN)."""
    world = canonical(world, "world", WORLDS)
    if isinstance(attitude, Rotation):
        return attitude if world == "ENU" else Rotation.from_quat(_NED_FROM_ENU) * attitude
    q = as_float_array(attitude, "attitude")
    if q.shape[-1:] != (4,):
        raise ShapeError(f"expected (..., 4) xyzw quaternions, got shape {q.shape}", argument="attitude")
    missing = np.isnan(q).all(axis=-1)  # a row with no truth there
    bad = ~np.isfinite(q).all(axis=-1) & ~missing
    if bad.any():
        row = tuple(int(k) for k in np.unravel_index(int(np.argmax(bad)), bad.shape))
        raise NonFiniteError(f"row {row} is neither a quaternion nor all NaN: {q[row]}", argument="attitude")
    if world == "ENU":
        return q.copy()
    out = np.full_like(q, np.nan)
    out[~missing] = quat.multiply(_NED_FROM_ENU, q[~missing])
    return out


class FilterState(_core.FilterState):
    """A saved filter state: immutable, so "copy" is just keeping the object; it pickles and
    deep-copies exactly.

    Fields by name: ``rotation`` (``R_wb``), ``quaternion`` (xyzw), ``gyro_bias`` [rad/s],
    ``initialized``, ``time`` (the absolute timestamp ``imu.t`` of the last sample of a ``run``, or
    the sum of the ``dt`` of ``update`` calls), the gate and rest clocks ``ramp_elapsed``,
    ``accel_rejected``, ``mag_rejected``, ``rest`` [s], the magnetometer reference ``mag_norm``,
    ``mag_dip_sin``, ``mag_dip_cos``, and ``extra``, the law's own fields (none for Mahony and
    Madgwick), ``mag_held`` / ``mag_held_s`` (the last streamed field sample in the last sample's
    body axes and its age: ``update(..., mag=None)`` uses it, turned by the gyro, for up to the
    filter's ``mag_hold_s``),
    and ``world`` (``"ENU"`` / ``"NED"``, the frame of ``quaternion``; None in a state
    stored before it was recorded: the world of the filter that takes it). A state of one filter
    continues another (the law's own fields restart); a filter of the other world turns the
    attitude into its own.

    Deprecated: ``FilterState(values)`` from the former ``(16,)`` layout and ``.values`` still work
    (with a DeprecationWarning); keep the object, or pickle it, instead.
    """

    __slots__ = ()

    def __new__(cls, values: ArrayLike | _core.FilterState | None = None, /, **fields: Any) -> FilterState:
        if values is None and fields:
            return super().__new__(cls, **fields)
        if isinstance(values, _core.FilterState):
            return super().__new__(cls, values, **fields)  # a copy; with fields, the core refuses
        if values is None:
            raise ParameterError("expected the state's fields by name, or a FilterState", argument="state")
        deprecated("FilterState(values) from the flat (16,) layout is deprecated: keep or pickle the state")
        v = np.array(as_float_array(values, "state"), dtype=np.float64)
        if v.shape != (16,):
            raise ShapeError(f"expected shape (16,), got {v.shape}", argument="state")
        return super().__new__(cls, **_core.FilterState._from_legacy_values(v.tolist()).fields())

    def __repr__(self) -> str:
        q, b = self.quaternion.tolist(), self.gyro_bias.tolist()
        return (
            f"FilterState(quaternion={q!r}, gyro_bias={b!r}, time={self.time!r}, "
            f"initialized={self.initialized!r}, world={self.world!r})"
        )

    @property
    def rotation(self) -> Rotation:
        """The attitude ``R_wb``."""
        return Rotation.from_quat(self.quaternion)

    @property
    def values(self) -> FloatArray:
        """Deprecated: the former flat ``(16,)`` layout (read-only)."""
        deprecated("FilterState.values is deprecated: read the fields by name")
        v = self._legacy_values()
        v.setflags(write=False)
        return v


class FilterResult(NamedTuple):
    """Output of ``run``: ``rotation`` (length N, ``R_wb``), ``gyro_bias`` (N, 3) after each sample,
    and ``state`` after the last sample (pass it as ``initial=`` to continue)."""

    rotation: Rotation
    gyro_bias: FloatArray
    state: FilterState


_Option = TypeVar("_Option", GainRamp, AccelLowPass, AccelRejection, MagRejection, RestDetection)


def _option(value: object, cls: type[_Option], name: str) -> _Option | None:
    """``value`` as option ``cls`` (None: off); a plain tuple of its fields (real numbers) is accepted."""
    if value is None or isinstance(value, cls):
        return value
    if isinstance(value, (tuple, list)):
        return cls(*(_real(v, name) for v in value))
    raise ParameterError(f"expected a {cls.__name__} or None, got {value!r}", argument=name)


def _real(value: object, name: str) -> float:
    """``value`` as a real number, refusing a bool or a string (a gain of ``True`` is no gain of 1):
    the Python-ness check of a numeric option; its value is the core's to check (finite, in range)."""
    return real_scalar(value, name, what="a real number", accept=lambda x: True)


def _run_mag(imu: ImuData, mag: ArrayLike | bool | None) -> FloatArray | None:
    """The magnetometer samples a filter's ``run`` uses, by one rule for every filter: None →
    ``imu.mag`` when there is one; ``False`` → none (6D); ``True`` → ``imu.mag``, which must be
    there; an ``(N, 3)`` array → those samples."""
    if isinstance(mag, (bool, np.bool_)) or mag is None:
        if mag and imu.mag is None:
            raise ParameterError("mag=True, but imu has no magnetometer samples (imu.mag is None)", argument="mag")
        mag = imu.mag if mag is None or mag else None
    if mag is None:
        return None
    n = len(imu.t)
    mags = np.ascontiguousarray(as_float_array(mag, "mag"))
    if mags.shape != (n, 3):
        raise ShapeError(f"expected shape (N, 3) with N = len(imu.t) = {n}, got {mags.shape}", argument="mag")
    return mags


# Largest component magnitude whose rows' norms cannot overflow (see _check_mag_norms).
_NORM_SAFE = 1e153


def _check_mag_norms(mags: FloatArray) -> FloatArray:
    """``mags`` (N, 3), refusing finite samples whose norm overflows: the filter keeps the first
    norm as its reference, which must stay finite."""
    # Row norms along an axis of 3 cost a quarter of a whole 9D run (62 ns/sample at 10^6
    # samples, docs/filters_robust.md); two contiguous reductions (1.8 ns) clear the common case:
    # components within ±1e153 have a finite norm (3·1e306 < 1.8e308), and NaN or inf fails the
    # test and takes the full check.
    if mags.size == 0 or (mags.min() >= -_NORM_SAFE and mags.max() <= _NORM_SAFE):
        return mags
    with np.errstate(over="ignore", invalid="ignore"):
        norms = np.linalg.norm(mags, axis=1)
    # NaN and inf themselves are the core's to report (naming the sample); here finite overflow.
    big = np.flatnonzero(np.isinf(norms) & np.isfinite(mags).all(axis=1))
    if big.size:
        raise NonFiniteError(f"sample {int(big[0])} is too large: its norm overflows float64", argument="mag")
    return mags


def _vec3(x: ArrayLike, name: str) -> list[float]:
    # A streaming sample is most often a float64 (3,) array: its finite values as they are, without
    # the general checks (8.6 µs against 1, a sixth of an update); anything else, or a non-finite
    # value, takes them and their named errors.
    if type(x) is np.ndarray and x.dtype == np.float64 and x.shape == (3,):
        v: list[float] = x.tolist()
        if all(map(math.isfinite, v)):
            return v
    return [float(e) for e in vector3(x, name)]


class _Locked:
    """A filter whose ``update`` reads, steps and replaces its state: from several threads at once,
    unlocked, updates were lost (issue 17); under ``_lock`` they run one after another. A lock is
    the object's, not its data: a copy (pickle, copy, deepcopy) gets a new one."""

    _lock: threading.Lock

    def __getstate__(self) -> dict[str, Any]:
        return {k: v for k, v in self.__dict__.items() if k != "_lock"}

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._lock = threading.Lock()


class _Filter(_Locked):
    """Common front of every filter: the shared options, the state and the three ways of running.
    A law's class sets its gains and calls :meth:`_setup` with its core filter class."""

    _core_filter: Any
    _state: FilterState

    def __init__(
        self,
        *,
        world: str = _OPTIONS.world,
        gravity: float = _OPTIONS.gravity,
        gain_ramp: GainRamp | None = _OPTIONS.gain_ramp,
        acc_lowpass: AccelLowPass | None = _OPTIONS.acc_lowpass,
        acc_rejection: AccelRejection | None = _OPTIONS.acc_rejection,
        mag_rejection: MagRejection | None = _OPTIONS.mag_rejection,
        rest_detection: RestDetection | None = _OPTIONS.rest_detection,
        mag_hold_s: float = _OPTIONS.mag_hold_s,
        **unknown: Any,
    ) -> None:
        if unknown:  # as Robust refuses an unknown parameter (a TypeError named _Filter.__init__ before)
            signatures = (inspect.signature(f).parameters for f in (type(self).__init__, _Filter.__init__))
            known = ", ".join(n for names in signatures for n in names if n not in ("self", "options", "unknown"))
            raise ParameterError(
                f"unknown option of {type(self).__name__}; it takes {known}", argument=next(iter(unknown))
            )
        self._lock = threading.Lock()
        if not isinstance(world, str):  # the core checks the name
            raise ParameterError(f"expected one of {WORLDS}, got {world!r}", argument="world")
        self.options = _core.FilterOptions(
            world=world,
            gravity=_real(gravity, "gravity"),
            gain_ramp=_option(gain_ramp, GainRamp, "gain_ramp"),
            acc_lowpass=_option(acc_lowpass, AccelLowPass, "acc_lowpass"),
            acc_rejection=_option(acc_rejection, AccelRejection, "acc_rejection"),
            mag_rejection=_option(mag_rejection, MagRejection, "mag_rejection"),
            rest_detection=_option(rest_detection, RestDetection, "rest_detection"),
            mag_hold_s=_real(mag_hold_s, "mag_hold_s"),
        )

    def _setup(self, core_filter: Any) -> None:
        self._core_filter = core_filter
        self.reset()

    @property
    def world(self) -> str:
        """``"ENU"`` or ``"NED"``."""
        return str(self.options.world)

    @property
    def gravity(self) -> float:
        """Gravity magnitude [m/s²] of the rejection and rest tests."""
        return float(self.options.gravity)

    @property
    def mag_hold_s(self) -> float:
        """Seconds a streamed field sample stands in for the samples without one."""
        return float(self.options.mag_hold_s)

    def reset(self, initial: Rotation | None = None) -> None:
        """Forget the state; the next :meth:`update` initialises (or, from ``initial``, is a step
        of its ``dt``; ``run(imu, initial=R)`` instead outputs ``R`` for its first sample)."""
        self._state = FilterState(_core.FilterState._initial(_initial_quat(initial)))

    def get_state(self) -> FilterState:
        """The current streaming state (immutable; keep it to restore later)."""
        return self._state

    def set_state(self, state: FilterState) -> None:
        """Restore a state from :meth:`get_state` or ``run(...).state``."""
        if not isinstance(state, FilterState):
            raise ParameterError(f"expected a FilterState, got {type(state).__name__}", argument="state")
        self._state = state

    def update(self, gyro: ArrayLike, accel: ArrayLike, dt: float, mag: ArrayLike | None = None) -> Rotation:
        """One streaming sample (``dt`` [s] since the previous one; ignored on the first, which
        initialises); returns the current attitude ``R_wb``. ``mag=None``: within ``mag_hold_s``
        (default 1 s) of the last field sample, that sample turned by the gyro stands in (a filter
        built with ``mag_hold_s=0`` uses no field then). Thread-safe: calls from several threads
        run one after another, none lost."""
        w, a = _vec3(gyro, "gyro"), _vec3(accel, "accel")
        step = real_scalar(dt, "dt", what="a step in seconds", accept=lambda x: True)
        m = None if mag is None else _vec3(mag, "mag")  # the core refuses a norm that overflows
        with self._lock:
            self._state = state = FilterState(self._core_filter.update(self._state, w, a, step, m))
        return rotation_from_unit_quat(state.quaternion)

    def run(
        self,
        imu: ImuData,
        *,
        mag: ArrayLike | bool | None = None,
        initial: Rotation | FilterState | None = None,
        body_from_sensor: tuple[Rotation, ArrayLike] | None = None,
    ) -> FilterResult:
        """Filter a whole recording in one native call (GIL released); the streaming state is not
        touched.

        Parameters
        ----------
        imu
            The gyro and accelerometer samples.
        mag
            None (default): ``imu.mag`` when the samples have one (9D), else 6D. ``False``: 6D even
            when ``imu.mag`` is there; ``True``: ``imu.mag``, which must be there. An ``(N, 3)``
            array: these magnetometer samples (9D), in place of ``imu.mag``.
        initial
            None: the first sample initialises. A ``Rotation``: the attitude at ``imu.t[0]`` (zero
            bias). A :class:`FilterState` (e.g. ``run(...).state`` of the previous chunk): continue
            from it, the first sample being a step of ``imu.t[0] − state.time``.
        body_from_sensor
            ``(R_bs, lever arm)``: the IMU's pose in the body frame; the filter estimates the body's
            attitude from the readings turned into body axes (rotation only: an attitude filter
            has no use for the lever arm, which must be zero). The estimated gyro bias is then in
            body axes.
        """
        if not isinstance(imu, ImuData):
            raise ParameterError(f"expected an imukit.ImuData, got {type(imu).__name__}", argument="imu")
        # The core refuses a finite sample whose squared norm overflows, naming it.
        mags = _run_mag(imu, mag)
        continued = isinstance(initial, FilterState)
        if isinstance(initial, FilterState):
            start = initial._at_time(initial.time - float(imu.t[0]))  # the core's clock is imu.seconds
        else:
            start = _core.FilterState._initial(_initial_quat(initial, "FilterState"))
        gyro, accel = imu.gyro, imu.accel
        if body_from_sensor is not None:
            rows, arm = sensor_pose(body_from_sensor)
            if any(v != 0.0 for v in arm):
                raise ParameterError(
                    "expected a zero lever arm: the filters use the rotation only", argument="body_from_sensor"
                )
            gyro, accel = _core.body_readings(imu.seconds, gyro, accel, ImuBias(), [list(r) for r in rows], list(arm))
            if mags is not None:
                mags = np.ascontiguousarray(body_from_sensor[0].apply(mags))
        q, bias, final = self._core_filter.run(imu.seconds, gyro, accel, mags, start, continued)
        return FilterResult(rotation_from_unit_quat(q), bias, FilterState(final._at_time(float(imu.t[-1]))))


def _initial_quat(initial: Rotation | None, state: str | None = None) -> list[float] | None:
    """``initial`` as xyzw; ``state`` names the state class the caller also takes (for the error)."""
    if initial is None:
        return None
    if isinstance(initial, Rotation) and initial.single:
        return [float(v) for v in initial.as_quat()]
    accepted = f"a single scipy Rotation, a {state} or None" if state else "a single scipy Rotation or None"
    raise ParameterError(f"expected {accepted}, got {initial!r}", argument="initial")


_MAHONY = _core.MahonyGains()
_MADGWICK = _core.MadgwickGains()


class Mahony(_Filter):
    """Mahony's explicit complementary filter (Mahony, Hamel & Pflimlin, IEEE TAC 2008):
    ``Ṙ̂ = R̂ [ω − b̂ + k_P ω_mes]×``, ``ḃ̂ = −k_I ω_mes``, ``ω_mes = Σ v_i × v̂_i``.

    Parameters
    ----------
    kp
        Proportional gain [1/s] (default 0.3, tuned on BROAD: docs/filters_accuracy.md).
    ki
        Integral gain [1/s²] of the gyro-bias estimate (default 0.01; 0 disables it).
    world
        ``"ENU"`` (default) or ``"NED"``.
    gravity
        Gravity magnitude [m/s²] for the rejection and rest tests (default 9.81).
    gain_ramp
        :class:`GainRamp` (default 3 s from 10×), or None for none.
    acc_lowpass
        :class:`AccelLowPass` (default 1 s per stage): the law sees the specific force low-passed
        in the gyro's frame, where accelerations that come and go cancel (Laidig & Seel 2023); None:
        the raw sample (the textbook law).
    acc_rejection, mag_rejection
        :class:`AccelRejection` / :class:`MagRejection` (defaults on), or None to use every sample.
        The accelerometer's drift rule switches its angle test off while the filtered norm says the
        estimate drifts on an unlearned gyro bias rather than accelerates (docs/filters.md).
    rest_detection
        :class:`RestDetection` (default on: the bias follows the gyro at rest, found from the gyro's
        and the accelerometer's deviations from their own low passes), or None for none.
    mag_hold_s
        Streaming (:meth:`update`) with a field slower than the gyro: on a sample with
        ``mag=None`` the last field sample, turned into the current body axes by the gyro, stands
        in for up to this many seconds (default 1.0), so the heading gain and the field's gate
        run in seconds whatever the field's rate. 0: a sample without a field has none.

    Every default is the Rust core's (``imukit._core.MahonyGains()``, ``FilterOptions.default()``).
    """

    def __init__(self, *, kp: float = _MAHONY.kp, ki: float = _MAHONY.ki, **options: Any) -> None:
        super().__init__(**options)
        self.gains = _core.MahonyGains(_real(kp, "kp"), _real(ki, "ki"))
        self._setup(_core.MahonyFilter(self.gains, self.options))

    @property
    def kp(self) -> float:
        """Proportional gain [1/s]."""
        return float(self.gains.kp)

    @property
    def ki(self) -> float:
        """Integral gain [1/s²]."""
        return float(self.gains.ki)


class Madgwick(_Filter):
    """Madgwick's gradient-descent filter (Madgwick 2010; Madgwick, Harrison & Vaidyanathan, ICORR
    2011): ``q̇ = ½ q ⊗ (ω − b̂) − β ∇f/max(‖∇f‖, θ₀)``.

    Parameters
    ----------
    beta
        ``β`` [1/s], the norm of the correction's quaternion rate (default 0.035, tuned on BROAD:
        docs/filters_accuracy.md). The bias estimate changes only through ``rest_detection``.
    full_rate_angle_rad
        ``θ₀`` [rad] (default 0.08): the step is ``2β ∇/max(‖∇‖, θ₀)``, proportional below a gap of
        about ``θ₀`` and Madgwick's full rate ``2β`` above; applied when the step has no field term
        (6D, or the field rejected). 0 is the textbook normalised step, which lets a sustained
        acceleration tilt the estimate by 5.5° where the default holds 1.7° (docs/filters.md).
    world, gravity, gain_ramp, acc_lowpass, acc_rejection, mag_rejection, rest_detection, mag_hold_s
        As for :class:`Mahony`.
    """

    def __init__(
        self,
        *,
        beta: float = _MADGWICK.beta,
        full_rate_angle_rad: float = _MADGWICK.full_rate_angle_rad,
        **options: Any,
    ) -> None:
        super().__init__(**options)
        self.gains = _core.MadgwickGains(_real(beta, "beta"), _real(full_rate_angle_rad, "full_rate_angle_rad"))
        self._setup(_core.MadgwickFilter(self.gains, self.options))

    @property
    def beta(self) -> float:
        """``β`` [1/s]."""
        return float(self.gains.beta)

    @property
    def full_rate_angle_rad(self) -> float:
        """``θ₀`` [rad]: the gap below which the step is proportional."""
        return float(self.gains.full_rate_angle_rad)


from imukit._robust import Robust, RobustResult, RobustState  # noqa: E402  (builds on the helpers above)
