"""``imukit.eval.time_offset``: the clock offset between an IMU and a reference from their angular
speeds. Analytic truth: a rotation about a fixed axis at a varying rate ``θ̇(t)`` (its speed is
``|θ̇|`` exactly) seen by an IMU mounted at an angle whose samples lag by a known ``δ``; and BROAD,
where the filters' error against the motion capture is least 0.6–0.75 sample earlier
(``docs/filters_robust.md``, "The reference's clock")."""

from __future__ import annotations

import pickle
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import imukit as ik
from euroc import load as load_euroc
from euroc import requires_euroc

BROAD = Path(__file__).resolve().parents[2] / "shared" / "data" / "broad"
AXIS = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
MOUNT = Rotation.from_rotvec([0.4, -1.1, 0.7])  # IMU axes against the reference body's


def rate(t: np.ndarray) -> np.ndarray:
    return 1.5 + np.sin(1.3 * t) + 0.5 * np.sin(3.7 * t + 0.4)


def angle(t: np.ndarray) -> np.ndarray:
    """∫₀ᵗ rate: the rotation angle about AXIS."""
    return 1.5 * t - (np.cos(1.3 * t) - 1.0) / 1.3 - 0.5 * (np.cos(3.7 * t + 0.4) - np.cos(0.4)) / 3.7


def reference(t: np.ndarray) -> ik.Trajectory:
    return ik.Trajectory(t, np.zeros((len(t), 3)), None, Rotation.from_rotvec(angle(t)[:, None] * AXIS))


def imu(delay: float, *, bias: float = 0.0, start: float = 0.013, seconds: float = 30.0) -> ik.ImuData:
    """200 Hz samples whose stamp t holds the rate at t − delay, in the IMU's mounted axes."""
    t = start + np.arange(int(seconds * 200)) / 200.0
    gyro = MOUNT.apply(rate(t - delay)[:, None] * AXIS) + bias
    return ik.ImuData(t, gyro, np.tile([0.0, 0.0, 9.81], (len(t), 1)))


@pytest.mark.parametrize("delay", [0.0037, -0.0052, 0.0, 0.021])
def test_a_known_lag_is_recovered_with_its_sign(delay: float) -> None:
    # Reference at 120 Hz, IMU at 200 Hz from another start: the offset is −delay (the IMU's stamp
    # t is the reference's t − delay). Measured error ≤ 1.1e-6 s; the bound, 5e-5 s, is 1% of the
    # 200 Hz step: a sign error, or the reference's speeds put at the intervals' ends instead of
    # their midpoints (a 4.2 ms bias), fails it.
    ref = reference(np.arange(0.0, 31.0, 1.0 / 120.0))
    got = ik.eval.time_offset(imu(delay), ref, max_offset=0.1)
    assert got.offset == pytest.approx(-delay, abs=5e-5)
    assert got.correlation > 0.999
    assert got.step == pytest.approx(0.005)


def test_bias_gaps_and_frames_do_not_move_it() -> None:
    # A 0.05 rad/s bias on every axis, the reference with two gaps (0.5 s and 2 s) and the IMU
    # mounted at an angle: the same offset within 5e-5 s (measured 1.6e-5). Without Pearson's
    # correlation per lag over the pairs that have a reference speed (the gaps zeroed, one
    # normalisation) it was 3.8e-4 off.
    t_ref = np.arange(0.0, 31.0, 1.0 / 120.0)
    keep = ~(((t_ref > 5.0) & (t_ref < 5.5)) | ((t_ref > 17.0) & (t_ref < 19.0)))
    got = ik.eval.time_offset(imu(0.0037, bias=0.05), reference(t_ref[keep]), max_offset=0.1)
    assert got.offset == pytest.approx(-0.0037, abs=5e-5)
    assert got.n_samples < 5800  # the gaps' grid points are left out (30 s at 200 Hz is 6000)


