"""How much to inflate the noise densities so that preintegration residuals against ground truth are
consistent: :func:`calibrate_from_residuals` (``docs/noise.md`` § Calibration from residuals).

=====================  ===========================================================================
input                  M preintegrated windows (:class:`imukit.preint.Preintegration`), the true
                       states at their starts and ends (:class:`imukit.preint.States`), the true
                       bias (one, or one per window)
residual, χ²           ``r_m`` (9,) of :func:`imukit.preint.residual`, ``[θ, v, p]``;
                       ``χ²_m = r_mᵀ Σ_m⁻¹ r_m`` is χ²₉ when the covariance ``Σ_m`` is right: mean 9
model                  ``Σ_m(f) = D Σ_m D``, ``D = diag(f_θ I₃, f_v I₃, f_p I₃)``: a factor on the
                       σ of each block, i.e. on the density that drives it; blocks scale by
                       ``f_b²``, cross blocks by ``f_b f_c``
estimator              maximum likelihood of the Gaussian residuals: ``u = 1/f`` minimises
                       ``uᵀ Q u − 2M Σ_k d_k log u_k``, ``Q_bc = Σ_m r_{m,b}ᵀ (Σ_m⁻¹)_{bc} r_{m,c}``,
                       ``d_k`` the dimension of group k; convex, solved by exact coordinate steps
densities              the θ block is driven by the gyro alone: gyro density × ``f_θ``; v and p
                       by the accelerometer (the gyro enters them through ``−ΔR [a]× δθ``, a
                       share ``|a|² σ_g² Δt² / (3 σ_a²)``, 2e-6 for EuRoC at 0.1 s): accel density
                       × the one factor of v and p fitted together
=====================  ===========================================================================
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence

import numpy as np

from imukit._arrays import FloatArray, as_float_array, check_finite_rows
from imukit._errors import NonFiniteError, ParameterError, ShapeError
from imukit._preint_math import States, residual
from imukit._preint_record import Preintegration
from imukit.imu import ImuBias, ImuNoise

__all__ = ["NoiseCalibration", "calibrate_from_residuals"]

_BLOCKS = ("θ", "v", "p")
# Groups of blocks sharing one factor: free (θ | v | p), and the densities' (θ | v, p).
_FREE = ((0,), (1,), (2,))
_DENSITIES = ((0,), (1, 2))


@dataclasses.dataclass(frozen=True, eq=False)
class NoiseCalibration:
    """Inflation factors of the noise densities fitted to preintegration residuals (module docs).

    Factors multiply densities (σ), so covariance blocks scale by their square. Intervals are at
    level :attr:`confidence`, from the Fisher information of the factors' logarithms, and assume
    independent windows (on real data consecutive windows are correlated: read them as a lower
    bound on the uncertainty).
    """

    block_factors: tuple[float, float, float]
    """``(f_θ, f_v, f_p)``, each block free."""
    block_intervals: tuple[tuple[float, float], tuple[float, float], tuple[float, float]]
    """Interval of each of :attr:`block_factors`."""
    gyro_factor: float
    """The gyro density's factor: θ's, fitted with one factor for v and p together."""
    accel_factor: float
    """The accelerometer density's factor: the one of v and p."""
    gyro_interval: tuple[float, float]
    accel_interval: tuple[float, float]
    noise: ImuNoise
    """The windows' densities times the factors; the random walks as they were (the 9×9 residual
    at the true bias does not see them)."""
    chi2_before: FloatArray
    """``(M,)`` whitened residuals with the windows' covariance."""
    chi2_after: FloatArray
    """``(M,)`` with the covariance scaled by (gyro, accel, accel): mean 9 at the optimum."""
    mean_interval: tuple[float, float]
    """Where the mean of M χ²₉ values falls with probability :attr:`confidence`:
    ``χ²_{9M}`` quantiles over M."""
    confidence: float

    @property
    def chi2_bound(self) -> float:
        """The χ²₉ quantile at :attr:`confidence` (21.67 at 0.99): about ``1 − confidence`` of consistent
        windows exceed it."""
        from scipy import stats  # here, not at the top: scipy.stats is 0.7 s of `import imukit`

        return float(stats.chi2(9).ppf(self.confidence))

    def __str__(self) -> str:
        level = f"{100 * self.confidence:g}%"
        blocks = ", ".join(
            f"{name} {f:.3g} [{lo:.3g}, {hi:.3g}]"
            for name, f, (lo, hi) in zip(_BLOCKS, self.block_factors, self.block_intervals)
        )
        lo, hi = self.mean_interval
        rows = [
            f"windows: {len(self.chi2_before)}; factors on the densities ({level} intervals):",
            f"  per block: {blocks}",
            f"  gyro {self.gyro_factor:.3g} [{self.gyro_interval[0]:.3g}, {self.gyro_interval[1]:.3g}], "
            f"accel {self.accel_factor:.3g} [{self.accel_interval[0]:.3g}, {self.accel_interval[1]:.3g}]",
        ]
        for name, chi2 in (("before", self.chi2_before), ("after", self.chi2_after)):
            rows.append(
                f"  chi2 {name}: mean {chi2.mean():.4g} ({level} interval of the mean of 9: [{lo:.4g}, {hi:.4g}]), "
                f"{np.mean(chi2 > self.chi2_bound):.3f} of windows over {self.chi2_bound:.4g} "
                f"(consistent: {1 - self.confidence:g})"
            )
        return "\n".join(rows)


