"""``imukit filter``: Mahony, Madgwick or Robust attitude estimation, scored against the reference when there is one."""

from __future__ import annotations

import argparse
from typing import Any, NamedTuple

import numpy as np
from scipy.spatial.transform import Rotation

from imukit import _core
from imukit._arrays import FloatArray
from imukit.cli._attitude_input import AttitudeInput, read_attitude_input
from imukit.cli._common import (
    CliError,
    add_input_options,
    add_max_dt_option,
    add_plot_option,
    chunks,
    out,
    output_path,
    progress,
    scored,
    wrote,
)
from imukit.eval import AttitudeError, attitude_error
from imukit.filters import WORLDS, FilterState, Madgwick, Mahony, Robust, RobustState, in_world
from imukit.io import write_tum
from imukit.state import Trajectory

METHODS: dict[str, type[Mahony | Madgwick | Robust]] = {"mahony": Mahony, "madgwick": Madgwick, "robust": Robust}
_DEFAULTS = _core.FilterOptions.default()  # the core's Options::default(), as the filters use
CHUNK = 50_000  # samples per native call: a progress step, state carried across (FilterState)


class Estimate(NamedTuple):
    """A filter's attitudes (``R_wb``), gyro biases and its state after the last sample."""

    rotation: Rotation
    gyro_bias: FloatArray
    state: FilterState | RobustState


DESCRIPTION = """\
Estimate the attitude R_wb of each IMU sample with an attitude filter (docs/filters.md): gyro and
accelerometer (6D: heading free, starts at yaw 0), or with --mag also the magnetometer (9D: heading
from magnetic north). --method robust is the most accurate on BROAD (docs/filters_robust.md);
with --offline it smooths the whole record (forward and backward passes fused: post-processing).

Reads: PATH in any format imukit detects, or a BROAD trial (.mat, or a .npz with its keys). A
magnetometer comes from BROAD trials, CSV files (--csv-mag-columns), EuRoC folders written with one
(mag0/data.csv) and ROS bags with a sensor_msgs/MagneticField topic; --mag on an input without one
is refused.
Frames and units: gyro rad/s, accelerometer m/s^2 in the body frame; world ENU (x east, y north,
z up; --world NED for x north, z down). Default gains are the BROAD-tuned ones.

Prints: with reference attitudes (ground truth, BROAD's motion capture), the RMSE of the total,
heading and inclination error in degrees (BROAD's split; 6D after removing the constant heading
offset; BROAD trials over their movement phase). A ground-truth trajectory gives the reference at
each IMU stamp by slerp, never across its steps over --max-dt (mocap dropouts; default 2.5 x the
truth's median step): the samples scored are printed as a fraction of all, the others counted
(outside the truth's span, in its gaps).
Writes: --out, .txt/.tum: a TUM file with zero positions and the attitude quaternions;
.csv: `t [s], qx, qy, qz, qw, bias_x, bias_y, bias_z [rad/s]` with a header line.
--plot: the attitude errors over time, or without reference attitudes the roll, pitch and yaw.

Example:
  imukit filter 06_undisturbed_fast_rotation_A.mat --method madgwick --mag --plot error.png
  imukit filter 06_undisturbed_fast_rotation_A.mat --method robust --offline --mag"""


