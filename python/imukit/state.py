"""Navigation states: one (:class:`NavState`) and a time series (:class:`Trajectory`).

=====================  ===========================================================================
frames                 position and velocity in the world frame ``w`` (z up by default); rotation
                       ``R_wb`` maps body vectors to world (``docs/conventions.md``)
position               [m], velocity [m/s]; ``(3,)`` for a state, ``(N, 3)`` for a trajectory
rotation               a scipy ``Rotation``: single for a state, length N for a trajectory
time                   float64 seconds ``t``; optionally exact int64 nanoseconds ``t_ns``
covariance             optional ``(M, 15, 15)`` at times ``covariance_t`` (M,) [s], error-state order
                       ``[δp, δv, δθ, δb_a, δb_g]`` unless the producer states otherwise (row 12)
=====================  ===========================================================================
"""

from __future__ import annotations

import operator
import os

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from imukit._arrays import (
    FloatArray,
    check_finite_rows,
    check_increasing,
    int64_stamps,
    readonly_array,
    readonly_copy,
    rotation_from_unit_quat,
    seconds_from_ns,
)
from imukit._errors import DTypeError, ParameterError, ShapeError, TimestampError

__all__ = ["NavState", "Trajectory"]

# Largest |t - t_ns/1e9| accepted when both are given: catches relative-vs-epoch mix-ups.
_T_NS_TOLERANCE_S = 1e-6
# Integer stamps whose median step is below this many ns are almost surely not nanoseconds (as in ImuData).
_MIN_NS_STEP = 1000


class NavState:
    """One navigation state: ``position`` (3,) [m], ``velocity`` (3,) [m/s] in the world frame, and
    ``rotation`` R_wb (a single scipy ``Rotation``, body to world). Immutable; arrays are read-only.
    """

    __slots__ = ("position", "rotation", "velocity")

    position: FloatArray
    velocity: FloatArray
    rotation: Rotation

    def __init__(self, position: ArrayLike, velocity: ArrayLike, rotation: Rotation) -> None:
        if not (isinstance(rotation, Rotation) and rotation.single):
            raise ParameterError(f"rotation: expected a single scipy Rotation, got {rotation!r}")
        object.__setattr__(self, "position", readonly_array(position, "position", (3,), "(3,)", "element"))
        object.__setattr__(self, "velocity", readonly_array(velocity, "velocity", (3,), "(3,)", "element"))
        object.__setattr__(self, "rotation", rotation)

    def __setattr__(self, name: str, value: object) -> None:
        raise AttributeError(f"NavState is immutable: cannot set {name!r}")

    def __repr__(self) -> str:
        return (
            f"NavState(position={self.position.tolist()}, velocity={self.velocity.tolist()}, "
            f"rotation=Rotation.from_quat({self.rotation.as_quat().tolist()}))"
        )


