"""A sensor's pose in the body frame (``body_from_sensor``): parsing the ``(Rotation, lever arm)``
pair, and preintegrated windows of the sensor written in the body frame.

=====================  ===========================================================================
pair                   ``(R_bs, r)``: a single scipy ``Rotation`` (sensor axes to body axes) and
                       the sensor's origin in body coordinates (3,) [m] (GTSAM's ``body_P_sensor``)
in the body frame      with ``ω_b = R_bs ω_s``, ``a_b = R_bs a_s`` (biases stay the sensor's):
                       ``ΔR_b = R_bs ΔR_s R_bsᵀ``, ``Δv_b = R_bs Δv_s``, ``Δp_b = R_bs Δp_s``; the
                       right perturbation turns with them, ``R ΔR_s Exp(δ) Rᵀ = ΔR_b Exp(R δ)``,
                       so ``Σ_b = T Σ_s Tᵀ`` and ``J_b = T J_s`` with ``T = blockdiag(R, R, R)``
                       (bias columns: the sensor's biases). Exact, window by window, so merging
                       stays exact
lever arm              the readings are turned into the body origin's before the step (the core's
                       ``body_readings``, ``crates/imukit/src/extrinsics.rs``: ``a_b = R(a_s − b_a)
                       − α×r − ω×(ω×r)``, α the gyro's central difference over the whole batch, so
                       windows cut from one batch see their neighbours) and preintegrated with
                       zero bias. The bias Jacobian is the body one mapped to the sensor's biases,
                       ``J_g = J_g^B R + L``, ``J_a = J_a^B R``, plus the centripetal term ``L``:
                       ``∂a_b,k/∂b_g = D(ω_k) R`` with ``D(ω) = ∂(ω×(ω×r))/∂ω = −[ω×r]× − [ω]×[r]×``
                       (α is a difference of rates: a constant bias cancels), and since Δv, Δp are
                       linear in the accelerometer readings for a fixed gyro sequence, ``L`` is the
                       (v, p) deltas of three preintegrations of the readings ``D(ω_k) R e_m``
                       (exact for the discrete scheme; they merge as deltas do, so merging stays
                       exact). Covariance: complete, from the core's ``LeverNoise``
                       (``crates/imukit/src/preint/lever.rs``): the direct noise and the gyro noise
                       that the conversion puts into the corrected accelerometer (centripetal
                       ``D(ω) R n_g``, tangential ``[r]× R Δn_g / Δt``), exact for correlated
                       noise, merging exactly; ``combined`` too. Window edges must be samples
=====================  ===========================================================================
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np
from scipy.spatial.transform import Rotation

from imukit import _core
from imukit._arrays import FloatArray, vector3
from imukit._errors import ParameterError

__all__ = [
    "Pose",
    "Readings",
    "has_lever_arm",
    "in_body",
    "lever_columns",
    "lever_jacobian",
    "lever_noise",
    "origin_readings",
    "sensor_pose",
]

Pose = tuple[tuple[tuple[float, ...], ...], tuple[float, float, float]]


def sensor_pose(body_from_sensor: object) -> Pose:
    """``(R_bs rows, lever arm)`` of a ``(Rotation, (3,))`` pair, as plain tuples (values compare
    and pickle); the core checks the values where it uses them."""
    if not (isinstance(body_from_sensor, tuple) and len(body_from_sensor) == 2):
        raise ParameterError(
            f"expected a pair (scipy Rotation, lever arm (3,)), got {body_from_sensor!r}", argument="body_from_sensor"
        )
    rotation, arm = body_from_sensor
    if not (isinstance(rotation, Rotation) and rotation.single):
        raise ParameterError(f"expected a single scipy Rotation, got {rotation!r}", argument="body_from_sensor")
    rows = tuple(tuple(float(v) for v in row) for row in rotation.as_matrix())
    lever = vector3(arm, "body_from_sensor")
    return rows, (float(lever[0]), float(lever[1]), float(lever[2]))


def in_body(arrays: tuple[Any, ...], pose: Pose) -> tuple[Any, ...]:
    """``(ΔR, Δv, Δp, Δt, covariance, bias Jacobian, combined or None)`` (leading M) of the sensor,
    written in the body frame (module docs)."""
    r = np.array(pose[0])
    dr, dv, dp, dt, cov, jac, combined = arrays
    t = np.kron(np.eye(3), r)
    t15 = np.eye(15)
    t15[:9, :9] = t
    return (
        r @ dr @ r.T,
        dv @ r.T,
        dp @ r.T,
        dt,
        t @ cov @ t.T,
        t @ jac,
        None if combined is None else t15 @ combined @ t15.T,
    )


def lever_noise(body: Readings, params: Any, edges: FloatArray, threads: int | None) -> list[_core.LeverNoise]:
    """The core's complete covariance state of each window between ``edges`` (sample stamps of
    ``body.seconds``) of the body readings ``body``, with ``params`` (a ``PreintParams`` with a
    lever arm)."""
    pose = params.body_from_sensor
    rows = [list(r) for r in pose[0]]
    return _core.lever_noise(body, rows, list(pose[1]), np.ascontiguousarray(edges), params._integrated(), threads)


def has_lever_arm(pose: Pose | None) -> bool:
    """Whether ``pose`` has a non-zero lever arm (the readings are then converted before the step)."""
    return pose is not None and any(v != 0.0 for v in pose[1])


class Readings(NamedTuple):
    """Samples as the core and the engines read them (by attribute): the converted readings with
    the sensor's stamps and saturation flags."""

    seconds: FloatArray
    gyro: FloatArray
    accel: FloatArray
    gyro_saturated: Any
    accel_saturated: Any


