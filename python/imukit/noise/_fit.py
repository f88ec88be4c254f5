"""The joint weighted least-squares fit of N, B and K to an Allan variance, and its intervals."""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy import linalg

from imukit._arrays import FloatArray, as_float_array, choice
from imukit._errors import NonFiniteError, ParameterError, ShapeError
from imukit.imu import ImuNoise, _number
from imukit.noise._allan import AllanDeviation

# σ² of flicker (1/f) rate noise of coefficient B: (2 ln 2 / π) B² (IEEE Std 952, Annex C).
FLICKER_FACTOR = 2.0 * math.log(2.0) / math.pi
_SENSORS = ("gyro", "accel")
# Units of (σ and B, N, K) for each sensor; None: the input's unit, written "u".
_UNITS = {
    "gyro": ("rad/s", "rad/s/√Hz", "rad/s²/√Hz"),
    "accel": ("m/s²", "m/s²/√Hz", "m/s³/√Hz"),
    None: ("u", "u/√Hz", "u/s/√Hz"),
}


def _edf(allan: AllanDeviation, fractions: FloatArray) -> FloatArray:
    """Equivalent degrees of freedom of each AVAR estimate for a mix of the three noises.

    ``fractions`` is ``(M, 3)``: the share of white, flicker and random-walk noise in σ²(τ).
    Overlapping: the simple formulas of Howe, Allan & Barnes (1981), tabulated in Riley, NIST
    SP 1065 (2008), Table 5, for white, flicker and random-walk FM (N + 1 phase points).
    Non-overlapping: the differences of adjacent cluster means are correlated at lag 1 only
    (exactly so for white and random-walk noise), with ρ fixed by how σ² scales from m to 2m
    (ρ = (4r − 6)/8 for σ²(2m) = r σ²(m): −1/2 white, −1/4 flicker, +1/4 random walk), and
    ``edf = 2 (Σ E d²)² / Var Σ d² = n² / (n + 2 (n − 1) ρ²)``. A mix combines as
    ``1/edf = Σ_c f_c / edf_c``: by Cauchy–Schwarz this bounds the cross terms from above, so it
    errs towards fewer degrees of freedom (tested against the exact Gaussian values).
    """
    m = allan.cluster_sizes.astype(np.float64)
    if allan.overlapping:
        p = float(allan.samples + 1)
        with np.errstate(divide="ignore", invalid="ignore"):
            white = (3.0 * (p - 1.0) / (2.0 * m) - 2.0 * (p - 2.0) / p) * 4.0 * m**2 / (4.0 * m**2 + 5.0)
            flicker = np.where(m == 1.0, 2.0 * (p - 2.0) ** 2 / (2.3 * p - 4.9), 5.0 * p**2 / (4.0 * m * (p + 3.0 * m)))
            walk = (p - 2.0) / (m * (p - 3.0) ** 2) * ((p - 1.0) ** 2 - 3.0 * m * (p - 1.0) + 4.0 * m**2)
        edf = np.stack([white, flicker, walk], axis=-1)
    else:
        n = allan.clusters.astype(np.float64)[:, None]
        rho = np.array([-0.5, -0.25, 0.25])
        edf = n**2 / (n + 2.0 * (n - 1.0) * rho**2)
    # The formulas are fits; at the edges (a handful of samples) keep them at least 1.
    edf = np.where(np.isfinite(edf), np.maximum(edf, 1.0), 1.0)
    return np.asarray(1.0 / np.sum(fractions / edf, axis=-1), dtype=np.float64)


def _design(taus: FloatArray) -> FloatArray:
    """Columns of σ²(τ) = N²/τ + (2 ln 2/π) B² + K² τ/3, linear in (N², B², K²)."""
    return np.stack([1.0 / taus, np.full_like(taus, FLICKER_FACTOR), taus / 3.0], axis=-1)


def _nnls(a: FloatArray, b: FloatArray) -> FloatArray:
    """min |a θ − b| with θ ≥ 0, columns scaled to unit norm first (they span ~10 decades)."""
    norms = np.linalg.norm(a, axis=0)
    norms[norms == 0.0] = 1.0
    # scipy.optimize, .signal and .stats are imported where used: at the top they were 1.2 s of
    # every `import imukit` (and of every CLI command), which most programs never call.
    from scipy import optimize

    theta, _ = optimize.nnls(a / norms, b)
    return np.asarray(theta / norms, dtype=np.float64)


