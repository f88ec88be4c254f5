"""Attitude-filter accuracy on the 12 shared BROAD trials and the EuRoC excerpt: imukit's filters
(``Mahony``, ``Madgwick``, and ``Robust`` online and offline once ``imukit.filters.Robust`` exists),
vqf (``VQF``, ``offlineVQF``, ``BasicVQF``), ahrs (Mahony, Madgwick) and imufusion, default
parameters, measured in one run.

Usage: ``python bench/broad_accuracy.py [--data ../shared/data/broad] [--out report.md]`` (about 6
minutes on a loaded 2-core machine; ahrs is pure Python and imufusion a Python loop).

Tables: per trial (one per quantity, a column per filter), per cross-validation group
(``GROUPS``) and over all trials: 6D inclination and heading (constant heading offset removed),
9D total, heading and inclination. EuRoC V1_02_medium (``../shared/data/euroc_v1_02_medium``,
200 Hz, no magnetometer): 6D inclination against its ground truth over the whole excerpt, read with
``tests/euroc.py``.

Metric (BROAD, Laidig et al., Data 2021): :func:`imukit.eval.attitude_error` — error quaternion in
the ENU world frame split into heading and inclination, RMSE over the trial's ``movement`` samples
that have a motion-capture quaternion (NaN rows excluded and counted); 6D filters with
``align_heading=True`` (constant heading offset removed, circular mean over those samples), 9D
filters as they are.

Every peer's output is converted to ``q_wb`` (body to world, Hamilton, w first) in ENU:

* ``vqf.VQF`` (the full online filter), ``vqf.offlineVQF`` and ``vqf.BasicVQF``: ENU
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

Gyro/mocap lag: ``ik.eval.time_offset`` correlates the gyro's angular speed with the motion
capture's and gives the lag in (fractional) samples, rounded to whole ones for the shifted table;
the RMSE columns are without any shift, and a second table gives the RMSE with truth shifted by
the rounded lag (the estimate at IMU sample k compared with mocap sample k − lag), so the effect is
visible, never silently applied.
"""

from __future__ import annotations

import argparse
import sys
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
# The cross-validation groups of ../shared/data/README.md; TRIALS is all of them, in order.
GROUPS: dict[str, tuple[str, ...]] = {
    "rotation": (
        "01_undisturbed_slow_rotation_A",
        "03_undisturbed_slow_rotation_C",
        "06_undisturbed_fast_rotation_A",
        "08_undisturbed_fast_rotation_with_breaks_A",
    ),
    "translation": (
        "10_undisturbed_slow_translation_A",
        "12_undisturbed_slow_translation_C",
        "18_undisturbed_fast_translation_with_breaks_B",
    ),
    "tapping+vibration": ("24_disturbed_tapping_A", "27_disturbed_phone_vibration_B"),
    "magnets": (
        "28_disturbed_stationary_magnet_A",
        "32_disturbed_attached_magnet_1cm",
        "34_disturbed_attached_magnet_3cm",
    ),
}
TRIALS: tuple[str, ...] = tuple(name for names in GROUPS.values() for name in names)
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


def run_basic_vqf(tr: Trial, nine: bool) -> np.ndarray:
    import vqf

    f = vqf.BasicVQF(1.0 / tr.rate)
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


def imukit_runner(name: str, **run_kw: Any) -> Callable[[Trial, bool], np.ndarray] | None:
    """imukit's filter ``imukit.filters.<name>`` (None while it does not exist, e.g. ``Robust``
    before it lands): ``<name>().run(imu, mag=..., **run_kw).rotation`` (``R_wb``, ENU)."""
    cls = getattr(ik.filters, name, None)
    if cls is None:
        return None

    def run(tr: Trial, nine: bool) -> np.ndarray:
        imu = ik.ImuData(np.arange(len(tr.gyr)) / tr.rate, tr.gyr, tr.acc)
        res: Any = cls().run(imu, mag=tr.mag if nine else None, **run_kw)
        return np.asarray(res.rotation.as_quat(scalar_first=True))

    return run


