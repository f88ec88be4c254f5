"""The ``imukit`` command line (console script ``imukit`` and ``python -m imukit``).

Each command lives in its own module with ``add(subparsers)`` (its parser and help, which sets
``run(args) -> int`` as the parser's default). Bad input ends the command with one line on stderr,
``imukit: error: <message>``, and exit code 1 (2 for a command line argparse refuses); ``--debug``
shows the traceback instead.
"""

from __future__ import annotations

import argparse
import os
import sys
import textwrap
import traceback
from collections.abc import Sequence
from typing import Any

from imukit import io
from imukit._errors import ImukitError
from imukit.cli._allan import add as add_allan
from imukit.cli._common import OTHER_LAYOUTS, error_line
from imukit.cli._demo import add as add_demo
from imukit.cli._evaluate import add as add_evaluate
from imukit.cli._filter import add as add_filter
from imukit.cli._fleet import add as add_fleet
from imukit.cli._integrate import add as add_integrate
from imukit.cli._preintegrate import add as add_preintegrate
from imukit.cli._simulate import add as add_simulate

__all__ = ["build_parser", "main"]

# Each adds its parser, with `run` as the default of `args.run`; in the order `imukit --help` lists them.
_COMMANDS = (add_integrate, add_preintegrate, add_filter, add_simulate, add_allan, add_evaluate, add_fleet, add_demo)

_DESCRIPTION = """\
IMU kinematics from the command line: integrate a recording into a trajectory, preintegrate it
into windows, run an attitude filter, simulate a sensor, identify its noise (Allan), score a
trajectory against ground truth, run a job over a fleet of logs on Dask, or run the demo.

{inputs}
Frames and units are imukit's everywhere (docs/conventions.md): SI units, world z up, gravity
(0, 0, -9.81) m/s^2, rotations R_wb (body to world), quaternions x y z w in files.

Run `imukit COMMAND --help` for what a command reads, writes and prints, with an example."""


def build_parser() -> argparse.ArgumentParser:
    """The parser of every command (``imukit --help``)."""
    # The formats as registered now (imukit.io.register_format), not as when this module was imported.
    inputs = textwrap.fill(
        f"Inputs are read by format, detected from the path: {io.listing('imu', others=OTHER_LAYOUTS)} "
        "(and for `filter`, a BROAD .mat trial).",
        width=99,
    )
    parser = argparse.ArgumentParser(
        prog="imukit",
        description=_DESCRIPTION.format(inputs=inputs),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--debug", action="store_true", help="on an error, show the Python traceback")
    parser.add_argument(
        "--skip-bad-lines",
        action="store_true",
        help="skip malformed lines, duplicate or backward stamps in input files, listing them on stderr "
        "(default: the first one ends the command with its file and line)",
    )
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for add in _COMMANDS:
        # The global options after the command too; SUPPRESS keeps one given before it.
        command = add(commands)
        for option in ("--debug", "--skip-bad-lines"):
            command.add_argument(option, action="store_true", default=argparse.SUPPRESS, help=argparse.SUPPRESS)
    return parser


class _ReaderMayLeave:
    """Standard output that, once its reader has gone (``imukit integrate … | head -1``), drops what is
    printed instead of ending the command: the files it writes matter more than its lines (they were
    never written, exit 1). The descriptor then points at ``/dev/null``, so the flush at exit is quiet."""

    def __init__(self, stream: Any) -> None:
        self._stream = stream

    def write(self, text: str) -> int:
        try:
            return int(self._stream.write(text))
        except BrokenPipeError:
            self._leave()
            return len(text)

    def flush(self) -> None:
        try:
            self._stream.flush()
        except BrokenPipeError:
            self._leave()

    def _leave(self) -> None:
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, self._stream.fileno())
        os.close(null)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._stream, name)


def main(argv: Sequence[str] | None = None) -> int:
    """Run one command; returns the exit code (0 success, 1 bad input or failure, 2 bad usage)."""
    args = build_parser().parse_args(argv)
    stdout = sys.stdout
    sys.stdout = _ReaderMayLeave(stdout)
    try:
        code: int = args.run(args)
    except (ImukitError, OSError, ValueError) as exc:
        if args.debug:
            traceback.print_exc()
        print(f"imukit: error: {error_line(exc)}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("imukit: interrupted", file=sys.stderr)
        return 130
    finally:
        sys.stdout = stdout
    return code
