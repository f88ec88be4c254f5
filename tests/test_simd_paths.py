"""Runtime CPU dispatch (``crates/imukit/src/simd.rs``): each instruction-set path, forced with
``IMUKIT_SIMD`` in a fresh process (the choice is made once per process), gives the baseline
path's results to 1e-12 relative (per quantity: each column of a table of samples, each matrix of a
stack) on the deltas, covariances, bias Jacobians and states of
preintegrate (euler, midpoint, combined, windows, clipped samples), propagate and integrate (also
in a rotating local-level frame, with and without transport), integrate_attitude, on
the attitudes and biases of the filters (Mahony, Madgwick 6D / 9D; Robust online and offline, 6D /
9D), on Allan deviations and on sim.simulate's truth and readings (every sensor error on). The paths
compute the same operations in the same order, so they agree bit for bit, except the preintegration
step, whose AVX paths fuse its 3×3 block algebra into FMAs (one rounding where the baseline rounds
twice; measured ≤ 3e-15 relative). 1e-12 is the stated tolerance (a reassociated sum of a vectorised
path would still pass, a wrong lane or a dropped term not).
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import imukit as ik

from conftest import forced_path

# Run in the child: every dispatched kernel on one input, results saved to argv[1] (an .npz).
CHILD = """
import sys
import numpy as np
from scipy.spatial.transform import Rotation
import imukit as ik

rng = np.random.default_rng(7)
n = 70_001  # past two parallel euler chunks (2 * 2**15 intervals): the chunked path and merges
t = np.arange(n) * 0.005 + 0.002 * rng.random(n)
t.sort()
s = np.arange(n) * 0.005
gyro = np.c_[0.9 * np.sin(1.1 * s), 0.6 * np.cos(0.7 * s), 1.5 * np.sin(1.3 * s)] + 0.01 * rng.normal(size=(n, 3))
accel = np.c_[0.5 * np.sin(0.9 * s), 0.4 * np.cos(0.3 * s), 9.81 + np.sin(1.7 * s)] + 0.05 * rng.normal(size=(n, 3))
imu = ik.ImuData(t, gyro, accel)
noise = ik.ImuNoise(gyro_density=1.7e-4, accel_density=2e-3, gyro_random_walk=2e-5, accel_random_walk=3e-3)
bias = ik.ImuBias(gyro=[0.01, -0.02, 0.005], accel=[0.05, 0.02, -0.1])
initial = ik.NavState([1.0, 2.0, 3.0], [0.5, -0.2, 0.1], Rotation.from_rotvec([0.1, -0.3, 0.7]))
out = {"path": np.array(ik.simd_path())}
for scheme in ("euler", "midpoint"):
    p = ik.preintegrate(imu, noise=noise, bias=bias, scheme=scheme, combined=scheme == "midpoint")
    out[scheme + "_deltas"] = np.r_[p.delta_rotation.as_matrix().ravel(), p.delta_velocity, p.delta_position]
    out[scheme + "_covariance"] = p.covariance
    out[scheme + "_jacobian"] = p.bias_jacobian
    if p.covariance_combined is not None:
        out[scheme + "_combined"] = p.covariance_combined
combined = ik.preintegrate(imu, noise=noise, bias=bias, combined=True)
out["combined_covariance"] = combined.covariance_combined
windows = ik.preintegrate_windows(imu, t[::500], ik.PreintParams(noise, bias=bias, scheme="midpoint"))
out["windows_covariance"] = windows.covariance
out["windows_deltas"] = windows.delta_position
prop = ik.propagate(imu, initial=initial, covariance=np.eye(15) * 1e-4, noise=noise, bias=bias, covariance_every=997)
out["propagate_covariance"] = prop.covariance
out["propagate_position"] = prop.position
for scheme in ("midpoint", "rk4"):
    traj = ik.integrate(imu, initial=initial, bias=bias, scheme=scheme)
    out["integrate_" + scheme] = np.c_[traj.position, traj.velocity]
traj = ik.integrate(imu, initial=initial, bias=bias, scheme="lie_euler")
out["integrate_lie_euler"] = np.c_[traj.position, traj.velocity]
# The rotating-world loops; a frame that follows the vehicle starts at its own (latitude, 0, height).
at = ik.NavState([0.7, 0.0, 120.0], initial.velocity, initial.rotation)
for transport in (False, True):
    frame = ik.LocalLevel(0.7, 120.0, transport=transport)
    traj = ik.integrate(imu, initial=at, bias=bias, frame=frame)
    out[f"integrate_earth_{transport}"] = np.c_[traj.position, traj.velocity]
    prop = ik.propagate(
        imu, initial=at, covariance=np.eye(15) * 1e-4, noise=noise, bias=bias, covariance_every=997, frame=frame
    )
    out[f"propagate_earth_{transport}"] = prop.covariance
