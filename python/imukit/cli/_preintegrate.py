"""``imukit preintegrate``: IMU preintegration over fixed-length windows, to CSV or NPZ."""

from __future__ import annotations

import argparse
import warnings
from typing import Any

import numpy as np
from numpy.typing import NDArray

from imukit._errors import ParameterError
from imukit.cli import _calibrate
from imukit.cli._common import (
    CliError,
    add_input_options,
    add_max_dt_option,
    chunks,
    note,
    out,
    output_path,
    positive,
    progress,
    read_imu,
    wrote,
)
from imukit.cli._initial import trim_to_truth
from imukit.cli._truth import truth_at
from imukit.imu import ImuBias, ImuData, ImuNoise
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
from imukit.state import Trajectory

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
Bias: the deltas are of the readings minus a bias, zero unless --gyro-bias / --accel-bias give a
constant one, or --bias-from-groundtruth takes each window's from the ground truth's biases at its
start (EuRoC's has them; interpolated, not across truth gaps over --max-dt; IMU samples before the
truth starts are skipped); the npz then holds them (bias_gyro, bias_accel).
Prints the number of windows and the largest window's deltas.
--calibrate YAML (PATH with ground truth with biases, e.g. an EuRoC folder): the windows whose ends
have ground truth are preintegrated at the truth's bias and compared with it; the factors on the
gyro and accelerometer densities that make the whitened residuals consistent (chi2 mean 9; per
block theta, v, p too) are printed with the chi2 before and after, and the inflated densities are
written to YAML as a Kalibr imu.yaml (docs/noise.md, "Calibration from residuals").

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
    p.add_argument("--gyro-bias", metavar="X,Y,Z", type=_vector, help="a constant gyro bias [rad/s] (default: 0)")
    p.add_argument("--accel-bias", metavar="X,Y,Z", type=_vector, help="a constant accel bias [m/s^2] (default: 0)")
    p.add_argument(
        "--bias-from-groundtruth",
        action="store_true",
        help="each window at the ground truth's biases at its start (PATH's or --groundtruth's)",
    )
    p.add_argument(
        "--calibrate",
        metavar="YAML",
        help="fit the density inflation that makes the residuals against the ground truth consistent; "
        "write the inflated densities to this Kalibr imu.yaml",
    )
    add_max_dt_option(p)
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


def _vector(text: str) -> NDArray[np.float64]:
    """argparse type: three comma-separated finite numbers."""
    try:
        values = np.array([float(v) for v in text.split(",")])
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected 3 comma-separated numbers, got {text!r}") from None
    if values.shape != (3,) or not np.isfinite(values).all():
        raise argparse.ArgumentTypeError(f"expected 3 comma-separated finite numbers, got {text!r}")
    return values


def window_biases(
    args: argparse.Namespace, truth: Trajectory | None, edges: NDArray[Any]
) -> tuple[NDArray[np.float64], NDArray[np.float64]] | None:
    """The (M, 3) gyro and accel biases of the M windows: --gyro-bias / --accel-bias held constant,
    or with --bias-from-groundtruth the truth's at each window start (all starts must have it); None
    for no bias at all."""
    m = len(edges) - 1
    if args.bias_from_groundtruth:
        if args.gyro_bias is not None or args.accel_bias is not None:
            raise CliError("give --bias-from-groundtruth or --gyro-bias / --accel-bias, not both")
        if truth is None:
            raise CliError("--bias-from-groundtruth: PATH has no ground truth (--groundtruth FILE gives one)")
        paired = truth_at(truth, edges[:-1], max_dt=args.max_dt, option="--max-dt")
        gyro, accel = paired.reference.gyro_bias, paired.reference.accel_bias
        if gyro is None or accel is None:
            raise CliError("--bias-from-groundtruth: the ground truth has no biases")
        if not paired.mask.all():
            raise CliError(
                f"{m - int(paired.mask.sum())} of {m} window starts have no ground truth ({paired.n_outside_span} "
                f"after its span, {paired.n_in_gaps} in its gaps longer than {paired.max_dt:.4g} s)",
                argument="--max-dt",
            )
        return gyro, accel
    if args.gyro_bias is None and args.accel_bias is None:
        return None
    zero = np.zeros(3)
    gyro = args.gyro_bias if args.gyro_bias is not None else zero
    accel = args.accel_bias if args.accel_bias is not None else zero
    return np.tile(gyro, (m, 1)), np.tile(accel, (m, 1))


def windows(
    imu: ImuData,
    edges: NDArray[Any],
    noise: ImuNoise,
    scheme: str,
    biases: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None,
) -> Preintegration:
    """:func:`imukit.preintegrate_windows` in calls of ``WINDOWS_PER_CALL`` windows, with a progress bar;
    with ``biases`` (M, 3) each, every window at its own bias (one call per run of equal biases)."""
    params = PreintParams(noise, scheme=scheme)
    runs = [(0, len(edges) - 1, params)]
    if biases is not None:
        gyro, accel = biases
        change = np.flatnonzero(np.any(np.diff(np.hstack([gyro, accel]), axis=0) != 0, axis=1)) + 1
        starts = [0, *change.tolist(), len(edges) - 1]
        runs = [(a, b, params.replace(bias=ImuBias(gyro[a], accel[a]))) for a, b in zip(starts[:-1], starts[1:])]
    pieces: list[Preintegration] = []
    with progress("preintegrating", len(edges) - 1) as advance:
        for first, last, run_params in runs:
            for a, b in chunks(last - first, WINDOWS_PER_CALL):
                pieces.append(preintegrate_windows(imu, edges[first + a : first + b + 1], run_params))
                advance(b - a)
    return concatenate(pieces)


def run(args: argparse.Namespace) -> int:
    target = None if args.out is None else output_path(args.out, (".csv", ".npz"), "--out", args)
    calibrated = None if args.calibrate is None else output_path(args.calibrate, (".yaml", ".yml"), "--calibrate", args)
    imu, truth = read_imu(args)
    if args.bias_from_groundtruth and truth is not None:
        imu = trim_to_truth(imu, truth)
    noise = noise_for(args.path, args.noise)
    edges = boundaries(imu, args.window)
    if calibrated is not None:
        calibration = _calibrate.calibrate(imu, truth, edges, noise, args.scheme, args.max_dt)
        _calibrate.write(calibrated, calibration, imu, args.window, args.scheme)
    biases = window_biases(args, truth, edges)
    table = window_arrays(windows(imu, edges, noise, args.scheme, biases))
    if biases is not None:
        table["bias_gyro"], table["bias_accel"] = biases
        note(_bias_note(biases, args.bias_from_groundtruth))
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


def _bias_note(biases: tuple[NDArray[np.float64], NDArray[np.float64]], from_truth: bool) -> str:
    gyro, accel = biases
    where = "the ground truth's at each window start, first" if from_truth else "constant"
    return (
        f"bias ({where}): gyro [{', '.join(f'{v:.6g}' for v in gyro[0])}] rad/s, "
        f"accel [{', '.join(f'{v:.6g}' for v in accel[0])}] m/s^2"
    )


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
