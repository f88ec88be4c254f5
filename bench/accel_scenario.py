"""Analytic motion for the attitude filters' sustained-acceleration check, shared by the tuner
(``tune_filters.py``: a default must hold it) and ``tests/test_filters_motion.py``. The gyro is the
exact body-rate increment between samples (``log(R_{k−1}ᵀ R_k)/dt``), so every tilt error left is
the accelerometer's."""

from __future__ import annotations

import functools

import numpy as np
from scipy.spatial.transform import Rotation

import imukit as ik

G = 9.81
RATE = 100.0


def imu_from(t: np.ndarray, rot: Rotation, accel_world: np.ndarray) -> ik.ImuData:
    """The IMU of a body at ``rot`` (``R_wb``, ENU) accelerating by ``accel_world`` [m/s²]."""
    gyro = np.zeros((len(t), 3))
    gyro[1:] = (rot[:-1].inv() * rot[1:]).as_rotvec() * RATE
    return ik.ImuData(t, gyro, rot.inv().apply(accel_world + np.array([0.0, 0.0, G])))


def tilt_deg(est: Rotation, truth: Rotation) -> np.ndarray:
    """Angle between estimated and true up, in body axes [°] (heading does not enter)."""
    a, b = est.inv().apply([0.0, 0.0, 1.0]), truth.inv().apply([0.0, 0.0, 1.0])
    return np.degrees(np.arccos(np.clip((a * b).sum(axis=1), -1.0, 1.0)))


def turning(t: np.ndarray) -> Rotation:
    """A slow yaw turn with roll and pitch swinging by ±0.2 and ±0.15 rad."""
    return Rotation.from_euler("zyx", np.c_[0.3 * t, 0.15 * np.sin(0.4 * t), 0.2 * np.sin(0.7 * t)])


@functools.cache  # the tuner scores hundreds of points on the same record
def sustained_then_figure_eight() -> tuple[ik.ImuData, Rotation, np.ndarray]:
    """60 s: 10 s still(ish), 5 m/s² along world x for 10 s, 10 s coasting, a horizontal
    figure-eight with 3 m/s² peaks on each axis (period 3 s: 0.68 m across) for 25 s, rest."""
    t = np.arange(int(60 * RATE)) / RATE
    acc = np.zeros((len(t), 3))
    acc[(t >= 10.0) & (t < 20.0), 0] = 5.0
    eight = (t >= 30.0) & (t < 55.0)
    w = 2.0 * np.pi / 3.0
    acc[eight, 0] = -3.0 * np.sin(w * (t[eight] - 30.0))
    acc[eight, 1] = -3.0 * np.sin(2.0 * w * (t[eight] - 30.0))
    rot = turning(t)
    return imu_from(t, rot, acc), rot, t


def worst_tilt(filt: object) -> tuple[float, float]:
    """``filt`` (an imukit filter, 6D) on :func:`sustained_then_figure_eight`: its worst tilt [°]
    from the sustained acceleration to the end of the coast (10–30 s), and over the figure-eight
    and the rest after it (30–60 s)."""
    imu, truth, t = sustained_then_figure_eight()
    err = tilt_deg(filt.run(imu).rotation, truth)  # type: ignore[attr-defined]
    return float(err[(t >= 10.0) & (t < 30.0)].max()), float(err[t >= 30.0].max())
