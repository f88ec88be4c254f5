"""``imukit preintegrate``: IMU preintegration over fixed-length windows, to CSV or NPZ."""

from __future__ import annotations

import argparse
import warnings
from typing import Any

import numpy as np
from numpy.typing import NDArray

from imukit._errors import ParameterError
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
from imukit.io import find_noise_model
from imukit.io._noise_model import NoNoiseModelError
from imukit.preint import (
    SCHEME_ALIASES,
    SCHEMES,
    Preintegration,
    PreintParams,
    concatenate,
    preintegrate_windows,
    regular_boundaries,
    window_arrays,
)

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
    p.add_argument(
        "--scheme",
        choices=(*SCHEMES, *SCHEME_ALIASES),  # the deprecated names keep working (with a warning)
        default=PreintParams.scheme,
        help="(default: %(default)s)",
    )
    p.add_argument("--noise", metavar="YAML", help="Kalibr imu.yaml with the noise densities")
    p.add_argument("--out", metavar="FILE", help="write the windows to this .csv or .npz file")
    add_input_options(p)
    p.set_defaults(run=run)
    return p


def noise_for(path: str, noise_yaml: str | None) -> ImuNoise:
    """:func:`imukit.io.find_noise_model`, its ``T_BS`` warning as a note, its absence as --noise."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            noise = find_noise_model(path, noise_yaml)
        except NoNoiseModelError as e:
            raise CliError(f"--noise: {e.message}") from None
    for w in caught:
        note(str(w.message))
    return noise


def boundaries(imu: ImuData, window_s: float) -> NDArray[Any]:
    """:func:`imukit.preint.regular_boundaries`, a window longer than the recording as --window."""
    try:
        return regular_boundaries(imu, window_s)
    except ParameterError as e:
        raise CliError(f"--window: {e.message}") from None


def windows(imu: ImuData, edges: NDArray[Any], noise: ImuNoise, scheme: str) -> Preintegration:
    """:func:`imukit.preintegrate_windows` in calls of ``WINDOWS_PER_CALL`` windows, with a progress bar."""
    params = PreintParams(noise, scheme=scheme)
    pieces: list[Preintegration] = []
    with progress("preintegrating", len(edges) - 1) as advance:
        for a, b in chunks(len(edges) - 1, WINDOWS_PER_CALL):
            pieces.append(preintegrate_windows(imu, edges[a : b + 1], params))
            advance(b - a)
    return concatenate(pieces)


def run(args: argparse.Namespace) -> int:
    target = None if args.out is None else output_path(args.out, (".csv", ".npz"), "--out")
    imu, _ = read_imu(args)
    noise = noise_for(args.path, args.noise)
    edges = boundaries(imu, args.window)
    table = window_arrays(windows(imu, edges, noise, args.scheme))
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
