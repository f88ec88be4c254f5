"""The formats :func:`imukit.io.read_imu` and :func:`imukit.io.read_trajectory` detect, in order.

A path goes to the first format whose ``sniff`` accepts it (:class:`imukit.io.Format`); the
"tried …" text of an unknown file and the CLI's list of inputs are made from the same list, so a
format added here (or with :func:`register_format`) is detected, named and listed at once. The
built-in sniffs tell formats apart by layout, file name and field count; where two accept the same
path the first wins: TUM-VI's folder (with ``mocap0/``) comes before EuRoC's, and a folder with
both ground truth and motion capture gives its EuRoC ground truth to ``read_trajectory``.
"""

from __future__ import annotations

from types import TracebackType
from typing import Literal

from imukit._errors import ParameterError
from imukit.io._euroc import EUROC_FOLDER, EUROC_GROUNDTRUTH, EUROC_GROUNDTRUTH_FOLDER, EUROC_IMU_CSV
from imukit.io._format import Format
from imukit.io._gtsam import GTSAM_TEXT
from imukit.io._named_csv import NAMED_CSV
from imukit.io._rosbag import ROSBAG
from imukit.io._trajectory_csv import NAMED_TRAJECTORY_CSV
from imukit.io._tum import TUM
from imukit.io._tumvi import TUMVI_FOLDER, TUMVI_MOCAP, TUMVI_MOCAP_FOLDER

__all__ = ["BUILT_IN", "formats", "listing", "register_format", "unregister_format"]

BUILT_IN: tuple[Format, ...] = (
    TUMVI_FOLDER,
    EUROC_FOLDER,
    EUROC_IMU_CSV,
    GTSAM_TEXT,
    ROSBAG,
    NAMED_CSV,
    TUM,
    EUROC_GROUNDTRUTH_FOLDER,
    EUROC_GROUNDTRUTH,
    NAMED_TRAJECTORY_CSV,
    TUMVI_MOCAP_FOLDER,
    TUMVI_MOCAP,
)
# The readers detection does not reach (they need more than a path), named after the list.
_OTHERS = {
    "imu": "; other layouts: read_imu_csv",
    "trajectory": " (or their folders); KITTI poses: read_kitti_poses; other layouts: read_trajectory_csv",
}
_registered = list(BUILT_IN)


def formats(kind: Literal["imu", "trajectory"] | None = None) -> tuple[Format, ...]:
    """The registered formats in detection order; with ``kind``, those ``read_imu`` (``"imu"``) or
    ``read_trajectory`` (``"trajectory"``) try."""
    return tuple(f for f in _registered if kind is None or f.reads(kind))


def listing(kind: Literal["imu", "trajectory"], others: str | None = None) -> str:
    """The formats of ``kind`` in one line, each description once, then the readers detection does not
    reach (``others`` replaces their text: the CLI names its options)."""
    names = ", ".join(dict.fromkeys(f.description for f in formats(kind)))
    if others is None:
        return names + _OTHERS[kind]
    return f"{names}; {others}"


class Registration:
    """What :func:`register_format` returns: ``with`` it, the format is unregistered at the end."""

    def __init__(self, fmt: Format) -> None:
        self.format = fmt

    def __enter__(self) -> Format:
        return self.format

    def __exit__(
        self, kind: type[BaseException] | None, exc: BaseException | None, traceback: TracebackType | None
    ) -> None:
        unregister_format(self.format.name)


def register_format(fmt: Format, *, before: str | None = None) -> Registration:
    """Add ``fmt`` to detection: last, or just before the format named ``before``.

    Returns a :class:`Registration`; ``with register_format(fmt): ...`` removes it again at the end
    of the block. A name already registered is a :class:`ParameterError` (unregister it first).
    """
    names = [f.name for f in _registered]
    if fmt.name in names:
        raise ParameterError(f"a format named {fmt.name!r} is registered already", argument="fmt")
    if before is not None and before not in names:
        raise ParameterError(f"no format named {before!r}; registered: {', '.join(names)}", argument="before")
    _registered.insert(names.index(before) if before is not None else len(names), fmt)
    return Registration(fmt)


def unregister_format(name: str) -> Format:
    """Remove the format named ``name`` from detection and return it (a built-in one too)."""
    for k, fmt in enumerate(_registered):
        if fmt.name == name:
            return _registered.pop(k)
    raise ParameterError(f"no format named {name!r} is registered", argument="name")
