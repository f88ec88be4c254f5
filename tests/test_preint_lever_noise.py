"""The covariance of a preintegration with a lever arm: the gyro noise that the conversion to the
body origin puts into the corrected accelerometer (centripetal ``D(ω) R n_k``, tangential
``[r]× R (n_k+1 − n_k−1) / Δt``) is in it (core: ``crates/imukit/src/preint/lever.rs``). Checked
against a dense reference (finite-difference sensitivities of the whole pipeline to every raw
reading), a Monte Carlo NEES that the old, direct-noise-only covariance fails, merge = one pass,
and the bias walk (``combined=True``) against its sum over the tail windows' bias Jacobians."""

from __future__ import annotations

import pickle

import numpy as np
import numpy.typing as npt
import pytest
from scipy.spatial.transform import Rotation
from scipy.stats import chi2

import imukit as ik
from imukit._extrinsics import origin_readings

Array = npt.NDArray[np.float64]
R_BS = Rotation.from_euler("ZYX", [120, -30, 45], degrees=True)
H = 0.005
RECORD = 103
# (σ_g, σ_a, |r| scale): tactical, and gyro noise dominating
CASES = {"tactical": (2e-3, 2e-2, 0.3), "gyro-dominated": (2e-3, 1e-4, 0.5)}


def noise(sigma_g: float, sigma_a: float, walk: float = 0.0) -> ik.ImuNoise:
    return ik.ImuNoise(gyro_density=sigma_g, accel_density=sigma_a, gyro_random_walk=walk, accel_random_walk=walk)


def clean(n: int, seed: int = 11) -> tuple[Array, Array]:
    """Smooth rates of about 1 rad/s and a random specific force around gravity, 200 Hz."""
    rng = np.random.default_rng(seed)
    k = np.arange(n)[:, None] * H
    gyro = np.sin(k * rng.uniform(1, 4, 3) + rng.uniform(0, 6, 3)) * rng.uniform(0.5, 2.0, 3)
    return gyro, rng.normal(0.0, 3.0, (n, 3)) + np.array([0.0, 0.0, 9.81])


def params_of(case: str, scheme: str, **kw: object) -> ik.PreintParams:
    sg, sa, arm = CASES[case]
    pose = (R_BS, np.array([arm, -arm / 3, arm / 2]))
    return ik.PreintParams(noise(sg, sa), scheme=scheme, body_from_sensor=pose, **kw)  # type: ignore[arg-type]


def deltas(pim: ik.PreintegratedImu | ik.Preintegration, m: int = 0) -> Array:
    s = pim.snapshot() if isinstance(pim, ik.PreintegratedImu) else pim
    rot = Rotation.from_matrix(s.delta_rotation[m]).as_rotvec()
    return np.concatenate([rot, s.delta_velocity[m], s.delta_position[m]])


def error(a: ik.Preintegration, b: ik.Preintegration, m: int) -> Array:
    """``[Log(ΔR_aᵀ ΔR_b), Δv_b − Δv_a, Δp_b − Δp_a]`` of window m."""
    rot = Rotation.from_matrix(a.delta_rotation[0].T @ b.delta_rotation[m]).as_rotvec()
    return np.concatenate([rot, b.delta_velocity[m] - a.delta_velocity[0], b.delta_position[m] - a.delta_position[0]])


