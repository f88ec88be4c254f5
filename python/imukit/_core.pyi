# Stubs of the compiled module (checked by mypy.stubtest). Every function takes a C-contiguous
# float64 array of shape (n, k), the argument name used in error messages, and options; it returns
# a new (n, m) float64 array. Use the public modules (imukit.so3, imukit.quat, imukit.euler).
from typing import Any, Literal, Protocol, final

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation
from typing_extensions import Self, disjoint_base

from imukit.sim import ConstantTwist, FigureEight, Helix, SensorErrors, Static, VioEllipse

__all__ = [
    "ATTITUDE_DEFAULT_SCHEME",
    "ATTITUDE_REPRESENTATIONS",
    "ATTITUDE_SCHEMES",
    "ATTITUDE_SCHEME_ALIASES",
    "DEFAULT_SATURATION_NOISE_FACTOR",
    "FILTER_WORLDS",
    "GRAVITY",
    "LOCAL_LEVEL_AXES",
    "PREINT_DEFAULT_SCHEME",
    "PREINT_SCHEMES",
    "PREINT_SCHEME_ALIASES",
    "QUAT_CONVENTIONS",
    "STRAPDOWN_DEFAULT_SCHEME",
    "STRAPDOWN_SCHEMES",
    "STRAPDOWN_SCHEME_ALIASES",
    "AccelLowPass",
    "AccelRejection",
    "FilterOptions",
    "FilterState",
    "GainRamp",
    "LeverNoise",
    "MadgwickFilter",
    "MadgwickGains",
    "MagRejection",
    "MahonyFilter",
    "MahonyGains",
    "Preintegrator",
    "RestDetection",
    "RobustFilter",
    "RobustParams",
    "RobustState",
    "__version__",
    "after_fork_in_child",
    "allan_variance",
    "attitude_integrate",
    "body_readings",
    "ellipsoid_integrate",
    "euler_from_matrix",
    "euler_rate_matrix",
    "euler_rate_matrix_inv",
    "euler_to_matrix",
    "get_num_threads",
    "lever_noise",
    "local_level",
    "preint_adjoint",
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
    "sim_ellipsoid",
    "sim_measure",
    "sim_motion",
    "sim_rotating_world",
    "sim_sensor_default",
    "sim_sensor_pose",
    "simd_path",
    "so3_exp",
    "so3_exp_double_integral",
    "so3_hat",
    "so3_jacobian",
    "so3_log",
    "so3_vee",
    "strapdown_integrate",
    "strapdown_propagate",
    "text_parse_block",
]

_Rows = NDArray[np.float64]
# Names as the core declares them (named_enum!; listed at runtime by the *_SCHEMES tuples below);
# deprecated aliases parse too (a warning in the public API): attitude "midpoint" (= "rk2"),
# strapdown "euler" (= "lie_euler"). `| str`: any string is accepted, an unknown one raises
# ParameterError for that argument.
_AttitudeScheme = Literal["euler", "exp", "rk2", "rk4", "magnus", "midpoint"]
_Representation = Literal["quaternion", "matrix", "euler"]
_StrapdownScheme = Literal["lie_euler", "midpoint", "rk4", "exp", "euler"]
_Convention = Literal["hamilton", "jpl"]
_Jacobian = Literal["right", "right_inv", "left", "left_inv"]
_Side = Literal["left", "right"]

class _Noise(Protocol):  # imukit.ImuNoise
    @property
    def gyro_density(self) -> float: ...
    @property
    def accel_density(self) -> float: ...
    @property
    def gyro_random_walk(self) -> float: ...
    @property
    def accel_random_walk(self) -> float: ...

class _Bias(Protocol):  # imukit.ImuBias
    @property
    def gyro(self) -> ArrayLike: ...
    @property
    def accel(self) -> ArrayLike: ...

class _NavState(Protocol):  # imukit.NavState
    @property
    def position(self) -> ArrayLike: ...
    @property
    def velocity(self) -> ArrayLike: ...
    @property
    def rotation(self) -> Rotation: ...

