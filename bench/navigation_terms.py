"""What each navigation term is worth: the position and attitude error of leaving it out, over 1 min
and 1 h at 45° N, next to the error each IMU grade's own bias causes (docs/navigation.md, "What
each term is worth"). Run ``python bench/navigation_terms.py``; it prints the markdown table.

Rows marked *measured* integrate exact simulated readings with imukit twice (with and without the
term, ``rk4`` at 10 Hz) and report the difference; rows marked *closed form* evaluate the term's
first-order effect (the test named beside it checks that form against imukit where it exists).
Grades (Groves 2013, table 4.1): consumer gyro bias 10 °/h, accelerometer 5 mg; tactical 1 °/h,
0.5 mg; navigation 0.01 °/h, 25 µg.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial.transform import Rotation

import imukit as ik

LAT = 45.0
SPANS = (60.0, 3600.0)
RATE = 10.0
DEG_PER_H = math.radians(1.0) / 3600.0
MG = 9.80665e-3
GRADES = {
    "consumer": (10 * DEG_PER_H, 5 * MG),
    "tactical": (DEG_PER_H, 0.5 * MG),
    "navigation": (0.01 * DEG_PER_H, 0.025 * MG),
}


def errors(a: ik.Trajectory, b: ik.Trajectory) -> tuple[float, float]:
    """Final position distance [m] and attitude angle [rad] between two runs."""
    dp = float(np.linalg.norm(a.position[-1] - b.position[-1]))
    return dp, float((a.rotation[-1].inv() * b.rotation[-1]).magnitude())


def resting(span: float, frame: ik.LocalLevel | None, gravity: np.ndarray) -> tuple[ik.ImuData, ik.NavState]:
    motion = ik.sim.Static(np.zeros(3), Rotation.identity())
    kw = {"frame": frame} if frame is not None else {"gravity": gravity}
    imu, truth = ik.sim.simulate(motion, rate=RATE, duration=span, **kw)
    return imu, truth.state(0)


def earth_rate(span: float) -> tuple[float, float]:
    """*Measured*: a resting IMU on the Earth integrated with the Earth model and without it."""
    frame = ik.LocalLevel(LAT, degrees=True)
    imu, x0 = resting(span, frame, frame.gravity)
    with_model = ik.integrate(imu, initial=x0, frame=frame, scheme="rk4")
    without = ik.integrate(imu, initial=x0, gravity=frame.gravity, scheme="rk4")
    return errors(with_model, without)


def gravity_model(span: float, height: float) -> tuple[float, float]:
    """*Measured*: normal gravity at 45° and ``height`` replaced by the constant 9.81 m/s²."""
    frame = ik.LocalLevel(LAT, height, degrees=True)
    imu, x0 = resting(span, None, frame.gravity)
    right = ik.integrate(imu, initial=x0, gravity=frame.gravity, scheme="rk4")
    return errors(right, ik.integrate(imu, initial=x0, scheme="rk4"))


def grade(span: float, gyro_bias: float, accel_bias: float) -> tuple[float, float]:
    """*Measured*: a resting IMU whose gyro and accelerometer carry the grade's bias on x."""
    imu, x0 = resting(span, None, np.array(ik.GRAVITY))
    biased = ik.ImuData(imu.t, imu.gyro + np.array([gyro_bias, 0, 0]), imu.accel + np.array([accel_bias, 0, 0]))
    return errors(ik.integrate(imu, initial=x0, scheme="rk4"), ik.integrate(biased, initial=x0, scheme="rk4"))


def coriolis(span: float, speed: float) -> float:
    """*Closed form*: ½ |2 ω_ie × v| T² for v east (|ω × v| = Ω v)."""
    return 0.5 * 2 * 7.292115e-5 * speed * span**2


def fixed_instead_of_transport(span: float, speed: float) -> float:
    """*Closed form*: the fixed frame's gravity not turned with the vehicle, γ v T³ / 6R
    (``tests/test_transport.py`` holds it to 1 % at 250 m/s over 60 s)."""
    return 9.806 * speed * span**3 / (6 * 6.3886e6)


def lever_arm(span: float, rate: float, arm: float) -> float:
    """*Closed form*: a sensor ``arm`` metres off the origin of a body turning at ``rate`` about z,
    integrated as if at the origin: the error is ``R r − R₀ r − T R₀ (ω × r)`` (the sensor's own
    circle minus the velocity its start adds; ``tests/test_lever_arm.py`` holds imukit to it)."""
    r, w = np.array([arm, 0.0, 0.0]), np.array([0.0, 0.0, rate])
    turned = Rotation.from_rotvec(w * span).apply(r)
    return float(np.linalg.norm(turned - r - span * np.cross(w, r)))


def row(name: str, values: list[tuple[float, float]] | list[float]) -> str:
    cells = []
    for v in values:
        if isinstance(v, tuple):
            cells.append(f"{v[0]:.3g} m, {v[1]:.3g} rad")
        else:
            cells.append("—" if math.isnan(v) else f"{v:.3g} m")
    return f"| {name} | " + " | ".join(cells) + " |"


def main() -> None:
    print("| term left out (45° N) | 1 min | 1 h |")
    print("|---|---|---|")
    print(row("Earth rate and Coriolis, at rest (*measured*)", [earth_rate(s) for s in SPANS]))
    for speed in (1.0, 10.0, 250.0):
        print(row(f"Coriolis at {speed:g} m/s (*closed form*)", [coriolis(s, speed) for s in SPANS]))
    for speed in (10.0, 250.0):
        print(
            row(
                f"transport: fixed frame at {speed:g} m/s (*closed form*)",
                [fixed_instead_of_transport(60.0, speed), math.nan],
            )
        )
    print(row("normal gravity → 9.81, h = 0 (*measured*)", [gravity_model(s, 0.0) for s in SPANS]))
    print(row("normal gravity → 9.81, h = 1000 m (*measured*)", [gravity_model(s, 1000.0) for s in SPANS]))
    print(row("lever arm 0.3 m at 1 rad/s (*closed form*)", [lever_arm(s, 1.0, 0.3) for s in SPANS]))
    for name, (bg, ba) in GRADES.items():
        print(row(f"{name} grade: its own biases (*measured*)", [grade(s, bg, ba) for s in SPANS]))


if __name__ == "__main__":
    main()
