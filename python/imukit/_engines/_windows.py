"""The windows an engine preintegrates, and the record it returns them in."""

from __future__ import annotations

from typing import Any, NamedTuple, Protocol

import numpy as np
from numpy.typing import NDArray

from imukit._arrays import FloatArray
from imukit._extrinsics import in_body, lever_columns, lever_jacobian, lever_noise, origin_readings
from imukit._preint_record import Preintegration, PreintParams


class Windows(NamedTuple):
    """Window edges (M + 1,): ``offsets`` on ``imu.seconds``' axis (what the engines integrate
    over), ``t`` float seconds on ``imu.t``'s clock and ``t_ns`` exact int64 ns (or None), which
    the record carries as ``t_start``/``t_end``."""

    offsets: FloatArray
    t: FloatArray
    t_ns: NDArray[np.int64] | None


def record(arrays: tuple[Any, ...], windows: Windows, params: PreintParams) -> Preintegration:
    """The record of ``arrays`` ``(ΔR, Δv, Δp, Δt, covariance, bias Jacobian, combined or None)``."""
    ns = windows.t_ns
    if params.body_from_sensor is not None:
        arrays = in_body(arrays, params.body_from_sensor)
    r, v, p, dt, cov, jac, combined = arrays
    t = np.array(windows.t, dtype=np.float64)  # a copy: the edges may be the caller's array
    return Preintegration._owning(
        delta_rotation=r,
        delta_velocity=v,
        delta_position=p,
        delta_t=dt,
        covariance=cov,
        bias_jacobian=jac,
        covariance_combined=combined,
        t_start=t[:-1],
        t_end=t[1:],
        params=params,
        t_start_ns=None if ns is None else np.array(ns[:-1]),
        t_end_ns=None if ns is None else np.array(ns[1:]),
    )


class _Run(Protocol):
    def __call__(self, imu: Any, windows: Windows, params: PreintParams, threads: int | None) -> Preintegration: ...


def lever_windows(run: _Run, imu: Any, windows: Windows, params: PreintParams, threads: int | None) -> Preintegration:
    """``run`` (an engine) over the body origin's readings of ``imu`` (a sensor with a lever arm),
    bias Jacobian mapped to the sensor's biases with its centripetal term, covariance the core's
    complete one (:mod:`imukit._extrinsics`; window edges must be samples).
    The readings are converted once over all of ``imu``: a window edge's angular acceleration uses
    the samples on both sides of it, so the windows are those of one pass."""
    pose = params.body_from_sensor
    inner = params._integrated()
    body = origin_readings(imu, params.bias, pose)
    out = run(body, windows, inner, threads)
    cols = [run(c, windows, inner, threads) for c in lever_columns(body, pose)]
    dv = np.stack([c.delta_velocity for c in cols], axis=-1)
    dp = np.stack([c.delta_position for c in cols], axis=-1)
    jac = lever_jacobian(out.bias_jacobian, np.array(pose[0]), dv, dp)
    states = [n.state() for n in lever_noise(body, params, windows.offsets, threads)]
    combined = np.array([s[2] for s in states]) if params.combined else None
    replaced = ("bias_jacobian", "params", "covariance", "covariance_combined")
    return Preintegration._owning(
        **{f: getattr(out, f) for f in out.__dataclass_fields__ if f not in replaced},
        covariance=np.array([s[0] for s in states]).reshape(-1, 9, 9),
        covariance_combined=combined,
        bias_jacobian=jac,
        params=params,
    )