@dataclass(frozen=True)
class AllanFit:
    """White noise N, bias instability B and random walk K fitted to an Allan variance.

    ====================  ======  ==============================  ===================================
    field                 symbol  unit (gyro / accel)             σ²(τ) term
    ====================  ======  ==============================  ===================================
    ``noise_density``     N       rad/s/√Hz  /  m/s²/√Hz          N²/τ (slope −½ in σ)
    ``bias_instability``  B       rad/s  /  m/s²                  (2 ln 2/π) B² (flat, σ = 0.664 B)
    ``random_walk``       K       rad/s²/√Hz  /  m/s³/√Hz         K² τ/3 (slope +½ in σ)
    ====================  ======  ==============================  ===================================

    Each ``*_interval`` is a two-sided interval at level :attr:`confidence`. N and K are the
    continuous densities of :class:`imukit.ImuNoise` (``gyro_density`` / ``gyro_random_walk`` …).
    """

    noise_density: float
    bias_instability: float
    random_walk: float
    noise_density_interval: tuple[float, float]
    bias_instability_interval: tuple[float, float]
    random_walk_interval: tuple[float, float]
    confidence: float
    sensor: str | None
    """``"gyro"``, ``"accel"`` or None (units unknown), as passed to :func:`fit_allan`."""
    covariance: FloatArray
    """``(3, 3)`` covariance of (N², B², K²), scaled by max(1, χ²/dof)."""
    chi2: float
    """Weighted residual sum of squares at the solution."""
    dof: int
    """Points used minus 3."""
    taus: FloatArray
    """``(M,)`` the τ values the fit used [s]."""

    @property
    def random_walk_resolved(self) -> bool:
        """False when the interval of K reaches 0: the recording cannot tell the random walk from none
        (typically too short, K showing only past τ ~ its length / 10). Written as the fitted value, a
        K of 0 tells a VIO system that the bias is constant; :func:`to_imu_noise` writes the upper end."""
        return self.random_walk_interval[0] > 0.0

    def variance(self, taus: ArrayLike) -> FloatArray:
        """Model σ²(τ) at ``taus`` [s]."""
        return np.asarray(self.components(taus) ** 2 @ np.ones(3), dtype=np.float64)

    def deviation(self, taus: ArrayLike) -> FloatArray:
        """Model σ(τ) at ``taus`` [s]."""
        return np.sqrt(self.variance(taus))

    def components(self, taus: ArrayLike) -> FloatArray:
        """``(M, 3)`` deviations of the white, flicker and random-walk terms alone at ``taus`` [s]."""
        t = as_float_array(taus, "taus").reshape(-1)
        bad = np.flatnonzero(~(np.isfinite(t) & (t > 0.0)))
        if bad.size:
            raise ParameterError(
                f"expected positive, finite seconds, got {float(t[bad[0]])!r} at index {bad[0]}", argument="taus"
            )
        theta = np.array([self.noise_density, self.bias_instability, self.random_walk]) ** 2
        with np.errstate(over="ignore", invalid="ignore"):  # 1/τ of a subnormal τ; a term whose θ is 0 is 0
            terms = np.where(theta > 0.0, np.sqrt(_design(t) * theta), 0.0)
        bad = np.flatnonzero(~np.isfinite(terms).all(axis=1))
        if bad.size:
            k = int(bad[0])
            raise NonFiniteError(f"the model overflows float64 at τ = {float(t[k])!r} s (index {k})", argument="taus")
        return np.asarray(terms, dtype=np.float64)

    def __str__(self) -> str:
        unit, density, walk = _UNITS[self.sensor]
        rows = (
            ("N", self.noise_density, self.noise_density_interval, density),
            ("B", self.bias_instability, self.bias_instability_interval, unit),
            ("K", self.random_walk, self.random_walk_interval, walk),
        )
        level = f"{100 * self.confidence:g}%"
        return "\n".join(f"{s} = {v:.4g} {u}  ({level}: [{lo:.4g}, {hi:.4g}])" for s, v, (lo, hi), u in rows)


