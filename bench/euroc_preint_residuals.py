"""Preintegration on real data: EuRoC V1_02_medium, consecutive non-overlapping windows inside the
ground-truth span, preintegrated with the ground-truth biases at the window start and the EuRoC
datasheet (Kalibr ``imu0/sensor.yaml``) noise; residual of the ground truth at j against the
prediction from the ground truth at i, whitened with ``pim.covariance``.

Usage: ``python bench/euroc_preint_residuals.py [--data DIR] [--window 0.5] [--out FILE.md] [--plot FILE.png]``.
Prints markdown tables; ``--plot`` needs matplotlib, which is not a dependency of the project (when it is
missing the plot is skipped with a note and the tables are printed as usual).

Finding (0.5 s windows, euler, measured with this script): the whitened residuals are far from χ²₉
(median ~650 against 8.3), in every block (θ ~6×, v ~13×, p ~12× the datasheet σ). The datasheet covariance
models only the sensor's white noise; what dominates instead:

* velocity and position (the bulk of the 9-dof value): a slowly varying acceleration discrepancy of
  ~0.06 m/s² rms between the IMU (with the ground-truth bias) and the ground truth. It grows linearly with
  the window in v and quadratically in p (ground-truth endpoint noise would not grow: it is ~1 mm/s per
  sample), is there already while the MAV stands on the ground (IMU against the ground truth's attitude
  and bias only), is correlated between consecutive windows, shows in the vertical as much as in the
  horizontal, and is not removed by a constant bias correction. Scratch checks (not in this script): a
  lever arm, or a 3×3 accelerometer scale/misalignment, fitted on the even windows did not reduce it on
  the odd ones; the gravity magnitude (9.80 to 9.815) changes it by < 3%. The ground truth is itself an
  estimate whose accelerometer bias is nearly constant; a time-varying accelerometer error of this size
  (or a ground-truth attitude error of ~6 mrad) is outside both the datasheet model and the ground truth.
* rotation: the euler scheme's half-sample lag (sample k held over ``[t_k, t_k+1)``), with a ~1 ms
  IMU/ground-truth stamp offset, is ~40% of the θ variance. The rest (still ~5× σ) grows between white
  noise and drift; the gyro's high-frequency content is ~3× the datasheet on the ground and ~14× in flight
  (vibration), and the residuals of consecutive windows are correlated (~0.4 on two axes). A 3×3 gyro
  scale/misalignment fitted on the even windows removed ~15% of it on the odd ones (scratch check).
* ground-truth noise proper matters only for the shortest windows.

The datasheet values below are the EuRoC ``imu0/sensor.yaml`` ones; the data README does not list them
(the folder has only ``gt0_sensor.yaml``), they match ``ImuNoise``'s worked example and
``tests/test_data_types.py``.
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation, Slerp
from scipy.stats import chi2

import imukit as ik

FloatArray = NDArray[np.float64]

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "euroc_v1_02_medium"
# EuRoC imu0/sensor.yaml (Kalibr, ADIS16448): densities [unit/√Hz] and random walks [unit/s/√Hz].
GYRO_DENSITY, ACCEL_DENSITY = 1.6968e-4, 2.0e-3
GYRO_WALK, ACCEL_WALK = 1.9393e-5, 3.0e-3
NOISE = ik.ImuNoise(GYRO_DENSITY, ACCEL_DENSITY, GYRO_WALK, ACCEL_WALK)
SCHEMES = ("euler", "midpoint")
BLOCKS = (("θ", slice(0, 3)), ("v", slice(3, 6)), ("p", slice(6, 9)))
SCALING_WINDOWS = (0.1, 0.25, 0.5, 1.0, 2.0)
SHIFTS_MS = np.arange(-5.0, 5.01, 0.5)
REST_SPEED = 0.05  # m/s: a window is "at rest" when the ground-truth speed stays below this


@dataclass(frozen=True)
class Recording:
    """IMU rows inside the ground-truth span (and those before it), all ground-truth rows; seconds count
    from the first IMU sample inside the span, as in ``tests/euroc.py``."""

    t_ns: NDArray[np.int64]  # (N,) IMU stamps inside the ground-truth span
    seconds: FloatArray  # (N,)
    gyro: FloatArray  # (N, 3)
    accel: FloatArray  # (N, 3)
    before: FloatArray  # (M, 6) IMU rows [gyro, accel] before the ground truth starts (MAV on the ground)
    gt_seconds: FloatArray  # (K,)
    gt: FloatArray  # (K, 16) [p, q_wxyz, v, b_g, b_a]


@dataclass(frozen=True)
class Truth:
    """Ground truth interpolated at the IMU stamps (shifted by ``shift`` seconds)."""

    position: FloatArray
    velocity: FloatArray
    rotation: Rotation
    gyro_bias: FloatArray
    accel_bias: FloatArray


@dataclass(frozen=True)
class Windows:
    """One row per window: residual (9,), covariance (9, 9), bias Jacobian (9, 6), start index i."""

    residual: FloatArray
    covariance: FloatArray
    bias_jacobian: FloatArray
    start: NDArray[np.intp]
    n: int  # samples per window


def load(folder: Path) -> Recording:
    imu_csv, gt_csv = folder / "imu0_data_first40s.csv", folder / "state_groundtruth_estimate0_data.csv"
    imu = np.loadtxt(imu_csv, delimiter=",", comments="#")
    gt = np.loadtxt(gt_csv, delimiter=",", comments="#")
    # float64 cannot hold 19-digit nanosecond stamps exactly: read the first column as int64.
    t_imu = np.loadtxt(imu_csv, delimiter=",", comments="#", usecols=0, dtype=np.int64)
    t_gt = np.loadtxt(gt_csv, delimiter=",", comments="#", usecols=0, dtype=np.int64)
    keep = (t_imu >= t_gt[0]) & (t_imu <= t_gt[-1])
    t0 = t_imu[keep][0]
    return Recording(
        t_ns=t_imu[keep],
        seconds=(t_imu[keep] - t0) * 1e-9,
        gyro=imu[keep, 1:4],
        accel=imu[keep, 4:7],
        before=imu[t_imu < t_gt[0], 1:7],
        gt_seconds=(t_gt - t0) * 1e-9,
        gt=gt[:, 1:17],
    )


def truth(rec: Recording, shift: float = 0.0) -> Truth:
    """Ground truth at ``seconds + shift`` (linear, slerp), clamped to the ground-truth span."""
    s = np.clip(rec.seconds + shift, rec.gt_seconds[0], rec.gt_seconds[-1])

    def interp(cols: slice) -> FloatArray:
        return np.stack([np.interp(s, rec.gt_seconds, c) for c in rec.gt[:, cols].T], axis=-1)

    rotation = Slerp(rec.gt_seconds, Rotation.from_quat(rec.gt[:, 3:7], scalar_first=True))(s)
    return Truth(interp(slice(0, 3)), interp(slice(7, 10)), rotation, interp(slice(10, 13)), interp(slice(13, 16)))


def window_starts(n_samples: int, n: int) -> NDArray[np.intp]:
    """Starts i of the non-overlapping windows [i, i + n] with i + n a valid sample."""
    return np.arange(0, n_samples - n, n)


def run_windows(
    rec: Recording,
    gt: Truth,
    window: float,
    scheme: str = "euler",
    gyro: FloatArray | None = None,
    accel: FloatArray | None = None,
) -> Windows:
    n = round(window / float(np.median(np.diff(rec.seconds))))
    gyro = rec.gyro if gyro is None else gyro
    accel = rec.accel if accel is None else accel
    starts = window_starts(len(rec.seconds), n)
    res, cov, jac = [], [], []
    for i in starts:
        j = i + n
        imu = ik.ImuData(rec.t_ns[i : j + 1], gyro[i : j + 1], accel[i : j + 1])
        bias = ik.ImuBias(gyro=gt.gyro_bias[i], accel=gt.accel_bias[i])
        pim = ik.preintegrate(imu, noise=NOISE, bias=bias, scheme=scheme)
        state_i = ik.NavState(gt.position[i], gt.velocity[i], gt.rotation[i])
        state_j = ik.NavState(gt.position[j], gt.velocity[j], gt.rotation[j])
        predicted = pim.predict(state_i)
        r = pim.residual(state_i, state_j)
        # The residual is the error of the prediction, expressed in frame i.
        assert np.allclose(r[6:9], state_i.rotation.inv().apply(state_j.position - predicted.position), atol=1e-9)
        res.append(r)
        cov.append(pim.covariance)
        jac.append(pim.bias_jacobian)
    return Windows(np.array(res), np.array(cov), np.array(jac), starts, n)


def whitened(w: Windows, block: slice = slice(0, 9)) -> FloatArray:
    r, s = w.residual[:, block], w.covariance[:, block, block]
    return np.asarray(np.einsum("ni,ni->n", r, np.linalg.solve(s, r[..., None])[..., 0]), dtype=np.float64)


def norms(w: Windows, block: slice) -> FloatArray:
    return np.asarray(np.linalg.norm(w.residual[:, block], axis=1), dtype=np.float64)


def rms(x: FloatArray) -> float:
    return float(np.sqrt(np.mean(np.square(x))))


def sigma_norm(w: Windows, block: slice) -> float:
    """√(mean trace) of the covariance block: the rms residual norm the covariance predicts."""
    return float(np.sqrt(np.mean(np.trace(w.covariance[:, block, block], axis1=1, axis2=2))))


def table(header: list[str], rows: list[list[str]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    lines += ["| " + " | ".join(row) + " |" for row in rows]
    return "\n".join(lines)


def g(x: float, digits: int = 3) -> str:
    return f"{x:.{digits}g}"


def distribution_table(results: dict[str, Windows]) -> str:
    dist = chi2(9)
    q95, q99 = float(dist.ppf(0.95)), float(dist.ppf(0.99))
    cols = {name: whitened(w) for name, w in results.items()}
    rows: list[list[str]] = [["windows", "—", *(str(len(c)) for c in cols.values())]]
    rows.append(["mean", g(float(dist.mean())), *(g(float(c.mean())) for c in cols.values())])
    rows.append(["median", g(float(dist.median())), *(g(float(np.median(c))) for c in cols.values())])
    for p in (5, 25, 75, 95):
        rows.append(
            [f"{p}th percentile", g(float(dist.ppf(p / 100))), *(g(float(np.percentile(c, p))) for c in cols.values())]
        )
    rows.append([f"fraction > χ²₉ 95% ({q95:.2f})", "0.05", *(f"{np.mean(c > q95):.2f}" for c in cols.values())])
    rows.append([f"fraction > χ²₉ 99% ({q99:.2f})", "0.01", *(f"{np.mean(c > q99):.2f}" for c in cols.values())])
    return table(["whitened rᵀΣ⁻¹r", "χ²₉", *results], rows)


def block_table(w: Windows, window: float) -> str:
    units = {"θ": ("mrad", 1e3), "v": ("mm/s", 1e3), "p": ("mm", 1e3)}
    rows = []
    for name, block in BLOCKS:
        e = whitened(w, block)
        unit, scale = units[name]
        rows.append(
            [
                name,
                "3",
                g(float(e.mean())),
                g(float(np.median(e))),
                g(float(chi2(3).median())),
                f"{rms(norms(w, block)) * scale:.3g} {unit}",
                f"{sigma_norm(w, block) * scale:.3g} {unit}",
                f"{np.sqrt(e.mean() / 3):.1f}×",
            ]
        )
    for name, block, dof in (("v, p", slice(3, 9), 6), ("all", slice(0, 9), 9)):
        e = whitened(w, block)
        rows.append(
            [name, str(dof), g(float(e.mean())), g(float(np.median(e))), g(float(chi2(dof).median())), "", "", ""]
        )
    rot = np.degrees(norms(w, slice(0, 3)))
    expected = np.degrees(GYRO_DENSITY * np.sqrt(window * chi2(3).median()))
    text = table(
        [
            "block",
            "dof",
            "mean whitened (χ²: = dof)",
            "median whitened",
            "χ² median",
            "rms residual norm",
            "datasheet σ norm",
            "σ inflation needed",
        ],
        rows,
    )
    return (
        f"{text}\n\nRotation residual |r_θ|: median {np.median(rot):.4f}°, 95th percentile "
        f"{np.percentile(rot, 95):.4f}°, max {rot.max():.4f}°; the datasheet white noise alone gives a "
        f"median of {expected:.4f}° (σ_g √(Δt · χ²₃ median))."
    )


def scaling_table(rec: Recording, gt: Truth) -> str:
    rows, prev = [], None
    for window in SCALING_WINDOWS:
        w = run_windows(rec, gt, window)
        now = [rms(norms(w, b)) for _, b in BLOCKS]
        slopes = (
            ["—"] * 3
            if prev is None
            else [f"{np.log(a / b) / np.log(window / prev[0]):.2f}" for a, b in zip(now, prev[1])]
        )
        row = [g(window), str(len(w.residual))]
        for k, (_, block) in enumerate(BLOCKS):
            row += [f"{now[k] * 1e3:.3g}", f"{now[k] / sigma_norm(w, block):.1f}", slopes[k]]
        row.append(g(float(np.median(whitened(w, slice(0, 3))) / chi2(3).median())))
        rows.append(row)
        prev = (window, now)
    header = ["Δt [s]", "windows"]
    for name, unit in (("θ", "mrad"), ("v", "mm/s"), ("p", "mm")):
        header += [f"rms \\|r_{name}\\| [{unit}]", "÷ datasheet σ", "log-log slope"]
    header.append("θ whitened median ÷ χ²₃ median")
    note = (
        "Expected log-log slopes: white noise (datasheet model) θ 0.5, v 0.5, p 1.5; a constant rate or "
        "acceleration error (bias, tilt) θ 1, v 1, p 2; ground-truth noise at the two ends θ 0, v 0, p 0 to 1."
    )
    return f"{table(header, rows)}\n\n{note}"


def timing_table(rec: Recording, window: float) -> tuple[str, dict[str, float]]:
    """θ residual against a shift of the ground truth, for the raw samples and for samples averaged
    over each interval ((x_k + x_k+1)/2 held over [t_k, t_k+1): a trapezoid, no half-sample lag)."""
    trap_g = rec.gyro.copy()
    trap_a = rec.accel.copy()
    trap_g[:-1] = 0.5 * (rec.gyro[:-1] + rec.gyro[1:])
    trap_a[:-1] = 0.5 * (rec.accel[:-1] + rec.accel[1:])
    curves: dict[str, list[float]] = {"euler (sample held)": [], "euler on interval means (trapezoid)": []}
    for shift in SHIFTS_MS:
        gt = truth(rec, shift * 1e-3)
        curves["euler (sample held)"].append(rms(norms(run_windows(rec, gt, window), slice(0, 3))))
        tw = run_windows(rec, gt, window, gyro=trap_g, accel=trap_a)
        curves["euler on interval means (trapezoid)"].append(rms(norms(tw, slice(0, 3))))
    rows = []
    zero = int(np.argmin(np.abs(SHIFTS_MS)))
    best_raw = best_trap = 0.0
    for name, values in curves.items():
        v = np.array(values)
        k = int(np.argmin(v))
        best = float(SHIFTS_MS[k])
        if 0 < k < len(v) - 1:  # parabola through the three points around the minimum
            a, b, c = v[k - 1], v[k], v[k + 1]
            best += 0.5 * float(SHIFTS_MS[1] - SHIFTS_MS[0]) * (a - c) / (a - 2 * b + c)
        if name.startswith("euler (sample"):
            best_raw = best
        else:
            best_trap = best
        share = 1 - (v[k] / v[zero]) ** 2
        if name.startswith("euler (sample"):
            key = {"share": share, "best_rms": float(v[k])}
        rows.append([name, f"{v[zero] * 1e3:.3g}", f"{best:+.2f}", f"{v[k] * 1e3:.3g}", f"{share:.0%}"])
    header = [
        "samples",
        "rms \\|r_θ\\| at shift 0 [mrad]",
        "best shift [ms]",
        "rms \\|r_θ\\| at best [mrad]",
        "variance removed",
    ]
    half = 0.5e3 * float(np.median(np.diff(rec.seconds)))
    note = (
        "The ground truth is read at t + shift. Holding sample k over [t_k, t_k+1) integrates the rate over an "
        f"interval shifted by −h/2 = −{half:.1f} ms, so euler's best shift is −h/2 + offset and the trapezoid's is "
        f"the offset between IMU and ground-truth stamps itself: measured {best_raw:+.2f} and {best_trap:+.2f} ms, "
        f"i.e. a lag of {best_trap - best_raw:.2f} ms (expected {half:.1f}) and an offset of ~{best_trap:+.1f} ms."
    )
    key.update(best_raw=best_raw, best_trap=best_trap)
    return f"{table(header, rows)}\n\n{note}", key


def bias_and_truth(rec: Recording, gt: Truth, w: Windows, window: float) -> tuple[str, dict[str, float]]:
    """The checks table, and a few of its numbers for the reading."""
    lines = []
    key: dict[str, float] = {}
    # A constant correction of the ground-truth biases: residual ≈ r − J δb, least squares per sensor.
    for name, rows, scale, units in [
        ("gyro", slice(0, 3), 1e3, ("mrad/s", "r_θ", "mrad")),
        ("accel", slice(3, 6), 1.0, ("m/s²", "r_v", "mm/s")),
    ]:
        j = w.bias_jacobian[:, rows, rows].reshape(-1, 3)
        r = w.residual[:, rows].reshape(-1)
        db = np.linalg.lstsq(j, r, rcond=None)[0]
        after = rms(np.linalg.norm((r - j @ db).reshape(-1, 3), axis=1))
        lines.append(
            [
                f"constant {name}-bias correction (least squares, 3 parameters)",
                f"δb = {np.array2string(db * scale, precision=3)} {units[0]}; rms \\|{units[1]}\\| "
                f"{rms(norms(w, rows)) * 1e3:.3g} → {after * 1e3:.3g} {units[2]}",
            ]
        )
    speed = np.linalg.norm(gt.velocity, axis=1)
    rest = np.array([speed[i : i + w.n + 1].max() < REST_SPEED for i in w.start])
    if rest.any():
        acc = norms(w, slice(3, 6))[rest] / window
        rate = norms(w, slice(0, 3))[rest] / window
        body = w.residual[rest, 3:6].mean(axis=0) / window
        drift = w.residual[rest, 0:3].mean(axis=0) / window
        lines.append(
            [
                f"{int(rest.sum())} windows at rest (ground-truth speed < {REST_SPEED} m/s, MAV on the ground): "
                "IMU against ground-truth attitude and bias only",
                f"\\|r_v\\|/Δt = {np.median(acc):.3f} m/s² (median), mean {np.array2string(body, precision=3)} m/s² "
                f"(frame i), a tilt of {np.median(acc) / 9.81 * 1e3:.1f} mrad; \\|r_θ\\|/Δt = "
                f"{np.median(rate) * 1e3:.2f} mrad/s (median), mean {np.array2string(drift * 1e3, precision=2)} mrad/s",
            ]
        )
        key["rest_accel"] = float(np.median(acc))
    for name, block in BLOCKS[:2]:
        r = w.residual[:, block]
        lag1 = [float(np.corrcoef(r[:-1, k], r[1:, k])[0, 1]) for k in range(3)]
        lines.append(
            [
                f"correlation of r_{name} between consecutive windows (frame i: x, y, z)",
                ", ".join(f"{c:.2f}" for c in lag1) + " (≈ 0 for white noise or independent endpoint noise)",
            ]
        )
    world = gt.rotation[w.start].apply(w.residual[:, 3:6])
    lines.append(
        [
            "r_v in the world frame, rms per axis (x, y horizontal; z vertical)",
            f"{np.array2string(np.sqrt(np.mean(world**2, axis=0)) * 1e3, precision=1)} mm/s: the vertical is as "
            "large as the horizontal, so a ground-truth tilt error (horizontal only) is not the whole story",
        ]
    )
    span = np.ptp(rec.gt[(rec.gt_seconds >= 0) & (rec.gt_seconds <= rec.seconds[-1]), 13:16], axis=0)
    lines.append(
        [
            "ground-truth accel bias over the excerpt, max − min per axis",
            f"{np.array2string(span * 1e3, precision=2)} mm/s²: the ground truth's bias is nearly constant",
        ]
    )
    accel_err = rms(norms(w, slice(3, 6))) / window
    key["accel_err"] = accel_err
    lines.append(
        [
            "acceleration discrepancy implied by r_v",
            f"rms \\|r_v\\|/Δt = {accel_err:.3f} m/s², i.e. an accel-bias error of that size or a ground-truth "
            f"tilt error of {accel_err / 9.81 * 1e3:.1f} mrad ({np.degrees(accel_err / 9.81):.2f}°); the "
            f"datasheet random walk allows {ACCEL_WALK * np.sqrt(rec.seconds[-1]):.3f} m/s² over the whole "
            f"{rec.seconds[-1]:.0f} s",
        ]
    )
    # Ground-truth noise: the second difference of a smooth signal is ~0, of white noise √6 σ.
    v_gt = rec.gt[:, 7:10]
    p_gt = rec.gt[:, 0:3]
    sv = np.std(np.diff(v_gt, 2, axis=0), axis=0) / np.sqrt(6)
    sp = np.std(np.diff(p_gt, 2, axis=0), axis=0) / np.sqrt(6)
    lines.append(
        [
            "ground-truth noise per sample, from second differences (upper bounds)",
            f"velocity {np.array2string(sv * 1e3, precision=2)} mm/s, position "
            f"{np.array2string(sp * 1e3, precision=3)} mm; at the two ends of a window: "
            f"√2·σ_v = {np.sqrt(2) * np.linalg.norm(sv) * 1e3:.2f} mm/s (norm)",
        ]
    )
    rate_hz = 1.0 / float(np.median(np.diff(rec.seconds)))
    per_sample = np.array([GYRO_DENSITY, ACCEL_DENSITY]) * np.sqrt(rate_hz)
    for what, data in (
        ("on the ground, before the ground truth", rec.before),
        ("in flight", np.hstack([rec.gyro, rec.accel])),
    ):
        hf = np.std(np.diff(data, axis=0), axis=0) / np.sqrt(2)
        key[f"gyro_hf_{what[:2]}"] = float(hf[:3].mean() / per_sample[0])
        lines.append(
            [
                f"IMU high-frequency content {what} (std of first differences / √2, per axis)",
                f"gyro {np.array2string(hf[:3], precision=4)} rad/s ({hf[:3].mean() / per_sample[0]:.1f}× the "
                f"datasheet {per_sample[0]:.2e}), accel {np.array2string(hf[3:], precision=3)} m/s² "
                f"({hf[3:].mean() / per_sample[1]:.0f}× the datasheet {per_sample[1]:.2e})",
            ]
        )
    return table(["check", "result"], lines), key


def log10_pdf(dof: int, y: FloatArray) -> FloatArray:
    """Density of log10 of a χ²_dof variable at y."""
    x = 10.0**y
    return np.asarray(chi2(dof).pdf(x) * x * np.log(10.0), dtype=np.float64)


def plot(path: Path, results: dict[str, Windows]) -> None:
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print(f"note: matplotlib is not installed (not a project dependency); --plot {path} skipped", file=sys.stderr)
        return
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.5))
    y = np.linspace(-2.0, 4.5, 500)
    bins = np.linspace(-1.0, 4.0, 51)
    for name, w in results.items():
        axes[0].hist(np.log10(whitened(w)), bins=bins, density=True, alpha=0.5, label=f"measured, {name}")
    axes[0].plot(y, log10_pdf(9, y), "k", label="χ²₉")
    axes[0].set_xlabel("log10 rᵀΣ⁻¹r (9 dof)")
    axes[0].set_ylabel("density")
    axes[0].legend()
    first = next(iter(results.values()))
    for name, block in BLOCKS:
        axes[1].hist(np.log10(whitened(first, block)), bins=bins, density=True, alpha=0.4, label=f"{name} block")
    axes[1].plot(y, log10_pdf(3, y), "k", label="χ²₃")
    axes[1].set_xlabel(f"log10 whitened block residual (3 dof), {next(iter(results))}")
    axes[1].legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    print(f"wrote {path}", file=sys.stderr)


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--data", type=Path, default=DATA, help=f"EuRoC excerpt folder (default {DATA})")
    parser.add_argument("--window", type=float, default=0.5, help="window length [s] (default 0.5)")
    parser.add_argument("--out", type=Path, help="also write the markdown to this file")
    parser.add_argument("--plot", type=Path, help="PNG histogram of the whitened residuals (needs matplotlib)")
    args = parser.parse_args()
    if not (args.data / "imu0_data_first40s.csv").exists():
        parser.error(f"no EuRoC excerpt in {args.data}")

    rec = load(args.data)
    gt = truth(rec)
    results: dict[str, Windows] = {}
    skipped = []
    for scheme in SCHEMES:
        try:
            results[scheme] = run_windows(rec, gt, args.window, scheme)
        except ik.ParameterError as err:
            skipped.append(f"`{scheme}`: not accepted by this build ({err})")
    w = results["euler"]
    timing, tk = timing_table(rec, args.window)
    checks, ck = bias_and_truth(rec, gt, w, args.window)
    inflation = [float(np.sqrt(whitened(w, b).mean() / 3)) for _, b in BLOCKS]
    theta_sigma = sigma_norm(w, slice(0, 3))
    out = [
        f"# Preintegration residuals on EuRoC V1_02_medium, {args.window:g} s windows",
        "",
        f"{len(w.residual)} non-overlapping windows in the {rec.seconds[-1]:.1f} s ground-truth span; ground-truth "
        f"biases at the window start; datasheet noise σ_g = {GYRO_DENSITY:g} rad/s/√Hz, σ_a = {ACCEL_DENSITY:g} "
        f"m/s²/√Hz (random walks {GYRO_WALK:g}, {ACCEL_WALK:g}); Σ = `pim.covariance` (9×9, [δθ, δv, δp]).",
        *(f"Scheme {s}" for s in skipped),
        "",
        "## Whitened residual against χ²₉",
        "",
        distribution_table(results),
        "",
        *(
            line
            for name, res in results.items()
            for line in (f"## Per block ({name})", "", block_table(res, args.window), "")
        ),
        "## Window length (euler)",
        "",
        scaling_table(rec, gt),
        "",
        "## Timing (euler)",
        "",
        timing,
        "",
        "## Bias, ground truth, vibration (euler)",
        "",
        checks,
        "",
        "## Reading",
        "",
        f"- The datasheet Σ is {inflation[0]:.1f}× (θ), {inflation[1]:.0f}× (v), {inflation[2]:.0f}× (p) too small "
        "in σ for these residuals; no block is near its χ²₃, so dropping the v and p blocks does not make the "
        "rest consistent. No covariance is inflated here: Σ models the sensor's white noise only.",
        f"- Rotation: the euler half-sample lag plus a {tk['best_trap']:+.1f} ms stamp offset remove "
        f"{tk['share']:.0%} of the θ variance (rms {tk['best_rms'] * 1e3:.2f} mrad, "
        f"{tk['best_rms'] / theta_sigma:.1f}× σ, left). The rest grows between white noise and drift "
        f"(log-log slope 0.5 to 0.8) and the gyro's high-frequency content is {ck['gyro_hf_on']:.1f}× the "
        f"datasheet on the ground and {ck['gyro_hf_in']:.0f}× in flight (vibration, partly real motion).",
        f"- Velocity/position: an acceleration discrepancy of {ck['accel_err']:.3f} m/s² rms, growing like a "
        "constant error (log-log slopes near 1 and 2, not 0 as ground-truth endpoint noise would), present at rest "
        f"({ck.get('rest_accel', float('nan')):.3f} m/s²), correlated between windows and not a constant bias: "
        "the IMU and the ground truth's attitude/bias disagree by that much; ground-truth noise "
        "(~1 mm/s per sample) matters only for the shortest windows.",
    ]
    text = "\n".join(out)
    print(text)
    if args.out:
        args.out.write_text(text + "\n", encoding="utf-8")
    if args.plot:
        plot(args.plot, results)


if __name__ == "__main__":
    main()
