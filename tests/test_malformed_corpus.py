"""Malformed-input corpus (issue 9): every public entry point that takes arrays, timestamps or
numeric options, driven with NaN, ±inf, subnormals, 1e300, empty and one-sample input, wrong
shapes and dtypes, odd memory layouts and broken timestamps (tests/malformed_strategies.py).

Each case must give the clean copy's exact result (valid odd layouts), or raise an
``imukit.ImukitError`` whose message starts with the argument's name, and never a panic or a NaN
from finite input. :func:`test_corpus_covers_every_public_entry_point` fails when a public
function or method has no entry here. The case count is printed in the pytest summary.
"""

from __future__ import annotations

import inspect
import math
import tempfile
import types
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

import imukit as ik
from imukit import filters, noise, sim
from malformed_strategies import EPOCH_NS, STATS, Arg, Entry, Expect, check_case, check_clean, mutations_of

EXAMPLES = 200  # random hypothesis examples per entry point, after the exhaustive sweep; one or two calls each

# ----------------------------------------------------------------------------- drawing valid calls


def batch(rng: np.random.Generator, tail: tuple[int, ...]) -> np.ndarray:
    lead = [(), (int(rng.integers(1, 5)),), (2, int(rng.integers(1, 4)))][int(rng.integers(3))]
    return rng.standard_normal((*lead, *tail))


def rotation_matrices(rng: np.random.Generator) -> np.ndarray:
    lead = int(rng.integers(1, 5))
    return Rotation.random(lead, rng=rng).as_matrix()


def stamps(rng: np.random.Generator, n: int) -> np.ndarray:
    return float(rng.uniform(0.0, 100.0)) + np.cumsum(rng.uniform(0.004, 0.006, n))


def imu_values(rng: np.random.Generator, n: int | None = None) -> dict[str, Any]:
    n = n or int(rng.integers(4, 12))
    return {
        "t": stamps(rng, n),
        "gyro": 0.5 * rng.standard_normal((n, 3)),
        "accel": np.array([0.0, 0.0, 9.81]) + 0.5 * rng.standard_normal((n, 3)),
    }


# A broken t may be reported on the arrays whose length it fixes; an overflow while integrating on
# the ImuData (the entry points' ``imu`` argument) and the bias together.
IMU_ARGS = {
    "t": Arg("times", names=("t", "gyro", "accel")),
    "gyro": Arg("array", names=("gyro", "imu")),
    "accel": Arg("array", names=("accel", "imu")),
}


def imu_of(v: dict[str, Any]) -> ik.ImuData:
    return ik.ImuData(v["t"], v["gyro"], v["accel"])


def state_values(rng: np.random.Generator, suffix: str = "") -> dict[str, Any]:
    return {
        "position" + suffix: rng.standard_normal(3),
        "velocity" + suffix: rng.standard_normal(3),
        "rotation" + suffix: Rotation.random(rng=rng),
    }


def state_args(suffix: str = "") -> dict[str, Arg]:
    return {
        "position" + suffix: Arg("array", names=("position",)),
        "velocity" + suffix: Arg("array", names=("velocity",)),
        "rotation" + suffix: Arg("rotation", names=("rotation",)),
    }


def state_of(v: dict[str, Any], suffix: str = "") -> ik.NavState:
    return ik.NavState(v["position" + suffix], v["velocity" + suffix], v["rotation" + suffix])


def bias_values(rng: np.random.Generator) -> dict[str, Any]:
    return {"bias_gyro": 0.01 * rng.standard_normal(3), "bias_accel": 0.1 * rng.standard_normal(3)}


BIAS_ARGS = {"bias_gyro": Arg("array", names=("gyro", "bias")), "bias_accel": Arg("array", names=("accel", "bias"))}


def bias_of(v: dict[str, Any]) -> ik.ImuBias:
    return ik.ImuBias(v["bias_gyro"], v["bias_accel"])


NOISE = ik.ImuNoise(1.7e-4, 2e-3, 1.9e-5, 3e-3)
_TRAJECTORY_OPTIONS = ("covariance", "covariance_t", "gyro_bias", "accel_bias")


def pick(values: dict[str, Any], *names: str) -> dict[str, Any]:
    """The keyword arguments ``names`` from a case's values."""
    return {name: values[name] for name in names}


# AllanFit's model methods flatten taus of any shape (a scalar included).
_ANY_SHAPE = tuple((label, Expect.EITHER) for label in ("0-d", "empty", "extra leading axis", "flattened"))

# ----------------------------------------------------------------------------- the entries

ENTRIES: list[Entry] = []


def entry(name: str, covers: tuple[str, ...], args: dict[str, Arg], **options: Any) -> Callable[..., Any]:
    """Register ``make`` (decorated) and ``call`` (its return value's "call") as one entry."""

    def register(make: Callable[[np.random.Generator], tuple[dict[str, Any], Callable[[dict[str, Any]], Any]]]) -> Any:
        def make_values(rng: np.random.Generator) -> dict[str, Any]:
            return make(rng)[0]

        def call(v: dict[str, Any]) -> Any:
            return v["__call__"](v)

        def make_with_call(rng: np.random.Generator) -> dict[str, Any]:
            values, fn = make(rng)
            return {**values, "__call__": fn}

        ENTRIES.append(Entry(name, covers, make_with_call, call, args, **options))
        return make_values

    return register


def batched_entry(module: types.ModuleType, fn_name: str, arg: str, tail: tuple[int, ...], **kw: Any) -> None:
    fn = getattr(module, fn_name)
    qual = f"{module.__name__.removeprefix('imukit.')}.{fn_name}"

    def make(rng: np.random.Generator) -> tuple[dict[str, Any], Callable[[dict[str, Any]], Any]]:
        value = rotation_matrices(rng) if tail == (3, 3) and fn_name in ("log", "from_rotation") else batch(rng, tail)
        options = {k: (draw(rng) if callable(draw) else draw) for k, draw in kw.items()}
        return {arg: value}, lambda v: fn(v[arg], **options)

    entry(qual + (f"[{', '.join(kw)}]" if kw else ""), (qual,), {arg: Arg("batch", tail)})(make)


def _flag(rng: np.random.Generator) -> bool:
    return bool(rng.integers(2))


for _name in (
    "hat",
    "exp",
    "right_jacobian",
    "right_jacobian_inv",
    "left_jacobian",
    "left_jacobian_inv",
    "exp_double_integral",
):
    batched_entry(ik.so3, _name, "phi", (3,))
batched_entry(ik.so3, "vee", "matrix", (3, 3))
batched_entry(ik.so3, "log", "rotation", (3, 3))
for _name in ("conjugate", "inverse", "normalize", "log"):
    batched_entry(ik.quat, _name, "q", (4,), scalar_first=_flag)
batched_entry(ik.quat, "exp", "phi", (3,), scalar_first=_flag)
batched_entry(ik.quat, "left_matrix", "q", (4,), scalar_first=_flag, convention="jpl")
batched_entry(ik.quat, "right_matrix", "p", (4,), scalar_first=_flag)
batched_entry(ik.quat, "omega_matrix", "w", (3,), scalar_first=_flag, convention="jpl")
batched_entry(ik.euler, "to_rotation", "angles", (3,), degrees=_flag)
batched_entry(ik.euler, "from_rotation", "rotation", (3, 3), degrees=_flag)
batched_entry(ik.euler, "rate_matrix_inv", "angles", (3,), degrees=_flag)


@entry("quat.multiply", ("quat.multiply",), {"q": Arg("batch", (4,)), "p": Arg("batch", (4,))})
def _multiply(rng: np.random.Generator) -> Any:
    q = batch(rng, (4,))
    conv, sf = ("hamilton", "jpl")[int(rng.integers(2))], _flag(rng)
    return {"q": q, "p": rng.standard_normal(q.shape)}, lambda v: ik.quat.multiply(
        v["q"], v["p"], convention=conv, scalar_first=sf
    )


