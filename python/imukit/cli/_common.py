"""What every command shares: the consoles, progress bars, one-line errors, input and output files."""

from __future__ import annotations

import argparse
import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any, Callable, Protocol

import numpy as np
from numpy.typing import NDArray
from rich.console import Console
from rich.progress import BarColumn, Progress, TaskProgressColumn, TextColumn, TimeElapsedColumn

from imukit import io
from imukit._errors import FileFormatError, ImukitError, ParameterError
from imukit.imu import ImuData
from imukit.io import ReadReport
from imukit.io._table import DELIMITER_NAMES
from imukit.state import Trajectory

# Results go to stdout, progress and notes to stderr, so `imukit ... > file` keeps only results.
out = Console(highlight=False, soft_wrap=True)
if not out.is_terminal:
    out = Console(highlight=False, soft_wrap=True, width=140)  # a pipe or a file: no 80-column wrapping
err = Console(stderr=True, highlight=False, soft_wrap=True)


class CliError(ImukitError):
    """Bad use of a command (a missing input, a refused option): printed as one line, exit code 1."""


def note(text: str) -> None:
    """A remark about what the command did (samples skipped, the initial state chosen), on stderr."""
    err.print(f"imukit: {text}", markup=False)


@contextmanager
def progress(description: str, total: int) -> Iterator[Callable[[int], None]]:
    """A progress bar on stderr over ``total`` units; yields ``advance(n)``. Shown only on a terminal."""
    bar = Progress(
        TextColumn("{task.description}"),
        BarColumn(),
        TaskProgressColumn(),
        TimeElapsedColumn(),
        console=err,
        transient=True,
        disable=not err.is_terminal,
    )
    with bar:
        task = bar.add_task(description, total=total)
        yield lambda n: bar.advance(task, n)


def chunks(n: int, size: int) -> Iterator[tuple[int, int]]:
    """``(start, stop)`` index pairs covering ``range(n)`` in pieces of ``size``."""
    for start in range(0, n, size):
        yield start, min(start + size, n)


def _report_skips(report: ReadReport) -> None:
    if report:
        err.print(f"imukit: {report}", markup=False)


# Library argument names and the options that set them: a ParameterError from the library names its
# argument (exc.argument == "delta"), the user typed the option: main() prints `--delta: <message>`.
OPTION_OF = {
    "imu_topic": "--imu-topic",
    "groundtruth_topic": "--groundtruth-topic",
    "time_source": "--time-source",
    "time_column": "--csv-time-column",
    "gyro_columns": "--csv-gyro-columns",
    "accel_columns": "--csv-accel-columns",
    "mag_columns": "--csv-mag-columns",
    "time_unit": "--csv-time-unit",
    "gyro_unit": "--gyro-unit",
    "accel_unit": "--accel-unit",
    "delimiter": "--csv-delimiter",
    "estimate": "EST",
    "reference": "GT",
    "delta": "--delta",
    "unit": "--delta-unit",
    "max_dt": "--max-dt",
    "offset": "--offset",
    "max_offset": "--max-offset",
    "align": "--align",
    "window": "--window",
    "max_gap": "--max-gap",
}
BAG_OPTIONS = ("imu_topic", "groundtruth_topic", "time_source")
CSV_OPTIONS = (
    "time_column",
    "gyro_columns",
    "accel_columns",
    "mag_columns",
    "time_unit",
    "gyro_unit",
    "accel_unit",
    "delimiter",
)
OTHER_LAYOUTS = "other layouts: the --csv-* options"
DELIMITERS = DELIMITER_NAMES  # --csv-delimiter's names of read_imu_csv's delimiters


def error_line(exc: Exception) -> str:
    """The one line ``main`` prints for ``exc``: a library ParameterError names the option (``OPTION_OF``)
    that set its argument, white space is collapsed, an OSError names its file."""
    message = str(exc)
    if isinstance(exc, ParameterError) and exc.argument in OPTION_OF:
        message = f"{OPTION_OF[exc.argument]}: {exc.message}"
    message = " ".join(message.split()) or type(exc).__name__
    if isinstance(exc, OSError) and exc.filename is not None and str(exc.filename) not in message:
        message = f"{exc.filename}: {message}"
    return message


