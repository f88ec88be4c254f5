"""IMU simulation with an exact truth: ``imukit.sim.simulate(trajectory, *, rate, duration, ...)``.

Trajectories have closed-form position, velocity, acceleration, attitude and body rate, so the ideal
readings are exact: body rate from the attitude's analytic derivative, specific force
``R_wbᵀ (a − g)``. Noise-free integration therefore reproduces the truth to the integrator's own
error (``docs/simulation.md``).

=====================  ======================================================================
``Static``             at rest at ``position`` with ``rotation``
``ConstantTwist``      constant body rate and body-frame velocity (a screw): ``R₀ Exp(ωt)``
``Circle``, ``Helix``  horizontal circle (climbing at ``climb_rate``), facing along the motion
``FigureEight``        ``(A sin Ωt, B sin 2Ωt, C sin 2Ωt)``, heading along the path, banking and pitching
``VioEllipse``         the VIO teaching trajectory (ellipse, sinusoidal height and attitude)
``Waypoints``          C² cubic spline through timed positions, C² rotation spline through attitudes
=====================  ======================================================================

The sensor model (per triad, ``docs/simulation.md``): ``m = Q(S(T u + b + n))`` with white noise
``n`` of density σ discretised with the actual step (``σ/√Δt``), bias ``b`` = constant
(``ImuBias``) + turn-on + random walk (``σ_w √Δt`` per step) + first-order Gauss–Markov, scale
factor and misalignment ``T``, saturation ``S`` and quantisation ``Q`` (:class:`SensorErrors`).
Seeded: the same seed gives the same output, whatever the number of cores.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, ClassVar, Literal, Union, cast

import numpy as np
from numpy.typing import ArrayLike
from scipy.spatial.transform import Rotation, RotationSpline

from imukit import _core
from imukit._arrays import (
    FloatArray,
    as_float_array,
    check_finite_rows,
    choice,
    real_scalar,
    rotation_from_unit_quat,
    vector3,
)
from imukit._errors import DTypeError, NonFiniteError, ParameterError, ShapeError
from imukit._extrinsics import sensor_pose
from imukit.earth import LocalLevel, world_of
from imukit.imu import GRAVITY, ImuBias, ImuData, ImuNoise
from imukit.state import Trajectory
from imukit.threads import checked

__all__ = [
    "Circle",
    "ConstantTwist",
    "FigureEight",
    "Helix",
    "Motion",
    "SensorErrors",
    "Static",
    "VioEllipse",
    "Waypoints",
    "simulate",
]

_MAX_SAMPLES = 2**31  # 5 arrays of (n, 3) float64 already need 240 GB


def _finite(value: object, name: str) -> float:
    return real_scalar(value, name, what="a finite number", accept=math.isfinite)


def _single(r: Rotation, name: str) -> Rotation:
    if not (isinstance(r, Rotation) and r.single):
        raise ParameterError(f"expected a single scipy Rotation, got {r!r}", argument=name)
    return r


# How a motion field is checked, by its annotation: float64 3-vectors, finite floats, one rotation.
_CHECKS: dict[str, Callable[[Any, str], Any]] = {"ArrayLike": vector3, "float": _finite, "Rotation": _single}


class _ClosedForm:
    """A motion evaluated in the compiled core, which reads its fields by name (every subclass is a
    frozen dataclass, its kind a name the core parses)."""

    _kind: ClassVar[Literal["static", "constant_twist", "helix", "figure_eight", "vio_ellipse"]]

    def _truth(self, t: FloatArray, gravity: FloatArray, threads: int | None) -> tuple[FloatArray, ...]:
        motion = cast("Static | ConstantTwist | Helix | FigureEight | VioEllipse", self)
        checked = {f.name: _CHECKS[str(f.type)](getattr(motion, f.name), f.name) for f in dataclasses.fields(motion)}
        return _core.sim_motion(self._kind, dataclasses.replace(motion, **checked), t, [*gravity], threads)


@dataclass(frozen=True)
class Static(_ClosedForm):
    """At rest at ``position`` [m] with attitude ``rotation`` (``R_wb``)."""

    position: ArrayLike = (0.0, 0.0, 0.0)
    rotation: Rotation = field(default_factory=Rotation.identity)
    _kind = "static"


@dataclass(frozen=True)
class ConstantTwist(_ClosedForm):
    """Constant ``body_rate`` ω [rad/s] and ``body_velocity`` v_b [m/s] (body frame): a screw motion,
    ``R(t) = R₀ Exp(ωt)``, ``p(t) = p₀ + R₀ J_l(ωt) v_b t``, ``a = R [ω]× v_b``."""

    body_velocity: ArrayLike = (1.0, 0.0, 0.0)
    body_rate: ArrayLike = (0.0, 0.0, 0.2)
    position: ArrayLike = (0.0, 0.0, 0.0)
    rotation: Rotation = field(default_factory=Rotation.identity)
    _kind = "constant_twist"


@dataclass(frozen=True)
class Helix(_ClosedForm):
    """``center + (r cos Ωt, r sin Ωt, climb_rate·t)``; body x along the horizontal velocity, z up."""

    radius: float = 5.0
    angular_rate: float = 0.5
    climb_rate: float = 0.2
    center: ArrayLike = (0.0, 0.0, 1.0)
    _kind = "helix"


@dataclass(frozen=True)
class Circle(Helix):
    """A :class:`Helix` that does not climb."""

    climb_rate: float = 0.0


@dataclass(frozen=True)
class FigureEight(_ClosedForm):
    """``center + (A sin Ωt, B sin 2Ωt, C sin 2Ωt)`` with ``amplitude = (A, B, C)`` [m], one eight every
    2π/Ω s; yaw along the horizontal velocity, roll ``roll·sin 2Ωt``, pitch ``pitch·sin Ωt`` [rad]."""

    amplitude: ArrayLike = (10.0, 5.0, 1.0)
    angular_rate: float = 2 * math.pi / 30.0
    roll: float = 0.3
    pitch: float = 0.2
    center: ArrayLike = (0.0, 0.0, 2.0)
    _kind = "figure_eight"


@dataclass(frozen=True)
class VioEllipse(_ClosedForm):
    """The VIO teaching trajectory (He Yijia's ``vio_data_simulation``): ``center + (a cos Kt, b sin Kt,
    c sin K₁Kt)``, yaw ``Kt``, pitch ``pitch·sin t``, roll ``roll·cos t``; its defaults."""

    amplitude: ArrayLike = (15.0, 20.0, 1.0)
    angular_rate: float = math.pi / 10.0
    height_frequency: float = 10.0
    roll: float = 0.1
    pitch: float = 0.2
    center: ArrayLike = (5.0, 5.0, 5.0)
    _kind = "vio_ellipse"


class Waypoints:
    """A smooth trajectory through timed waypoints: a C² cubic spline in position (scipy
    ``CubicSpline``, ``bc_type`` as there; default ``"clamped"``: at rest at both ends) and a C² cubic
    rotation spline in attitude (scipy ``RotationSpline``). Derivatives are the splines' analytic ones:
    velocity and acceleration, and the body rate ``R_wbᵀ Ṙ_wb``.

    ``times`` (M,) strictly increasing seconds, ``positions`` (M, 3) [m], ``rotations`` a scipy
    ``Rotation`` of length M (``R_wb``), M ≥ 2; simulate within ``[times[0], times[-1]]``.
    """

    def __init__(
        self,
        times: ArrayLike,
        positions: ArrayLike,
        rotations: Rotation,
        *,
        bc_type: Literal["not-a-knot", "clamped", "natural", "periodic"] = "clamped",
    ) -> None:
        if np.issubdtype(np.asarray(times).dtype, np.integer):
            raise DTypeError(
                "integer times are nanoseconds elsewhere in imukit (ImuData, Trajectory), but a spline "
                "runs in seconds: pass float seconds (times_ns / 1e9)",
                argument="times",
            )
        choice(bc_type, "bc_type", ("not-a-knot", "clamped", "natural", "periodic"))
        t = as_float_array(times, "times")
        if t.ndim != 1 or len(t) < 2 or not np.all(np.diff(t) > 0):
            raise ParameterError(f"expected (M,) strictly increasing seconds, M ≥ 2, got {t!r}", argument="times")
        check_finite_rows(t, "times")
        p = as_float_array(positions, "positions")
        if p.shape != (len(t), 3):
            raise ShapeError(
                f"expected shape (M, 3) with M = len(times) = {len(t)}, got {p.shape}", argument="positions"
            )
        check_finite_rows(p, "positions")
        if bc_type == "periodic" and not np.array_equal(p[0], p[-1]):
            raise ParameterError(
                f"'periodic' needs the last position equal to the first, got {p[0].tolist()} and {p[-1].tolist()}",
                argument="bc_type",
            )
        if not isinstance(rotations, Rotation) or rotations.single or len(rotations) != len(t):
            raise ShapeError(f"expected a scipy Rotation of length M = len(times) = {len(t)}", argument="rotations")
        self.times = t
        # scipy.interpolate is imported here: at the top it was 0.2 s of every `import imukit`.
        from scipy.interpolate import CubicSpline

        # Steps that are positive but tiny next to the span (1e-300 s) overflow the splines' 1/h³
        # terms: scipy then raised its own ValueError ("array must not contain infs or NaNs").
        try:
            with np.errstate(over="raise", divide="raise", invalid="raise"):
                self._position = CubicSpline(t, p, bc_type=bc_type)
                self._rotation = RotationSpline(t, rotations)
        except (FloatingPointError, ValueError, np.linalg.LinAlgError):
            steps = np.diff(t)
            raise ParameterError(
                f"steps from {steps.min():.3g} s to {steps.max():.3g} s cannot be fitted by a spline "
                "(its coefficients overflow): space the waypoints more evenly",
                argument="times",
            ) from None

    def _truth(self, t: FloatArray, gravity: FloatArray, threads: int | None) -> tuple[FloatArray, ...]:
        del threads  # scipy's splines run on the calling thread
        if t[0] < self.times[0] or t[-1] > self.times[-1]:
            raise ParameterError(
                f"the waypoints span [{self.times[0]}, {self.times[-1]}] s, the simulation [{t[0]}, {t[-1]}] s",
                argument="duration",
            )
        try:
            rot = self._rotation(t)
        except ValueError as e:  # scipy: the spline's rotation vectors overflowed
            raise NonFiniteError(f"times / rotations: the rotation spline cannot be evaluated ({e})") from None
        accel = self._position(t, 2)
        specific_force = rot.inv().apply(accel - gravity)
        truth = (
            self._position(t),
            self._position(t, 1),
            rot.as_quat(),
            np.ascontiguousarray(self._rotation(t, 1)),  # scipy's rate is body-frame: R(t)ᵀ Ṙ(t)
            specific_force,
        )
        # A sum is finite when every element is (one pass, no temporary); only when it is not, look
        # closer: huge finite values can overflow the sum (inf − inf warns: silenced, it is the test).
        with np.errstate(over="ignore", invalid="ignore"):
            if not all(np.isfinite(a.sum()) or np.isfinite(a).all() for a in truth):
                raise NonFiniteError("the motion is beyond float64", argument="trajectory")
        return truth


def _parameter_names(motion: object) -> list[str]:
    if dataclasses.is_dataclass(motion):
        return [f.name for f in dataclasses.fields(motion)]
    return ["times", "positions", "rotations"]


def _motion_error(motion: object, message: str) -> NonFiniteError:
    """The core's error about the track it computed, put on the motion's parameters (which the user set)."""
    return NonFiniteError(message, argument=" / ".join(_parameter_names(motion)))


Motion = Union[Static, ConstantTwist, Helix, FigureEight, VioEllipse, Waypoints]
"""Every trajectory :func:`simulate` accepts."""


# The core's perfect triad (its SensorModel::default()): the defaults of SensorErrors.
_PERFECT = _core.sim_sensor_default()


@dataclass(frozen=True)
class SensorErrors:
    """Errors of one triad beyond white noise, random walk and constant bias (``ImuNoise``, ``ImuBias``).

    ``matrix`` 3×3 scale factor and misalignment ``T`` (reading ``T u``; identity: none; see
    :meth:`from_scale_misalignment`); ``turn_on_sigma`` std of a bias drawn once per run;
    ``gauss_markov_sigma`` / ``gauss_markov_tau`` [s] stationary std and correlation time of a
    first-order Gauss–Markov bias; ``range`` saturation (readings clamped to ±range); ``resolution``
    quantisation step (readings rounded to multiples). Units are the sensor's (rad/s or m/s²).
    """

    matrix: ArrayLike = tuple(map(tuple, _PERFECT["matrix"]))
    turn_on_sigma: float = _PERFECT["turn_on_sigma"]
    gauss_markov_sigma: float = _PERFECT["gauss_markov_sigma"]
    gauss_markov_tau: float = _PERFECT["gauss_markov_tau"]
    range: float = _PERFECT["range"]
    resolution: float = _PERFECT["resolution"]

    def __post_init__(self) -> None:
        # Stored as the floats they were checked as: the core reads these attributes by name.
        for name in ("turn_on_sigma", "gauss_markov_sigma", "resolution"):
            what = "a finite, non-negative number"
            x = real_scalar(getattr(self, name), name, what=what, accept=lambda x: math.isfinite(x) and x >= 0)
            object.__setattr__(self, name, x)
        for name in ("gauss_markov_tau", "range"):
            x = real_scalar(getattr(self, name), name, what="a positive number (inf for none)", accept=lambda x: x > 0)
            object.__setattr__(self, name, x)
        if self._full_scale() == 0.0:
            raise ParameterError(
                f"resolution / range: a step of {self.resolution!r} rounds the range {self.range!r} "
                "(and so every reading) to 0"
            )
        matrix = as_float_array(self.matrix, "matrix")
        if matrix.shape != (3, 3):
            raise ShapeError(f"expected shape (3, 3), got {matrix.shape}", argument="matrix")
        check_finite_rows(matrix, "matrix", "row")

    @classmethod
    def from_scale_misalignment(cls, scale: ArrayLike, misalignment: ArrayLike, **kwargs: float) -> SensorErrors:
        """``T = (I + diag(scale)) (I + M)``: ``scale`` (3,) relative scale-factor errors, ``misalignment``
        (3, 3) small non-orthogonality angles [rad] off the diagonal (the diagonal must be zero)."""
        s = vector3(scale, "scale")
        m = as_float_array(misalignment, "misalignment")
        if m.shape != (3, 3) or np.any(np.diag(m) != 0.0):
            raise ShapeError(f"expected a (3, 3) matrix with a zero diagonal, got {m!r}", argument="misalignment")
        check_finite_rows(m, "misalignment", "row")
        return cls(matrix=(np.eye(3) + np.diag(s)) @ (np.eye(3) + m), **kwargs)

    def _full_scale(self) -> float | None:
        """The largest magnitude the triad reports: ``range`` quantised as the core quantises
        readings (to the nearest multiple of ``resolution``, halves away from zero); None without
        saturation."""
        limit, step = float(self.range), float(self.resolution)
        if math.isinf(limit) or step == 0.0:
            return None if math.isinf(limit) else limit
        steps = limit / step
        if math.isinf(steps):  # a step too fine to count: the core reports the overflow it causes
            return limit
        whole = math.floor(steps)
        return (whole + (1.0 if steps - whole >= 0.5 else 0.0)) * step


# Fourth-order first-derivative stencils on nodes t + jδ: central (j = −2…2) and, within 2δ of the
# end of a motion with a span (Waypoints), one-sided (j = 0…4 forward, −4…0 backward; Fornberg 1988,
# the weights of the derivative on five equispaced nodes).
_STENCILS = {
    "central": (range(-2, 3), (1.0, -8.0, 0.0, 8.0, -1.0)),
    "forward": (range(0, 5), (-25.0, 48.0, -36.0, 16.0, -3.0)),
    "backward": (range(-4, 1), (3.0, -16.0, 36.0, -48.0, 25.0)),
}


def _angular_acceleration(
    trajectory: Motion, t: FloatArray, g: FloatArray, count: int | None, rotating: list[float] | None
) -> FloatArray:
    """The body's angular acceleration in body axes at ``t``: a fourth-order stencil over
    δ = 1 ms, central (``(ω(t−2δ) − 8ω(t−δ) + 8ω(t+δ) − ω(t+2δ)) / 12δ``) or, within 2δ of a
    waypoint span's ends, one-sided, on the ideal gyro readings (the rotating world's rate included
    when ``rotating`` is given)."""
    delta = 1e-3

    def rate(at: FloatArray) -> FloatArray:
        _, velocity, quat, gyro, accel = trajectory._truth(at, g, count)
        if rotating is not None:
            _core.sim_rotating_world(rotating, quat, velocity, gyro, accel)
        return gyro

    lo, hi = (trajectory.times[0], trajectory.times[-1]) if isinstance(trajectory, Waypoints) else (-np.inf, np.inf)
    forward, backward = t - 2 * delta < lo, t + 2 * delta > hi
    alpha = np.empty((len(t), 3))
    for name, rows in (
        ("central", ~(forward | backward)),
        ("forward", forward),
        ("backward", backward & ~forward),
    ):
        if rows.any():
            nodes, weights = _STENCILS[name]
            at = t[rows]
            alpha[rows] = sum(w * rate(at + j * delta) for j, w in zip(nodes, weights) if w != 0.0) / (12 * delta)
    return alpha


def simulate(
    trajectory: Motion,
    *,
    rate: float,
    duration: float,
    noise: ImuNoise | None = None,
    bias: ImuBias | None = None,
    gyro_errors: SensorErrors | None = None,
    accel_errors: SensorErrors | None = None,
    gravity: ArrayLike = GRAVITY,
    seed: int = 0,
    start: float = 0.0,
    threads: int | None = None,
    frame: LocalLevel | None = None,
    body_from_sensor: tuple[Rotation, ArrayLike] | None = None,
) -> tuple[ImuData, Trajectory]:
    """Simulate ``trajectory`` at ``rate`` [Hz] for ``duration`` [s] from time ``start``: samples
    ``t_k = start + k / rate``, ``k = 0 … floor(duration·rate)``. Returns the readings as
    :class:`imukit.ImuData` (float seconds) and the truth as :class:`imukit.Trajectory` with the
    true biases (``gyro_bias``, ``accel_bias``) at every sample. Without ``noise``, ``bias`` and
    errors, the readings are the exact ideal ones. A finite ``SensorErrors.range`` becomes the
    ImuData's ``gyro_range`` / ``accel_range``, so the clipped samples are flagged
    (``ImuData.gyro_saturated``, ``accel_saturated``). ``gravity`` is the world-frame ``g`` [m/s²] in
    ``R_wbᵀ (a − g)``, by default :data:`imukit.GRAVITY`.

    ``frame``: an :class:`imukit.earth.LocalLevel`: the trajectory is given in that Earth-fixed
    frame, so the gyro also reads the Earth rate ``R_wbᵀ ω_ie`` and the accelerometer
    ``R_wbᵀ (a − g + 2 ω_ie × v)`` with the frame's gravity (leave ``gravity`` at its default).
    With ``LocalLevel(..., transport=True)`` the trajectory is flown over the WGS-84 ellipsoid from
    the frame's latitude and height (longitude 0): its velocity, acceleration and attitude are read
    in the local-level frame at the vehicle, its height changes with its up (NED: −down) position;
    the gyro reads ``ω_nb + R_nbᵀ (ω_ie + ω_en)`` and the accelerometer
    ``R_nbᵀ (v̇ − g(φ, h) + (2 ω_ie + ω_en) × v)``, and the truth's positions are geodetic
    ``(latitude, longitude, height)`` (latitude and longitude by RK4 on the exact velocities).

    ``body_from_sensor``: ``(R_bs, lever arm)`` (a scipy ``Rotation`` and (3,) [m], as in
    :func:`imukit.integrate`): the readings are those of a sensor at that pose on the simulated
    body, ``ω_s = R_bsᵀ ω_b``, ``f_s = R_bsᵀ (f_b + α × r + ω × (ω × r))``, with the body's angular
    acceleration ``α`` from the trajectory's closed-form rate (the frame's rate included) by the
    fourth-order central stencil over ±1 ms, ±2 ms (one-sided within 2 ms of a ``Waypoints``
    span's ends; truncation ~1e-13 rad/s² for rates that vary on second scales); the truth stays
    the body's. Not with a frame that follows the vehicle.

    ``threads``: threads for this call (None: :func:`imukit.set_num_threads`'s setting), see :mod:`imukit.threads`.
    """
    rate_hz = real_scalar(
        rate, "rate", what="a positive, finite rate in Hz", accept=lambda x: math.isfinite(x) and x > 0
    )
    what = "at least one sample interval (1 / rate)"
    span = real_scalar(
        duration, "duration", what=what, accept=lambda x: math.isfinite(x * rate_hz) and x * rate_hz >= 1
    )
    begin = _finite(start, "start")
    count = checked(threads)
    if not isinstance(seed, int) or isinstance(seed, bool) or not 0 <= seed < 2**64:
        raise ParameterError(f"expected an int in [0, 2**64), got {seed!r}", argument="seed")
    for name, value, kind, shown in (
        ("gyro_errors", gyro_errors, SensorErrors, "imukit.sim.SensorErrors"),
        ("accel_errors", accel_errors, SensorErrors, "imukit.sim.SensorErrors"),
        ("noise", noise, ImuNoise, "imukit.ImuNoise"),
        ("bias", bias, ImuBias, "imukit.ImuBias"),
    ):
        if value is not None and not isinstance(value, kind):
            raise ParameterError(f"expected an {shown} or None, got {type(value).__name__}", argument=name)
    world_g, rotating = world_of(frame, [float(v) for v in vector3(gravity, "gravity")])
    g = np.asarray(world_g)
    n = math.floor(span * rate_hz + 1e-9) + 1
    if n > _MAX_SAMPLES:
        raise ParameterError(
            f"{duration!r} s at {rate_hz!r} Hz is {n} samples, more than {_MAX_SAMPLES}", argument="duration"
        )
    # In place: fresh 8-byte-per-sample temporaries cost more than the arithmetic. From 0, k / rate
    # rises strictly for every k ≤ _MAX_SAMPLES: consecutive quotients differ by 1/k relative, far
    # above the 2^-52 of their rounding.
    t = np.arange(n, dtype=np.float64)
    t /= rate_hz
    if begin != 0.0:
        t += begin
        if not np.all(t[1:] > t[:-1]):
            raise ParameterError(
                f"{start!r} s is too large for steps of 1 / rate = {1 / rate_hz!r} s to show", argument="start"
            )
    moving = frame if frame is not None and frame.transport else None
    try:
        # The core checks its values as it writes them (no pass of its own); Waypoints checks here.
        position, velocity, quat, gyro, accel = trajectory._truth(t, np.zeros(3) if moving is not None else g, count)
    except NonFiniteError as exc:
        if exc.argument != "trajectory":
            raise
        over = f"[{float(t[0])!r}, {float(t[-1])!r}] s"
        raise _motion_error(trajectory, f"the motion is beyond float64 over {over}") from exc
    if moving is not None:
        mid_position, mid_velocity, *_ = trajectory._truth(0.5 * (t[1:] + t[:-1]), np.zeros(3), count)
        origin = [moving.latitude, 0.0, moving.height]
        try:
            position = _core.sim_ellipsoid(
                moving.axes, origin, t, position, velocity, mid_position, mid_velocity, quat, gyro, accel
            )
        except NonFiniteError as exc:  # the core names the track; the user set the motion's parameters
            if exc.argument != "trajectory":
                raise
            at = float(t[exc.index or 0])
            raise _motion_error(trajectory, f"the motion reaches a pole or overflows at {at!r} s") from exc
    elif frame is not None:
        _core.sim_rotating_world(rotating, quat, velocity, gyro, accel)
    if body_from_sensor is not None:
        if moving is not None:
            raise ParameterError(
                "a sensor pose with a frame that follows the vehicle is not supported yet", argument="body_from_sensor"
            )
        rows, arm = sensor_pose(body_from_sensor)
        alpha = _angular_acceleration(trajectory, t, g, count, rotating if frame is not None else None)
        _core.sim_sensor_pose(rows, list(arm), alpha, gyro, accel)
    n = len(t)
    bias_g, bias_a = np.zeros((n, 3)), np.zeros((n, 3))
    perfect = noise is None and bias is None and gyro_errors is None and accel_errors is None
    if not perfect:
        noise = noise or ImuNoise(0.0, 0.0, 0.0, 0.0)
        b = bias or ImuBias()
        # In place: gyro and accel are this call's own fresh arrays (and Waypoints' fresh results).
        bias_g = _core.sim_measure(
            t, gyro, gyro_errors or SensorErrors(), b.gyro, noise.gyro_density, noise.gyro_random_walk, seed, 0, count
        )
        bias_a = _core.sim_measure(
            t,
            accel,
            accel_errors or SensorErrors(),
            b.accel,
            noise.accel_density,
            noise.accel_random_walk,
            seed,
            1,
            count,
        )
    ranges = [None if e is None else e._full_scale() for e in (gyro_errors, accel_errors)]
    imu = ImuData._from_core(t, gyro, accel, *ranges)
    arrays = {"position": position, "velocity": velocity, "gyro_bias": bias_g, "accel_bias": bias_a}
    return imu, Trajectory._from_core(imu.t, None, arrays, rotation_from_unit_quat(quat))
