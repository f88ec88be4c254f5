"""``imukit demo``: the whole toolkit on embedded data (no arguments, no network)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

DESCRIPTION = """\
Run imukit on embedded data, with no download: a simulated figure-eight with EuRoC-like noise
(dead reckoning with every strapdown scheme, gyro integration with every attitude scheme,
preintegration over 0.5 s windows), the same motion noise-free at five rates (the schemes'
convergence orders), a simulated static gyro (Allan deviation and fit), and a real 40 s excerpt of
BROAD trial 06 shipped in the package (Robust, Mahony and Madgwick, 6D and 9D, against motion capture;
CC BY 4.0, Laidig et al. 2021).

Prints: one table of errors and timings.
Writes: into --out (default: a new temporary folder, named at the end) trajectory_top_view.png,
attitude_error.png, scheme_convergence.png, allan_gyro.png and results.json (the table's numbers
and the parameters). Takes about 5 s.

Example:
  imukit demo --out demo_results/"""


def add(commands: Any) -> argparse.ArgumentParser:
    p: argparse.ArgumentParser = commands.add_parser(
        "demo",
        help="run everything on embedded data: one table, four plots",
        description=DESCRIPTION,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument(
        "--out", metavar="FOLDER", help="where to write the plots and results.json (default: a new temp folder)"
    )
    p.set_defaults(run=run)
    return p


def run(args: argparse.Namespace) -> int:
    from imukit._demo import run as demo

    demo(None if args.out is None else Path(args.out))
    return 0
