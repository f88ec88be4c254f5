"""Spatial alignment of an estimate onto a reference: Sim(3) / SE(3) (Umeyama), yaw, translation."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from scipy.spatial.transform import Rotation

from imukit._arrays import FloatArray, choice
from imukit._errors import NonFiniteError, ParameterError, ShapeError
from imukit.eval._checks import check_trajectory
from imukit.state import Trajectory

METHODS = ("se3", "sim3", "position", "yaw", "none")

# Smallest accepted ratio of the second to the first singular value of the cross-covariance (se3,
# sim3) or of the horizontal correlation to the horizontal spreads (yaw): below it the rotation is
# not determined by the data (collinear or coincident points), and rounding alone would pick it.
_DEGENERATE = 1e-10


class Alignment(NamedTuple):
    """The similarity ``x ↦ scale · rotation · x + translation`` from estimate to reference world.

    ``rotation`` is a single scipy ``Rotation`` (a proper rotation, det +1), ``translation`` (3,)
    [m], ``scale`` > 0 (1 except for ``"sim3"``), ``method`` the name given to :func:`align`.
    """

    rotation: Rotation
    translation: FloatArray
    scale: float
    method: str

    def apply(self, trajectory: Trajectory) -> Trajectory:
        """``trajectory`` moved into the reference world: ``p' = s R p + t``, ``R_wb' = R R_wb``,
        ``v' = s R v`` (the time derivative of ``p'``: the scale applies to velocities too).

        Stamps and biases (body-frame quantities) are kept; covariances are not carried over.
        """
        traj = check_trajectory(trajectory, "trajectory")
        # row vectors times (s R)ᵀ; Rotation.apply refuses the trajectory's read-only arrays
        sr_t = self.scale * self.rotation.as_matrix().T
        return Trajectory(
            None if traj.t_ns is not None else traj.t,
            traj.position @ sr_t + self.translation,
            None if traj.velocity is None else traj.velocity @ sr_t,
            self.rotation * traj.rotation,
            t_ns=traj.t_ns,
            gyro_bias=traj.gyro_bias,
            accel_bias=traj.accel_bias,
        )


def identity(method: str = "none") -> Alignment:
    return Alignment(Rotation.identity(), np.zeros(3), 1.0, method)


def align(estimate: Trajectory, reference: Trajectory, *, method: str = "se3") -> Alignment:
    """The transform that best maps the estimate's positions onto the reference's, in least squares.

    Minimises ``Σ_i ‖y_i − (s R x_i + t)‖²`` over the allowed parameters, with ``x_i`` the
    estimate's and ``y_i`` the reference's positions, paired by index (run :func:`associate` first
    when the stamps differ). Orientations do not enter (as in evo and the TUM benchmark tools).

    Parameters
    ----------
    estimate, reference
        :class:`~imukit.Trajectory` objects of equal length N.
    method
        ``"se3"``: rotation + translation (Umeyama 1991 with ``s = 1``); the gauge of a stereo or
        absolute-position system. ``"sim3"``: also the scale ``s`` (monocular VO/SLAM, where scale is
        unobservable). ``"yaw"``: rotation about the world z axis + translation, the four
        unobservable directions of visual-inertial odometry (gravity fixes roll and pitch).
        ``"position"``: translation only, ``t = ȳ − x̄``. ``"none"``: the identity.

    Returns
    -------
    Alignment
        Apply it with :meth:`Alignment.apply`.

    Raises
    ------
    ParameterError
        ``"se3"`` / ``"sim3"`` with fewer than 3 points or collinear / coincident points (the
        rotation about their line is undetermined); ``"yaw"`` when the points have no horizontal
        spread. ShapeError when the lengths differ.
    """
    choice(method, "method", METHODS)
    est = check_trajectory(estimate, "estimate")
    ref = check_trajectory(reference, "reference")
    if len(est) != len(ref):
        raise ShapeError(
            f"expected equally long trajectories paired by index, got {len(est)} and {len(ref)} samples "
            "(associate them first: imukit.eval.associate)",
            argument="estimate / reference",
        )
    if method == "none":
        return identity()
    x, y = est.position, ref.position
    mean_x, mean_y = x.mean(axis=0), y.mean(axis=0)
    if method == "position":
        return Alignment(Rotation.identity(), mean_y - mean_x, 1.0, method)
    xc, yc = x - mean_x, y - mean_y
    if method == "yaw":
        rotation = _yaw(xc, yc)
        return Alignment(rotation, mean_y - rotation.apply(mean_x), 1.0, method)
    return _umeyama(xc, yc, mean_x, mean_y, with_scale=method == "sim3")


def _umeyama(xc: FloatArray, yc: FloatArray, mean_x: FloatArray, mean_y: FloatArray, *, with_scale: bool) -> Alignment:
    # Umeyama (1991), "Least-squares estimation of transformation parameters between two point
    # patterns", IEEE PAMI 13(4). For centred points the optimal t = ȳ − s R x̄ removes the means, and
    #   Σ‖yc − s R xc‖² = Σ‖yc‖² − 2 s tr(Rᵀ Σ_xy) n + s² n σx²,  Σ_xy = (1/n) Σ yc xcᵀ = U D Vᵀ.
    # Maximising tr(Rᵀ U D Vᵀ) over det R = +1 gives R = U S Vᵀ with S = diag(1, 1, det U det V): when
    # U Vᵀ is a reflection (det −1, e.g. a mirrored point set), the best *rotation* flips the axis of
    # the smallest singular value instead (Umeyama's eq. 39–43). Then setting ∂/∂s = 0:
    #   s = tr(D S) / σx²,  σx² = (1/n) Σ‖xc‖².
    n = len(xc)
    method = "sim3" if with_scale else "se3"
    if n < 3:
        raise ParameterError(
            f"{method} alignment needs at least 3 non-collinear positions, got {n}", argument="estimate"
        )
    # R is unchanged when xc and yc are divided by their scales a and b, and s becomes (b / a) s̃: the
    # products stay within float64 for positions from 1e-300 to 1e300 (1e154 overflowed the squares,
    # and LAPACK's SVD of an inf matrix ran for over 10 min; 1e-200 underflowed σx² to 0).
    a, b = (float(np.max(np.abs(c))) or 1.0 for c in (xc, yc))
    xc, yc = xc / a, yc / b
    u, d, vt = np.linalg.svd(yc.T @ xc / n)
    if not d[1] > _DEGENERATE * d[0]:
        raise ParameterError(
            f"{method} alignment needs at least 3 non-collinear positions; the "
            f"cross-covariance has singular values {d.tolist()} (collinear or coincident points leave "
            "the rotation about their line undetermined)",
            argument="estimate / reference",
        )
    s = np.array([1.0, 1.0, np.sign(np.linalg.det(u) * np.linalg.det(vt))])
    r = (u * s) @ vt
    scale = float(d @ s / np.mean(np.sum(xc * xc, axis=1))) * (b / a) if with_scale else 1.0
    with np.errstate(over="ignore", invalid="ignore"):  # refused below
        translation = mean_y - scale * r @ mean_x
    if not (np.isfinite(scale) and scale > 0.0 and np.isfinite(translation).all()):
        raise NonFiniteError(
            f"the {method} alignment (scale {scale!r}, translation {translation.tolist()}) is beyond float64: "
            f"the positions' spreads differ by a factor {b / a:.3g}",
            argument="estimate / reference",
        )
    return Alignment(Rotation.from_matrix(r), translation, scale, method)


def _yaw(xc: FloatArray, yc: FloatArray) -> Rotation:
    # With R = Rz(θ) (z untouched, so only horizontal components depend on θ):
    #   Σ ycᵀ Rz(θ) xc = cos θ Σ (xc_x yc_x + xc_y yc_y) + sin θ Σ (xc_x yc_y − xc_y yc_x) + const,
    # maximal at θ = atan2(B, A) with A, B the two sums.
    a = float(np.sum(xc[:, 0] * yc[:, 0] + xc[:, 1] * yc[:, 1]))
    b = float(np.sum(xc[:, 0] * yc[:, 1] - xc[:, 1] * yc[:, 0]))
    spread = float(np.sqrt(np.sum(xc[:, :2] ** 2) * np.sum(yc[:, :2] ** 2)))
    if not np.hypot(a, b) > _DEGENERATE * spread:  # also when spread = 0
        raise ParameterError(
            "yaw alignment needs positions with a horizontal spread that determines the heading (all points "
            "on one vertical line, or uncorrelated horizontally)",
            argument="estimate / reference",
        )
    return Rotation.from_rotvec([0.0, 0.0, np.arctan2(b, a)])
