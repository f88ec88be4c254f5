"""Relative pose error (RPE): the error of the motion between pairs of samples a fixed distance apart."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from imukit._arrays import FloatArray, choice, flag, row_norms
from imukit._errors import NonFiniteError, ParameterError
from imukit.eval._align import Alignment
from imukit.eval._checks import finite_float
from imukit.eval._prepare import prepare
from imukit.eval._stats import ErrorStats, error_stats
from imukit.state import Trajectory

UNITS = ("m", "s", "frames")


class RelativeError(NamedTuple):
    """Result of :func:`rpe`: one error per pair (i, j) of associated samples, and statistics.

    ``pairs`` (M, 2) indexes ``estimate`` and ``reference`` (the associated, aligned trajectories);
    ``separation`` (M,) is how far apart each pair is, in ``unit`` (travelled reference distance
    [m], time [s] or frames), ≥ ``delta``; ``translation / separation`` is the drift per unit.
    ``mask``, ``n_dropped``, ``n_outside_span``, ``n_in_gaps`` and ``max_dt`` come from
    :func:`associate`.
    """

    translation: FloatArray  # (M,) ‖translation of E_ij‖ [m]
    rotation: FloatArray  # (M,) rotation angle of E_ij [rad], in [0, π]
    translation_stats: ErrorStats  # [m]
    rotation_stats: ErrorStats  # [rad]
    pairs: NDArray[np.int64]
    separation: FloatArray
    delta: float
    unit: str
    alignment: Alignment
    estimate: Trajectory
    reference: Trajectory
    mask: NDArray[np.bool_]
    n_dropped: int
    n_outside_span: int
    n_in_gaps: int
    max_dt: float


def rpe(
    estimate: Trajectory,
    reference: Trajectory,
    *,
    delta: float = 1.0,
    unit: str = "m",
    align: str = "none",
    all_pairs: bool = False,
    max_dt: float | None = None,
    offset: float = 0.0,
) -> RelativeError:
    """Relative pose error of ``estimate`` against ``reference`` over pairs ``delta`` apart.

    The trajectories are first associated (:func:`associate`, with ``max_dt`` [s] and ``offset``
    [s]) and the estimate aligned (:func:`align` with ``method=align``). For a pair (i, j) of
    associated samples, with poses ``T = (R, p)`` in SE(3), the error is

        ``E_ij = (T_ref,i⁻¹ T_ref,j)⁻¹ (T_est,i⁻¹ T_est,j)``,

    reported as the norm of its translation [m] (``‖ΔR_refᵀ (Δp_est − Δp_ref)‖`` with the motions
    ``Δp = R_iᵀ (p_j − p_i)`` in the body frame at i) and its rotation angle [rad]. A rigid
    alignment cancels in ``T_i⁻¹ T_j``, so only ``"sim3"``'s scale changes the result.

    Pairs, with the separation ``d(i, j)`` = the reference's travelled distance
    ``Σ_{i≤k<j} ‖p_ref,k+1 − p_ref,k‖`` (``unit="m"``), its time ``t_j − t_i`` (``"s"``; integer
    nanoseconds when the associated stamps have them) or ``j − i`` (``"frames"``; ``delta`` then a
    positive integer): from a start i, j is the first sample with ``d(i, j) ≥ delta``. Without
    ``all_pairs`` the starts are 0 and each previous pair's end, so the pairs tile the trajectory
    without overlap; with ``all_pairs`` every sample that has such a j is a start. Starts whose j
    would lie past the end are not used.

    This is evo's ``RPE`` with ``pairs_from_reference=True`` (evo chooses pairs on the estimate by
    default) for consecutive pairs, and for ``all_pairs`` over frames; evo's ``all_pairs`` over
    metres takes from each i the j whose distance is *closest* to delta (within 10 %) instead.
    evo sums the distance step by step from each start, imukit differences the cumulative sum, and
    takes a float ``d(i, j)`` within rounding of ``delta`` (8 ulps of the axis' largest value) as
    ``delta``: a pair can differ only there.

    Raises
    ------
    ParameterError
        A bad option, or no pair ``delta`` apart (the message gives the trajectory's extent).
    """
    choice(unit, "unit", UNITS)
    delta = finite_float(delta, "delta", positive=True)
    if unit == "frames" and not delta.is_integer():
        raise ParameterError(f"expected a whole number of frames for unit='frames', got {delta!r}", argument="delta")
    flag(all_pairs, "all_pairs")
    prepared = prepare(estimate, reference, method=align, max_dt=max_dt, offset=offset)
    est, ref = prepared.estimate, prepared.reference

    axis = _separation_axis(ref, unit)
    in_ns = axis.dtype.kind == "i" and unit == "s"
    to_unit = 1e-9 if in_ns else 1.0  # axis units to `unit`
    pairs = _pairs(axis, round(delta * 1e9) if in_ns else delta, bool(all_pairs))
    if len(pairs) == 0:
        extent = float(axis[-1] - axis[0]) * to_unit
        raise ParameterError(
            f"no pair of associated samples is {delta:g} {unit} apart; they extend over {extent:g} {unit}",
            argument="delta",
        )
    i, j = pairs[:, 0], pairs[:, 1]
    rel_ref = ref.rotation[i].inv() * ref.rotation[j]
    rel_est = est.rotation[i].inv() * est.rotation[j]
    dp_ref = ref.rotation[i].inv().apply(ref.position[j] - ref.position[i])
    dp_est = est.rotation[i].inv().apply(est.position[j] - est.position[i])
    with np.errstate(over="ignore", invalid="ignore"):  # an overflowing difference: refused below
        translation = row_norms(dp_est - dp_ref, "estimate")  # ΔR_refᵀ preserves the norm
    rotation = np.asarray((rel_ref.inv() * rel_est).magnitude(), dtype=np.float64)
    separation = (axis[j] - axis[i]).astype(np.float64) * to_unit
    t_stats, r_stats = error_stats(translation), error_stats(rotation)
    return RelativeError(translation, rotation, t_stats, r_stats, pairs, separation, delta, unit, *prepared)


def _separation_axis(ref: Trajectory, unit: str) -> NDArray[np.float64] | NDArray[np.int64]:
    """Non-decreasing coordinate along the reference in which separations are differences."""
    if unit == "frames":
        return np.arange(len(ref), dtype=np.int64)
    if unit == "s":
        return ref.t if ref.t_ns is None else ref.t_ns
    # Scale-safe steps: squares of 1e160 m overflow and of 1e-170 m underflow (pairs and
    # separations were inf, NaN or none at those scales before 2026-12-07).
    with np.errstate(over="ignore"):
        path = np.concatenate([[0.0], np.cumsum(row_norms(np.diff(ref.position, axis=0), "reference"))])
    if not np.isfinite(path[-1]):
        raise NonFiniteError("its path length overflows float64", argument="reference")
    return path


def _pairs(axis: NDArray[np.float64] | NDArray[np.int64], delta: float, all_pairs: bool) -> NDArray[np.int64]:
    """(M, 2) pairs (i, j): j the first index with ``axis[j] − axis[i] ≥ delta`` (j > i always), a
    float separation within rounding of ``delta`` counting as ``delta``."""
    n = len(axis)
    if axis.dtype.kind == "f":
        # 30 Hz stamps from np.arange put 30 frames 0.9999999999999964 s apart: without the slack
        # the pair took 31 frames (1.033 s), and every later pair shifted (before 2026-12-07).
        delta -= 8.0 * np.finfo(float).eps * max(abs(float(axis[0])), abs(float(axis[-1])), delta)
    # first j with axis[j] ≥ axis[i] + delta; at least i + 1 (a stationary stretch repeats values)
    first = np.maximum(np.searchsorted(axis, axis + delta, side="left"), np.arange(1, n + 1))
    if all_pairs:
        starts = np.flatnonzero(first < n)
        return np.stack([starts, first[starts]], axis=1).astype(np.int64)
    chain = [0]
    while first[chain[-1]] < n:
        chain.append(int(first[chain[-1]]))
    ids = np.asarray(chain, dtype=np.int64)
    return np.stack([ids[:-1], ids[1:]], axis=1)
