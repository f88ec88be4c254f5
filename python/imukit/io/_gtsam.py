"""GTSAM / KITTI IMU text files: :func:`read_gtsam_imu` (``docs/io.md``).

The layout of ``KittiEquivBiasedImu.txt`` in GTSAM's examples (read by its
``IMUKittiExampleGPS``): a header line ``Time dt accelX accelY accelZ omegaX omegaY omegaZ``, then
one sample per line, white-space separated.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from imukit._errors import FileFormatError
from imukit.imu import ImuData
from imukit.io._format import Format, Head
from imukit.io._lines import Rows, as_file_error, data_lines, increasing, parse_rows, public_reader, require_rows
from imukit.io._report import BadLines, OnBadLine, ReadReport

__all__ = ["read_gtsam_imu"]

GTSAM_COLUMNS = ["Time", "dt", "accelX", "accelY", "accelZ", "omegaX", "omegaY", "omegaZ"]
# The dt column is printed from the unrounded clock: on KITTI 00 it matches the printed stamps to
# 1.5e-11 s. One microsecond still tells a step before the sample from one after it (KITTI's steps
# jitter by 0.1 ms) and from a nominal constant.
DT_TOLERANCE_S = 1e-6


def gtsam_imu(path: str | os.PathLike[str], bad: BadLines) -> ImuData:
    """:func:`read_gtsam_imu` reporting to ``bad``."""
    rows = parse_rows(
        _without_header(path),
        path,
        bad,
        split=str.split,
        width=8,
        expected="fields 'Time dt accelX accelY accelZ omegaX omegaY omegaZ'",
        columns=range(8),
    )
    stamps = [f[0] for f in rows.fields]
    rows = rows.take(increasing(rows, [row[0] for row in rows.values], stamps, path, bad))
    require_rows(rows, path, bad)
    _check_dt(rows, path, bad)
    data = np.array(rows.values, dtype=np.float64)
    return as_file_error(path, lambda: ImuData(data[:, 0], data[:, 5:8], data[:, 2:5]))


@public_reader(gtsam_imu)
def read_gtsam_imu(  # type: ignore[empty-body]
    path: str | os.PathLike[str], *, on_bad_line: OnBadLine = "raise", report: ReadReport | None = None
) -> ImuData:
    """Read a GTSAM / KITTI IMU text file: ``Time dt accelX accelY accelZ omegaX omegaY omegaZ``.

    Columns: time [s] (float), dt [s], specific force [m/s²] and angular rate [rad/s] in the IMU
    frame (KITTI: x forward, y left, z up). The header line is optional; ``#`` and blank lines are
    skipped. Returns an :class:`imukit.ImuData` with float-second ``t`` (``t_ns`` None: the source
    prints decimal seconds, ~1e-9 s).

    **The dt column is checked, then dropped.** The files hold ``dt[k] = t[k] − t[k−1]``, the step
    *before* the sample, and GTSAM's example integrates sample k over it, ``[t[k−1], t[k]]``.
    :class:`imukit.ImuData` takes every step from the stamps, and imukit's held-input schemes
    (``euler``, ``exp``) hold sample k over the step *after* it, ``[t[k], t[k+1]]``
    (``docs/strapdown.md``): the step lengths agree, the samples are assigned to the steps one apart, so
    imukit does not reproduce GTSAM's integration sample for sample. The reader checks dt for every line
    whose previous data line is a kept sample, to 1 µs (KITTI 00 agrees to 1.5e-11 s), and raises
    :class:`FileFormatError` otherwise, in both ``on_bad_line`` modes: a dt that disagrees means a
    different convention (a step after the sample, or a nominal constant), not a bad line, and keeping
    or skipping samples could not fix it. Read such a file with :func:`imukit.io.read_imu_csv`
    (``time_column=0``), which ignores dt. The first line's dt is not checked (GTSAM's KITTI file has
    ``dt = Time`` there).

    All samples are kept, gaps included: KITTI 00 starts with an orphan sample 1.92 s before the
    next one (use ``ImuData(..., max_gap=...)`` or slice it off to integrate without it).

    Parameters
    ----------
    path
        The text file.
    on_bad_line, report
        As in :func:`imukit.io.read_euroc_imu`: not 8 fields, text that is not a number, non-finite
        values, and stamps out of order (the longest strictly increasing run of stamps is kept) are the
        bad lines.

    Raises
    ------
    FileFormatError
        Naming the file and line: the bad lines above ("raise" mode), a dt that disagrees with the
        stamps, or no data.
    """


def _without_header(path: str | os.PathLike[str]) -> Iterator[tuple[int, str]]:
    lines = data_lines(path)
    for number, text in lines:
        if text.split() != GTSAM_COLUMNS:
            yield number, text
        break
    yield from lines


def _check_dt(rows: Rows, path: str | os.PathLike[str], bad: BadLines) -> None:
    where = os.fspath(path)
    skipped = np.array(sorted(s.line for s in bad.records if s.path == where), dtype=np.int64)
    lines = np.array(rows.lines, dtype=np.int64)
    data = np.array(rows.values, dtype=np.float64)
    with np.errstate(over="ignore"):  # values near ±1e308: an infinite difference, which is a mismatch
        step = np.diff(data[:, 0])
        mismatch = np.abs(data[1:, 1] - step) > DT_TOLERANCE_S
    # A kept line right after a skipped one has no known previous stamp.
    follows_kept = np.searchsorted(skipped, lines[1:]) == np.searchsorted(skipped, lines[:-1])
    off = np.flatnonzero(follows_kept & mismatch)
    if off.size:
        k = int(off[0]) + 1
        raise FileFormatError(
            f"{where}, line {rows.lines[k]}: dt = {float(data[k, 1])!r} s, but the stamps step by "
            f"{float(step[k - 1])!r} s since line {rows.lines[k - 1]}; read_gtsam_imu expects GTSAM's "
            "dt[k] = t[k] - t[k-1] (read_imu_csv reads the file without its dt)",
            argument="path",
        )


def _gtsam_header(path: Path, head: Head) -> bool:
    lines = head.lines or []
    return bool(lines) and lines[0][1].split() == GTSAM_COLUMNS


GTSAM_TEXT = Format("gtsam-text", "imu", _gtsam_header, gtsam_imu, "GTSAM / KITTI text")