def fit_allan(
    allan: AllanDeviation,
    *,
    sensor: str | None = None,
    axis: int | None = None,
    confidence: float = 0.95,
    tau_min: float | None = None,
    tau_max: float | None = None,
) -> AllanFit:
    """Fit N, B and K jointly to an Allan variance by weighted non-negative least squares.

    Parameters
    ----------
    allan
        The result of :func:`allan_deviation`.
    sensor
        ``"gyro"`` or ``"accel"``: what the signal is, for units and :func:`to_imu_noise`; None
        leaves the units unnamed.
    axis
        For ``(M, C)`` deviations: the column to fit. None fits one (N, B, K) to all columns
        together (independent axes of one sensor type, as :class:`imukit.ImuNoise` assumes).
    confidence
        Level of the intervals, in (0, 1).
    tau_min, tau_max
        Fit only τ in ``[tau_min, tau_max]`` [s] (e.g. to leave out quantisation noise at short τ).

    Returns
    -------
    AllanFit

    Raises
    ------
    ParameterError
        An option out of its domain, fewer than 4 τ values to fit, or an ``allan`` that is not an
        :class:`AllanDeviation`.

    Notes
    -----
    σ²(τ) = N²/τ + (2 ln 2/π) B² + K² τ/3 is linear in θ = (N², B², K²), so all three are fitted
    at once, by least squares on the variances with θ ≥ 0 (scipy's NNLS), rather than by reading
    straight lines of slope −½, 0, +½ off the log-log plot, which attributes to one term what
    the others add. Each point is weighted by the inverse variance of its estimate,
    ``Var σ̂² = 2 σ⁴ / edf``, with σ² from the current model and the equivalent degrees of freedom
    of the estimator for the current mix of noises (:func:`_edf`); the fit is iterated until θ
    settles. Octave-spaced τ values are close to uncorrelated (Schlossberger & Howe, "Analysis
    of powers-of-two calculations of the Allan variance", 2019), so the points are treated as
    independent. Intervals: the WLS covariance ``(AᵀWA)⁻¹`` of θ, scaled by max(1, χ²/dof)
    (Birge ratio) to absorb a misfit, gives the interval ``θ ± q σ_θ`` (q the normal quantile, or
    Student's with dof when scaled) clipped at 0; its end points, square-rooted, bound N, B and
    K (square root is monotone, so coverage carries over, and a term at 0 gets ``[0, …]``).
    """
    allan = _checked(allan)
    if sensor is not None and sensor not in _SENSORS:
        raise ParameterError(f"expected one of {_SENSORS} or None, got {sensor!r}", argument="sensor")
    if not (isinstance(confidence, (float, int)) and 0.0 < confidence < 1.0):
        raise ParameterError(f"expected a number in (0, 1), got {confidence!r}", argument="confidence")
    dev = np.asarray(allan.deviation, dtype=np.float64)
    columns = dev.reshape(len(allan.taus), -1)
    if axis is not None:
        if not isinstance(axis, (int, np.integer)) or not -columns.shape[1] <= axis < columns.shape[1]:
            raise ParameterError(
                f"expected None or a column index below {columns.shape[1]}, got {axis!r}", argument="axis"
            )
        columns = columns[:, [int(axis)]]
    lo = 0.0 if tau_min is None else _bound(tau_min, "tau_min")
    hi = math.inf if tau_max is None else _bound(tau_max, "tau_max")
    if lo > hi:
        raise ParameterError(f"expected tau_min ≤ tau_max, got {lo} > {hi} s", argument="tau_min / tau_max")
    keep = (allan.taus >= lo) & (allan.taus <= hi)
    if np.count_nonzero(keep) < 4:
        raise ParameterError(
            f"fitting 3 parameters needs at least 4 τ values, got {np.count_nonzero(keep)} "
            f"in [tau_min, tau_max] = [{lo}, {hi}] s",
            argument="allan" if tau_min is None and tau_max is None else "tau_min / tau_max",
        )
    sub = allan._replace(taus=allan.taus[keep], deviation=columns[keep], clusters=np.asarray(allan.clusters)[keep])
    taus = sub.taus
    a_one = _design(taus)
    k = columns.shape[1]
    if not np.any(sub.deviation > 0.0):
        raise ParameterError("the Allan variance is 0 at every τ (a constant signal): nothing to fit", argument="allan")
    # Fitted in units of the largest deviation, so that the weights (which go as σ⁻⁴) neither
    # overflow nor underflow: θ = (N², B², K²) scales back by scale², its covariance by scale⁴.
    scale = float(np.max(sub.deviation))
    sub = sub._replace(deviation=sub.deviation / scale)
    ys = (sub.deviation**2).T  # (k, M): one row per fitted column
    theta = _gls_step(sub, a_one, ys, None)
    for _ in range(50):
        new = _gls_step(sub, a_one, ys, theta)
        settled = np.allclose(new, theta, rtol=1e-9, atol=1e-12 * float(np.max(new)))
        theta = new
        if settled:
            break
    chol = np.linalg.cholesky(_estimate_covariance(sub, a_one, theta, ys))
    aw = linalg.solve_triangular(chol, a_one, lower=True)
    resid = linalg.solve_triangular(chol, ys.T - (a_one @ theta)[:, None], lower=True)
    chi2 = float(np.sum(resid**2))
    dof = resid.size - 3
    norms = np.linalg.norm(aw, axis=0)
    norms[norms == 0.0] = 1.0
    cov = np.linalg.pinv(k * (aw / norms).T @ (aw / norms)) / np.outer(norms, norms)
    birge = chi2 / dof if dof > 0 else 1.0
    from scipy import stats

    if birge > 1.0:
        cov = cov * birge
        q = float(stats.t.ppf(0.5 + confidence / 2.0, dof))
    else:
        q = float(stats.norm.ppf(0.5 + confidence / 2.0))
    half = q * np.sqrt(np.maximum(np.diag(cov), 0.0))
    ends = [(scale * math.sqrt(max(t - h, 0.0)), scale * math.sqrt(t + h)) for t, h in zip(theta, half)]
    n_, b_, k_ = (scale * math.sqrt(t) for t in theta)
    with np.errstate(over="ignore"):
        cov = cov * scale**2 * scale**2
    if not np.isfinite(cov).all():
        raise NonFiniteError(
            f"values up to {scale!r} make the covariance of (N², B², K²) overflow float64", argument="allan.deviation"
        )
    return AllanFit(
        noise_density=n_,
        bias_instability=b_,
        random_walk=k_,
        noise_density_interval=ends[0],
        bias_instability_interval=ends[1],
        random_walk_interval=ends[2],
        confidence=float(confidence),
        sensor=sensor,
        covariance=cov,
        chi2=chi2,
        dof=dof,
        taus=taus.copy(),
    )