@entry("quat.rotate", ("quat.rotate",), {"q": Arg("batch", (4,)), "v": Arg("batch", (3,))})
def _rotate(rng: np.random.Generator) -> Any:
    q = batch(rng, (4,))
    return {"q": q, "v": rng.standard_normal((*q.shape[:-1], 3))}, lambda v: ik.quat.rotate(v["q"], v["v"])


@entry("euler.rate_matrix", ("euler.rate_matrix",), {"angles": Arg("batch", (3,)), "tolerance_rad": Arg("scalar")})
def _rate_matrix(rng: np.random.Generator) -> Any:
    return {"angles": 0.5 * batch(rng, (3,)), "tolerance_rad": 1e-6}, lambda v: ik.euler.rate_matrix(
        v["angles"], tolerance_rad=v["tolerance_rad"]
    )


@entry(
    "integrate_attitude",
    ("integrate_attitude",),
    {
        "t": Arg("times", names=("t", "gyro")),
        "gyro": Arg("array"),
        "initial": Arg("rotation", optional=True),
        "gimbal_tolerance_rad": Arg("scalar"),
    },
)
def _integrate_attitude(rng: np.random.Generator) -> Any:
    v = imu_values(rng)
    scheme = ik.attitude.SCHEMES[int(rng.integers(5))]
    rep = (
        ("quaternion", "matrix", "euler")[int(rng.integers(3))] if scheme in ("euler", "midpoint", "rk4") else "matrix"
    )
    final = _flag(rng)
    values = {"t": v["t"], "gyro": v["gyro"], "initial": Rotation.random(rng=rng), "gimbal_tolerance_rad": 1e-6}
    return values, lambda v: ik.integrate_attitude(
        v["t"],
        v["gyro"],
        initial=v["initial"],
        scheme=scheme,
        representation=rep,
        final_only=final,
        gimbal_tolerance_rad=v["gimbal_tolerance_rad"],
    )


# `simd_path` takes no argument; its one input, the IMUKIT_SIMD variable, is refused when
# malformed in tests/test_simd_paths.py (a process of its own: the choice is made once).
@entry("set_num_threads", ("set_num_threads", "get_num_threads", "simd_path"), {"n": Arg("int")})
def _set_num_threads(rng: np.random.Generator) -> Any:
    before = ik.get_num_threads()

    def call(v: dict[str, Any]) -> Any:
        try:
            ik.set_num_threads(v["n"])
            assert ik.simd_path() in ("avx512", "avx2", "baseline")
            return np.array([float(ik.get_num_threads())])
        finally:
            ik.set_num_threads(before)

    return {"n": 2}, call


@entry(
    "ImuData",
    ("ImuData",),
    {
        **IMU_ARGS,
        "max_gap": Arg("scalar", optional=True, names=("max_gap", "t")),
        "gyro_range": Arg("scalar", optional=True),
        "accel_range": Arg("scalar", optional=True),
    },
)
def _imu_data(rng: np.random.Generator) -> Any:
    v = imu_values(rng)

    def call(v: dict[str, Any]) -> Any:
        imu = ik.ImuData(v["t"], v["gyro"], v["accel"], **pick(v, "max_gap", "gyro_range", "accel_range"))
        return imu, imu.gyro_saturated, imu.accel_saturated

    return {**v, "max_gap": 1.0, "gyro_range": 0.5, "accel_range": 20.0}, call


@entry("ImuBias", ("ImuBias",), BIAS_ARGS)
def _imu_bias(rng: np.random.Generator) -> Any:
    return bias_values(rng), bias_of


_NOISE_KEYS = ("gyro_density", "accel_density", "gyro_random_walk", "accel_random_walk")


@entry("ImuNoise", ("ImuNoise", "ImuNoise.from_kalibr"), {k: Arg("scalar") for k in _NOISE_KEYS})
def _imu_noise(rng: np.random.Generator) -> Any:
    kalibr = (
        "gyroscope_noise_density",
        "accelerometer_noise_density",
        "gyroscope_random_walk",
        "accelerometer_random_walk",
    )

    def call(v: dict[str, Any]) -> Any:
        return ik.ImuNoise(**{k: v[k] for k in _NOISE_KEYS}), ik.ImuNoise.from_kalibr(
            **{name: v[k] for name, k in zip(kalibr, _NOISE_KEYS)}
        )

    return {k: float(rng.uniform(0, 1e-2)) for k in _NOISE_KEYS}, call


@entry(
    "ImuNoise.from_discrete / to_discrete_sigmas / discrete",
    ("ImuNoise.from_discrete", "ImuNoise.to_discrete_sigmas", "ImuNoise.discrete"),
    {
        "gyro_sigma": Arg("scalar", names=("gyro_sigma", "gyro_density")),
        # A tiny rate makes huge densities, whose variances overflow in discrete(): named there.
        "rate_hz": Arg("scalar", names=("rate_hz", "gyro_density")),
        "dt": Arg("scalar"),
    },
)
def _imu_noise_discrete(rng: np.random.Generator) -> Any:
    def call(v: dict[str, Any]) -> Any:
        n = ik.ImuNoise.from_discrete(
            gyro_sigma=v["gyro_sigma"],
            accel_sigma=0.03,
            gyro_walk_sigma=1e-6,
            accel_walk_sigma=2e-4,
            rate_hz=v["rate_hz"],
        )
        return n, n.to_discrete_sigmas(v["rate_hz"]), n.discrete(v["dt"])

    return {"gyro_sigma": 2.4e-3, "rate_hz": 200.0, "dt": 0.005}, call


@entry("NavState", ("NavState",), state_args())
def _nav_state(rng: np.random.Generator) -> Any:
    return state_values(rng), state_of


@entry(
    "Trajectory",
    ("Trajectory", "Trajectory.state"),
    {
        "t": Arg("times", names=("t", "position")),
        "position": Arg("array"),
        "velocity": Arg("array", optional=True),
        "rotation": Arg("rotations"),
        "covariance": Arg("array", optional=True),
        "covariance_t": Arg("times", optional=True, names=("covariance_t", "covariance")),
        "gyro_bias": Arg("array", optional=True),
        "accel_bias": Arg("array", optional=True),
        "k": Arg("int", index=True),
    },
)
def _trajectory(rng: np.random.Generator) -> Any:
    n = int(rng.integers(2, 8))
    t = stamps(rng, n)
    a = rng.standard_normal((n, 15, 15))
    values = {
        "t": t,
        "position": rng.standard_normal((n, 3)),
        "velocity": rng.standard_normal((n, 3)),
        "rotation": Rotation.random(n, rng=rng),
        "covariance": a @ np.swapaxes(a, 1, 2),
        "covariance_t": t.copy(),
        "gyro_bias": rng.standard_normal((n, 3)),
        "accel_bias": rng.standard_normal((n, 3)),
        "k": int(rng.integers(-n, n)),
    }

    def call(v: dict[str, Any]) -> Any:
        traj = ik.Trajectory(v["t"], v["position"], v["velocity"], v["rotation"], **pick(v, *_TRAJECTORY_OPTIONS))
        return traj, traj.state(v["k"])

    return values, call


@entry(
    "Trajectory(t=None, t_ns=...)", ("Trajectory",), {"t_ns": Arg("times", names=("t_ns", "t"))}, clean_is_valid=False
)
def _trajectory_ns(rng: np.random.Generator) -> Any:
    n = int(rng.integers(2, 8))
    position, rotation = rng.standard_normal((n, 3)), Rotation.random(n, rng=rng)
    # Float stamps are mutated into integer ones (and back): every float here must be refused.
    return {"t_ns": stamps(rng, n)}, lambda v: ik.Trajectory(None, position, None, rotation, t_ns=v["t_ns"])