def origin_readings(imu: Any, bias: Any, pose: Pose) -> Readings:
    """The body origin's readings of ``imu`` (an ``ImuData``), ``bias`` removed (the core's
    ``body_readings``)."""
    gyro, accel = _core.body_readings(imu.seconds, imu.gyro, imu.accel, bias, [list(r) for r in pose[0]], list(pose[1]))
    return Readings(imu.seconds, gyro, accel, imu.gyro_saturated, imu.accel_saturated)


def lever_columns(body: Readings, pose: Pose) -> list[Readings]:
    """The three accelerometer sequences ``D(ω_k) R e_m`` (m = 0, 1, 2) on the body rates, whose
    (v, p) deltas are the centripetal term ``L`` of the gyro-bias Jacobian (module docs)."""
    r, arm = np.array(pose[0]), np.array(pose[1])
    w = np.asarray(body.gyro)
    # D(ω) = −[ω×r]× − [ω]×[r]×, from δ(ω×(ω×r)) = δω×(ω×r) + ω×(δω×r).
    d = -_hat(np.cross(w, arm)) - _hat(w) @ _hat(arm)
    x = d @ r
    return [body._replace(accel=np.ascontiguousarray(x[:, :, m])) for m in range(3)]


def lever_jacobian(jac: FloatArray, rotation: FloatArray, dv: FloatArray, dp: FloatArray) -> FloatArray:
    """The sensor-bias Jacobian (M, 9, 6) from the body readings' ``jac`` (M, 9, 6) and the (v, p)
    deltas (M, 3, 3) (columns m) of :func:`lever_columns`: ``[J_g^B R + L, J_a^B R]``."""
    out = np.array(jac)
    out[:, :, 0:3] = jac[:, :, 0:3] @ rotation
    out[:, :, 3:6] = jac[:, :, 3:6] @ rotation
    out[:, 3:6, 0:3] += dv
    out[:, 6:9, 0:3] += dp
    return out


def _hat(v: FloatArray) -> FloatArray:
    """``[v]×`` of (..., 3) rows, (..., 3, 3)."""
    out = np.zeros((*v.shape[:-1], 3, 3))
    out[..., 0, 1], out[..., 0, 2], out[..., 1, 2] = -v[..., 2], v[..., 1], -v[..., 0]
    out[..., 1, 0], out[..., 2, 0], out[..., 2, 1] = v[..., 2], -v[..., 1], v[..., 0]
    return out
