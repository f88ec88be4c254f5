"""imukit: IMU kinematics with a Rust core and a numpy front.

Conventions (Hamilton quaternions stored xyzw, active ``R_wb``, body rates right-multiplied,
right perturbations, intrinsic ZYX Euler angles, SI units) are tabulated with worked numbers in
``docs/conventions.md``.

>>> import numpy as np, imukit as ik
>>> R = ik.so3.exp([0.0, 0.0, np.pi / 2])   # a quarter turn about z
>>> np.round(R @ [1.0, 0.0, 0.0], 12)       # maps body x onto world y
array([0., 1., 0.])
"""

from imukit import earth, euler, filters, io, noise, quat, sim, so3
from imukit import eval as eval  # the module imukit.eval (ATE / RPE / attitude errors); shadows the builtin here only
from imukit._core import GRAVITY, __version__
from imukit._errors import (
    DTypeError,
    FileFormatError,
    GimbalLockError,
    ImukitError,
    InvalidQuaternionError,
    InvalidRotationError,
    MissingDependencyError,
    NonFiniteError,
    ParameterError,
    ResourceError,
    ShapeError,
    TimestampError,
)
from imukit.attitude import integrate_attitude
from imukit.earth import LocalLevel
from imukit.imu import ImuBias, ImuData, ImuNoise
from imukit.preint import (
    PreintegratedImu,
    Preintegration,
    PreintParams,
    ResidualJacobians,
    preintegrate,
    preintegrate_windows,
)
from imukit.state import NavState, Trajectory
from imukit.strapdown import integrate, propagate
from imukit.threads import get_num_threads, set_num_threads, simd_path

__all__ = [
    "GRAVITY",
    "DTypeError",
    "FileFormatError",
    "GimbalLockError",
    "ImuBias",
    "ImuData",
    "ImuNoise",
    "ImukitError",
    "InvalidQuaternionError",
    "InvalidRotationError",
    "LocalLevel",
    "MissingDependencyError",
    "NavState",
    "NonFiniteError",
    "ParameterError",
    "PreintParams",
    "PreintegratedImu",
    "Preintegration",
    "ResidualJacobians",
    "ResourceError",
    "ShapeError",
    "TimestampError",
    "Trajectory",
    "__version__",
    "earth",
    "euler",
    "eval",
    "filters",
    "get_num_threads",
    "integrate",
    "integrate_attitude",
    "io",
    "noise",
    "preintegrate",
    "preintegrate_windows",
    "propagate",
    "quat",
    "set_num_threads",
    "sim",
    "simd_path",
    "so3",
]