__version__: str
# Default world-frame gravity [m/s²], z up: `imukit::imu::GRAVITY`, the one place it is written.
GRAVITY: tuple[float, float, float]
# Canonical names (tuples, in the core's order) and deprecated aliases ({old: canonical}).
ATTITUDE_SCHEMES: tuple[str, ...]
# `attitude::Options::default().scheme`.
ATTITUDE_DEFAULT_SCHEME: str
ATTITUDE_SCHEME_ALIASES: dict[str, str]
ATTITUDE_REPRESENTATIONS: tuple[str, ...]
STRAPDOWN_SCHEMES: tuple[str, ...]
# `strapdown::Options::default().scheme`.
STRAPDOWN_DEFAULT_SCHEME: str
STRAPDOWN_SCHEME_ALIASES: dict[str, str]
QUAT_CONVENTIONS: tuple[str, ...]
FILTER_WORLDS: tuple[str, ...]

# The process-wide thread count of the parallel kernels (default: rayon's, one per core). Every
# kernel below that takes `threads` runs on that many threads, None: on this process-wide count.
def set_num_threads(n: int) -> None: ...
def after_fork_in_child() -> None: ...
def get_num_threads() -> int: ...
def simd_path() -> str: ...

# imukit.torch's CPU kernels (crates/imukit/src/adjoint): C-contiguous float64 buffers read in
# place, h (B, N), w / a / a_end (B, N, 3), covariances (B, N, 3, 3) or noise_density (B, 2)
# (variance densities); without bar the records (B, N or 1, width), with bar (their
# cotangents) the input cotangents (B, N, grad_width).
def preint_adjoint(
    h: _Rows,
    w: _Rows,
    a: _Rows,
    *,
    bar: _Rows | None,
    a_end: _Rows | None,
    gyro_cov: _Rows | None,
    accel_cov: _Rows | None,
    noise_density: _Rows | None,
    per_step: bool,
    covariance: bool,
    jacobian: bool,
) -> _Rows: ...

# so3 / quat / euler row maps: `x` is a C-contiguous (n, k) float64 array, `name` the argument
# named in errors, `threads` the thread count; each returns a new (n, m) array. Bad rows raise
# with `exc.index` = the row.
def so3_hat(x: _Rows, name: str, threads: int | None = None) -> _Rows: ...  # (n, 3) -> (n, 9)
def so3_vee(x: _Rows, name: str, threads: int | None = None) -> _Rows: ...  # (n, 9) -> (n, 3)
def so3_exp(x: _Rows, name: str, threads: int | None = None) -> _Rows: ...  # (n, 3) -> (n, 9)
def so3_exp_double_integral(x: _Rows, name: str, threads: int | None = None) -> _Rows: ...  # (n, 3) -> (n, 9)
def so3_log(x: _Rows, name: str, threads: int | None = None) -> _Rows: ...  # (n, 9) -> (n, 3)
def so3_jacobian(
    x: _Rows, name: str, kind: _Jacobian | str, threads: int | None = None
) -> _Rows: ...  # (n, 3) -> (n, 9)
def quat_multiply(
    x: _Rows, name: str, convention: _Convention | str, threads: int | None = None
) -> _Rows: ...  # (n, 8) [q, p] -> (n, 4)
def quat_conjugate(x: _Rows, name: str, threads: int | None = None) -> _Rows: ...  # (n, 4) -> (n, 4)
def quat_inverse(x: _Rows, name: str, threads: int | None = None) -> _Rows: ...  # (n, 4) -> (n, 4)
def quat_normalize(x: _Rows, name: str, threads: int | None = None) -> _Rows: ...  # (n, 4) -> (n, 4)
def quat_rotate(x: _Rows, name: str, threads: int | None = None) -> _Rows: ...  # (n, 7) [q, v] -> (n, 3)
def quat_product_matrix(
    x: _Rows, name: str, side: _Side | str, convention: _Convention | str, threads: int | None = None
) -> _Rows: ...  # (n, 4) -> (n, 16)
def quat_omega_matrix(
    x: _Rows, name: str, convention: _Convention | str, threads: int | None = None
) -> _Rows: ...  # (n, 3) -> (n, 16)
def quat_exp(x: _Rows, name: str, threads: int | None = None) -> _Rows: ...  # (n, 3) -> (n, 4)
def quat_log(x: _Rows, name: str, threads: int | None = None) -> _Rows: ...  # (n, 4) -> (n, 3)
def euler_to_matrix(x: _Rows, name: str, threads: int | None = None) -> _Rows: ...  # (n, 3) ZYX -> (n, 9)
def euler_from_matrix(x: _Rows, name: str, threads: int | None = None) -> _Rows: ...  # (n, 9) -> (n, 3) ZYX
def euler_rate_matrix(
    x: _Rows, name: str, tolerance: float, threads: int | None = None
) -> _Rows: ...  # (n, 3) -> (n, 9)
def euler_rate_matrix_inv(x: _Rows, name: str, threads: int | None = None) -> _Rows: ...  # (n, 3) -> (n, 9)

