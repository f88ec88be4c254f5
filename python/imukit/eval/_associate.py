"""Time association: each estimate sample paired with the reference interpolated at its stamp."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from imukit._arrays import FloatArray
from imukit._errors import ParameterError
from imukit.eval._checks import check_trajectory, finite_float
from imukit.io._gaps import reference_max_dt
from imukit.state import Trajectory

_INT64 = np.iinfo(np.int64)


class Association(NamedTuple):
    """Two trajectories at the same instants, from :func:`associate`.

    ``estimate`` holds the kept estimate samples (positions, velocities, rotations, biases as they
    were) stamped in the reference's clock, i.e. its own stamps plus ``offset``; ``reference`` holds
    the reference interpolated at exactly those stamps. ``mask`` (len of the input estimate,) marks
    the kept input samples; ``n_dropped = n_outside_span + n_in_gaps`` counts the others;
    ``max_dt`` is the longest reference step interpolated across [s] (given, or derived).
    """

    estimate: Trajectory
    reference: Trajectory
    mask: NDArray[np.bool_]
    n_dropped: int
    n_outside_span: int  # before the first or after the last reference stamp
    n_in_gaps: int  # inside the span, between reference samples more than max_dt apart
    max_dt: float  # [s] the limit used: the argument, or REFERENCE_GAP_FACTOR x the reference's median step

    @property
    def scored(self) -> float:
        """The fraction of the input estimate samples that were paired, in [0, 1]."""
        return float(np.mean(self.mask))


def culprit(offset: float, n_outside: int, n_in_gaps: int) -> str:
    """The argument an error about unpaired samples names first: ``max_dt`` when every loss was a
    reference gap, else ``offset`` when one was given (a wrong clock offset is the usual cause),
    else ``estimate``."""
    if n_in_gaps and not n_outside:
        return "max_dt"
    return "offset" if offset != 0.0 else "estimate"


def associate(
    estimate: Trajectory,
    reference: Trajectory,
    *,
    max_dt: float | None = None,
    offset: float = 0.0,
) -> Association:
    """Pair every estimate sample with the reference interpolated at the same instant.

    Parameters
    ----------
    estimate, reference
        :class:`~imukit.Trajectory` objects; only their stamps, positions, rotations and (when
        present) velocities and biases are used.
    max_dt
        Longest reference interval [s] across which the reference may be interpolated. An estimate
        stamp ``s`` with ``r_k < s < r_{k+1}`` is kept only when ``r_{k+1} − r_k ≤ max_dt``; a stamp
        equal to a reference stamp needs no interpolation and is always kept. None (default): by the
        reference's own rate, :func:`imukit.io.reference_max_dt` (``REFERENCE_GAP_FACTOR`` = 2.5
        times its median step), so a gap-free 20 Hz ground truth pairs every IMU sample in its span.
    offset
        Clock offset [s] **added** to the estimate's stamps before pairing: estimate time ``t``
        corresponds to reference time ``t + offset``.

    Returns
    -------
    Association
        The kept estimate samples and the reference at their stamps ``s = t + offset``:
        position ``p_k + f (p_{k+1} − p_k)`` and velocity likewise (when the reference has one),
        rotation by slerp ``R_k Exp(f Log(R_kᵀ R_{k+1}))``, biases linearly, with
        ``f = (s − r_k) / (r_{k+1} − r_k)``. Samples before the first or after the last reference
        stamp and samples inside a reference gap longer than ``max_dt`` are dropped and counted,
        never extrapolated.

    Stamps are compared as int64 nanoseconds when both trajectories carry ``t_ns`` (exact;
    ``offset`` is then rounded to the nearest nanosecond), else as float seconds. The returned
    trajectories carry ``t_ns`` exactly when that comparison was in nanoseconds. Covariances are
    not carried over.

    Raises
    ------
    ParameterError
        When no estimate sample can be paired; the message gives both spans and the drop counts, and
        starts with ``max_dt`` when every sample fell in a reference gap, else with ``offset`` when
        one was given, else with ``estimate``.
    """
    est = check_trajectory(estimate, "estimate")
    ref = check_trajectory(reference, "reference")
    max_dt = reference_max_dt(ref) if max_dt is None else finite_float(max_dt, "max_dt", positive=True)
    offset = finite_float(offset, "offset")
    in_ns = est.t_ns is not None and ref.t_ns is not None
    stamps: NDArray[np.int64] | FloatArray
    ref_stamps: NDArray[np.int64] | FloatArray
    if est.t_ns is not None and ref.t_ns is not None:
        shift = round(offset * 1e9)
        if not (_INT64.min <= int(est.t_ns[0]) + shift and int(est.t_ns[-1]) + shift <= _INT64.max):
            raise ParameterError(
                f"{offset:g} s moves the estimate's nanosecond stamps out of the int64 range", argument="offset"
            )
        stamps, ref_stamps, max_gap = est.t_ns + shift, ref.t_ns, max_dt * 1e9
    else:
        stamps, ref_stamps, max_gap = est.t + offset, ref.t, max_dt

    n_ref = len(ref_stamps)
    lo = np.searchsorted(ref_stamps, stamps, side="right") - 1  # r[lo] ≤ s < r[lo + 1]
    inside = (lo >= 0) & (stamps <= ref_stamps[-1])
    lo = np.clip(lo, 0, n_ref - 1)
    hi = np.minimum(lo + 1, n_ref - 1)
    exact = inside & (ref_stamps[lo] == stamps)
    gap = (ref_stamps[hi] - ref_stamps[lo]).astype(np.float64)
    between = inside & ~exact
    keep = exact | (between & (gap <= max_gap))
    n_outside = int((~inside).sum())
    n_gaps = int((between & ~keep).sum())
    if not keep.any():
        a, b = float(est.t[0]) + offset, float(est.t[-1]) + offset
        raise ParameterError(
            f"no estimate sample can be paired with the reference: the estimate spans {span_text(a, b)} "
            f"(offset {offset:g} s applied), the reference {span_text(float(ref.t[0]), float(ref.t[-1]))}; "
            f"{n_outside} samples outside the reference span, {n_gaps} inside reference gaps longer than "
            f"max_dt = {max_dt:.6g} s",
            argument=culprit(offset, n_outside, n_gaps),
        )

    lo, hi, s = lo[keep], hi[keep], stamps[keep]
    frac = np.where(exact[keep], 0.0, (s - ref_stamps[lo]).astype(np.float64) / np.where(gap[keep] > 0, gap[keep], 1))

    def lerp(x: FloatArray) -> FloatArray:
        return np.asarray(x[lo] + frac[:, None] * (x[hi] - x[lo]), dtype=np.float64)

    r_lo = ref.rotation[lo]
    rotation = r_lo * Rotation.from_rotvec(frac[:, None] * (r_lo.inv() * ref.rotation[hi]).as_rotvec())
    t_s, t_ns = (None, s) if in_ns else (s, None)
    reference_out = Trajectory(
        t_s,
        lerp(ref.position),
        None if ref.velocity is None else lerp(ref.velocity),
        rotation,
        t_ns=t_ns,
        gyro_bias=None if ref.gyro_bias is None else lerp(ref.gyro_bias),
        accel_bias=None if ref.accel_bias is None else lerp(ref.accel_bias),
    )
    estimate_out = Trajectory(
        t_s,
        est.position[keep],
        None if est.velocity is None else est.velocity[keep],
        est.rotation[keep],
        t_ns=t_ns,
        gyro_bias=None if est.gyro_bias is None else est.gyro_bias[keep],
        accel_bias=None if est.accel_bias is None else est.accel_bias[keep],
    )
    return Association(estimate_out, reference_out, keep, n_outside + n_gaps, n_outside, n_gaps, max_dt)


def span_text(a: float, b: float) -> str:
    """``[a, b] s`` to the millisecond, never in exponent notation: Unix-epoch stamps read
    ``[1403715273.262, 1403715418.512] s``, not ``[1.40371527e+09, 1.40371542e+09]``."""
    a_text, b_text = (np.format_float_positional(x, precision=3, trim="-") for x in (a, b))
    return f"[{a_text}, {b_text}] s"
