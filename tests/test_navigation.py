"""Navigation on the rotating Earth: ``imukit.LocalLevel``, ``sim.simulate(..., frame=)`` and
``integrate(..., frame=)``.

Expected values are written here from the published models, not read from imukit: the Earth rate
in ENU / NED axes (Groves 2013, eq. 2.123), WGS-84 normal gravity by Somigliana's formula with
the TR8350.2 constants, and the drift of a resting IMU integrated without the Earth model in closed
form (the attitude turns with the Earth, ``R(t) = Exp(ω t) R₀``).
"""

from __future__ import annotations

import math
import pickle

import numpy as np
import numpy.typing as npt
import pytest
from scipy.spatial.transform import Rotation

import imukit as ik

Array = npt.NDArray[np.float64]
OMEGA = 7.292115e-5


def somigliana(latitude: float) -> float:
    """WGS-84 normal gravity on the ellipsoid (TR8350.2 eq. 4-1): γ_e (1 + k sin²φ)/√(1 − e² sin²φ)."""
    s2 = math.sin(latitude) ** 2
    return 9.7803253359 * (1 + 0.00193185265241 * s2) / math.sqrt(1 - 0.00669437999014 * s2)


@pytest.mark.parametrize("latitude", [0.0, 45.0, 89.0])
def test_local_level_earth_rate_and_gravity(latitude: float) -> None:
    phi = math.radians(latitude)
    enu = ik.LocalLevel(latitude, degrees=True)
    ned = ik.LocalLevel(phi, 0.0, "ned")
    assert np.allclose(enu.earth_rate, OMEGA * np.array([0, math.cos(phi), math.sin(phi)]), rtol=0, atol=1e-19)
    assert np.allclose(ned.earth_rate, OMEGA * np.array([math.cos(phi), 0, -math.sin(phi)]), rtol=0, atol=1e-19)
    assert enu.gravity[2] == pytest.approx(-somigliana(phi), abs=1e-9)
    assert ned.gravity[2] == pytest.approx(somigliana(phi), abs=1e-9)
    # 1 km up: the free-air gradient, about −3.086e-6 s⁻²
    high = ik.LocalLevel(latitude, 1000.0, degrees=True)
    assert (high.gravity[2] - enu.gravity[2]) / 1000.0 == pytest.approx(3.086e-6, rel=2e-3)
    assert pickle.loads(pickle.dumps(enu)).earth_rate.tolist() == enu.earth_rate.tolist()


def test_local_level_values_are_checked_by_the_core() -> None:
    with pytest.raises(ik.ParameterError, match="latitude"):
        ik.LocalLevel(91.0, degrees=True)
    with pytest.raises(ik.ParameterError, match="axes"):
        ik.LocalLevel(0.5, axes="nwu")
    with pytest.raises(ik.ParameterError, match="frame"):
        ik.integrate(ik.ImuData(np.arange(3.0), np.zeros((3, 3)), np.zeros((3, 3))), initial=_rest(), frame="enu")
    # At a pole a fixed frame is fine, one that follows the vehicle has no north: refused when built.
    assert ik.LocalLevel(90.0, degrees=True).latitude == pytest.approx(np.pi / 2)
    for pole in (90.0, -90.0):
        with pytest.raises(ik.ParameterError, match=r"^latitude: .*poles") as raised:
            ik.LocalLevel(pole, degrees=True, transport=True)
        assert raised.value.argument == "latitude"
    assert ik.LocalLevel(89.9, degrees=True, transport=True).transport


def _rest() -> ik.NavState:
    return ik.NavState(np.zeros(3), np.zeros(3), Rotation.identity())


def resting(latitude: float, rate: float, duration: float) -> tuple[ik.LocalLevel, ik.ImuData, ik.Trajectory]:
    frame = ik.LocalLevel(latitude, 120.0, degrees=True)
    attitude = Rotation.from_euler("ZYX", [40, 3, -2], degrees=True)
    imu, truth = ik.sim.simulate(
        ik.sim.Static(position=(0.0, 0.0, 0.0), rotation=attitude), rate=rate, duration=duration, frame=frame
    )
    return frame, imu, truth