@pytest.mark.parametrize("scheme", ["midpoint", "lie_euler"])
def test_covariance_equals_the_dense_sensitivity_reference(scheme: str) -> None:
    """Σ = Σ_k S_k q_k S_kᵀ over every raw reading (gyro and accelerometer, 3 axes, each sample of
    a record of 30, the window the samples 1..28 so that its edges have neighbours outside), with
    ``S_k`` central differences (step 1e-6) of the whole pipeline (conversion and preintegration)
    and ``q = σ²/h``. Measured 2.2e-10 (midpoint), 2.3e-10 (lie_euler) relative; the
    direct-noise-only covariance is 99.8 % off (largest entry) in this gyro-dominated case."""
    n = 30
    gyro, accel = clean(n)
    imu = ik.ImuData(np.arange(n) * H, gyro, accel)
    params = params_of("gyro-dominated", scheme)
    span = (float(imu.t[1]), float(imu.t[-2]))
    got = ik.preintegrate(imu, params, span=span).covariance
    base = ik.preintegrate(imu, params, span=span).snapshot()
    ref = np.zeros((9, 9))
    step = 1e-6
    for sensor, density in (("gyro", params.noise.gyro_density), ("accel", params.noise.accel_density)):
        for k in range(n):
            for axis in range(3):
                cols = []
                for sign in (1.0, -1.0):
                    g, a = gyro.copy(), accel.copy()
                    (g if sensor == "gyro" else a)[k, axis] += sign * step
                    cols.append(error(base, ik.preintegrate(ik.ImuData(imu.t, g, a), params, span=span).snapshot(), 0))
                s = (cols[0] - cols[1]) / (2 * step)
                ref += np.outer(s, s) * density**2 / H
    assert np.abs(got - ref).max() < 1e-7 * np.abs(ref).max()
    body = origin_readings(imu, params.bias, params.body_from_sensor)
    old = _direct_only(body, params, span)
    assert np.abs(old - ref).max() > 0.1 * np.abs(ref).max()


def _direct_only(body: object, params: ik.PreintParams, span: tuple[float, float]) -> Array:
    """The old covariance: the converted readings' own, in the body frame, with independent noise."""
    imu = ik.ImuData(body.seconds, body.gyro, body.accel)  # type: ignore[attr-defined]
    plain = params.replace(body_from_sensor=None)
    return ik.preintegrate(imu, plain, span=span).covariance


def runs(case: str, scheme: str, count: int) -> tuple[Array, Array, Array]:
    """``count`` noisy re-runs of one 0.5 s window (samples 1..101 of a 103-sample record, periodic
    so that one batch holds them all: each window's differences see its own record only), their
    errors against the noise-free window, its complete covariance and the old one."""
    n = RECORD
    gyro, accel = clean(n)
    params = params_of(case, scheme)
    rng = np.random.default_rng(5)
    sg, sa = params.noise.gyro_density / np.sqrt(H), params.noise.accel_density / np.sqrt(H)
    total = n * count
    t = np.arange(total) * H
    noisy_gyro = np.tile(gyro, (count, 1)) + rng.normal(0, sg, (total, 3))
    imu = ik.ImuData(t, noisy_gyro, np.tile(accel, (count, 1)) + rng.normal(0, sa, (total, 3)))
    edges = np.sort(np.concatenate([t[1::n], t[n - 2 :: n]]))
    rec = ik.preintegrate_windows(imu, edges, params)
    one = ik.ImuData(t[:n], gyro, accel)
    span = (float(t[1]), float(t[n - 2]))
    ref = ik.preintegrate(one, params, span=span)
    errs = np.array([error(ref.snapshot(), rec, m) for m in range(0, len(rec.delta_t), 2)])
    old = _direct_only(origin_readings(one, params.bias, params.body_from_sensor), params, span)
    return errs, ref.covariance, old


def mean_nees(errs: Array, cov: Array) -> float:
    return float(np.mean(np.einsum("ni,ij,nj->n", errs, np.linalg.inv(cov), errs)))


@pytest.mark.parametrize("case", list(CASES))
@pytest.mark.parametrize("scheme", ["midpoint", "lie_euler"])
def test_monte_carlo_nees_is_chi2_with_the_lever_arm_noise(case: str, scheme: str) -> None:
    """Mean NEES over 800 runs inside the 95 % interval of its χ² (8.71, 9.30): measured midpoint
    8.96 / 9.02, lie_euler 8.92 / 9.06 (tactical / gyro-dominated). The old covariance (the lever
    term zero) gives 12.0 / 12.8 and 1.7e4 / 2.1e4; the lever term doubled 7.9 / 7.7 and 27 / 57."""
    count = 800
    errs, cov, old = runs(case, scheme, count)
    lo, hi = chi2.ppf([0.025, 0.975], 9 * count) / count
    nees = mean_nees(errs, cov)
    assert lo < nees < hi, nees
    assert mean_nees(errs, old) > hi
    assert not lo < mean_nees(errs, old + 2 * (cov - old)) < hi