@entry(
    "Trajectory(t=..., t_ns=...)",
    ("Trajectory",),
    {"t": Arg("times", optional=True, names=("t", "t_ns")), "t_ns": Arg("times", optional=True)},
)
def _trajectory_both_clocks(rng: np.random.Generator) -> Any:
    """Seconds and nanoseconds of the same instants: a mutated clock (relative seconds against epoch
    nanoseconds, floats as t_ns, ...) must be refused, never silently paired."""
    n = int(rng.integers(2, 8))
    t_ns = EPOCH_NS + np.cumsum(rng.integers(4_000_000, 6_000_000, n))
    position, rotation = rng.standard_normal((n, 3)), Rotation.random(n, rng=rng)
    values = {"t": t_ns / 1e9, "t_ns": t_ns}
    return values, lambda v: ik.Trajectory(v["t"], position, None, rotation, t_ns=v["t_ns"])


def _strapdown_values(rng: np.random.Generator) -> dict[str, Any]:
    return {**imu_values(rng), **state_values(rng), **bias_values(rng), "gravity": np.array([0.0, 0.0, -9.81])}


_STRAPDOWN_ARGS = {**IMU_ARGS, **state_args(), **BIAS_ARGS, "gravity": Arg("array")}


@entry("integrate", ("integrate",), _STRAPDOWN_ARGS)
def _integrate(rng: np.random.Generator) -> Any:
    scheme = ik.strapdown.SCHEMES[int(rng.integers(4))]
    return _strapdown_values(rng), lambda v: ik.integrate(
        imu_of(v), initial=state_of(v), gravity=v["gravity"], bias=bias_of(v), scheme=scheme
    )


_LAT, _HEIGHT = 0.7, 120.0


@entry(
    "integrate(frame=LocalLevel(transport=True))",
    ("integrate", "LocalLevel"),
    {**IMU_ARGS, "velocity": Arg("array"), "rotation": Arg("rotation"), **BIAS_ARGS},
)
def _integrate_transport(rng: np.random.Generator) -> Any:
    """Over the ellipsoid: the state's position is geodetic, fixed at the frame's start here (a
    different start is refused, tested in test_transport.py)."""
    scheme = ("midpoint", "rk4")[int(rng.integers(2))]
    frame = ik.LocalLevel(_LAT, _HEIGHT, ("enu", "ned")[int(rng.integers(2))], transport=True)
    values = {**imu_values(rng), **state_values(rng), **bias_values(rng)}
    del values["position"]
    return values, lambda v: ik.integrate(
        imu_of(v),
        initial=ik.NavState(np.array([_LAT, 0.2, _HEIGHT]), v["velocity"], v["rotation"]),
        bias=bias_of(v),
        scheme=scheme,
        frame=frame,
    )


@entry(
    "propagate",
    ("propagate",),
    {**_STRAPDOWN_ARGS, "covariance": Arg("array"), "covariance_every": Arg("int"), "noise": Arg("object")},
)
def _propagate(rng: np.random.Generator) -> Any:
    scheme = ik.strapdown.SCHEMES[int(rng.integers(4))]
    values = {**_strapdown_values(rng), "covariance": np.eye(15) * 1e-4, "covariance_every": 2, "noise": NOISE}
    return values, lambda v: ik.propagate(
        imu_of(v),
        initial=state_of(v),
        covariance=v["covariance"],
        noise=v["noise"],
        bias=bias_of(v),
        gravity=v["gravity"],
        scheme=scheme,
        covariance_every=v["covariance_every"],
    )


@entry(
    "propagate(frame=LocalLevel)",
    ("propagate", "LocalLevel"),
    {
        **{k: a for k, a in _STRAPDOWN_ARGS.items() if k != "gravity"},
        "covariance": Arg("array"),
        "latitude": Arg("scalar", names=("latitude", "frame")),
    },
)
def _propagate_frame(rng: np.random.Generator) -> Any:
    values = {**_strapdown_values(rng), "covariance": np.eye(15) * 1e-4, "latitude": float(rng.uniform(-1.5, 1.5))}
    del values["gravity"]
    axes = ("enu", "ned")[int(rng.integers(2))]
    return values, lambda v: ik.propagate(
        imu_of(v),
        initial=state_of(v),
        covariance=v["covariance"],
        noise=NOISE,
        bias=bias_of(v),
        frame=ik.LocalLevel(v["latitude"], 0.0, axes),
    )


@entry(
    "propagate(frame=LocalLevel(transport=True))",
    ("propagate", "LocalLevel"),
    {**IMU_ARGS, "velocity": Arg("array"), "rotation": Arg("rotation"), **BIAS_ARGS, "covariance": Arg("array")},
)
def _propagate_transport(rng: np.random.Generator) -> Any:
    """As integrate's over the ellipsoid, with the covariance."""
    frame = ik.LocalLevel(_LAT, _HEIGHT, ("enu", "ned")[int(rng.integers(2))], transport=True)
    values = {**imu_values(rng), **state_values(rng), **bias_values(rng), "covariance": np.eye(15) * 1e-4}
    del values["position"]
    return values, lambda v: ik.propagate(
        imu_of(v),
        initial=ik.NavState(np.array([_LAT, 0.2, _HEIGHT]), v["velocity"], v["rotation"]),
        covariance=v["covariance"],
        noise=NOISE,
        bias=bias_of(v),
        frame=frame,
    )


@entry(
    "propagate with a lever arm",
    ("propagate",),
    {
        **IMU_ARGS,
        **state_args(),
        "gravity": Arg("array"),
        "covariance": Arg("array"),
        "rotation_bs": Arg("rotation", names=("body_from_sensor",)),
        "lever_arm": Arg("array", names=("body_from_sensor",)),
    },
)
def _propagate_lever_arm(rng: np.random.Generator) -> Any:
    """No bias mutations: the conversion removes the bias first, so an overflow it causes names
    ``imu`` (as in ``integrate(body_from_sensor=)``; not yet traced back to the bias)."""
    values = {
        **{k: v for k, v in _strapdown_values(rng).items() if not k.startswith("bias")},
        "covariance": np.eye(15) * 1e-4,
        "rotation_bs": Rotation.random(rng=rng),
        "lever_arm": rng.normal(0.0, 0.3, 3),
    }
    return values, lambda v: ik.propagate(
        imu_of(v),
        initial=state_of(v),
        covariance=v["covariance"],
        noise=NOISE,
        gravity=v["gravity"],
        body_from_sensor=(v["rotation_bs"], v["lever_arm"]),
    )


_PREINT_ARGS = {**IMU_ARGS, **BIAS_ARGS, "gravity": Arg("array"), "noise": Arg("object")}


def _preint_values(rng: np.random.Generator) -> dict[str, Any]:
    return {**imu_values(rng), **bias_values(rng), "gravity": np.array([0.0, 0.0, -9.81]), "noise": NOISE}


def _pim(v: dict[str, Any], scheme: str, combined: bool) -> ik.PreintegratedImu:
    return ik.PreintegratedImu(
        noise=v["noise"], bias=bias_of(v), gravity=v["gravity"], scheme=scheme, combined=combined
    )


@entry("preintegrate", ("preintegrate", "PreintegratedImu", "PreintegratedImu.integrate"), _PREINT_ARGS)
def _preintegrate(rng: np.random.Generator) -> Any:
    scheme, combined = ("midpoint", "euler")[int(rng.integers(2))], _flag(rng)
    return _preint_values(rng), lambda v: ik.preintegrate(
        imu_of(v), noise=v["noise"], bias=bias_of(v), gravity=v["gravity"], scheme=scheme, combined=combined
    )


