"""The clock offset between an IMU and a reference trajectory, from their angular speeds:
:func:`time_offset`.

Both sensors see the same rotation, so the IMU's angular speed ``‖ω(t)‖`` and the reference's,
``‖Log(R_jᵀ R_j+1)‖ / (t_j+1 − t_j)`` at the interval's midpoint, are the same signal on two clocks.
The magnitude does not depend on the frames, so neither the IMU-to-body rotation nor the
reference's world needs to be known (the approach of hand-eye and camera–IMU calibration tools
that start from rates: Furgale, Rehder & Siegwart, IROS 2013, estimate the offset in the full
model; the correlation of rate magnitudes is its usual initial guess). Both speeds are
interpolated onto one grid at the IMU's median step over the span they share, their means
removed, and cross-correlated (``scipy.signal.correlate``) over lags within ``±max_offset``; the
peak's position is refined by the parabola through it and its two neighbours.

Convention, as :func:`imukit.eval.associate`'s ``offset``: IMU time ``t`` is reference time
``t + offset``. An IMU whose samples lag the reference by 4 ms gives ``offset = −0.004``.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from scipy import signal

from imukit._arrays import FloatArray
from imukit._errors import ParameterError
from imukit.eval._checks import check_trajectory, finite_float
from imukit.imu import ImuData
from imukit.state import Trajectory

# A reference interval longer than this many median steps is a gap: no speed is taken across it.
_GAP_STEPS = 3.0


class TimeOffset(NamedTuple):
    """The result of :func:`time_offset`."""

    offset: float  # [s]: IMU time t is reference time t + offset
    correlation: float  # normalised cross-correlation of the two angular speeds at the peak (≤ 1)
    step: float  # [s]: the grid step, the IMU's median sample interval
    n_samples: int  # grid samples the correlation used


def time_offset(imu: ImuData, reference: Trajectory, *, max_offset: float = 0.5) -> TimeOffset:
    """The clock offset between ``imu`` and ``reference`` from their angular speeds (module doc).

    Parameters
    ----------
    imu
        The IMU record; only its stamps and gyro are used (rad/s; a constant bias only lowers the
        correlation a little).
    reference
        A trajectory whose rotations (``R_wb`` or any fixed frame change of it) are sampled over an
        overlapping span, e.g. motion capture.
    max_offset
        Largest offset searched [s], either sign.

    Returns
    -------
    TimeOffset
        ``offset`` [s] (IMU time ``t`` is reference time ``t + offset``, as ``associate``'s
        ``offset``), the correlation at the peak, the grid step and the number of grid samples.
        Its resolution is a small fraction of the step when the motion changes speed within
        ``max_offset``; a record that turns at a constant speed has no offset to find.

    Raises :class:`imukit.ParameterError` naming the argument: no overlap of the two spans, no
    change of angular speed (nothing to correlate), a ``max_offset`` that is not a positive number
    or reaches beyond the shared span, or a correlation whose peak lies on the edge of the searched
    window (the offset may be larger: widen ``max_offset``).
    """
    if not isinstance(imu, ImuData):
        raise ParameterError(f"expected an imukit ImuData, got {type(imu).__name__}", argument="imu")
    reference = check_trajectory(reference, "reference")
    max_offset = finite_float(max_offset, "max_offset", positive=True)
    if len(imu) < 3:
        raise ParameterError(f"expected at least 3 samples, got {len(imu)}", argument="imu")
    if len(reference) < 3:
        raise ParameterError(f"expected at least 3 samples, got {len(reference)}", argument="reference")

    t_ref = np.asarray(reference.t, dtype=float)
    dt_ref = np.diff(t_ref)
    speed_ref = (reference.rotation[:-1].inv() * reference.rotation[1:]).magnitude() / dt_ref
    mid = t_ref[:-1] + 0.5 * dt_ref
    in_span = dt_ref <= _GAP_STEPS * np.median(dt_ref)
    t_imu = np.asarray(imu.t, dtype=float)
    step = float(np.median(np.diff(t_imu)))
    start, end = max(t_imu[0], mid[0]), min(t_imu[-1], mid[-1])
    if not end > start:
        raise ParameterError(
            f"covers {t_ref[0]:g}–{t_ref[-1]:g} s, the IMU {t_imu[0]:g}–{t_imu[-1]:g} s: no shared span",
            argument="reference",
        )
    grid = np.arange(start, end, step)
    lags = int(np.ceil(max_offset / step))
    if lags + 2 >= len(grid):
        raise ParameterError(
            f"expected well below the shared span of {end - start:g} s, got {max_offset:g} s", argument="max_offset"
        )
    a = np.interp(grid, t_imu, np.linalg.norm(imu.gyro, axis=1))
    b = np.interp(grid, mid, speed_ref)
    # Grid points inside a reference gap carry no reference speed. Each lag's correlation is
    # Pearson's over the points it pairs with reference speeds (masked normalised
    # cross-correlation): zeroing the gaps alone would pull the peak towards 0, where the gaps of
    # both signals line up (BROAD trial 06, 32 short gaps in fast rotation: −4.1 → −3.4 ms).
    # A point has one when both speeds it is interpolated between are of intervals without a gap.
    upper = np.clip(np.searchsorted(mid, grid), 1, len(mid) - 1)
    covered = (in_span[upper - 1] & in_span[upper]).astype(float)
    if not covered.any():
        raise ParameterError("has no interval without a gap over the IMU's span", argument="reference")
    a = a - a.mean()
    b = np.where(covered > 0.0, b - b[covered > 0.0].mean(), 0.0)
    if not (np.dot(a, a) > 0.0 and np.dot(b, b) > 0.0):
        which = "imu" if not np.dot(a, a) > 0.0 else "reference"
        raise ParameterError(
            "expected a change of angular speed over the shared span: nothing to correlate", argument=which
        )

    def corr(x: FloatArray, y: FloatArray) -> FloatArray:
        return np.asarray(signal.correlate(x, y, mode="full", method="fft"), dtype=float)

    lag = signal.correlation_lags(len(b), len(a), mode="full")
    window = np.abs(lag) <= lags
    # Pearson's correlation over the pairs (a[n], b[n + lag]) that have a reference speed, per lag.
    ones = np.ones_like(a)
    count, sum_a, sum_b = corr(covered, ones)[window], corr(covered, a)[window], corr(b, ones)[window]
    ab = corr(b, a)[window] - sum_a * sum_b / count
    aa = corr(covered, a * a)[window] - sum_a**2 / count
    bb = corr(b * b, ones)[window] - sum_b**2 / count
    c = ab / np.sqrt(np.maximum(aa * bb, np.finfo(float).tiny))
    lag = lag[window]
    i = int(np.argmax(c))
    if i == 0 or i == len(c) - 1:
        raise ParameterError(
            f"the angular speeds correlate best at the window's edge ({lag[i] * step:g} s): the offset may "
            f"be larger than {max_offset:g} s",
            argument="max_offset",
        )
    y0, y1, y2 = c[i - 1], c[i], c[i + 1]
    curvature = y0 - 2.0 * y1 + y2
    frac = 0.5 * (y0 - y2) / curvature if curvature < 0.0 else 0.0
    return TimeOffset(float((lag[i] + frac) * step), float(y1), step, int(covered.sum()))
