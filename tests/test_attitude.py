"""integrate_attitude: exactness for constant rate, measured convergence orders, agreement of
representations, real data (EuRoC), and bad input."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import imukit as ik
from trajectories import attitude, body_rate, coning_attitude, coning_body_rate

PAIRS = [
    (s, r)
    for r in ik.attitude.REPRESENTATIONS
    for s in ik.attitude.SCHEMES
    if r != "euler" or s not in ("exp", "magnus")
]
EXPECTED_ORDER = {"euler": 1, "exp": 1, "rk2": 2, "midpoint": 2, "rk4": 4, "magnus": 4}


def angle_error(a: Rotation, b: Rotation) -> np.ndarray:
    return (a.inv() * b).magnitude()


@pytest.mark.parametrize("scheme", ["exp", "magnus"])
@pytest.mark.parametrize("representation", ["quaternion", "matrix"])
def test_constant_rate_is_exact_after_a_million_steps(scheme: str, representation: str) -> None:
    n = 1_000_000
    t = np.arange(n) * 0.001
    w = np.array([0.31, -0.52, 0.77])
    r0 = Rotation.from_rotvec([0.1, 0.2, -0.3])
    final = ik.integrate_attitude(
        t, np.tile(w, (n, 1)), initial=r0, scheme=scheme, representation=representation, final_only=True
    )
    truth = r0 * Rotation.from_rotvec(w * (t[-1] - t[0]))
    assert angle_error(final, truth) < 1e-9


def final_error(scheme: str, representation: str, h: float, *, jitter: bool = False) -> float:
    duration = 3.0
    n = round(duration / h) + 1
    t = np.linspace(0.0, duration, n)
    if jitter:  # non-uniform sampling, end points kept
        t[1:-1] += 0.25 * h * np.sin(np.arange(1, n - 1) * 1.7)
    r = ik.integrate_attitude(
        t, body_rate(t), initial=attitude(t[:1])[0], scheme=scheme, representation=representation, final_only=True
    )
    return float(angle_error(r, attitude(t[-1:])[0]))


def measured_order(scheme: str, representation: str, *, jitter: bool = False) -> float:
    steps = np.array([0.04, 0.02, 0.01, 0.005])
    if EXPECTED_ORDER[scheme] == 4:
        steps = steps * 2  # keep the finest error well above rounding
    errors = np.array([final_error(scheme, representation, h, jitter=jitter) for h in steps])
    slope = np.polyfit(np.log(steps), np.log(errors), 1)[0]
    return float(slope)


@pytest.mark.parametrize(("scheme", "representation"), PAIRS)
def test_convergence_order(scheme: str, representation: str) -> None:
    order = measured_order(scheme, representation)
    assert abs(order - EXPECTED_ORDER[scheme]) < 0.3, f"{scheme}/{representation}: measured order {order:.2f}"


@pytest.mark.parametrize("scheme", ["rk4", "magnus", "midpoint"])
def test_convergence_order_on_jittered_timestamps(scheme: str) -> None:
    order = measured_order(scheme, "quaternion", jitter=True)
    assert abs(order - EXPECTED_ORDER[scheme]) < 0.3, f"{scheme}: measured order {order:.2f}"


def _coning_error(h: float, coning_sign: float | None) -> float:
    """Final error of R ← R Exp(½h(ω₁+ω₂) + s (√3/12) h² ω₁×ω₂) on the coning trajectory.

    ``coning_sign=None`` runs imukit's magnus; ±1 runs this reference loop with the term's sign s.
    """
    n = round(4.0 / h) + 1
    t = np.linspace(0.0, 4.0, n)
    r0 = coning_attitude(t[:1])[0]
    if coning_sign is None:
        r = ik.integrate_attitude(t, coning_body_rate(t), initial=r0, scheme="magnus", final_only=True)
    else:
        g = h * np.sqrt(3) / 6
        w1, w2 = coning_body_rate(t[:-1] + h / 2 - g), coning_body_rate(t[:-1] + h / 2 + g)
        theta = h / 2 * (w1 + w2) + coning_sign * np.sqrt(3) / 12 * h**2 * np.cross(w1, w2)
        r = r0
        for step in Rotation.from_rotvec(theta):
            r = r * step
    return float(angle_error(r, coning_attitude(t[-1:])[0]))


def test_magnus_coning_term_and_its_sign() -> None:
    """On coning motion the commutator term carries the fourth order, and only with its sign.

    The reference loop uses exact rates at the Gauss nodes; imukit interpolates them from samples.
    """
    steps = np.array([0.04, 0.02, 0.01, 0.005])

    def order(sign: float | None) -> float:
        errors = [_coning_error(h, sign) for h in steps]
        return float(np.polyfit(np.log(steps), np.log(errors), 1)[0])

    assert abs(order(None) - 4) < 0.3
    assert abs(order(+1.0) - 4) < 0.3
    assert abs(order(-1.0) - 2) < 0.3
    assert _coning_error(0.01, None) < 1e-3 * _coning_error(0.01, -1.0)


def test_representations_agree_as_dt_shrinks() -> None:
    t = np.linspace(0.0, 3.0, 3001)
    w = body_rate(t)
    r0 = attitude(t[:1])[0]
    results = {
        r: ik.integrate_attitude(t, w, initial=r0, scheme="rk4", representation=r) for r in ik.attitude.REPRESENTATIONS
    }
    for name in ("matrix", "euler"):
        assert angle_error(results[name], results["quaternion"]).max() < 1e-10
    coarse = {
        r: ik.integrate_attitude(t[::30], w[::30], initial=r0, scheme="euler", representation=r)
        for r in ik.attitude.REPRESENTATIONS
    }
    fine = {
        r: ik.integrate_attitude(t, w, initial=r0, scheme="euler", representation=r)
        for r in ik.attitude.REPRESENTATIONS
    }
    for name in ("matrix", "euler"):
        gap_coarse = angle_error(coarse[name][-1], coarse["quaternion"][-1])
        gap_fine = angle_error(fine[name][-1], fine["quaternion"][-1])
        assert gap_fine < gap_coarse / 10  # first order: 30x smaller step, > 10x smaller gap


def test_output_layout_and_time_units() -> None:
    t = np.linspace(0.0, 1.0, 201)
    w = body_rate(t)
    r0 = Rotation.from_rotvec([0.0, 0.0, 1.0])
    out = ik.integrate_attitude(t, w, initial=r0)
    assert len(out) == 201
    assert angle_error(out[0], r0) == 0.0
    final = ik.integrate_attitude(t, w, initial=r0, final_only=True)
    assert final.single
    assert angle_error(final, out[-1]) < 1e-15
    # int64 nanoseconds with a large epoch give the same answer as float seconds
    t_ns = 1_403_715_523_912_140_000 + np.round(t * 1e9).astype(np.int64)
    assert angle_error(ik.integrate_attitude(t_ns, w, initial=r0), out).max() < 1e-13
    # matrices stay orthonormal
    m = ik.integrate_attitude(t, w, representation="matrix", scheme="euler").as_matrix()
    assert np.abs(np.swapaxes(m, 1, 2) @ m - np.eye(3)).max() < 1e-14
    assert len(ik.integrate_attitude(t[:1], w[:1])) == 1


def test_bad_input() -> None:
    t = np.linspace(0.0, 1.0, 11)
    w = np.zeros((11, 3))
    with pytest.raises(ik.TimestampError, match=r"^t: .*sample 6"):
        ik.integrate_attitude(np.concatenate([t[:6], t[5:10]]), w)
    bad = w.copy()
    bad[4, 2] = np.nan
    with pytest.raises(ik.NonFiniteError, match=r"gyro: element 4 "):
        ik.integrate_attitude(t, bad)
    with pytest.raises(ik.ShapeError, match=r"gyro: expected shape \(N, 3\) with N = len\(t\) = 11"):
        ik.integrate_attitude(t, w[:10])
    with pytest.raises(ik.ParameterError, match=r"^scheme: .*supports \[\"euler\", \"rk2\", \"rk4\"\]") as info:
        ik.integrate_attitude(t, w, scheme="magnus", representation="euler")
    assert info.value.argument == "scheme"  # it was "gyro" before 2026-12-07
    with pytest.raises(ik.ParameterError, match="scheme"):
        ik.integrate_attitude(t, w, scheme="rk45")
    with pytest.raises(ik.ParameterError, match="nanoseconds"):
        ik.integrate_attitude(np.arange(11), w)
    with pytest.raises(ik.ShapeError, match=r"^t: expected shape \(N,\) with N ≥ 1, got \(0,\)"):
        ik.integrate_attitude(np.zeros(0), np.zeros((0, 3)))
    with pytest.raises(ik.ParameterError, match="initial"):
        ik.integrate_attitude(t, w, initial=Rotation.random(2))


def test_gimbal_lock_names_the_sample() -> None:
    t = np.linspace(0.0, 2.0, 2001)
    w = np.tile([0.0, 1.0, 0.0], (len(t), 1))  # pitch up at 1 rad/s: ±90° at t = π/2
    with pytest.raises(ik.GimbalLockError, match=r"element 15\d\d"):
        ik.integrate_attitude(t, w, representation="euler", scheme="rk4", gimbal_tolerance_rad=1e-3)
    # the group representations pass straight through
    r = ik.integrate_attitude(t, w, representation="quaternion", scheme="rk4", final_only=True)
    assert angle_error(r, Rotation.from_rotvec([0.0, 2.0, 0.0])) < 1e-12


def _rk4_linear_rate_error(h: float) -> float:
    """Classical RK4 on q̇ = ½ q ⊗ [ω, 0] with the mid-step rate taken as the mean of the two
    samples (a straight line between samples), written here in numpy."""
    n = round(3.0 / h) + 1
    t = np.linspace(0.0, 3.0, n)
    w = body_rate(t)
    q = attitude(t[:1])[0].as_quat()

    def f(q: np.ndarray, w: np.ndarray) -> np.ndarray:
        return 0.5 * ik.quat.multiply(q, np.append(w, 0.0))

    for k in range(n - 1):
        wm = 0.5 * (w[k] + w[k + 1])
        k1 = f(q, w[k])
        k2 = f(q + 0.5 * h * k1, wm)
        k3 = f(q + 0.5 * h * k2, wm)
        k4 = f(q + h * k3, w[k + 1])
        q = q + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        q /= np.linalg.norm(q)
    return float(angle_error(Rotation.from_quat(q), attitude(t[-1:])[0]))


def test_a_straight_line_between_samples_caps_rk4_at_second_order() -> None:
    """Why rk4 and magnus interpolate with a cubic: with linear rates RK4 is only order 2."""
    steps = np.array([0.04, 0.02, 0.01, 0.005])
    errors = [_rk4_linear_rate_error(h) for h in steps]
    slope = float(np.polyfit(np.log(steps), np.log(errors), 1)[0])
    assert abs(slope - 2) < 0.3
    assert final_error("rk4", "quaternion", 0.01) < 1e-2 * _rk4_linear_rate_error(0.01)


def test_jumping_across_gimbal_lock_between_samples_is_refused() -> None:
    """With h = 0.01 s and a pitch rate of 1 rad/s no sample lands within 1e-6 rad of 90°: the sign
    change of cos(pitch) between samples still raises, naming the sample after the jump."""
    t = np.arange(300) * 0.01
    w = np.tile([0.0, 1.0, 0.001], (300, 1))
    for scheme in ("euler", "midpoint", "rk4"):
        with pytest.raises(ik.GimbalLockError, match=r"element 15[78]: .*passed"):
            ik.integrate_attitude(t, w, representation="euler", scheme=scheme)


def test_overflowing_rates_are_an_error_and_tolerance_is_validated() -> None:
    t = np.arange(5) * 0.01
    for scheme in ik.attitude.SCHEMES:
        for final_only in (False, True):
            with pytest.raises(ik.NonFiniteError, match="too large"):
                ik.integrate_attitude(t, np.full((5, 3), 1e200), scheme=scheme, final_only=final_only)
    for bad in (np.pi / 2, 1.6, -1.0, np.nan):
        with pytest.raises(ik.ParameterError, match="gimbal_tolerance"):
            ik.integrate_attitude(t, np.zeros((5, 3)), gimbal_tolerance_rad=bad)