def calibrate_from_residuals(
    windows: Preintegration,
    state_i: States,
    state_j: States,
    *,
    bias: ImuBias | Sequence[ImuBias] | None = None,
    confidence: float = 0.99,
) -> NoiseCalibration:
    """Per-block inflation factors of the noise densities that make the whitened residuals of
    ``windows`` against the true states consistent (χ² mean 9), and the corrected densities.

    Parameters
    ----------
    windows
        M ≥ 1 preintegrated windows, e.g. :func:`imukit.preintegrate_windows` of a recording with
        ground truth; ``windows.params.noise`` are the densities to calibrate.
    state_i, state_j
        The true states at the windows' starts and ends (:class:`imukit.preint.States`, M rows each).
    bias
        The true bias: one :class:`imukit.ImuBias` for every window, a sequence of M (e.g. the
        ground-truth bias at each window's start), or None (the windows' integration bias). Applied
        by the first-order correction, as in :func:`imukit.preint.residual`.
    confidence
        Level of the factors' intervals and of the χ² bounds, in (0, 1).

    Returns
    -------
    NoiseCalibration

    Raises
    ------
    ParameterError
        A bias sequence of the wrong length, ``confidence`` outside (0, 1), a block whose residuals
        are all zero (nothing to scale), a singular covariance (a density of 0).
    ShapeError, DTypeError, NonFiniteError
        States that are not (M, 3), (M, 3), (M, 3, 3) finite real arrays (naming ``state_i`` /
        ``state_j``); residuals, covariances or factors that are not finite (naming ``windows``).

    Notes
    -----
    With ``D = diag(f_θ I₃, f_v I₃, f_p I₃)`` and ``u = 1/f``, twice the negative log-likelihood of
    the residuals under ``D Σ_m D`` is, up to a constant, ``J(u) = uᵀ Q u − 2M Σ_b 3 log u_b`` with
    ``Q_bc = Σ_m r_{m,b}ᵀ (Σ_m⁻¹)_{bc} r_{m,c}`` (3×3, positive semi-definite). ``J`` is strictly
    convex for u > 0 (its Hessian ``2 Q + 6M diag(u)⁻²`` is positive definite whatever the data), so
    the optimum is unique: each factor is identifiable, pinned by its own block's 3M whitened
    components (the cross terms only couple them). At the optimum
    ``u_b (Q u)_b = 3M`` for each b, so ``uᵀ Q u = 9M``: the mean χ² after the correction is exactly
    9. Each coordinate step solves its quadratic exactly; tying v and p to one factor (the
    accelerometer's) is the same with a group of dimension 6. The intervals come from the inverse
    Hessian in ``log u``, ``(diag(u) Q diag(u) + M diag(d))⁻¹``. The consistency test itself (the
    mean of M whitened errors against ``χ²_{9M} / M``) is the NEES test of Bar-Shalom, Li &
    Kirubarajan, "Estimation with Applications to Tracking and Navigation" (2001), § 5.4.
    """
    if not isinstance(windows, Preintegration):
        raise ParameterError(
            f"expected an imukit.preint.Preintegration, got {type(windows).__name__}", argument="windows"
        )
    if not (isinstance(confidence, (float, int)) and not isinstance(confidence, bool) and 0.0 < confidence < 1.0):
        raise ParameterError(f"expected a number in (0, 1), got {confidence!r}", argument="confidence")
    m = len(windows)
    r = _residuals(windows, _states(state_i, "state_i", m), _states(state_j, "state_j", m), bias)
    cov = windows.covariance
    if not (np.isfinite(r).all() and np.isfinite(cov).all()):
        raise NonFiniteError("the residuals or covariances are not all finite", argument="windows")
    try:
        chol = np.linalg.cholesky(cov)
    except np.linalg.LinAlgError:
        raise ParameterError("a window's covariance is singular (a noise density of 0?)", argument="windows") from None
    # Each block's residual alone, whitened: y_b = L⁻¹ (r restricted to b), so that Q_bc = Σ_m y_bᵀ y_c
    # is a Gram matrix (positive semi-definite in floating point too) and χ² = |Σ_b y_b|².
    blocks = np.einsum("mi,bi->mbi", r, np.repeat(np.eye(3), 3, axis=1))
    with np.errstate(over="ignore", invalid="ignore"):
        y = np.linalg.solve(chol[:, None], blocks[..., None])[..., 0]  # (M, block, 9)
        q = np.einsum("mbi,mci->bc", y, y)
    if not np.isfinite(q).all():
        raise NonFiniteError(
            "the whitened residuals overflow float64 (states far from the windows?)", argument="windows"
        )
    whole = y.sum(axis=1)
    chi2_before = np.einsum("mi,mi->m", whole, whole)
    from scipy import stats

    z = float(stats.norm.ppf(0.5 + confidence / 2.0))
    given = windows.params.noise
    with np.errstate(over="ignore", invalid="ignore"):  # an overflow is refused just below
        free, free_iv = _fit(q, m, _FREE, z)
        tied, tied_iv = _fit(q, m, _DENSITIES, z)
        densities = {"gyro_density": given.gyro_density * tied[0], "accel_density": given.accel_density * tied[1]}
    if not all(map(math.isfinite, (*free, *tied, *densities.values()))):
        raise NonFiniteError("the factors overflow float64 (states far from the windows?)", argument="windows")
    noise = dataclasses.replace(given, **densities)
    after = np.einsum("mbi,b->mi", y, [1.0 / tied[0], 1.0 / tied[1], 1.0 / tied[1]])
    chi2_after = np.einsum("mi,mi->m", after, after)
    dist = stats.chi2(9 * m)
    return NoiseCalibration(
        block_factors=(free[0], free[1], free[2]),
        block_intervals=(free_iv[0], free_iv[1], free_iv[2]),
        gyro_factor=tied[0],
        accel_factor=tied[1],
        gyro_interval=tied_iv[0],
        accel_interval=tied_iv[1],
        noise=noise,
        chi2_before=chi2_before,
        chi2_after=chi2_after,
        mean_interval=(float(dist.ppf((1 - confidence) / 2) / m), float(dist.ppf((1 + confidence) / 2) / m)),
        confidence=float(confidence),
    )


