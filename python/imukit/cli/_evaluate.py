"""``imukit evaluate``: absolute (and relative) trajectory error of an estimate against ground truth."""

from __future__ import annotations

import argparse
import inspect
import math
from typing import Any

from rich.table import Table

from imukit._errors import ParameterError
from imukit.cli._common import (
    CliError,
    add_groundtruth_options,
    add_max_dt_option,
    add_plot_option,
    groundtruth_csv,
    out,
    output_path,
    positive,
    read_trajectory,
    scored,
    wrote,
)
from imukit.eval import ErrorStats, ape, rpe, time_offset

ALIGNMENTS = ("se3", "sim3", "yaw", "position", "none")
# --offset auto's window without --max-offset: the library's default, read from it (one place).
MAX_OFFSET_S = inspect.signature(time_offset).parameters["max_offset"].default

DESCRIPTION = """\
Score the trajectory EST against the ground truth GT: the absolute trajectory error (ATE / evo's
APE) after an alignment, and with --delta the relative pose error (RPE) over pairs --delta apart,
after the same alignment (sim3's scale matters to the RPE; the others leave it unchanged).
Definitions and the comparison with evo: docs/evaluation.md.

Reads: EST and GT as trajectory files, format detected: TUM (`t x y z qx qy qz qw`), an EuRoC
ground-truth CSV, a TUM-VI mocap CSV, a CSV whose header names its pose columns
(`transform.translation.x` ... `transform.rotation.w`); GT of any other layout by its columns
(--gt-time-column, --gt-position-columns, --gt-quaternion-columns). Each EST pose is paired with
GT interpolated at its stamp (position linear, rotation slerp; not across GT steps over --max-dt s,
by default 2.5 x GT's median step); the poses scored are printed as a fraction of all, the others
counted: outside GT's span apart from in its gaps.
Alignment (--align): se3 (rotation + translation, Umeyama; the default), sim3 (+ scale: monocular
VO), yaw (rotation about z + translation: the 4 unobservable DoF of VIO), position (translation
only), none.
Units: translation errors in m, rotation errors in degrees.
Prints a table of RMSE, mean, median, std, min and max. Writes --plot: a top view of the aligned
estimate and the ground truth.

Example:
  imukit evaluate traj.txt MH_01_easy/mav0/state_groundtruth_estimate0/data.csv --align se3 --delta 1"""


def add(commands: Any) -> argparse.ArgumentParser:
    p: argparse.ArgumentParser = commands.add_parser(
        "evaluate",
        help="absolute / relative trajectory error of an estimate against ground truth",
        description=DESCRIPTION,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("estimate", metavar="EST", help="the estimated trajectory (TUM, EuRoC ground-truth CSV, ...)")
    p.add_argument("groundtruth", metavar="GT", help="the ground truth, same formats")
    p.add_argument("--align", choices=ALIGNMENTS, default="se3", help="alignment before the ATE (default: %(default)s)")
    p.add_argument("--delta", type=positive, metavar="D", help="also the RPE over pairs D apart (see --delta-unit)")
    p.add_argument("--delta-unit", choices=("m", "s", "frames"), default="m", help="unit of --delta (default: m)")
    add_max_dt_option(p)
    p.add_argument(
        "--offset",
        type=_offset,
        default=0.0,
        metavar="S",
        help="clock offset [s] added to EST's stamps before pairing (EST time t is GT time t + S; default 0), "
        "or 'auto': estimated from the two trajectories' angular speeds (imukit.eval.time_offset, within "
        "--max-offset) and printed",
    )
    p.add_argument(
        "--max-offset",
        type=positive,
        default=None,
        metavar="S",
        help=f"largest clock offset [s] --offset auto searches, either sign (default: {MAX_OFFSET_S})",
    )
    add_plot_option(p, "a top view of the aligned estimate and the ground truth")
    add_groundtruth_options(p, file_option=False)
    p.set_defaults(run=run)
    return p


def _offset(text: str) -> float | str:
    """A number of seconds, or ``auto``."""
    if text == "auto":
        return text
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number of seconds or 'auto', got {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"expected a finite number of seconds or 'auto', got {text!r}")
    return value


def _row(table: Table, name: str, stats: ErrorStats, unit: str, scale: float) -> None:
    values = (stats.rmse, stats.mean, stats.median, stats.std, stats.min, stats.max)
    table.add_row(name, unit, *(f"{v * scale:.4g}" for v in values), str(stats.n))


def run(args: argparse.Namespace) -> int:
    png = None if args.plot is None else output_path(args.plot, (".png",), "--plot", args)
    estimate = read_trajectory(args.estimate, skip_bad_lines=args.skip_bad_lines)
    truth = read_trajectory(args.groundtruth, skip_bad_lines=args.skip_bad_lines, csv=groundtruth_csv(args))
    if args.max_offset is not None and args.offset != "auto":
        raise CliError("only with --offset auto (a given offset is not searched)", argument="--max-offset")
    if args.offset == "auto":
        try:
            found = time_offset(
                estimate, truth, max_offset=MAX_OFFSET_S if args.max_offset is None else args.max_offset
            )
        except ParameterError as exc:  # its first argument is EST here
            argument = "estimate" if exc.argument == "imu" else exc.argument
            raise ParameterError(exc.message, argument=argument) from exc
        args.offset = found.offset
        out.print(
            f"clock offset from the angular speeds: {found.offset:+.6g} s (EST time t is GT time t + offset; "
            f"correlation {found.correlation:.4f} over {found.n_samples} samples)",
            markup=False,
        )
    absolute = ape(estimate, truth, align=args.align, max_dt=args.max_dt, offset=args.offset)
    table = Table(title=f"{args.estimate} against {args.groundtruth} (alignment: {args.align})")
    for column in ("error", "unit", "RMSE", "mean", "median", "std", "min", "max", "samples"):
        table.add_column(column, justify="left" if column in ("error", "unit") else "right")
    _row(table, "ATE translation", absolute.translation_stats, "m", 1.0)
    _row(table, "ATE rotation", absolute.rotation_stats, "deg", math.degrees(1.0))
    if args.delta is not None:
        relative = rpe(
            estimate,
            truth,
            delta=args.delta,
            unit=args.delta_unit,
            align=args.align,
            max_dt=args.max_dt,
            offset=args.offset,
        )
        span = f"{args.delta:g} {args.delta_unit}"
        _row(table, f"RPE translation / {span}", relative.translation_stats, "m", 1.0)
        _row(table, f"RPE rotation / {span}", relative.rotation_stats, "deg", math.degrees(1.0))
    out.print(table)
    out.print(scored("estimate poses", absolute, args.max_dt), markup=False)
    if absolute.alignment.scale != 1.0:
        out.print(f"sim3 scale: {absolute.alignment.scale:.6g}", markup=False)
    if png is not None:
        from imukit.plot import trajectory_top_view

        trajectory_top_view(
            png,
            {f"{args.estimate} ({args.align}-aligned)": absolute.estimate},
            truth=truth,
            title=f"ATE RMSE {absolute.translation_stats.rmse:.4g} m: {args.estimate}",
        )
        wrote("top view", png)
    return 0