def test_an_estimated_trajectory_in_place_of_the_imu() -> None:
    # The same turn as an estimate at 100 Hz whose stamps run 12 ms late against the reference:
    # its speeds come from its rotations, as the reference's do.
    t = np.arange(0.0, 30.0, 0.01)
    late = ik.Trajectory(t + 0.012, np.zeros((len(t), 3)), None, Rotation.from_rotvec(angle(t)[:, None] * AXIS))
    got = ik.eval.time_offset(late, reference(np.arange(0.0, 31.0, 1.0 / 120.0)), max_offset=0.1)
    assert got.offset == pytest.approx(-0.012, abs=5e-5)


def test_a_coarse_reference_is_compared_like_with_like_wherever_its_stamps_fall() -> None:
    # A turn with a 3.7 Hz component, read at 10 Hz from 8 phases against a 200 Hz IMU: the grid
    # compared each reference interval's mean speed with the IMU's instant one and was off by
    # −0.45 to +0.42 ms, by phase (±0.09 ms at 20 Hz; a MAV's flight in EuRoC V1_02 read at 20 Hz:
    # ±0.8 ms); the turn over the same intervals on both sides: within 1 µs (measured 0.001 ms).
    def fast_angle(t: np.ndarray) -> np.ndarray:
        return angle(t) - 0.6 * (np.cos(23.0 * t) - 1.0) / 23.0

    t = 0.013 + np.arange(6000) / 200.0
    delay = 0.0037
    gyro = MOUNT.apply((rate(t - delay) + 0.6 * np.sin(23.0 * (t - delay)))[:, None] * AXIS)
    late = ik.ImuData(t, gyro, np.tile([0.0, 0.0, 9.81], (len(t), 1)))
    for phase in np.linspace(0.0, 0.1, 8, endpoint=False):
        t_ref = np.arange(phase, 31.0, 0.1)
        ref = ik.Trajectory(
            t_ref, np.zeros((len(t_ref), 3)), None, Rotation.from_rotvec(fast_angle(t_ref)[:, None] * AXIS)
        )
        got = ik.eval.time_offset(late, ref, max_offset=0.1)
        assert got.offset == pytest.approx(-delay, abs=2e-5), phase
        assert got.n_samples < len(t_ref)  # reference intervals, not grid points
        # the estimate's side of the same code: a 10 Hz estimate against a 200 Hz reference
        ref_200 = ik.Trajectory(
            t, np.zeros((len(t), 3)), None, Rotation.from_rotvec(fast_angle(t - delay)[:, None] * AXIS)
        )
        estimate = ik.Trajectory(
            t_ref, np.zeros((len(t_ref), 3)), None, Rotation.from_rotvec(fast_angle(t_ref)[:, None] * AXIS)
        )
        assert ik.eval.time_offset(estimate, ref_200, max_offset=0.1).offset == pytest.approx(delay, abs=2e-5)


def test_result_is_data_that_pickles() -> None:
    got = ik.eval.time_offset(imu(0.0037), reference(np.arange(0.0, 31.0, 1.0 / 120.0)), max_offset=0.1)
    assert pickle.loads(pickle.dumps(got)) == got
    assert isinstance(got, ik.eval.TimeOffset)


@pytest.mark.parametrize(
    ("kwargs", "argument"),
    [
        ({"imu": "not an imu"}, "imu"),
        ({"reference": np.zeros((3, 4))}, "reference"),
        ({"max_offset": -0.1}, "max_offset"),
        ({"max_offset": float("nan")}, "max_offset"),
        ({"max_offset": 40.0}, "max_offset"),  # beyond the 30 s shared span
        ({"reference": reference(np.arange(100.0, 110.0, 0.01))}, "reference"),  # no shared span
    ],
)
def test_bad_input_names_the_argument(kwargs: dict[str, object], argument: str) -> None:
    args: dict[str, object] = {
        "imu": imu(0.0),
        "reference": reference(np.arange(0.0, 31.0, 1.0 / 120.0)),
        "max_offset": 0.1,
    }
    args.update(kwargs)
    with pytest.raises(ik.ParameterError) as info:
        ik.eval.time_offset(args["imu"], args["reference"], max_offset=args["max_offset"])
    assert info.value.argument == argument


