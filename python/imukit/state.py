"""Navigation states: one (:class:`NavState`) and a time series (:class:`Trajectory`).

=====================  ===========================================================================
frames                 position and velocity in the world frame ``w`` (z up by default); rotation
                       ``R_wb`` maps body vectors to world (``docs/conventions.md``)
position               [m], velocity [m/s]; ``(3,)`` for a state, ``(N, 3)`` for a trajectory
rotation               a scipy ``Rotation``: single for a state, length N for a trajectory
time                   float64 seconds ``t``; optionally exact int64 nanoseconds ``t_ns`` (integer input,
                       told apart by dtype as in ``ImuData``)
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
    MIN_NS_STEP,
    FloatArray,
    Stamps,
    as_stamps,
    float_seconds,
    int64_stamps,
    plain_array,
    readonly_array,
    readonly_copy,
    rotation_from_unit_quat,
    too_fine_for_ns,
)
from imukit._deprecation import deprecated
from imukit._errors import DTypeError, ParameterError, ShapeError
from imukit._frozen import Frozen

__all__ = ["NavState", "Trajectory"]


class NavState(Frozen):
    """One navigation state: ``position`` (3,) [m], ``velocity`` (3,) [m/s] in the world frame, and
    ``rotation`` R_wb (a single scipy ``Rotation``, body to world). Immutable; arrays are read-only.
    """

    __slots__ = ("position", "rotation", "velocity")
    _fields = ("position", "velocity", "rotation")

    position: FloatArray
    velocity: FloatArray
    rotation: Rotation

    def __init__(self, position: ArrayLike, velocity: ArrayLike, rotation: Rotation) -> None:
        if not (isinstance(rotation, Rotation) and rotation.single):
            raise ParameterError(f"expected a single scipy Rotation, got {rotation!r}", argument="rotation")
        p = readonly_array(position, "position", (3,), "(3,)", "element")
        self._set(p, readonly_array(velocity, "velocity", (3,), "(3,)", "element"), rotation)

    def __repr__(self) -> str:
        return (
            f"NavState(position={self.position.tolist()}, velocity={self.velocity.tolist()}, "
            f"rotation=Rotation.from_quat({self.rotation.as_quat().tolist()}))"
        )


class Trajectory(Frozen):
    """N timed navigation states, with an optional covariance history. Immutable; arrays read-only.

    Parameters
    ----------
    t
        ``(N,)`` sample times, strictly increasing, N ≥ 1: float **seconds**, or integer
        **nanoseconds** (the dtype decides, as in :class:`imukit.ImuData`: ``t`` is then
        ``t_ns / 1e9``, nearest float, and ``t_ns`` the integers). May be None when ``t_ns`` is given.
    position
        ``(N, 3)`` world-frame positions [m].
    velocity
        ``(N, 3)`` world-frame velocities [m/s], or None when unknown (e.g. read from a TUM file).
    rotation
        scipy ``Rotation`` of length N: ``R_wb`` (body to world) at each ``t[k]``.
    t_ns
        ``(N,)`` integer nanoseconds of the same instants (the older spelling of integer ``t``, kept);
        with float ``t`` also given, ``t`` must agree with
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
    _fields = (
        "t",
        "t_ns",
        "position",
        "velocity",
        "rotation",
        "covariance",
        "covariance_t",
        "gyro_bias",
        "accel_bias",
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
        stamps = _stamps(t, t_ns)
        n = len(stamps.t)
        rows = f"(N, 3) with N = len(t) = {n}"
        position_ = readonly_array(position, "position", (n, 3), rows)
        velocity_ = None if velocity is None else readonly_array(velocity, "velocity", (n, 3), rows)
        if not isinstance(rotation, Rotation) or rotation.single or len(rotation) != n:
            got = (
                f"a {'single ' if rotation.single else ''}Rotation"
                if isinstance(rotation, Rotation)
                else repr(rotation)
            )
            length = f" of length {len(rotation)}" if isinstance(rotation, Rotation) and not rotation.single else ""
            raise ShapeError(
                f"expected a scipy Rotation of length N = len(t) = {n}, got {got}{length}", argument="rotation"
            )
        # A copy: the caller's Rotation could be modified in place (Rotation.__setitem__).
        rotation_ = rotation_from_unit_quat(rotation.as_quat())
        if (covariance is None) != (covariance_t is None):
            raise ParameterError("give covariance and covariance_t together, or neither", argument="covariance")
        cov = cov_t = None
        if covariance is not None and covariance_t is not None:
            cov_t = readonly_copy(float_seconds(covariance_t, "covariance_t"))
            m = len(cov_t)
            cov = readonly_array(covariance, "covariance", (m, 15, 15), f"(M, 15, 15) with M = len(covariance_t) = {m}")
        if (gyro_bias is None) != (accel_bias is None):
            raise ParameterError("give gyro_bias and accel_bias together, or neither", argument="gyro_bias")
        biases = [
            None if b is None else readonly_array(b, name, (n, 3), rows)
            for name, b in (("gyro_bias", gyro_bias), ("accel_bias", accel_bias))
        ]
        # t may be the caller's array; t_ns is fresh.
        self._set(readonly_copy(stamps.t), stamps.t_ns, position_, velocity_, rotation_, cov, cov_t, *biases)

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
        p, v, bg, ba = (arrays.get(name) for name in ("position", "velocity", "gyro_bias", "accel_bias"))
        return cls._from_validated(imu_t, imu_t_ns, p, v, rotation, covariance, covariance_t, bg, ba)

    def __len__(self) -> int:
        return len(self.t)

    def state(self, k: int) -> NavState:
        """The :class:`NavState` at sample ``k`` (negative counts from the end); needs a velocity."""
        if self.velocity is None:
            raise ParameterError("this trajectory has no velocity, so it has no NavState", argument="k")
        # A bool is no index (operator.index(True) is 1): checked before the conversion drops it.
        if isinstance(k, (bool, np.bool_)):
            raise ParameterError(f"expected an integer sample index, got {k!r}", argument="k")
        try:
            k = operator.index(k)
        except TypeError:
            raise ParameterError(f"expected an integer sample index, got {k!r}", argument="k") from None
        n = len(self)
        if not -n <= k < n:
            raise IndexError(f"k: sample {k} out of range for a trajectory of {n} samples")
        return NavState(self.position[k], self.velocity[k], self.rotation[k])

    def write_tum(self, path: str | os.PathLike[str]) -> None:
        """Deprecated: use ``imukit.io.write_tum(trajectory, path)``, which this calls.

        A trajectory is data and the file formats live in :mod:`imukit.io`; this alias stays for
        existing code and warns with :class:`DeprecationWarning`.
        """
        deprecated("Trajectory.write_tum(path) is deprecated; use imukit.io.write_tum(trajectory, path)")
        # imported here: imukit.io imports this module (readers build Trajectory objects).
        from imukit.io import write_tum

        write_tum(self, path)

    def __repr__(self) -> str:
        extras = [name for name in ("t_ns", "velocity", "covariance", "gyro_bias") if getattr(self, name) is not None]
        with_ = f" with {', '.join(extras)}" if extras else ""
        return f"Trajectory({len(self)} samples, {float(self.t[0])!r} … {float(self.t[-1])!r} s{with_})"


def _stamps(t: ArrayLike | None, t_ns: ArrayLike | None) -> Stamps:
    """:func:`as_stamps`; integer ``t`` that is not nanoseconds keeps the :class:`DTypeError` it got
    when ``t`` took float seconds only (integer nanoseconds went in ``t_ns``)."""
    raw = None if t is None else plain_array(t, "t")
    if t_ns is None and raw is not None and raw.dtype.kind in "iu" and raw.ndim == 1:
        if too_fine_for_ns(int64_stamps(raw, "t")) is not None:
            raise DTypeError(
                f"expected float seconds, got an array of dtype {raw.dtype}; pass integer nanoseconds "
                f"(a median step of at least {MIN_NS_STEP} ns), not seconds or sample indices",
                argument="t",
            )
    return as_stamps(t, t_ns)
