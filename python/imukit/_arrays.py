"""Array plumbing between the public API and the compiled core.

Inputs are validated here once (dtype, trailing shape) and flattened to ``(n, k)`` C-contiguous
float64; the core checks finiteness row by row and returns ``(n, m)``, reshaped back to the
caller's batch shape. Leading dimensions broadcast like numpy's.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, NamedTuple, TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from imukit._errors import DTypeError, NonFiniteError, ParameterError, ShapeError, TimestampError
from imukit.threads import checked

FloatArray = NDArray[np.float64]
Kernel = Callable[..., FloatArray]
_T = TypeVar("_T", bound=np.generic)

# xyzw <-> wxyz index maps for the scalar_first option.
_TO_XYZW = [1, 2, 3, 0]
_TO_WXYZ = [3, 0, 1, 2]


def plain_array(x: ArrayLike, name: str) -> NDArray[Any]:
    """``x`` as a numpy array: the one conversion of array input. Nested sequences of different
    lengths are a :class:`ShapeError` (numpy's own ``ValueError`` names no argument); a masked
    array with masked values is a :class:`DTypeError`, since ``np.asarray`` would silently use the
    values under the mask (one without masked values is its data)."""
    masked = int(np.count_nonzero(np.ma.getmaskarray(x))) if isinstance(x, np.ma.MaskedArray) else 0
    if masked:
        raise DTypeError(
            f"expected plain numbers, got a masked array with {masked} masked values: "
            "fill them (x.filled(np.nan) to have them refused as missing) or drop them",
            argument=name,
        )
    try:
        return np.asarray(x)
    except ValueError:  # numpy: "setting an array element with a sequence ... inhomogeneous shape"
        raise ShapeError(
            "expected a rectangular array, got nested sequences of different lengths", argument=name
        ) from None


def as_float_array(x: ArrayLike, name: str) -> FloatArray:
    """``x`` as a float64 array (:func:`plain_array`), refusing dtypes that are not real numbers."""
    arr = plain_array(x, name)
    if arr.dtype.kind not in "fiub":
        raise DTypeError(f"expected real numbers, got an array of dtype {arr.dtype}", argument=name)
    if arr.dtype.kind == "b":
        raise DTypeError("expected real numbers, got booleans", argument=name)
    return arr.astype(np.float64, copy=False)


def vector3(x: ArrayLike, name: str) -> FloatArray:
    """``x`` as one finite float64 3-vector; :class:`ShapeError` / :class:`NonFiniteError` naming ``name``."""
    v = as_float_array(x, name)
    if v.shape != (3,):
        raise ShapeError(f"expected shape (3,), got {v.shape}", argument=name)
    check_finite_rows(v, name, "element")
    return v


def real_scalar(value: object, name: str, *, what: str, accept: Callable[[float], bool]) -> float:
    """``value`` as a float for which ``accept`` holds, else :class:`ParameterError` naming ``name``.

    Only real numbers qualify: a string that happens to parse as one, a bool (``dt=True`` is no step
    of 1 s), None and arrays with more than one element are refused, so that a wrongly typed option
    fails here and not as a bare ``TypeError`` deep inside.
    """
    x = math.nan
    if not isinstance(value, (str, bytes, bool, np.bool_)):
        try:
            x = float(value)  # type: ignore[arg-type]
        except (TypeError, ValueError, OverflowError):  # OverflowError: an int beyond float64
            pass
    if math.isnan(x) or not accept(x):
        raise ParameterError(f"expected {what}, got {value!r}", argument=name)
    return x


def _shape_text(tail: tuple[int, ...]) -> str:
    return "(..., " + ", ".join(str(d) for d in tail) + ")"


def check_tail(arr: FloatArray, name: str, tail: tuple[int, ...]) -> None:
    """Raise :class:`ShapeError` unless ``arr.shape`` ends with ``tail``."""
    if arr.ndim < len(tail) or arr.shape[arr.ndim - len(tail) :] != tail:
        raise ShapeError(f"expected shape {_shape_text(tail)}, got {arr.shape}", argument=name)


def batched(
    kernel: Kernel,
    inputs: list[tuple[ArrayLike, str, tuple[int, ...]]],
    out_tail: tuple[int, ...],
    *options: Any,
    threads: object = None,
) -> FloatArray:
    """Broadcast ``inputs`` over their leading dimensions, run ``kernel`` once on ``threads``
    threads (the public function's argument, checked here), reshape back.

    Several inputs are concatenated row-wise (``[q, p]`` for a product), so the core sees one
    contiguous ``(n, sum of widths)`` array. The error name given to the core is the first
    input's when there is one input, else all names joined.
    """
    count = checked(threads)
    arrays = []
    for x, name, tail in inputs:
        arr = as_float_array(x, name)
        check_tail(arr, name, tail)
        arrays.append(arr)
    try:
        batch = np.broadcast_shapes(*(a.shape[: a.ndim - len(t)] for a, (_, _, t) in zip(arrays, inputs)))
    except ValueError:
        shapes = ", ".join(f"{n} {a.shape}" for a, (_, n, _) in zip(arrays, inputs))
        names = " / ".join(n for _, n, _ in inputs)
        raise ShapeError(f"leading dimensions do not broadcast: {shapes}", argument=names) from None
    rows = [np.broadcast_to(a, batch + t).reshape(-1, int(np.prod(t))) for a, (_, _, t) in zip(arrays, inputs)]
    flat = np.ascontiguousarray(rows[0] if len(rows) == 1 else np.concatenate(rows, axis=1))
    name = " / ".join(n for _, n, _ in inputs)
    out = kernel(flat, name, *options, threads=count)
    return out.reshape(batch + out_tail)


def flag(value: object, name: str) -> bool:
    """``value`` as a bool, else :class:`ParameterError` naming ``name``: ``"no"`` is truthy and 1 may
    be a count, so only ``bool`` and numpy's are taken (the one rule of every flag option)."""
    if not isinstance(value, (bool, np.bool_)):
        raise ParameterError(f"expected a bool, got {value!r}", argument=name)
    return bool(value)


def to_xyzw(q: ArrayLike, name: str, scalar_first: bool) -> ArrayLike:
    """Reorder ``wxyz`` input to the core's ``xyzw`` when ``scalar_first``."""
    if not flag(scalar_first, "scalar_first"):
        return q
    arr = as_float_array(q, name)
    check_tail(arr, name, (4,))
    return arr[..., _TO_XYZW]


def quat_out(q: FloatArray, scalar_first: bool) -> FloatArray:
    """Reorder core ``xyzw`` output to ``wxyz`` when ``scalar_first``."""
    return np.ascontiguousarray(q[..., _TO_WXYZ]) if flag(scalar_first, "scalar_first") else q


def matrix4_out(m: FloatArray, scalar_first: bool) -> FloatArray:
    """Re-express a 4x4 operator on ``xyzw`` vectors as one on ``wxyz`` vectors when ``scalar_first``."""
    return np.ascontiguousarray(m[..., _TO_WXYZ, :][..., :, _TO_WXYZ]) if flag(scalar_first, "scalar_first") else m


def choice(value: str, name: str, allowed: tuple[str, ...]) -> str:
    """Validate a string option."""
    if value not in allowed:
        raise ParameterError(f"expected one of {allowed}, got {value!r}", argument=name)
    return value


def rotation_from_unit_quat(q: FloatArray) -> Rotation:
    """A scipy ``Rotation`` from xyzw quaternions that are unit to rounding already.

    ``Rotation.from_quat`` renormalises at about 100 ns per rotation, more than imukit's whole
    integration step; the constructor with ``normalize=False`` takes the array as it is.
    """
    try:
        return Rotation(q, normalize=False, copy=False)
    except TypeError:  # a scipy without these keywords
        return Rotation.from_quat(q)


# Integer stamps whose median step is below this many ns are almost surely not nanoseconds but
# seconds or sample indices given as integers: every integer-stamp input refuses them.
MIN_NS_STEP = 1000
# Largest |t - t_ns/1e9| accepted when both clocks are given: catches relative-vs-epoch mix-ups.
_T_NS_TOLERANCE_S = 1e-6


class Stamps(NamedTuple):
    """Validated sample times (:func:`as_stamps`).

    ``t`` float64 seconds: the float input, or ``t_ns / 1e9`` (nearest float); ``t_ns`` int64
    nanoseconds for integer input, else None.
    """

    t: FloatArray
    t_ns: NDArray[np.int64] | None

    @property
    def seconds(self) -> FloatArray:
        """The clock the integrators consume: float input as given; with ``t_ns``, exact offsets from
        the first stamp (an epoch in float64 resolves only ~0.24 µs)."""
        return self.t if self.t_ns is None else seconds_from_ns(self.t_ns - self.t_ns[:1])


def as_stamps(t: ArrayLike | None, t_ns: ArrayLike | None = None, *, name: str = "t") -> Stamps:
    """Sample times from float64 seconds or integer nanoseconds (told apart by dtype), or from both
    clocks: ``t`` float seconds with ``t_ns`` integer nanoseconds of the same instants (agreeing to
    1 µs, so relative seconds cannot be paired with epoch stamps), or ``t=None`` and ``t_ns``.

    Integer stamps must be within int64 and have a median step of at least :data:`MIN_NS_STEP` ns;
    every clock must hold N ≥ 1 finite, strictly increasing stamps (:class:`TimestampError` etc.
    naming the argument and the first bad sample).
    """
    if t_ns is None:
        if t is None:
            raise ParameterError(
                f"expected (N,) float seconds; {name} may be None only when t_ns is given", argument=name
            )
        raw = _stamp_array(t, name)
        if raw.dtype.kind in "iu":
            stamps = nanoseconds(raw, name)
            return Stamps(seconds_from_ns(stamps), stamps)
        if raw.dtype.kind != "f":
            what = f"float seconds or integer nanoseconds, got an array of dtype {raw.dtype}"
            raise DTypeError(f"expected {what}", argument=name)
        return Stamps(float_seconds(raw, name), None)
    stamps = nanoseconds(_stamp_array(t_ns, "t_ns"), "t_ns")
    if t is None:
        return Stamps(seconds_from_ns(stamps), stamps)
    seconds = float_seconds(t, name)
    if stamps.shape != seconds.shape:
        raise ShapeError(
            f"expected shape (N,) with N = len({name}) = {len(seconds)}, got {stamps.shape}", argument="t_ns"
        )
    off = np.abs(seconds - seconds_from_ns(stamps))
    if off.max() > _T_NS_TOLERANCE_S:
        k = int(np.argmax(off))
        raise TimestampError(
            f"sample {k} is {stamps[k]} ns but {name}[{k}] = {float(seconds[k])!r} s "
            f"(off by {off[k]:.3g} s; {name} must be t_ns / 1e9, not relative seconds)",
            argument="t_ns",
        )
    return Stamps(seconds, stamps)


def _stamp_array(x: ArrayLike, name: str) -> NDArray[Any]:
    raw = plain_array(x, name)
    if raw.ndim != 1 or len(raw) == 0:
        raise ShapeError(f"expected shape (N,) with N ≥ 1, got {raw.shape}", argument=name)
    return raw


def float_seconds(x: ArrayLike, name: str) -> FloatArray:
    """``x`` as (N,) finite, strictly increasing float64 seconds, N ≥ 1; only a float dtype qualifies."""
    raw = _stamp_array(x, name)
    if raw.dtype.kind != "f":
        raise DTypeError(f"expected float seconds, got an array of dtype {raw.dtype}", argument=name)
    seconds = np.ascontiguousarray(raw, dtype=np.float64)
    check_finite_rows(seconds, name)
    check_increasing(seconds, name, "s")
    return seconds


def nanoseconds(raw: NDArray[Any], name: str) -> NDArray[np.int64]:
    """Integer stamps as int64 nanoseconds (:func:`int64_stamps`) whose median step is at least
    :data:`MIN_NS_STEP`; other dtypes are a :class:`DTypeError`."""
    if raw.dtype.kind not in "iu":
        raise DTypeError(f"expected integer nanoseconds, got an array of dtype {raw.dtype}", argument=name)
    stamps = int64_stamps(raw, name)
    median = too_fine_for_ns(stamps)
    if median is not None:
        raise ParameterError(
            f"integer timestamps are read as nanoseconds, but the median step is {median} ns; "
            "pass float seconds instead",
            argument=name,
        )
    return stamps


def too_fine_for_ns(stamps: NDArray[np.int64]) -> float | None:
    """The median step of int64 ``stamps`` when it is under :data:`MIN_NS_STEP` (they are not
    nanoseconds), else None."""
    if len(stamps) < 2:
        return None
    median = float(np.median(np.diff(stamps)))
    return median if median < MIN_NS_STEP else None


def int64_stamps(raw: NDArray[Any], name: str) -> NDArray[np.int64]:
    """Integer nanosecond stamps as int64: strictly increasing, within int64, and spanning less than
    2⁶³ ns (292 years), so that every offset from the first stamp is an int64 too."""
    if raw.dtype.kind == "u" and len(raw) and raw.max() > np.iinfo(np.int64).max:
        raise ParameterError(f"integer nanoseconds exceed the int64 range (max {raw.max()})", argument=name)
    stamps = raw.astype(np.int64)
    check_increasing(stamps, name, "ns")
    if len(stamps) and int(stamps[-1]) - int(stamps[0]) > np.iinfo(np.int64).max:
        raise TimestampError(
            f"the stamps span {int(stamps[-1]) - int(stamps[0])} ns, more than int64 can hold (292 years)",
            argument=name,
        )
    return stamps


def seconds_from_ns(t_ns: NDArray[np.int64]) -> FloatArray:
    """Float seconds of int64 nanosecond stamps.

    Below 2⁵³ ns (104 days; every relative time) the stamp is exact in float64 and one correctly
    rounded division gives the float nearest ``t_ns / 1e9``. Larger stamps (epochs, 1.4e18 ns) are
    split into whole seconds and the nanosecond remainder, converted separately: within one unit in
    the last place of the exact value, not the 256 ns-coarse ``float(t_ns)`` scaled.
    """
    exact = np.abs(t_ns) < 2**53
    whole, frac = np.divmod(t_ns, np.int64(1_000_000_000))
    split = whole.astype(np.float64) + frac.astype(np.float64) / 1e9
    return np.ascontiguousarray(np.where(exact, t_ns.astype(np.float64) / 1e9, split))


def readonly_copy(arr: NDArray[_T]) -> NDArray[_T]:
    """A C-contiguous copy of ``arr`` with the writeable flag cleared."""
    out = np.array(arr, order="C", copy=True)
    out.flags.writeable = False
    return out


def immutable(arr: np.ndarray) -> bool:
    """Whether nothing can write ``arr``'s memory: it and every array it views are read-only, down to
    an owner that is none (a read-only array owning its memory) or ``bytes`` (an unpickled array).
    A read-only view of a writeable array is not (its owner can still write), nor is a memory map,
    even a read-only one (the file under it can be rewritten). The same rule as the glue's
    ``frozen_or_copy`` (imukit-py/src/convert.rs), which the kernels apply to their inputs."""
    root: object = arr
    while isinstance(root, np.ndarray):
        if root.flags.writeable:
            return False
        root = root.base
    return root is None or isinstance(root, bytes)


def frozen(arr: NDArray[_T]) -> NDArray[_T]:
    """``arr`` itself when it is C-contiguous and :func:`immutable` (read in place: no copy, the
    view keeps its owner alive as any numpy view does), else :func:`readonly_copy`. An owner that
    sets the flag back and writes anyway breaks the promise the flag made, not this function."""
    if arr.flags.c_contiguous and immutable(arr):
        return arr
    return readonly_copy(arr)


def check_finite_rows(arr: FloatArray, name: str, what: str = "sample") -> None:
    """Raise :class:`NonFiniteError` naming the first row (along axis 0) holding NaN or ±inf."""
    bad = ~np.isfinite(arr)
    if bad.any():
        k = int(np.argmax(bad.reshape(len(arr), -1).any(axis=1)))
        raise NonFiniteError(f"non-finite value at {what} {k}: {arr[k].tolist()}", argument=name)


def check_increasing(t: NDArray[np.int64] | FloatArray, name: str, unit: str) -> None:
    """Raise :class:`TimestampError` naming the first sample whose step from the previous is ≤ 0.

    Compares neighbours instead of differencing them: an int64 difference can wrap around.
    """
    bad = np.flatnonzero(t[1:] <= t[:-1])
    if bad.size:
        k = int(bad[0])
        step = int(t[k + 1]) - int(t[k]) if t.dtype.kind in "iu" else float(t[k + 1]) - float(t[k])
        raise TimestampError(
            f"time must increase strictly: step into sample {k + 1} has dt = {step} {unit}", argument=name
        )


def relative_seconds(seconds: FloatArray, name: str) -> FloatArray:
    """``seconds - seconds[0]``, the clock the kernels integrate over, checked: finite (a span beyond
    1.8e308 s overflows) and strictly increasing (a step below the rounding of a huge span is lost:
    ``[-1e16, 0.5, 0.75]``), else a :class:`TimestampError` naming ``name``, never a later kernel
    blaming a step that the input does not have."""
    with np.errstate(over="ignore", invalid="ignore"):
        relative: FloatArray = seconds - seconds[0]
    if not np.isfinite(relative[-1]):  # increasing: the last is the largest
        k = int(np.argmax(~np.isfinite(relative)))
        raise TimestampError(
            f"the span from the first stamp ({float(seconds[0])!r} s) to sample {k} ({float(seconds[k])!r} s) "
            "overflows float64",
            argument=name,
        )
    lost = np.flatnonzero(relative[1:] <= relative[:-1])
    if lost.size:
        k = int(lost[0]) + 1
        raise TimestampError(
            f"samples {k - 1} and {k} ({float(seconds[k - 1])!r} s, {float(seconds[k])!r} s) are "
            f"{float(seconds[k]) - float(seconds[k - 1]):.6g} s apart, but relative to the first stamp "
            f"({float(seconds[0])!r} s) both are {float(relative[k])!r} s: the span is too long for "
            "the step in float64",
            argument=name,
        )
    return relative


def readonly_array(
    x: ArrayLike, name: str, shape: tuple[int, ...], shape_text: str, what: str = "sample"
) -> FloatArray:
    """``x`` as a finite float64 array of exactly ``shape``, read-only: :func:`frozen` (an immutable
    C-contiguous float64 input is read in place, anything else copied).

    ``shape_text`` is how the message states the expected shape, e.g. ``"(N, 3) with N = len(t) = 5"``.
    """
    arr = as_float_array(x, name)
    if arr.shape != shape:
        raise ShapeError(f"expected shape {shape_text}, got {arr.shape}", argument=name)
    check_finite_rows(arr, name, what)
    return frozen(arr)


def row_norms(x: FloatArray, name: str) -> FloatArray:
    """Euclidean norms of the rows of ``x`` (N, k), scale-safe: each row is divided by its largest
    magnitude before squaring, so rows near 1e154 (whose squares overflow) or 1e-200 (whose squares
    underflow to 0) get their true norm. A norm beyond float64 itself (an overflowing difference, a
    row of ±1e308) is a :class:`NonFiniteError` naming ``name``."""
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        scale = np.max(np.abs(x), axis=1)
        safe = np.where(scale > 0, scale, 1.0)
        out: FloatArray = scale * np.sqrt(np.sum((x / safe[:, None]) ** 2, axis=1))
    bad = np.flatnonzero(~np.isfinite(out))
    if bad.size:
        raise NonFiniteError(f"row {int(bad[0])} is too large in magnitude: its norm overflows float64", argument=name)
    return out