@entry(
    "preintegrate with a lever arm",
    ("preintegrate",),
    {
        **_PREINT_ARGS,
        "t": Arg("times", names=("t", "gyro", "accel", "span")),
        "rotation": Arg("rotation", names=("body_from_sensor",)),
        "lever_arm": Arg("array", names=("body_from_sensor",)),
        "span": Arg("array", names=("span",), optional=True),
    },
)
def _preintegrate_lever_arm(rng: np.random.Generator) -> Any:
    scheme = ("midpoint", "lie_euler")[int(rng.integers(2))]
    values = {**_preint_values(rng), "rotation": Rotation.random(rng=rng), "lever_arm": rng.normal(0.0, 0.3, 3)}
    values["span"] = np.array([values["t"][1], values["t"][-1]])  # the edges see a neighbour
    return values, lambda v: _lever_arm_call(v, scheme)


def _lever_arm_call(v: dict[str, Any], scheme: str) -> Any:
    return ik.preintegrate(
        imu_of(v),
        noise=v["noise"],
        bias=bias_of(v),
        gravity=v["gravity"],
        scheme=scheme,
        body_from_sensor=(v["rotation"], v["lever_arm"]),
        span=v["span"],
    )


@entry(
    "preintegrate_windows",
    ("preintegrate_windows",),
    {
        **_PREINT_ARGS,
        "t": Arg("times", names=("t", "gyro", "accel", "boundaries")),
        "boundaries": Arg("array", free_length=True),
        "threads": Arg("int", optional=True),
    },
)
def _preintegrate_windows(rng: np.random.Generator) -> Any:
    v = _preint_values(rng)
    t = v["t"]
    m = int(rng.integers(2, 5))
    boundaries = np.sort(rng.uniform(t[0], t[-1], m))
    boundaries[0], boundaries[-1] = t[0], t[-1]
    scheme = ("midpoint", "euler")[int(rng.integers(2))]
    return {**v, "boundaries": np.unique(boundaries), "threads": 1}, lambda v: ik.preintegrate_windows(
        imu_of(v),
        v["boundaries"],
        noise=v["noise"],
        bias=bias_of(v),
        gravity=v["gravity"],
        scheme=scheme,
        threads=v["threads"],
    )


@entry(
    "PreintParams and Preintegration",
    ("PreintParams", "PreintParams.replace", "PreintegratedImu.snapshot", "Preintegration"),
    _PREINT_ARGS,
)
def _preint_params(rng: np.random.Generator) -> Any:
    scheme = ("midpoint", "lie_euler")[int(rng.integers(2))]

    def call(v: dict[str, Any]) -> Any:
        params = ik.PreintParams(v["noise"], bias_of(v), v["gravity"], scheme).replace(combined=True)
        s = ik.preintegrate(imu_of(v), params).snapshot()
        fields = (s.delta_rotation, s.delta_velocity, s.delta_position, s.delta_t, s.covariance, s.bias_jacobian)
        return ik.Preintegration(*fields, s.covariance_combined, s.t_start, s.t_end, params)

    return _preint_values(rng), call


@entry(
    "PreintegratedImu.integrate_measurement",
    ("PreintegratedImu.integrate_measurement",),
    {"m_accel": Arg("array", names=("accel",)), "m_gyro": Arg("array", names=("gyro",)), "dt": Arg("scalar")},
)
def _integrate_measurement(rng: np.random.Generator) -> Any:
    scheme = ("midpoint", "euler")[int(rng.integers(2))]

    def call(v: dict[str, Any]) -> Any:
        pim = ik.PreintegratedImu(noise=NOISE, scheme=scheme, combined=True)
        pim.integrate_measurement([0.0, 0.0, 9.81], [0.1, 0.0, 0.0], 0.0 if scheme == "midpoint" else 0.005)
        pim.integrate_measurement(v["m_accel"], v["m_gyro"], v["dt"])
        return pim

    return {"m_accel": rng.standard_normal(3), "m_gyro": rng.standard_normal(3), "dt": 0.005}, call


def _preint_method_values(rng: np.random.Generator) -> dict[str, Any]:
    return {**_preint_values(rng), **state_values(rng, "_i"), **state_values(rng, "_j"), **bias_values(rng)}


_METHOD_ARGS = {**state_args("_i"), **state_args("_j"), **BIAS_ARGS}


@entry(
    "PreintegratedImu methods",
    (
        "PreintegratedImu.reintegrate",
        "PreintegratedImu.merge",
        "PreintegratedImu.corrected",
        "PreintegratedImu.predict",
        "PreintegratedImu.residual",
        "PreintegratedImu.residual_jacobians",
    ),
    {**_METHOD_ARGS, "other": Arg("object")},
)
def _preint_methods(rng: np.random.Generator) -> Any:
    values = _preint_method_values(rng)
    imu = imu_of(values)
    scheme = ("midpoint", "euler")[int(rng.integers(2))]
    half = len(imu) // 2
    pim = ik.preintegrate(imu[: half + 1], noise=NOISE, scheme=scheme)
    second = ik.preintegrate(imu[half:], noise=NOISE, scheme=scheme)  # starts with pim's last sample

    def call(v: dict[str, Any]) -> Any:
        bias, s_i, s_j = bias_of(v), state_of(v, "_i"), state_of(v, "_j")
        return (
            pim.reintegrate(bias),
            pim.merge(v["other"]),
            pim.corrected(bias),
            pim.predict(s_i, bias),
            pim.residual(s_i, s_j, bias),
            pim.residual_jacobians(s_i, s_j, bias),
        )

    return {**values, "other": second}, call


# -- simulation


def _simulate(motion: Callable[[dict[str, Any]], Any], v: dict[str, Any], **kw: Any) -> Any:
    return sim.simulate(motion(v), rate=50.0, duration=0.2, **kw)


_ROT = Rotation.from_rotvec([0.1, -0.2, 0.3])


@entry("sim.Static", ("sim.Static",), {"position": Arg("array"), "rotation": Arg("rotation")})
def _static(rng: np.random.Generator) -> Any:
    return {"position": rng.standard_normal(3), "rotation": Rotation.random(rng=rng)}, lambda v: _simulate(
        lambda v: sim.Static(v["position"], v["rotation"]), v
    )


@entry(
    "sim.ConstantTwist",
    ("sim.ConstantTwist",),
    {"body_velocity": Arg("array"), "body_rate": Arg("array"), "position": Arg("array"), "rotation": Arg("rotation")},
)
def _twist(rng: np.random.Generator) -> Any:
    values = {
        "body_velocity": rng.standard_normal(3),
        "body_rate": rng.standard_normal(3),
        "position": rng.standard_normal(3),
        "rotation": Rotation.random(rng=rng),
    }
    return values, lambda v: _simulate(
        lambda v: sim.ConstantTwist(v["body_velocity"], v["body_rate"], v["position"], v["rotation"]), v
    )


for _cls in (sim.Helix, sim.Circle):

    @entry(
        f"sim.{_cls.__name__}",
        (f"sim.{_cls.__name__}",),
        {"radius": Arg("scalar"), "angular_rate": Arg("scalar"), "climb_rate": Arg("scalar"), "center": Arg("array")},
    )
    def _helix(rng: np.random.Generator, cls: Any = _cls) -> Any:
        values = {"radius": 5.0, "angular_rate": 0.5, "climb_rate": 0.2, "center": rng.standard_normal(3)}
        return values, lambda v: _simulate(
            lambda v: cls(
                radius=v["radius"], angular_rate=v["angular_rate"], climb_rate=v["climb_rate"], center=v["center"]
            ),
            v,
        )