def _checked(allan: object) -> AllanDeviation:
    """``allan`` with float64 ``taus`` (M,) > 0 and ``deviation`` (M,) or (M, C) ≥ 0 whose squares are
    finite, and ``clusters`` (M,) ≥ 1: a record built by hand is checked as allan_deviation's input is."""
    if not isinstance(allan, AllanDeviation):
        raise ParameterError(
            f"expected the AllanDeviation of allan_deviation(), got {type(allan).__name__}", argument="allan"
        )
    taus = as_float_array(allan.taus, "allan.taus")
    if taus.ndim != 1 or not (np.isfinite(taus).all() and (taus > 0).all()):
        raise ParameterError(f"expected (M,) positive, finite seconds, got {allan.taus!r}", argument="allan.taus")
    rate = _number(allan.rate, "allan.rate", positive=True, what="a positive, finite sample rate in Hz")
    samples = allan.samples
    if isinstance(samples, bool) or not isinstance(samples, (int, np.integer)) or samples < 2:
        raise ParameterError(f"expected an integer N ≥ 2, got {samples!r}", argument="allan.samples")
    m = np.rint(taus * rate)
    if not ((m >= 1) & (2 * m <= samples)).all():
        raise ParameterError(
            f"expected τ = m / rate with 1 ≤ m ≤ N/2 = {samples // 2} samples, got {allan.taus!r}",
            argument="allan.taus",
        )
    dev = as_float_array(allan.deviation, "allan.deviation")
    if dev.ndim not in (1, 2) or len(dev) != len(taus):
        raise ShapeError(
            f"expected shape (M,) or (M, C) with M = len(taus) = {len(taus)}, got {dev.shape}",
            argument="allan.deviation",
        )
    with np.errstate(over="ignore"):
        squares_finite = np.isfinite(dev * dev).all()
    if not (squares_finite and (dev >= 0).all()):
        raise NonFiniteError("expected non-negative values whose squares are finite", argument="allan.deviation")
    clusters = np.asarray(allan.clusters)
    if clusters.shape != taus.shape or clusters.dtype.kind not in "iu" or not (clusters >= 1).all():
        raise ParameterError(f"expected (M,) integers ≥ 1, got {allan.clusters!r}", argument="allan.clusters")
    return allan._replace(taus=taus, deviation=dev)