def _states(states: object, name: str, m: int) -> States:
    """``states`` as :class:`States` of M finite float64 rows: (M, 3), (M, 3), (M, 3, 3)."""
    if not isinstance(states, States):
        raise ParameterError(f"expected an imukit.preint.States, got {type(states).__name__}", argument=name)
    fields = []
    for field, tail in zip(States._fields, ((3,), (3,), (3, 3))):
        array = np.ascontiguousarray(as_float_array(getattr(states, field), f"{name}.{field}"))
        if array.shape != (m, *tail):
            raise ShapeError(f"expected shape {('M', *tail)} with M = {m} windows, got {array.shape}", argument=name)
        check_finite_rows(array, name, "window")
        fields.append(array)
    return States(*fields)


def _residuals(
    windows: Preintegration, state_i: States, state_j: States, bias: ImuBias | Sequence[ImuBias] | None
) -> FloatArray:
    """(M, 9) residuals; a bias per window is applied window by window (``residual`` takes one)."""
    if bias is None or isinstance(bias, ImuBias):
        return residual(windows, state_i, state_j, bias)
    biases = list(bias)
    if len(biases) != len(windows):
        raise ParameterError(
            f"expected one ImuBias or {len(windows)} (one per window), got {len(biases)}", argument="bias"
        )
    rows = [
        residual(windows[k], States(*(a[k : k + 1] for a in state_i)), States(*(a[k : k + 1] for a in state_j)), b)
        for k, b in enumerate(biases)
    ]
    return np.concatenate(rows)


def _fit(
    q: FloatArray, m: int, groups: tuple[tuple[int, ...], ...], z: float
) -> tuple[list[float], list[tuple[float, float]]]:
    """The factors ``f = 1/u`` of ``groups`` of blocks minimising ``J`` (module docs), and their intervals."""
    member = np.zeros((3, len(groups)))
    for k, blocks in enumerate(groups):
        member[list(blocks), k] = 1.0
    qg = member.T @ q @ member
    dims = 3.0 * member.sum(axis=0)
    empty = np.flatnonzero(np.diag(qg) <= 0.0)
    if empty.size:
        names = ", ".join(_BLOCKS[b] for b in groups[int(empty[0])])
        raise ParameterError(f"the residuals of block {names} are all zero: nothing to scale", argument="windows")
    u = np.sqrt(m * dims / np.diag(qg))  # each group alone, a start within the convex basin
    for _ in range(10_000):
        before = u.copy()
        for k in range(len(u)):
            s = float(qg[k] @ u - qg[k, k] * u[k])
            u[k] = (-s + math.sqrt(s * s + 4.0 * qg[k, k] * m * dims[k])) / (2.0 * qg[k, k])
        if np.max(np.abs(u - before) / u) < 1e-14:
            break
    hessian = u[:, None] * qg * u[None, :] + np.diag(m * dims)
    sd = np.sqrt(np.diag(np.linalg.inv(hessian)))  # of log u, hence of log f
    factors = [float(1.0 / x) for x in u]
    return factors, [(f * math.exp(-z * s), f * math.exp(z * s)) for f, s in zip(factors, sd)]