def periodic_motion_entry(cls: type, amplitude: tuple[float, ...], scalars: dict[str, float]) -> None:
    """FigureEight and VioEllipse: an amplitude and a center vector plus scalar parameters."""

    def make(rng: np.random.Generator) -> Any:
        values = {"amplitude": np.array(amplitude), "center": rng.standard_normal(3), **scalars}
        return values, lambda v: _simulate(lambda v: cls(**{k: v[k] for k in ("amplitude", "center", *scalars)}), v)

    args = {"amplitude": Arg("array"), "center": Arg("array"), **{k: Arg("scalar") for k in scalars}}
    entry(f"sim.{cls.__name__}", (f"sim.{cls.__name__}",), args)(make)


periodic_motion_entry(sim.FigureEight, (10.0, 5.0, 1.0), {"angular_rate": 0.2, "roll": 0.3, "pitch": 0.2})
periodic_motion_entry(
    sim.VioEllipse, (15.0, 20.0, 1.0), {"angular_rate": 0.3, "height_frequency": 10.0, "roll": 0.1, "pitch": 0.2}
)


@entry(
    "sim.Waypoints",
    ("sim.Waypoints",),
    {
        # Waypoint times are seconds whatever the dtype (not nanoseconds as for IMU stamps).
        "times": Arg("times", names=("times", "duration"), relabel=(("sample indices as ints", Expect.EITHER),)),
        "positions": Arg("array"),
        "rotations": Arg("rotations"),
    },
)
def _waypoints(rng: np.random.Generator) -> Any:
    m = int(rng.integers(2, 6))
    times = np.linspace(0.0, 1.0, m) + np.r_[0.0, rng.uniform(-0.02, 0.02, m - 2), 0.0]
    values = {
        "times": times,
        "positions": rng.standard_normal((len(times), 3)),
        "rotations": Rotation.random(len(times), rng=rng),
    }
    return values, lambda v: _simulate(lambda v: sim.Waypoints(v["times"], v["positions"], v["rotations"]), v)


_SENSOR = ("turn_on_sigma", "gauss_markov_sigma", "gauss_markov_tau", "range", "resolution")


@entry(
    "sim.simulate(frame=LocalLevel(transport=True))",
    ("sim.simulate",),
    {"body_velocity": Arg("array"), "body_rate": Arg("array"), "rotation": Arg("rotation")},
)
def _simulate_transport(rng: np.random.Generator) -> Any:
    frame = ik.LocalLevel(_LAT, _HEIGHT, ("enu", "ned")[int(rng.integers(2))], transport=True)
    values = {
        "body_velocity": 100.0 * rng.standard_normal(3),
        "body_rate": rng.standard_normal(3),
        "rotation": Rotation.random(rng=rng),
    }
    return values, lambda v: _simulate(
        lambda v: sim.ConstantTwist(v["body_velocity"], v["body_rate"], rotation=v["rotation"]), v, frame=frame
    )


@entry(
    "sim.simulate(body_from_sensor=...)",
    ("sim.simulate",),
    {"lever_arm": Arg("array", names=("body_from_sensor",)), "rotation": Arg("rotation", names=("body_from_sensor",))},
)
def _simulate_sensor_pose(rng: np.random.Generator) -> Any:
    values = {"lever_arm": 0.3 * rng.standard_normal(3), "rotation": Rotation.random(rng=rng)}
    motion = sim.ConstantTwist((1.0, 0.0, 0.2), (0.1, -0.05, 2.0))
    return values, lambda v: sim.simulate(
        motion, rate=50.0, duration=0.2, body_from_sensor=(v["rotation"], v["lever_arm"])
    )


@entry(
    "sim.simulate with SensorErrors",
    ("sim.simulate", "sim.SensorErrors", "sim.SensorErrors.from_scale_misalignment"),
    {
        "rate": Arg("scalar", names=("rate", "duration")),
        "duration": Arg("scalar"),
        "start": Arg("scalar"),
        "seed": Arg("int"),
        "gravity": Arg("array"),
        "matrix": Arg("array"),
        "scale": Arg("array"),
        "misalignment": Arg("array"),
        "noise": Arg("object", optional=True),
        **BIAS_ARGS,
        **{k: Arg("scalar", names=(k, "gyro_errors")) for k in _SENSOR},
    },
)
def _simulate_errors(rng: np.random.Generator) -> Any:
    mis = 1e-3 * rng.standard_normal((3, 3))
    np.fill_diagonal(mis, 0.0)
    values = {
        "rate": 50.0,
        "duration": 0.2,
        "start": float(rng.uniform(0, 10)),
        "seed": int(rng.integers(2**32)),
        "gravity": np.array([0.0, 0.0, -9.81]),
        "matrix": np.eye(3) + 1e-3 * rng.standard_normal((3, 3)),
        "scale": 1e-3 * rng.standard_normal(3),
        "misalignment": mis,
        "noise": NOISE,
        **bias_values(rng),
        "turn_on_sigma": 1e-3,
        "gauss_markov_sigma": 1e-3,
        "gauss_markov_tau": 10.0,
        "range": 20.0,
        "resolution": 1e-4,
    }

    def call(v: dict[str, Any]) -> Any:
        gyro_errors = sim.SensorErrors(matrix=v["matrix"], **{k: v[k] for k in _SENSOR})
        accel_errors = sim.SensorErrors.from_scale_misalignment(v["scale"], v["misalignment"])
        return sim.simulate(
            sim.Helix(),
            rate=v["rate"],
            duration=v["duration"],
            noise=v["noise"],
            bias=bias_of(v),
            gyro_errors=gyro_errors,
            accel_errors=accel_errors,
            gravity=v["gravity"],
            seed=v["seed"],
            start=v["start"],
        )

    return values, call


# -- noise


@entry(
    "LocalLevel",
    ("LocalLevel", "earth.LocalLevel"),
    {"latitude": Arg("scalar"), "height": Arg("scalar")},
)
def _local_level(rng: np.random.Generator) -> Any:
    values = {"latitude": float(rng.uniform(-1.5, 1.5)), "height": float(rng.uniform(-100.0, 3000.0))}
    axes = ("enu", "ned")[int(rng.integers(2))]
    moving = bool(rng.integers(2))
    return values, lambda v: ik.LocalLevel(v["latitude"], v["height"], axes, transport=moving).gravity


@entry(
    "noise.moving_seconds", ("noise.moving_seconds",), {**IMU_ARGS, "gyro_threshold": Arg("scalar", names=("gyro",))}
)
def _moving_seconds(rng: np.random.Generator) -> Any:
    return {**imu_values(rng), "gyro_threshold": 0.05}, lambda v: noise.moving_seconds(
        imu_of(v), gyro=v["gyro_threshold"]
    )


@entry("filters.in_world", ("filters.in_world",), {"attitude": Arg("batch", (4,), nan_ok=True)})
def _in_world(rng: np.random.Generator) -> Any:
    world = ("ENU", "NED")[int(rng.integers(2))]
    return {"attitude": batch(rng, (4,))}, lambda v: ik.filters.in_world(v["attitude"], world)


@entry("noise.mean_rate_hz", ("noise.mean_rate_hz",), IMU_ARGS)
def _mean_rate(rng: np.random.Generator) -> Any:
    return imu_values(rng), lambda v: noise.mean_rate_hz(imu_of(v))