class Trajectory:
    """N timed navigation states, with an optional covariance history. Immutable; arrays read-only.

    Parameters
    ----------
    t
        ``(N,)`` float **seconds**, strictly increasing, N ≥ 1 (integer nanoseconds go in ``t_ns``).
        May be None when ``t_ns`` is given: it is then ``t_ns / 1e9`` (nearest float), as in
        :class:`imukit.ImuData`.
    position
        ``(N, 3)`` world-frame positions [m].
    velocity
        ``(N, 3)`` world-frame velocities [m/s], or None when unknown (e.g. read from a TUM file).
    rotation
        scipy ``Rotation`` of length N: ``R_wb`` (body to world) at each ``t[k]``.
    t_ns
        ``(N,)`` integer nanoseconds of the same instants; with both given, ``t`` must agree with
        ``t_ns / 1e9`` to 1 µs (so relative seconds cannot be paired with epoch stamps by mistake).
    covariance
        ``(M, 15, 15)`` error-state covariances (order stated by the producer), with
        ``covariance_t`` ``(M,)`` their float times [s], strictly increasing. Give both or neither.
    gyro_bias, accel_bias
        ``(N, 3)`` true or estimated sensor biases at each ``t[k]`` [rad/s], [m/s²] (a simulation's
        truth, EuRoC's ground truth), or None when unknown. Give both or neither.
    """

    __slots__ = (
        "accel_bias",
        "covariance",
        "covariance_t",
        "gyro_bias",
        "position",
        "rotation",
        "t",
        "t_ns",
        "velocity",
    )

    t: FloatArray
    t_ns: NDArray[np.int64] | None
    position: FloatArray
    velocity: FloatArray | None
    rotation: Rotation
    covariance: FloatArray | None
    covariance_t: FloatArray | None
    gyro_bias: FloatArray | None
    accel_bias: FloatArray | None

    def __init__(
        self,
        t: ArrayLike | None,
        position: ArrayLike,
        velocity: ArrayLike | None,
        rotation: Rotation,
        *,
        t_ns: ArrayLike | None = None,
        covariance: ArrayLike | None = None,
        covariance_t: ArrayLike | None = None,
        gyro_bias: ArrayLike | None = None,
        accel_bias: ArrayLike | None = None,
    ) -> None:
        stamps_ns = None if t_ns is None else _nanoseconds(t_ns)
        if t is None:
            if stamps_ns is None:
                raise ParameterError("t: expected (N,) float seconds; t may be None only when t_ns is given")
            seconds = seconds_from_ns(stamps_ns)
        else:
            seconds = _float_seconds(t, "t")
            if stamps_ns is not None:
                if stamps_ns.shape != seconds.shape:
                    raise ShapeError(
                        f"t_ns: expected shape (N,) with N = len(t) = {len(seconds)}, got {stamps_ns.shape}"
                    )
                off = np.abs(seconds - seconds_from_ns(stamps_ns))
                if off.max() > _T_NS_TOLERANCE_S:
                    k = int(np.argmax(off))
                    raise TimestampError(
                        f"t_ns: sample {k} is {stamps_ns[k]} ns but t[{k}] = {float(seconds[k])!r} s "
                        f"(off by {off[k]:.3g} s; t must be t_ns / 1e9, not relative seconds)"
                    )
        n = len(seconds)
        rows = f"(N, 3) with N = len(t) = {n}"
        set_ = object.__setattr__
        set_(self, "t", readonly_copy(seconds))
        set_(self, "t_ns", None if stamps_ns is None else readonly_copy(stamps_ns))
        set_(self, "position", readonly_array(position, "position", (n, 3), rows))
        set_(self, "velocity", None if velocity is None else readonly_array(velocity, "velocity", (n, 3), rows))
        if not isinstance(rotation, Rotation) or rotation.single or len(rotation) != n:
            got = (
                f"a {'single ' if rotation.single else ''}Rotation"
                if isinstance(rotation, Rotation)
                else repr(rotation)
            )
            length = f" of length {len(rotation)}" if isinstance(rotation, Rotation) and not rotation.single else ""
            raise ShapeError(f"rotation: expected a scipy Rotation of length N = len(t) = {n}, got {got}{length}")
        # A copy: the caller's Rotation could be modified in place (Rotation.__setitem__).
        set_(self, "rotation", rotation_from_unit_quat(rotation.as_quat()))
        if (covariance is None) != (covariance_t is None):
            raise ParameterError("covariance: give covariance and covariance_t together, or neither")
        if covariance is None or covariance_t is None:
            set_(self, "covariance", None)
            set_(self, "covariance_t", None)
        else:
            cov_t = _float_seconds(covariance_t, "covariance_t")
            m = len(cov_t)
            cov = readonly_array(covariance, "covariance", (m, 15, 15), f"(M, 15, 15) with M = len(covariance_t) = {m}")
            set_(self, "covariance", cov)
            set_(self, "covariance_t", readonly_copy(cov_t))
        if (gyro_bias is None) != (accel_bias is None):
            raise ParameterError("gyro_bias: give gyro_bias and accel_bias together, or neither")
        for name, bias in (("gyro_bias", gyro_bias), ("accel_bias", accel_bias)):
            set_(self, name, None if bias is None else readonly_array(bias, name, (n, 3), rows))

    def __setattr__(self, name: str, value: object) -> None:
        raise AttributeError(f"Trajectory is immutable: cannot set {name!r}")

    @classmethod
    def _from_core(
        cls,
        imu_t: FloatArray,
        imu_t_ns: NDArray[np.int64] | None,
        arrays: dict[str, FloatArray],
        rotation: Rotation,
        covariance: FloatArray | None = None,
        covariance_t: FloatArray | None = None,
    ) -> Trajectory:
        """A trajectory over arrays the compiled core has just produced, without re-validating or
        copying them (they are fresh, finite and correctly shaped by construction; copying 10⁶ states
        cost more than integrating them). ``arrays`` maps ``position``, ``velocity`` and optionally
        ``gyro_bias`` / ``accel_bias`` to ``(N, 3)`` views, made read-only here; the timestamps are an
        ImuData's, read-only already. As everywhere in numpy, the read-only flag is a guard, not a
        lock: the owner of a buffer can set it writeable again.
        """
        traj = object.__new__(cls)
        set_ = object.__setattr__
        for name in ("position", "velocity", "gyro_bias", "accel_bias"):
            value = arrays.get(name)
            if value is not None:
                value.setflags(write=False)
            set_(traj, name, value)
        for name, item in (
            ("t", imu_t),
            ("t_ns", imu_t_ns),
            ("rotation", rotation),
            ("covariance", covariance),
            ("covariance_t", covariance_t),
        ):
            set_(traj, name, item)
        return traj

    def __len__(self) -> int:
        return len(self.t)

    def state(self, k: int) -> NavState:
        """The :class:`NavState` at sample ``k`` (negative counts from the end); needs a velocity."""
        if self.velocity is None:
            raise ParameterError("k: this trajectory has no velocity, so it has no NavState")
        try:
            k = operator.index(k)
        except TypeError:
            raise ParameterError(f"k: expected an integer sample index, got {k!r}") from None
        if isinstance(k, bool):
            raise ParameterError(f"k: expected an integer sample index, got {k!r}")
        n = len(self)
        if not -n <= k < n:
            raise IndexError(f"k: sample {k} out of range for a trajectory of {n} samples")
        return NavState(self.position[k], self.velocity[k], self.rotation[k])

    def write_tum(self, path: str | os.PathLike[str]) -> None:
        """Write ``timestamp tx ty tz qx qy qz qw`` lines; see :func:`imukit.io.write_tum`."""
        from imukit.io import write_tum

        write_tum(self, path)

    def __repr__(self) -> str:
        extras = [name for name in ("t_ns", "velocity", "covariance", "gyro_bias") if getattr(self, name) is not None]
        with_ = f" with {', '.join(extras)}" if extras else ""
        return f"Trajectory({len(self)} samples, {float(self.t[0])!r} … {float(self.t[-1])!r} s{with_})"


