"""``imukit preintegrate``: IMU preintegration over fixed-length windows, to CSV or NPZ."""

from __future__ import annotations

import argparse
from typing import Any

import numpy as np
from numpy.typing import NDArray

from imukit.cli._common import (
    CliError,
    add_input_options,
    chunks,
    note,
    out,
    output_path,
    positive,
    progress,
    read_imu,
    wrote,
)
from imukit.imu import ImuData, ImuNoise
from imukit.io import read_euroc_sensor, read_kalibr_imu
from imukit.io._euroc import euroc_extrinsics
from imukit.preint import PreintegratedImu, preintegrate_windows

WINDOWS_PER_CALL = 2_000  # a progress step; each window is computed alone, so the split changes nothing

COLUMNS = (
    "t_start [s]",
    "t_end [s]",
    "delta_t [s]",
    "dR_qx",
    "dR_qy",
    "dR_qz",
    "dR_qw",
    "dv_x [m/s]",
    "dv_y [m/s]",
    "dv_z [m/s]",
    "dp_x [m]",
    "dp_y [m]",
    "dp_z [m]",
    *(f"var_{name}_{axis}" for name in ("theta", "v", "p") for axis in "xyz"),
)
EXACT_COLUMNS = ("t_start_ns", "t_end_ns")  # last in the CSV, for nanosecond stamps only

DESCRIPTION = f"""\
Preintegrate the IMU samples of PATH over consecutive windows of --window seconds (Forster et al.
2017; docs/preintegration.md), from the first sample; a last partial window is dropped.

Reads: PATH in any format imukit detects; the noise model (for the covariance) from --noise, a
Kalibr imu.yaml, else from the EuRoC sensor.yaml of PATH (imu0/ or mav0/imu0/ of a folder, or
beside a bare data.csv; its T_BS is not applied: the body frame is the IMU's).
Frames and units: each window's deltas are in the body frame at its start (frame i); gravity is not
in them (add it with PreintegratedImu.predict); the covariance is in [dtheta, dv, dp] order with
the right perturbation of dR; rad, m/s, m.

Writes --out:
  .csv: one row per window, a header line, columns
        {", ".join(COLUMNS[:13])},
        then the covariance diagonal var_theta_x..z [rad^2], var_v_x..z [m^2/s^2], var_p_x..z [m^2],
        and for nanosecond stamps (EuRoC, TUM-VI, bags) t_start_ns, t_end_ns: the edges as exact
        integers (the float seconds columns round them to about 0.2 us for Unix-epoch stamps);
  .npz: the same as arrays t_start, t_end, delta_t (M,), dR_xyzw, dv, dp (M, 3 or 4), the full
        covariance (M, 9, 9) and bias_jacobian (M, 9, 6) (columns [b_g, b_a]), and t_start_ns,
        t_end_ns (M,) int64 for nanosecond stamps.
Window edges: every --window s from the first sample, the last edge at or before the last sample
(computed in integer ns for nanosecond stamps, the window rounded to a whole ns).
Prints the number of windows and the largest window's deltas.

Example:
  imukit preintegrate MH_01_easy/ --window 0.5 --noise imu.yaml --out windows.csv"""