def add_input_options(parser: argparse.ArgumentParser) -> None:
    """The options of a command that reads IMU samples from PATH: ``--max-gap``, the generic CSV
    columns and units (:func:`imukit.io.read_imu_csv`), and the ROS bag topics."""
    parser.add_argument(
        "--max-gap",
        type=positive,
        metavar="S",
        help=f"refuse input with a step between samples longer than S seconds (default: accept any gap, "
        f"naming on stderr the longest one when it exceeds {io.GAP_FACTOR:g} x the median step)",
    )
    parser.add_argument_group("PATH", f"found by its format: {io.listing('imu', others=OTHER_LAYOUTS)}")
    csv = parser.add_argument_group(
        "any CSV (PATH a delimited text file of another layout: imukit.io.read_imu_csv; columns by header name "
        "or 0-based index)"
    )
    csv.add_argument("--csv-time-column", dest="time_column", metavar="COL", help="the time column")
    csv.add_argument(
        "--csv-gyro-columns", dest="gyro_columns", metavar="X,Y,Z", help="the angular-rate columns, comma-separated"
    )
    csv.add_argument(
        "--csv-accel-columns", dest="accel_columns", metavar="X,Y,Z", help="the specific-force columns, comma-separated"
    )
    csv.add_argument(
        "--csv-mag-columns",
        dest="mag_columns",
        metavar="X,Y,Z",
        help="the magnetometer columns, comma-separated (optional; read as they are, uT by convention)",
    )
    csv.add_argument(
        "--csv-time-unit",
        dest="time_unit",
        choices=("s", "ms", "us", "ns"),
        help="unit of the time column (default: the unit its header name states, else s)",
    )
    csv.add_argument(
        "--gyro-unit",
        dest="gyro_unit",
        choices=("rad/s", "deg/s"),
        help="unit of the gyro columns (default: the unit their header names state, else rad/s)",
    )
    csv.add_argument(
        "--accel-unit",
        dest="accel_unit",
        choices=("m/s^2", "g", "mg"),
        help="unit of the accelerometer columns (default: the unit their header names state, else m/s^2)",
    )
    csv.add_argument(
        "--csv-delimiter",
        dest="delimiter",
        choices=tuple(DELIMITERS),
        help="(default: detected from the first line)",
    )
    bag = parser.add_argument_group("ROS bags (PATH a .bag, .mcap or .db3 file, or a ROS 2 bag folder)")
    bag.add_argument(
        "--imu-topic",
        metavar="TOPIC",
        help="the sensor_msgs/Imu topic (default: the bag's only one; several: an error)",
    )
    bag.add_argument(
        "--groundtruth-topic",
        metavar="TOPIC",
        help="the PoseStamped / TransformStamped / Odometry ground truth (default: the bag's only one, else none)",
    )
    bag.add_argument(
        "--time-source",
        choices=("header", "record"),
        help="stamps from each message's header.stamp (the default) or the time the recorder received it",
    )
    add_groundtruth_options(parser, file_option=True)


def _column(text: str) -> int | str:
    """A column given on the command line: a 0-based index when all digits, else a header name."""
    text = text.strip()
    return int(text) if text.isdigit() else text


def _columns(text: str, option: str, axes: str = "x, y, z") -> list[int | str]:
    columns = [_column(c) for c in text.split(",")]
    if len(columns) != len(axes.split(", ")):
        raise CliError(
            f"expected {len(axes.split(', '))} comma-separated columns ({axes}), got {text!r}", argument=option
        )
    return columns


