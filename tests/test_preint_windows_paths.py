"""``preintegrate_windows`` on every forced instruction-set path (``IMUKIT_SIMD``, a fresh process
each) and on one and two threads, in both schemes, with and without the bias walk (``combined``):
each window equals ``preintegrate`` of the window's samples (the batch loop, another caller of the
per-sample kernel) within 1e-12 relative in deltas, covariance (the combined 15×15 one too) and
bias Jacobian; the thread count changes no bit; the paths agree with the baseline path within
1e-12. The windows hold 1, 2, 3, 5, 7, 9 … 200 intervals. On the AVX paths the windows run in the
SIMD lanes (docs/performance.md, "Structure of arrays"), on the baseline one window at a time.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from conftest import forced_path

FIELDS = ("delta_rotation", "delta_velocity", "delta_position", "covariance", "bias_jacobian")
# (scheme, combined) of each run; the combined runs add the 15×15 covariance.
CONFIGS = (("lie_euler", False), ("midpoint", False), ("lie_euler", True), ("midpoint", True))


def fields(combined: bool) -> tuple[str, ...]:
    return (*FIELDS, "covariance_combined") if combined else FIELDS


CHILD = """
import sys
import numpy as np
import imukit as ik

FIELDS = FIELDS_VALUE
CONFIGS = CONFIGS_VALUE
rng = np.random.default_rng(20)
n = 600
t = 0.3 + np.arange(n) * 0.005 + 1e-3 * rng.random(n)
s = t - t[0]
gyro = np.c_[0.9 * np.sin(1.1 * s) + 0.3, 0.6 * np.cos(0.7 * s), 1.5 * np.sin(1.3 * s)] + 0.05 * rng.normal(size=(n, 3))
accel = np.c_[0.5 * np.sin(0.9 * s), 0.4 * np.cos(0.3 * s), 9.81 + np.sin(1.7 * s)] + 0.05 * rng.normal(size=(n, 3))
imu = ik.ImuData(t, gyro, accel)
noise = ik.ImuNoise(gyro_density=1.7e-4, accel_density=2e-3, gyro_random_walk=2e-5, accel_random_walk=3e-3)
bias = ik.ImuBias(gyro=[0.01, -0.02, 0.005], accel=[0.05, 0.02, -0.1])
lengths = [1, 2, 3, 4, 5, 7, 8, 9, 17, 1, 2, 40, 3, 5, 9, 1, 7, 30, 6, 1, 2, 11, 200, 199, 3]
edges = np.cumsum([3] + lengths)
out = {"path": np.array(ik.simd_path()), "edges": edges}
for scheme, combined in CONFIGS:
    params = ik.PreintParams(noise, bias=bias, scheme=scheme, combined=combined)
    names = (*FIELDS, "covariance_combined") if combined else FIELDS
    key = f"{scheme}_{combined}"
    for threads in (1, 2):
        w = ik.preintegrate_windows(imu, t[edges], params, threads=threads)
        for name in names:
            out[f"{key}_{name}_{threads}"] = getattr(w, name)
    alone = [ik.preintegrate(imu[a : b + 1], params, threads=1) for a, b in zip(edges[:-1], edges[1:])]
    out[f"{key}_delta_rotation_alone"] = np.stack([p.delta_rotation.as_matrix() for p in alone])
    for name in names[1:]:
        out[f"{key}_{name}_alone"] = np.stack([getattr(p, name) for p in alone])
np.savez(sys.argv[1], **out)
""".replace("FIELDS_VALUE", repr(FIELDS)).replace("CONFIGS_VALUE", repr(CONFIGS))


def run(path: str, tmp: Path) -> dict[str, np.ndarray]:
    target = tmp / f"{path}.npz"
    env = dict(os.environ, IMUKIT_SIMD=path)
    subprocess.run([sys.executable, "-c", CHILD, str(target)], env=env, check=True)
    with np.load(target) as data:
        return dict(data)


@pytest.fixture(scope="module")
def paths(tmp_path_factory: pytest.TempPathFactory) -> dict[str, dict[str, np.ndarray]]:
    tmp = tmp_path_factory.mktemp("windows_paths")
    return {path: run(path, tmp) for path in ("baseline", "avx2", "avx512")}


def relative(a: np.ndarray, b: np.ndarray) -> float:
    """Largest difference per window over that window's largest entry."""
    axes = tuple(range(1, a.ndim))
    return float(np.max(np.max(np.abs(a - b), axis=axes) / np.max(np.abs(b), axis=axes)))


@pytest.mark.parametrize("config", CONFIGS, ids=lambda c: f"{c[0]}{'-combined' if c[1] else ''}")
@pytest.mark.parametrize("path", ["baseline", "avx2", "avx512"])
def test_windows_equal_the_per_sample_kernel(
    paths: dict[str, dict[str, np.ndarray]], path: str, config: tuple[str, bool]
) -> None:
    got, key = forced_path(paths, path), f"{config[0]}_{config[1]}"
    steps = np.diff(got["edges"])
    assert {1, 2, 3, 5, 7, 9} <= set(steps.tolist())
    for name in fields(config[1]):
        assert relative(got[f"{key}_{name}_1"], got[f"{key}_{name}_alone"]) < 1e-12, name


@pytest.mark.parametrize("config", CONFIGS, ids=lambda c: f"{c[0]}{'-combined' if c[1] else ''}")
@pytest.mark.parametrize("path", ["baseline", "avx2", "avx512"])
def test_windows_do_not_depend_on_the_thread_count(
    paths: dict[str, dict[str, np.ndarray]], path: str, config: tuple[str, bool]
) -> None:
    got, key = forced_path(paths, path), f"{config[0]}_{config[1]}"
    for name in fields(config[1]):
        np.testing.assert_array_equal(got[f"{key}_{name}_1"], got[f"{key}_{name}_2"], err_msg=name)


@pytest.mark.parametrize("config", CONFIGS, ids=lambda c: f"{c[0]}{'-combined' if c[1] else ''}")
@pytest.mark.parametrize("path", ["avx2", "avx512"])
def test_paths_agree_with_the_baseline_path(
    paths: dict[str, dict[str, np.ndarray]], path: str, config: tuple[str, bool]
) -> None:
    got, base, key = forced_path(paths, path), forced_path(paths, "baseline"), f"{config[0]}_{config[1]}"
    for name in fields(config[1]):
        assert relative(got[f"{key}_{name}_1"], base[f"{key}_{name}_1"]) < 1e-12, name
