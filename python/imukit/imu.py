"""IMU data types: samples (:class:`ImuData`), biases (:class:`ImuBias`), noise (:class:`ImuNoise`).

=====================  ===========================================================================
frame                  gyro and accel are in the body (IMU) frame ``b``
gyro                   ``(N, 3)`` angular rate ω_b [rad/s]
accel                  ``(N, 3)`` specific force ``a_m = R_wbᵀ (a_w − g_w)`` [m/s²]; +9.81 on the up
                       axis at rest (``docs/conventions.md``, row 7)
mag                    ``(N, 3)`` magnetic field ``R_wbᵀ m_w`` in the body frame, or None; µT by
                       convention (readers say when they know the unit), any unit for the filters,
                       which use its direction, norm ratios and dip only (row 13)
time                   ``t`` float64 seconds, or integer nanoseconds (EuRoC / ROS), told apart by
                       dtype (row 10); every ``dt`` comes from the stamps
noise                  continuous-time densities, Kalibr style (row 11); :meth:`ImuNoise.discrete`
                       turns them into per-sample variances for the actual ``dt``
=====================  ===========================================================================
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imukit import _core
from imukit._arrays import FloatArray, as_stamps, frozen, readonly_array, real_scalar, relative_seconds
from imukit._errors import NonFiniteError, ShapeError, TimestampError
from imukit._frozen import Frozen

__all__ = ["GRAVITY", "DiscreteNoise", "DiscreteSigmas", "ImuBias", "ImuData", "ImuNoise"]

GRAVITY: tuple[float, float, float] = _core.GRAVITY
"""The default world-frame gravity [m/s²], z up: ``(0, 0, −9.81)``, the core's ``imukit::imu::GRAVITY``
(written there only); every ``gravity=`` default refers to it."""


# Integer stamps are nanoseconds; microseconds passed as such show a rate 1000x too high and, for epoch
# stamps, an epoch 1000x too early: the µs of 2001-2100 fall 11.6-47 days after 1970 as ns (issue 17).
_NS_RATE_WARN_HZ = 20_000.0
_US_EPOCH_AS_NS = (10**15, 4 * 10**15)


def _plausible_ns(t_ns: NDArray[np.int64] | None) -> None:
    """Refuse integer stamps that look like microseconds (an epoch 11.6-47 days after 1970 and a rate over
    20 kHz), warn about a rate over 20 kHz alone (a relative µs clock; a real IMU rarely samples so fast)."""
    if t_ns is None or len(t_ns) < 2:
        return
    step = float(np.median(np.diff(t_ns)))
    rate = 1e9 / step
    if rate <= _NS_RATE_WARN_HZ:
        return
    days = float(t_ns[0]) / 86_400e9
    as_us = f"read as microseconds they would be {rate / 1000:.4g} Hz"
    if _US_EPOCH_AS_NS[0] <= t_ns[0] < _US_EPOCH_AS_NS[1]:
        raise TimestampError(
            f"integer stamps are nanoseconds, but these start {days:.3g} days after 1970 with a median step of "
            f"{step:g} ns ({rate:.4g} Hz): they look like microseconds ({as_us} from "
            f"{np.datetime64(int(t_ns[0]), 'us')}); pass t * 1000",
            argument="t",
        )
    warnings.warn(
        f"t: integer stamps are nanoseconds, but their median step is {step:g} ns ({rate:.4g} Hz); if they are "
        f"microseconds ({as_us}), pass t * 1000",
        UserWarning,
        stacklevel=3,
    )


# Float stamps are seconds. Beyond 1e11 s (the year 5138) they are another unit: float64 there resolves
# only 15 µs, and the epochs of 1973-2100 in ms, µs or ns land there. A median step over 1 s (an IMU
# below 1 Hz) is more likely milliseconds than a slow sensor: a warning.
_SECONDS_LIMIT = 1e11
_SLOW_STEP_S = 1.0
_EPOCH_S = (1e8, 4.2e9)  # 1973 to 2103


def _plausible_seconds(seconds: FloatArray, t_ns: NDArray[np.int64] | None) -> None:
    """Refuse float stamps beyond 1e11 s, naming the unit that would make them an epoch of 1973-2103;
    warn about a median step over 1 s."""
    if t_ns is not None or len(seconds) == 0:
        return
    first = float(seconds[0])
    if abs(first) >= _SECONDS_LIMIT:
        units = (("milliseconds", 1e3), ("microseconds", 1e6), ("nanoseconds", 1e9))
        guess = next(((u, d) for u, d in units if _EPOCH_S[0] <= abs(first) / d < _EPOCH_S[1]), None)
        hint = (
            "pass them in seconds or as integer nanoseconds"
            if guess is None
            else f"they look like {guess[0]} ({np.datetime64(int(first / guess[1]), 's')}): pass t / {int(guess[1])}, "
            "or integer nanoseconds (a reader: its time_unit)"
        )
        raise TimestampError(
            f"float stamps are seconds, but these start at {first:.6g} s, beyond {_SECONDS_LIMIT:.0e} s (the year "
            f"5138): {hint}",
            argument="t",
        )
    if len(seconds) >= 2:
        step = float(np.median(np.diff(seconds)))
        if step > _SLOW_STEP_S:
            warnings.warn(
                f"t: float stamps are seconds, but their median step is {step:g} s ({1.0 / step:.3g} Hz); if they "
                "are milliseconds, pass t / 1000 (a reader: time_unit='ms')",
                UserWarning,
                stacklevel=3,
            )


class ImuData(Frozen):
    """Validated, immutable IMU samples: ``t`` (N,), ``gyro`` (N, 3) [rad/s], ``accel`` (N, 3) [m/s²],
    and optionally ``mag`` (N, 3) [µT].

    Parameters
    ----------
    t
        ``(N,)`` sample times, strictly increasing, N ≥ 1: float **seconds**, or integer
        **nanoseconds** (the dtype decides, as in :func:`imukit.integrate_attitude`; integer stamps
        whose median step is under 1 µs are refused with :class:`imukit.ParameterError`, float
        stamps beyond 1e11 s (the year 5138: milliseconds or finer) with
        :class:`imukit.TimestampError`, and float stamps whose median step exceeds 1 s warn).
    gyro
        ``(N, 3)`` body angular rates ω_b [rad/s]; row k taken at ``t[k]``.
    accel
        ``(N, 3)`` body specific force [m/s²]; row k taken at ``t[k]``.
    max_gap
        If given [s], a step ``t[k] − t[k-1]`` larger than it is an error
        (:class:`imukit.TimestampError` naming sample k): dropped samples are reported, not
        integrated over.
    gyro_range, accel_range
        The sensor's full-scale range per axis [rad/s], [m/s²], or None when unknown. Samples
        with some axis at or beyond it in magnitude are clipped, not measured:
        :attr:`gyro_saturated` and :attr:`accel_saturated` flag them. Give the smaller of the two
        limits the sensor actually reports: a 16-bit two's-complement gyro rated ±2000 °/s reads
        −32768 LSB down to −2000 °/s but only +32767 LSB up to 2000·32767/32768 °/s, so its range
        is ``np.deg2rad(2000) * 32767 / 32768`` — the datasheet's ``np.deg2rad(2000)`` would never
        flag a gyro pinned at its positive limit.
    mag
        ``(N, 3)`` magnetometer samples in the body frame, row k taken at ``t[k]``, finite, or None
        (no magnetometer). µT by convention; the filters accept any unit (they use the direction,
        norm ratios and dip), so a file in gauss or nT needs no conversion for them.

    Attributes
    ----------
    t
        ``(N,)`` float64 seconds: the float input, or ``t_ns / 1e9`` (nearest float) for integer
        input. Absolute epoch seconds resolve only ~0.24 µs: integrate over :attr:`seconds`.
    t_ns
        ``(N,)`` int64 nanoseconds for integer input, else None.
    gyro, accel
        ``(N, 3)`` float64, C-contiguous, read-only copies of the input.
    mag
        ``(N, 3)`` float64 read-only copy, or None.
    gyro_range, accel_range
        As given (float or None).

    Raises
    ------
    ShapeError, DTypeError, NonFiniteError, TimestampError, ParameterError
        Messages start with the argument name and name the first bad sample.
    """

    __slots__ = ("_seconds", "accel", "accel_range", "gyro", "gyro_range", "mag", "t", "t_ns")
    _fields = ("t", "t_ns", "gyro", "accel", "_seconds", "gyro_range", "accel_range", "mag")

    t: FloatArray
    t_ns: NDArray[np.int64] | None
    gyro: FloatArray
    accel: FloatArray
    gyro_range: float | None
    accel_range: float | None
    mag: FloatArray | None
    _seconds: FloatArray

    def __init__(
        self,
        t: ArrayLike,
        gyro: ArrayLike,
        accel: ArrayLike,
        *,
        max_gap: float | None = None,
        gyro_range: float | None = None,
        accel_range: float | None = None,
        mag: ArrayLike | None = None,
    ) -> None:
        stamps = as_stamps(t)
        _plausible_ns(stamps.t_ns)
        seconds = relative_seconds(stamps.seconds, "t")
        _plausible_seconds(stamps.seconds, stamps.t_ns)
        n = len(seconds)
        gyro_arr = readonly_array(gyro, "gyro", (n, 3), f"(N, 3) with N = len(t) = {n}")
        accel_arr = readonly_array(accel, "accel", (n, 3), f"(N, 3) with N = len(t) = {n}")
        mag_arr = None if mag is None else readonly_array(mag, "mag", (n, 3), f"(N, 3) with N = len(t) = {n}")
        if max_gap is not None:
            gap = _number(max_gap, "max_gap", positive=True, what="a positive number of seconds or None")
            steps = np.diff(seconds)
            over = np.flatnonzero(steps > gap)
            if over.size:
                k = int(over[0])
                ns = stamps.t_ns
                step = f"{steps[k]:.12g} s" if ns is None else f"{int(ns[k + 1] - ns[k])} ns"
                raise TimestampError(
                    f"gap into sample {k + 1} has dt = {step}, larger than max_gap = {gap!r} s", argument="t"
                )
        # t may be the caller's array (kept if frozen); t_ns and seconds are fresh.
        ranges = _ranges(gyro_range, accel_range)
        self._set(frozen(stamps.t), stamps.t_ns, gyro_arr, accel_arr, seconds, *ranges, mag_arr)

    @classmethod
    def _from_core(
        cls,
        t: FloatArray,
        gyro: FloatArray,
        accel: FloatArray,
        gyro_range: float | None = None,
        accel_range: float | None = None,
    ) -> ImuData:
        """Samples the compiled core has just produced, without validating or copying them (fresh,
        finite, strictly increasing float seconds by construction; copying 10⁷ samples cost more than
        simulating them). The arrays are made read-only here and must not be shared elsewhere."""
        ranges = _ranges(gyro_range, accel_range)
        # From a first stamp of 0, t − t[0] is t itself (increasing, as the core's stamps are).
        relative = t if t[0] == 0.0 else relative_seconds(t, "t")
        return cls._from_validated(t, None, gyro, accel, relative, *ranges, None)

    @property
    def gyro_saturated(self) -> NDArray[np.bool_]:
        """``(N,)`` True where some gyro axis reads ±:attr:`gyro_range` or beyond (clipped); all
        False when the range is unknown."""
        return _at_range(self.gyro, self.gyro_range)

    @property
    def accel_saturated(self) -> NDArray[np.bool_]:
        """``(N,)`` True where some accelerometer axis reads ±:attr:`accel_range` or beyond
        (clipped); all False when the range is unknown."""
        return _at_range(self.accel, self.accel_range)

    @property
    def seconds(self) -> FloatArray:
        """``(N,)`` float64 seconds since the first sample (read-only); exact from ``t_ns`` when present.

        For integer input the offsets are taken in int64 and rounded once, so every ``dt`` is
        right to far below a nanosecond even at a 1.4e18 ns epoch. Integrators consume this.
        """
        return self._seconds

    @property
    def dt(self) -> FloatArray:
        """``(N-1,)`` steps [s], ``np.diff(seconds)``."""
        return np.diff(self._seconds)

    @property
    def rate_hz(self) -> float:
        """Median sample rate ``median(1 / dt)`` [Hz]; needs at least 2 samples."""
        if len(self) < 2:
            raise ShapeError("a single sample has no rate", argument="rate_hz")
        return float(np.median(1.0 / self.dt))

    @property
    def duration(self) -> float:
        """``t[-1] − t[0]`` [s] (0 for one sample)."""
        return float(self._seconds[-1])

    def __len__(self) -> int:
        return len(self.t)

    def __getitem__(self, index: slice | NDArray[np.bool_]) -> ImuData:
        """A slice of the samples as a new ``ImuData`` (negative indices count from the end, as in
        Python; the step must be positive and the slice non-empty), or the samples where a boolean
        mask of length N is True (at least one)."""
        n = len(self)
        if isinstance(index, np.ndarray) and index.dtype == np.bool_:
            if index.shape != (n,):
                raise ShapeError(f"a boolean mask must have shape ({n},), got {index.shape}", argument="index")
            if not index.any():
                raise ShapeError(f"the mask selects no sample of {n}; an ImuData has at least one", argument="index")
        elif not isinstance(index, slice):
            raise TypeError(
                "ImuData indices must be slices (imu[k:k + 1] for sample k) or a boolean mask of length N, got "
                f"{type(index).__name__}"
            )
        elif index.step == 0:
            raise ShapeError(f"ImuData slices need a positive step, got {index}", argument="index")
        else:
            self._check_slice(index, n)
        t = self.t if self.t_ns is None else self.t_ns
        ranges = {"gyro_range": self.gyro_range, "accel_range": self.accel_range}
        mag = None if self.mag is None else self.mag[index]
        return ImuData(t[index], self.gyro[index], self.accel[index], **ranges, mag=mag)

    @staticmethod
    def _check_slice(index: slice, n: int) -> None:
        start, stop, step = index.indices(n)
        if step <= 0:
            raise ShapeError(f"ImuData slices need a positive step, got {index}", argument="index")
        if len(range(start, stop, step)) == 0:
            raise ShapeError(
                f"{index} selects no sample of {n} (it runs from {start} to {stop}); an ImuData has at least one",
                argument="index",
            )

    def __eq__(self, other: object) -> bool:
        """Equal samples: the same stamps (and stamp type), readings, ranges and magnetometer, bit for bit."""
        if not isinstance(other, ImuData):
            return NotImplemented
        arrays = ("t", "t_ns", "gyro", "accel", "mag")
        same = all(_same_array(getattr(self, name), getattr(other, name)) for name in arrays)
        return same and (self.gyro_range, self.accel_range) == (other.gyro_range, other.accel_range)

    __hash__ = None  # type: ignore[assignment]

    def __repr__(self) -> str:
        stamps = "int64 ns" if self.t_ns is not None else "float s"
        rate = f", {self.rate_hz:.6g} Hz" if len(self) > 1 else ""
        mag = ", with mag" if self.mag is not None else ""
        return f"ImuData({len(self)} samples, {self.duration:.6g} s{rate}, t in {stamps}{mag})"


def _same_array(a: NDArray[np.generic] | None, b: NDArray[np.generic] | None) -> bool:
    return a is b if a is None or b is None else bool(a.dtype == b.dtype and np.array_equal(a, b))


def _ranges(gyro_range: float | None, accel_range: float | None) -> tuple[float | None, float | None]:
    what = "a positive, finite full-scale range or None"
    gyro, accel = (
        None if value is None else _number(value, name, positive=True, what=what)
        for name, value in (("gyro_range", gyro_range), ("accel_range", accel_range))
    )
    return gyro, accel


def _at_range(values: FloatArray, full_scale: float | None) -> NDArray[np.bool_]:
    flags: NDArray[np.bool_] = np.zeros(len(values), dtype=bool)
    if full_scale is not None:
        flags = np.asarray((np.abs(values) >= full_scale).any(axis=1))
    flags.setflags(write=False)
    return flags


class ImuBias(Frozen):
    """Constant IMU biases in the body frame: ``gyro`` (3,) [rad/s], ``accel`` (3,) [m/s²]; immutable.

    The measurement model is ``ω_m = ω_b + b_g + n_g`` and ``a_m = R_wbᵀ (a_w − g_w) + b_a + n_a``,
    so a bias is subtracted from the readings to correct them.
    """

    __slots__ = ("accel", "gyro")
    _fields = ("gyro", "accel")

    gyro: FloatArray
    accel: FloatArray

    def __init__(self, gyro: ArrayLike = (0.0, 0.0, 0.0), accel: ArrayLike = (0.0, 0.0, 0.0)) -> None:
        self._set(
            readonly_array(gyro, "gyro", (3,), "(3,)", "element"),
            readonly_array(accel, "accel", (3,), "(3,)", "element"),
        )

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, ImuBias):
            return NotImplemented
        return bool(np.array_equal(self.gyro, other.gyro) and np.array_equal(self.accel, other.accel))

    __hash__ = None  # type: ignore[assignment]

    def __repr__(self) -> str:
        return f"ImuBias(gyro={self.gyro.tolist()}, accel={self.accel.tolist()})"


class DiscreteNoise(NamedTuple):
    """Per-sample VARIANCES for one step ``dt`` (see :meth:`ImuNoise.discrete`)."""

    gyro_var: float
    """White gyro noise of one sample, ``σ_g² / dt`` [(rad/s)²]."""
    accel_var: float
    """White accelerometer noise of one sample, ``σ_a² / dt`` [(m/s²)²]."""
    gyro_bias_var: float
    """Gyro bias change over the step, ``σ_bg² dt`` [(rad/s)²]."""
    accel_bias_var: float
    """Accelerometer bias change over the step, ``σ_ba² dt`` [(m/s²)²]."""


class DiscreteSigmas(NamedTuple):
    """Per-sample STANDARD DEVIATIONS at a fixed rate (see :meth:`ImuNoise.to_discrete_sigmas`).

    Field names match the keywords of :meth:`ImuNoise.from_discrete`, so
    ``ImuNoise.from_discrete(**s._asdict(), rate_hz=r)`` inverts ``to_discrete_sigmas(r)``.
    """

    gyro_sigma: float
    """White gyro noise of one sample [rad/s]."""
    accel_sigma: float
    """White accelerometer noise of one sample [m/s²]."""
    gyro_walk_sigma: float
    """Std of the gyro bias change per sample [rad/s]."""
    accel_walk_sigma: float
    """Std of the accelerometer bias change per sample [m/s²]."""


def _number(value: object, name: str, *, positive: bool, what: str) -> float:
    """``value`` as a finite float that is ≥ 0 (or > 0 when ``positive``), else :class:`ParameterError`."""

    def accept(x: float) -> bool:
        return math.isfinite(x) and (x > 0.0 if positive else x >= 0.0)

    return real_scalar(value, name, what=what, accept=accept)


def _density(value: float, name: str) -> float:
    return _number(value, name, positive=False, what="a finite, non-negative number")


def _rate(rate_hz: float) -> float:
    return _number(rate_hz, "rate_hz", positive=True, what="a positive, finite rate in Hz")


@dataclass(frozen=True)
class ImuNoise:
    """Continuous-time IMU noise densities (Kalibr / Allan-variance convention), scalars for all axes.

    =====================  ======  ===========  =================================
    field                  symbol  unit         per sample of length dt
    =====================  ======  ===========  =================================
    ``gyro_density``       σ_g     rad/s/√Hz    white: σ = σ_g / √dt [rad/s]
    ``accel_density``      σ_a     m/s²/√Hz     white: σ = σ_a / √dt [m/s²]
    ``gyro_random_walk``   σ_bg    rad/s²/√Hz   bias step: σ = σ_bg √dt [rad/s]
    ``accel_random_walk``  σ_ba    m/s³/√Hz     bias step: σ = σ_ba √dt [m/s²]
    =====================  ======  ===========  =================================

    Worked example, EuRoC's Kalibr values at 200 Hz (dt = 0.005 s, √200 = 14.1421):
    gyroscope_noise_density 1.6968e-04 → σ = 1.6968e-04 · 14.1421 = 2.3996e-03 rad/s;
    accelerometer_noise_density 2.0e-03 → 2.8284e-02 m/s²; gyroscope_random_walk 1.9393e-05 →
    bias step 1.9393e-05 / 14.1421 = 1.3713e-06 rad/s; accelerometer_random_walk 3.0e-03 →
    2.1213e-04 m/s². Discretise with the actual dt of each step, never a nominal rate
    (``docs/conventions.md``, row 11). All four must be finite and ≥ 0.
    """

    gyro_density: float
    accel_density: float
    gyro_random_walk: float
    accel_random_walk: float

    def __post_init__(self) -> None:
        for name in ("gyro_density", "accel_density", "gyro_random_walk", "accel_random_walk"):
            object.__setattr__(self, name, _density(getattr(self, name), name))

    @classmethod
    def from_kalibr(
        cls,
        *,
        gyroscope_noise_density: float,
        accelerometer_noise_density: float,
        gyroscope_random_walk: float,
        accelerometer_random_walk: float,
    ) -> ImuNoise:
        """From the four entries of a Kalibr ``imu.yaml``: same units, no conversion."""
        return cls(
            gyro_density=gyroscope_noise_density,
            accel_density=accelerometer_noise_density,
            gyro_random_walk=gyroscope_random_walk,
            accel_random_walk=accelerometer_random_walk,
        )

    @classmethod
    def from_discrete(
        cls,
        *,
        gyro_sigma: float,
        accel_sigma: float,
        gyro_walk_sigma: float,
        accel_walk_sigma: float,
        rate_hz: float,
    ) -> ImuNoise:
        """From per-sample standard deviations at ``rate_hz``.

        White noise: ``σ_c = σ_d / √rate_hz`` (``gyro_sigma`` [rad/s] → σ_g [rad/s/√Hz]). Bias
        random walk: ``σ_w = σ_step · √rate_hz``, σ_step being the std of the bias change per sample
        (``gyro_walk_sigma`` [rad/s] → σ_bg [rad/s²/√Hz]). Example at 200 Hz: ``gyro_sigma`` 2.3996e-03
        gives σ_g = 2.3996e-03 / 14.1421 = 1.6968e-04; ``gyro_walk_sigma`` 1.3713e-06 gives
        σ_bg = 1.3713e-06 · 14.1421 = 1.9393e-05. Check which a configuration file holds: the same
        key names are used for densities in some projects and per-sample σ in others.
        """
        root = math.sqrt(_rate(rate_hz))
        return cls(
            gyro_density=_density(gyro_sigma, "gyro_sigma") / root,
            accel_density=_density(accel_sigma, "accel_sigma") / root,
            gyro_random_walk=_density(gyro_walk_sigma, "gyro_walk_sigma") * root,
            accel_random_walk=_density(accel_walk_sigma, "accel_walk_sigma") * root,
        )

    def to_discrete_sigmas(self, rate_hz: float) -> DiscreteSigmas:
        """Per-sample standard deviations at ``rate_hz``, the inverse of :meth:`from_discrete`.

        ``gyro_sigma = σ_g √rate_hz``, ``gyro_walk_sigma = σ_bg / √rate_hz`` (same for accel).
        """
        rate = _rate(rate_hz)
        root = math.sqrt(rate)
        sigmas = DiscreteSigmas(
            gyro_sigma=self.gyro_density * root,
            accel_sigma=self.accel_density * root,
            gyro_walk_sigma=self.gyro_random_walk / root,
            accel_walk_sigma=self.accel_random_walk / root,
        )
        if not all(map(math.isfinite, sigmas)):
            density = max(self.gyro_density, self.accel_density)
            raise NonFiniteError(
                f"a density of {density!r} at {rate!r} Hz gives a per-sample sigma beyond float64",
                argument="rate_hz",
            )
        return sigmas

    def discrete(self, dt: float) -> DiscreteNoise:
        """Per-sample variances for a step ``dt`` [s] (> 0), per axis.

        ``gyro_var = σ_g² / dt``, ``accel_var = σ_a² / dt``, ``gyro_bias_var = σ_bg² dt``,
        ``accel_bias_var = σ_ba² dt``. Example: σ_g = 1.6968e-04 and dt = 0.005 give
        ``gyro_var`` = 2.8791e-08 / 0.005 = 5.7582e-06 (rad/s)², i.e. σ = 2.3996e-03 rad/s.
        """
        step = _number(dt, "dt", positive=True, what="a positive, finite step in seconds")

        def variance(name: str, white: bool) -> float:
            sigma = float(getattr(self, name))
            # Multiplied, not **2: a float power that overflows raises OverflowError.
            v = sigma * sigma / step if white else sigma * sigma * step
            if not math.isfinite(v):
                raise NonFiniteError(
                    f"{sigma!r} with dt = {step!r} s gives a variance beyond float64", argument=f"{name} / dt"
                )
            return v

        return DiscreteNoise(
            gyro_var=variance("gyro_density", white=True),
            accel_var=variance("accel_density", white=True),
            gyro_bias_var=variance("gyro_random_walk", white=False),
            accel_bias_var=variance("accel_random_walk", white=False),
        )
