"""Files: trajectories (TUM), EuRoC / ASL dataset folders, Kalibr IMU noise files.

=====================  ===========================================================================
TUM                    :func:`write_tum`, :func:`read_tum`: ``timestamp tx ty tz qx qy qz qw`` lines,
                       quaternion ``q_wb`` scalar-last; ``t_ns`` printed exactly with 9 decimals
EuRoC / ASL            :func:`write_euroc`, :func:`read_euroc` (a folder), :func:`read_euroc_imu`,
                       :func:`read_euroc_groundtruth` (one CSV each): integer-nanosecond stamps,
                       ``q_RS`` = ``R_wb`` scalar-first, EuRoC's header lines
Kalibr ``imu.yaml``    :func:`write_kalibr_imu`, :func:`read_kalibr_imu` → :class:`KalibrImu`:
                       continuous-time noise densities (:class:`imukit.ImuNoise`) and the rate
=====================  ===========================================================================

Writers print floats with ``repr``, the shortest text that reads back to the same float, so every
write → read round trip is bit-exact; nanosecond stamps are read as integers, never through
float64. Readers raise :class:`FileFormatError` (a ``ValueError``) naming the file and the line or
key. Columns, units and frames: ``docs/io.md``.
"""

from __future__ import annotations

from imukit._errors import FileFormatError
from imukit.io._euroc import read_euroc, read_euroc_groundtruth, read_euroc_imu, write_euroc
from imukit.io._kalibr import KalibrImu, read_kalibr_imu, write_kalibr_imu
from imukit.io._rosbag import list_rosbag_topics, read_rosbag
from imukit.io._tum import read_tum, write_tum

__all__ = [
    "FileFormatError",
    "KalibrImu",
    "list_rosbag_topics",
    "read_euroc",
    "read_euroc_groundtruth",
    "read_euroc_imu",
    "read_kalibr_imu",
    "read_rosbag",
    "read_tum",
    "write_euroc",
    "write_kalibr_imu",
    "write_tum",
]
