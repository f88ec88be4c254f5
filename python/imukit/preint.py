"""IMU preintegration: ``preintegrate``, ``preintegrate_windows`` and ``PreintegratedImu``.

=====================  ===========================================================================
deltas                 ``ΔR_ij`` (scipy ``Rotation``), ``Δv_ij``, ``Δp_ij`` in the body frame at i,
                       gravity-free; ``Δt_ij``
schemes                ``"midpoint"`` (default; VINS-Mono: averaged rates, specific forces rotated
                       at both ends of each interval), ``"lie_euler"`` (Forster et al. T-RO 2017 and
                       GTSAM: sample k held over ``[t_k, t_k+1)``, exact rotation steps; the old
                       name ``"euler"`` is a deprecated alias); names: :data:`SCHEMES`
options                :class:`PreintParams` (one frozen value; the keyword options of every
                       function here build one)
results                :class:`Preintegration`: M windows as arrays with a leading window
                       dimension, from ``preintegrate_windows(imu, boundaries, params)`` (one native
                       call) or ``PreintegratedImu.snapshot()``; batched ``predict``, ``residual``,
                       ``residual_jacobians``, ``corrected`` and ``reintegrate`` over it
engines                ``engine="rust"`` (default) or ``"numpy_ref"`` (:mod:`imukit._engines`)
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

import contextlib
import math
import threading
from typing import Any, NamedTuple, overload

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from imukit import _core, _preint_math
from imukit._arrays import FloatArray, as_float_array, flag, plain_array, real_scalar, seconds_from_ns
from imukit._deprecation import deprecated
from imukit._engines import ENGINES, Windows
from imukit._engines._windows import lever_windows
from imukit._errors import DTypeError, ParameterError, ShapeError
from imukit._extrinsics import has_lever_arm, in_body, lever_columns, lever_jacobian, lever_noise, origin_readings
from imukit._preint_math import Deltas, ResidualJacobians, States
from imukit._preint_record import SCHEME_ALIASES, SCHEMES, Preintegration, PreintParams
from imukit.imu import ImuBias, ImuData, ImuNoise
from imukit.state import NavState
from imukit.threads import checked

__all__ = [
    "SCHEMES",
    "SCHEME_ALIASES",
    "Deltas",
    "PreintParams",
    "PreintegratedImu",
    "Preintegration",
    "ResidualJacobians",
    "States",
    "concatenate",
    "corrected",
    "predict",
    "preintegrate",
    "preintegrate_windows",
    "regular_boundaries",
    "reintegrate",
    "residual",
    "residual_jacobians",
    "window_arrays",
]

corrected = _preint_math.corrected
predict = _preint_math.predict
residual = _preint_math.residual
residual_jacobians = _preint_math.residual_jacobians

_DEFAULT_FACTOR = _core.DEFAULT_SATURATION_NOISE_FACTOR
_DEFAULT_GRAVITY = _core.GRAVITY
_DEFAULT_SCHEME = PreintParams.scheme


def _params(
    params: PreintParams | None,
    noise: ImuNoise | None,
    bias: ImuBias | None,
    gravity: ArrayLike,
    scheme: str,
    combined: bool,
    saturation_noise_factor: float,
    body_from_sensor: object = None,
) -> PreintParams:
    """``params``, or the one the keyword options describe; both at once is refused (a keyword next
    to ``params`` was dropped without a word before 2026-12-07)."""
    if params is not None:
        if not isinstance(params, PreintParams):
            raise ParameterError(f"expected an imukit.PreintParams, got {type(params).__name__}", argument="params")
        given = {
            "noise": noise is not None,
            "bias": bias is not None,
            "gravity": gravity is not _DEFAULT_GRAVITY,
            "scheme": scheme is not _DEFAULT_SCHEME,
            "combined": combined is not False,
            "saturation_noise_factor": saturation_noise_factor is not _DEFAULT_FACTOR,
            "body_from_sensor": body_from_sensor is not None,
        }
        for name, is_given in given.items():
            if is_given:
                raise ParameterError(
                    f"given with params, which already holds it: set it in PreintParams (params.{name}) "
                    "or pass every option as a keyword without params",
                    argument=name,
                )
        return params
    return PreintParams(noise, bias, gravity, scheme, combined, saturation_noise_factor, body_from_sensor)  # type: ignore[arg-type]


class _Measurement(NamedTuple):
    """One :meth:`PreintegratedImu.integrate_measurement` call, for the deprecated ``reintegrate(bias)``."""

    accel: FloatArray
    gyro: FloatArray
    dt: float
    gyro_saturated: bool
    accel_saturated: bool


class _Window(NamedTuple):
    """A window of the deprecated list form of :func:`preintegrate_windows`, for ``reintegrate(bias)``."""

    imu: ImuData
    lo: Any
    hi: Any


class _Span(NamedTuple):
    """An :meth:`PreintegratedImu.integrate` call with ``span``, for the deprecated ``reintegrate(bias)``."""

    imu: ImuData
    span: tuple[float, float]


_Input = ImuData | _Window | _Measurement | _Span


class PreintegratedImu:
    """Preintegrated IMU measurements between two keyframes i and j, a GTSAM-style streaming
    accumulator; see the module docs.

    Build it with :func:`preintegrate`, or empty (``PreintegratedImu(params)`` or the keyword
    options) and then feed it with :meth:`integrate_measurement` (one sample, GTSAM / VINS-Mono
    style) or :meth:`integrate` (a batch of samples). :meth:`snapshot` is its state as a
    :class:`Preintegration` record (M = 1), read in one call; the properties read that snapshot.
    """

    def __init__(
        self,
        params: PreintParams | None = None,
        *,
        noise: ImuNoise | None = None,
        bias: ImuBias | None = None,
        gravity: ArrayLike = _DEFAULT_GRAVITY,
        scheme: str = _DEFAULT_SCHEME,
        combined: bool = False,
        saturation_noise_factor: float = _DEFAULT_FACTOR,
        body_from_sensor: tuple[Rotation, ArrayLike] | None = None,
    ) -> None:
        self.params = _params(params, noise, bias, gravity, scheme, combined, saturation_noise_factor, body_from_sensor)
        # The name as given: "euler" stays "euler" for code that compares it.
        self._scheme = self.params.scheme if params is not None else scheme
        self._core = self.params._template()
        # With a lever arm: the three preintegrations of the centripetal bias term (_extrinsics).
        self._lever = (
            [self.params._template() for _ in range(3)] if has_lever_arm(self.params.body_from_sensor) else None
        )
        # With a lever arm: the complete covariance (the gyro noise in the corrected accelerometer).
        self._noise: _core.LeverNoise | None = None
        self._snapshot: Preintegration | None = None
        self._span = (math.nan, math.nan)
        # What was integrated, for the deprecated reintegrate(bias) only: reintegrate(imu, bias)
        # takes the samples explicitly.
        self._inputs: list[_Input] = []
        self._started = False  # whether anything was integrated (the span's start is set)
        self._lock = threading.Lock()

    def __reduce__(self) -> tuple[Any, ...]:
        # The core pickles its complete state; the replay log of the deprecated reintegrate(bias)
        # travels too (its samples are data), so a copy behaves as the original in every call.
        state = (self._span, self._inputs, self._started, self._snapshot, self._lever, self._noise)
        return (_restore, (self.params, self._scheme, self._core, *state))

    def _like(
        self,
        core: _core.Preintegrator,
        inputs: list[_Input],
        params: PreintParams,
        lever: list[_core.Preintegrator] | None = None,
        noise: _core.LeverNoise | None = None,
    ) -> PreintegratedImu:
        out = object.__new__(PreintegratedImu)
        out.params, out._scheme, out._core, out._inputs = params, self._scheme, core, inputs
        out._lever, out._noise = lever, noise
        out._started = True
        out._snapshot, out._span = None, (math.nan, math.nan)
        out._lock = threading.Lock()
        return out

    @property
    def noise(self) -> ImuNoise:
        """The noise densities."""
        return self.params.noise

    @property
    def bias(self) -> ImuBias:
        """The bias the samples were integrated with."""
        return self.params.bias

    @property
    def gravity(self) -> FloatArray:
        """Gravity (3,) [m/s²] of :meth:`predict` and :meth:`residual`."""
        return np.array(self.params.gravity)

    @property
    def scheme(self) -> str:
        """The scheme, as named when built."""
        return self._scheme

    @property
    def combined(self) -> bool:
        """Whether the 15×15 ``covariance_combined`` is tracked."""
        return self.params.combined

    @property
    def saturation_noise_factor(self) -> float:
        """Multiplier of a clipped sample's white-noise densities."""
        return self.params.saturation_noise_factor

    def _changed(self, start: float = math.nan, end: float = math.nan) -> None:
        """After an input: the snapshot is stale; the span starts with the first input's."""
        self._snapshot = None
        self._span = (self._span[0] if self._started else start, end)
        self._started = True

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

        ``"lie_euler"``: the sample is held over the next ``dt`` seconds (GTSAM's
        ``integrateMeasurement``). ``"midpoint"``: the sample was taken ``dt`` seconds after the
        previous one (VINS-Mono's ``push_back``); the window's first sample comes with ``dt=0``.
        ``gyro_saturated`` / ``accel_saturated`` mark a sensor clipped at its range: its white-noise
        density is multiplied by ``saturation_noise_factor`` for this sample (module docs). The core
        checks the values (finite readings, the dt rules) and refuses a step that would overflow,
        leaving the preintegration as it was.
        """
        if self._lever is not None:
            raise ParameterError(
                "one sample at a time has no angular acceleration for the lever arm: integrate(imu) a batch",
                argument="body_from_sensor",
            )
        a, w = as_float_array(accel, "accel"), as_float_array(gyro, "gyro")
        for v, name in ((a, "accel"), (w, "gyro")):
            if v.shape != (3,):
                raise ShapeError(f"expected shape (3,), got {v.shape}", argument=name)
        step = real_scalar(dt, "dt", what="a step in seconds", accept=lambda x: True)
        flags = (flag(gyro_saturated, "gyro_saturated"), flag(accel_saturated, "accel_saturated"))
        with self._lock:
            self._core.integrate_measurement([*a], [*w], step, *flags)
            self._inputs.append(_Measurement(a, w, step, *flags))
            self._changed()

    def integrate(self, imu: ImuData, *, span: tuple[float, float] | None = None, threads: int | None = None) -> None:
        """Add the N − 1 intervals between the samples of ``imu``, GIL released. In the midpoint
        scheme a batch after earlier samples must start with the last of them (consecutive windows
        share their boundary sample). Long batches of either scheme (over 65,536 intervals, without
        ``combined``) run as fixed chunks on all cores, merged in order: equal to streaming to
        rounding (1e-12 relative) and independent of the core count.

        ``span=(t_a, t_b)``: only the intervals between the samples stamped ``t_a`` and ``t_b``
        (two stamps of ``imu.t``); the samples outside still inform a lever arm's angular
        acceleration at the edges (``body_from_sensor``), so spans cut from one batch merge
        exactly into the whole batch's preintegration. With a lever arm, stream that way (the
        buffer and a span per call): batches converted on their own have one-sided differences
        at their ends, their shared sample differs, and the continuation is refused.

        ``threads``: threads for this call (None: :func:`imukit.set_num_threads`'s setting), see :mod:`imukit.threads`.
        """
        if not isinstance(imu, ImuData):
            raise ParameterError(f"expected an imukit.ImuData, got {type(imu).__name__}", argument="imu")
        count = checked(threads)
        lo, hi = _span(imu, span)
        clock = (float(imu.t[lo]), float(imu.t[hi - 1]))
        # The core call releases the GIL: the lock makes each call whole (the core state, the span
        # and the snapshot change together); calls from several threads run one after another.
        with self._lock:
            if self._lever is None:
                _feed(self._core, _arrays_of(imu), (lo, hi), clock, count)
            else:
                body = origin_readings(imu, self.params.bias, self.params.body_from_sensor)
                _feed(self._core, body, (lo, hi), clock, count)
                for core, readings in zip(self._lever, lever_columns(body, self.params.body_from_sensor), strict=True):
                    _feed(core, readings, (lo, hi), clock, count)
                edges = np.array([body.seconds[lo], body.seconds[hi - 1]])
                noise = lever_noise(body, self.params, edges, count)[0]
                self._noise = noise if self._noise is None else self._noise.merge(noise)
            self._inputs.append(imu if span is None else _Span(imu, span))
            self._changed(*clock)

    def snapshot(self) -> Preintegration:
        """The preintegration as a :class:`Preintegration` record (M = 1), read from the core in one
        call and kept until the next sample; ``t_start``/``t_end`` are those of the samples given
        to :meth:`integrate` (NaN after :meth:`integrate_measurement` or :meth:`merge`)."""
        with self._lock:
            return self._read_snapshot()

    def _read_snapshot(self) -> Preintegration:
        if self._snapshot is None:
            state = self._core.state()
            pose = self.params.body_from_sensor
            if self._lever is not None and pose is not None:
                cols = [c.state() for c in self._lever]
                dv = np.stack([c[1] for c in cols], axis=-1)[None]
                dp = np.stack([c[2] for c in cols], axis=-1)[None]
                jac = lever_jacobian(state[5][None], np.array(pose[0]), dv, dp)[0]
                cov, _, combined = self._noise.state() if self._noise is not None else (state[4], jac, state[6])
                state = (*state[:4], cov, jac, combined)
            elif pose is not None:
                state = in_body(state, pose)
            r, v, p, dt, cov, jac, combined = state
            self._snapshot = Preintegration._owning(
                delta_rotation=np.asarray(r)[None],
                delta_velocity=v[None],
                delta_position=p[None],
                delta_t=np.array([dt]),
                covariance=cov[None],
                bias_jacobian=jac[None],
                covariance_combined=None if combined is None else combined[None],
                t_start=np.array([self._span[0]]),
                t_end=np.array([self._span[1]]),
                params=self.params,
            )
        return self._snapshot

    def reintegrate(self, imu: ImuData | ImuBias, bias: ImuBias | None = None) -> PreintegratedImu:
        """``reintegrate(imu, bias)``: a new preintegration of the samples ``imu`` with ``bias`` (the
        same options otherwise): exact, where :meth:`corrected` is first order. Its error grows
        with the square of the bias change; VINS-Mono re-integrates when the change exceeds
        0.01 rad/s (gyro) or 0.1 m/s² (accelerometer), a sensible default threshold for 200 Hz
        windows of about 0.5 s.

        ``reintegrate(bias)`` (deprecated) replays what was integrated, from a log this object keeps.
        """
        if isinstance(imu, ImuData):
            if not isinstance(bias, ImuBias):
                raise ParameterError(f"expected an imukit.ImuBias, got {type(bias).__name__}", argument="bias")
            return preintegrate(imu, self.params.replace(bias=bias))
        deprecated("reintegrate(bias) is deprecated: pass the samples, reintegrate(imu, bias)")
        return self._replay(imu)

    def _replay(self, bias: ImuBias) -> PreintegratedImu:
        params = self.params.replace(bias=bias)

        def empty() -> PreintegratedImu:
            lever = None if self._lever is None else [params._template() for _ in range(3)]
            return self._like(params._template(), [], params, lever)

        out = empty()
        for item in self._inputs:
            if isinstance(item, _Window):
                # A window starts from an empty preintegration; after a merge it may follow other
                # inputs, so it is preintegrated on its own and merged on, as merge() did.
                (piece,) = _core_windows(item.imu, [item.lo, item.hi], params)
                out._core = out._core.merge(piece) if out._inputs else piece
                out._inputs.append(item)
            elif isinstance(item, ImuData):
                out.integrate(item)
            elif isinstance(item, _Span):
                out.integrate(item.imu, span=item.span)
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
            raise ParameterError(f"expected an imukit.PreintegratedImu, got {type(other).__name__}", argument="other")
        if self.params.gravity != other.params.gravity:
            raise ParameterError("expected the same gravity", argument="other")
        if self.params.body_from_sensor != other.params.body_from_sensor:
            raise ParameterError("expected the same body_from_sensor", argument="other")
        params = self.params.replace(combined=False)
        # Both locks, taken in one global order (a.merge(b) and b.merge(a) at once cannot deadlock).
        with contextlib.ExitStack() as held:
            for _, lock in sorted({id(x): x._lock for x in (self, other)}.items()):
                held.enter_context(lock)
            lever, noise = None, None
            if self._lever is not None and other._lever is not None:
                lever = [a.merge(b) for a, b in zip(self._lever, other._lever, strict=True)]
            if self._noise is not None and other._noise is not None:
                noise = self._noise.merge(other._noise)
            core = self._core.merge(other._core)
            return self._like(core, self._inputs + other._inputs, params, lever, noise)

    def _state(self) -> tuple[FloatArray, FloatArray, FloatArray, float, FloatArray, FloatArray]:
        """The old ``(ΔR, Δv, Δp, Δt, covariance, bias Jacobian)`` tuple (test helpers read it)."""
        s = self.snapshot()
        return (
            s.delta_rotation[0],
            s.delta_velocity[0],
            s.delta_position[0],
            float(s.delta_t[0]),
            s.covariance[0],
            s.bias_jacobian[0],
        )

    @property
    def delta_rotation(self) -> Rotation:
        """``ΔR_ij``."""
        return Rotation.from_matrix(self.snapshot().delta_rotation[0])

    @property
    def delta_velocity(self) -> FloatArray:
        """``Δv_ij`` [m/s], gravity-free, frame i."""
        return np.array(self.snapshot().delta_velocity[0])  # a fresh array, as before the snapshot

    @property
    def delta_position(self) -> FloatArray:
        """``Δp_ij`` [m], gravity-free, frame i."""
        return np.array(self.snapshot().delta_position[0])  # a fresh array, as before the snapshot

    @property
    def delta_t(self) -> float:
        """``Δt_ij`` [s]."""
        return float(self.snapshot().delta_t[0])

    @property
    def covariance(self) -> FloatArray:
        """9×9 covariance of ``[δθ, δv, δp]``."""
        return np.array(self.snapshot().covariance[0])  # a fresh array, as before the snapshot

    @property
    def covariance_combined(self) -> FloatArray | None:
        """15×15 covariance of ``[δθ, δv, δp, δb_g, δb_a]`` including the bias random walk between i
        and j (``ImuNoise`` random-walk densities); None unless built with ``combined=True``."""
        c = self.snapshot().covariance_combined
        return None if c is None else c[0].copy()

    @property
    def bias_jacobian(self) -> FloatArray:
        """9×6 ``∂(θ, v, p)/∂(b_g, b_a)``."""
        return np.array(self.snapshot().bias_jacobian[0])  # a fresh array, as before the snapshot

    def corrected(self, bias: ImuBias) -> tuple[Rotation, FloatArray, FloatArray]:
        """Deltas for ``bias`` to first order, without re-integration (rotation right-applied):
        ``ΔR Exp(J_θ δb_g)``, ``Δv + J_v δb``, ``Δp + J_p δb`` with ``δb = bias − integration bias``."""
        if not isinstance(bias, ImuBias):
            raise ParameterError(f"expected an imukit.ImuBias, got {type(bias).__name__}", argument="bias")
        r, v, p = corrected(self.snapshot(), bias)
        return Rotation.from_matrix(r[0]), v[0], p[0]

    def predict(
        self,
        state_i: NavState,
        bias: ImuBias | None = None,
        *,
        omega_coriolis: ArrayLike | None = None,
        second_order_coriolis: bool = False,
        exact_coriolis: bool = False,
    ) -> NavState:
        """The state at j from the state at i (deltas corrected to ``bias`` when given).

        ``omega_coriolis`` (3,) [rad/s]: the navigation frame's rotation rate in its own axes (the
        Earth rate of a local-level frame, GTSAM's ``omegaCoriolis``); the Coriolis terms to first
        order (GTSAM 4.2), ``second_order_coriolis`` adds the centrifugal ones, ``exact_coriolis``
        the closed form of GTSAM 4.3 (``docs/navigation.md``)."""
        p, v, r = predict(
            self.snapshot(),
            _states(state_i, "state_i"),
            bias,
            omega_coriolis=omega_coriolis,
            second_order_coriolis=second_order_coriolis,
            exact_coriolis=exact_coriolis,
        )
        return NavState(p[0], v[0], Rotation.from_matrix(r[0]))

    def residual(
        self,
        state_i: NavState,
        state_j: NavState,
        bias: ImuBias | None = None,
        *,
        omega_coriolis: ArrayLike | None = None,
        second_order_coriolis: bool = False,
        exact_coriolis: bool = False,
    ) -> FloatArray:
        """``[Log(ΔR̃ᵀ R_iᵀ R_j), R_iᵀ(v_j − v_i − g Δt) − Δṽ, R_iᵀ(p_j − p_i − v_i Δt − ½ g Δt²) − Δp̃]``,
        the deltas corrected to ``bias`` when given (9,). With ``omega_coriolis`` (as in
        :meth:`predict`): the deltas the two states imply in the rotating frame minus the measured
        ones, so :attr:`covariance` stays the residual's."""
        out: FloatArray = residual(
            self.snapshot(),
            _states(state_i, "state_i"),
            _states(state_j, "state_j"),
            bias,
            omega_coriolis=omega_coriolis,
            second_order_coriolis=second_order_coriolis,
            exact_coriolis=exact_coriolis,
        )[0]
        return out

    def residual_jacobians(
        self,
        state_i: NavState,
        state_j: NavState,
        bias: ImuBias | None = None,
        *,
        omega_coriolis: ArrayLike | None = None,
        second_order_coriolis: bool = False,
        exact_coriolis: bool = False,
    ) -> ResidualJacobians:
        """Jacobians of :meth:`residual` (Forster et al. 2017, eqs. 44–45, in imukit's charts):
        w.r.t. state i and j (columns ``[δp, δv, δθ]``, ``R Exp(δθ)``) and the bias (``[δb_g, δb_a]``,
        through the first-order correction); in a rotating frame with ``omega_coriolis``, each
        model (first order, ``second_order_coriolis``, ``exact_coriolis``)."""
        jac = residual_jacobians(
            self.snapshot(),
            _states(state_i, "state_i"),
            _states(state_j, "state_j"),
            bias,
            omega_coriolis=omega_coriolis,
            second_order_coriolis=second_order_coriolis,
            exact_coriolis=exact_coriolis,
        )
        return ResidualJacobians(*(j[0] for j in jac))


def _restore(
    params: PreintParams,
    scheme: str,
    core: _core.Preintegrator,
    span: tuple[float, float],
    inputs: list[_Input],
    started: bool,
    snapshot: Preintegration | None,
    lever: list[_core.Preintegrator] | None = None,
    noise: _core.LeverNoise | None = None,
) -> PreintegratedImu:
    """A pickled :class:`PreintegratedImu` (its ``__reduce__``)."""
    out = PreintegratedImu(params)
    out._scheme, out._core, out._span, out._inputs = scheme, core, span, inputs
    out._started, out._snapshot, out._lever, out._noise = started, snapshot, lever, noise
    return out


def _arrays_of(imu: ImuData) -> tuple[FloatArray, FloatArray, FloatArray, Any, Any]:
    """What the core's ``integrate`` reads of the samples, in its order."""
    return (imu.seconds, imu.gyro, imu.accel, imu.gyro_saturated, imu.accel_saturated)


def _span(imu: ImuData, span: object) -> tuple[int, int]:
    """The sample range ``[lo, hi)`` that ``span`` (two stamps of ``imu.t``, or integer ns of
    ``imu.t_ns``; None: all) names."""
    if span is None:
        return 0, len(imu)
    edges = plain_array(span, "span")  # type: ignore[arg-type]
    if edges.shape != (2,):
        raise ShapeError(f"expected shape (2,), got {edges.shape}", argument="span")
    if edges.dtype.kind not in "iuf":
        raise DTypeError(f"expected two numbers (sample stamps), got dtype {edges.dtype}", argument="span")
    stamps = imu.t_ns if edges.dtype.kind in "iu" and imu.t_ns is not None else imu.t
    k = np.searchsorted(stamps, edges)
    inside = (k < len(imu)) & (stamps[np.minimum(k, len(imu) - 1)] == edges)
    if not inside.all() or k[1] <= k[0]:
        raise ParameterError(
            f"expected two stamps of imu.t, the first before the second, got {span!r}", argument="span"
        )
    return int(k[0]), int(k[1]) + 1


def _feed(
    core: _core.Preintegrator,
    arrays: tuple[Any, Any, Any, Any, Any],
    cut: tuple[int, int],
    clock: tuple[float, float],
    threads: int | None,
) -> None:
    """Samples ``[lo, hi)`` of ``(t, gyro, accel, gyro_saturated, accel_saturated)`` into ``core``."""
    t, gyro, accel, gyro_clipped, accel_clipped = (np.ascontiguousarray(a[cut[0] : cut[1]]) for a in arrays)
    core.integrate(t, gyro, accel, gyro_clipped, accel_clipped, clock, threads)


def _states(state: NavState, name: str) -> States:
    if not isinstance(state, NavState):  # None had no .position: an AttributeError
        raise ParameterError(f"expected an imukit.NavState, got {type(state).__name__}", argument=name)
    return States(state.position[None], state.velocity[None], state.rotation.as_matrix()[None])


def preintegrate(
    imu: ImuData,
    params: PreintParams | None = None,
    *,
    noise: ImuNoise | None = None,
    bias: ImuBias | None = None,
    gravity: ArrayLike = _DEFAULT_GRAVITY,
    scheme: str = _DEFAULT_SCHEME,
    combined: bool = False,
    saturation_noise_factor: float = _DEFAULT_FACTOR,
    threads: int | None = None,
    body_from_sensor: tuple[Rotation, ArrayLike] | None = None,
    span: tuple[float, float] | None = None,
) -> PreintegratedImu:
    """Preintegrate all samples of ``imu`` (N samples → N − 1 intervals); see :class:`PreintegratedImu`.

    Options: ``params``, or the same as keywords (not both: a keyword next to ``params`` is
    refused). ``combined=True`` also tracks the 15×15 covariance with the bias random walk
    (``covariance_combined``), at about twice the cost per sample. Samples that ``imu`` flags as
    clipped (``gyro_saturated`` / ``accel_saturated``, from its ``gyro_range`` / ``accel_range``)
    have that sensor's white-noise density multiplied by ``saturation_noise_factor`` (finite, ≥ 1;
    1 ignores the flags); see the module docs for which intervals that covers.

    ``body_from_sensor``: ``(R_bs, lever arm)``, the IMU's pose in the body frame (GTSAM's
    ``body_P_sensor``): the deltas, covariance and bias Jacobian are the body's (biases stay the
    sensor's). A lever arm converts the readings to the body origin's before the step, with the
    angular acceleration from the gyro's central difference (:mod:`imukit._extrinsics`); the
    covariance (and ``combined``'s) includes the gyro noise that the conversion puts into the
    corrected accelerometer (``docs/navigation.md``). ``span``: as in :meth:`PreintegratedImu.integrate`.

    ``threads``: threads for this call (None: :func:`imukit.set_num_threads`'s setting), see :mod:`imukit.threads`.
    """
    pim = PreintegratedImu(
        params,
        noise=noise,
        bias=bias,
        gravity=gravity,
        scheme=scheme,
        combined=combined,
        saturation_noise_factor=saturation_noise_factor,
        body_from_sensor=body_from_sensor,
    )
    pim.integrate(imu, span=span, threads=threads)
    return pim


def _windows(imu: ImuData, boundaries: ArrayLike) -> Windows:
    """The edges on ``imu.seconds``' axis and as the record's times (``boundaries`` on ``imu.t``'s
    clock: integer ns for integer stamps, else float seconds)."""
    if not isinstance(imu, ImuData):
        raise ParameterError(f"expected an imukit.ImuData, got {type(imu).__name__}", argument="imu")
    raw = plain_array(boundaries, "boundaries")
    if raw.ndim != 1:
        raise ShapeError(f"expected shape (M,), got {raw.shape}", argument="boundaries")
    if raw.dtype.kind in "iu" and imu.t_ns is not None:
        if raw.size:  # exact Python ints: int64 differences near ±2^63 wrap, uint64 above 2^63 too
            _within_span(int(raw.min()), int(raw.max()), int(imu.t_ns[0]), int(imu.t_ns[-1]), "integer ns")
        ns = raw.astype(np.int64)
        return Windows(seconds_from_ns(ns - imu.t_ns[0]), ns / 1e9, ns)
    t = as_float_array(raw, "boundaries")
    offsets = t - imu.t[0]
    finite = t[np.isfinite(t)]  # NaN and inf are the core's to name
    if finite.size and (finite.min() < imu.t[0] or (finite - imu.t[0]).max() > imu.seconds[-1]):
        _within_span(float(finite.min()), float(finite.max()), float(imu.t[0]), float(imu.t[-1]), "seconds")
    if imu.t_ns is not None:
        # Float boundaries taken from an ns recording's imu.t (epoch seconds, 0.24 µs apart): a
        # sample's own time is that sample exactly, so the last one stays inside the span and
        # windows between samples are as long as their ns stamps say (not 0.10000014 s).
        k = np.minimum(np.searchsorted(imu.t, t), len(imu) - 1)
        on_sample = imu.t[k] == t
        offsets[on_sample] = imu.seconds[k[on_sample]]
        if on_sample.all():
            ns = imu.t_ns[k]
            return Windows(offsets, t, ns)
    return Windows(offsets, t, None)


def _within_span(low: float, high: float, first: float, last: float, unit: str) -> None:
    """A ParameterError unless boundaries from ``low`` to ``high`` lie within the samples' span
    ``[first, last]`` on ``imu.t``'s clock; boundaries that fit the span from 0 are named as such."""
    if first <= low and high <= last:
        return
    hint = ""
    if 0 <= low and high <= last - first:
        hint = ": they fit the span counted from the first sample; pass imu.t[0] + boundaries"
    raise ParameterError(
        f"expected times on imu.t's clock ({unit}) within the samples' span [{first!r}, {last!r}], got {low!r} to "
        f"{high!r}{hint}",
        argument="boundaries",
    )


def _core_windows(
    imu: ImuData, boundaries: ArrayLike, params: PreintParams, threads: int | None = None
) -> list[_core.Preintegrator]:
    b = np.ascontiguousarray(_windows(imu, boundaries).offsets)
    return _core.preint_windows(imu, b, params._template(), threads)


@overload
def preintegrate_windows(
    imu: ImuData,
    boundaries: ArrayLike,
    params: None = ...,
    *,
    noise: ImuNoise,
    bias: ImuBias | None = ...,
    gravity: ArrayLike = ...,
    scheme: str = ...,
    combined: bool = ...,
    saturation_noise_factor: float = ...,
    threads: int | None = ...,
) -> list[PreintegratedImu]: ...
@overload
def preintegrate_windows(
    imu: ImuData, boundaries: ArrayLike, params: PreintParams, *, engine: str = ..., threads: int | None = ...
) -> Preintegration: ...
def preintegrate_windows(
    imu: ImuData,
    boundaries: ArrayLike,
    params: PreintParams | None = None,
    *,
    engine: str = "rust",
    noise: ImuNoise | None = None,
    bias: ImuBias | None = None,
    gravity: ArrayLike = _DEFAULT_GRAVITY,
    scheme: str = _DEFAULT_SCHEME,
    combined: bool = False,
    saturation_noise_factor: float = _DEFAULT_FACTOR,
    threads: int | None = None,
) -> Preintegration | list[PreintegratedImu]:
    """Every window ``[boundaries[m], boundaries[m+1]]`` (M + 1 times → M windows) preintegrated
    with ``params``, as one :class:`Preintegration` record, filled by one native call (``engine=
    "rust"``), the windows in parallel, GIL released.

    ``boundaries`` (M + 1,) are times on ``imu.t``'s clock (integer ns for integer stamps; the
    record then carries them exactly as ``t_start_ns``/``t_end_ns``), strictly increasing, within
    the samples' span. A boundary between two samples is a point of the scheme's signal model: the
    held sample in ``"lie_euler"`` (as ``integrateMeasurement(a_k, ω_k, b − t_k)``), the linear
    interpolation of its neighbours in ``"midpoint"``; consecutive windows share it. Clipped
    samples inflate the noise as in :func:`preintegrate`, so a window holding one has a larger
    covariance; the other windows are unchanged. ``engine``: a name of :data:`imukit._engines.ENGINES`.
    ``threads``: threads for this call (None: :func:`imukit.set_num_threads`'s setting), see :mod:`imukit.threads`.

    Deprecated form: without ``params``, the keyword options (``noise=`` …) give the old result, a
    list of :class:`PreintegratedImu` (one per window; they merge and ``reintegrate(bias)``).
    """
    n = checked(threads)
    if params is None:
        deprecated(
            "preintegrate_windows(imu, boundaries, noise=...) returning a list is deprecated: pass a "
            "PreintParams, preintegrate_windows(imu, boundaries, params), for one Preintegration record"
        )
        p = _params(None, noise, bias, gravity, scheme, combined, saturation_noise_factor)
        like = PreintegratedImu(p)
        like._scheme = scheme
        cores = _core_windows(imu, boundaries, p, n)
        b = np.asarray(boundaries)
        return [like._like(core, [_Window(imu, b[m], b[m + 1])], p) for m, core in enumerate(cores)]
    params = _params(params, noise, bias, gravity, scheme, combined, saturation_noise_factor)
    if engine not in ENGINES:
        raise ParameterError(f"expected one of {tuple(ENGINES)}, got {engine!r}", argument="engine")
    if has_lever_arm(params.body_from_sensor):
        return lever_windows(ENGINES[engine], imu, _windows(imu, boundaries), params, n)
    return ENGINES[engine](imu, _windows(imu, boundaries), params, n)


def reintegrate(
    preintegration: Preintegration, imu: ImuData, bias: ImuBias, *, engine: str = "rust", threads: int | None = None
) -> Preintegration:
    """The windows of ``preintegration`` preintegrated again from the samples ``imu`` with ``bias``
    (the same options otherwise): exact, where :func:`corrected` is first order.

    ``threads``: threads for this call (None: :func:`imukit.set_num_threads`'s setting), see :mod:`imukit.threads`.
    """
    if not isinstance(preintegration, Preintegration):
        raise ParameterError(
            f"expected an imukit.Preintegration, got {type(preintegration).__name__}", argument="preintegration"
        )
    if not isinstance(bias, ImuBias):
        raise ParameterError(f"expected an imukit.ImuBias, got {type(bias).__name__}", argument="bias")
    start: NDArray[Any] = preintegration.t_start
    end: NDArray[Any] = preintegration.t_end
    if preintegration.t_start_ns is not None and preintegration.t_end_ns is not None and imu.t_ns is not None:
        start, end = preintegration.t_start_ns, preintegration.t_end_ns
    params = preintegration.params.replace(bias=bias)
    if np.array_equal(start[1:], end[:-1]):
        return preintegrate_windows(imu, np.append(start, end[-1:]), params, engine=engine, threads=threads)
    pieces = [
        preintegrate_windows(imu, [a, b], params, engine=engine, threads=threads)
        for a, b in zip(start, end, strict=True)
    ]
    return concatenate(pieces)


def concatenate(records: list[Preintegration]) -> Preintegration:
    """One record of the windows of ``records``, in order (they share their params)."""
    first = records[0]
    fields: dict[str, Any] = {}
    for name in (
        "delta_rotation",
        "delta_velocity",
        "delta_position",
        "delta_t",
        "covariance",
        "bias_jacobian",
        "covariance_combined",
        "t_start",
        "t_end",
        "t_start_ns",
        "t_end_ns",
    ):
        parts = [getattr(r, name) for r in records]
        fields[name] = None if parts[0] is None else np.concatenate(parts)
    return Preintegration(params=first.params, **fields)


def regular_boundaries(imu: ImuData, period: float) -> NDArray[Any]:
    """Window edges on ``imu.t``'s clock every ``period`` seconds from the first sample, the last
    one at or before the last sample: integer ns for ns stamps (the period rounded to a whole ns,
    the count by integer division: exact), else float seconds (the count lowered while rounding puts
    the last edge past the last sample). At least one window, and at most one per sample step: a
    period longer than the recording, or shorter than its mean sample step, is a
    :class:`ParameterError` naming ``period`` (``imukit preintegrate --window 1e-9`` asked for 2·10¹⁰
    windows of a 20 s recording and ran out of memory)."""
    if not isinstance(imu, ImuData):
        raise ParameterError(f"expected an imukit.ImuData, got {type(imu).__name__}", argument="imu")
    window_s = real_scalar(period, "period", what="a positive, finite period [s]", accept=lambda x: 0 < x < math.inf)
    if not window_s <= imu.duration:  # before the count, which would overflow for 1e308
        raise ParameterError(f"{window_s} s is longer than the recording ({imu.duration:.6g} s)", argument="period")
    step = imu.duration / (len(imu) - 1)
    if window_s < step:
        raise ParameterError(
            f"{window_s} s is shorter than the sample step ({step:.6g} s): more windows than samples",
            argument="period",
        )
    if imu.t_ns is not None:
        step = max(round(window_s * 1e9), 1)
        count = int(imu.t_ns[-1] - imu.t_ns[0]) // step
    else:
        count = int(np.floor(imu.duration / window_s))
        while count > 0 and imu.t[0] + count * window_s > imu.t[-1]:
            count -= 1
    if count < 1:
        raise ParameterError(f"{window_s} s is longer than the recording ({imu.duration:.6g} s)", argument="period")
    if imu.t_ns is not None:
        return np.asarray(imu.t_ns[0] + np.arange(count + 1, dtype=np.int64) * step, dtype=np.int64)
    return np.asarray(imu.t[0] + np.arange(count + 1) * window_s)


def window_arrays(record: Preintegration) -> dict[str, NDArray[Any]]:
    """The windows as named arrays (what ``imukit preintegrate --out x.npz`` writes,
    the rows of the fleet job ``preintegrate``); ``t_start_ns``, ``t_end_ns`` (int64,
    exact) when the stamps are ns."""
    start, end = record.t_start_ns, record.t_end_ns
    exact = {} if start is None or end is None else {"t_start_ns": start, "t_end_ns": end}
    return {
        **exact,
        "t_start": record.t_start,
        "t_end": record.t_end,
        "delta_t": record.delta_t,
        "dR_xyzw": Rotation.from_matrix(record.delta_rotation).as_quat(),
        "dv": record.delta_velocity,
        "dp": record.delta_position,
        "covariance": record.covariance,
        "bias_jacobian": record.bias_jacobian,
    }
