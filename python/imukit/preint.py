"""IMU preintegration: ``preintegrate``, ``preintegrate_windows`` and ``PreintegratedImu``.

=====================  ===========================================================================
deltas                 ``ΔR_ij`` (scipy ``Rotation``), ``Δv_ij``, ``Δp_ij`` in the body frame at i,
                       gravity-free; ``Δt_ij``
schemes                ``"midpoint"`` (default; VINS-Mono: averaged rates, specific forces rotated
                       at both ends of each interval), ``"euler"`` (Forster et al. T-RO 2017 and
                       GTSAM: sample k held over ``[t_k, t_k+1)``, exact rotation steps)
covariance             9×9 of ``[δθ, δv, δp]``, right perturbation ``ΔR = ΔR̂ Exp(δθ)``
bias Jacobian          9×6, rows ``[θ, v, p]``, columns ``[b_g, b_a]``
prediction             ``R_j = R_i ΔR``, ``v_j = v_i + g Δt + R_i Δv``, ``p_j = p_i + v_i Δt + ½ g Δt² + R_i Δp``
residual               ``[Log(ΔR̃ᵀ R_iᵀ R_j), R_iᵀ(v_j − v_i − g Δt) − Δṽ, R_iᵀ(p_j − p_i − v_i Δt − ½ g Δt²) − Δp̃]``
residual Jacobians     rows ``[θ, v, p]``; state columns ``[δp, δv, δθ]`` (imukit's NavState
                       perturbation: ``p + δp``, ``v + δv``, ``R Exp(δθ)``); bias columns ``[b_g, b_a]``
saturation             clipped samples (``ImuData.gyro_saturated`` / ``accel_saturated``) are
                       integrated as read (deltas unchanged) with that sensor's white-noise density
                       × ``saturation_noise_factor`` (default 100, as OKVIS): ``"euler"`` on the
                       interval the sample starts, ``"midpoint"`` on both intervals it bounds (an
                       interpolated window boundary is clipped if either neighbour is), so the
                       covariance grows and the factor's weight drops
=====================  ===========================================================================

Gravity is added as everywhere in imukit (default ``(0, 0, −9.81)``, z up). Formulas and the noise
model of each scheme: ``docs/preintegration.md`` and the module docs of ``crates/imukit/src/preint``.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike
from scipy.spatial.transform import Rotation

from imukit import _core, so3
from imukit._arrays import FloatArray, as_float_array, choice, real_scalar, seconds_from_ns, vector3
from imukit._errors import NonFiniteError, ParameterError, ShapeError
from imukit.imu import ImuBias, ImuData, ImuNoise
from imukit.state import NavState

__all__ = ["PreintegratedImu", "ResidualJacobians", "preintegrate", "preintegrate_windows"]

_SCHEMES = ("midpoint", "euler")
_MAX_THREADS = 4096  # a thread pool beyond this is a mistake (and past usize for huge ints)


def _flag(value: object, name: str) -> bool:
    """``value`` as a bool, else :class:`ParameterError` naming ``name`` (1 or "yes" are mistakes)."""
    if not isinstance(value, (bool, np.bool_)):
        raise ParameterError(f"{name}: expected a bool, got {value!r}")
    return bool(value)


class ResidualJacobians(NamedTuple):
    """Jacobians of :meth:`PreintegratedImu.residual`, rows ``[θ, v, p]``."""

    state_i: FloatArray
    """9×9, columns ``[δp_i, δv_i, δθ_i]``."""
    state_j: FloatArray
    """9×9, columns ``[δp_j, δv_j, δθ_j]``."""
    bias: FloatArray
    """9×6, columns ``[δb_g, δb_a]``."""


class _Measurement(NamedTuple):
    """One :meth:`PreintegratedImu.integrate_measurement` call, kept for :meth:`reintegrate`."""

    accel: FloatArray
    gyro: FloatArray
    dt: float
    gyro_saturated: bool
    accel_saturated: bool


class _Window(NamedTuple):
    """A window cut from ``imu`` by :func:`preintegrate_windows`, kept for :meth:`reintegrate`."""

    imu: ImuData
    lo: float
    hi: float


class PreintegratedImu:
    """Preintegrated IMU measurements between two keyframes i and j; see the module docs.

    Build it with :func:`preintegrate` or :func:`preintegrate_windows`, or empty and then feed it
    with :meth:`integrate_measurement` (one sample, GTSAM / VINS-Mono style) or :meth:`integrate`
    (a batch of samples).
    """

    def __init__(
        self,
        *,
        noise: ImuNoise,
        bias: ImuBias | None = None,
        gravity: ArrayLike = (0.0, 0.0, -9.81),
        scheme: str = "midpoint",
        combined: bool = False,
        saturation_noise_factor: float = 100.0,
    ) -> None:
        if not isinstance(noise, ImuNoise):
            raise ParameterError(f"noise: expected an imukit.ImuNoise, got {type(noise).__name__}")
        if bias is not None and not isinstance(bias, ImuBias):
            raise ParameterError(f"bias: expected an imukit.ImuBias or None, got {type(bias).__name__}")
        self.bias = bias or ImuBias()
        self.noise = noise
        self.gravity = vector3(gravity, "gravity")
        self.scheme = choice(scheme, "scheme", _SCHEMES)
        self.combined = bool(combined)
        self.saturation_noise_factor = real_scalar(
            saturation_noise_factor,
            "saturation_noise_factor",
            what="a finite factor ≥ 1",
            accept=lambda x: math.isfinite(x) and x >= 1.0,
        )
        self._core = _core.Preintegrator(
            self._bias_values(), self._noise_values(), self.combined, scheme, self.saturation_noise_factor
        )
        # What was integrated, in order, so that reintegrate() can replay it with another bias.
        self._inputs: list[ImuData | _Window | _Measurement] = []

    def _bias_values(self) -> list[float]:
        return [*self.bias.gyro, *self.bias.accel]

    def _noise_values(self) -> list[float]:
        n = self.noise
        return [n.gyro_density, n.accel_density, n.gyro_random_walk, n.accel_random_walk]

    def _like(self, core: _core.Preintegrator, inputs: list[ImuData | _Window | _Measurement]) -> PreintegratedImu:
        out = object.__new__(PreintegratedImu)
        out.bias, out.noise, out.gravity, out.scheme, out.combined, out.saturation_noise_factor = (
            self.bias,
            self.noise,
            self.gravity,
            self.scheme,
            self.combined,
            self.saturation_noise_factor,
        )
        out._core, out._inputs = core, inputs
        return out

    def integrate_measurement(
        self,
        accel: ArrayLike,
        gyro: ArrayLike,
        dt: float,
        *,
        gyro_saturated: bool = False,
        accel_saturated: bool = False,
    ) -> None:
        """Add one sample, ``accel`` [m/s²] and ``gyro`` [rad/s].

        ``"euler"``: the sample is held over the next ``dt`` seconds (GTSAM's
        ``integrateMeasurement``). ``"midpoint"``: the sample was taken ``dt`` seconds after the
        previous one (VINS-Mono's ``push_back``); the window's first sample comes with ``dt=0``.
        ``gyro_saturated`` / ``accel_saturated`` mark a sensor clipped at its range: its white-noise
        density is multiplied by ``saturation_noise_factor`` for this sample (module docs).
        """
        a, w = vector3(accel, "accel"), vector3(gyro, "gyro")
        step = real_scalar(dt, "dt", what="a step in seconds", accept=lambda x: True)
        flags = [_flag(gyro_saturated, "gyro_saturated"), _flag(accel_saturated, "accel_saturated")]
        self._core.integrate_measurement([*a], [*w], step, *flags)
        self._inputs.append(_Measurement(a, w, step, *flags))

    def integrate(self, imu: ImuData) -> None:
        """Add the N − 1 intervals between the samples of ``imu``, GIL released. In the midpoint
        scheme a batch after earlier samples must start with the last of them (consecutive windows
        share their boundary sample). Long euler batches (over 65,536 intervals, without
        ``combined``) run as fixed chunks on all cores, merged in order: equal to streaming to
        rounding (1e-12 relative) and independent of the core count."""
        if not isinstance(imu, ImuData):
            raise ParameterError(f"imu: expected an imukit.ImuData, got {type(imu).__name__}")
        self._core.integrate(imu.seconds, imu.gyro, imu.accel, imu.gyro_saturated, imu.accel_saturated)
        self._inputs.append(imu)

    def reintegrate(self, bias: ImuBias) -> PreintegratedImu:
        """A new preintegration of the same samples with ``bias``: exact, where :meth:`corrected` is
        first order. Its error grows with the square of the bias change; VINS-Mono re-integrates when
        the change exceeds 0.01 rad/s (gyro) or 0.1 m/s² (accelerometer), a sensible default
        threshold for 200 Hz windows of about 0.5 s.
        """

        def empty() -> PreintegratedImu:
            return _empty(self.noise, bias, self.gravity, self.scheme, self.combined, self.saturation_noise_factor)

        out = empty()
        for item in self._inputs:
            if isinstance(item, _Window):
                # A window starts from an empty preintegration; after a merge it may follow other
                # inputs, so it is preintegrated on its own and merged on, as merge() did.
                (piece,) = _windows(item.imu, [item.lo, item.hi], empty(), threads=0)
                out._core = out._core.merge(piece) if out._inputs else piece
                out._inputs.append(item)
            elif isinstance(item, ImuData):
                out.integrate(item)
            else:
                out.integrate_measurement(
                    item.accel,
                    item.gyro,
                    item.dt,
                    gyro_saturated=item.gyro_saturated,
                    accel_saturated=item.accel_saturated,
                )
        return out

    def merge(self, other: PreintegratedImu) -> PreintegratedImu:
        """This preintegration (i → j) followed by ``other`` (j → k) as one (i → k), covariance and
        bias Jacobian included. Both need the same scheme, bias, noise, saturation noise factor and
        gravity; in the midpoint scheme ``other`` starts with this one's last sample. The bias random
        walk is not merged: the result has no ``covariance_combined``."""
        if not isinstance(other, PreintegratedImu):
            raise ParameterError(f"other: expected an imukit.PreintegratedImu, got {type(other).__name__}")
        if not np.array_equal(self.gravity, other.gravity):
            raise ParameterError("other: expected the same gravity")
        merged = self._like(self._core.merge(other._core), self._inputs + other._inputs)
        merged.combined = False
        return merged

    def _state(self) -> tuple[FloatArray, FloatArray, FloatArray, float, FloatArray, FloatArray]:
        return self._core.state()

    @property
    def delta_rotation(self) -> Rotation:
        """``ΔR_ij``."""
        return Rotation.from_matrix(self._state()[0])

    @property
    def delta_velocity(self) -> FloatArray:
        """``Δv_ij`` [m/s], gravity-free, frame i."""
        return self._state()[1]

    @property
    def delta_position(self) -> FloatArray:
        """``Δp_ij`` [m], gravity-free, frame i."""
        return self._state()[2]

    @property
    def delta_t(self) -> float:
        """``Δt_ij`` [s]."""
        return self._state()[3]

    @property
    def covariance(self) -> FloatArray:
        """9×9 covariance of ``[δθ, δv, δp]``."""
        return self._state()[4]

    @property
    def covariance_combined(self) -> FloatArray | None:
        """15×15 covariance of ``[δθ, δv, δp, δb_g, δb_a]`` including the bias random walk between i
        and j (``ImuNoise`` random-walk densities); None unless built with ``combined=True``."""
        return self._core.covariance_combined()

    @property
    def bias_jacobian(self) -> FloatArray:
        """9×6 ``∂(θ, v, p)/∂(b_g, b_a)``."""
        return self._state()[5]

    def _bias_change(self, bias: ImuBias) -> FloatArray:
        if not isinstance(bias, ImuBias):
            raise ParameterError(f"bias: expected an imukit.ImuBias, got {type(bias).__name__}")
        return np.concatenate([bias.gyro - self.bias.gyro, bias.accel - self.bias.accel])

    def corrected(self, bias: ImuBias) -> tuple[Rotation, FloatArray, FloatArray]:
        """Deltas for ``bias`` to first order, without re-integration (rotation right-applied):
        ``ΔR Exp(J_θ δb_g)``, ``Δv + J_v δb``, ``Δp + J_p δb`` with ``δb = bias − integration bias``."""
        r, v, p, _, _, jac = self._state()
        d = jac @ self._bias_change(bias)
        if not (np.isfinite(d).all() and np.isfinite(np.linalg.norm(d))):
            raise NonFiniteError(f"bias: too far from the integration bias to correct for: J δb = {d.tolist()}")
        return Rotation.from_matrix(r) * Rotation.from_rotvec(d[0:3]), v + d[3:6], p + d[6:9]

    def _deltas(self, bias: ImuBias | None) -> tuple[Rotation, FloatArray, FloatArray, float]:
        """``(ΔR, Δv, Δp, Δt)``, corrected to ``bias`` when given, from one read of the core state."""
        if bias is not None:
            return (*self.corrected(bias), self.delta_t)
        r, v, p, dt, _, _ = self._state()
        return Rotation.from_matrix(r), v, p, dt

    def predict(self, state_i: NavState, bias: ImuBias | None = None) -> NavState:
        """The state at j from the state at i (deltas corrected to ``bias`` when given)."""
        dr, dv, dp, dt = self._deltas(bias)
        g, r_i = self.gravity, state_i.rotation
        return NavState(
            state_i.position + state_i.velocity * dt + 0.5 * g * dt * dt + r_i.apply(dp),
            state_i.velocity + g * dt + r_i.apply(dv),
            r_i * dr,
        )

    def _residual_parts(
        self, state_i: NavState, state_j: NavState, bias: ImuBias | None
    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """The residual and the world-frame differences it rotates: ``(r, u_v, u_p, E)``."""
        dr, dv, dp, dt = self._deltas(bias)
        g, r_i = self.gravity, state_i.rotation
        u_v = state_j.velocity - state_i.velocity - g * dt
        u_p = state_j.position - state_i.position - state_i.velocity * dt - 0.5 * g * dt * dt
        e = dr.inv() * r_i.inv() * state_j.rotation
        r = np.concatenate([e.as_rotvec(), r_i.inv().apply(u_v) - dv, r_i.inv().apply(u_p) - dp])
        return r, u_v, u_p, e.as_matrix()

    def residual(self, state_i: NavState, state_j: NavState, bias: ImuBias | None = None) -> FloatArray:
        """``[Log(ΔR̃ᵀ R_iᵀ R_j), R_iᵀ(v_j − v_i − g Δt) − Δṽ, R_iᵀ(p_j − p_i − v_i Δt − ½ g Δt²) − Δp̃]``,
        the deltas corrected to ``bias`` when given (9,)."""
        return self._residual_parts(state_i, state_j, bias)[0]

    def residual_jacobians(
        self, state_i: NavState, state_j: NavState, bias: ImuBias | None = None
    ) -> ResidualJacobians:
        """Jacobians of :meth:`residual` (Forster et al. 2017, eqs. 44–45, in imukit's charts):
        w.r.t. state i and j (columns ``[δp, δv, δθ]``, ``R Exp(δθ)``) and the bias (``[δb_g, δb_a]``,
        through the first-order correction)."""
        r, u_v, u_p, e = self._residual_parts(state_i, state_j, bias)
        jac = self.bias_jacobian
        ri_t = state_i.rotation.inv().as_matrix()
        jr_inv = so3.right_jacobian_inv(r[0:3])
        dbg = np.zeros(3) if bias is None else self._bias_change(bias)[0:3]
        d_i, d_j, d_b = np.zeros((9, 9)), np.zeros((9, 9)), np.zeros((9, 6))
        # θ: E Exp(δθ_j) on the right; R_i Exp(δθ_i) enters as E Exp(−R_jᵀ R_i δθ_i).
        rj_t_ri = state_j.rotation.inv().as_matrix() @ state_i.rotation.as_matrix()
        d_i[0:3, 6:9] = -jr_inv @ rj_t_ri
        d_j[0:3, 6:9] = jr_inv
        d_b[0:3, 0:3] = -jr_inv @ e.T @ so3.right_jacobian(jac[0:3, 0:3] @ dbg) @ jac[0:3, 0:3]
        # v, p: R_iᵀ u with R_i Exp(δθ_i) gives +[R_iᵀ u]× δθ_i.
        d_i[3:6, 3:6], d_i[3:6, 6:9] = -ri_t, so3.hat(ri_t @ u_v)
        d_j[3:6, 3:6] = ri_t
        d_i[6:9, 0:3], d_i[6:9, 3:6], d_i[6:9, 6:9] = -ri_t, -ri_t * self.delta_t, so3.hat(ri_t @ u_p)
        d_j[6:9, 0:3] = ri_t
        d_b[3:9] = -jac[3:9]
        return ResidualJacobians(d_i, d_j, d_b)


def _empty(
    noise: ImuNoise,
    bias: ImuBias | None,
    gravity: ArrayLike,
    scheme: str,
    combined: bool,
    saturation_noise_factor: float,
) -> PreintegratedImu:
    """An empty :class:`PreintegratedImu` with the options of :func:`preintegrate`."""
    return PreintegratedImu(
        noise=noise,
        bias=bias,
        gravity=gravity,
        scheme=scheme,
        combined=combined,
        saturation_noise_factor=saturation_noise_factor,
    )


def preintegrate(
    imu: ImuData,
    *,
    noise: ImuNoise,
    bias: ImuBias | None = None,
    gravity: ArrayLike = (0.0, 0.0, -9.81),
    scheme: str = "midpoint",
    combined: bool = False,
    saturation_noise_factor: float = 100.0,
) -> PreintegratedImu:
    """Preintegrate all samples of ``imu`` (N samples → N − 1 intervals); see :class:`PreintegratedImu`.

    ``combined=True`` also tracks the 15×15 covariance with the bias random walk
    (``covariance_combined``), at about twice the cost per sample. Samples that ``imu`` flags as
    clipped (``gyro_saturated`` / ``accel_saturated``, from its ``gyro_range`` / ``accel_range``)
    have that sensor's white-noise density multiplied by ``saturation_noise_factor`` (finite, ≥ 1;
    1 ignores the flags); see the module docs for which intervals that covers.
    """
    pim = _empty(noise, bias, gravity, scheme, combined, saturation_noise_factor)
    pim.integrate(imu)
    return pim


def _seconds_of(imu: ImuData, boundaries: ArrayLike) -> FloatArray:
    """Boundary times on ``imu.seconds``' axis: same units as ``imu.t`` (integer ns or float s)."""
    raw = np.asarray(boundaries)
    if raw.ndim != 1:
        raise ShapeError(f"boundaries: expected shape (M,), got {raw.shape}")
    if raw.dtype.kind in "iu" and imu.t_ns is not None:
        return seconds_from_ns(raw.astype(np.int64) - imu.t_ns[0])
    seconds: FloatArray = as_float_array(raw, "boundaries") - imu.t[0]
    return seconds


def _windows(imu: ImuData, boundaries: ArrayLike, like: PreintegratedImu, *, threads: int) -> list[_core.Preintegrator]:
    b = np.ascontiguousarray(_seconds_of(imu, boundaries))
    return _core.preint_windows(
        imu.seconds,
        imu.gyro,
        imu.accel,
        imu.gyro_saturated,
        imu.accel_saturated,
        b,
        like._core,
        threads,
    )


def preintegrate_windows(
    imu: ImuData,
    boundaries: ArrayLike,
    *,
    noise: ImuNoise,
    bias: ImuBias | None = None,
    gravity: ArrayLike = (0.0, 0.0, -9.81),
    scheme: str = "midpoint",
    combined: bool = False,
    saturation_noise_factor: float = 100.0,
    threads: int | None = None,
) -> list[PreintegratedImu]:
    """One :class:`PreintegratedImu` per window ``[boundaries[m], boundaries[m+1]]`` (M times → M − 1
    windows), in one call, the windows in parallel on ``threads`` threads (default: all cores), GIL
    released.

    ``boundaries`` (M,) are times on ``imu.t``'s clock (integer ns for integer stamps), strictly
    increasing, within the samples' span. A boundary between two samples is a point of the scheme's
    signal model: the held sample in ``"euler"`` (as ``integrateMeasurement(a_k, ω_k, b − t_k)``),
    the linear interpolation of its neighbours in ``"midpoint"``; consecutive windows share it.
    Clipped samples inflate the noise as in :func:`preintegrate` (``saturation_noise_factor``), so
    a window holding one has a larger covariance; the other windows are unchanged.
    """
    like = _empty(noise, bias, gravity, scheme, combined, saturation_noise_factor)
    if not isinstance(imu, ImuData):
        raise ParameterError(f"imu: expected an imukit.ImuData, got {type(imu).__name__}")
    if threads is not None and (
        isinstance(threads, bool) or not isinstance(threads, int) or not 1 <= threads <= _MAX_THREADS
    ):
        raise ParameterError(f"threads: expected an int in [1, {_MAX_THREADS}] or None, got {threads!r}")
    cores = _windows(imu, boundaries, like, threads=threads or 0)
    b = np.asarray(boundaries)
    return [like._like(core, [_Window(imu, b[m], b[m + 1])]) for m, core in enumerate(cores)]