clipped = ik.ImuData(t, np.clip(gyro, -1.2, 1.2), np.clip(accel, -10.5, 10.5), gyro_range=1.2, accel_range=10.5)
p = ik.preintegrate(clipped, noise=noise, bias=bias)
out["preintegrate_clipped_deltas"] = np.r_[p.delta_velocity, p.delta_position]
out["preintegrate_clipped_covariance"] = p.covariance
out["allan_1"] = ik.noise.allan_deviation(gyro[:, 0], 200.0).deviation
out["allan_2"] = ik.noise.allan_deviation(gyro[:, :2], 200.0).deviation
out["attitude"] = ik.integrate_attitude(t, gyro).as_quat()
out["attitude_rk4"] = ik.integrate_attitude(t, gyro, scheme="rk4").as_quat()
out["allan"] = ik.noise.allan_deviation(gyro, 200.0).deviation
errors = ik.sim.SensorErrors(
    matrix=[[1.001, 2e-4, 0.0], [0.0, 0.998, -1e-4], [3e-4, 0.0, 1.0005]],
    turn_on_sigma=1e-3, gauss_markov_sigma=1e-3, gauss_markov_tau=30.0, range=4.0, resolution=1e-4,
)
sim_imu, sim_truth = ik.sim.simulate(
    ik.sim.FigureEight(), rate=200.0, duration=100.0, noise=noise, bias=bias, gyro_errors=errors, seed=3
)
sim_rows = (sim_imu.gyro, sim_imu.accel, sim_truth.position, sim_truth.velocity, sim_truth.rotation.as_quat())
out["simulate"] = np.concatenate(sim_rows, axis=1)
mag = np.c_[20.0 * np.cos(0.2 * s), 20.0 * np.sin(0.2 * s), np.full(n, -40.0)] + 0.2 * rng.normal(size=(n, 3))
for name, f in (("mahony", ik.filters.Mahony()), ("madgwick", ik.filters.Madgwick())):
    for dim, m in (("6d", None), ("9d", mag)):
        r = f.run(imu, mag=m)
        out[f"{name}_{dim}"] = np.c_[r.rotation.as_quat(canonical=True), r.gyro_bias]
for offline in (False, True):
    for dim, m in (("6d", False), ("9d", mag)):
        r = ik.filters.Robust().run(imu, mag=m, offline=offline)
        q = r.rotation.as_quat(canonical=True)
        out[f"robust_{dim}_{'offline' if offline else 'online'}"] = np.c_[q, r.gyro_bias, r.gyro_bias_sigma]
np.savez(sys.argv[1], **out)
"""


def _run(path: str, target: Path) -> dict[str, np.ndarray]:
    env = dict(os.environ, IMUKIT_SIMD=path, RAYON_NUM_THREADS="2")
    subprocess.run([sys.executable, "-c", CHILD, str(target)], env=env, check=True, timeout=600)
    with np.load(target) as data:
        return {k: data[k] for k in data.files}


@pytest.fixture(scope="module")
def results(tmp_path_factory: pytest.TempPathFactory) -> dict[str, dict[str, np.ndarray]]:
    folder = tmp_path_factory.mktemp("simd")
    return {p: _run(p, folder / f"{p}.npz") for p in ("baseline", "avx2", "avx512")}


def _relative_gap(a: np.ndarray, b: np.ndarray) -> float:
    """The largest difference relative to its own quantity's scale: per column of a table of
    samples (a quaternion's, a bias's, a σ's columns each against their own largest entry, not the
    quaternion's), per matrix of a stack (each covariance against its own largest entry), over the
    whole of a 1-D array. A quantity that is all zeros must be zero on both paths."""
    axes = (0,) if a.ndim == 2 else tuple(range(1, a.ndim)) if a.ndim > 2 else None
    scale = np.abs(a).max(axis=axes)
    gap = np.abs(a - b).max(axis=axes)
    assert np.all(gap[scale == 0] == 0), "an all-zero quantity differs"
    return float(np.max(gap[scale > 0] / scale[scale > 0], initial=0.0))


@pytest.mark.parametrize("path", ["avx2", "avx512"])
def test_each_path_gives_the_baseline_results(results: dict[str, dict[str, np.ndarray]], path: str) -> None:
    base, other = forced_path(results, "baseline"), forced_path(results, path)
    assert set(other) == set(base)
    for key in base:
        if key == "path":
            continue
        gap = _relative_gap(base[key], other[key])
        assert gap <= 1e-12, f"{key}: {gap:.2e} relative to the baseline path"


def test_a_forced_path_is_the_one_in_use_or_the_best_below_it(results: dict[str, dict[str, np.ndarray]]) -> None:
    order = ["baseline", "avx2", "avx512"]
    for forced, res in results.items():
        used = str(res["path"])
        assert order.index(used) <= order.index(forced), (forced, used)
    best = ik.simd_path() if "IMUKIT_SIMD" not in os.environ else None
    if best is not None:
        # Unforced, the best path the CPU has: a forced path at or below it is honoured.
        for forced, res in results.items():
            if order.index(forced) <= order.index(best):
                assert str(res["path"]) == forced


def test_an_unknown_path_name_is_refused_at_import_naming_the_variable() -> None:
    # Importing imukit raises, so no kernel can run the best path in its place; the class is
    # imukit's ParameterError (named by its module and name: the package did not import).
    code = (
        "try:\n    import imukit\nexcept Exception as e:\n"
        "    print(type(e).__module__, type(e).__name__, e.argument, str(e))"
    )
    env = dict(os.environ, IMUKIT_SIMD="sse9")
    done = subprocess.run([sys.executable, "-c", code], env=env, check=True, capture_output=True, text=True)
    module, name, argument, message = done.stdout.strip().split(" ", 3)
    assert (module, name, argument) == ("imukit", "ParameterError", "IMUKIT_SIMD")
    assert '"sse9"' in message and "'avx2'" in message


def test_auto_and_an_empty_value_choose_the_best_path() -> None:
    code = "import imukit as ik\nprint(ik.simd_path())"
    paths = []
    for value in ("auto", ""):
        env = dict(os.environ, IMUKIT_SIMD=value)
        done = subprocess.run([sys.executable, "-c", code], env=env, check=True, capture_output=True, text=True)
        paths.append(done.stdout.strip())
    unset = {k: v for k, v in os.environ.items() if k != "IMUKIT_SIMD"}
    done = subprocess.run([sys.executable, "-c", code], env=unset, check=True, capture_output=True, text=True)
    assert paths == [done.stdout.strip()] * 2