def _csv_arguments(args: argparse.Namespace) -> dict[str, Any] | None:
    """read_imu_csv's arguments from the --csv-* options, or None when none was given."""
    given = {name: getattr(args, name) for name in CSV_OPTIONS if getattr(args, name) is not None}
    if not given:
        return None
    for name in ("time_column", "gyro_columns", "accel_columns"):
        if name not in given:
            raise CliError(f"needed with {', '.join(OPTION_OF[n] for n in given)}", argument=OPTION_OF[name])
    given["time_column"] = _column(given["time_column"])
    given["gyro_columns"] = _columns(given["gyro_columns"], "--csv-gyro-columns")
    given["accel_columns"] = _columns(given["accel_columns"], "--csv-accel-columns")
    if "mag_columns" in given:
        given["mag_columns"] = _columns(given["mag_columns"], "--csv-mag-columns")
    if "delimiter" in given:
        given["delimiter"] = DELIMITERS[given["delimiter"]]
    return given


def check_gaps(imu: ImuData, max_gap: float | None) -> None:
    """With ``max_gap`` [s], a CliError naming the first step longer than it; without, a note naming
    the longest step when it is over ``io.GAP_FACTOR`` times the median (:func:`imukit.io.find_gaps`;
    integrating across it is the user's call, but not a silent one)."""
    gaps = io.find_gaps(imu, longer_than=max_gap)
    if gaps and max_gap is not None:
        raise CliError(f"{gaps[0]}, longer than --max-gap = {max_gap:g} s", argument="--max-gap")
    if gaps:
        gap = max(gaps, key=lambda g: g.step)
        note(
            f"{gap}, {gap.step / gap.median:.3g} x the median {gap.median:.6g} s; integrated across "
            "(--max-gap S refuses it)"
        )


def read_imu(args: argparse.Namespace) -> tuple[ImuData, Trajectory | None]:
    """The IMU samples and ground truth at ``args.path`` (:func:`imukit.io.read_imu`, with the options of
    :func:`add_input_options`); with ``args.skip_bad_lines``, bad lines are skipped and
    listed on stderr instead of ending the command. Gaps are checked by :func:`check_gaps`."""
    report = ReadReport()
    bag = {name: getattr(args, name) for name in BAG_OPTIONS}
    with err.status(f"reading {args.path}"):
        try:
            result = io.read_imu(
                args.path,
                csv=_csv_arguments(args),
                **bag,
                on_bad_line="skip" if args.skip_bad_lines else "raise",
                report=report,
            )
        except FileFormatError as exc:  # the formats tried, with the CLI's options for other layouts
            message = exc.message.replace(io.listing("imu"), io.listing("imu", others=OTHER_LAYOUTS))
            raise FileFormatError(message, argument=exc.argument) from exc
    _report_skips(report)
    check_gaps(result[0], args.max_gap)
    return result[0], groundtruth_for(args, result[1])


def refuse_reader_options(args: argparse.Namespace, what: str) -> None:
    """A CliError naming the first bag or CSV option given, for an input read otherwise (``what`` says
    what it is)."""
    if getattr(args, "groundtruth", None) is not None:
        raise CliError(f"{args.path} is {what}, with a reference of its own", argument="--groundtruth")
    for names, kind in ((BAG_OPTIONS, "ROS bags"), (CSV_OPTIONS, "a generic CSV")):
        for name in names:
            value = getattr(args, name)
            if value is not None:
                raise CliError(f"{value!r} is for {kind}, but {args.path} is {what}", argument=OPTION_OF[name])


def read_trajectory(path: str, *, skip_bad_lines: bool, csv: dict[str, Any] | None = None) -> Trajectory:
    """A trajectory file (TUM, EuRoC ground truth, TUM-VI mocap, a CSV naming its pose columns):
    :func:`imukit.io.read_trajectory`, or with ``csv`` (:func:`groundtruth_csv`'s keywords)
    :func:`imukit.io.read_trajectory_csv`; ``skip_bad_lines`` as for :func:`read_imu`."""
    report = ReadReport()
    mode: Any = "skip" if skip_bad_lines else "raise"
    with err.status(f"reading {path}"):
        if csv is None:
            result = io.read_trajectory(path, on_bad_line=mode, report=report)
        else:
            try:
                result = io.read_trajectory_csv(path, **csv, on_bad_line=mode, report=report)
            except ParameterError as exc:  # its argument as the --gt-* option that set it
                raise CliError(exc.message, argument=GT_OPTION_OF.get(exc.argument or "", exc.argument)) from exc
    _report_skips(report)
    return result