# Attitudes (n, 4) xyzw from (n,) seconds and (n, 3) rates; (1, 4) with final_only. `initial` xyzw.
def attitude_integrate(
    t: _Rows,
    gyro: _Rows,
    initial: _Rows | list[float],
    scheme: _AttitudeScheme | str,
    representation: _Representation | str,
    gimbal_tolerance: float,
    final_only: bool,
    threads: int | None = None,
) -> _Rows: ...

# Strapdown: (N, 6) rows [p, v] and (N, 4) quaternions xyzw, row 0 = `initial`. `initial`,
# `bias` and `noise` are read by attribute name (imukit.NavState, ImuBias, ImuNoise).
def strapdown_integrate(
    t: _Rows,
    gyro: _Rows,
    accel: _Rows,
    initial: _NavState,
    bias: _Bias,
    gravity: list[float],
    scheme: _StrapdownScheme | str,
    earth_rate: list[float],
    threads: int | None,
) -> tuple[_Rows, _Rows]: ...

# (gyro, accel) (N, 3) at the body origin from a sensor at (R_bs rows, lever arm), biases removed.
def body_readings(
    t: _Rows,
    gyro: _Rows,
    accel: _Rows,
    bias: _Bias,
    rotation: list[list[float]],
    lever_arm: list[float],
) -> tuple[_Rows, _Rows]: ...

# As strapdown_integrate, plus (M, 225) row-major 15x15 covariances every `every` samples and at
# the last one, from the initial `covariance` (15, 15); `lever_arm` [m] (body axes) of readings
# already converted to the body origin, `transport` a frame that follows the vehicle (or None).
def strapdown_propagate(
    t: _Rows,
    gyro: _Rows,
    accel: _Rows,
    initial: _NavState,
    covariance: _Rows,
    bias: _Bias,
    noise: _Noise,
    gravity: list[float],
    scheme: _StrapdownScheme | str,
    every: int,
    earth_rate: list[float],
    lever_arm: list[float],
    transport: _LocalLevel | None,
) -> tuple[_Rows, _Rows, _Rows]: ...
def allan_variance(
    y: NDArray[np.float64], name: str, rate: float, clusters: list[int], overlapping: bool, threads: int | None = None
) -> tuple[NDArray[np.float64], NDArray[np.int64]]: ...  # (M, C) variances, (M,) term counts
def text_parse_block(
    block: bytes,
    first_line: int,
    separator: int | None,
    width: int,
    columns: list[int],
    stamp_column: int,
    stamp: str,
    stamp_required: bool,
    trailing: bool,
) -> tuple[
    NDArray[np.uint64],
    NDArray[np.uint64],
    NDArray[np.float64],
    NDArray[np.int64],
    bool,
    NDArray[np.uint64],
    NDArray[np.uint64],
    int,
]: ...  # rows' lines, offsets, (N, C) values, exact stamps, all exact, deferred lines, offsets, line count

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
class AccelLowPass:
    tau_s: float
    def __new__(cls, tau_s: _Number | None = None) -> AccelLowPass: ...
    def __getnewargs__(self) -> tuple[float, ...]: ...