def add(commands: Any) -> argparse.ArgumentParser:
    p: argparse.ArgumentParser = commands.add_parser(
        "filter",
        help="run the Mahony, Madgwick or Robust attitude filter (errors, quaternion file, error plot)",
        description=DESCRIPTION,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("path", metavar="PATH", help="the recording (EuRoC folder, bag, BROAD .mat, ...)")
    p.add_argument(
        "--method",
        choices=sorted(METHODS),
        default="robust",
        help="the filter (default: %(default)s, the most accurate on BROAD)",
    )
    p.add_argument("--offline", action="store_true", help="--method robust only: smooth the whole record (acausal)")
    p.add_argument("--mag", action="store_true", help="use the magnetometer (9D); the input must have one")
    p.add_argument("--world", choices=WORLDS, default=_DEFAULTS.world, help="world frame (default: %(default)s)")
    add_max_dt_option(p)
    p.add_argument("--out", metavar="FILE", help="write the attitudes: TUM (.txt, .tum) or quaternion CSV (.csv)")
    add_plot_option(p, "the attitude error over time (without a reference: the attitude)")
    add_input_options(p)
    p.set_defaults(run=run)
    return p


def run_chunked(
    filt: Mahony | Madgwick | Robust, data: AttitudeInput, *, use_mag: bool, chunk: int = CHUNK, offline: bool = False
) -> Estimate:
    """``filt.run`` over ``chunk``-sample pieces, each continuing from the previous one's state, with
    a progress bar. Equal to one call but for the first step of each piece, whose dt is taken from
    absolute stamps (rounding: below 1e-12 in the quaternions). ``offline`` (``Robust``'s smoother)
    reads the whole record at once: one piece."""
    imu, n = data.imu, len(data.imu)
    rotations: list[FloatArray] = []
    biases: list[FloatArray] = []
    state: FilterState | RobustState | None = None
    with progress(f"{type(filt).__name__} {'smoother' if offline else 'filter'}", n) as advance:
        for a, b in chunks(n, n if offline else chunk):
            if isinstance(filt, Robust):
                assert not isinstance(state, FilterState)
                piece: Any = filt.run(imu[a:b], mag=use_mag, initial=state, offline=offline)
            else:
                assert not isinstance(state, RobustState)
                piece = filt.run(imu[a:b], mag=use_mag, initial=state)
            state = piece.state
            rotations.append(piece.rotation.as_quat())
            biases.append(piece.gyro_bias)
            advance(b - a)
    assert state is not None  # an ImuData has at least one sample
    return Estimate(Rotation.from_quat(np.concatenate(rotations)), np.concatenate(biases), state)


def run(args: argparse.Namespace) -> int:
    target = None if args.out is None else output_path(args.out, (".txt", ".tum", ".csv"), "--out", args)
    png = None if args.plot is None else output_path(args.plot, (".png",), "--plot", args)
    data = read_attitude_input(args)
    if args.mag and data.mag is None:
        raise CliError(
            f"--mag: {args.path} has no magnetometer samples (BROAD trials, CSV files read with "
            "--csv-mag-columns, EuRoC folders with mag0/ and bags with a MagneticField topic have one); "
            "run without --mag for 6D"
        )
    if args.offline and args.method != "robust":
        raise CliError(f"--offline: only --method robust has a smoother, not {args.method}")
    filt = METHODS[args.method](world=args.world)
    result = run_chunked(filt, data, use_mag=args.mag, offline=args.offline)
    name = f"{type(filt).__name__}{' offline' if args.offline else ''} {'9D' if args.mag else '6D'}"
    out.print(f"{name}: {len(data.imu)} samples over {data.imu.duration:.3f} s", markup=False)
    if target is not None:  # before the plot, which may fail for want of matplotlib
        _write(target, data, result)
        wrote("attitudes", target)
    error = None
    if data.truth_xyzw is not None:
        truth = in_world(data.truth_xyzw, args.world)  # the readers' ground truths are z up
        error = attitude_error(result.rotation, truth, world=args.world, align_heading=not args.mag, mask=data.mask)
        rmse = error.rmse(degrees=True)
        out.print(
            f"attitude error RMSE over {rmse.n_samples} samples: total {rmse.total:.3f} deg, heading "
            f"{rmse.heading:.3f} deg, inclination {rmse.inclination:.3f} deg"
            + ("" if args.mag else " (constant heading offset removed: 6D)"),
            markup=False,
        )
        if data.paired is not None:
            out.print(scored("IMU samples", data.paired, args.max_dt), markup=False)
    if png is not None:
        _plot(png, data, name, result, error, args.path)
    return 0


def _plot(png: Any, data: AttitudeInput, name: str, result: Estimate, error: AttitudeError | None, path: str) -> None:
    """The attitude errors when there is a reference (``error``), else the attitudes themselves."""
    from imukit.plot import attitude_error_plot, attitude_plot

    t = data.imu.t - data.imu.t[0]
    if error is not None:
        attitude_error_plot(png, t, {name: error}, title=f"{name}: {path}")
        wrote("attitude error plot", png)
    else:
        attitude_plot(png, t, {name: result.rotation}, title=f"{name}: {path} (no reference)")
        wrote("attitude plot", png)


def _write(target: Any, data: AttitudeInput, result: Estimate) -> None:
    imu = data.imu
    if target.suffix.lower() == ".csv":
        rows = np.column_stack([imu.t, result.rotation.as_quat(), result.gyro_bias])
        np.savetxt(target, rows, fmt="%.17g", delimiter=",", header="t [s],qx,qy,qz,qw,bias_x,bias_y,bias_z [rad/s]")
        return
    zeros = np.zeros((len(imu), 3))
    t = None if imu.t_ns is not None else imu.t
    write_tum(Trajectory(t, zeros, None, result.rotation, t_ns=imu.t_ns), target)