def test_constant_speed_has_no_offset_to_find() -> None:
    t = np.arange(0.0, 20.0, 0.005)
    steady = ik.ImuData(t, np.tile([0.0, 0.0, 1.0], (len(t), 1)), np.tile([0.0, 0.0, 9.81], (len(t), 1)))
    with pytest.raises(ik.ParameterError, match="change of angular speed") as info:
        ik.eval.time_offset(steady, reference(np.arange(0.0, 21.0, 0.01)), max_offset=0.1)
    assert info.value.argument == "imu"


def test_the_simulators_imu_has_no_offset_against_its_truth() -> None:
    # imukit.sim stamps each gyro sample with the time of the true rate it holds: 60 s of a noisy
    # figure eight give 0.1 ms (1% of its 10 ms step).
    noise = ik.ImuNoise(1.7e-4, 2.0e-3, 1.9e-5, 3.0e-3)
    gyro, truth = ik.sim.simulate(ik.sim.FigureEight(), rate=100.0, duration=60.0, noise=noise, seed=0)
    assert abs(ik.eval.time_offset(gyro, truth, max_offset=0.05).offset) < 2e-4


def test_a_motion_that_does_not_fix_the_offset_is_refused() -> None:
    # 3 s of a figure eight (noisy gyro) against its own truth: its speed changes slowly and
    # smoothly, and every lag within ±50 ms correlates within the peak's mismatch (1 − r = 1.5e-4);
    # the peak's place (−38 ms) was noise.
    noise = ik.ImuNoise(1.7e-4, 2.0e-3, 1.9e-5, 3.0e-3)
    gyro, truth = ik.sim.simulate(ik.sim.FigureEight(), rate=100.0, duration=3.0, noise=noise, seed=1)
    with pytest.raises(ik.ParameterError, match="does not fix the offset") as info:
        ik.eval.time_offset(gyro, truth, max_offset=0.05)
    assert info.value.argument == "imu"


def test_an_offset_beyond_the_window_is_refused_not_clipped() -> None:
    # 0.3 s of lag searched within ±0.1 s: the peak sits on the window's edge.
    with pytest.raises(ik.ParameterError, match="edge") as info:
        ik.eval.time_offset(imu(0.3), reference(np.arange(0.0, 31.0, 1.0 / 120.0)), max_offset=0.1)
    assert info.value.argument == "max_offset"


@pytest.mark.skipif(not BROAD.exists(), reason=f"BROAD not found at {BROAD} (the team's shared/ folder)")
@pytest.mark.parametrize("trial", ["06_undisturbed_fast_rotation_A", "10_undisturbed_slow_translation_A"])
def test_broad_gyro_lags_its_motion_capture_by_about_4_ms(trial: str) -> None:
    # Every one of the 12 shared trials gives −4.10 to −4.21 ms (1.2 samples at 286 Hz); the
    # filters, which integrate sample k over the half sample before it, are best against the
    # reference read 0.6–0.75 sample earlier: 1.2 − 0.5, the same offset.
    scipy_io = pytest.importorskip("scipy.io")
    d = scipy_io.loadmat(BROAD / f"{trial}.mat")
    rate_hz = float(d["sampling_rate"].item())
    gyr, acc, quat = (np.ascontiguousarray(d[k], dtype=float) for k in ("imu_gyr", "imu_acc", "opt_quat"))
    t = np.arange(len(gyr)) / rate_hz
    ok = np.all(np.isfinite(quat), axis=1)
    ref = ik.Trajectory(t[ok], np.zeros((ok.sum(), 3)), None, Rotation.from_quat(quat[ok], scalar_first=True))
    got = ik.eval.time_offset(ik.ImuData(t, gyr, acc), ref, max_offset=0.1)
    assert -4.4e-3 < got.offset < -3.9e-3
    assert got.correlation > 0.98


@requires_euroc
def test_euroc_ground_truth_is_on_the_imu_clock() -> None:
    # EuRoC's ground truth was put on the IMU's clock by its authors: V1_02's first 40 s give
    # −0.09 ms (2% of its 5 ms step), where BROAD's motion capture gives −4.2 ms.
    d = load_euroc()
    imu = ik.ImuData(d.seconds, d.gyro, d.accel)
    reference = ik.Trajectory(d.seconds, np.zeros((len(d.seconds), 3)), None, d.rotation)
    assert abs(ik.eval.time_offset(imu, reference, max_offset=0.1).offset) < 5e-4
