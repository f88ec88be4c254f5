"""VQF 6D on a real BROAD trial through imukit.eval.attitude_error: the metric reproduces the published
accuracy, and a wrong frame convention is caught; imukit's filters meet issue 7's accuracy targets on
the 3 shared trials. Skips when the shared data folder is absent."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import imukit as ik

TRIAL = Path(__file__).resolve().parents[2] / "shared" / "data" / "broad" / "06_undisturbed_fast_rotation_A.mat"

pytestmark = pytest.mark.skipif(
    not TRIAL.exists(),
    reason=f"BROAD trial not found at {TRIAL} (it lives in the team's shared/ folder, not in the repo)",
)


@pytest.fixture(scope="module")
def vqf_run() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(VQF 6D estimate, mocap truth, movement mask), quaternions w first, ENU."""
    scipy_io = pytest.importorskip("scipy.io")
    vqf = pytest.importorskip("vqf")
    d = scipy_io.loadmat(TRIAL)
    gyr, acc = (np.ascontiguousarray(d[k], dtype=float) for k in ("imu_gyr", "imu_acc"))
    est = vqf.VQF(1.0 / float(d["sampling_rate"].item())).updateBatch(gyr, acc)["quat6D"]
    return np.asarray(est), np.asarray(d["opt_quat"], dtype=float), d["movement"].ravel().astype(bool)


def test_vqf_6d_inclination_matches_the_published_accuracy(vqf_run: tuple[np.ndarray, ...]) -> None:
    est, truth, movement = vqf_run
    err = ik.eval.attitude_error(est, truth, scalar_first=True, align_heading=True, mask=movement)
    r = err.rmse(degrees=True)
    # VQF paper (Laidig & Seel 2023): mean 6D inclination RMSE 0.72° over the 39 BROAD trials;
    # per trial it stays within a few tenths to ~2°. This trial gives 0.80°.
    assert 0.2 < r.inclination < 3.0
    assert r.total < 5.0  # after removing the constant heading offset
    # the mocap dropouts inside the movement phase are excluded and counted, not propagated
    missing_in_movement = int((movement & np.isnan(truth).any(axis=1)).sum())
    assert missing_in_movement > 0
    assert r.n_samples == int(movement.sum()) - missing_in_movement
    assert np.isfinite([r.total, r.heading, r.inclination]).all()


def test_wrong_conventions_give_large_errors(vqf_run: tuple[np.ndarray, ...]) -> None:
    est, truth, movement = vqf_run
    good = ik.eval.attitude_error(est, truth, scalar_first=True, align_heading=True, mask=movement).rmse(degrees=True)
    # q_bw instead of q_wb (a conjugated estimate)
    conj = est * np.array([1.0, -1.0, -1.0, -1.0])
    bad = ik.eval.attitude_error(conj, truth, scalar_first=True, align_heading=True, mask=movement).rmse(degrees=True)
    assert bad.inclination > 10 * good.inclination and bad.inclination > 10.0
    # truth re-expressed in NED against the ENU estimate: upside down
    ned = Rotation.from_matrix([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
    ok = ~np.isnan(truth).any(axis=1)
    truth_ned = np.full_like(truth, np.nan)
    truth_ned[ok] = (ned * Rotation.from_quat(truth[ok], scalar_first=True)).as_quat(scalar_first=True)
    upside = ik.eval.attitude_error(est, truth_ned, scalar_first=True, align_heading=True, mask=movement)
    assert upside.rmse(degrees=True).inclination > 170.0
    # the heading alignment moves heading and total only: the inclination is independent of it
    raw = ik.eval.attitude_error(est, truth, scalar_first=True, mask=movement).rmse(degrees=True)
    assert raw.inclination == pytest.approx(good.inclination, rel=1e-9)  # tilt is heading-independent


BROAD = TRIAL.parent
TRIALS = ("01_undisturbed_slow_rotation_A", "06_undisturbed_fast_rotation_A", "24_disturbed_tapping_A")


def test_imukit_filters_meet_the_broad_accuracy_targets() -> None:
    """Issue 7: with default parameters, on the 3 shared trials, the best imukit filter has a mean
    6D inclination RMSE ≤ 1.0° and a mean 9D total RMSE ≤ 3.0° (docs/filters_accuracy.md: Mahony
    6D 0.85°, Madgwick 9D 2.24°; 1.73° and 6.26° with the defaults before tuning)."""
    scipy_io = pytest.importorskip("scipy.io")
    inc6: dict[str, list[float]] = {"Mahony": [], "Madgwick": []}
    tot9: dict[str, list[float]] = {"Mahony": [], "Madgwick": []}
    for name in TRIALS:
        d = scipy_io.loadmat(BROAD / f"{name}.mat")
        gyr, acc, mag = (np.ascontiguousarray(d[k], dtype=float) for k in ("imu_gyr", "imu_acc", "imu_mag"))
        imu = ik.ImuData(np.arange(len(gyr)) / float(d["sampling_rate"].item()), gyr, acc)
        truth, movement = np.asarray(d["opt_quat"], dtype=float), d["movement"].ravel().astype(bool)
        for cls in (ik.filters.Mahony, ik.filters.Madgwick):
            for nine in (False, True):
                q = cls().run(imu, mag=mag if nine else None).rotation.as_quat(scalar_first=True)
                r = ik.eval.attitude_error(q, truth, scalar_first=True, align_heading=not nine, mask=movement).rmse(
                    degrees=True
                )
                (tot9 if nine else inc6)[cls.__name__].append(r.total if nine else r.inclination)
    best6 = min(float(np.mean(v)) for v in inc6.values())
    best9 = min(float(np.mean(v)) for v in tot9.values())
    assert best6 <= 1.0, inc6
    assert best9 <= 3.0, tot9
