"""``import imukit`` (hence every CLI command, every fleet worker) loads what every program needs and
leaves the heavy optional parts to the functions that use them: scipy's stats, signal, optimize
and interpolate were 1.2 s of a 2.2 s import until they moved into ``imukit.noise`` and
``imukit.sim``'s spline trajectory. That the functions still import what they use is what their
own tests show (``test_noise_allan.py``, ``test_noise_calibrate.py``, ``test_sim.py``)."""

from __future__ import annotations

import subprocess
import sys

LAZY = (
    "scipy.stats",
    "scipy.signal",
    "scipy.optimize",
    "scipy.interpolate",
    "matplotlib",
    "dask",
    "torch",
    "pyarrow",
    "rosbags",
)


def test_import_imukit_and_its_cli_leave_the_heavy_modules_to_their_functions() -> None:
    probe = f"import sys, imukit, imukit.cli; print(*[m for m in {LAZY!r} if m in sys.modules])"
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True, timeout=120)
    assert out.stdout.split() == []
