"""imukit.filters.Robust from Python: defaults from the core, streaming = batch, save / restore /
resume, pickling, NED, offline determinism, errors by name, and an accuracy regression on the shared
BROAD trials (one trial per group, bounds from docs/filters_robust.md)."""

from __future__ import annotations

import pickle
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import imukit as ik
from imukit._errors import ParameterError

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "broad"


def _imu(seconds: float = 30.0, rate: float = 100.0) -> tuple[ik.ImuData, np.ndarray, Rotation]:
    t = np.arange(int(seconds * rate)) / rate
    w = np.stack([0.4 * np.sin(0.7 * t), 0.3 * np.sin(0.5 * t + 1), 0.5 * np.cos(0.3 * t)], 1)
    w[t < 3] = 0.0
    steps = Rotation.from_rotvec(w[:-1] / rate)
    q = [Rotation.from_euler("xyz", [0.3, -0.2, 1.0])]
    for s in steps:
        q.append(q[-1] * s)
    truth = Rotation.concatenate(q)
    acc = truth.inv().apply([0.0, 0.0, 9.81])
    mag = truth.inv().apply([0.0, 20.0, -40.0])
    return ik.ImuData(t, w + np.radians([0.3, -0.2, 0.1]), acc), mag, truth


def test_defaults_come_from_the_core() -> None:
    f = ik.filters.Robust()
    assert f.DEFAULTS == dict(ik._core.RobustParams().fields())
    assert f.tau_acc_s == ik._core.RobustParams().fields()["tau_acc_s"]
    assert ik.filters.Robust(tau_acc_s=2.5).tau_acc_s == 2.5


def test_run_tracks_a_simulated_rotation() -> None:
    imu, mag, truth = _imu()
    for m in (None, mag):
        res = ik.filters.Robust().run(imu, mag=m)
        err = ik.eval.attitude_error(res.rotation.as_quat(), truth.as_quat(), align_heading=m is None)
        assert err.rmse(degrees=True).total < 1.0  # uncorrected, the 0.3 °/s bias alone gives degrees
        assert res.gyro_bias.shape == res.gyro_bias_sigma.shape == (len(imu.t), 3)
        assert res.rest.dtype == bool and res.rest[250] and not res.rest[-1]
        assert not res.mag_disturbed.any()


def test_mag_follows_the_same_rule_as_mahony() -> None:
    """``mag=None`` takes ``imu.mag`` when the samples carry one (a silent 6D run of a 9D recording
    was the old behaviour), ``False`` forces 6D, ``True`` demands it."""
    imu, mag, _ = _imu(10.0)
    with_mag = ik.ImuData(imu.t, imu.gyro, imu.accel, mag=mag)
    f = ik.filters.Robust()
    nine, six = f.run(imu, mag=mag).rotation.as_quat(), f.run(imu).rotation.as_quat()
    assert np.abs(nine - six).max() > 1e-3  # the heading differs: the two runs are distinguishable
    np.testing.assert_array_equal(f.run(with_mag).rotation.as_quat(), nine)
    np.testing.assert_array_equal(f.run(with_mag, mag=True).rotation.as_quat(), nine)
    np.testing.assert_array_equal(f.run(with_mag, mag=False).rotation.as_quat(), six)
    with pytest.raises(ik.ParameterError, match="mag: mag=True"):
        f.run(imu, mag=True)


def _stream(f: ik.filters.Robust, imu: ik.ImuData, mag: np.ndarray, has_field: np.ndarray) -> Rotation:
    out = [f.update(imu.gyro[0], imu.accel[0], 0.0, mag[0] if has_field[0] else None)]
    for k in range(1, len(imu)):
        out.append(f.update(imu.gyro[k], imu.accel[k], imu.t[k] - imu.t[k - 1], mag[k] if has_field[k] else None))
    return Rotation.concatenate(out)