# The arguments of the commands that name files or folders they read (every one --out must spare).
INPUT_ARGUMENTS = ("path", "noise", "trajectory", "estimate", "groundtruth")
# The files the readers read inside an input folder (EuRoC, TUM-VI, ROS 2 bag folders).
_READ_IN_FOLDERS = ("data.csv", "sensor.yaml", "metadata.yaml", "*.db3", "*.mcap")


def output_path(path: str, suffixes: tuple[str, ...], option: str, args: argparse.Namespace) -> Path:
    """``path`` as a file to write: its suffix one of ``suffixes``, its folder existing, and not an input.

    An input is any of ``args``' :data:`INPUT_ARGUMENTS` that is given: ``path`` must not resolve to it
    (``os.path.samefile``, so another relative spelling, a symlink or a hard link of it is refused too)
    nor, for an input folder (a dataset), to a file inside it that the readers read (``data.csv``,
    ``sensor.yaml``, ``metadata.yaml``, ``*.db3``, ``*.mcap``).
    """
    p = Path(path)
    if p.suffix.lower() not in suffixes:
        raise CliError(f"expected a file name ending in {' or '.join(suffixes)}, got {path!r}", argument=option)
    if not p.parent.is_dir():
        raise CliError(f"folder {os.fspath(p.parent)!r} does not exist", argument=option)
    if p.exists():
        target = p.resolve()
        for name in INPUT_ARGUMENTS:
            given = getattr(args, name, None)
            if not isinstance(given, str) or not os.path.exists(given):
                continue
            inside = (
                Path(given).is_dir()
                and Path(given).resolve() in target.parents
                and any(target.match(name) for name in _READ_IN_FOLDERS)
            )
            if inside or os.path.samefile(p, given):
                what = "is a file inside the input folder" if inside else "is the input file"
                raise CliError(f"{path!r} {what} {given!r}: refusing to overwrite what is read", argument=option)
    return p


