"""Analytic attitude trajectories for the integrator tests: R(t) and its body rate in closed form.

The trajectory is R(t) = Rz(ψ(t)) Ry(θ(t)) Rx(φ(t)) with smooth angles, and the body rate is
ω_b = E⁻¹(χ) χ̇ with E⁻¹ written out here (not taken from imukit), so the integrators are checked
against an independent truth whose rotation axes keep changing (coning).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation


def angles(t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """χ(t) = [ψ, θ, φ] and χ̇(t), each (N, 3)."""
    psi = 0.3 * np.sin(1.1 * t) + 0.2 * t
    theta = 0.4 * np.sin(0.7 * t + 0.3)
    phi = 0.5 * np.cos(1.3 * t)
    dpsi = 0.33 * np.cos(1.1 * t) + 0.2
    dtheta = 0.28 * np.cos(0.7 * t + 0.3)
    dphi = -0.65 * np.sin(1.3 * t)
    return np.stack([psi, theta, phi], axis=-1), np.stack([dpsi, dtheta, dphi], axis=-1)


def attitude(t: np.ndarray) -> Rotation:
    """R_wb(t) as a scipy Rotation (intrinsic ZYX)."""
    return Rotation.from_euler("ZYX", angles(t)[0])


def body_rate(t: np.ndarray) -> np.ndarray:
    """ω_b(t) = E⁻¹(χ) χ̇ (rad/s), the exact body rate of :func:`attitude`."""
    chi, dchi = angles(t)
    _, theta, phi = chi.T
    dpsi, dtheta, dphi = dchi.T
    return np.stack(
        [
            dphi - np.sin(theta) * dpsi,
            np.cos(phi) * dtheta + np.sin(phi) * np.cos(theta) * dpsi,
            -np.sin(phi) * dtheta + np.cos(phi) * np.cos(theta) * dpsi,
        ],
        axis=-1,
    )


CONE_HALF_ANGLE = 0.3  # rad
CONE_RATE = 3.0  # rad/s


def coning_attitude(t: np.ndarray) -> Rotation:
    """Classic coning: R(t) = Exp(β [cos Ωt, sin Ωt, 0]), a rotation vector whose axis circles."""
    b, w = CONE_HALF_ANGLE, CONE_RATE
    return Rotation.from_rotvec(b * np.stack([np.cos(w * t), np.sin(w * t), np.zeros_like(t)], axis=-1))


def coning_body_rate(t: np.ndarray) -> np.ndarray:
    """ω = J_r(φ) φ̇ with the textbook right Jacobian (Chirikjian 2011), written out independently."""
    b, w = CONE_HALF_ANGLE, CONE_RATE
    phi = b * np.stack([np.cos(w * t), np.sin(w * t), np.zeros_like(t)], axis=-1)
    dphi = b * w * np.stack([-np.sin(w * t), np.cos(w * t), np.zeros_like(t)], axis=-1)
    cross = np.cross(phi, dphi)
    cross2 = np.cross(phi, cross)
    return dphi - (1 - np.cos(b)) / b**2 * cross + (b - np.sin(b)) / b**3 * cross2


GRAVITY = np.array([0.0, 0.0, -9.81])


def position(t: np.ndarray) -> np.ndarray:
    """p(t) [m] of the strapdown test trajectory (with :func:`attitude` as its attitude)."""
    return np.stack([2.0 * np.sin(0.7 * t), 1.5 * np.cos(0.5 * t), 0.3 * np.sin(1.1 * t)], axis=-1)


def velocity(t: np.ndarray) -> np.ndarray:
    return np.stack([1.4 * np.cos(0.7 * t), -0.75 * np.sin(0.5 * t), 0.33 * np.cos(1.1 * t)], axis=-1)


def acceleration(t: np.ndarray) -> np.ndarray:
    return np.stack([-0.98 * np.sin(0.7 * t), -0.375 * np.cos(0.5 * t), -0.363 * np.sin(1.1 * t)], axis=-1)


def specific_force(t: np.ndarray) -> np.ndarray:
    """What an ideal accelerometer reads: Rᵀ (a − g), body frame [m/s²]."""
    return attitude(t).inv().apply(acceleration(t) - GRAVITY)