def _bound(value: object, name: str) -> float:
    return _number(value, name, positive=False, what="a non-negative number of seconds or None")


def _gls_step(allan: AllanDeviation, a_one: FloatArray, ys: FloatArray, theta: FloatArray | None) -> FloatArray:
    """θ ≥ 0 minimising the generalised squared residual of every column, with the covariance of
    the estimates taken at ``theta`` (None: from the data, as white noise)."""
    chol = np.linalg.cholesky(_estimate_covariance(allan, a_one, theta, ys))
    aw = linalg.solve_triangular(chol, a_one, lower=True)
    yw = linalg.solve_triangular(chol, ys.T, lower=True)
    return _nnls(np.tile(aw, (ys.shape[0], 1)), yw.T.reshape(-1))


def _estimate_covariance(
    allan: AllanDeviation, a_one: FloatArray, theta: FloatArray | None, ys: FloatArray
) -> FloatArray:
    """``(M, M)`` covariance of the σ̂² estimates of one column under the model θ (None: the data).

    Diagonal: ``2 σ⁴ / edf`` with σ² from the model and the edf of its mix of noises (:func:`_edf`).
    Off the diagonal: estimates at different τ from one record are strongly correlated (0.53
    between adjacent octaves for white noise, 0.89 for random walk, overlapping estimator), so
    treating them as independent makes the intervals far too narrow. The correlation of each
    pure noise comes from :func:`_kernel_correlations`; a mix takes
    ``ρ_ij = Σ_c √(f_c(τ_i) f_c(τ_j)) ρ_c(τ_i, τ_j)`` (noises are independent; a cross term between
    two noises is dropped), then the matrix is projected onto the positive-definite cone.
    """
    parts = a_one * theta if theta is not None else None
    if parts is None or not np.any(parts.sum(axis=1) > 0.0):
        level = np.maximum(ys.mean(axis=0), 1e-12 * float(np.max(ys)))
        fractions = np.tile([1.0, 0.0, 0.0], (len(level), 1))
    else:
        level = parts.sum(axis=1)
        fractions = parts / np.where(level > 0.0, level, 1.0)[:, None]
        fractions[level <= 0.0] = [1.0, 0.0, 0.0]
        level = np.maximum(level, 1e-12 * float(np.max(level)))
    sd = level * np.sqrt(2.0 / _edf(allan, fractions))
    rho = _kernel_correlations(
        tuple(int(v) for v in allan.cluster_sizes), tuple(int(v) for v in allan.clusters), allan.overlapping
    )
    root = np.sqrt(fractions).T  # (3, M)
    mix = np.einsum("ci,cij,cj->ij", root, rho, root)
    values, vectors = np.linalg.eigh(mix)
    mix = (vectors * np.maximum(values, 1e-9 * values[-1])) @ vectors.T
    return np.asarray(mix * np.outer(sd, sd), dtype=np.float64)


# Correlations between cluster sizes above this are taken at the same ratio, scaled down
# (they depend on the ratio alone once m is past ~8).
_MAX_KERNEL = 2048


def _kernel(m: int, kind: int) -> FloatArray:
    """Weights of the samples (white noise) or of the steps (random walk) in one difference d_k."""
    if kind == 0:
        return np.concatenate([-np.ones(m), np.ones(m)])
    j = np.arange(2 * m + 1, dtype=np.float64)
    return np.minimum(j, 2.0 * m - j)


@functools.lru_cache(maxsize=4096)
def _lag_power(a: int, b: int, kind: int, step: int) -> float:
    """``Σ_{h ∈ step ℤ} X(h)²``, X the cross-correlation of the kernels of cluster sizes a and b."""
    from scipy import signal

    kb = _kernel(b, kind)
    x = signal.fftconvolve(_kernel(a, kind), kb[::-1])
    lags = np.arange(len(x)) - (len(kb) - 1)
    return float(np.sum(x[lags % step == 0] ** 2))