def test_streaming_with_a_slower_field_keeps_the_heading() -> None:
    """A field on every 10th sample: the samples between kept the attitude without its heading
    (57° off here, every time) before 2026-12-07."""
    imu, mag, truth = _imu(20.0)
    every_tenth = np.arange(len(imu)) % 10 == 0
    heading = ik.eval.attitude_error(_stream(ik.filters.Robust(), imu, mag, every_tenth), truth).heading
    assert np.degrees(np.abs(heading)).max() < 1.0


def test_a_slower_streamed_field_keeps_the_heading_gain() -> None:
    """Gyro 1 °/s off in its vertical bias, field on every 10th / 50th sample: between its samples
    the last field, turned by the gyro, stands in, so the heading loop and the field's gate run in
    seconds as with a field on every sample. Before 2026-12-07 the loop ran on the field's samples
    only (a tenth / fiftieth of its gain): 1.6° / 1.8° of heading at 30 s for 0.64°."""
    imu, mag, truth = _imu(120.0)
    gyro = imu.gyro + np.radians([0.0, 0.0, 1.0])
    turned = ik.ImuData(imu.t, gyro, imu.accel)

    def heading(every: int) -> np.ndarray:
        has_field = np.arange(len(imu)) % every == 0
        rotation = _stream(ik.filters.Robust(), turned, mag, has_field)
        return np.degrees(np.abs(ik.eval.attitude_error(rotation, truth).heading))

    full = heading(1)
    for every in (10, 50):
        slow = heading(every)
        assert np.abs(slow[1000:] - full[1000:]).max() < 0.05, (every, slow[3000], full[3000])
    # mag_hold_s=0: the field's samples alone (the former behaviour)
    off = np.degrees(
        np.abs(
            ik.eval.attitude_error(
                _stream(ik.filters.Robust(mag_hold_s=0.0), turned, mag, np.arange(len(imu)) % 10 == 0), truth
            ).heading
        )
    )
    assert off[3000] > 2 * full[3000]
    with pytest.raises(ik.ParameterError, match=r"^mag_hold_s: "):
        ik.filters.Robust(mag_hold_s=-1.0)
    # The error names what each call takes (it named FilterState, and reset takes no state).
    with pytest.raises(ik.ParameterError, match=r"^initial: expected a single scipy Rotation, a RobustState or None"):
        ik.filters.Robust().run(turned, initial=ik.filters.Mahony().get_state())  # type: ignore[arg-type]
    with pytest.raises(ik.ParameterError, match=r"^initial: expected a single scipy Rotation or None, got"):
        ik.filters.Robust().reset(ik.filters.Robust().get_state())  # type: ignore[arg-type]
    with pytest.raises(ik.ParameterError, match=r"^state: "):
        ik.filters.RobustState(**{**ik.filters.Robust().get_state().fields(), "mag_held_s": -1.0})


def test_a_field_that_starts_late_gives_the_heading() -> None:
    """The field from sample 50 on (streaming): its first sample sets the heading, as the first
    sample's would have; before 2026-12-07 the loop took it over minutes (17° at 20 s) and drove the
    vertical bias to its clip. With an initial attitude 30° off in heading, the same."""
    imu, mag, truth = _imu(20.0)
    late = np.arange(len(imu)) >= 50
    streamed = ik.filters.Robust()
    error = ik.eval.attitude_error(_stream(streamed, imu, mag, late), truth)
    assert np.degrees(np.abs(error.heading[50:])).max() < 1.0
    assert abs(streamed.get_state().gyro_bias[2] - np.radians(0.1)) < np.radians(0.05)  # true 0.1 °/s
    f = ik.filters.Robust()
    f.reset(Rotation.from_euler("z", 30, degrees=True) * truth[0])
    for k in range(1, 61):
        turned = f.update(imu.gyro[k], imu.accel[k], imu.t[k] - imu.t[k - 1], mag[k] if late[k] else None)
    heading = ik.eval.attitude_error(Rotation.concatenate([turned]), truth[60:61]).heading[0]
    assert abs(np.degrees(heading)) < 1.0


