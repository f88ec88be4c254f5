"""The Allan-variance estimator: :func:`allan_deviation` and its result."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imukit import _core
from imukit._arrays import FloatArray, as_float_array, flag
from imukit._errors import ParameterError, ShapeError
from imukit.imu import ImuData, _number
from imukit.threads import checked


class AllanDeviation(NamedTuple):
    """Allan deviation of a rate signal, as returned by :func:`allan_deviation`."""

    taus: FloatArray
    """``(M,)`` averaging times ``τ = m / rate`` [s]."""
    deviation: FloatArray
    """``(M,)`` for ``(N,)`` input, ``(M, C)`` for ``(N, C)`` input: σ(τ) [unit of the input]."""
    clusters: NDArray[np.int64]
    """``(M,)`` number of squared differences averaged at each τ (allantools' ``ns``):
    ``N − 2m + 1`` overlapping, ``⌊N/m⌋ − 1`` non-overlapping."""
    rate: float
    """Sample rate [Hz]."""
    samples: int
    """Record length N."""
    overlapping: bool
    """Which estimator produced :attr:`deviation`."""

    @property
    def variance(self) -> FloatArray:
        """σ²(τ), same shape as :attr:`deviation`."""
        return self.deviation**2

    @property
    def cluster_sizes(self) -> NDArray[np.int64]:
        """``(M,)`` cluster sizes ``m = τ · rate``."""
        return np.rint(self.taus * self.rate).astype(np.int64)


def _rate(rate: object) -> float:
    return _number(rate, "rate", positive=True, what="a positive, finite sample rate in Hz")


def _cluster_sizes(taus: ArrayLike | None, rate: float, n: int) -> list[int]:
    if taus is None:
        if n < 4:
            raise ShapeError(f"the default τ grid (m = 1, 2, 4, … ≤ N/4) needs N ≥ 4 samples, got {n}", argument="x")
        return [1 << j for j in range((n // 4).bit_length())]
    t = as_float_array(taus, "taus")
    if t.ndim != 1 or t.size == 0:
        raise ShapeError(f"expected a non-empty (M,) array of seconds, got shape {t.shape}", argument="taus")
    bad = np.flatnonzero(~(np.isfinite(t) & (t > 0.0)))
    if bad.size:
        k = int(bad[0])
        raise ParameterError(f"expected positive, finite seconds, got taus[{k}] = {float(t[k])!r}", argument="taus")
    m = t * rate
    whole = np.rint(m)
    small = np.flatnonzero(whole < 1)
    if small.size:
        k = int(small[0])
        raise ParameterError(
            f"taus[{k}] = {float(t[k])!r} s is shorter than one sample (1/rate = {1.0 / rate!r} s)", argument="taus"
        )
    off = np.flatnonzero(np.abs(m - whole) > 1e-9 * np.maximum(whole, 1.0))
    if off.size:
        k = int(off[0])
        raise ParameterError(
            f"every τ must be a whole multiple of 1/rate = {1.0 / rate!r} s; "
            f"taus[{k}] = {float(t[k])!r} s is {float(m[k])!r} samples",
            argument="taus",
        )
    big = np.flatnonzero(2.0 * whole > n)
    if big.size:
        k = int(big[0])
        raise ParameterError(
            f"taus[{k}] = {float(t[k])!r} s is m = {int(whole[k])} samples; two clusters need 2m ≤ N = {n}",
            argument="taus",
        )
    return [int(v) for v in whole]


def allan_deviation(
    x: ArrayLike, rate: float, *, taus: ArrayLike | None = None, overlapping: bool = True, threads: int | None = None
) -> AllanDeviation:
    """Allan deviation σ(τ) of a rate signal ``x`` sampled at ``rate`` Hz.

    Parameters
    ----------
    x
        ``(N,)`` or ``(N, C)`` samples (one column per axis), e.g. a gyro at rest [rad/s]. Finite.
    rate
        Sample rate [Hz], positive; ``τ0 = 1 / rate``.
    taus
        Averaging times [s], each a whole multiple ``m τ0`` with ``2m ≤ N``, in any order. Default:
        octaves ``m = 1, 2, 4, …`` up to ``N/4`` (at least four clusters; Riley, NIST SP 1065).
    overlapping
        The overlapping estimator (default: every start index, the better-determined estimate) or
        the non-overlapping one (disjoint adjacent clusters).
    threads
        ``threads``: threads for this call (None: :func:`imukit.set_num_threads`'s setting), see :mod:`imukit.threads`.

    Returns
    -------
    AllanDeviation
        ``taus`` [s], ``deviation`` (``(M,)`` or ``(M, C)``), ``clusters`` (terms per τ), and the
        ``rate``, ``samples`` and ``overlapping`` that :func:`fit_allan` needs.

    Raises
    ------
    ShapeError, DTypeError, NonFiniteError, ParameterError
        Messages start with the argument name (``x``, ``rate``, ``taus``).

    Notes
    -----
    ``AVAR(mτ0) = Σ_k (x_{k+2m} − 2x_{k+m} + x_k)² / (2 m² τ0² n)`` with the phase
    ``x_j = τ0 Σ_{i<j} y_i`` and ``n`` the number of terms; computed in the Rust core without
    forming the phase, to within a few ulps (``docs/noise.md``). Agrees with
    ``allantools.oadev(x, rate, data_type="freq", taus=taus)`` (and ``adev``) to 1e-10 relative.
    """
    arr = as_float_array(x, "x")
    if arr.ndim not in (1, 2):
        raise ShapeError(f"expected shape (N,) or (N, C), got {arr.shape}", argument="x")
    data = np.ascontiguousarray(arr if arr.ndim == 2 else arr[:, None])
    if data.shape[1] == 0:
        raise ShapeError(f"expected shape (N, C) with C ≥ 1, got {arr.shape}", argument="x")
    n = data.shape[0]
    if n < 2:
        raise ShapeError(f"expected at least 2 samples, got {n}", argument="x")
    f = _rate(rate)
    m = _cluster_sizes(taus, f, n)
    count = checked(threads)
    overlapping = flag(overlapping, "overlapping")
    # Columns far from 1 in magnitude are scaled by a power of two first (exact): the sums of
    # squares underflowed to a deviation of 0 at 1e-300 and overflowed at 1e154 (before 2026-12-07).
    largest = np.max(np.abs(data), axis=0)
    far = np.isfinite(largest) & (largest > 0) & ((largest < 1e-100) | (largest > 1e100))  # NaN: the core names it
    scale = np.where(far, np.exp2(np.floor(np.log2(np.where(far, largest, 1.0)))), 1.0)
    if far.any():
        data = np.ascontiguousarray(data / scale)
    variance, terms = _core.allan_variance(data, "x", f, m, overlapping, count)
    deviation = np.sqrt(variance) * scale
    return AllanDeviation(
        taus=np.asarray(m, dtype=np.float64) / f,
        deviation=deviation if arr.ndim == 2 else deviation[:, 0],
        clusters=terms,
        rate=f,
        samples=n,
        overlapping=overlapping,
    )


def mean_rate_hz(imu: ImuData) -> float:
    """Intervals per second over the recording, ``(N − 1) / (t_N − t_1)``; from integer nanoseconds
    when there are some, so that 60000 intervals over 600 s give 100 Hz exactly. Float stamps too
    (they gave the median rate, ``ImuData.rate_hz``, before 2026-12-07: KITTI's 100.02 Hz for
    99.60, its dropouts unseen)."""
    if not isinstance(imu, ImuData):
        raise ParameterError(f"expected an imukit.ImuData, got {type(imu).__name__}", argument="imu")
    if len(imu) < 2:
        raise ShapeError("a single sample has no rate", argument="imu")
    if imu.t_ns is not None:
        return (len(imu) - 1) * 1e9 / float(imu.t_ns[-1] - imu.t_ns[0])
    return (len(imu) - 1) / imu.duration