@entry(
    "noise.allan_deviation",
    ("noise.allan_deviation",),
    {
        "x": Arg("signal"),
        "rate": Arg("scalar", names=("rate", "taus")),
        "taus": Arg("array", optional=True, free_length=True),
    },
)
def _allan(rng: np.random.Generator) -> Any:
    n = int(rng.integers(8, 40))
    x = rng.standard_normal((n, int(rng.integers(1, 4)))) if _flag(rng) else rng.standard_normal(n)
    taus = np.array([1.0, 2.0]) / 10.0
    overlapping = _flag(rng)
    return {"x": x, "rate": 10.0, "taus": taus}, lambda v: noise.allan_deviation(
        v["x"], v["rate"], taus=v["taus"], overlapping=overlapping
    )


def _allan_result(rng: np.random.Generator) -> noise.AllanDeviation:
    return noise.allan_deviation(rng.standard_normal((400, 2)), 100.0)


@entry(
    "noise.fit_allan",
    (
        "noise.fit_allan",
        "noise.AllanDeviation",
        "noise.AllanFit.variance",
        "noise.AllanFit.deviation",
        "noise.AllanFit.components",
        "noise.to_imu_noise",
    ),
    {
        "deviation": Arg("array", names=("allan",)),
        "taus": Arg("array", names=("allan",)),
        "confidence": Arg("scalar"),
        "tau_min": Arg("scalar", optional=True, names=("tau_min", "allan")),
        "tau_max": Arg("scalar", optional=True, names=("tau_max", "allan")),
        "eval_taus": Arg("array", free_length=True, names=("taus",), relabel=_ANY_SHAPE),
        "gyro": Arg("object"),
    },
    examples=60,  # each fit iterates a weighted least squares
)
def _fit_allan(rng: np.random.Generator) -> Any:
    allan = _allan_result(rng)
    gyro_fit = noise.fit_allan(allan, sensor="gyro")

    def call(v: dict[str, Any]) -> Any:
        a = allan._replace(deviation=v["deviation"], taus=v["taus"])
        fit = noise.fit_allan(a, sensor="accel", confidence=v["confidence"], tau_min=v["tau_min"], tau_max=v["tau_max"])
        taus = v["eval_taus"]
        return (
            fit,
            fit.variance(taus),
            fit.deviation(taus),
            fit.components(taus),
            noise.to_imu_noise(gyro=v["gyro"], accel=fit),
        )

    values = {
        "deviation": allan.deviation,
        "taus": allan.taus,
        "confidence": 0.9,
        "tau_min": None,
        "tau_max": None,
        "eval_taus": np.array([0.01, 0.5, 2.0]),
        "gyro": gyro_fit,
    }
    return values, call


def _calibration_states(rng: np.random.Generator, m: int, suffix: str) -> dict[str, Any]:
    return {
        "position" + suffix: rng.standard_normal((m, 3)),
        "velocity" + suffix: rng.standard_normal((m, 3)),
        "rotation" + suffix: Rotation.random(m, rng=rng).as_matrix(),
    }


@entry(
    "noise.calibrate_from_residuals",
    ("noise.calibrate_from_residuals",),
    {
        # so3.log names a matrix that is not a rotation "rotation" (the residual takes both states).
        **{
            f"{f}_{e}": Arg("array", names=(f"state_{e}", "windows", f))
            for f in ("position", "velocity", "rotation")
            for e in "ij"
        },
        "confidence": Arg("scalar"),
    },
)
def _calibrate(rng: np.random.Generator) -> Any:
    imu, _ = sim.simulate(sim.FigureEight(), rate=100.0, duration=0.4, noise=NOISE, seed=int(rng.integers(2**32)))
    windows = ik.preintegrate_windows(imu, imu.t[[0, 20, 40]], ik.PreintParams(NOISE))  # 0.2 s each

    def call(v: dict[str, Any]) -> Any:
        def states(e: str) -> ik.preint.States:
            return ik.preint.States(v[f"position_{e}"], v[f"velocity_{e}"], v[f"rotation_{e}"])

        return noise.calibrate_from_residuals(windows, states("i"), states("j"), confidence=v["confidence"])

    values = {**_calibration_states(rng, 2, "_i"), **_calibration_states(rng, 2, "_j"), "confidence": 0.9}
    return values, call


_PLOTS = tempfile.TemporaryDirectory(prefix="imukit-corpus-")  # removed when the module is collected


@entry(
    "noise.plot_allan",
    ("noise.plot_allan",),
    {"allan": Arg("object"), "fit": Arg("object", optional=True)},
    examples=6,  # matplotlib draws each in 0.1 s
)
def _plot_allan(rng: np.random.Generator) -> Any:
    allan = _allan_result(rng)
    path = Path(_PLOTS.name) / "allan.png"
    return {"allan": allan, "fit": noise.fit_allan(allan)}, lambda v: noise.plot_allan(v["allan"], path, fit=v["fit"])


# -- filters


def _filter(kind: str, v: dict[str, Any]) -> filters.Mahony | filters.Madgwick:
    options = {
        "gravity": v["f_gravity"],
        "gain_ramp": filters.GainRamp(v["ramp_duration_s"], v["ramp_factor"]),
        "acc_lowpass": filters.AccelLowPass(v["acc_lowpass_tau_s"]),
        "acc_rejection": filters.AccelRejection(v["acc_norm"], v["acc_angle_rad"], v["acc_recovery_s"]),
        "mag_rejection": filters.MagRejection(v["mag_norm_fraction"], v["mag_dip_rad"], v["mag_recovery_s"]),
        "rest_detection": filters.RestDetection(v["rest_gyro"], v["rest_accel"], v["rest_duration_s"], v["rest_tau_s"]),
    }
    if kind == "mahony":
        return filters.Mahony(kp=v["gain"], ki=v["ki"], **options)
    return filters.Madgwick(beta=v["gain"], **options)


_FILTER_SCALARS = {
    "gain": 0.5,
    "ki": 0.01,
    "f_gravity": 9.81,
    "ramp_duration_s": 3.0,
    "ramp_factor": 10.0,
    "acc_lowpass_tau_s": 1.0,
    "acc_norm": 4.0,
    "acc_angle_rad": 0.5,
    "acc_recovery_s": 5.0,
    "mag_norm_fraction": 0.1,
    "mag_dip_rad": 0.17,
    "mag_recovery_s": 10.0,
    "rest_gyro": 0.05,
    "rest_accel": 0.2,
    "rest_duration_s": 1.0,
    "rest_tau_s": 1.0,
}
_FILTER_NAMES = {
    "gain": ("kp", "beta", "gains"),
    "f_gravity": ("gravity",),
    "ramp_duration_s": ("gain_ramp",),
    "ramp_factor": ("gain_ramp", "gains"),  # the ramp multiplies the gains
    "acc_lowpass_tau_s": ("acc_lowpass",),
    **{k: ("acc_rejection",) for k in ("acc_norm", "acc_angle_rad", "acc_recovery_s")},
    **{k: ("mag_rejection",) for k in ("mag_norm_fraction", "mag_dip_rad", "mag_recovery_s")},
    **{k: ("rest_detection",) for k in ("rest_gyro", "rest_accel", "rest_duration_s", "rest_tau_s")},
}
_FILTER_ARGS = {k: Arg("scalar", names=_FILTER_NAMES.get(k, (k,))) for k in _FILTER_SCALARS}
_FILTER_COVERS = (
    "filters.GainRamp",
    "filters.AccelLowPass",
    "filters.AccelRejection",
    "filters.MagRejection",
    "filters.RestDetection",
)

