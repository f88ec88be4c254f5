"""The clock offset between an IMU and a reference trajectory, from their angular speeds:
:func:`time_offset`.

Both sensors see the same rotation, so the IMU's angular speed ``‖ω(t)‖`` and the reference's,
``‖Log(R_jᵀ R_j+1)‖ / (t_j+1 − t_j)`` at the interval's midpoint, are the same signal on two clocks.
The magnitude does not depend on the frames, so neither the IMU-to-body rotation nor the
reference's world needs to be known (Kalibr, Furgale, Rehder & Siegwart, IROS 2013, estimates
the offset within its full calibration model and starts it from such a correlation of rate norms).
Both speeds are interpolated onto one grid at the IMU's median step over the span they share;
each lag within ``±max_offset`` gets Pearson's correlation over the pairs that have both speeds
(``scipy.signal.correlate`` of the signals, their squares and their masks; grid points in a gap
of either record take no part); the peak's position is refined by the parabola through it and
its two neighbours. A motion whose correlation stays within the peak's own mismatch ``1 − r`` out
to the window's edge does not fix the offset and is refused rather than answered.

Convention, as :func:`imukit.eval.associate`'s ``offset``: IMU time ``t`` is reference time
``t + offset``. An IMU whose samples lag the reference by 4 ms gives ``offset = −0.004``.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from imukit._arrays import FloatArray
from imukit._errors import ParameterError
from imukit.eval._checks import check_trajectory, finite_float
from imukit.imu import ImuData
from imukit.io._gaps import reference_max_dt
from imukit.state import Trajectory


class TimeOffset(NamedTuple):
    """The result of :func:`time_offset`."""

    offset: float  # [s]: IMU time t is reference time t + offset
    correlation: float  # Pearson's correlation of the two angular speeds at the peak (≤ 1)
    step: float  # [s]: the grid step, the IMU's median sample interval
    n_samples: int  # grid samples the correlation used


def time_offset(imu: ImuData | Trajectory, reference: Trajectory, *, max_offset: float = 0.5) -> TimeOffset:
    """The clock offset between ``imu`` and ``reference`` from their angular speeds (module doc).

    Parameters
    ----------
    imu
        The IMU record (only its stamps and gyro are used, rad/s; a constant bias only lowers the
        correlation a little), or an estimated trajectory, whose speeds are taken from its
        rotations as the reference's are.
    reference
        A trajectory whose rotations (``R_wb`` or any fixed frame change of it) are sampled over an
        overlapping span, e.g. motion capture.
    max_offset
        Largest offset searched [s], either sign.

    Returns
    -------
    TimeOffset
        ``offset`` [s] (``imu``'s time ``t`` is reference time ``t + offset``, as ``associate``'s
        ``offset``), Pearson's correlation of the two speeds at the peak, the grid step and the
        number of grid samples with both speeds. Its resolution is a small fraction of the step
        when the motion changes speed within ``max_offset``; a record that turns at a constant speed
        has no offset to find.

    Raises :class:`imukit.ParameterError` naming the argument: no overlap of the two spans, no
    change of angular speed (nothing to correlate), a correlation that stays within the peak's own
    mismatch ``1 − r`` of it out to the window's edge (``imu``: the motion does not fix the offset),
    a ``max_offset`` that is not a positive number or not well below the shared span, or a
    correlation whose peak lies on the edge of the searched window (the offset may be larger: widen
    ``max_offset``).
    """
    if not isinstance(imu, (ImuData, Trajectory)):
        raise ParameterError(f"expected an imukit ImuData or Trajectory, got {type(imu).__name__}", argument="imu")
    reference = check_trajectory(reference, "reference")
    max_offset = finite_float(max_offset, "max_offset", positive=True)
    for name, x in (("imu", imu), ("reference", reference)):
        if len(x) < 3:
            raise ParameterError(f"expected at least 3 samples, got {len(x)}", argument=name)
    from scipy import signal  # not at import: scipy.signal loads scipy.stats and more (test_import.py)

    if isinstance(imu, ImuData):
        t_imu, g = np.asarray(imu.t, dtype=float), imu.gyro
        # hypot: a finite 1e300 rad/s keeps a finite speed (its square would not).
        speed_imu, in_imu = np.hypot(np.hypot(g[:, 0], g[:, 1]), g[:, 2]), np.ones(len(t_imu), dtype=bool)
    else:
        t_imu, speed_imu, in_imu = _speeds(imu, "imu")
    t_ref, speed_ref, in_ref = _speeds(reference, "reference")
    step = float(np.median(np.diff(np.asarray(imu.t, dtype=float))))
    start, end = max(t_imu[0], t_ref[0]), min(t_imu[-1], t_ref[-1])
    if not end > start:
        raise ParameterError(
            f"covers {reference.t[0]:g}–{reference.t[-1]:g} s, imu {imu.t[0]:g}–{imu.t[-1]:g} s: no shared span",
            argument="reference",
        )
    grid = np.arange(start, end, step)
    lags = int(np.ceil(max_offset / step))
    if lags + 2 >= len(grid):
        raise ParameterError(
            f"expected well below the shared span of {end - start:g} s, got {max_offset:g} s", argument="max_offset"
        )
    # Grid points within a gap carry no speed. Each lag's correlation is Pearson's over the pairs
    # (a[n], b[n + lag]) that have both speeds (masked normalised cross-correlation): zeroing the
    # gaps with one normalisation pulled the peak towards 0, where the gaps of both signals line up
    # (BROAD trial 06, 32 short dropouts in fast rotation: −4.19 → −3.42 ms).
    a, ma = _on_grid(grid, t_imu, speed_imu, in_imu)
    b, mb = _on_grid(grid, t_ref, speed_ref, in_ref)
    for name, values, m in (("imu", a, ma), ("reference", b, mb)):
        if not (m.any() and np.ptp(values[m > 0.0]) > 0.0):
            raise ParameterError(
                "expected a change of angular speed over the shared span: nothing to correlate", argument=name
            )
    # Pearson's correlation does not depend on the scale; at most 1 in size, no product overflows.
    a, b = a * ma / np.max(np.abs(a)), b * mb / np.max(np.abs(b))

    def corr(x: FloatArray, y: FloatArray) -> FloatArray:
        return np.asarray(signal.correlate(x, y, mode="full", method="fft"), dtype=float)

    lag = signal.correlation_lags(len(b), len(a), mode="full")
    window = np.abs(lag) <= lags
    count, sum_a, sum_b = corr(mb, ma)[window], corr(mb, a)[window], corr(b, ma)[window]
    count = np.maximum(count, 1.0)
    ab = corr(b, a)[window] - sum_a * sum_b / count
    aa = corr(mb, a * a)[window] - sum_a**2 / count
    bb = corr(b * b, ma)[window] - sum_b**2 / count
    c = ab / np.sqrt(np.maximum(aa * bb, np.finfo(float).tiny))
    lag = lag[window]
    i = int(np.argmax(c))
    if i == 0 or i == len(c) - 1:
        raise ParameterError(
            f"the angular speeds correlate best at the window's edge ({lag[i] * step:g} s): the offset may "
            f"be larger than {max_offset:g} s",
            argument="max_offset",
        )
    # Lags whose correlation is within the peak's own mismatch (1 − r) of it are not told apart:
    # when they reach the window's edge, the motion does not fix the offset (a slow, smooth change
    # of speed correlates as well at any lag; a 3 s figure eight's did, off by 38 ms).
    close = c >= c[i] - max(1.0 - c[i], 1e-12)
    if close[: i + 1].all() or close[i:].all():
        raise ParameterError(
            f"the angular speeds correlate within their own mismatch (1 − r = {1.0 - c[i]:.2g}) out to the "
            f"window's edge (±{max_offset:g} s): the motion does not fix the offset (a longer record, or one "
            "whose rotation rate changes more within the window, does)",
            argument="imu",
        )
    y0, y1, y2 = c[i - 1], c[i], c[i + 1]
    curvature = y0 - 2.0 * y1 + y2
    frac = 0.5 * (y0 - y2) / curvature if curvature < 0.0 else 0.0
    return TimeOffset(float((lag[i] + frac) * step), float(y1), step, int((ma * mb).sum()))


def _speeds(x: Trajectory, name: str) -> tuple[FloatArray, FloatArray, NDArray[np.bool_]]:
    """A trajectory's angular speed ``‖Log(R_jᵀ R_j+1)‖ / Δt`` at each interval's midpoint, and
    whether the interval is no gap (not longer than :func:`imukit.io.reference_max_dt`, the step
    ``associate`` interpolates across); ``name`` the argument."""
    t = np.asarray(x.t, dtype=float)
    dt = np.diff(t)
    with np.errstate(over="ignore"):
        speed = (x.rotation[:-1].inv() * x.rotation[1:]).magnitude() / dt
    if not np.isfinite(speed).all():
        k = int(np.argmax(~np.isfinite(speed)))
        raise ParameterError(
            f"a turn over a step of {dt[k]:g} s at row {k} gives no finite angular speed", argument=name, index=k
        )
    return t[:-1] + 0.5 * dt, speed, dt <= reference_max_dt(x)


def _on_grid(
    grid: FloatArray, t: FloatArray, speed: FloatArray, valid: NDArray[np.bool_]
) -> tuple[FloatArray, FloatArray]:
    """``speed`` interpolated at ``grid``, its mean removed, and 1 where both samples it is
    interpolated between are valid (else 0, the value set to 0 too)."""
    x = np.interp(grid, t, speed)
    upper = np.clip(np.searchsorted(t, grid), 1, len(t) - 1)
    m = (valid[upper - 1] & valid[upper]).astype(float)
    if m.any():
        x = x - x[m > 0.0].mean()
    return np.where(m > 0.0, x, 0.0), m