@pytest.mark.parametrize("offline", [False, True])
def test_an_initial_heading_off_the_field_is_not_learned_as_bias(offline: bool) -> None:
    """9D with ``initial=`` 30° / 170° off the field in heading (motion capture's north, say): the
    heading loop took a minute over it (1.4° / 6.7° left at 60 s online) and learned its corrections
    as a vertical bias (0.17 / 0.47 °/s for a true 0.1 °/s), before 2026-12-07. The field's first
    sample now gives the heading: the run is the one from the exact initial attitude."""
    imu, mag, truth = _imu(90.0)
    exact = ik.filters.Robust().run(imu, mag=mag, initial=truth[0], offline=offline)
    for off in (30, 170):
        turned = Rotation.from_euler("z", off, degrees=True) * truth[0]
        run = ik.filters.Robust().run(imu, mag=mag, initial=turned, offline=offline)
        heading = np.degrees(np.abs(ik.eval.attitude_error(run.rotation, truth).heading))
        assert heading[1000:].max() < 0.5, (off, heading[1000:].max())
        bias_z = np.degrees(run.gyro_bias[1000:, 2])
        assert np.abs(bias_z - 0.1).max() < 0.02, (off, bias_z.min(), bias_z.max())
        np.testing.assert_allclose(run.rotation[1:].as_quat(), exact.rotation[1:].as_quat(), atol=1e-9)


@pytest.mark.parametrize("gap", [1.5, 2.0, 5.0])
def test_a_gap_in_the_stamps_does_not_tilt_a_still_sensor(gap: float) -> None:
    """A still, level sensor whose stamps skip ``gap`` seconds: the low passes' delay elements,
    read with the gap's coefficients, turned the estimate upside down for 5-12 s (before
    2026-12-07; offline from t = 0 for 5 s). Online, offline, 6D, 9D, and one streaming step."""
    t = np.arange(0, 60, 0.01)
    t = np.concatenate([t[t < 30], t[t >= 30 + gap]])
    turn = Rotation.from_euler("z", 30, degrees=True)
    n = len(t)
    field = np.tile(turn.inv().apply([0, 22, -42]), (n, 1))
    imu = ik.ImuData(t, np.zeros((n, 3)), np.tile(turn.inv().apply([0, 0, 9.81]), (n, 1)), mag=field)
    for offline in (False, True):
        for nine in (False, True):
            estimate = ik.filters.Robust().run(imu, mag=nine, offline=offline).rotation
            tilt = np.degrees(np.arccos(np.clip(estimate.apply([0, 0, 1])[:, 2], -1, 1)))
            assert tilt.max() < 1e-6, (offline, nine)
    f = ik.filters.Robust()
    for k in range(1500):
        up = f.update(np.zeros(3), [0, 0, 9.81], gap if k == 1000 else 0.01).apply([0, 0, 1])
        assert up[2] > 1 - 1e-12, k


def test_6d_starts_at_yaw_0_in_either_world() -> None:
    """``yaw 0`` is the world's own (Mahony's and Madgwick's rule): in NED Robust started at yaw 90°
    (the internal ENU yaw 0) before 2026-12-07, online and offline."""
    imu, _, _ = _imu(5.0)
    for world in ("ENU", "NED"):
        for offline in (False, True):
            first = ik.filters.Robust(world=world).run(imu, offline=offline).rotation[0]
            # offline: the smoothed first sample, 1e-4 rad from the start (the bug: π/2)
            assert abs(first.as_euler("ZYX")[0]) < (1e-3 if offline else 1e-9), (world, offline)
        assert abs(ik.filters.Mahony(world=world).run(imu).rotation[0].as_euler("ZYX")[0]) < 1e-12


