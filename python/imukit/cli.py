"""The ``imukit`` command line. Jobs arrive with their issues; today: ``demo``."""

from __future__ import annotations

import argparse
from collections.abc import Sequence


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="imukit",
        description="IMU kinematics toolkit. Conventions: docs/conventions.md.",
    )
    jobs = parser.add_subparsers(dest="job", required=True, metavar="JOB")
    jobs.add_parser(
        "demo",
        help="show the conventions in numbers and time so3.exp/log against scipy",
        description="Prints worked examples of imukit's conventions and a short speed comparison.",
    )
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the console script; returns the exit code."""
    args = _parser().parse_args(argv)
    if args.job == "demo":
        from imukit._demo import run

        run()
    return 0