def euroc_trial() -> Trial | None:
    """The EuRoC excerpt as a 6D trial (every sample scored; no magnetometer), or None when absent."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
    from euroc import IMU_CSV
    from euroc import load as load_euroc

    if not IMU_CSV.exists():
        return None
    d = load_euroc()
    n = len(d.seconds)
    rate = float((n - 1) / d.seconds[-1])
    return Trial(
        "euroc_v1_02_medium",
        np.ascontiguousarray(d.gyro),
        np.ascontiguousarray(d.accel),
        np.zeros((n, 3)),
        d.rotation.as_quat(scalar_first=True),
        np.ones(n, bool),
        rate,
    )


# --- lag ------------------------------------------------------------------------------------------


def measure_lag(tr: Trial) -> tuple[int, ik.eval.TimeOffset]:
    """The gyro's lag L behind the motion capture in whole samples (L > 0: the gyro lags), from
    ``ik.eval.time_offset`` on the gyro and the mocap rotations (its offset: the IMU's time t is
    the reference's t + offset, so L = round(−offset · rate))."""
    t = np.arange(len(tr.gyr)) / tr.rate
    ok = np.all(np.isfinite(tr.truth), axis=1)
    mocap = ik.Trajectory(t[ok], np.zeros((ok.sum(), 3)), None, Rotation.from_quat(tr.truth[ok], scalar_first=True))
    found = ik.eval.time_offset(ik.ImuData(t, tr.gyr, tr.acc), mocap)
    return round(-found.offset * tr.rate), found


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


RUNNERS: list[tuple[str, Callable[[Trial, bool], np.ndarray] | None]] = [
    ("imukit Mahony", imukit_runner("Mahony")),
    ("imukit Madgwick", imukit_runner("Madgwick")),
    ("imukit Robust", imukit_runner("Robust")),
    ("imukit Robust offline", imukit_runner("Robust", offline=True)),
    ("vqf VQF", run_vqf),
    ("vqf offlineVQF", run_offline_vqf),
    ("vqf BasicVQF", run_basic_vqf),
    ("ahrs Mahony", run_ahrs_mahony),
    ("ahrs Madgwick", run_ahrs_madgwick),
    ("imufusion Ahrs", run_imufusion),
]
QUANTITIES = (  # (mode, field of the RMSE, title)
    ("6D", "inclination", "6D inclination"),
    ("6D", "heading", "6D heading (offset removed)"),
    ("9D", "total", "9D total"),
    ("9D", "heading", "9D heading"),
    ("9D", "inclination", "9D inclination"),
)


def measure(label: str, runner: Callable[[Trial, bool], np.ndarray], tr: Trial, nine: bool, lag: int) -> dict[str, Any]:
    """One filter on one trial: its RMSE (as is and with truth shifted by ``lag``), or why it failed."""
    row: dict[str, Any] = dict(filter=label, mode="9D" if nine else "6D", trial=tr.name)
    start = time.perf_counter()
    try:
        q = runner(tr, nine)
    except Exception as exc:  # a peer failing is a result to report, not a crash
        row["failed"] = f"{type(exc).__name__}: {exc}"
        return row
    row["us"] = 1e6 * (time.perf_counter() - start) / len(q)
    if not np.isfinite(q).all():
        row["failed"] = f"non-finite output from sample {int(np.argmax(~np.isfinite(q).all(axis=1)))}"
        return row
    for key, truth in (("raw", tr.truth), ("lag", shifted(tr.truth, lag))):
        err = ik.eval.attitude_error(q, truth, scalar_first=True, align_heading=not nine, mask=tr.movement, world="ENU")
        row[key] = err.rmse(degrees=True)
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", type=Path, default=DATA, help="folder of the BROAD .mat files (default: %(default)s)")
    parser.add_argument("--out", type=Path, default=None, help="also write the markdown report here")
    args = parser.parse_args()

    runners = [(label, r) for label, r in RUNNERS if r is not None]
    labels = [label for label, _ in runners]
    trials = [load(args.data / f"{name}.mat") for name in TRIALS]
    lines: list[str] = []

    def emit(s: str = "") -> None:
        print(s, flush=True)
        lines.append(s)

    lags = {}
    emit("### Gyro vs motion-capture lag\n")
    emit(
        "| trial | N | movement samples | NaN mocap (all / in movement) | lag [samples] "
        "| gyro lag from `ik.eval.time_offset` [samples] | correlation at it |"
    )
    emit("|---|---|---|---|---|---|---|")
    for tr in trials:
        lag, found = measure_lag(tr)
        lags[tr.name] = lag
        nan = np.isnan(tr.truth).any(axis=1)
        emit(
            f"| {tr.name} | {len(tr.gyr)} | {tr.movement.sum()} | {nan.sum()} / {(nan & tr.movement).sum()} "
            f"| {lag:+d} | {-found.offset * tr.rate:+.3f} | {found.correlation:.5f} |"
        )

    rows = {
        (label, nine, tr.name): measure(label, runner, tr, nine, lags[tr.name])
        for label, runner in runners
        for nine in (False, True)
        for tr in trials
    }

    def value(label: str, mode: str, field: str, names: tuple[str, ...], key: str = "raw") -> str:
        sel = [rows[(label, mode == "9D", n)] for n in names]
        if any("failed" in r for r in sel):
            return "failed"
        return f"{np.mean([getattr(r[key], field) for r in sel]):.2f}"

    head = "| | " + " | ".join(labels) + " |\n|---|" + "---|" * len(labels)
    for mode, field, title in QUANTITIES:
        emit(f"\n### {title} RMSE during movement [°], per trial\n")
        emit(head)
        for tr in trials:
            emit(f"| {tr.name} | " + " | ".join(value(lb, mode, field, (tr.name,)) for lb in labels) + " |")
    emit("\n### Means per group and over all 12 trials [°]\n")
    emit("| quantity | group | " + " | ".join(labels) + " |\n|---|---|" + "---|" * len(labels))
    for mode, field, title in QUANTITIES:
        for group, names in (*GROUPS.items(), ("all 12", TRIALS)):
            emit(f"| {title} | {group} | " + " | ".join(value(lb, mode, field, names) for lb in labels) + " |")
    emit("\n### All 12 trials with truth shifted by the measured lag [°]\n")
    emit("| quantity | " + " | ".join(labels) + " |\n|---|" + "---|" * len(labels))
    for mode, field, title in QUANTITIES:
        emit(f"| {title} | " + " | ".join(value(lb, mode, field, TRIALS, "lag") for lb in labels) + " |")
    emit("\n### Median time per sample [µs] (one whole-trial call, Python loops included)\n")
    emit("| mode | " + " | ".join(labels) + " |\n|---|" + "---|" * len(labels))
    for mode in ("6D", "9D"):
        us = [[rows[(lb, mode == "9D", n)].get("us", np.nan) for n in TRIALS] for lb in labels]
        emit(f"| {mode} | " + " | ".join(f"{np.nanmedian(u):.2f}" for u in us) + " |")
    failed = [f"{k[0]} {'9D' if k[1] else '6D'} {k[2]}: {r['failed']}" for k, r in rows.items() if "failed" in r]
    if failed:
        emit("\nFailed runs: " + "; ".join(failed) + ".")
    missing = [label for label, r in RUNNERS if r is None]
    if missing:
        emit(f"\nNot in this build (rows appear once they exist): {', '.join(missing)}.")

    euroc = euroc_trial()
    if euroc is None:
        emit("\nEuRoC excerpt not found: skipped.")
    else:
        emit(f"\n### EuRoC V1_02_medium excerpt ({len(euroc.gyr)} samples, {euroc.rate:.1f} Hz), 6D [°]\n")
        emit("| filter | inclination RMSE | heading RMSE (offset removed) | max inclination |")
        emit("|---|---|---|---|")
        for label, runner in runners:
            q = runner(euroc, False)
            err = ik.eval.attitude_error(q, euroc.truth, scalar_first=True, align_heading=True, world="ENU")
            r = err.rmse(degrees=True)
            worst = float(np.degrees(np.nanmax(err.inclination)))
            emit(f"| {label} | {r.inclination:.2f} | {r.heading:.2f} | {worst:.2f} |")
    if args.out is not None:
        args.out.write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