def test_an_initial_attitude_off_in_tilt_is_not_learned_as_bias() -> None:
    """``initial=`` 5° off in tilt on exact readings of a turning sensor (true bias 0): the first
    sample's alignment with the accelerometer counted in the bias window and was learned as a bias
    (0.063 rad/s, then 9.4° of tilt, before 2026-12-07). Now it runs as from the exact initial."""
    t = np.arange(0, 60, 0.01)
    w = np.stack([0.4 * np.sin(2 * np.pi * 0.2 * t), 0.4 * np.cos(2 * np.pi * 0.13 * t), 0.3 + 0 * t], 1)
    steps = Rotation.from_rotvec(w[1:] * 0.01)
    q = [Rotation.identity()]
    for step in steps:
        q.append(q[-1] * step)
    truth = Rotation.concatenate(q)
    imu = ik.ImuData(t, w, truth.inv().apply([0, 0, 9.81]))
    exact = ik.filters.Robust().run(imu, initial=truth[0])
    off = ik.filters.Robust().run(imu, initial=Rotation.from_euler("x", 5, degrees=True) * truth[0])
    tilt = np.degrees(np.abs(ik.eval.attitude_error(off.rotation, truth).inclination))
    assert tilt[1:].max() < 0.01
    assert np.abs(off.gyro_bias).max() < 1e-4 and np.abs(exact.gyro_bias).max() < 1e-4


def test_streaming_equals_batch_and_resume() -> None:
    # 50 s at 100 Hz: the batch run is fed to the core in parts of 4096 rows (robust_glue.rs).
    imu, mag, _ = _imu(50.0)
    f = ik.filters.Robust()
    batch = f.run(imu, mag=mag)
    streamed = []
    for k in range(len(imu.t)):
        dt = 0.0 if k == 0 else imu.t[k] - imu.t[k - 1]
        streamed.append(f.update(imu.gyro[k], imu.accel[k], dt, mag=mag[k]).as_quat())
    assert np.array_equal(np.array(streamed), batch.rotation.as_quat())
    h = len(imu.t) // 2
    first = f.run(imu[:h], mag=mag[:h])
    saved = pickle.loads(pickle.dumps(first.state))
    assert saved == first.state
    second = f.run(imu[h:], mag=mag[h:], initial=saved)
    assert np.array_equal(second.rotation.as_quat(), batch.rotation[h:].as_quat())
    f.set_state(saved)
    assert f.get_state() is saved


def test_ned_and_pickled_filter() -> None:
    imu, mag, _ = _imu(10.0)
    enu = ik.filters.Robust().run(imu, mag=mag).rotation
    ned = pickle.loads(pickle.dumps(ik.filters.Robust(world="NED"))).run(imu, mag=mag).rotation
    c = Rotation.from_matrix([[0, 1, 0], [1, 0, 0], [0, 0, -1]])
    assert np.degrees(((c * enu).inv() * ned).magnitude()).max() < 1e-7


def test_a_state_copies_a_state_and_refuses_a_state_with_fields() -> None:
    imu, mag, _ = _imu(5.0)
    state = ik.filters.Robust().run(imu, mag=mag).state
    copy = ik.filters.RobustState(state)
    assert type(copy) is ik.filters.RobustState and copy == state
    assert copy.fields() == state.fields()
    # The same state from its fields by name (what pickling stores), and from the core's own class.
    assert ik.filters.RobustState(**state.fields()) == state
    assert ik.filters.RobustState(ik._core.RobustState(state)) == state
    for make in (ik.filters.RobustState, ik._core.RobustState):
        with pytest.raises(ParameterError) as e:
            make(state, time=1.0)
        assert e.value.argument == "state"


