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
its two neighbours. When one record is at least twice as coarse as the other, the peak is found
again within a grid step comparing like with like (:func:`_refined`). A motion whose correlation
stays within the peak's own mismatch ``1 − r`` out to the window's edge does not fix the offset and
is refused rather than answered.

Convention, as :func:`imukit.eval.associate`'s ``offset``: IMU time ``t`` is reference time
``t + offset``. An IMU whose samples lag the reference by 4 ms gives ``offset = −0.004``.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from imukit import quat
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
    n_samples: int  # grid points, or the coarse record's intervals (module doc), the correlation used


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
    coarse = TimeOffset(float((lag[i] + frac) * step), float(y1), step, int((ma * mb).sum()))
    return _refined(imu, reference, coarse)


def _refined(imu: ImuData | Trajectory, reference: Trajectory, coarse: TimeOffset) -> TimeOffset:
    """The peak found again within a grid step of ``coarse`` when one record is at least twice as
    coarse as the other, comparing like with like: the coarse record's turn over each of its
    intervals against the fine one's over the same interval shifted by the offset, both as
    ``‖Log(R_aᵀ R_b)‖ / Δt``.

    The grid compares an interval's mean speed with the other record's instant one, the same signal
    only while the speed is linear over the interval: a 20 Hz reference of a MAV's flight put the
    peak up to ±0.8 ms off by where its stamps fell (10 Hz: ±1.6 ms). Between records of about one
    rate the grid is right (200 Hz against 200 Hz: 0), and a fine record interpolated within its
    own samples would not be.
    """
    mine = _Turns.of_imu(imu) if isinstance(imu, ImuData) else _Turns.of_trajectory(imu)
    theirs = _Turns.of_trajectory(reference)
    # IMU time t is reference time t + offset: a reference interval is the IMU's shifted by −offset.
    if mine.step >= 2.0 * theirs.step:
        c, f, sign = mine, theirs, -1.0
    elif theirs.step >= 2.0 * mine.step:
        c, f, sign = theirs, mine, 1.0
    else:
        return coarse
    dt = np.diff(c.t)
    speed_c = _angles(c.q[:-1], c.q[1:]) / dt
    bracket = (coarse.offset - coarse.step, coarse.offset + coarse.step)
    # One set of intervals for the whole bracket (the correlation stays continuous in the offset):
    # both ends inside the fine record at every offset searched, and no gap of either record.
    reach = (min(sign * x for x in bracket), max(sign * x for x in bracket))
    first, last = c.t[:-1] - reach[1], c.t[1:] - reach[0]
    gaps = np.concatenate([[0], np.cumsum(~f.ok)])
    keep = c.ok & (first >= f.t[0]) & (last <= f.t[-1])
    keep &= gaps[f.interval(last) + 1] == gaps[f.interval(first)]
    if keep.sum() < 3 or np.ptp(speed_c[keep]) == 0.0:
        return coarse
    a, b, dt, speed_c = c.t[:-1][keep], c.t[1:][keep], dt[keep], speed_c[keep]

    def mismatch(offset: float) -> float:
        """Minus Pearson's correlation of the two records' turns at ``offset``."""
        speed_f = _angles(f.at(a - sign * offset), f.at(b - sign * offset)) / dt
        return -float(np.corrcoef(speed_c, speed_f)[0, 1]) if np.ptp(speed_f) > 0.0 else 1.0

    from scipy.optimize import minimize_scalar  # not at import, as scipy.signal above

    best = minimize_scalar(mismatch, bounds=bracket, method="bounded", options={"xatol": 1e-4 * coarse.step})
    return TimeOffset(float(best.x), -float(best.fun), coarse.step, int(keep.sum()))


class _Turns(NamedTuple):
    """A record's rotations at its stamps (``xyzw`` quaternions), which intervals are no gap, and
    within an interval ``q(t_k + s h) = q_k ⊗ Exp(s φ_k + s² ψ_k)``: a trajectory's slerp (ψ = 0);
    an IMU's gyro, linear over the interval, integrated (``φ = h ω_k``, ``ψ = h (ω_k+1 − ω_k) / 2``:
    the rk2 step at ``s = 1``). Quaternion arrays and :mod:`imukit.quat`: scipy's ``Rotation``
    products took 140 ns an element, 5 of the 7 s of an hour at 100 Hz against 400 Hz."""

    t: FloatArray
    q: FloatArray
    ok: NDArray[np.bool_]
    phi: FloatArray
    psi: FloatArray | None

    @property
    def step(self) -> float:
        return float(np.median(np.diff(self.t)))

    @staticmethod
    def of_trajectory(x: Trajectory) -> _Turns:
        t, q = np.asarray(x.t, dtype=float), x.rotation.as_quat()
        phi = quat.log(quat.multiply(quat.conjugate(q[:-1]), q[1:]))
        return _Turns(t, q, np.diff(t) <= reference_max_dt(x), phi, None)

    @staticmethod
    def of_imu(imu: ImuData) -> _Turns:
        from imukit.attitude import integrate_attitude

        t, w = np.asarray(imu.t, dtype=float), np.asarray(imu.gyro, dtype=float)
        h = np.diff(t)[:, None]
        q = integrate_attitude(t, w, scheme="rk2").as_quat()
        return _Turns(t, q, np.ones(len(t) - 1, dtype=bool), h * w[:-1], 0.5 * h * np.diff(w, axis=0))

    def interval(self, x: FloatArray) -> NDArray[np.intp]:
        """The interval holding each ``x`` (its start's index), the last one at the record's end."""
        return np.clip(np.searchsorted(self.t, x, "right") - 1, 0, len(self.t) - 2)

    def at(self, x: FloatArray) -> FloatArray:
        k = self.interval(x)
        s = ((x - self.t[k]) / (self.t[k + 1] - self.t[k]))[:, None]
        turn = s * self.phi[k] if self.psi is None else s * self.phi[k] + s * s * self.psi[k]
        return quat.multiply(self.q[k], quat.exp(turn))


def _angles(a: FloatArray, b: FloatArray) -> FloatArray:
    """The angle [rad] of the turn ``a⁻¹ ⊗ b`` between unit quaternion rows (``xyzw``)."""
    d = quat.multiply(quat.conjugate(a), b)
    return np.asarray(2.0 * np.arctan2(np.linalg.norm(d[:, :3], axis=1), np.abs(d[:, 3])), dtype=float)


def _speeds(x: Trajectory, name: str) -> tuple[FloatArray, FloatArray, NDArray[np.bool_]]:
    """A trajectory's angular speed ``‖Log(R_jᵀ R_j+1)‖ / Δt`` at each interval's midpoint, and
    whether the interval is no gap (not longer than :func:`imukit.io.reference_max_dt`, the step
    ``associate`` interpolates across); ``name`` the argument."""
    t = np.asarray(x.t, dtype=float)
    dt = np.diff(t)
    with np.errstate(over="ignore"):
        q = x.rotation.as_quat()
        speed = _angles(q[:-1], q[1:]) / dt
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