@final
class AccelRejection:
    norm: float
    angle_rad: float
    recovery_s: float
    filtered_norm: float
    drift_s: float
    def __new__(
        cls,
        norm: _Number | None = None,
        angle_rad: _Number | None = None,
        recovery_s: _Number | None = None,
        filtered_norm: _Number | None = None,
        drift_s: _Number | None = None,
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
    max_bias: float
    def __new__(
        cls,
        gyro: _Number | None = None,
        accel: _Number | None = None,
        duration_s: _Number | None = None,
        tau_s: _Number | None = None,
        max_bias: _Number | None = None,
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
    full_rate_angle_rad: float
    def __new__(cls, beta: _Number | None = None, full_rate_angle_rad: _Number | None = None) -> MadgwickGains: ...
    def __getnewargs__(self) -> tuple[float, ...]: ...

@final
class FilterOptions:
    world: str
    gravity: float
    gain_ramp: GainRamp | None
    acc_lowpass: AccelLowPass | None
    acc_rejection: AccelRejection | None
    mag_rejection: MagRejection | None
    rest_detection: RestDetection | None
    mag_hold_s: float
    def __new__(
        cls,
        *,
        world: str,
        gravity: _Number,
        gain_ramp: GainRamp | None,
        acc_lowpass: AccelLowPass | None,
        acc_rejection: AccelRejection | None,
        mag_rejection: MagRejection | None,
        rest_detection: RestDetection | None,
        mag_hold_s: _Number | None = None,
    ) -> FilterOptions: ...
    @staticmethod
    def default() -> FilterOptions: ...
    def __getnewargs_ex__(self) -> tuple[tuple[()], dict[str, object]]: ...

@disjoint_base
class FilterState:
    def __new__(
        cls,
        state: FilterState | None = None,
        /,
        *,
        quaternion: list[float] | None = None,
        gyro_bias: list[float] | None = None,
        initialized: bool | None = None,
        time: float | None = None,
        ramp_elapsed: float | None = None,
        accel_rejected: float | None = None,
        mag_rejected: float | None = None,
        rest: float | None = None,
        mag_norm: float | None = None,
        mag_dip_sin: float | None = None,
        mag_dip_cos: float | None = None,
        acc_lp1: list[float] = ...,
        acc_lp2: list[float] = ...,
        gyro_lp: list[float] = ...,
        rest_gyro_ms: float = ...,
        rest_accel_lp: list[float] = ...,
        rest_accel_ms: float = ...,
        accel_calm: float = ...,
        accel_drift: bool = ...,
        mag_held: list[float] = ...,
        mag_held_s: float = ...,
        world: str | None = None,
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
    def acc_lp1(self) -> NDArray[np.float64]: ...
    @property
    def acc_lp2(self) -> NDArray[np.float64]: ...
    @property
    def gyro_lp(self) -> NDArray[np.float64]: ...
    @property
    def rest_gyro_ms(self) -> float: ...
    @property
    def rest_accel_lp(self) -> NDArray[np.float64]: ...
    @property
    def rest_accel_ms(self) -> float: ...
    @property
    def accel_calm(self) -> float: ...
    @property
    def accel_drift(self) -> bool: ...
    @property
    def mag_held(self) -> NDArray[np.float64]: ...
    @property
    def mag_held_s(self) -> float: ...
    @property
    def world(self) -> str | None: ...
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
PREINT_SCHEMES: tuple[str, ...]
# `preint::Scheme::default()`.
PREINT_DEFAULT_SCHEME: str
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
        clock: tuple[float, float],
        threads: int | None = None,
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
    kind: Literal["static", "constant_twist", "helix", "figure_eight", "vio_ellipse"],
    trajectory: Static | ConstantTwist | Helix | FigureEight | VioEllipse,
    t: NDArray[np.float64],
    gravity: list[float],
    threads: int | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]: ...
def sim_sensor_default() -> dict[str, Any]: ...

# Adds the Earth rate (R^T w) to `gyro` and the Coriolis term (R^T (2 w x v)) to `accel`, in place.
def sim_rotating_world(
    earth_rate: list[float],
    rotation: NDArray[np.float64],
    velocity: NDArray[np.float64],
    gyro: NDArray[np.float64],
    accel: NDArray[np.float64],
) -> None: ...

# The readings of a sensor at (R_bs rows, lever arm) on the body: gyro and accel (body) turned into
# the sensor's in place, with the body's angular acceleration `alpha` (N, 3).
def sim_sensor_pose(
    rotation: tuple[tuple[float, ...], ...],
    lever_arm: list[float],
    alpha: NDArray[np.float64],
    gyro: NDArray[np.float64],
    accel: NDArray[np.float64],
) -> None: ...

class _LocalLevel(Protocol):
    latitude: float
    height: float
    axes: str

# integrate over the WGS-84 ellipsoid in a frame that follows the vehicle: (N, 6) rows
# [latitude, longitude, height, v] and (N, 4) quaternions.
def ellipsoid_integrate(
    t: _Rows,
    gyro: _Rows,
    accel: _Rows,
    initial: _NavState,
    bias: _Bias,
    frame: _LocalLevel,
    scheme: _StrapdownScheme | str,
) -> tuple[_Rows, _Rows]: ...

# The readings of a motion flown over the ellipsoid from `start` (latitude, longitude, height):
# Earth rate, transport rate, Coriolis and gravity added to `gyro` / `accel` in place; returns the
# (N, 3) geodetic track.
def sim_ellipsoid(
    axes: str,
    start: list[float],
    t: _Rows,
    position: _Rows,
    velocity: _Rows,
    mid_position: _Rows,
    mid_velocity: _Rows,
    rotation: _Rows,
    gyro: _Rows,
    accel: _Rows,
) -> _Rows: ...

LOCAL_LEVEL_AXES: tuple[str, ...]

# (earth_rate, gravity) of a local-level frame read by field name; the core checks the values.
def local_level(frame: _LocalLevel) -> tuple[list[float], list[float]]: ...
def sim_measure(
    t: NDArray[np.float64],
    ideal: NDArray[np.float64],
    errors: SensorErrors,
    bias: NDArray[np.float64],
    density: float,
    random_walk: float,
    seed: int,
    triad: int,
    threads: int | None = None,
) -> NDArray[np.float64]: ...

@final
class RobustParams:
    def __new__(cls, **fields: float) -> RobustParams: ...
    def fields(self) -> dict[str, float]: ...
    def __getnewargs_ex__(self) -> tuple[tuple[()], dict[str, float]]: ...
    def __eq__(self, value: object, /) -> bool: ...

@disjoint_base
class RobustState:
    def __new__(cls, state: RobustState | None = None, /, **fields: float) -> Self: ...
    def fields(self) -> dict[str, float]: ...
    def __getnewargs_ex__(self) -> tuple[tuple[()], dict[str, float]]: ...
    def _at_time(self, time: float) -> RobustState: ...
    def __eq__(self, value: object, /) -> bool: ...
    @property
    def quaternion(self) -> NDArray[np.float64]: ...
    @property
    def gyro_bias(self) -> NDArray[np.float64]: ...
    @property
    def gyro_bias_sigma(self) -> NDArray[np.float64]: ...
    @property
    def initialized(self) -> bool: ...
    @property
    def time(self) -> float: ...

@final
class RobustFilter:
    def __new__(cls, params: RobustParams, world: str) -> RobustFilter: ...
    def __getnewargs__(self) -> tuple[RobustParams, str]: ...
    def initial_state(self, q: list[float] | None = None, time: float = 0.0) -> RobustState: ...
    def update(
        self, state: RobustState, gyro: list[float], accel: list[float], dt: float, mag: list[float] | None = None
    ) -> RobustState: ...
    def run(
        self,
        t: NDArray[np.float64],
        gyro: NDArray[np.float64],
        accel: NDArray[np.float64],
        mag: NDArray[np.float64] | None,
        state: RobustState,
        continued: bool,
        offline: bool,
        threads: int | None,
    ) -> tuple[
        NDArray[np.float64],
        NDArray[np.float64],
        NDArray[np.float64],
        NDArray[np.bool_],
        NDArray[np.bool_],
        RobustState,
    ]: ...

@final
class LeverNoise:
    @staticmethod
    def from_state(words: list[float]) -> LeverNoise: ...
    def __reduce__(self) -> tuple[Any, tuple[list[float]]]: ...
    def merge(self, next: LeverNoise) -> LeverNoise: ...
    def state(self) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64] | None]: ...

def lever_noise(
    imu: _ImuArrays,
    rotation: list[list[float]],
    lever_arm: list[float],
    boundaries: NDArray[np.float64],
    params: _PreintFields,
    threads: int | None,
) -> list[LeverNoise]: ...
