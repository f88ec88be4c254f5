"""imukit.eval.rpe against analytic drift on a constant-velocity trajectory, and its pair rule by hand."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import imukit as ik

STEP = 0.125  # s and m: exact in binary, so the 1 m / 1 s pairs fall on samples without rounding
T = np.arange(81) * STEP  # 10 s at 8 Hz, 1 m/s along x
EPS, OMEGA = 0.01, 0.02  # the estimate runs 1 % fast and turns at 0.02 rad/s


def along_x(speed: float, turn_rate: float = 0.0, t: np.ndarray = T) -> ik.Trajectory:
    position = np.outer(speed * t, [1.0, 0.0, 0.0])
    return ik.Trajectory(t, position, None, Rotation.from_rotvec(np.outer(turn_rate * t, [0.0, 0.0, 1.0])))


def drift_truth(t_i: np.ndarray, span: float) -> tuple[np.ndarray, np.ndarray]:
    """Analytic RPE of along_x(1 + EPS, OMEGA) against along_x(1) over pairs ``span`` seconds apart.

    Reference motion: ΔR = I, Δp = span e_x. Estimate: ΔR = Rz(ω span), Δp = Rz(−ω t_i) (1 + ε) span e_x
    (the displacement seen from the drifted heading at t_i). E's translation is their difference.
    """
    translation = span * np.sqrt((1 + EPS) ** 2 + 1 - 2 * (1 + EPS) * np.cos(OMEGA * t_i))
    return translation, np.full_like(t_i, OMEGA * span)


@pytest.mark.parametrize(("delta", "unit"), [(1.0, "m"), (1.0, "s"), (8, "frames")])
def test_drift_matches_the_analytic_error(delta: float, unit: str) -> None:
    err = ik.eval.rpe(along_x(1 + EPS, OMEGA), along_x(1.0), delta=delta, unit=unit, max_dt=0.2)
    assert (err.n_dropped, err.n_outside_span, err.n_in_gaps) == (0, 0, 0)
    np.testing.assert_array_equal(err.pairs, np.stack([np.arange(0, 80, 8), np.arange(8, 81, 8)], axis=1))
    translation, rotation = drift_truth(T[err.pairs[:, 0]], 1.0)
    np.testing.assert_allclose(err.translation, translation, rtol=1e-10)  # the truth's 1 − cos cancels digits
    np.testing.assert_allclose(err.rotation, rotation, rtol=1e-9)
    np.testing.assert_allclose(err.separation, float(delta))
    assert err.translation_stats.rmse == pytest.approx(np.sqrt(np.mean(translation**2)), rel=1e-12)
    assert err.translation_stats.n == 10 and err.translation[0] == pytest.approx(EPS, rel=1e-12)


def test_all_pairs_start_at_every_sample() -> None:
    err = ik.eval.rpe(along_x(1 + EPS, OMEGA), along_x(1.0), delta=2.0, unit="s", all_pairs=True, max_dt=0.2)
    starts = np.arange(81 - 16)
    np.testing.assert_array_equal(err.pairs, np.stack([starts, starts + 16], axis=1))
    translation, rotation = drift_truth(T[starts], 2.0)
    np.testing.assert_allclose(err.translation, translation, rtol=1e-10)  # the truth's 1 − cos cancels digits
    np.testing.assert_allclose(err.rotation, rotation, rtol=1e-9)


def test_only_the_scale_of_an_alignment_changes_the_rpe() -> None:
    est = along_x(2.0)  # twice too far, no drift otherwise: every 1 m of reference is 2 m estimated
    ref = along_x(1.0)
    raw = ik.eval.rpe(est, ref, max_dt=0.2)
    np.testing.assert_allclose(raw.translation, 1.0, rtol=1e-14)
    # se3 cannot be determined on a straight line: turn the reference into a planar curve first
    curve = ik.Trajectory(T, np.stack([T, np.sin(T), np.zeros_like(T)], axis=1), None, Rotation.identity(81))
    doubled = ik.Trajectory(T, 2.0 * curve.position, None, Rotation.identity(81))
    for method, expected in (("none", 1.0), ("se3", 1.0), ("sim3", 0.0)):
        err = ik.eval.rpe(doubled, curve, align=method, unit="frames", delta=8, max_dt=0.2)
        dp = curve.position[err.pairs[:, 1]] - curve.position[err.pairs[:, 0]]
        np.testing.assert_allclose(err.translation, expected * np.linalg.norm(dp, axis=1), atol=1e-12, err_msg=method)


def test_pairs_over_distance_skip_stationary_stretches() -> None:
    # positions along x: 0, 0.5, 0.5, 0.5, 1, 1.5, 2 (the reference stands still for two samples)
    x = np.array([0.0, 0.5, 0.5, 0.5, 1.0, 1.5, 2.0])
    ref = ik.Trajectory(np.arange(7.0), np.outer(x, [1.0, 0.0, 0.0]), None, Rotation.identity(7))
    err = ik.eval.rpe(ref, ref, delta=1.0, unit="m", max_dt=2.0)
    np.testing.assert_array_equal(err.pairs, [[0, 4], [4, 6]])
    every = ik.eval.rpe(ref, ref, delta=1.0, unit="m", all_pairs=True, max_dt=2.0)
    np.testing.assert_array_equal(every.pairs, [[0, 4], [1, 5], [2, 5], [3, 5], [4, 6]])
    np.testing.assert_allclose(every.separation, 1.0)
    np.testing.assert_allclose(every.translation, 0.0, atol=0)


def test_nanosecond_stamps_pair_exactly() -> None:
    t_ns = 1_403_715_524_907_143_168 + np.arange(0, 41) * 5_000_192  # epoch stamps, 5.000192 ms apart
    ref = ik.Trajectory(None, np.outer(np.arange(41.0), [1.0, 0, 0]), None, Rotation.identity(41), t_ns=t_ns)
    # delta = 10 steps of 5.000192 ms, compared in integer nanoseconds: separations exact
    err = ik.eval.rpe(ref, ref, delta=0.05000192, unit="s")
    np.testing.assert_array_equal(err.pairs, [[0, 10], [10, 20], [20, 30], [30, 40]])
    np.testing.assert_allclose(err.separation, 0.05000192, rtol=1e-15)


def test_float_separations_within_rounding_of_delta_count_as_delta() -> None:
    # 30 Hz float stamps from np.arange: 30 frames are 0.9999999999999964 s apart at frame 930;
    # read strictly, that pair took 31 frames (1.033 s) and 28 of the 59 pairs moved by a frame.
    t = np.arange(0.013, 59.9, 1 / 30.0)
    assert t[960] - t[930] < 1.0
    ref = along_x(1.0, t=t)
    err = ik.eval.rpe(ref, ref, delta=1.0, unit="s", max_dt=0.1)
    assert len(err.pairs) == 59
    np.testing.assert_array_equal(np.diff(err.pairs, axis=1).ravel(), 30)
    np.testing.assert_allclose(err.separation, 1.0, rtol=1e-13)
    # a real difference of one part in 1e12 is not rounding: the next frame
    late = ik.eval.rpe(ref, ref, delta=1.0 + 1e-12, unit="s", max_dt=0.1)
    np.testing.assert_array_equal(np.diff(late.pairs, axis=1).ravel(), 31)
    # the same over distance: 0.1 m steps summed, 1 m apart to rounding
    by_metre = ik.eval.rpe(ref, along_x(3.0, t=t), delta=1.0, unit="m", max_dt=0.1)
    np.testing.assert_array_equal(np.diff(by_metre.pairs, axis=1).ravel(), 10)


def test_no_pair_and_bad_arguments() -> None:
    ref = along_x(1.0)
    with pytest.raises(ik.ParameterError, match=r"^delta: no pair of associated samples is 100 m apart; .* 10 m"):
        ik.eval.rpe(ref, ref, delta=100.0, max_dt=0.2)
    for kwargs, message in (
        ({"unit": "km"}, r"^unit: expected one of"),
        ({"delta": 0.0}, r"^delta: expected a finite positive"),
        ({"delta": 1.5, "unit": "frames"}, r"^delta: expected a whole number of frames"),
        ({"all_pairs": "yes"}, r"^all_pairs: expected a bool"),
    ):
        with pytest.raises(ik.ParameterError, match=message):
            ik.eval.rpe(ref, ref, max_dt=0.2, **kwargs)  # type: ignore[arg-type]


@pytest.mark.parametrize("scale", [1e160, 1e-170])
def test_pairs_over_distance_at_extreme_scales_are_those_at_scale_one(scale: float) -> None:
    """The path length summed squared steps: at 1e160 m every separation was inf or NaN and every
    consecutive pair was taken, at 1e-170 m no pair was found (before 2026-12-07)."""
    _, truth = ik.sim.simulate(ik.sim.FigureEight(), rate=100.0, duration=20.0)
    ref = ik.Trajectory(truth.t, truth.position, None, truth.rotation)
    est = ik.Trajectory(truth.t, truth.position * 1.01, None, truth.rotation)
    base = ik.eval.rpe(est, ref, delta=1.0)
    big = ik.eval.rpe(
        ik.Trajectory(truth.t, est.position * scale, None, truth.rotation),
        ik.Trajectory(truth.t, ref.position * scale, None, truth.rotation),
        delta=scale,
    )
    np.testing.assert_array_equal(big.pairs, base.pairs)
    np.testing.assert_allclose(big.separation, base.separation * scale, rtol=1e-12)
    np.testing.assert_allclose(big.translation, base.translation * scale, rtol=1e-9)
    huge = ik.Trajectory(truth.t, ref.position * 1e307, None, truth.rotation)  # each step finite, 41 m of path not
    with pytest.raises(ik.NonFiniteError, match=r"^reference: ") as e:
        ik.eval.rpe(huge, huge, delta=1e307)
    assert e.value.argument == "reference"
