"""Files: IMU datasets (EuRoC, TUM-VI, GTSAM/KITTI, ROS bags, any CSV), trajectories, Kalibr noise files.

=====================  ===========================================================================
any IMU source         :func:`read_imu` → ``(ImuData, Trajectory | None)``: finds the format (EuRoC or
                       TUM-VI folder, EuRoC IMU CSV, GTSAM/KITTI text, ROS bag, a CSV naming its
                       columns), or reads a CSV by its columns (``csv=``, :func:`read_imu_csv`'s
                       keywords); :func:`read_trajectory` → ``Trajectory`` (TUM, EuRoC ground truth,
                       a CSV naming its pose columns, TUM-VI mocap)
TUM                    :func:`write_tum`, :func:`read_tum`: ``timestamp tx ty tz qx qy qz qw`` lines,
                       quaternion ``q_wb`` scalar-last; ``t_ns`` printed exactly with 9 decimals
EuRoC / ASL            :func:`write_euroc`, :func:`read_euroc` (a folder), :func:`read_euroc_imu`,
                       :func:`read_euroc_groundtruth` (one CSV each): integer-nanosecond stamps,
                       ``q_RS`` = ``R_wb`` scalar-first, EuRoC's header lines;
                       :func:`read_euroc_sensor`: the noise and rate of ``imu0/sensor.yaml``
TUM-VI                 :func:`read_tumvi`: EuRoC-layout folder with ``mocap0/data.csv`` poses
GTSAM / KITTI          :func:`read_gtsam_imu`: ``Time dt accelX … omegaZ`` text (dt checked against the
                       stamps); :func:`read_kitti_poses`: 3×4 pose rows plus a times file
any CSV                :func:`read_imu_csv`: columns by header name or index; s/ms/us/ns, deg/s, g;
                       :func:`read_trajectory_csv`: poses by column, quaternion xyzw or wxyz
ROS bags               :func:`read_rosbag`, :func:`list_rosbag_topics` (ROS 1, ROS 2, MCAP; needs
                       ``imukit[ros]``)
Kalibr ``imu.yaml``    :func:`write_kalibr_imu`, :func:`read_kalibr_imu` → :class:`KalibrImu`:
                       continuous-time noise densities (:class:`imukit.ImuNoise`) and the rate
new formats            :class:`Format` (a name, a sniff, a reader) and :func:`register_format`: detection,
                       its error text and the CLI's help take it up; :func:`formats` lists them
gaps                   :func:`find_gaps`: steps between samples far longer than the others;
                       :func:`reference_max_dt`: how far a reference is interpolated (2.5 steps)
bad lines              every reader takes ``on_bad_line="raise" | "skip"`` and ``report=``: skipped
                       lines go to a :class:`ReadReport` (:class:`SkippedLine` records) or, without
                       one, into one :class:`SkippedLinesWarning`
=====================  ===========================================================================

Writers print floats with ``repr``, the shortest text that reads back to the same float, so every
write → read round trip is bit-exact; nanosecond stamps are read as integers, never through
float64. Readers raise :class:`FileFormatError` (a ``ValueError``) naming the file and the line or
key. Columns, units and frames: ``docs/io.md``.
"""

from __future__ import annotations

from imukit._errors import FileFormatError
from imukit.io._csv import read_imu_csv
from imukit.io._detect import read_imu, read_trajectory
from imukit.io._euroc import read_euroc, read_euroc_groundtruth, read_euroc_imu, read_euroc_sensor, write_euroc
from imukit.io._format import Format, Head
from imukit.io._gaps import GAP_FACTOR, REFERENCE_GAP_FACTOR, Gap, find_gaps, reference_max_dt
from imukit.io._gtsam import read_gtsam_imu
from imukit.io._kalibr import KalibrImu, read_kalibr_imu, write_kalibr_imu
from imukit.io._kitti import read_kitti_poses
from imukit.io._noise_model import find_noise_model
from imukit.io._registry import Registration, formats, listing, register_format, unregister_format
from imukit.io._report import ReadReport, SkippedLine, SkippedLinesWarning
from imukit.io._rosbag import list_rosbag_topics, read_rosbag
from imukit.io._trajectory_csv import read_trajectory_csv
from imukit.io._tum import read_tum, write_tum
from imukit.io._tumvi import read_tumvi

__all__ = [
    "GAP_FACTOR",
    "REFERENCE_GAP_FACTOR",
    "FileFormatError",
    "Format",
    "Gap",
    "Head",
    "KalibrImu",
    "ReadReport",
    "Registration",
    "SkippedLine",
    "SkippedLinesWarning",
    "find_gaps",
    "find_noise_model",
    "formats",
    "list_rosbag_topics",
    "listing",
    "read_euroc",
    "read_euroc_groundtruth",
    "read_euroc_imu",
    "read_euroc_sensor",
    "read_gtsam_imu",
    "read_imu",
    "read_imu_csv",
    "read_kalibr_imu",
    "read_kitti_poses",
    "read_rosbag",
    "read_trajectory",
    "read_trajectory_csv",
    "read_tum",
    "read_tumvi",
    "reference_max_dt",
    "register_format",
    "unregister_format",
    "write_euroc",
    "write_kalibr_imu",
    "write_tum",
]
