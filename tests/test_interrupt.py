"""Ctrl-C during a long kernel returns promptly (issue 17, item 15): ``propagate`` of 25 M samples
deferred a KeyboardInterrupt for 11.6 s, until it returned. Long kernels (strapdown, propagation,
preintegration, attitude integration, the filters' ``run`` (``Robust``'s online run too), the
simulator) now run on a thread of their own while the calling thread runs the signal handlers
every 20 ms; the kernel polls a cancel flag every 65,536 samples (the simulator: every chunk of
rows; ``preintegrate_windows``: every block of at most 4096 windows and about 2^17 samples).
"""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import textwrap
import time

import pytest

CHILD = textwrap.dedent(
    """
    import json, signal, sys, time
    import numpy as np
    from scipy.spatial.transform import Rotation
    import imukit as ik
    import imukit.filters
    import imukit.sim

    n = 4_000_000  # about 2 s of propagate on an idle core
    imu = ik.ImuData(np.arange(n) * 0.005, np.tile([0.01, 0.02, 0.03], (n, 1)), np.tile([0.0, 0.0, 9.81], (n, 1)))
    rest = ik.NavState(np.zeros(3), np.zeros(3), Rotation.identity())
    noise = ik.ImuNoise(1.7e-4, 2e-3, 1.9e-5, 3e-3)
    call = {"propagate": lambda: ik.propagate(imu, initial=rest, covariance=np.eye(15), noise=noise,
                                              covariance_every=1000),
            "integrate": lambda: ik.integrate(imu, initial=rest),
            "preintegrate": lambda: ik.preintegrate(imu, noise=noise, combined=True),
            "preintegrate_windows": lambda: ik.preintegrate_windows(
                imu, np.linspace(imu.t[0], imu.t[-1], 40_001), ik.PreintParams(noise, combined=True)),
            "preintegrate_windows(list)": lambda: ik.preintegrate_windows(  # the deprecated list form
                imu, np.linspace(imu.t[0], imu.t[-1], 40_001), noise=noise, combined=True),
            "integrate_attitude": lambda: ik.integrate_attitude(imu.t, imu.gyro, scheme="rk4",
                                                                representation="euler"),
            "mahony": lambda: ik.filters.Mahony().run(imu),
            "robust": lambda: ik.filters.Robust().run(imu),
            "simulate": lambda: ik.sim.simulate(ik.sim.FigureEight(), rate=1000.0, duration=n / 1000.0,
                                                noise=noise)}[sys.argv[1]]
    # A shell's background job inherits SIGINT ignored, and Python then installs no handler: the
    # test is of imukit's handling, not of the parent's disposition.
    signal.signal(signal.SIGINT, signal.default_int_handler)
    print("start", flush=True)
    start = time.perf_counter()
    try:
        # a kernel faster than the 0.3 s before the signal runs again, so the signal always lands
        # inside one
        while time.perf_counter() - start < 20.0:
            call()
        outcome = "returned"
    except KeyboardInterrupt:
        outcome = "KeyboardInterrupt"
    print(json.dumps([outcome, time.perf_counter() - start]), flush=True)
    """
)


@pytest.mark.skipif(sys.platform == "win32", reason="SIGINT to a child process is POSIX")
@pytest.mark.parametrize(
    "kernel",
    [
        "propagate",
        "integrate",
        "preintegrate",
        "preintegrate_windows",
        "preintegrate_windows(list)",
        "integrate_attitude",
        "mahony",
        "robust",
        "simulate",
    ],
)
def test_ctrl_c_stops_a_long_kernel_promptly(kernel: str) -> None:
    child = subprocess.Popen(
        [sys.executable, "-c", CHILD, kernel], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    assert child.stdout is not None
    assert child.stdout.readline().strip() == "start"
    time.sleep(0.3)
    child.send_signal(signal.SIGINT)
    out, err = child.communicate(timeout=120)
    assert child.returncode == 0, err
    outcome, seconds = json.loads(out.strip().splitlines()[-1])
    assert outcome == "KeyboardInterrupt"
    assert seconds < 1.0  # 0.3 s to the signal, then at most one 20 ms poll and 65,536 samples
