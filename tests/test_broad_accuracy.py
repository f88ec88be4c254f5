"""VQF 6D on a real BROAD trial through imukit.eval.attitude_error: the metric reproduces the published
accuracy, and a wrong frame convention is caught; imukit's filters hold their accuracy at the defaults
on the 12 shared trials (issue 15). Skips when the shared data folder is absent."""

from __future__ import annotations

import sys
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
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "bench"))
from broad_accuracy import GROUPS  # noqa: E402  (the cross-validation groups, one place)

# Measured at the defaults (docs/filters_accuracy.md, bench/broad_accuracy.py), per group
# (6D inclination, 9D total) [°]; the bounds are 15% above, so a 20% regression fails.
MEASURED = {
    "Mahony": {
        "rotation": (1.17, 3.52),
        "translation": (0.43, 1.42),
        "tapping+vibration": (0.51, 4.29),
        "magnets": (1.28, 6.89),
    },
    "Madgwick": {
        "rotation": (0.90, 2.91),
        "translation": (0.46, 1.61),
        "tapping+vibration": (0.52, 4.39),
        "magnets": (0.84, 1.93),
    },
}
MEAN = {"Mahony": (0.90, 3.96), "Madgwick": (0.71, 2.59)}  # over the 12 trials


@pytest.fixture(scope="module")
def broad_scores() -> dict[tuple[str, str], tuple[float, float]]:
    """(filter, trial) -> (6D inclination, 9D total) RMSE [°] at the defaults."""
    scipy_io = pytest.importorskip("scipy.io")
    out = {}
    for name in (n for names in GROUPS.values() for n in names):
        d = scipy_io.loadmat(BROAD / f"{name}.mat")
        gyr, acc, mag = (np.ascontiguousarray(d[k], dtype=float) for k in ("imu_gyr", "imu_acc", "imu_mag"))
        imu = ik.ImuData(np.arange(len(gyr)) / float(d["sampling_rate"].item()), gyr, acc)
        truth, movement = np.asarray(d["opt_quat"], dtype=float), d["movement"].ravel().astype(bool)
        for cls in (ik.filters.Mahony, ik.filters.Madgwick):
            r = []
            for nine in (False, True):
                q = cls().run(imu, mag=mag if nine else None).rotation.as_quat(scalar_first=True)
                e = ik.eval.attitude_error(q, truth, scalar_first=True, align_heading=not nine, mask=movement)
                r.append(e.rmse(degrees=True).total if nine else e.rmse(degrees=True).inclination)
            out[(cls.__name__, name)] = (r[0], r[1])
    return out


@pytest.mark.parametrize("filt", ["Mahony", "Madgwick"])
def test_imukit_filters_hold_their_broad_accuracy(
    filt: str, broad_scores: dict[tuple[str, str], tuple[float, float]]
) -> None:
    """Issue 15: at the defaults no trial has a 6D inclination RMSE above 3° (the textbook laws
    reached 31.6° (Mahony) and 7.6° (Madgwick) on trial 18), and the per-group and overall means stay
    within 15% of the measured ones."""
    scores = {n: broad_scores[(filt, n)] for names in GROUPS.values() for n in names}
    worst = max(scores, key=lambda n: scores[n][0])
    assert scores[worst][0] <= 3.0, (worst, scores[worst])
    for group, names in GROUPS.items():
        inc6, tot9 = (float(np.mean([scores[n][i] for n in names])) for i in (0, 1))
        bound6, bound9 = (1.15 * m for m in MEASURED[filt][group])
        assert inc6 <= bound6 and tot9 <= bound9, (group, inc6, tot9)
    inc6, tot9 = (float(np.mean([s[i] for s in scores.values()])) for i in (0, 1))
    assert inc6 <= 1.15 * MEAN[filt][0] and tot9 <= 1.15 * MEAN[filt][1], (inc6, tot9)


@pytest.mark.parametrize("filt", ["Mahony", "Madgwick"])
def test_a_gap_at_rest_does_not_throw_the_estimate(filt: str) -> None:
    """5 s of samples dropped at rest on BROAD 01: the step across the gap is capped where it lands
    on the measurement. Unbounded, it left Madgwick 20.8° and Mahony 7.8° off the uninterrupted run
    (9D; 141° and 13.6° in the gain ramp); capped, 0.98° and 4.4° (one sample of BROAD's field,
    noisy in heading: the filters' averaging then resumes) and 0.07° in 6D."""
    scipy_io = pytest.importorskip("scipy.io")
    d = scipy_io.loadmat(BROAD / "01_undisturbed_slow_rotation_A.mat")
    gyr, acc, mag = (np.ascontiguousarray(d[k], dtype=float) for k in ("imu_gyr", "imu_acc", "imu_mag"))
    rate = float(d["sampling_rate"].item())
    t = np.arange(len(gyr)) / rate
    still = ~d["movement"].ravel().astype(bool)
    hold, skip = int(8 * rate), int(20 * rate)
    start = next(k for k in range(skip, len(t) - hold) if still[k : k + hold].all()) + int(rate)
    keep = np.ones(len(t), bool)
    keep[start : start + int(5 * rate)] = False
    cls = getattr(ik.filters, filt)
    for nine, limit in ((False, 0.3), (True, {"Mahony": 6.0, "Madgwick": 2.0}[filt])):
        whole = cls().run(ik.ImuData(t, gyr, acc), mag=mag if nine else None).rotation[keep]
        gappy = cls().run(ik.ImuData(t[keep], gyr[keep], acc[keep]), mag=mag[keep] if nine else None).rotation
        off = np.degrees((gappy * whole.inv()).magnitude())
        assert off.max() < limit, (nine, off.max())
