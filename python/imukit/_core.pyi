# Stubs of the compiled module (checked by mypy.stubtest). Every function takes a C-contiguous
# float64 array of shape (n, k), the argument name used in error messages, and options; it returns
# a new (n, m) float64 array. Use the public modules (imukit.so3, imukit.quat, imukit.euler).
from typing import Any, final

import numpy as np
from numpy.typing import NDArray
from typing_extensions import Self, disjoint_base

__all__ = [
    "GRAVITY",
    "AccelRejection",
    "FilterOptions",
    "FilterState",
    "GainRamp",
    "MadgwickFilter",
    "MadgwickGains",
    "MagRejection",
    "MahonyFilter",
    "MahonyGains",
    "Preintegrator",
    "RestDetection",
    "__version__",
    "allan_variance",
    "attitude_integrate",
    "euler_from_matrix",
    "euler_rate_matrix",
    "euler_rate_matrix_inv",
    "euler_to_matrix",
    "get_num_threads",
    "preint_windows",
    "quat_conjugate",
    "quat_exp",
    "quat_inverse",
    "quat_log",
    "quat_multiply",
    "quat_normalize",
    "quat_omega_matrix",
    "quat_product_matrix",
    "quat_rotate",
    "set_num_threads",
    "sim_measure",
    "sim_motion",
    "so3_exp",
    "so3_hat",
    "so3_jacobian",
    "so3_log",
    "so3_vee",
    "strapdown_integrate",
    "strapdown_propagate",
]

__version__: str
# Default world-frame gravity [m/s²], z up: `imukit::imu::GRAVITY`, the one place it is written.
GRAVITY: tuple[float, float, float]

# The process-wide thread count of the parallel kernels (default: rayon's, one per core).
def set_num_threads(n: int) -> None: ...
def get_num_threads() -> int: ...
def so3_hat(x: NDArray[np.float64], name: str) -> NDArray[np.float64]: ...
def so3_vee(x: NDArray[np.float64], name: str) -> NDArray[np.float64]: ...
def so3_exp(x: NDArray[np.float64], name: str) -> NDArray[np.float64]: ...
def so3_log(x: NDArray[np.float64], name: str) -> NDArray[np.float64]: ...
def so3_jacobian(x: NDArray[np.float64], name: str, kind: str) -> NDArray[np.float64]: ...
def quat_multiply(x: NDArray[np.float64], name: str, convention: str) -> NDArray[np.float64]: ...
def quat_conjugate(x: NDArray[np.float64], name: str) -> NDArray[np.float64]: ...
def quat_inverse(x: NDArray[np.float64], name: str) -> NDArray[np.float64]: ...
def quat_normalize(x: NDArray[np.float64], name: str) -> NDArray[np.float64]: ...
def quat_rotate(x: NDArray[np.float64], name: str) -> NDArray[np.float64]: ...
def quat_product_matrix(x: NDArray[np.float64], name: str, side: str, convention: str) -> NDArray[np.float64]: ...
def quat_omega_matrix(x: NDArray[np.float64], name: str, convention: str) -> NDArray[np.float64]: ...
def quat_exp(x: NDArray[np.float64], name: str) -> NDArray[np.float64]: ...
def quat_log(x: NDArray[np.float64], name: str) -> NDArray[np.float64]: ...
def euler_to_matrix(x: NDArray[np.float64], name: str) -> NDArray[np.float64]: ...
def euler_from_matrix(x: NDArray[np.float64], name: str) -> NDArray[np.float64]: ...
def euler_rate_matrix(x: NDArray[np.float64], name: str, tolerance: float) -> NDArray[np.float64]: ...
def euler_rate_matrix_inv(x: NDArray[np.float64], name: str) -> NDArray[np.float64]: ...
def allan_variance(
    y: NDArray[np.float64], name: str, rate: float, clusters: list[int], overlapping: bool
) -> tuple[NDArray[np.float64], NDArray[np.int64]]: ...  # (M, C) variances, (M,) term counts
def attitude_integrate(
    t: NDArray[np.float64],
    gyro: NDArray[np.float64],
    initial: NDArray[np.float64],
    scheme: str,
    representation: str,
    gimbal_tolerance: float,
    final_only: bool,
) -> NDArray[np.float64]: ...
def strapdown_integrate(
    t: NDArray[np.float64],
    gyro: NDArray[np.float64],
    accel: NDArray[np.float64],
    initial: list[float],
    bias_values: list[float],
    gravity: list[float],
    scheme: str,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]: ...  # (N, 6) [p, v] and (N, 4) q (xyzw)