@pytest.mark.parametrize("scheme", ["midpoint", "lie_euler"])
def test_merge_and_windows_equal_one_pass_with_the_edge_correlation(scheme: str) -> None:
    """Spans merged, streamed, and the windows of one batch equal one pass: covariance 1e-10
    relative (the correlation through the edge sample's shared noise included), and pickling
    keeps it."""
    gyro, accel = clean(120, 3)
    imu = ik.ImuData(np.arange(120) * H, gyro, accel)
    params = params_of("gyro-dominated", scheme)
    t = imu.t
    whole = ik.preintegrate(imu, params, span=(float(t[2]), float(t[117])))
    cuts = [2, 3, 40, 42, 117]  # parts of 1 and 2 intervals share edge noises with both neighbours
    spans = [(float(t[a]), float(t[b])) for a, b in zip(cuts, cuts[1:], strict=False)]
    parts = [ik.preintegrate(imu, params, span=s) for s in spans]
    merged = parts[0]
    for p in parts[1:]:
        merged = merged.merge(pickle.loads(pickle.dumps(p)))
    scale = np.abs(whole.covariance).max()
    assert np.abs(merged.covariance - whole.covariance).max() < 1e-10 * scale
    assert np.abs(merged.bias_jacobian - whole.bias_jacobian).max() < 1e-10 * np.abs(whole.bias_jacobian).max()
    assert np.abs(deltas(merged) - deltas(whole)).max() < 1e-12
    streamed = ik.PreintegratedImu(params)
    for s in spans:
        streamed.integrate(imu, span=s)
    assert np.abs(streamed.covariance - whole.covariance).max() < 1e-10 * scale
    rec = ik.preintegrate_windows(imu, t[cuts], params)
    for m, p in enumerate(parts):
        assert np.array_equal(rec.covariance[m], p.covariance)
    with pytest.raises(ik.ParameterError, match="boundaries"):
        ik.preintegrate_windows(imu, [0.0, 0.1234, float(t[-1])], params)


@pytest.mark.parametrize("scheme", ["midpoint", "lie_euler"])
def test_combined_with_a_lever_arm(scheme: str) -> None:
    """``combined=True`` with a lever arm: the 9×9 block is the complete covariance; the bias
    block's cross covariance equals ``Σ_m T_m J_b(tail m) q_w h``, the bias Jacobians of the tail
    windows (from the bias Jacobian's own path, the three preintegrations of ``L``) transported by
    ``T_m = blockdiag(I, ΔR_m, ΔR_m)``, with no white noise (measured 6e-16 relative); the windows
    of one batch equal the spans."""
    n = 40
    gyro, accel = clean(n, 9)
    imu = ik.ImuData(np.arange(n) * H, gyro, accel)
    walk = 1e-3
    pose = (R_BS, np.array([0.5, -0.2, 0.3]))
    params = ik.PreintParams(noise(0.0, 0.0, walk), scheme=scheme, combined=True, body_from_sensor=pose)
    t = imu.t
    first, last = 1, n - 2
    pim = ik.preintegrate(imu, params, span=(float(t[first]), float(t[last])))
    comb = pim.covariance_combined
    assert comb is not None
    cross = np.zeros((9, 6))
    for m in range(first + 1, last):
        head = ik.preintegrate(imu, params.replace(combined=False), span=(float(t[first]), float(t[m]))).snapshot()
        tail = ik.preintegrate(imu, params.replace(combined=False), span=(float(t[m]), float(t[last]))).bias_jacobian
        tm = np.eye(9)
        tm[3:6, 3:6] = tm[6:9, 6:9] = head.delta_rotation[0]
        cross += tm @ tail * walk**2 * H
    assert np.abs(comb[:9, 9:] - cross).max() < 1e-9 * np.abs(cross).max()
    assert np.allclose(np.diag(comb)[9:], walk**2 * H * (last - first), rtol=1e-12)
    rec = ik.preintegrate_windows(imu, [t[first], t[last]], params)
    assert rec.covariance_combined is not None
    assert np.array_equal(rec.covariance_combined[0], comb)
    full = params.replace(noise=noise(1e-2, 1e-3, walk))
    both = ik.preintegrate(imu, full, span=(float(t[first]), float(t[last])))
    assert both.covariance_combined is not None
    assert np.array_equal(both.covariance_combined[:9, :9], both.covariance)
