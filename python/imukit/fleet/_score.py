"""The ``evaluate`` job and the trajectory scores it shares with ``integrate``.

``evaluate`` scores an estimate someone else produced (a VIO or SLAM output, one file per log)
against its reference: ``path`` is the estimate, ``reference`` the ground truth, both read by
:func:`imukit.io.read_trajectory` (TUM, EuRoC ground-truth CSV, TUM-VI mocap, a CSV naming its pose
columns, or a recording folder: its ground truth). The reference is per log: the manifest's
``reference`` column (:func:`imukit.fleet.find_inputs`; relative to the manifest), or one file for
every log (``reference=``: the runs of several estimators on one sequence).

:func:`scores` (both jobs): ATE (:func:`imukit.eval.ape`) after ``align`` and RPE over
``rpe_delta_s`` seconds (:func:`imukit.eval.rpe`, same alignment), the estimate's poses paired with
the reference interpolated at their stamps (``max_dt``: the longest reference gap bridged, None: by
its own rate). Scalars: ``ate_rmse_m``, ``ate_max_m``, ``ate_rotation_rmse_deg``, ``rpe_rmse_m``,
``rpe_rotation_rmse_deg``, ``final_position_error_m`` (at the last scored pose) and
``scored_samples``. ``integrate`` scores its dead reckoning without alignment (it starts from the
truth's state); ``evaluate`` aligns by ``se3`` by default, as ``imukit evaluate`` does.
"""

from __future__ import annotations

import os

import numpy as np

from imukit._errors import ParameterError
from imukit.eval import AbsoluteError, ape, rpe
from imukit.fleet._load import JobOutput, Scalar, skipped_counts
from imukit.io import ReadReport, read_trajectory
from imukit.io._report import OnBadLine
from imukit.state import Trajectory

__all__ = ["evaluate", "scores"]


def scores(
    estimate: Trajectory, reference: Trajectory, *, align: str, rpe_delta_s: float, max_dt: float | None
) -> tuple[dict[str, Scalar], AbsoluteError]:
    """The scalars of the module doc, and the ATE result they come from."""
    ate = ape(estimate, reference, align=align, max_dt=max_dt)
    drift = rpe(estimate, reference, delta=rpe_delta_s, unit="s", align=align, max_dt=max_dt)
    final = ate.estimate.position[-1] - ate.reference.position[-1]
    scalars: dict[str, Scalar] = {
        "ate_rmse_m": ate.translation_stats.rmse,
        "ate_max_m": ate.translation_stats.max,
        "ate_rotation_rmse_deg": float(np.degrees(ate.rotation_stats.rmse)),
        "rpe_rmse_m": drift.translation_stats.rmse,
        "rpe_rotation_rmse_deg": float(np.degrees(drift.rotation_stats.rmse)),
        "final_position_error_m": float(np.linalg.norm(final)),
        "scored_samples": ate.translation_stats.n,
    }
    return scalars, ate


def evaluate(
    path: str | os.PathLike[str],
    *,
    reference: str | os.PathLike[str] | None = None,
    align: str = "se3",
    rpe_delta_s: float = 1.0,
    max_dt: float | None = None,
    on_bad_line: OnBadLine = "skip",
) -> JobOutput:
    """The ``evaluate`` job: the estimate at ``path`` scored against ``reference`` (module doc).
    Rows, one per scored pose: ``t_s``, ``translation_error_m``, ``rotation_error_deg``; scalars also
    ``estimate_samples`` and ``skipped_<kind>_lines`` (both files' bad lines)."""
    if reference is None:
        raise ParameterError(
            "the evaluate job needs a reference trajectory: a 'reference' column in the manifest or reference=",
            argument="reference",
        )
    skipped = ReadReport()
    estimate = read_trajectory(path, on_bad_line=on_bad_line, report=skipped)
    truth = read_trajectory(reference, on_bad_line=on_bad_line, report=skipped)
    scalars, ate = scores(estimate, truth, align=align, rpe_delta_s=rpe_delta_s, max_dt=max_dt)
    rows = {
        "t_s": ate.estimate.t,
        "translation_error_m": ate.translation,
        "rotation_error_deg": np.degrees(ate.rotation),
    }
    return JobOutput({"estimate_samples": len(estimate), **scalars, **skipped_counts(skipped)}, rows)