def test_offline_is_deterministic_and_finite() -> None:
    imu, mag, _ = _imu()
    f = ik.filters.Robust()
    a, b = f.run(imu, mag=mag, offline=True), f.run(imu, mag=mag, offline=True)
    assert np.array_equal(a.rotation.as_quat(), b.rotation.as_quat())
    assert np.isfinite(a.rotation.as_quat()[[0, -1]]).all() and np.isfinite(a.gyro_bias[[0, -1]]).all()
    # The smoothed bias at the start is what the online filter only knows later.
    online = f.run(imu, mag=mag)
    true_bias = np.radians([0.3, -0.2, 0.1])
    assert np.linalg.norm(a.gyro_bias[50] - true_bias) < 0.5 * np.linalg.norm(online.gyro_bias[50] - true_bias)


def test_errors_name_the_argument() -> None:
    imu, _, _ = _imu(1.0)
    with pytest.raises(ParameterError) as e:
        ik.filters.Robust(tau_acc_s=-1.0)
    assert "tau_acc_s" in str(e.value)
    with pytest.raises(ParameterError):
        ik.filters.Robust(no_such_parameter=1.0)
    with pytest.raises(ParameterError):
        ik.filters.Robust().run(imu, offline=1)  # type: ignore[arg-type]
    with pytest.raises(ik.ShapeError):
        ik.filters.Robust().run(imu, mag=np.zeros((3, 3)))
    # A bad sample in a later part of a long run names its row in the whole record.
    imu, mag, _ = _imu(50.0)
    mag[4100, 1] = np.inf
    with pytest.raises(ik.NonFiniteError) as e:
        ik.filters.Robust().run(imu, mag=mag)
    assert "4100" in str(e.value)


def test_a_field_whose_norm_overflows_is_refused_at_its_row() -> None:
    """Components from 1.4e154 on overflow the squared norm (the reference the filter keeps); the
    check's fast bound (±1e153) must not let them through, nor refuse what merely exceeds it."""
    imu, mag, _ = _imu(1.0)
    for row, big in ((7, [2e154, 0.0, 0.0]), (60, [-2e154, 3.0, 1.0])):
        bad = mag.copy()
        bad[row] = big
        with pytest.raises(ik.NonFiniteError, match=f"sample {row} is too large"):
            ik.filters.Robust().run(imu, mag=bad)
    # Beyond the bound, norm finite (3·(5e153)² = 7.5e307): no error from the check.
    fine = mag.copy()
    fine[7] = [5e153, -5e153, 5e153]
    ik.filters.Robust().run(imu, mag=fine)


# Accuracy regression on the 12 shared BROAD trials at defaults, online and offline: every trial
# within 15% of its measured value, each group's mean and the mean of all 12 within 10% (a 20%
# regression of any trial, group or the whole fails).
REGRESSION = {
    # trial: (6D inclination, 9D total) online, then offline [°], the report's metric, measured
    # 2026-12-06 (the same as docs/filters_robust.md's tables, bench/robust_tune.py)
    "01_undisturbed_slow_rotation_A": ((0.5484, 1.6132), (0.3738, 3.1088)),
    "03_undisturbed_slow_rotation_C": ((0.4187, 2.0350), (0.3930, 1.3188)),
    "06_undisturbed_fast_rotation_A": ((0.8007, 4.1771), (0.7515, 3.6554)),
    "08_undisturbed_fast_rotation_with_breaks_A": ((1.6895, 4.5172), (0.9183, 1.8224)),
    "10_undisturbed_slow_translation_A": ((0.3250, 2.0284), (0.2502, 1.8082)),
    "12_undisturbed_slow_translation_C": ((0.2844, 1.1682), (0.1939, 0.7577)),
    "18_undisturbed_fast_translation_with_breaks_B": ((0.6202, 0.8973), (0.5428, 0.9010)),
    "24_disturbed_tapping_A": ((0.6115, 1.3028), (0.5126, 0.9397)),
    "27_disturbed_phone_vibration_B": ((0.4211, 6.8839), (0.2840, 6.0795)),
    "28_disturbed_stationary_magnet_A": ((1.1623, 2.1586), (0.8063, 1.6680)),
    "32_disturbed_attached_magnet_1cm": ((0.5486, 1.6969), (0.3747, 1.2006)),
    "34_disturbed_attached_magnet_3cm": ((0.6373, 1.2756), (0.4462, 1.4518)),
}
GROUPS = {"rotation": "01 03 06 08", "translation": "10 12 18", "tapping+vibration": "24 27", "magnets": "28 32 34"}
MODES = [(offline, nine) for offline in (False, True) for nine in (False, True)]


