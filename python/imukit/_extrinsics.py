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
lever arm              preintegration takes the rotation only for now: a non-zero lever arm is
                       refused (``integrate`` handles both, ``crates/imukit/src/extrinsics.rs``)
=====================  ===========================================================================
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from imukit._arrays import vector3
from imukit._errors import ParameterError

__all__ = ["Pose", "check_preint_pose", "in_body", "sensor_pose"]

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


def check_preint_pose(pose: Pose | None) -> None:
    """Refuses what preintegration does not do yet: a lever arm."""
    if pose is not None and any(v != 0.0 for v in pose[1]):
        raise ParameterError(
            "a lever arm is not supported by preintegration yet (the rotation is); integrate() takes both",
            argument="body_from_sensor",
        )