def positive(text: str) -> float:
    """argparse type: a positive, finite float."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not (np.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}")
    return value


def wrote(what: str, path: str | os.PathLike[str]) -> None:
    """Report a written file on stdout."""
    out.print(f"wrote {what}: {os.fspath(path)}", markup=False)


def add_plot_option(parser: argparse.ArgumentParser, what: str) -> None:
    parser.add_argument(
        "--plot", metavar="PNG", help=f"write {what} to this PNG file (needs matplotlib: pip install 'imukit[plot]')"
    )


def add_max_dt_option(parser: argparse.ArgumentParser) -> None:
    """``--max-dt``: the longest ground-truth step the reference is interpolated across."""
    parser.add_argument(
        "--max-dt",
        type=positive,
        metavar="S",
        help=f"longest ground-truth step to interpolate the reference across [s] (default: "
        f"{io.REFERENCE_GAP_FACTOR:g} x the truth's median step, its own rate); samples in longer gaps or "
        "outside the truth's span are not scored, and counted",
    )


class Paired(Protocol):
    """What :func:`scored` reads: an :class:`imukit.eval.Association`, ``AbsoluteError`` or ``RelativeError``."""

    @property
    def mask(self) -> NDArray[np.bool_]: ...
    @property
    def n_outside_span(self) -> int: ...
    @property
    def n_in_gaps(self) -> int: ...
    @property
    def max_dt(self) -> float: ...


def scored(what: str, paired: Paired, given: float | None, *, before: int = 0) -> str:
    """One line: how many of ``what`` (e.g. ``"IMU samples"``) were scored against the ground truth, as
    a fraction of all, and why the others were not (outside its span, in its gaps longer than the
    limit: ``--max-dt`` when ``given``, else the one derived from the truth's rate). ``before``: samples
    the command dropped before pairing because the truth starts later (counted outside its span)."""
    total, kept = len(paired.mask) + before, int(np.count_nonzero(paired.mask))
    line = f"scored {kept} of {total} {what} ({kept / total:.2%})"
    if kept == total:
        return line
    limit = (
        f"--max-dt = {given:g} s"
        if given is not None
        else f"{paired.max_dt:.4g} s ({io.REFERENCE_GAP_FACTOR:g} x its median step; --max-dt sets it)"
    )
    return (
        f"{line}; left out {paired.n_outside_span + before} outside the ground truth's span (before its first or after "
        f"its last stamp), {paired.n_in_gaps} in its gaps longer than {limit}"
    )


# read_trajectory_csv's arguments and the --gt-* options that set them.
GT_OPTION_OF = {
    "time_column": "--gt-time-column",
    "position_columns": "--gt-position-columns",
    "quaternion_columns": "--gt-quaternion-columns",
    "quaternion_order": "--gt-quaternion-order",
    "time_unit": "--gt-time-unit",
    "delimiter": "--gt-delimiter",
}


def add_groundtruth_options(parser: argparse.ArgumentParser, *, file_option: bool) -> None:
    """``--groundtruth FILE`` (with ``file_option``: a ground truth for any input, replacing PATH's
    own) and the ``--gt-*`` columns that read it, or GT, as a CSV (:func:`imukit.io.read_trajectory_csv`)."""
    group = parser.add_argument_group(
        "ground truth from a file" if file_option else "GT as a CSV of another layout",
        "a trajectory file (TUM, EuRoC ground truth, TUM-VI mocap, a CSV naming its pose columns), or any CSV "
        "by --gt-time-column, --gt-position-columns and --gt-quaternion-columns (header names or 0-based indices)",
    )
    if file_option:
        group.add_argument("--groundtruth", metavar="FILE", help="the ground truth (replaces the one PATH has)")
    group.add_argument("--gt-time-column", metavar="COL", help="the time column")
    group.add_argument("--gt-position-columns", metavar="X,Y,Z", help="the position columns [m]")
    group.add_argument("--gt-quaternion-columns", metavar="A,B,C,D", help="the quaternion columns (R_wb)")
    group.add_argument(
        "--gt-quaternion-order", choices=("xyzw", "wxyz"), help="the order of those columns (default: xyzw)"
    )
    group.add_argument("--gt-time-unit", choices=("s", "ms", "us", "ns"), help="(default: s)")
    group.add_argument("--gt-delimiter", choices=tuple(DELIMITERS), help="(default: detected from the first line)")


def groundtruth_csv(args: argparse.Namespace) -> dict[str, Any] | None:
    """read_trajectory_csv's arguments from the --gt-* options, or None when none was given."""
    given = {name: getattr(args, f"gt_{name}") for name in GT_OPTION_OF if getattr(args, f"gt_{name}") is not None}
    if not given:
        return None
    for name in ("time_column", "position_columns", "quaternion_columns"):
        if name not in given:
            raise CliError(f"needed with {', '.join(GT_OPTION_OF[n] for n in given)}", argument=GT_OPTION_OF[name])
    given["time_column"] = _column(given["time_column"])
    for name, count in (("position_columns", 3), ("quaternion_columns", 4)):
        columns = [_column(c) for c in given[name].split(",")]
        if len(columns) != count:
            raise CliError(
                f"expected {count} comma-separated columns, got {given[name]!r}", argument=GT_OPTION_OF[name]
            )
        given[name] = columns
    if "delimiter" in given:
        given["delimiter"] = DELIMITERS[given["delimiter"]]
    return given


def groundtruth_for(args: argparse.Namespace, own: Trajectory | None) -> Trajectory | None:
    """The ground truth of a command reading PATH: ``--groundtruth FILE`` when given (a note when it
    replaces PATH's own), else PATH's; --gt-* options without --groundtruth are a CliError."""
    csv = groundtruth_csv(args)
    if args.groundtruth is None:
        if csv is not None:
            raise CliError("needs --groundtruth FILE", argument=GT_OPTION_OF[next(iter(csv))])
        return own
    if own is not None:
        note(f"using the ground truth of {args.groundtruth}, not the one {args.path} has")
    return read_trajectory(args.groundtruth, skip_bad_lines=args.skip_bad_lines, csv=csv)
