"""Attitude-estimation error metrics: total, heading and inclination error against a reference.

The split follows the BROAD benchmark (Laidig, Caruso, Cereatti & Seel, "BROAD — A Benchmark for
Robust Inertial Orientation Estimation", Data 6(7):72, 2021, and its ``broad_utils.py``):

* the error is a rotation expressed in the **world** frame,
  ``q_err = q_truth ⊗ q_estimate⁻¹`` (Hamilton, ``q_wb`` maps body to world, see
  ``docs/conventions.md``): the rotation that carries the estimated body frame onto the true one,
  written in world axes. BROAD's reference code forms the inverse, ``q_estimate ⊗ q_truth⁻¹``; the
  three error magnitudes are identical for a rotation and its inverse, only the sign of
  :attr:`AttitudeError.heading_signed` differs.
* ``q_err`` is decomposed as ``q_err = q_z(ψ) ⊗ q_tilt`` with ``q_z(ψ)`` a rotation by ψ about the
  world vertical and ``q_tilt`` a rotation about a horizontal axis (the decomposition exists and
  is unique for every rotation whose ``w`` and ``z`` components are not both zero). With
  ``q_err = [x, y, z, w]``: ``ψ = 2 atan2(z, w)``, heading error ``|ψ|``, inclination error
  ``2 atan2(√(x² + y²), √(w² + z²))``, total error ``2 atan2(‖(x, y, z)‖, |w|)``. They satisfy
  ``cos(total/2) = cos(heading/2) · cos(inclination/2)`` exactly.

The vertical is the world z axis both for ``world="ENU"`` (z up) and ``world="NED"`` (z down), so the
magnitudes do not depend on ``world``; it fixes the sign of ``heading_signed``, which is measured
about the *up* direction in both cases (positive = counter-clockwise seen from above): about +z in
ENU, about −z in NED.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from imukit._arrays import FloatArray, as_float_array, choice, flag
from imukit._errors import DTypeError, InvalidQuaternionError, NonFiniteError, ParameterError, ShapeError
from imukit.state import Trajectory

__all__ = ["AttitudeError", "AttitudeRmse", "attitude_error"]

_WORLDS = ("ENU", "NED")


class AttitudeRmse(NamedTuple):
    """Root-mean-square errors over the selected samples, in rad (or degrees when asked)."""

    total: float
    heading: float
    inclination: float
    n_samples: int  # samples that entered the mean


class AttitudeError(NamedTuple):
    """Per-sample attitude errors of :func:`attitude_error` (all arrays of shape ``(N,)``).

    Rows where the reference is missing (a NaN quaternion, e.g. a motion-capture dropout) hold NaN
    in every error array and ``False`` in :attr:`valid`; :meth:`rmse` leaves them out and
    :attr:`n_missing` counts them.
    """

    total: FloatArray  # rotation angle of q_err, in [0, π]
    heading: FloatArray  # |rotation about the world vertical|, in [0, π]
    inclination: FloatArray  # tilt angle (rotation about a horizontal axis), in [0, π]
    heading_signed: FloatArray  # rotation about world *up*, in (−π, π]
    valid: NDArray[np.bool_]  # reference present (finite) at this sample
    mask: NDArray[np.bool_]  # samples used for the heading offset and by default in rmse(): caller's mask & valid
    heading_offset: float  # rotation about world up removed from the estimate (0 unless align_heading)
    n_missing: int  # samples whose reference is NaN

    def rmse(self, mask: ArrayLike | None = None, *, degrees: bool = False) -> AttitudeRmse:
        """RMSE of the three errors over ``self.mask`` (and ``mask`` too, when given).

        Samples without a reference never count. Raises :class:`~imukit.ParameterError` when no
        sample is left, rather than returning NaN.
        """
        use = self.mask if mask is None else self.mask & _bool_mask(mask, "mask", len(self.total))
        count = int(use.sum())
        if count == 0:
            raise ParameterError("no sample with a reference is selected; the RMSE is undefined", argument="mask")
        scale = np.degrees(1.0) if flag(degrees, "degrees") else 1.0

        def rms(e: FloatArray) -> float:
            return float(np.sqrt(np.mean(e[use] ** 2)) * scale)

        return AttitudeRmse(rms(self.total), rms(self.heading), rms(self.inclination), count)


def _bool_mask(mask: ArrayLike, name: str, n: int) -> NDArray[np.bool_]:
    arr = np.asarray(mask)
    if arr.dtype.kind != "b":
        if arr.dtype.kind in "iu" and arr.size and np.isin(arr, (0, 1)).all():
            arr = arr.astype(bool)  # MATLAB files store logical masks as uint8 0/1
        else:
            raise DTypeError(f"expected a boolean array, got dtype {arr.dtype}", argument=name)
    if arr.shape != (n,):
        raise ShapeError(f"expected shape (N,) with N = {n}, got {arr.shape}", argument=name)
    return arr


def _quats(q: Rotation | ArrayLike, name: str, scalar_first: bool) -> FloatArray:
    """(N, 4) or (4,) xyzw float64 quaternions, normalised; NaN rows kept (zero-norm ones refused)."""
    if isinstance(q, Rotation):
        return np.asarray(q.as_quat(), dtype=np.float64)
    if isinstance(q, Trajectory):  # its own stamps, not the other argument's
        raise ParameterError(
            "a Trajectory: pass its attitudes at the other argument's samples, e.g. "
            "imukit.eval.truth_at_imu(trajectory, imu) for a ground truth (its .reference.rotation and "
            ".mask), or trajectory.rotation when the stamps are the same",
            argument=name,
        )
    arr = as_float_array(q, name)
    if arr.ndim not in (1, 2) or arr.shape[-1] != 4:
        raise ShapeError(f"expected shape (N, 4) or (4,), got {arr.shape}", argument=name)
    if flag(scalar_first, "scalar_first"):
        arr = arr[..., [1, 2, 3, 0]]
    if np.isinf(arr).any():
        raise NonFiniteError("holds ±inf", argument=name)
    # Scale first (a quaternion's scale carries no rotation): rows near 1e154 would overflow when squared.
    with np.errstate(invalid="ignore", divide="ignore"):
        largest = np.max(np.abs(arr), axis=-1, keepdims=True)
        arr = arr / np.where(largest > 0, largest, 1.0)
    norm = np.linalg.norm(arr, axis=-1, keepdims=True)
    zero = (norm == 0).ravel()
    if zero.any():
        k = int(np.argmax(zero))
        raise InvalidQuaternionError(f"zero-norm quaternion at sample {k}, which is no rotation", argument=name)
    return np.asarray(arr / norm, dtype=np.float64)


def _split(q_err: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """(total, inclination, ψ about world +z) of xyzw error quaternions (q and −q alike)."""
    x, y, z, w = np.moveaxis(q_err, -1, 0)
    s = np.where(w < 0, -1.0, 1.0)  # pick the representative with w ≥ 0: ψ then lies in [−π, π]
    x, y, z, w = s * x, s * y, s * z, s * w
    total = 2.0 * np.arctan2(np.sqrt(x * x + y * y + z * z), w)
    inclination = 2.0 * np.arctan2(np.hypot(x, y), np.hypot(w, z))
    psi = 2.0 * np.arctan2(z, w)
    return total, inclination, psi


def _wrap(a: FloatArray) -> FloatArray:
    """Angles wrapped to (−π, π]."""
    out = np.asarray(np.pi - np.mod(np.pi - a, 2.0 * np.pi), dtype=np.float64)
    return out


def _multiply(a: FloatArray, b: FloatArray) -> FloatArray:
    """Hamilton product of xyzw quaternions, broadcasting (NaN-transparent, unlike scipy Rotation)."""
    ax, ay, az, aw = np.moveaxis(a, -1, 0)
    bx, by, bz, bw = np.moveaxis(b, -1, 0)
    return np.stack(
        [
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
            aw * bw - ax * bx - ay * by - az * bz,
        ],
        axis=-1,
    )


def attitude_error(
    estimate: Rotation | ArrayLike,
    truth: Rotation | ArrayLike,
    *,
    world: str = "ENU",
    align_heading: bool = False,
    mask: ArrayLike | None = None,
    scalar_first: bool = False,
) -> AttitudeError:
    """Total, heading and inclination error of ``estimate`` against ``truth`` (BROAD's metric).

    Parameters
    ----------
    estimate, truth
        Orientations ``R_wb`` (body to world) as scipy ``Rotation`` or quaternion arrays of shape
        ``(N, 4)`` (one ``(4,)`` quaternion broadcasts), scalar-last ``xyzw`` unless
        ``scalar_first=True``. Quaternions are normalised; q and −q give the same errors. ``truth``
        may hold NaN rows (missing reference): those samples get NaN errors and are excluded from
        the RMSE and the heading offset. ``estimate`` must be finite.
    world
        ``"ENU"`` or ``"NED"``: both have a vertical z axis; ``world`` only fixes the sign of
        ``heading_signed`` (about up: +z in ENU, −z in NED). Both orientations must use it.
    align_heading
        Remove a constant heading offset from the estimate first (for 6D filters, whose heading
        is unobservable and starts arbitrary): the offset δ is the circular mean
        ``atan2(Σ sin ψ, Σ cos ψ)`` of the signed heading error ψ over ``mask`` (valid samples only),
        and the estimate is replaced by ``q_z(δ) ⊗ q_estimate`` (a turn of the world frame about
        the vertical). This shifts every ψ by exactly −δ and leaves the inclination unchanged.
    mask
        Boolean ``(N,)`` selecting the samples for the heading offset and for :meth:`AttitudeError.rmse`
        (e.g. BROAD's ``movement``); default all samples. An integer array of only 0 and 1 (a MATLAB
        logical, a uint8 column) counts as booleans; a float array is refused, as it may hold weights.

    Returns
    -------
    AttitudeError
        Per-sample errors in rad, the selection mask, the removed offset and the NaN count; call
        ``.rmse()`` (``degrees=True`` for degrees).

    The conventions (``q_err = q_truth ⊗ q_estimate⁻¹`` in the world frame, the split, the
    identity ``cos(total/2) = cos(heading/2) cos(inclination/2)``) are in this module's docstring.
    """
    choice(world, "world", _WORLDS)
    flag(align_heading, "align_heading")
    q_est = _quats(estimate, "estimate", scalar_first)
    q_true = _quats(truth, "truth", scalar_first)
    if np.isnan(q_est).any():
        k = int(np.argmax(np.isnan(q_est).reshape(-1, 4).any(axis=1)))
        raise NonFiniteError(
            f"NaN at sample {k} (the estimate must be finite; only truth may miss rows)", argument="estimate"
        )
    if q_est.ndim == 2 and q_true.ndim == 2 and len(q_est) != len(q_true):
        raise ShapeError(f"estimate / truth: lengths differ: {len(q_est)} vs {len(q_true)}")
    q_est_2d = np.atleast_2d(q_est)
    q_true_2d = np.atleast_2d(q_true)
    n = max(len(q_est_2d), len(q_true_2d))
    conj = q_est_2d * np.array([-1.0, -1.0, -1.0, 1.0])
    q_err = np.broadcast_to(_multiply(q_true_2d, conj), (n, 4))
    valid = np.broadcast_to(~np.isnan(q_true_2d).any(axis=1), (n,)).copy()
    use = valid if mask is None else valid & _bool_mask(mask, "mask", n)

    offset = 0.0
    if align_heading:
        _, _, psi = _split(q_err)
        if not use.any():
            raise ParameterError(
                "no sample with a reference is selected; cannot estimate the heading offset", argument="mask"
            )
        offset = float(np.arctan2(np.sin(psi[use]).sum(), np.cos(psi[use]).sum()))
        # q_truth ⊗ (q_z(δ) ⊗ q_est)⁻¹ = q_err ⊗ q_z(−δ): heading ψ − δ, same tilt angle.
        half = -0.5 * offset
        q_err = _multiply(q_err, np.array([0.0, 0.0, np.sin(half), np.cos(half)]))

    total, inclination, psi = _split(q_err)
    up = 1.0 if world == "ENU" else -1.0
    heading_signed = _wrap(up * psi)
    return AttitudeError(
        total=total,
        heading=np.abs(heading_signed),
        inclination=inclination,
        heading_signed=heading_signed,
        valid=valid,
        mask=use,
        heading_offset=up * offset,
        n_missing=int(n - valid.sum()),
    )