for _kind, _cls_name in (("mahony", "Mahony"), ("madgwick", "Madgwick")):

    @entry(
        f"filters.{_cls_name}.run",
        (f"filters.{_cls_name}", f"filters.{_cls_name}.run", *_FILTER_COVERS),
        {
            **{k: Arg(a.role, names=(*(a.names or (k,)), "imu")) for k, a in IMU_ARGS.items()},
            **{k: a for k, a in _FILTER_ARGS.items() if k != "ki" or _kind == "mahony"},
            "mag": Arg("array", optional=True),
            "initial": Arg("rotation", optional=True),
        },
    )
    def _run(rng: np.random.Generator, kind: str = _kind) -> Any:
        v = imu_values(rng)
        values = {**v, **_FILTER_SCALARS, "mag": rng.standard_normal(v["gyro"].shape), "initial": None}
        return values, lambda v: _filter(kind, v).run(imu_of(v), mag=v["mag"], initial=v["initial"])

    @entry(
        f"filters.{_cls_name}.update",
        (*(f"filters.{_cls_name}.{m}" for m in ("update", "get_state", "set_state", "reset")), "filters.FilterState"),
        {
            "u_gyro": Arg("array", names=("gyro",)),
            "u_accel": Arg("array", names=("accel",)),
            "dt": Arg("scalar"),
            "u_mag": Arg("array", optional=True, names=("mag",)),
            "state_values": Arg("array", names=("state",)),
            "initial": Arg("rotation", optional=True),
        },
    )
    def _update(rng: np.random.Generator, kind: str = _kind) -> Any:
        template = _filter(kind, _FILTER_SCALARS)
        template.update([0.0, 0.0, 0.0], [0.0, 0.0, 9.81], 0.01)
        values = {
            "u_gyro": 0.1 * rng.standard_normal(3),
            "u_accel": np.array([0.0, 0.0, 9.81]) + rng.standard_normal(3),
            "dt": 0.01,
            "u_mag": rng.standard_normal(3),
            "state_values": template.get_state().values.copy(),
            "initial": Rotation.random(rng=rng),
        }

        def call(v: dict[str, Any]) -> Any:
            f = _filter(kind, _FILTER_SCALARS)
            f.reset(v["initial"])
            first = f.update(v["u_gyro"], v["u_accel"], v["dt"], v["u_mag"])
            f.set_state(filters.FilterState(v["state_values"]))
            second = f.update(v["u_gyro"], v["u_accel"], v["dt"], v["u_mag"])
            return first, second, f.get_state()

        return values, call


@entry(
    "filters.Robust.run",
    ("filters.Robust", "filters.Robust.run"),
    {
        **{k: Arg(a.role, names=(*(a.names or (k,)), "imu")) for k, a in IMU_ARGS.items()},
        "mag": Arg("array", optional=True),
        "initial": Arg("rotation", optional=True),
    },
)
def _robust_run(rng: np.random.Generator) -> Any:
    v = imu_values(rng)
    values = {**v, "mag": rng.standard_normal(v["gyro"].shape), "initial": None}
    return values, lambda v: filters.Robust().run(imu_of(v), mag=v["mag"], initial=v["initial"])


@entry(
    "filters.Robust.update",
    (*(f"filters.Robust.{m}" for m in ("update", "get_state", "set_state", "reset")), "filters.RobustState"),
    {
        "u_gyro": Arg("array", names=("gyro",)),
        "u_accel": Arg("array", names=("accel",)),
        "dt": Arg("scalar"),
        "u_mag": Arg("array", optional=True, names=("mag",)),
        "initial": Arg("rotation", optional=True),
    },
)
def _robust_update(rng: np.random.Generator) -> Any:
    values = {
        "u_gyro": 0.1 * rng.standard_normal(3),
        "u_accel": np.array([0.0, 0.0, 9.81]) + rng.standard_normal(3),
        "dt": 0.01,
        "u_mag": rng.standard_normal(3),
        "initial": Rotation.random(rng=rng),
    }

    def call(v: dict[str, Any]) -> Any:
        f = filters.Robust()
        f.reset(v["initial"])
        first = f.update(v["u_gyro"], v["u_accel"], v["dt"], v["u_mag"])
        f.set_state(filters.RobustState(**f.get_state().fields()))
        second = f.update(v["u_gyro"], v["u_accel"], v["dt"], v["u_mag"])
        return first, second, f.get_state()

    return values, call


# -- evaluation


def _traj_values(rng: np.random.Generator, prefix: str, n: int, t0: float) -> dict[str, Any]:
    return {
        prefix + "t": t0 + np.arange(n) * 0.1,
        prefix + "position": np.cumsum(rng.standard_normal((n, 3)), axis=0),
        prefix + "rotation": Rotation.random(n, rng=rng),
    }


def _traj_args(prefix: str) -> dict[str, Arg]:
    return {
        prefix + "t": Arg("times", names=("t", "estimate", "reference", "position", "rotation")),
        prefix + "position": Arg("array", names=("position", prefix.rstrip("_"))),
        prefix + "rotation": Arg("rotations", names=("rotation", prefix.rstrip("_"))),
    }


def _traj_of(v: dict[str, Any], prefix: str) -> ik.Trajectory:
    return ik.Trajectory(v[prefix + "t"], v[prefix + "position"], None, v[prefix + "rotation"])


@entry(
    "eval.attitude_error",
    ("eval.attitude_error", "eval.AttitudeError.rmse"),
    {
        "estimate": Arg("array"),
        "truth": Arg("array", nan_ok=True),
        "mask": Arg("mask", optional=True),
        "rmse_mask": Arg("mask", optional=True, names=("mask",)),
    },
)
def _attitude_error(rng: np.random.Generator) -> Any:
    n = int(rng.integers(2, 10))
    align = _flag(rng)
    values = {
        "estimate": Rotation.random(n, rng=rng).as_quat(),
        "truth": Rotation.random(n, rng=rng).as_quat(),
        "mask": np.ones(n, dtype=bool),
        "rmse_mask": np.ones(n, dtype=bool),
    }

    def call(v: dict[str, Any]) -> Any:
        err = ik.eval.attitude_error(v["estimate"], v["truth"], mask=v["mask"], align_heading=align)
        return err, err.rmse(v["rmse_mask"])

    return values, call


if hasattr(ik.eval, "ape"):  # imukit.eval's trajectory metrics (issue 8)

    @entry(
        "eval.associate / align / ape / rpe / truth_at_imu",
        tuple(f"eval.{n}" for n in ("associate", "align", "ape", "rpe", "Alignment.apply", "truth_at_imu")),
        {
            **_traj_args("estimate_"),
            **_traj_args("reference_"),
            "max_dt": Arg("scalar", names=("max_dt", "estimate")),
            "offset": Arg("scalar", names=("offset", "estimate")),
            "delta": Arg("scalar"),
        },
    )
    def _trajectory_metrics(rng: np.random.Generator) -> Any:
        n = int(rng.integers(4, 12))
        values = {
            **_traj_values(rng, "estimate_", n, 10.0),
            **_traj_values(rng, "reference_", n + 2, 9.9),
            "max_dt": 0.2,
            "offset": 0.0,
            "delta": 0.2,
        }

        def call(v: dict[str, Any]) -> Any:
            est, ref = _traj_of(v, "estimate_"), _traj_of(v, "reference_")
            assoc = ik.eval.associate(est, ref, max_dt=v["max_dt"], offset=v["offset"])
            alignment = ik.eval.align(assoc[0], assoc[1], method="se3")
            return (
                assoc,
                alignment,
                alignment.apply(est),
                ik.eval.ape(est, ref, max_dt=v["max_dt"], offset=v["offset"]),
                ik.eval.rpe(est, ref, delta=v["delta"], unit="s", max_dt=v["max_dt"]),
                ik.eval.truth_at_imu(ref, est.t, max_dt=v["max_dt"]),
            )

        return values, call