def _mode(offline: bool, nine: bool) -> str:
    return f"{'offline' if offline else 'online'} {'9D' if nine else '6D'}"


@pytest.fixture(scope="module")
def broad_scores() -> dict[str, list[float]]:
    """Per trial, the four measured values in REGRESSION's order."""
    if not DATA.is_dir():
        pytest.skip("../shared/data/broad (the shared BROAD trials) is absent")
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "bench"))
    from broad_accuracy import load

    scores = {}
    for name in REGRESSION:
        tr = load(DATA / f"{name}.mat")
        imu = ik.ImuData(np.arange(len(tr.gyr)) / tr.rate, tr.gyr, tr.acc)
        scores[name] = []
        for offline, nine in MODES:
            res = ik.filters.Robust().run(imu, mag=tr.mag if nine else None, offline=offline)
            q = res.rotation.as_quat(scalar_first=True)
            err = ik.eval.attitude_error(q, tr.truth, scalar_first=True, align_heading=not nine, mask=tr.movement)
            rmse = err.rmse(degrees=True)
            scores[name].append(rmse.total if nine else rmse.inclination)
    return scores


def _measured(name: str) -> list[float]:
    online, offline = REGRESSION[name]
    return [*online, *offline]


@pytest.mark.parametrize("name", sorted(REGRESSION))
def test_accuracy_regression_on_broad(broad_scores: dict[str, list[float]], name: str) -> None:
    for (offline, nine), value, bound in zip(MODES, broad_scores[name], _measured(name), strict=True):
        assert value < 1.15 * bound, f"{name} {_mode(offline, nine)}: {value:.3f}° vs {bound}°"


def test_accuracy_regression_per_group_and_overall(broad_scores: dict[str, list[float]]) -> None:
    sets = {group: [n for n in REGRESSION if n[:2] in ids.split()] for group, ids in GROUPS.items()}
    assert sorted(n for names in sets.values() for n in names) == sorted(REGRESSION)
    sets["all 12"] = list(REGRESSION)
    for group, names in sets.items():
        for i, (offline, nine) in enumerate(MODES):
            value = np.mean([broad_scores[n][i] for n in names])
            bound = np.mean([_measured(n)[i] for n in names])
            assert value < 1.10 * bound, f"{group} {_mode(offline, nine)}: mean {value:.3f}° vs {bound:.3f}°"


@pytest.mark.skipif(
    not (DATA.parent / "euroc_v1_02_medium" / "imu0_data_first40s.csv").exists(),
    reason="../shared/data/euroc_v1_02_medium (the shared EuRoC excerpt) is absent",
)
def test_accuracy_regression_on_euroc() -> None:
    """Issue 15: a drone idling under rotor vibration with a 4.45 °/s bias about z. Rest must be
    found on the ground and the bias measured there: with the raw-sample rest test and VQF's 2 °/s
    clip the 6D heading was 25.4° online / 24.8° offline. Bounds: measured (docs/filters_robust.md,
    "Issue 15") + 15%."""
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from euroc import load as load_euroc

    d = load_euroc()
    imu = ik.ImuData(d.seconds, d.gyro, d.accel)
    truth = d.rotation.as_quat(scalar_first=True)
    # (heading with the offset removed, inclination) [°], online then offline
    for offline, (heading, inclination) in ((False, (0.37, 1.94)), (True, (0.15, 0.94))):
        res = ik.filters.Robust().run(imu, offline=offline)
        assert res.rest[: int(2.5 * 200)].any(), "no rest on the ground"
        q = res.rotation.as_quat(scalar_first=True)
        rmse = ik.eval.attitude_error(q, truth, scalar_first=True, align_heading=True).rmse(degrees=True)
        what = "offline" if offline else "online"
        assert rmse.heading < 1.15 * heading, f"{what} heading {rmse.heading:.3f}°"
        assert rmse.inclination < 1.15 * inclination, f"{what} inclination {rmse.inclination:.3f}°"