@pytest.mark.parametrize("latitude", [0.0, 45.0, 89.0])
def test_resting_navigation_grade_imu(latitude: float) -> None:
    """A perfect (navigation-grade, noise-free) IMU at rest for one hour at 10 Hz.

    - it reads the Earth rate in its own axes, ``R_wbᵀ ω_ie``, and ``R_wbᵀ (−g)``;
    - integrated with the Earth model it stays still: measured ≤ 4.8e-12 rad, ≤ 4.9e-6 m, ≤ 4.3e-9
      m/s (rounding of 36,000 steps of 7e-6 rad);
    - without it, the attitude turns with the Earth, ``Ω T`` = 0.2625 rad, to 1.1e-13
      relative, about the Earth's axis, and the position runs off (97 km at 89°, 5500 km at the
      equator after 1 h; the closed form in the next test).
    """
    frame, imu, truth = resting(latitude, 10.0, 3600.0)
    phi = math.radians(latitude)
    r0 = truth.rotation[0]
    expected_gyro = r0.inv().apply(OMEGA * np.array([0, math.cos(phi), math.sin(phi)]))
    assert np.abs(imu.gyro - expected_gyro).max() < 1e-19
    assert np.abs(imu.accel - r0.inv().apply(-frame.gravity)).max() < 1e-14

    initial = ik.NavState(truth.position[0], truth.velocity[0], r0)
    # Every scheme: "exp" (exact for held inputs) drifted 113 m at 60° N before 2026-12-07, its
    # specific force turned at the body rate without the world's own.
    for scheme in ik.strapdown.SCHEMES:
        still = ik.integrate(imu, initial=initial, frame=frame, scheme=scheme)
        assert (still.rotation * r0.inv()).magnitude().max() < 2e-11, scheme
        assert np.abs(still.position).max() < 2e-5 and np.abs(still.velocity).max() < 2e-8, scheme

    drift = ik.integrate(imu, initial=initial, gravity=frame.gravity)
    turned = (drift.rotation[-1] * r0.inv()).magnitude()
    assert turned == pytest.approx(OMEGA * 3600.0, rel=1e-9)
    # the turn is about the Earth's axis: R(t) = Exp(ω t) R₀
    expected = Rotation.from_rotvec(frame.earth_rate * 3600.0) * r0
    assert (drift.rotation[-1] * expected.inv()).magnitude() < 1e-9


def test_position_drift_without_the_earth_model_is_predicted() -> None:
    """Over 10 min at 45°: ``p(T) = ∫₀ᵀ∫₀ˢ (I − Exp(ωu)) g du ds`` by the series of Exp (closed
    form, ours), against imukit's integration without the Earth model: equal to 1e-6 relative
    (the midpoint scheme's own error is far smaller); the drift is 18.2 km."""
    frame, imu, truth = resting(45.0, 20.0, 600.0)
    initial = ik.NavState(truth.position[0], truth.velocity[0], truth.rotation[0])
    drift = ik.integrate(imu, initial=initial, gravity=frame.gravity)
    t = 600.0
    wx = np.array(
        [
            [0.0, -frame.earth_rate[2], frame.earth_rate[1]],
            [frame.earth_rate[2], 0.0, -frame.earth_rate[0]],
            [-frame.earth_rate[1], frame.earth_rate[0], 0.0],
        ]
    )
    # ∫∫ Exp(ωu) du ds = Σ_n (wx t)ⁿ t² / (n + 2)!
    double = sum(np.linalg.matrix_power(wx * t, n) * t * t / math.factorial(n + 2) for n in range(12))
    expected = 0.5 * t * t * frame.gravity - double @ frame.gravity
    assert np.linalg.norm(expected) > 10.0
    assert np.abs(drift.position[-1] - expected).max() < 1e-6 * np.linalg.norm(expected)