if hasattr(ik.eval, "time_offset"):

    def _turn(t: np.ndarray, axis: np.ndarray) -> tuple[np.ndarray, Rotation]:
        """A turn about ``axis`` at a varying rate: the rates and the rotations at ``t``."""
        rate = 1.5 + np.sin(1.3 * t) + 0.5 * np.sin(3.7 * t + 0.4)
        angle = 1.5 * t - np.cos(1.3 * t) / 1.3 - 0.5 * np.cos(3.7 * t + 0.4) / 3.7
        return rate[:, None] * axis, Rotation.from_rotvec(angle[:, None] * axis)

    # A corrupted speed (one huge sample) may put the correlation's peak on the window's edge,
    # which is reported on max_offset; a broken IMU may also be reported as the motion ("imu").
    @entry(
        "eval.time_offset",
        ("eval.time_offset",),
        {
            "t": Arg("times", names=("t", "gyro", "accel", "imu", "reference", "max_offset")),
            "gyro": Arg("array", names=("gyro", "imu", "max_offset")),
            "accel": Arg("array", names=("accel", "imu")),
            "reference_t": Arg("times", names=("t", "reference", "position", "rotation", "imu", "max_offset")),
            "reference_position": Arg("array", names=("position", "reference")),
            "reference_rotation": Arg("rotations", names=("rotation", "reference")),
            "max_offset": Arg("scalar", names=("max_offset", "imu")),
        },
    )
    def _time_offset(rng: np.random.Generator) -> Any:
        axis = Rotation.random(rng=rng).apply([0.0, 0.0, 1.0])
        lag = float(rng.uniform(-0.02, 0.02))
        t = 0.5 + np.arange(int(rng.integers(500, 700))) * 0.005
        t_ref = np.arange(0.0, t[-1] + 0.5, 1.0 / 120.0)
        values = {
            "t": t,
            "gyro": _turn(t - lag, axis)[0],
            "accel": np.tile([0.0, 0.0, 9.81], (len(t), 1)),
            "reference_t": t_ref,
            "reference_position": np.zeros((len(t_ref), 3)),
            "reference_rotation": _turn(t_ref, axis)[1],
            "max_offset": 0.08,
        }

        def call(v: dict[str, Any]) -> Any:
            imu = ik.ImuData(v["t"], v["gyro"], v["accel"])
            ref = _traj_of(v, "reference_")
            return ik.eval.time_offset(imu, ref, max_offset=v["max_offset"])

        return values, call


# ----------------------------------------------------------------------------- the tests


@pytest.mark.parametrize("corpus_entry", ENTRIES, ids=[e.name for e in ENTRIES])
def test_malformed_inputs(corpus_entry: Entry) -> None:
    failures: list[str] = []
    per_example = corpus_entry.examples or EXAMPLES

    @settings(
        max_examples=per_example,
        deadline=None,
        derandomize=True,
        database=None,
        suppress_health_check=list(HealthCheck),
    )
    @given(seed=st.integers(0, 2**32 - 1), pick=st.integers(0, 2**32 - 1), mutate=st.integers(0, 2**32 - 1))
    def run(seed: int, pick: int, mutate: int) -> None:
        rng = np.random.default_rng(seed)
        values = corpus_entry.make(rng)
        names = sorted(corpus_entry.args)
        if pick % 8 == 0 and corpus_entry.clean_is_valid:
            problem = check_clean(corpus_entry, values)
        else:
            arg_name = names[pick % len(names)]
            options = mutations_of(corpus_entry.args[arg_name], values[arg_name], rng)
            problem = check_case(corpus_entry, values, arg_name, options[mutate % len(options)])
        if problem:
            failures.append(problem)

    # Every mutation through every argument once (fixed draw), then the random examples above.
    rng = np.random.default_rng(20261122)
    values = corpus_entry.make(rng)
    for arg_name, arg in sorted(corpus_entry.args.items()):
        for mutation in mutations_of(arg, values[arg_name], rng):
            problem = check_case(corpus_entry, values, arg_name, mutation)
            if problem:
                failures.append(problem)
    run()
    STATS.failures += len(failures)
    assert not failures, f"{len(failures)} failing cases:\n" + "\n".join(sorted(set(failures))[:40])


def _public(module: types.ModuleType, prefix: str) -> Iterator[tuple[str, Any]]:
    for name in getattr(module, "__all__", ()):
        obj = getattr(module, name)
        yield prefix + name, obj
        if inspect.isclass(obj) and not issubclass(obj, BaseException):
            for member in dir(obj):
                if member.startswith("_"):
                    continue
                static = inspect.getattr_static(obj, member)
                if isinstance(static, (types.FunctionType, classmethod, staticmethod)):
                    yield f"{prefix}{name}.{member}", static


# Public names that are not entry points for arrays, timestamps or numeric options, with why.
NOT_ENTRY_POINTS = {
    "io": "file readers and writers: malformed files are fuzzed (fuzz/) and tested in tests/test_io_*.py",
    "Trajectory.write_tum": "writes a validated Trajectory to a path (imukit.io)",
    "ResidualJacobians": "a plain record returned by PreintegratedImu.residual_jacobians",
    "filters.FilterResult": "a plain record returned by run",
    "filters.RobustResult": "a plain record returned by run",
    "noise.AllanFit": "the result of fit_allan (its methods are covered)",
    "noise.NoiseCalibration": "the result of calibrate_from_residuals (a record; its property reads its fields)",
    "sim.Motion": "a typing alias of the motion classes",
}


def _exempt(name: str, obj: Any) -> bool:
    if name in NOT_ENTRY_POINTS or name.split(".")[0] in NOT_ENTRY_POINTS:
        return True
    if isinstance(obj, types.ModuleType) or (inspect.isclass(obj) and issubclass(obj, BaseException)):
        return True
    if inspect.isclass(obj) and issubclass(obj, tuple) and name not in {n for e in ENTRIES for n in e.covers}:
        return True  # result records (NamedTuples); options NamedTuples are covered by their consumers
    return not callable(obj) and not isinstance(obj, (classmethod, staticmethod))


def public_entry_points() -> list[str]:
    found = []
    for name in ik.__all__:
        obj = getattr(ik, name)
        if isinstance(obj, types.ModuleType):
            found += [n for n, o in _public(obj, name + ".") if not _exempt(n, o)]
        else:
            found += [n for n, o in _public(ik, "") if n.split(".")[0] == name and not _exempt(n, o)]
    return sorted(set(found))


def test_corpus_covers_every_public_entry_point() -> None:
    covered = {n for e in ENTRIES for n in e.covers}
    missing = [n for n in public_entry_points() if n not in covered]
    assert not missing, f"public entry points without malformed-input corpus entries: {missing}"
    stale = sorted(covered - set(public_entry_points()))
    assert not stale, f"corpus entries for names that are not public: {stale}"


def test_a_panic_or_a_nan_would_be_caught() -> None:
    """The checker itself: a NaN result from finite input, a wrong exception type and a
    BaseException (like pyo3's PanicException) are all reported as failures."""

    class FakePanic(BaseException):
        pass

    def panics(v: dict[str, Any]) -> Any:
        raise FakePanic("index out of bounds")

    def nan(v: dict[str, Any]) -> Any:
        return np.array([math.nan])

    def value_error(v: dict[str, Any]) -> Any:
        raise ValueError("x: bad")

    for fn, text in ((panics, "PANIC FakePanic"), (nan, "NaN or inf in"), (value_error, "raised ValueError")):
        e = Entry("fake", (), lambda rng: {"x": np.zeros(3)}, fn, {"x": Arg("array")})
        mutation = mutations_of(e.args["x"], np.zeros(3), np.random.default_rng(0))[0]
        cases = STATS.cases
        problem = check_case(e, {"x": np.zeros(3)}, "x", mutation)
        STATS.cases = cases  # not a corpus case
        assert problem is not None and text in problem, problem
