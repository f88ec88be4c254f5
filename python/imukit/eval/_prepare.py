"""The first two steps of :func:`ape` and :func:`rpe`: associate in time, then align in space."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from imukit._arrays import choice
from imukit._errors import ParameterError
from imukit.eval._align import METHODS, Alignment, align
from imukit.eval._associate import associate, culprit
from imukit.state import Trajectory


class Prepared(NamedTuple):
    """The trailing fields of :class:`AbsoluteError` and :class:`RelativeError`, in their order."""

    alignment: Alignment
    estimate: Trajectory  # associated, then aligned
    reference: Trajectory  # interpolated at the estimate's stamps
    mask: NDArray[np.bool_]  # over the input estimate: samples kept by the association
    n_dropped: int  # = n_outside_span + n_in_gaps
    n_outside_span: int
    n_in_gaps: int
    max_dt: float  # [s] the association's limit (given, or by the reference's rate)


def prepare(
    estimate: Trajectory, reference: Trajectory, *, method: str, max_dt: float | None, offset: float
) -> Prepared:
    """:func:`associate` (``max_dt``, ``offset``), fit :func:`align` (``method``) on all pairs, apply it."""
    choice(method, "align", METHODS)  # named as ape's and rpe's keyword
    pair = associate(estimate, reference, max_dt=max_dt, offset=offset)
    kept = len(pair.estimate)
    if method in ("se3", "sim3") and kept < 3 and pair.n_dropped:
        raise ParameterError(
            f"{method} alignment needs at least 3 paired "
            f"samples, but only {kept} of {len(pair.mask)} estimate samples could be paired with the reference "
            f"({pair.n_outside_span} outside its span, {pair.n_in_gaps} in gaps longer than "
            f"max_dt = {pair.max_dt:.6g} s)",
            argument=culprit(offset, pair.n_outside_span, pair.n_in_gaps),
        )
    alignment = align(pair.estimate, pair.reference, method=method)
    estimate_out = alignment.apply(pair.estimate)
    return Prepared(alignment, estimate_out, pair.reference, pair.mask, *pair[3:])