@functools.lru_cache(maxsize=64)
def _kernel_correlations(m: tuple[int, ...], n: tuple[int, ...], overlapping: bool) -> FloatArray:
    """``(3, M, M)`` correlations of σ̂²(m_i) and σ̂²(m_j) for white, flicker, random-walk noise.

    For Gaussian noise ``Cov(Σ d_j², Σ e_k²) = 2 Σ_{j,k} Cov(d_j, e_k)²``, and ``Cov(d_j, e_k)`` is the
    cross-correlation X of the two difference kernels (white: the samples' weights −1…−1, +1…+1;
    random walk: the steps' weights, a tent) at the lag between the start indices. With every
    start (overlapping) the double sum is ``min(n_a, n_b) Σ_h X(h)²``; with starts on ``a ℤ`` and
    ``b ℤ`` (non-overlapping, a ≤ b) it is ``n_b (g/a) Σ_{h ∈ g ℤ} X(h)²``, g = gcd(a, b); end
    effects are neglected. Past m = 2048 a pair is evaluated at the same ratio scaled down (the
    correlation depends on the ratio alone once m exceeds ~8). Flicker noise, which has no finite
    kernel, takes the mean of the two.
    """
    size = len(m)
    out = np.ones((3, size, size))
    for kind in (0, 2):
        for i in range(size):
            for j in range(i + 1, size):
                (a, na), (b, nb) = sorted(((m[i], n[i]), (m[j], n[j])))
                if b > _MAX_KERNEL:
                    a, b = max(1, round(a * _MAX_KERNEL / b)), _MAX_KERNEL
                if overlapping:
                    cross = min(na, nb) * _lag_power(a, b, kind, 1)
                    own = na * _lag_power(a, a, kind, 1) * nb * _lag_power(b, b, kind, 1)
                else:
                    g = math.gcd(a, b)
                    cross = nb * g / a * _lag_power(a, b, kind, g)
                    own = na * _lag_power(a, a, kind, a) * nb * _lag_power(b, b, kind, b)
                out[kind, i, j] = out[kind, j, i] = cross / math.sqrt(own)
    out[1] = 0.5 * (out[0] + out[2])
    return out


UNRESOLVED = ("upper", "fitted")
"""What :func:`to_imu_noise` may write for a random walk that is not resolved."""


def to_imu_noise(*, gyro: AllanFit, accel: AllanFit, unresolved: str = "upper") -> ImuNoise:
    """An :class:`imukit.ImuNoise` from a gyro fit and an accelerometer fit (continuous densities).

    ``gyro_density = gyro.noise_density``, ``gyro_random_walk = gyro.random_walk``, and the same
    for the accelerometer; the bias instabilities have no place in ``ImuNoise`` and are dropped.
    Each fit must have been made with the matching ``sensor=``, so the two cannot be swapped.

    ``unresolved``: the random walk of a fit whose K interval reaches 0
    (:attr:`AllanFit.random_walk_resolved` False) is, with ``"upper"`` (default), the upper end of
    that interval: the largest K the data allow, never below the fitted one, so that a filter using
    the file keeps its bias estimate open; with ``"fitted"``, the fitted value as it is (possibly 0,
    which a VIO system reads as a constant bias).
    """
    policy = choice(unresolved, "unresolved", UNRESOLVED)
    for name, fit in (("gyro", gyro), ("accel", accel)):
        if not isinstance(fit, AllanFit):
            raise ParameterError(f"expected an AllanFit, got {type(fit).__name__}", argument=name)
        if fit.sensor != name:
            raise ParameterError(f"expected a fit made with sensor={name!r}, got sensor={fit.sensor!r}", argument=name)

    def walk(fit: AllanFit) -> float:
        return fit.random_walk_interval[1] if policy == "upper" and not fit.random_walk_resolved else fit.random_walk

    return ImuNoise(
        gyro_density=gyro.noise_density,
        accel_density=accel.noise_density,
        gyro_random_walk=walk(gyro),
        accel_random_walk=walk(accel),
    )