def strapdown_propagate(
    t: NDArray[np.float64],
    gyro: NDArray[np.float64],
    accel: NDArray[np.float64],
    initial: list[float],
    covariance: NDArray[np.float64],
    bias_values: list[float],
    noise: list[float],
    gravity: list[float],
    scheme: str,
    every: int,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]: ...

# Attitude filters: option values (a field left out or None takes the Rust Default), the state
# by field name, and one filter class per law.
_Number = float | int | np.floating

@final
class GainRamp:
    duration_s: float
    factor: float
    def __new__(cls, duration_s: _Number | None = None, factor: _Number | None = None) -> GainRamp: ...
    def __getnewargs__(self) -> tuple[float, ...]: ...

@final
class AccelRejection:
    norm: float
    angle_rad: float
    recovery_s: float
    def __new__(
        cls, norm: _Number | None = None, angle_rad: _Number | None = None, recovery_s: _Number | None = None
    ) -> AccelRejection: ...
    def __getnewargs__(self) -> tuple[float, ...]: ...

@final
class MagRejection:
    norm_fraction: float
    dip_rad: float
    recovery_s: float
    def __new__(
        cls, norm_fraction: _Number | None = None, dip_rad: _Number | None = None, recovery_s: _Number | None = None
    ) -> MagRejection: ...
    def __getnewargs__(self) -> tuple[float, ...]: ...

@final
class RestDetection:
    gyro: float
    accel: float
    duration_s: float
    tau_s: float
    def __new__(
        cls,
        gyro: _Number | None = None,
        accel: _Number | None = None,
        duration_s: _Number | None = None,
        tau_s: _Number | None = None,
    ) -> RestDetection: ...
    def __getnewargs__(self) -> tuple[float, ...]: ...

@final
class MahonyGains:
    kp: float
    ki: float
    def __new__(cls, kp: _Number | None = None, ki: _Number | None = None) -> MahonyGains: ...
    def __getnewargs__(self) -> tuple[float, ...]: ...

@final
class MadgwickGains:
    beta: float
    def __new__(cls, beta: _Number | None = None) -> MadgwickGains: ...
    def __getnewargs__(self) -> tuple[float, ...]: ...

@final
class FilterOptions:
    WORLDS: list[str]
    world: str
    gravity: float
    gain_ramp: GainRamp | None
    acc_rejection: AccelRejection | None
    mag_rejection: MagRejection | None
    rest_detection: RestDetection | None
    def __new__(
        cls,
        *,
        world: str,
        gravity: _Number,
        gain_ramp: GainRamp | None,
        acc_rejection: AccelRejection | None,
        mag_rejection: MagRejection | None,
        rest_detection: RestDetection | None,
    ) -> FilterOptions: ...
    @staticmethod
    def default() -> FilterOptions: ...
    def __getnewargs_ex__(self) -> tuple[tuple[()], dict[str, object]]: ...

