# Stubs of the compiled module (checked by mypy.stubtest). Every function takes a C-contiguous
# float64 array of shape (n, k), the argument name used in error messages, and options; it returns
# a new (n, m) float64 array. Use the public modules (imukit.so3, imukit.quat, imukit.euler).
from typing import Any, Protocol, final

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "DEFAULT_SATURATION_NOISE_FACTOR",
    "GRAVITY",
    "PREINT_SCHEMES",
    "PREINT_SCHEME_ALIASES",
    "AttitudeFilter",
    "Preintegrator",
    "__version__",
    "allan_variance",
    "attitude_integrate",
    "euler_from_matrix",
    "euler_rate_matrix",
    "euler_rate_matrix_inv",
    "euler_to_matrix",
    "get_num_threads",
    "preint_windows",
    "preint_windows_record",
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

@final
class AttitudeFilter:
    def __new__(
        cls,
        algorithm: str,
        gains: list[float],
        world: str,
        gravity: float,
        ramp: list[float],
        accel_rejection: list[float] | None,
        mag_rejection: list[float] | None,
        rest: list[float] | None,
    ) -> AttitudeFilter: ...
    @staticmethod
    def initial_state(q: list[float] | None = None) -> NDArray[np.float64]: ...
    def update(
        self,
        state: NDArray[np.float64],
        gyro: list[float],
        accel: list[float],
        dt: float,
        mag: list[float] | None = None,
    ) -> NDArray[np.float64]: ...
    def run(
        self,
        t: NDArray[np.float64],
        gyro: NDArray[np.float64],
        accel: NDArray[np.float64],
        mag: NDArray[np.float64] | None,
        state: NDArray[np.float64],
        continued: bool,
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]: ...

class _ImuArrays(Protocol):
    """What the preintegration windows read from an ``imukit.ImuData``, by attribute name."""

    @property
    def seconds(self) -> NDArray[np.float64]: ...
    @property
    def gyro(self) -> NDArray[np.float64]: ...
    @property
    def accel(self) -> NDArray[np.float64]: ...
    @property
    def gyro_saturated(self) -> NDArray[np.bool_]: ...
    @property
    def accel_saturated(self) -> NDArray[np.bool_]: ...

class _NoiseFields(Protocol):
    @property
    def gyro_density(self) -> float: ...
    @property
    def accel_density(self) -> float: ...
    @property
    def gyro_random_walk(self) -> float: ...
    @property
    def accel_random_walk(self) -> float: ...

class _BiasFields(Protocol):
    @property
    def gyro(self) -> NDArray[np.float64]: ...
    @property
    def accel(self) -> NDArray[np.float64]: ...

class _PreintFields(Protocol):
    """What the core reads from an ``imukit.PreintParams``, by attribute name."""

    @property
    def noise(self) -> _NoiseFields: ...
    @property
    def bias(self) -> _BiasFields: ...
    @property
    def scheme(self) -> str: ...
    @property
    def combined(self) -> bool: ...
    @property
    def saturation_noise_factor(self) -> float: ...

DEFAULT_SATURATION_NOISE_FACTOR: float
PREINT_SCHEMES: list[str]
PREINT_SCHEME_ALIASES: dict[str, str]

@final
class Preintegrator:
    def __new__(cls, params: _PreintFields) -> Preintegrator: ...
    @staticmethod
    def from_state(words: list[float]) -> Preintegrator: ...
    def __reduce__(self) -> tuple[Any, tuple[list[float]]]: ...
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
        NDArray[np.float64],
        NDArray[np.float64],
        NDArray[np.float64],
        float,
        NDArray[np.float64],
        NDArray[np.float64],
        NDArray[np.float64] | None,
    ]: ...

def preint_windows(
    imu: _ImuArrays,
    boundaries: NDArray[np.float64],
    template: Preintegrator,
    threads: int | None,
) -> list[Preintegrator]: ...
def preint_windows_record(
    imu: _ImuArrays,
    boundaries: NDArray[np.float64],
    params: _PreintFields,
    threads: int | None,
) -> tuple[
    NDArray[np.float64],
    NDArray[np.float64],
    NDArray[np.float64],
    NDArray[np.float64],
    NDArray[np.float64],
    NDArray[np.float64],
    NDArray[np.float64] | None,
]: ...
def sim_motion(
    kind: str, params: list[float], t: NDArray[np.float64], gravity: list[float]
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]: ...
def sim_measure(
    t: NDArray[np.float64], ideal: NDArray[np.float64], model: list[float], seed: int, triad: int
) -> NDArray[np.float64]: ...
