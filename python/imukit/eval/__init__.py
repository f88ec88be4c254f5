"""Evaluation against a reference: trajectory errors (ATE / RPE) and attitude errors.

=======================  =========================================================================
:func:`associate`        estimate stamps paired with the reference interpolated there (position
                         linear, rotation slerp); samples that cannot be paired are counted
:func:`align`            the similarity (``"se3"``, ``"sim3"``: Umeyama 1991), translation-only
                         (``"position"``), heading-only (``"yaw"``) or identity (``"none"``)
                         transform that best fits the estimate's positions onto the reference's
:func:`ape`              absolute trajectory error (ATE; evo's APE) after association + alignment
:func:`rpe`              relative pose error over a travelled distance, a time or a frame count
:func:`attitude_error`   total / heading / inclination split of orientation errors (BROAD)
:func:`truth_at_imu`     a ground truth at an IMU's stamps (the ``filter`` / ``integrate`` commands')
:func:`time_offset`      the clock offset between an IMU and a reference, from their angular speeds
=======================  =========================================================================

Definitions, the choice of alignment and the comparison with ``evo`` are in
``docs/evaluation.md``.

>>> import numpy as np, imukit as ik
>>> from scipy.spatial.transform import Rotation
>>> t = np.arange(100) * 0.1
>>> truth = ik.Trajectory(t, np.c_[np.cos(t), np.sin(t), 0.1 * t], None, Rotation.identity(100))
>>> estimate = ik.Trajectory(t, truth.position + [1.0, 2.0, 0.0], None, Rotation.identity(100))
>>> round(ik.eval.ape(estimate, truth, align="none").translation_stats.rmse, 6)  # the offset, √5 m
2.236068
>>> ik.eval.ape(estimate, truth, align="se3").translation_stats.max < 1e-12  # removed by the alignment
True
"""

from __future__ import annotations

from imukit.eval._align import Alignment, align
from imukit.eval._ape import AbsoluteError, ape
from imukit.eval._associate import Association, associate
from imukit.eval._at_imu import truth_at_imu
from imukit.eval._attitude import AttitudeError, AttitudeRmse, attitude_error
from imukit.eval._rpe import RelativeError, rpe
from imukit.eval._stats import ErrorStats
from imukit.eval._time_offset import TimeOffset, time_offset

__all__ = [
    "AbsoluteError",
    "Alignment",
    "Association",
    "AttitudeError",
    "AttitudeRmse",
    "ErrorStats",
    "RelativeError",
    "TimeOffset",
    "align",
    "ape",
    "associate",
    "attitude_error",
    "rpe",
    "time_offset",
    "truth_at_imu",
]