@disjoint_base
class FilterState:
    def __new__(
        cls,
        *,
        quaternion: list[float],
        gyro_bias: list[float],
        initialized: bool,
        time: float,
        ramp_elapsed: float,
        accel_rejected: float,
        mag_rejected: float,
        rest: float,
        mag_norm: float,
        mag_dip_sin: float,
        mag_dip_cos: float,
        extra: list[tuple[str, float]] | None = None,
    ) -> Self: ...
    @staticmethod
    def _initial(q: list[float] | None = None) -> FilterState: ...
    @staticmethod
    def _from_legacy_values(values: list[float]) -> FilterState: ...
    def _legacy_values(self) -> NDArray[np.float64]: ...
    def _at_time(self, time: float) -> FilterState: ...
    def fields(self) -> dict[str, Any]: ...
    def __getnewargs_ex__(self) -> tuple[tuple[()], dict[str, object]]: ...
    @property
    def quaternion(self) -> NDArray[np.float64]: ...
    @property
    def gyro_bias(self) -> NDArray[np.float64]: ...
    @property
    def initialized(self) -> bool: ...
    @property
    def time(self) -> float: ...
    @property
    def ramp_elapsed(self) -> float: ...
    @property
    def accel_rejected(self) -> float: ...
    @property
    def mag_rejected(self) -> float: ...
    @property
    def rest(self) -> float: ...
    @property
    def mag_norm(self) -> float: ...
    @property
    def mag_dip_sin(self) -> float: ...
    @property
    def mag_dip_cos(self) -> float: ...
    @property
    def extra(self) -> list[tuple[str, float]]: ...

_Outputs = tuple[NDArray[np.float64], NDArray[np.float64], FilterState]

@final
class MahonyFilter:
    def __new__(cls, gains: MahonyGains, options: FilterOptions) -> MahonyFilter: ...
    def __getnewargs__(self) -> tuple[MahonyGains, FilterOptions]: ...
    def update(
        self, state: FilterState, gyro: list[float], accel: list[float], dt: float, mag: list[float] | None = None
    ) -> FilterState: ...
    def run(
        self,
        t: NDArray[np.float64],
        gyro: NDArray[np.float64],
        accel: NDArray[np.float64],
        mag: NDArray[np.float64] | None,
        state: FilterState,
        continued: bool,
    ) -> _Outputs: ...

@final
class MadgwickFilter:
    def __new__(cls, gains: MadgwickGains, options: FilterOptions) -> MadgwickFilter: ...
    def __getnewargs__(self) -> tuple[MadgwickGains, FilterOptions]: ...
    def update(
        self, state: FilterState, gyro: list[float], accel: list[float], dt: float, mag: list[float] | None = None
    ) -> FilterState: ...
    def run(
        self,
        t: NDArray[np.float64],
        gyro: NDArray[np.float64],
        accel: NDArray[np.float64],
        mag: NDArray[np.float64] | None,
        state: FilterState,
        continued: bool,
    ) -> _Outputs: ...

@final
class Preintegrator:
    def __new__(
        cls, bias_values: list[float], noise: list[float], combined: bool, scheme: str, saturation_noise_factor: float
    ) -> Preintegrator: ...
    def covariance_combined(self) -> NDArray[np.float64] | None: ...
    def merge(self, next: Preintegrator) -> Preintegrator: ...
    def integrate_measurement(
        self, accel: list[float], gyro: list[float], dt: float, gyro_saturated: bool, accel_saturated: bool
    ) -> None: ...
    def integrate(
        self,
        t: NDArray[np.float64],
        gyro: NDArray[np.float64],
        accel: NDArray[np.float64],
        gyro_saturated: NDArray[np.bool_],
        accel_saturated: NDArray[np.bool_],
    ) -> None: ...
    def state(
        self,
    ) -> tuple[
        NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], float, NDArray[np.float64], NDArray[np.float64]
    ]: ...

def preint_windows(
    t: NDArray[np.float64],
    gyro: NDArray[np.float64],
    accel: NDArray[np.float64],
    gyro_saturated: NDArray[np.bool_],
    accel_saturated: NDArray[np.bool_],
    boundaries: NDArray[np.float64],
    template: Preintegrator,
    threads: int,
) -> list[Preintegrator]: ...
def sim_motion(
    kind: str, params: list[float], t: NDArray[np.float64], gravity: list[float]
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]: ...
def sim_measure(
    t: NDArray[np.float64], ideal: NDArray[np.float64], model: list[float], seed: int, triad: int
) -> NDArray[np.float64]: ...
