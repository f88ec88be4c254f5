"""Absolute trajectory error (ATE; evo's APE): per-sample pose error after association and alignment."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from imukit._arrays import FloatArray, row_norms
from imukit.eval._align import Alignment
from imukit.eval._prepare import prepare
from imukit.eval._stats import ErrorStats, error_stats
from imukit.state import Trajectory


class AbsoluteError(NamedTuple):
    """Result of :func:`ape`: per-sample errors over the N associated samples and their statistics.

    ``estimate`` is the associated estimate after ``alignment``; ``reference`` the reference at
    the same stamps. ``mask``, ``n_dropped``, ``n_outside_span``, ``n_in_gaps`` and ``max_dt`` come from
    :func:`associate` (over the input estimate).
    """

    translation: FloatArray  # (N,) ‖p_est − p_ref‖ [m], world frame, after alignment
    rotation: FloatArray  # (N,) angle of R_ref⁻¹ R_est [rad], in [0, π]
    translation_stats: ErrorStats  # [m]
    rotation_stats: ErrorStats  # [rad]
    alignment: Alignment
    estimate: Trajectory
    reference: Trajectory
    mask: NDArray[np.bool_]
    n_dropped: int
    n_outside_span: int
    n_in_gaps: int
    max_dt: float


def ape(
    estimate: Trajectory,
    reference: Trajectory,
    *,
    align: str = "se3",
    max_dt: float | None = None,
    offset: float = 0.0,
) -> AbsoluteError:
    """Absolute trajectory error (ATE; evo's APE) of ``estimate`` against ``reference``.

    1. :func:`associate` (``max_dt`` [s], None: by the reference's rate; ``offset`` [s]): the
       reference interpolated at the estimate's stamps; unpaired samples are dropped and counted.
    2. :func:`align` with ``method=align`` (``"se3"``, ``"sim3"``, ``"yaw"``, ``"position"``,
       ``"none"``), fitted on all associated positions, applied to the estimate.
    3. Per sample i: translation error ``‖p'_est,i − p_ref,i‖`` [m] (the aligned estimate ``p'``)
       and rotation error ``∠(R_ref,i⁻¹ R'_est,i)`` [rad] (the rotation angle, in ``[0, π]``), with
       their :class:`ErrorStats`.

    With synchronised stamps (no interpolation) these are evo's ``APE`` with
    ``PoseRelation.translation_part`` and ``rotation_angle_rad`` after ``traj.align(...)``.
    """
    prepared = prepare(estimate, reference, method=align, max_dt=max_dt, offset=offset)
    est, ref = prepared.estimate, prepared.reference
    with np.errstate(over="ignore", invalid="ignore"):  # an overflowing difference: refused below
        translation = row_norms(est.position - ref.position, "estimate")
    rotation = np.asarray((ref.rotation.inv() * est.rotation).magnitude(), dtype=np.float64)
    return AbsoluteError(translation, rotation, error_stats(translation), error_stats(rotation), *prepared)