@pytest.mark.parametrize(
    ("options", "argument"),
    [
        ({"bias_sigma_init_rad_s": 1e160}, "bias_sigma_init_rad_s"),
        ({"bias_sigma_motion_rad_s": 1e200}, "bias_sigma_motion_rad_s"),
        ({"bias_sigma_rest_rad_s": 1e151}, "bias_sigma_rest_rad_s"),
        ({"bias_sigma_init_rad_s": 1e6, "bias_forgetting_s": 1e-300}, "bias_forgetting_s"),
    ],
)
def test_sigmas_whose_squares_overflow_are_refused(options: dict[str, float], argument: str) -> None:
    """``bias_sigma_init_rad_s=1e160`` returned an infinite σ for every sample (and NaN in the
    state's covariance) before 2026-12-07."""
    with pytest.raises(ParameterError, match=rf"^{argument}: ") as e:
        ik.filters.Robust(**options)
    assert e.value.argument == argument
    imu, _, _ = _imu(5.0)
    result = ik.filters.Robust(bias_sigma_init_rad_s=1e6, bias_sigma_motion_rad_s=1e6).run(imu)  # at the bound
    assert np.isfinite(result.gyro_bias_sigma).all() and np.isfinite(result.gyro_bias).all()


def _drop(imu: ik.ImuData, mag: np.ndarray, seed: int) -> tuple[ik.ImuData, np.ndarray, np.ndarray]:
    """0.5 % of the samples start a run of 1-3 dropped ones; the kept gyro sample after a run is
    the mean over the interval it now spans (as a sensor's integrating output would be)."""
    rng = np.random.default_rng(seed)
    n = len(imu)
    keep = np.ones(n, bool)
    for s in rng.choice(np.arange(10, n - 10), size=n // 200, replace=False):
        keep[s : s + rng.integers(1, 4)] = False
    idx = np.flatnonzero(keep)
    total = np.vstack([np.zeros(3), np.cumsum(imu.gyro, axis=0)])
    before = np.concatenate([[-1], idx[:-1]])
    gyro = (total[idx + 1] - total[before + 1]) / (idx - before)[:, None]
    gyro[0] = imu.gyro[0]
    return ik.ImuData(imu.t[idx], gyro, imu.accel[idx]), mag[idx], idx


def test_dropped_samples_cost_nothing() -> None:
    """Dropped samples (steps of 2-4 nominal ones): each changed step mapped the Butterworths'
    delay elements keeping the level and dropping the slope, and at a ratio of exactly 2 the
    stamps' rounding mapped into the gap and not out of it. BROAD trial 08 online 6D went from
    1.29° to 2.52° with 0.5 % dropped, offline up to 10° off over 10 s, before 2026-12-07. Now a
    ramp's level and slope are carried: the dropped run stays within hundredths of a degree of the
    whole one (synthetic turning record here; BROAD below)."""
    imu, mag, _ = _imu(60.0, rate=200.0)
    accel = imu.accel + np.stack([np.sin(1.3 * imu.t), np.cos(0.9 * imu.t), 0 * imu.t], 1)  # accelerations
    imu = ik.ImuData(imu.t, imu.gyro, accel)
    for seed in (0, 1):
        dropped, dmag, idx = _drop(imu, mag, seed)
        for offline in (False, True):
            for nine in (False, True):
                whole = ik.filters.Robust().run(imu, mag=mag if nine else False, offline=offline).rotation[idx]
                part = ik.filters.Robust().run(dropped, mag=dmag if nine else False, offline=offline).rotation
                d = np.degrees((part * whole.inv()).magnitude())
                # measured: mean ≤ 0.18°, max ≤ 0.44° (seed 0: the 4 s bias windows end on other
                # samples, 0.025 °/s apart); seed 1 0.002° / 0.19°
                assert d.mean() < 0.25 and d.max() < 0.6, (seed, _mode(offline, nine), d.mean(), d.max())


def test_dropped_samples_on_broad_cost_nothing() -> None:
    if not DATA.is_dir():
        pytest.skip("../shared/data/broad (the shared BROAD trials) is absent")
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "bench"))
    from broad_accuracy import load

    tr = load(DATA / "08_undisturbed_fast_rotation_with_breaks_A.mat")
    imu = ik.ImuData(np.arange(len(tr.gyr)) / tr.rate, tr.gyr, tr.acc)
    dropped, dmag, idx = _drop(imu, tr.mag, 0)
    for offline in (False, True):
        for nine in (False, True):
            whole = ik.filters.Robust().run(imu, mag=tr.mag if nine else False, offline=offline).rotation[idx]
            part = ik.filters.Robust().run(dropped, mag=dmag if nine else False, offline=offline).rotation
            d = np.degrees((part * whole.inv()).magnitude())
            # measured: mean ≤ 0.023°, 99.9th percentile ≤ 0.08° (offline 9D's heading steps by up
            # to 1.8° in one sample at rest, in the whole run too, one sample later or earlier)
            assert d.mean() < 0.05 and np.percentile(d, 99.9) < 0.3, (_mode(offline, nine), d.mean(), d.max())


