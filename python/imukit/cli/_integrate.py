"""``imukit integrate``: dead reckoning of a recording into a trajectory."""

from __future__ import annotations

import argparse
from typing import Any

import numpy as np

from imukit import _core
from imukit.cli._common import (
    CliError,
    add_input_options,
    add_max_dt_option,
    add_plot_option,
    err,
    note,
    out,
    output_path,
    positive,
    read_imu,
    scored,
    wrote,
)
from imukit.cli._initial import (
    STATIC_ACCEL_RMS,
    STATIC_GYRO_STD,
    STATIC_MEAN_RATE,
    from_truth,
    levelled_at_rest,
    trim_to_truth,
)
from imukit.io import write_tum
from imukit.strapdown import SCHEME_ALIASES, SCHEMES, integrate

DESCRIPTION = f"""\
Integrate the IMU samples of PATH into positions, velocities and attitudes (strapdown dead
reckoning: no correction, so the error grows with time; see docs/strapdown.md).

Reads: PATH in any format imukit detects (an EuRoC folder, a ROS bag, ...; `imukit --help`).
Frames and units: body = the IMU frame; world z up, gravity (0, 0, -9.81) m/s^2; positions in m.
Schemes: lie_euler (order 1; the old name euler still works), midpoint (order 2, VINS-Mono's),
rk4 (order 4), exp (exact while the samples are held over a step; order 1 on smooth motion).

The initial state:
  - with ground truth in PATH: the truth's position, velocity and attitude interpolated at the
    first IMU sample inside the truth's span (IMU samples before the truth starts are skipped,
    and the count is printed);
  - without: at the origin, at rest, roll and pitch levelled from the mean accelerometer over the
    first --static-seconds (yaw 0), so the recording must start at rest; a note says when that
    window does not look static: a gyro axis's std over {STATIC_GYRO_STD:g} rad/s, the RMS of
    |accel| - 9.81 over {STATIC_ACCEL_RMS:g} m/s^2, or a mean rate over {STATIC_MEAN_RATE:g} rad/s (a gyro
    bias moves the mean, rarely that far).
--bias-from-groundtruth subtracts the truth's gyro and accelerometer biases at that first sample
(EuRoC's ground truth has them) as a constant bias.

Writes: --out, a TUM file (`t x y z qx qy qz qw`, one line per IMU sample); --plot, a top view
(x-y, metres) of the trajectory and the ground truth.
Prints: with ground truth, the final position error and the absolute trajectory error (RMSE over
the samples inside the truth's span, no alignment: the start is the truth's), and the samples scored
as a fraction of all; the others are counted: after the truth ends, or in its gaps longer than
--max-dt (default: 2.5 x the truth's median step, so a gap-free 20 Hz truth scores every sample).

Example:
  imukit integrate MH_01_easy/ --scheme rk4 --bias-from-groundtruth --out traj.txt --plot top.png"""


def add(commands: Any) -> argparse.ArgumentParser:
    p: argparse.ArgumentParser = commands.add_parser(
        "integrate",
        help="dead-reckon a recording into a trajectory (TUM file, top-view plot)",
        description=DESCRIPTION,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("path", metavar="PATH", help="the recording (EuRoC folder, CSV, bag, ...)")
    p.add_argument(
        "--scheme",
        choices=(*SCHEMES, *SCHEME_ALIASES),  # the deprecated names keep working (with a warning)
        default=_core.STRAPDOWN_DEFAULT_SCHEME,
        help="integration scheme (default: %(default)s)",
    )
    p.add_argument(
        "--bias-from-groundtruth", action="store_true", help="subtract the ground truth's biases at the start"
    )
    p.add_argument(
        "--static-seconds",
        type=positive,
        default=2.0,
        metavar="S",
        help="without ground truth: level the start from the first S seconds, at rest (default: %(default)s)",
    )
    p.add_argument("--out", metavar="TUM", help="write the trajectory to this TUM file (.txt or .tum)")
    add_plot_option(p, "a top view of the trajectory and the ground truth")
    add_max_dt_option(p)
    add_input_options(p)
    p.set_defaults(run=run)
    return p


def run(args: argparse.Namespace) -> int:
    tum = None if args.out is None else output_path(args.out, (".txt", ".tum"), "--out", args)
    png = None if args.plot is None else output_path(args.plot, (".png",), "--plot", args)
    imu, truth = read_imu(args)
    bias = None
    if truth is not None:
        n_read = len(imu)
        imu = trim_to_truth(imu, truth)
        initial, truth_bias = from_truth(truth, imu, max_dt=args.max_dt)
        if args.bias_from_groundtruth:
            if truth_bias is None:
                raise CliError("--bias-from-groundtruth: the ground truth in PATH has no biases")
            bias = truth_bias
    elif args.bias_from_groundtruth:
        raise CliError("--bias-from-groundtruth: PATH has no ground truth")
    else:
        initial = levelled_at_rest(imu, args.static_seconds)
        note(f"no ground truth: starting at rest, levelled from the first {args.static_seconds} s")
    with err.status(f"integrating {len(imu)} samples ({args.scheme})"):
        trajectory = integrate(imu, initial=initial, scheme=args.scheme, bias=bias)
    out.print(f"integrated {len(imu)} samples over {imu.duration:.3f} s with {args.scheme}", markup=False)
    if truth is not None:
        _report_errors(trajectory, truth, args.max_dt, before=n_read - len(imu))
    if tum is not None:
        write_tum(trajectory, tum)
        wrote("trajectory (TUM)", tum)
    if png is not None:
        from imukit.plot import trajectory_top_view

        trajectory_top_view(
            png, {f"imukit {args.scheme}": trajectory}, truth=truth, title=f"Dead reckoning: {args.path}"
        )
        wrote("top view", png)
    return 0


def _report_errors(trajectory: Any, truth: Any, max_dt: float | None, *, before: int) -> None:
    from imukit.eval import ape

    error = ape(trajectory, truth, align="none", max_dt=max_dt)
    final = float(np.linalg.norm(error.estimate.position[-1] - error.reference.position[-1]))
    out.print(
        f"final position error {final:.4g} m; ATE RMSE {error.translation_stats.rmse:.4g} m, max "
        f"{error.translation_stats.max:.4g} m over {error.translation_stats.n} samples (no alignment)",
        markup=False,
    )
    out.print(scored("samples", error, max_dt, before=before), markup=False)
