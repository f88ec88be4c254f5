"""IMU preintegration: ``preintegrate`` and ``PreintegratedImu`` (Forster et al., T-RO 2017).

=====================  ===========================================================================
deltas                 ``ΔR_ij`` (scipy ``Rotation``), ``Δv_ij``, ``Δp_ij`` in the body frame at i,
                       gravity-free; ``Δt_ij``
scheme                 ``"euler"``: sample k held over ``[t_k, t_k+1)``, exact rotation steps
covariance             9×9 of ``[δθ, δv, δp]``, right perturbation ``ΔR = ΔR̂ Exp(δθ)``
bias Jacobian          9×6, rows ``[θ, v, p]``, columns ``[b_g, b_a]``
prediction             ``R_j = R_i ΔR``, ``v_j = v_i + g Δt + R_i Δv``, ``p_j = p_i + v_i Δt + ½ g Δt² + R_i Δp``
=====================  ===========================================================================

Gravity is added as everywhere in imukit (default ``(0, 0, −9.81)``, z up). Formulas: the module
docs of ``crates/imukit/src/preint.rs``. Still to come with the preintegration issue: the VINS
midpoint scheme, residual Jacobians and keyframe windows.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike
from scipy.spatial.transform import Rotation

from imukit import _core
from imukit._arrays import FloatArray, as_float_array, choice
from imukit._errors import ParameterError, ShapeError
from imukit.imu import ImuBias, ImuData, ImuNoise
from imukit.state import NavState

__all__ = ["PreintegratedImu", "preintegrate"]

_SCHEMES = ("euler",)


def _vector(x: ArrayLike, name: str) -> FloatArray:
    v = as_float_array(x, name)
    if v.shape != (3,):
        raise ShapeError(f"{name}: expected shape (3,), got {v.shape}")
    return v


class PreintegratedImu:
    """Preintegrated IMU measurements between two keyframes i and j; see the module docs.

    Build it with :func:`preintegrate`, or empty and then feed it with :meth:`integrate_measurement`
    (one interval, GTSAM-style) or :meth:`integrate` (a batch of samples).
    """

    def __init__(
        self,
        *,
        noise: ImuNoise,
        bias: ImuBias | None = None,
        gravity: ArrayLike = (0.0, 0.0, -9.81),
        scheme: str = "euler",
        combined: bool = False,
    ) -> None:
        if not isinstance(noise, ImuNoise):
            raise ParameterError(f"noise: expected an imukit.ImuNoise, got {type(noise).__name__}")
        if bias is not None and not isinstance(bias, ImuBias):
            raise ParameterError(f"bias: expected an imukit.ImuBias or None, got {type(bias).__name__}")
        choice(scheme, "scheme", _SCHEMES)
        self.bias = bias or ImuBias()
        self.noise = noise
        self.gravity = _vector(gravity, "gravity")
        self.scheme = scheme
        densities = [noise.gyro_density, noise.accel_density, noise.gyro_random_walk, noise.accel_random_walk]
        self.combined = bool(combined)
        self._core = _core.Preintegrator([*self.bias.gyro, *self.bias.accel], densities, self.combined)
        # What was integrated, in order, so that reintegrate() can replay it with another bias.
        self._inputs: list[ImuData | tuple[FloatArray, FloatArray, float]] = []

    def integrate_measurement(self, accel: ArrayLike, gyro: ArrayLike, dt: float) -> None:
        """Add one interval of ``dt`` seconds with ``accel`` [m/s²] and ``gyro`` [rad/s] held over it."""
        a, w = _vector(accel, "accel"), _vector(gyro, "gyro")
        self._core.integrate_measurement([*a], [*w], float(dt))
        self._inputs.append((a, w, float(dt)))

    def integrate(self, imu: ImuData) -> None:
        """Add the N − 1 intervals of ``imu`` (sample k held over ``[t_k, t_k+1)``), GIL released."""
        if not isinstance(imu, ImuData):
            raise ParameterError(f"imu: expected an imukit.ImuData, got {type(imu).__name__}")
        self._core.integrate(imu.seconds, imu.gyro, imu.accel)
        self._inputs.append(imu)

    def reintegrate(self, bias: ImuBias) -> PreintegratedImu:
        """A new preintegration of the same samples with ``bias``: exact, where :meth:`corrected` is
        first order. Its error grows with the square of the bias change; VINS-Mono re-integrates when
        the change exceeds 0.01 rad/s (gyro) or 0.1 m/s² (accelerometer), a sensible default
        threshold for 200 Hz windows of about 0.5 s.
        """
        out = PreintegratedImu(
            noise=self.noise, bias=bias, gravity=self.gravity, scheme=self.scheme, combined=self.combined
        )
        for item in self._inputs:
            if isinstance(item, ImuData):
                out.integrate(item)
            else:
                out.integrate_measurement(*item)
        return out

    def merge(self, other: PreintegratedImu) -> PreintegratedImu:
        """This preintegration (i → j) followed by ``other`` (j → k) as one (i → k), covariance and
        bias Jacobian included. Both need the same bias, noise and gravity. The bias random walk is
        not merged: the result has no ``covariance_combined``."""
        if not isinstance(other, PreintegratedImu):
            raise ParameterError(f"other: expected an imukit.PreintegratedImu, got {type(other).__name__}")
        if not np.array_equal(self.gravity, other.gravity):
            raise ParameterError("other: expected the same gravity")
        merged = object.__new__(PreintegratedImu)
        merged.bias, merged.noise, merged.gravity, merged.scheme = self.bias, self.noise, self.gravity, self.scheme
        merged.combined = False
        merged._core = self._core.merge(other._core)
        merged._inputs = self._inputs + other._inputs
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

    def corrected(self, bias: ImuBias) -> tuple[Rotation, FloatArray, FloatArray]:
        """Deltas for ``bias`` to first order, without re-integration (rotation right-applied):
        ``ΔR Exp(J_θ δb_g)``, ``Δv + J_v δb``, ``Δp + J_p δb`` with ``δb = bias − integration bias``."""
        r, v, p, _, _, jac = self._state()
        db = np.concatenate([bias.gyro - self.bias.gyro, bias.accel - self.bias.accel])
        d = jac @ db
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

    def residual(self, state_i: NavState, state_j: NavState, bias: ImuBias | None = None) -> FloatArray:
        """``[Log(ΔR̃ᵀ R_iᵀ R_j), R_iᵀ(v_j − v_i − g Δt) − Δṽ, R_iᵀ(p_j − p_i − v_i Δt − ½ g Δt²) − Δp̃]``."""
        dr, dv, dp, dt = self._deltas(bias)
        g, r_i = self.gravity, state_i.rotation
        r_v = r_i.inv().apply(state_j.velocity - state_i.velocity - g * dt) - dv
        r_p = r_i.inv().apply(state_j.position - state_i.position - state_i.velocity * dt - 0.5 * g * dt * dt) - dp
        r_theta = (dr.inv() * r_i.inv() * state_j.rotation).as_rotvec()
        return np.concatenate([r_theta, r_v, r_p])


def preintegrate(
    imu: ImuData,
    *,
    noise: ImuNoise,
    bias: ImuBias | None = None,
    gravity: ArrayLike = (0.0, 0.0, -9.81),
    scheme: str = "euler",
    combined: bool = False,
) -> PreintegratedImu:
    """Preintegrate all samples of ``imu`` (N samples → N − 1 intervals); see :class:`PreintegratedImu`.

    ``combined=True`` also tracks the 15×15 covariance with the bias random walk
    (``covariance_combined``), at about twice the cost per sample.
    """
    pim = PreintegratedImu(noise=noise, bias=bias, gravity=gravity, scheme=scheme, combined=combined)
    pim.integrate(imu)
    return pim
