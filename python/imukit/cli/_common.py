"""What every command shares: the consoles, progress bars, one-line errors, input and output files."""

from __future__ import annotations

import argparse
import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Callable

import numpy as np
from rich.console import Console
from rich.progress import BarColumn, Progress, TaskProgressColumn, TextColumn, TimeElapsedColumn

from imukit import io
from imukit._errors import ImukitError, ParameterError
from imukit.imu import ImuData
from imukit.io import ReadReport
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


# read_imu's bag arguments and the options that set them.
BAG_OPTIONS = {"imu_topic": "--imu-topic", "groundtruth_topic": "--groundtruth-topic", "time_source": "--time-source"}


def add_bag_options(parser: argparse.ArgumentParser) -> None:
    """``--imu-topic``, ``--groundtruth-topic``, ``--time-source``: for a ROS bag PATH only."""
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


def read_imu(args: argparse.Namespace) -> tuple[ImuData, Trajectory | None]:
    """The IMU samples and ground truth at ``args.path``, whatever its format (:func:`imukit.io.read_imu`,
    with the bag options of :func:`add_bag_options`); with ``args.skip_bad_lines``, bad lines are skipped
    and listed on stderr instead of ending the command."""
    report = ReadReport()
    bag = {name: getattr(args, name) for name in BAG_OPTIONS}
    try:
        with err.status(f"reading {args.path}"):
            result = io.read_imu(
                args.path, **bag, on_bad_line="skip" if args.skip_bad_lines else "raise", report=report
            )
    except ParameterError as exc:
        # The library names its argument (imu_topic: ...); the user typed the option.
        name, _, rest = str(exc).partition(": ")
        if name in BAG_OPTIONS:
            raise CliError(f"{BAG_OPTIONS[name]}: {rest}") from exc
        raise
    _report_skips(report)
    return result


def refuse_bag_options(args: argparse.Namespace, what: str) -> None:
    """A CliError naming the first bag option given, for an input that is not a bag (``what`` says what it is)."""
    for name, option in BAG_OPTIONS.items():
        value = getattr(args, name)
        if value is not None:
            raise CliError(f"{option}: {value!r} is for ROS bags, but {args.path} is {what}")


def read_trajectory(path: str, *, skip_bad_lines: bool) -> Trajectory:
    """A trajectory file (TUM, EuRoC ground truth, TUM-VI mocap): :func:`imukit.io.read_trajectory`;
    ``skip_bad_lines`` as for :func:`read_imu`."""
    report = ReadReport()
    with err.status(f"reading {path}"):
        result = io.read_trajectory(path, on_bad_line="skip" if skip_bad_lines else "raise", report=report)
    _report_skips(report)
    return result


def output_path(path: str, suffixes: tuple[str, ...], option: str) -> Path:
    """``path`` as a file to write: its suffix one of ``suffixes``, its folder existing."""
    p = Path(path)
    if p.suffix.lower() not in suffixes:
        raise CliError(f"{option}: expected a file name ending in {' or '.join(suffixes)}, got {path!r}")
    if not p.parent.is_dir():
        raise CliError(f"{option}: folder {os.fspath(p.parent)!r} does not exist")
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


def unpaired(what: str, n_outside_span: int, n_in_gaps: int, max_dt: str) -> str:
    """One line saying which ``what`` (e.g. ``"estimate poses"``) had no ground truth to be scored
    against and why: outside the truth's span, or in its gaps longer than ``max_dt`` (e.g.
    ``"--max-dt = 0.02 s"``); from :func:`imukit.eval.ape`'s counts."""
    return (
        f"{n_outside_span + n_in_gaps} {what} had no ground truth and were left out: {n_outside_span} outside "
        f"its span (before its first or after its last stamp), {n_in_gaps} in its gaps longer than {max_dt}"
    )