def add(commands: Any) -> argparse.ArgumentParser:
    p: argparse.ArgumentParser = commands.add_parser(
        "preintegrate",
        help="preintegrate into fixed windows (deltas, covariance) to CSV or NPZ",
        description=DESCRIPTION,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("path", metavar="PATH", help="the recording (EuRoC folder, CSV, bag, ...)")
    p.add_argument("--window", type=positive, required=True, metavar="S", help="window length [s]")
    p.add_argument("--scheme", choices=("euler", "midpoint"), default="midpoint", help="(default: %(default)s)")
    p.add_argument("--noise", metavar="YAML", help="Kalibr imu.yaml with the noise densities")
    p.add_argument("--out", metavar="FILE", help="write the windows to this .csv or .npz file")
    add_input_options(p)
    p.set_defaults(run=run)
    return p


def noise_for(path: str, noise_yaml: str | None) -> ImuNoise:
    """``--noise``, else the EuRoC ``imu0/sensor.yaml`` that goes with PATH
    (:func:`imukit.io.read_euroc_sensor`), else an error."""
    if noise_yaml is not None:
        return read_kalibr_imu(noise_yaml).noise
    sensor = read_euroc_sensor(path)
    if sensor is None:
        raise CliError(f"--noise: {path} has no imu0/sensor.yaml; give the noise model as a Kalibr imu.yaml")
    t_bs = euroc_extrinsics(sensor)
    if t_bs is not None and not np.array_equal(t_bs, np.eye(4)):
        note("the sensor.yaml's T_BS is not the identity; it is not applied: the body frame is the IMU's")
    return sensor.noise


def boundaries(imu: ImuData, window_s: float) -> NDArray[Any]:
    """Window edges on ``imu.t``'s clock, every ``window_s`` from the first sample, the last one at
    or before the last sample: integer ns for ns stamps (the window rounded to a whole ns, the count
    by integer division: exact), else float seconds (the count lowered while rounding puts the last
    edge past the last sample)."""
    if imu.t_ns is not None:
        step = max(round(window_s * 1e9), 1)
        count = int(imu.t_ns[-1] - imu.t_ns[0]) // step
    else:
        count = int(np.floor(imu.duration / window_s))
        while count > 0 and imu.t[0] + count * window_s > imu.t[-1]:
            count -= 1
    if count < 1:
        raise CliError(f"--window: {window_s} s is longer than the recording ({imu.duration:.6g} s)")
    if imu.t_ns is not None:
        return np.asarray(imu.t_ns[0] + np.arange(count + 1, dtype=np.int64) * step, dtype=np.int64)
    return np.asarray(imu.t[0] + np.arange(count + 1) * window_s)


def windows(imu: ImuData, edges: NDArray[Any], noise: ImuNoise, scheme: str) -> list[PreintegratedImu]:
    """:func:`imukit.preintegrate_windows` in calls of ``WINDOWS_PER_CALL`` windows, with a progress bar."""
    result: list[PreintegratedImu] = []
    with progress("preintegrating", len(edges) - 1) as advance:
        for a, b in chunks(len(edges) - 1, WINDOWS_PER_CALL):
            result += preintegrate_windows(imu, edges[a : b + 1], noise=noise, scheme=scheme)
            advance(b - a)
    return result


def arrays(imu: ImuData, edges: NDArray[Any], pims: list[PreintegratedImu]) -> dict[str, NDArray[Any]]:
    """The windows as named arrays (what the ``.npz`` holds); ``t_start_ns``, ``t_end_ns`` (int64,
    exact) when the stamps are ns."""
    seconds = edges / 1e9 if imu.t_ns is not None else edges
    exact = {} if imu.t_ns is None else {"t_start_ns": edges[:-1], "t_end_ns": edges[1:]}
    return {
        **exact,
        "t_start": np.asarray(seconds[:-1], dtype=np.float64),
        "t_end": np.asarray(seconds[1:], dtype=np.float64),
        "delta_t": np.array([p.delta_t for p in pims]),
        "dR_xyzw": np.array([p.delta_rotation.as_quat() for p in pims]),
        "dv": np.array([p.delta_velocity for p in pims]),
        "dp": np.array([p.delta_position for p in pims]),
        "covariance": np.array([p.covariance for p in pims]),
        "bias_jacobian": np.array([p.bias_jacobian for p in pims]),
    }


def run(args: argparse.Namespace) -> int:
    target = None if args.out is None else output_path(args.out, (".csv", ".npz"), "--out")
    imu, _ = read_imu(args)
    noise = noise_for(args.path, args.noise)
    edges = boundaries(imu, args.window)
    table = arrays(imu, edges, windows(imu, edges, noise, args.scheme))
    dp = np.linalg.norm(table["dp"], axis=1)
    largest = int(np.argmax(dp))
    out.print(
        f"{len(edges) - 1} windows of {args.window} s ({args.scheme}); largest |dp| {dp[largest]:.4g} m "
        f"in window {largest} (|dv| {np.linalg.norm(table['dv'][largest]):.4g} m/s)",
        markup=False,
    )
    if target is not None:
        if target.suffix.lower() == ".npz":
            named: dict[str, Any] = table
            np.savez_compressed(target, **named)
        else:
            _write_csv(target, table)
        wrote("windows", target)
    return 0


def _write_csv(target: Any, table: dict[str, NDArray[Any]]) -> None:
    """One row per window: :data:`COLUMNS` as %.17g, then ``t_start_ns``, ``t_end_ns`` as integers
    when the table has them (an int64 stamp does not survive a float column)."""
    diag = np.diagonal(table["covariance"], axis1=1, axis2=2)
    rows = np.column_stack([table[k] for k in ("t_start", "t_end", "delta_t", "dR_xyzw", "dv", "dp")] + [diag])
    exact = "t_start_ns" in table
    header = ",".join(COLUMNS + (EXACT_COLUMNS if exact else ()))
    with open(target, "w", encoding="utf-8") as f:
        f.write(f"# {header}\n")
        for k, row in enumerate(rows):
            line = ",".join(f"{v:.17g}" for v in row)
            if exact:
                line += f",{int(table['t_start_ns'][k])},{int(table['t_end_ns'][k])}"
            f.write(line + "\n")
