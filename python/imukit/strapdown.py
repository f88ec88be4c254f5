"""Strapdown integration and error-state covariance propagation: ``integrate``, ``propagate``.

Model (``docs/strapdown.md``): ``ṗ = v``, ``v̇ = R (a_m − b_a) + g``, ``Ṙ = R [ω_m − b_g]×`` with
``g`` added (default ``(0, 0, −9.81)``, z up; NED users pass ``(0, 0, +9.81)``); ``a_m`` is the
specific force the accelerometer reads (+9.81 on the up axis at rest). Positions and velocities
are in the world frame, rotations ``R_wb`` map body to world.
"""

from __future__ import annotations

import operator

import numpy as np
from numpy.typing import ArrayLike
from scipy.spatial.transform import Rotation

from imukit import _core
from imukit._arrays import (
    FloatArray,
    as_float_array,
    check_finite_rows,
    readonly_copy,
    rotation_from_unit_quat,
    vector3,
)
from imukit._errors import ParameterError, ShapeError
from imukit._extrinsics import sensor_pose
from imukit._names import canonical
from imukit.earth import LocalLevel, world_of
from imukit.imu import ImuBias, ImuData, ImuNoise
from imukit.state import NavState, Trajectory
from imukit.threads import checked

__all__ = ["SCHEMES", "SCHEME_ALIASES", "integrate", "propagate"]

#: The schemes, as the core lists them: ``("lie_euler", "midpoint", "rk4", "exp")``.
SCHEMES: tuple[str, ...] = _core.STRAPDOWN_SCHEMES
#: Deprecated scheme names and their canonical names: ``{"euler": "lie_euler"}``.
SCHEME_ALIASES: dict[str, str] = _core.STRAPDOWN_SCHEME_ALIASES
_DEFAULT_GRAVITY = _core.GRAVITY


def _common(
    imu: ImuData, initial: NavState, bias: ImuBias | None, gravity: ArrayLike, scheme: str
) -> tuple[ImuBias, list[float], str]:
    if not isinstance(imu, ImuData):
        raise ParameterError(f"expected an imukit.ImuData, got {type(imu).__name__}", argument="imu")
    if not isinstance(initial, NavState):
        raise ParameterError(f"expected an imukit.NavState, got {type(initial).__name__}", argument="initial")
    if bias is not None and not isinstance(bias, ImuBias):
        raise ParameterError(f"expected an imukit.ImuBias or None, got {type(bias).__name__}", argument="bias")
    scheme = canonical(scheme, "scheme", SCHEMES, SCHEME_ALIASES)
    g = vector3(gravity, "gravity")
    return bias or ImuBias(), [float(v) for v in g], scheme


def _in_body(
    imu: ImuData, bias: ImuBias, body_from_sensor: object
) -> tuple[FloatArray, FloatArray, ImuBias, list[float]]:
    """The readings and bias to integrate: the IMU's own, or the body origin's (bias removed), and
    the lever arm (zero without a sensor pose)."""
    if body_from_sensor is None:
        return imu.gyro, imu.accel, bias, [0.0, 0.0, 0.0]
    rows, arm = sensor_pose(body_from_sensor)
    gyro, accel = _core.body_readings(imu.seconds, imu.gyro, imu.accel, bias, [list(r) for r in rows], list(arm))
    return gyro, accel, ImuBias(), [float(v) for v in arm]


def _trajectory(
    imu: ImuData,
    position_velocity: FloatArray,
    quaternions: FloatArray,
    covariance: FloatArray | None = None,
    covariance_t: FloatArray | None = None,
) -> Trajectory:
    # Fresh arrays from the core: the quaternions become the Rotation's own buffer.
    rotation = rotation_from_unit_quat(quaternions)
    arrays = {"position": position_velocity[:, 0:3], "velocity": position_velocity[:, 3:6]}
    return Trajectory._from_core(imu.t, imu.t_ns, arrays, rotation, covariance, covariance_t)