@pytest.mark.parametrize("gap_s", [2.0, 5.0, 10.0, 30.0])
@pytest.mark.parametrize("at_s", [0.5, 20.0])
def test_a_gap_at_rest_keeps_robust_level(gap_s: float, at_s: float) -> None:
    """A level sensor at rest (100 Hz, noisy), its stamps jumping by ``gap_s`` at ``at_s``: the
    estimate stays level, online and offline, 6D and 9D, but for the gyro's one sample turned over
    the gap (the rate over a gap is unknown; the sample after it stands for it), gone within 10 s.
    Before: the online low pass started in the steady state of the first sample's inert
    coefficients, a transient (its output 28% low after 0.5 s) that the ramp carry across a gap
    extrapolated (2 s or more 0.5 s in: upside down, also on BROAD 01), and the bilinear prewarp
    ``tan(dt / 2τ)`` wrapped past π τ (a 30 s gap 20 s in: 60° off on BROAD 01)."""
    rng = np.random.default_rng(7)
    rate, n = 100.0, 4000
    t = np.arange(n) / rate
    t[t >= at_s] += gap_s
    bias = np.array([1e-3, -2e-3, 1.5e-3])
    gyro = rng.normal(0.0, 2e-3, (n, 3)) + bias
    acc = rng.normal(0.0, 0.02, (n, 3)) + np.array([0.0, 0.0, 9.81])
    mag = rng.normal(0.0, 0.3, (n, 3)) + np.array([0.0, 20.0, -40.0])
    imu = ik.ImuData(t, gyro, acc)
    after = int(np.searchsorted(t, at_s + gap_s))
    turn = np.degrees(np.linalg.norm(gyro[after] - bias) * gap_s)  # its noise, the bias learned
    later = t >= t[after] + 10.0
    for offline in (False, True):
        for nine in (False, True):
            rot = ik.filters.Robust().run(imu, mag=mag if nine else None, offline=offline).rotation
            up = rot.inv().apply([0.0, 0.0, 1.0])
            tilt = np.degrees(np.arccos(np.clip(up[:, 2], -1.0, 1.0)))
            mode = _mode(offline, nine)
            assert tilt.max() < 1.0 + turn, (mode, tilt.max(), int(np.argmax(tilt)), turn)
            assert tilt[later].max() < 1.0, (mode, tilt[later].max())
