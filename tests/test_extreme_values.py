"""Finite extreme input and the argument errors name (issue 17, items 8 and 12).

- NaN/inf from finite input: ``residual`` / ``residual_jacobians`` / ``predict`` with states at
  ±1e308 returned inf or raised about an internal ``phi``; ``eval.ape`` with positions ~1e154
  overflowed the norm (squares). Now: scale-safe norms (``_arrays.row_norms``, the statistics
  scaled by the largest error) and a ``NonFiniteError`` naming ``state_i`` / ``state_j`` when the
  difference itself is beyond float64.
- Errors naming the wrong argument: an overflowing ``covariance`` or ``noise`` in ``propagate``
  and an overflowing ``initial`` state were all blamed on "imu / bias"; huge ``noise`` in
  ``sim.simulate`` on "gyro_errors"; a pure yaw integrated with dt = 1e15 s in Euler-angle form
  raised a false gimbal lock.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import imukit as ik

NOISE = ik.ImuNoise(1.7e-4, 2e-3, 1.9e-5, 3e-3)
N = 50
IMU = ik.ImuData(np.arange(N) * 0.01, np.tile([0.1, 0.2, 0.3], (N, 1)), np.tile([0.0, 0.0, 9.81], (N, 1)))
REST = ik.NavState(np.zeros(3), np.zeros(3), Rotation.identity())


def _state(p: float, v: float) -> ik.NavState:
    return ik.NavState([p, 0.0, 0.0], [v, 0.0, 0.0], Rotation.identity())


def test_preintegration_residuals_at_extreme_states_refuse_naming_the_state() -> None:
    pim = ik.preintegrate(IMU, noise=NOISE)
    far_i, far_j = _state(-1e308, 1e308), _state(1e308, -1e308)
    for call in (pim.residual, pim.residual_jacobians):
        with pytest.raises(ik.NonFiniteError) as info:
            call(far_i, far_j)
        assert info.value.argument == "state_j"
    with pytest.raises(ik.NonFiniteError) as info:
        pim.predict(_state(1.7e308, 1.7e308))
    assert info.value.argument == "state_i"
    # Large but representable: finite residuals.
    assert np.isfinite(pim.residual(_state(-1e300, 0.0), _state(1e300, 0.0))).all()


@pytest.mark.parametrize("scale", [1e154, 1e300, 1e-200])
def test_ape_norms_are_scale_safe(scale: float) -> None:
    n = 20
    p = np.column_stack([np.arange(n), np.sin(np.arange(n)), np.zeros(n)]) * scale
    ref = ik.Trajectory(np.arange(n) * 0.1, p, None, Rotation.identity(n))
    est = ik.Trajectory(np.arange(n) * 0.1, p * 1.01, None, Rotation.identity(n))
    result = ik.eval.ape(est, ref, align="none")
    expected = 0.01 * np.linalg.norm(p / scale, axis=1) * scale  # the norm of unscaled rows, scaled
    np.testing.assert_allclose(result.translation, expected, rtol=1e-14)
    stats = result.translation_stats
    assert stats.rmse == pytest.approx(scale * 0.01 * np.sqrt(np.mean(np.sum((p / scale) ** 2, axis=1))), rel=1e-14)
    assert np.isfinite([stats.rmse, stats.mean, stats.std]).all()


@pytest.mark.parametrize(
    ("kwargs", "argument"),
    [
        ({"covariance": np.eye(15) * 1e307, "noise": NOISE, "initial": REST}, "covariance"),
        ({"covariance": np.eye(15), "noise": ik.ImuNoise(1e200, 1e200, 1.0, 1.0), "initial": REST}, "noise"),
        ({"covariance": np.eye(15), "noise": NOISE, "initial": _state(1.7e308, 1.7e308)}, "initial"),
    ],
)
def test_propagate_overflow_names_the_argument(kwargs: dict, argument: str) -> None:  # type: ignore[type-arg]
    with pytest.raises(ik.NonFiniteError) as info:
        ik.propagate(IMU, **kwargs)
    assert info.value.argument == argument


def test_integrate_overflow_names_initial_or_imu() -> None:
    with pytest.raises(ik.NonFiniteError) as info:
        ik.integrate(IMU, initial=_state(1.7e308, 1.7e308))
    assert info.value.argument == "initial"
    huge = ik.ImuData(IMU.t, IMU.gyro, np.full((N, 3), 1.7e308))
    with pytest.raises(ik.NonFiniteError) as info:
        ik.integrate(huge, initial=REST)
    assert info.value.argument == "imu"


def test_simulate_overflow_from_noise_names_noise() -> None:
    with pytest.raises(ik.NonFiniteError) as info:
        ik.sim.simulate(ik.sim.Static(), rate=1000, duration=1, noise=ik.ImuNoise(1e307, 1e307, 0.0, 0.0))
    assert info.value.argument == "noise"


def test_pure_yaw_with_a_huge_step_is_no_gimbal_lock() -> None:
    t = np.array([0.0, 1e15, 2e15])
    q = ik.integrate_attitude(t, np.tile([0.0, 0.0, 1.0], (3, 1)), representation="euler")
    # A pure yaw (the yaw's value itself resolves only 0.25 rad at 2e15 rad, f64's spacing there).
    roll, pitch = q[-1].as_euler("ZYX")[2], q[-1].as_euler("ZYX")[1]
    assert abs(roll) < 1e-12 and abs(pitch) < 1e-12
    # A real singularity still is one: pitch driven through 90°.
    with pytest.raises(ik.GimbalLockError):
        ik.integrate_attitude(np.arange(200) * 0.01, np.tile([0.0, 1.0, 0.0], (200, 1)), representation="euler")


@pytest.mark.parametrize("scale", [1e154, 1e-200, 1e300])
@pytest.mark.parametrize("method", ["se3", "sim3"])
def test_alignment_is_scale_safe(scale: float, method: str) -> None:
    """``align`` / ``ape`` with se3 and sim3 at positions ~1e154 (the cross-covariance overflowed and the
    SVD of an inf matrix ran for over 10 min) and ~1e-200 (σx² underflowed to 0): the known rotation and
    scale come back, the errors as at scale 1, scaled."""
    n = 20
    k = np.arange(n)
    unit = np.column_stack([k, np.sin(k), np.cos(0.7 * k)])
    turn = Rotation.from_rotvec([0.1, 0.2, 0.3])

    def pair(s: float) -> tuple[ik.Trajectory, ik.Trajectory]:
        ref = ik.Trajectory(k * 0.1, unit * s, None, Rotation.identity(n))
        return ik.Trajectory(k * 0.1, turn.apply(unit * s) * 0.5 + 3 * s, None, Rotation.identity(n)), ref

    alignment = ik.eval.align(*pair(scale), method=method)
    assert (alignment.rotation * turn).magnitude() < 1e-14
    assert alignment.scale == pytest.approx(2.0 if method == "sim3" else 1.0, rel=1e-14)
    rmse = ik.eval.ape(*pair(scale), align=method).translation_stats.rmse
    assert rmse / scale == pytest.approx(ik.eval.ape(*pair(1.0), align=method).translation_stats.rmse, rel=1e-12)


def test_sim3_scale_beyond_float64_is_refused_naming_the_trajectories() -> None:
    n = 10
    k = np.arange(n)
    p = np.column_stack([k, np.sin(k), np.cos(0.7 * k)])
    est = ik.Trajectory(k * 0.1, p * 1e-300, None, Rotation.identity(n))
    ref = ik.Trajectory(k * 0.1, p * 1e300, None, Rotation.identity(n))
    with pytest.raises(ik.NonFiniteError) as info:
        ik.eval.align(est, ref, method="sim3")
    assert info.value.argument == "estimate / reference"


@pytest.mark.parametrize(
    ("t", "expected"),
    [
        ([-1e308, 1e308], "the span from the first stamp (-1e+308 s) to sample 1 (1e+308 s) overflows float64"),
        ([-1e16, 0.5, 0.75], "samples 1 and 2 (0.5 s, 0.75 s) are 0.25 s apart, but relative to the first stamp"),
    ],
)
def test_stamps_whose_relative_clock_breaks_are_refused_at_construction(t: list[float], expected: str) -> None:
    """Strictly increasing, finite stamps whose offsets from the first overflow (duration inf) or round
    two steps together (later calls then blamed ``t`` for a step the input does not have)."""
    with pytest.raises(ik.TimestampError) as info:
        ik.ImuData(np.array(t), np.zeros((len(t), 3)), np.zeros((len(t), 3)))
    assert info.value.argument == "t"
    assert expected in str(info.value)


def test_discrete_sigmas_beyond_float64_are_refused() -> None:
    noise = ik.ImuNoise(1e300, 1e300, 1e300, 1e300)
    with pytest.raises(ik.NonFiniteError) as info:
        noise.to_discrete_sigmas(1e300)
    assert info.value.argument == "rate_hz"
    assert noise.to_discrete_sigmas(1e10).gyro_walk_sigma == pytest.approx(1e295, rel=1e-15)  # finite: kept