def integrate(
    imu: ImuData,
    *,
    initial: NavState,
    gravity: ArrayLike = _DEFAULT_GRAVITY,
    bias: ImuBias | None = None,
    scheme: str = _core.STRAPDOWN_DEFAULT_SCHEME,
    frame: LocalLevel | None = None,
    body_from_sensor: tuple[Rotation, ArrayLike] | None = None,
    threads: int | None = None,
) -> Trajectory:
    """Integrate IMU samples into positions, velocities and attitudes, one per sample.

    Schemes over ``h = t[k+1] − t[k]`` with bias-corrected samples ``â = a_m − b_a``, ``ω̂ = ω_m − b_g``:

    - ``"lie_euler"`` (order 1): ``a = R_k â_k + g``; ``p += v h + ½ a h²``; ``v += a h``;
      ``R ← R Exp(ω̂_k h)``. Formerly named ``"euler"``; that name still works but is deprecated
      (``DeprecationWarning``): in :func:`imukit.integrate_attitude` ``"euler"`` is forward Euler
      on the ODE, a different rule;
    - ``"midpoint"`` (order 2, VINS-Mono's): ``R⁺ = R Exp(½(ω̂_k + ω̂_{k+1}) h)``,
      ``a = ½(R_k â_k + R⁺ â_{k+1}) + g``, then as lie_euler;
    - ``"rk4"`` (order 4): classical Runge-Kutta; the mid-step samples come from the cubic through
      samples k-1 … k+2 (see ``docs/attitude.md``);
    - ``"exp"``: exact when ``ω̂_k`` and ``â_k`` are held over the step (zero-order hold; order 1 on
      smooth motion): ``v += R Γ₁(ω̂h) â h + g h``, ``p += v h + R Γ₂(ω̂h) â h² + ½ g h²``.

    ``initial`` is the state at the first sample; ``bias`` (constant) is subtracted from the samples.
    Returns a :class:`Trajectory` with the IMU's timestamps (``t_ns`` kept when the IMU has it).

    ``frame``: an :class:`imukit.earth.LocalLevel`: the world is that Earth-fixed frame, turning at
    its Earth rate ``ω``: ``Ṙ = R[ω̂]× − [ω]×R``, ``v̇ = R â + g − 2ω×v`` with the frame's gravity
    (leave ``gravity`` at its default); ``docs/navigation.md``. With ``LocalLevel(...,
    transport=True)`` the frame follows the vehicle over the WGS-84 ellipsoid: ``initial.position``
    and the trajectory's positions are geodetic ``(latitude [rad], longitude [rad], height [m])``
    starting at the frame's latitude and height, velocities are in the local-level axes at the
    vehicle, the frame turns at ``ω_ie + ω_en`` (transport rate), Coriolis is
    ``(2ω_ie + ω_en) × v`` and gravity follows latitude and height; schemes ``"midpoint"``
    (default) and ``"rk4"`` only.

    ``body_from_sensor``: ``(R_bs, lever arm)``, a scipy ``Rotation`` and a (3,) offset [m]: the
    IMU's pose in the body frame (GTSAM's ``body_P_sensor``); the trajectory is then the body
    origin's. The readings become the body's, ``ω_b = R_bs (ω_s − b_g)``,
    ``a_b = R_bs (a_s − b_a) − α × r − ω_b × (ω_b × r)``, with the angular acceleration ``α`` the
    central difference of the gyro (one-sided at the ends); ``crates/imukit/src/extrinsics.rs``.

    Records over 65,537 samples in an inertial world (no ``frame``) run in parallel chunks: each
    chunk is integrated from rest without gravity and then started from the state the chunks
    before it reach (exact for every scheme, ``crates/imukit/src/strapdown/chunks.rs``); the result
    equals one sequential run to rounding (1e-12 relative) whatever the thread count.
    ``threads``: threads for this call (None: :func:`imukit.set_num_threads`'s setting), see
    :mod:`imukit.threads`.
    """
    count = checked(threads)
    b, g, scheme = _common(imu, initial, bias, gravity, scheme)
    g, rate = world_of(frame, g)
    gyro, accel, b, _ = _in_body(imu, b, body_from_sensor)
    if frame is not None and frame.transport:
        pv, quaternions = _core.ellipsoid_integrate(imu.seconds, gyro, accel, initial, b, frame, scheme)
    else:
        pv, quaternions = _core.strapdown_integrate(imu.seconds, gyro, accel, initial, b, g, scheme, rate, count)
    return _trajectory(imu, pv, quaternions)


