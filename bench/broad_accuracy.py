"""Attitude-filter accuracy on the shared BROAD trials: vqf, ahrs, imufusion (and imukit's filters
when ``imukit.filters`` exists), default parameters, measured in one run.

Usage: ``python bench/broad_accuracy.py [--data ../shared/data/broad] [--out report.md]`` (about 70 s;
ahrs is pure Python).

Metric (BROAD, Laidig et al., Data 2021): :func:`imukit.eval.attitude_error` — error quaternion in
the ENU world frame split into heading and inclination, RMSE over the trial's ``movement`` samples
that have a motion-capture quaternion (NaN rows excluded and counted); 6D filters with
``align_heading=True`` (constant heading offset removed, circular mean over those samples), 9D
filters as they are.

Every peer's output is converted to ``q_wb`` (body to world, Hamilton, w first) in ENU:

* ``vqf.VQF`` (the full online filter, not ``BasicVQF``; ``offlineVQF`` as an extra row): ENU
  (its magnetometer correction puts north on +y), ``q_wb``: used as is.
* ``ahrs.filters.Mahony``: propagates ``q ⊗ [0, ω]`` (``q_wb``) and pulls the estimate towards
  gravity on world +z and the horizontal magnetic field on world +y: ENU, used as is. Its 9D start
  (``am2q``) is not in that frame; the correction rotates it in during the initial rest.
* ``ahrs.filters.Madgwick``: ``q_wb``, gravity on +z, magnetic reference ``[b_x, 0, b_z]``: north on
  +x, i.e. NWU (its 9D start, ``ecompass(frame="NED")``, is NED: converges in the rest phase).
  Converted with ``q_enu = q_z(+90°) ⊗ q_nwu`` (as BROAD's own ``process_data.py`` does).
* ``imufusion.Ahrs`` (default settings, default convention NWU; inputs in deg/s and g with
  g = 9.80665 m/s²; ``set_sample_period(1/rate)``): ``q_wb`` in NWU, converted like Madgwick.
  It has no batch API: its time includes a Python loop with one call per sample.

The sample rate (285.714 Hz) is passed to every filter: it is not a tuning parameter. ahrs's
default rate is 100 Hz and imufusion's 100 Hz, so leaving them out would be a bug, not a default.

Gyro/mocap lag: the script cross-correlates the gyro with the body rate differentiated from the
mocap quaternions (central differences) and reports the lag; the RMSE columns are without any
shift, and a second table gives the RMSE with truth shifted by the measured lag (the estimate at
IMU sample k compared with mocap sample k − lag), so the effect is visible, never silently applied.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import scipy.io
from scipy.spatial.transform import Rotation

import imukit as ik

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "broad"  # the team's shared/ folder
TRIALS = ("01_undisturbed_slow_rotation_A", "06_undisturbed_fast_rotation_A", "24_disturbed_tapping_A")
G = 9.80665
# q_z(+90°), w first: NWU world -> ENU world (north x -> y, west y -> -x)
NWU_TO_ENU = np.array([np.sqrt(0.5), 0.0, 0.0, np.sqrt(0.5)])


@dataclass(frozen=True)
class Trial:
    name: str
    gyr: np.ndarray  # (N, 3) rad/s
    acc: np.ndarray  # (N, 3) m/s²
    mag: np.ndarray  # (N, 3) µT
    truth: np.ndarray  # (N, 4) w x y z, ENU, NaN where mocap dropped out
    movement: np.ndarray  # (N,) bool
    rate: float


def load(path: Path) -> Trial:
    d = scipy.io.loadmat(path)
    c = np.ascontiguousarray
    return Trial(
        path.stem,
        c(d["imu_gyr"], dtype=float),
        c(d["imu_acc"], dtype=float),
        c(d["imu_mag"], dtype=float),
        c(d["opt_quat"], dtype=float),
        d["movement"].ravel().astype(bool),
        float(d["sampling_rate"].item()),
    )


# --- peers: each returns (N, 4) w-first q_wb in ENU ---------------------------------------------


def run_vqf(tr: Trial, nine: bool) -> np.ndarray:
    import vqf  # type: ignore[import-untyped]

    f = vqf.VQF(1.0 / tr.rate)
    if nine:
        return np.asarray(f.updateBatch(tr.gyr, tr.acc, tr.mag)["quat9D"])
    return np.asarray(f.updateBatch(tr.gyr, tr.acc)["quat6D"])


def run_offline_vqf(tr: Trial, nine: bool) -> np.ndarray:
    import vqf

    out = vqf.offlineVQF(tr.gyr, tr.acc, tr.mag if nine else None, 1.0 / tr.rate)
    return np.asarray(out["quat9D" if nine else "quat6D"])


def run_ahrs_mahony(tr: Trial, nine: bool) -> np.ndarray:
    from ahrs.filters import Mahony  # type: ignore[import-untyped]

    f = Mahony(gyr=tr.gyr, acc=tr.acc, mag=tr.mag if nine else None, frequency=tr.rate)
    return np.asarray(f.Q)  # ENU (see the module docstring)


def run_ahrs_madgwick(tr: Trial, nine: bool) -> np.ndarray:
    from ahrs.filters import Madgwick

    f = Madgwick(gyr=tr.gyr, acc=tr.acc, mag=tr.mag if nine else None, frequency=tr.rate)
    return ik.quat.multiply(NWU_TO_ENU, np.asarray(f.Q), scalar_first=True)


def run_imufusion(tr: Trial, nine: bool) -> np.ndarray:
    import imufusion

    ahrs = imufusion.Ahrs()
    ahrs.set_sample_period(1.0 / tr.rate)
    gyr, acc, mag = np.degrees(tr.gyr), tr.acc / G, tr.mag
    out = np.empty((len(gyr), 4))
    for k in range(len(gyr)):
        if nine:
            ahrs.update(gyr[k], acc[k], mag[k])
        else:
            ahrs.update_no_magnetometer(gyr[k], acc[k])
        out[k] = ahrs.get_quaternion()
    return ik.quat.multiply(NWU_TO_ENU, out, scalar_first=True)


def imukit_runner(name: str) -> Callable[[Trial, bool], np.ndarray] | None:
    """HOOK for imukit's own filters: used when ``imukit.filters.<name>`` exists, else skipped.

    Expected API (issue 7): ``imukit.filters.<name>().run(imu, mag=...)`` returning a scipy
    ``Rotation`` (R_wb, ENU) or an object with ``.rotation``.
    """
    try:
        from imukit import filters
    except ImportError:
        return None
    cls = getattr(filters, name, None)
    if cls is None:
        return None

    def run(tr: Trial, nine: bool) -> np.ndarray:
        imu = ik.ImuData(np.arange(len(tr.gyr)) / tr.rate, tr.gyr, tr.acc)
        res: Any = cls().run(imu, mag=tr.mag if nine else None)
        rot = res.rotation if hasattr(res, "rotation") else res
        return np.asarray(rot.as_quat(scalar_first=True))

    return run


# --- lag ------------------------------------------------------------------------------------------


def mocap_body_rate(tr: Trial) -> np.ndarray:
    """Body rate from the mocap quaternions by central differences (NaN where a neighbour is NaN)."""
    q = tr.truth
    ok = ~np.isnan(q).any(axis=1)
    filled = np.where(ok[:, None], q, [1.0, 0.0, 0.0, 0.0])
    r = Rotation.from_quat(filled, scalar_first=True)
    rate = np.full((len(q), 3), np.nan)
    rel = (r[:-2].inv() * r[2:]).as_rotvec() * tr.rate / 2.0
    good = ok[:-2] & ok[2:]
    rate[1:-1][good] = rel[good]
    return rate


def measure_lag(tr: Trial, max_lag: int = 10) -> tuple[int, dict[int, float]]:
    """Lag L (samples) maximising corr(gyro[k], mocap_rate[k − L]); L > 0: the gyro lags."""
    w = mocap_body_rate(tr)
    corr = {}
    n = len(w)
    for lag in range(-max_lag, max_lag + 1):
        g = tr.gyr[max_lag : n - max_lag]
        m = w[max_lag - lag : n - max_lag - lag]
        ok = ~np.isnan(m).any(axis=1)
        corr[lag] = float(np.corrcoef(g[ok].ravel(), m[ok].ravel())[0, 1])
    best = max(corr, key=lambda k: corr[k])
    return best, corr


def shifted(truth: np.ndarray, lag: int) -> np.ndarray:
    """truth[k − lag] at index k (NaN where undefined)."""
    out = np.full_like(truth, np.nan)
    if lag > 0:
        out[lag:] = truth[:-lag]
    elif lag < 0:
        out[:lag] = truth[-lag:]
    else:
        out[:] = truth
    return out


# --- report ---------------------------------------------------------------------------------------


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", type=Path, default=DATA, help="folder of the BROAD .mat files (default: %(default)s)")
    parser.add_argument("--out", type=Path, default=None, help="also write the markdown report here")
    args = parser.parse_args()

    runners: list[tuple[str, str, Callable[[Trial, bool], np.ndarray] | None]] = [
        ("imukit Mahony", "imukit.filters.Mahony()", imukit_runner("Mahony")),
        ("imukit Madgwick", "imukit.filters.Madgwick()", imukit_runner("Madgwick")),
        ("vqf VQF", "vqf.VQF(Ts)", run_vqf),
        ("vqf offlineVQF", "vqf.offlineVQF", run_offline_vqf),
        ("ahrs Mahony", "ahrs.filters.Mahony", run_ahrs_mahony),
        ("ahrs Madgwick", "ahrs.filters.Madgwick", run_ahrs_madgwick),
        ("imufusion Ahrs", "imufusion.Ahrs", run_imufusion),
    ]
    trials = [load(args.data / f"{name}.mat") for name in TRIALS]
    lines: list[str] = []

    def emit(s: str = "") -> None:
        print(s, flush=True)
        lines.append(s)

    lags = {}
    emit("### Gyro vs motion-capture lag\n")
    emit("| trial | N | movement samples | NaN mocap (all / in movement) | lag [samples] | corr at −1, 0, +1, +2 |")
    emit("|---|---|---|---|---|---|")
    for tr in trials:
        lag, corr = measure_lag(tr)
        lags[tr.name] = lag
        nan = np.isnan(tr.truth).any(axis=1)
        cs = ", ".join(f"{corr[k]:.5f}" for k in (-1, 0, 1, 2))
        emit(
            f"| {tr.name} | {len(tr.gyr)} | {tr.movement.sum()} | {nan.sum()} / {(nan & tr.movement).sum()} "
            f"| {lag:+d} | {cs} |"
        )

    rows: list[dict[str, Any]] = []
    skipped = []
    for label, _, runner in runners:
        if runner is None:
            skipped.append(label)
            continue
        for nine in (False, True):
            mode = "9D" if nine else "6D"
            for tr in trials:
                start = time.perf_counter()
                try:
                    q = runner(tr, nine)
                except Exception as exc:  # a peer failing is a result to report, not a crash
                    rows.append(dict(filter=label, mode=mode, trial=tr.name, failed=f"{type(exc).__name__}: {exc}"))
                    continue
                elapsed = time.perf_counter() - start
                row: dict[str, Any] = dict(filter=label, mode=mode, trial=tr.name, us=1e6 * elapsed / len(q))
                if not np.isfinite(q).all():
                    row["failed"] = f"non-finite output from sample {int(np.argmax(~np.isfinite(q).all(axis=1)))}"
                    rows.append(row)
                    continue
                for key, truth in (("raw", tr.truth), ("lag", shifted(tr.truth, lags[tr.name]))):
                    err = ik.eval.attitude_error(
                        q, truth, scalar_first=True, align_heading=not nine, mask=tr.movement, world="ENU"
                    )
                    row[key] = err.rmse(degrees=True)
                    if key == "raw":
                        aligned = ik.eval.attitude_error(
                            q, truth, scalar_first=True, align_heading=True, mask=tr.movement
                        )
                        row["offset"] = np.degrees(aligned.heading_offset)
                        row["missing"] = int((tr.movement & ~err.valid).sum())
                rows.append(row)

    emit("\n### RMSE during movement [°] (6D: heading offset removed; 9D: as estimated)\n")
    emit("| filter | mode | trial | total | heading | inclination | heading offset [°] | µs/sample |")
    emit("|---|---|---|---|---|---|---|---|")
    for r in rows:
        if "failed" in r:
            emit(f"| {r['filter']} | {r['mode']} | {r['trial']} | failed: {r['failed']} | | | | |")
            continue
        e = r["raw"]
        emit(
            f"| {r['filter']} | {r['mode']} | {r['trial']} | {e.total:.2f} | {e.heading:.2f} | {e.inclination:.2f} "
            f"| {r['offset']:+.1f} | {r['us']:.2f} |"
        )

    emit("\n### Mean over the 3 trials [°], median time per sample\n")
    emit("| filter | mode | total | heading | inclination | total, lag-comp. | incl., lag-comp. | µs/sample |")
    emit("|---|---|---|---|---|---|---|---|")
    for label, _, runner in runners:
        if runner is None:
            continue
        for mode in ("6D", "9D"):
            sel = [r for r in rows if r["filter"] == label and r["mode"] == mode]
            ok = [r for r in sel if "failed" not in r]
            if len(ok) < len(sel):
                emit(f"| {label} | {mode} | {len(sel) - len(ok)} of {len(sel)} trials failed | | | | | |")
                if not ok:
                    continue

            def mean(key: str, field: str, ok: list[dict[str, Any]] = ok) -> float:
                return float(np.mean([getattr(r[key], field) for r in ok]))

            us = float(np.median([r["us"] for r in ok]))
            emit(
                f"| {label} | {mode} | {mean('raw', 'total'):.2f} | {mean('raw', 'heading'):.2f} "
                f"| {mean('raw', 'inclination'):.2f} | {mean('lag', 'total'):.2f} | {mean('lag', 'inclination'):.2f} "
                f"| {us:.2f} |"
            )
    if skipped:
        emit(f"\nSkipped (not available in this build): {', '.join(skipped)}.")
    emit(
        f"\nMovement samples without a mocap quaternion, excluded: "
        f"{ {tr.name: int((tr.movement & np.isnan(tr.truth).any(axis=1)).sum()) for tr in trials} }."
    )
    if args.out is not None:
        args.out.write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