def _float_seconds(t: ArrayLike, name: str) -> FloatArray:
    raw = np.asarray(t)
    if raw.dtype.kind != "f":
        hint = "; pass integer nanoseconds as t_ns=" if raw.dtype.kind in "iu" and name == "t" else ""
        raise DTypeError(f"{name}: expected float seconds, got an array of dtype {raw.dtype}{hint}")
    if raw.ndim != 1 or len(raw) == 0:
        raise ShapeError(f"{name}: expected shape (N,) with N ≥ 1, got {raw.shape}")
    seconds = raw.astype(np.float64)
    check_finite_rows(seconds, name)
    check_increasing(seconds, name, "s")
    return seconds


def _nanoseconds(t_ns: ArrayLike) -> NDArray[np.int64]:
    raw = np.asarray(t_ns)
    if raw.dtype.kind not in "iu":
        raise DTypeError(f"t_ns: expected integer nanoseconds, got an array of dtype {raw.dtype}")
    if raw.ndim != 1 or len(raw) == 0:
        raise ShapeError(f"t_ns: expected shape (N,) with N ≥ 1, got {raw.shape}")
    stamps = int64_stamps(raw, "t_ns")
    if len(stamps) > 1 and np.median(np.diff(stamps)) < _MIN_NS_STEP:
        raise ParameterError(
            f"t_ns: the median step is {np.median(np.diff(stamps))} ns; expected integer nanoseconds "
            f"(steps of at least {_MIN_NS_STEP} ns), not seconds or sample indices"
        )
    return stamps