def propagate(
    imu: ImuData,
    *,
    initial: NavState,
    covariance: ArrayLike,
    noise: ImuNoise,
    bias: ImuBias | None = None,
    gravity: ArrayLike = _DEFAULT_GRAVITY,
    scheme: str = _core.STRAPDOWN_DEFAULT_SCHEME,
    covariance_every: int = 1,
    body_from_sensor: tuple[Rotation, ArrayLike] | None = None,
    frame: LocalLevel | None = None,
) -> Trajectory:
    """:func:`integrate` plus the 15×15 error-state covariance (ESKF; Solà 2017, §5.4).

    Error state ``δx = [δp, δv, δθ, δb_a, δb_g]`` with the **right** (local) rotation perturbation
    ``R = R̂ Exp(δθ)`` and additive ``p = p̂ + δp``, ``v``, ``b`` alike. ``covariance`` is the
    initial 15×15 covariance in that order. Per step ``P ← F_x P F_xᵀ + F_i Q_i F_iᵀ`` with the exact
    Jacobians of the first-order step and ``Q_i = diag(σ_a² h, σ_g² h, σ_ba² h, σ_bg² h) ⊗ I₃`` from
    ``noise`` (continuous densities) and the actual step ``h``; the formulas are in
    ``docs/strapdown.md``. The covariance is kept at samples ``0, covariance_every, 2·covariance_every,
    …`` and at the last sample (``Trajectory.covariance`` with times ``covariance_t``), so memory stays
    bounded for long recordings.

    ``body_from_sensor``: ``(R_bs, r)``, as in :func:`integrate` (the same mean); the readings are
    turned into the body origin's with ``bias`` removed, so the covariance's bias blocks are in body
    axes (isotropic noise: the same densities). With a lever arm ``r ≠ 0`` the covariance carries
    the gyro noise the conversion puts into the specific force, the centripetal ``D(ω) w_k`` and
    the tangential ``[r]× (w_{k+1} − w_{k−1}) / (t_{k+1} − t_{k−1})`` (three samples, carried
    exactly by an augmented step), and the gyro-bias error through ``D(ω)``,
    ``D(ω) = −[ω×r]× − [ω]×[r]×``; ``docs/navigation.md``.

    ``frame``: a :class:`imukit.earth.LocalLevel`, as in :func:`integrate` (the same mean). A fixed
    frame adds the Coriolis term of the velocity error, ``−2h[ω]×`` in ``∂δv⁺/∂δv`` and
    ``−h²[ω]×`` in ``∂δp⁺/∂δv`` (the Earth's turn leaves the right attitude error unchanged). A
    frame that follows the vehicle (``transport=True``) takes the full local-level error model:
    ``δp`` is then ``(δφ, δλ, δh)`` (rad, rad, m), coupled through the radii of curvature, the
    transport rate and gravity's change with latitude and height (the Schuler loop and the
    vertical channel); ``docs/navigation.md``.
    """
    b, g, scheme = _common(imu, initial, bias, gravity, scheme)
    g, rate = world_of(frame, g)
    transport = frame if frame is not None and frame.transport else None
    if not isinstance(noise, ImuNoise):
        raise ParameterError(f"expected an imukit.ImuNoise, got {type(noise).__name__}", argument="noise")
    p0 = np.ascontiguousarray(as_float_array(covariance, "covariance"))
    if p0.shape != (15, 15):
        raise ShapeError(f"expected shape (15, 15), got {p0.shape}", argument="covariance")
    check_finite_rows(p0, "covariance", "row")
    try:
        every = operator.index(covariance_every)
    except TypeError:
        raise ParameterError(
            f"expected an integer ≥ 1, got {covariance_every!r}", argument="covariance_every"
        ) from None
    if every < 1 or isinstance(covariance_every, bool):
        raise ParameterError(f"expected an integer ≥ 1, got {covariance_every!r}", argument="covariance_every")
    n = len(imu)
    every = min(every, max(n - 1, 1))  # a stride past the end keeps the first and last samples
    gyro, accel, b, arm = _in_body(imu, b, body_from_sensor)
    pv, quaternions, covs = _core.strapdown_propagate(
        imu.seconds, gyro, accel, initial, p0, b, noise, g, scheme, every, rate, arm, transport
    )
    # Sorted and distinct by construction: numpy's `unique` (a hash table since 2.3) cost
    # ~1.7 µs a sample at `covariance_every=1`, more than the propagation itself.
    kept = np.arange(0, n, every)
    if kept[-1] != n - 1:
        kept = np.append(kept, n - 1)
    covs.setflags(write=False)
    return _trajectory(imu, pv, quaternions, covs.reshape(-1, 15, 15), readonly_copy(imu.t[kept]))
