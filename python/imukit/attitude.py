"""Gyro integration: ``integrate_attitude``.

Body rates in, a scipy ``Rotation`` per sample out (``R_wb``, body to world). The ODE is
``Ṙ = R [ω]×`` (body rates right-multiplied). Formulas, orders and the measured convergence
table are in ``docs/attitude.md``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike
from scipy.spatial.transform import Rotation

from imukit import _core
from imukit._arrays import (
    as_float_array,
    as_stamps,
    check_tail,
    flag,
    real_scalar,
    rotation_from_unit_quat,
)
from imukit._errors import ParameterError, ShapeError
from imukit._names import canonical
from imukit.threads import checked

__all__ = ["REPRESENTATIONS", "SCHEMES", "SCHEME_ALIASES", "integrate_attitude"]

#: The schemes, as the core lists them: ``("euler", "exp", "rk2", "rk4", "magnus")``.
SCHEMES: tuple[str, ...] = _core.ATTITUDE_SCHEMES
#: Deprecated scheme names and their canonical names: ``{"midpoint": "rk2"}``.
SCHEME_ALIASES: dict[str, str] = _core.ATTITUDE_SCHEME_ALIASES
#: The representations: ``("quaternion", "matrix", "euler")``.
REPRESENTATIONS: tuple[str, ...] = _core.ATTITUDE_REPRESENTATIONS


def integrate_attitude(
    t: ArrayLike,
    gyro: ArrayLike,
    *,
    initial: Rotation | None = None,
    scheme: str = _core.ATTITUDE_DEFAULT_SCHEME,
    representation: str = "quaternion",
    final_only: bool = False,
    gimbal_tolerance_rad: float = 1e-6,
    threads: int | None = None,
) -> Rotation:
    """Integrate body rates into attitudes ``R_wb``, one per sample.

    Parameters
    ----------
    t
        ``(N,)`` timestamps, strictly increasing, any spacing: float64 **seconds**, or integer
        **nanoseconds** (the dtype decides; EuRoC / ROS stamps can be passed as they are).
    gyro
        ``(N, 3)`` body angular rates [rad/s], sample k taken at ``t[k]``.
    initial
        Attitude at ``t[0]`` (a single ``Rotation``); identity when None.
    scheme
        Over a step ``h = t[k+1] - t[k]``:

        - ``"euler"``: forward Euler on the ODE with ``ω_k`` (order 1);
        - ``"exp"``: ``R ← R Exp(ω_k h)``, exact for a rate held over the step (order 1);
        - ``"rk2"``: explicit midpoint (second-order Runge-Kutta) on the ODE with
          ``(ω_k + ω_{k+1})/2`` (order 2). Formerly named ``"midpoint"``; that name still works
          but is deprecated (``DeprecationWarning``): in :func:`imukit.integrate` and
          preintegration ``"midpoint"`` is a different rule, ``Exp`` of the averaged rate;
        - ``"rk4"``: classical Runge-Kutta; the mid-step rate comes from the cubic through samples
          k-1 … k+2 (order 4 for smooth motion);
        - ``"magnus"``: ``R ← R Exp(½h(ω₁+ω₂) + (√3/12)h² ω₁×ω₂)`` with ω₁, ω₂ from the cubic at
          the Gauss nodes ``h(½ ∓ √3/6)`` (order 4; exact for constant rate).
    representation
        ``"quaternion"`` (renormalised), ``"matrix"`` (re-orthonormalised: after every step for the ODE
        schemes, every 16 steps for the exact-rotation ``exp``/``magnus``) or
        ``"euler"`` (ZYX angles through ``χ̇ = E(χ) ω``; ``euler``, ``rk2`` and ``rk4`` only;
        raises :class:`imukit.GimbalLockError` naming the sample where pitch comes within
        ``gimbal_tolerance_rad`` of ±90°).
    final_only
        Return only the attitude at ``t[-1]`` (a single ``Rotation``).
    threads
        ``threads``: threads for this call (None: :func:`imukit.set_num_threads`'s setting), see :mod:`imukit.threads`.

    Returns
    -------
    Rotation
        Length N (element 0 is ``initial``, element k the attitude at ``t[k]``), or a single
        rotation with ``final_only``.
    """
    scheme = canonical(scheme, "scheme", SCHEMES, SCHEME_ALIASES)
    representation = canonical(representation, "representation", REPRESENTATIONS)
    seconds = as_stamps(t).seconds
    rates = as_float_array(gyro, "gyro")
    check_tail(rates, "gyro", (3,))
    if rates.shape != (len(seconds), 3):
        raise ShapeError(f"expected shape (N, 3) with N = len(t) = {len(seconds)}, got {rates.shape}", argument="gyro")
    if initial is None:
        start = np.array([0.0, 0.0, 0.0, 1.0])
    elif isinstance(initial, Rotation) and initial.single:
        start = initial.as_quat()
    else:
        raise ParameterError(f"expected a single scipy Rotation or None, got {initial!r}", argument="initial")
    tolerance = real_scalar(
        gimbal_tolerance_rad,
        "gimbal_tolerance_rad",
        what="an angle in [0, π/2) radians",
        accept=lambda x: 0.0 <= x < np.pi / 2,
    )
    count = checked(threads)
    final = flag(final_only, "final_only")
    out = _core.attitude_integrate(
        seconds, np.ascontiguousarray(rates), start, scheme, representation, tolerance, final, count
    )
    return rotation_from_unit_quat(out[0] if final else out)
