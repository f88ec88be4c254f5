"""Allocations sized by the input are checked (issue 17, item 1): under an address-space limit
(``resource.setrlimit(RLIMIT_AS)``, in a subprocess) every call below used to abort the process
(SIGABRT from a failed Rust allocation) or raise ``PanicException`` (rust-numpy's constructors on a
null array); now each raises ``imukit.ResourceError`` (an ``ImukitError`` and a ``MemoryError``)
naming the argument that sized the request and the size, and the process carries on.
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
import textwrap

import pytest

resource = pytest.importorskip("resource", reason="RLIMIT_AS needs the POSIX resource module")

# 1.5 GB of address space: the interpreter with numpy, scipy and imukit maps about 350 MB.
LIMIT = 1_500_000_000

SCRIPT = textwrap.dedent(
    """
    import json, resource, sys, warnings
    import numpy as np
    import imukit as ik
    from scipy.spatial.transform import Rotation

    resource.setrlimit(resource.RLIMIT_AS, (BYTES, BYTES))
    warnings.simplefilter("ignore", DeprecationWarning)
    noise = ik.ImuNoise(1.7e-4, 2e-3, 1.9e-5, 3e-3)
    t = np.arange(2001) * 0.01
    imu = ik.ImuData(t, np.tile([0.1, 0.2, 0.3], (2001, 1)), np.tile([0.0, 0.0, 9.81], (2001, 1)))
    edges = np.linspace(0, 20, 20_000_001)
    n = 1_000_000
    rest = ik.NavState(np.zeros(3), np.zeros(3), Rotation.identity())
    long = ik.ImuData(np.arange(n) * 0.005, np.zeros((n, 3)), np.tile([0.0, 0.0, 9.81], (n, 1)))
    cases = {
        "windows_list": lambda: ik.preintegrate_windows(imu, edges, noise=noise),
        "windows_record": lambda: ik.preintegrate_windows(imu, edges, ik.PreintParams(noise)),
        "propagate": lambda: ik.propagate(long, initial=rest, covariance=np.eye(15), noise=noise),
        "so3_exp": lambda: ik.so3.exp(np.zeros((12_000_000, 3))),
    }
    out = {}
    for name, call in cases.items():
        try:
            call()
            out[name] = ["returned", ""]
        except BaseException as e:  # PanicException is a BaseException
            out[name] = [type(e).__name__, str(e), isinstance(e, MemoryError), isinstance(e, ik.ImukitError)]
    # The process is sound afterwards.
    out["after"] = float(ik.preintegrate(imu, noise=noise).delta_t)
    print(json.dumps(out))
    """
).replace("BYTES", str(LIMIT))


def test_allocations_sized_by_input_are_refused_not_aborted() -> None:
    run = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-2000:]
    out = json.loads(run.stdout.strip().splitlines()[-1])
    expected = {
        "windows_list": r"boundaries: 20,000,000 windows need \d+\.\d GB",
        "windows_record": r"boundaries: 20,000,000 windows need 24\.2 GB",
        "propagate": r"covariance_every: 1,000,000 covariances need 1\.9 GB",
        "so3_exp": r"phi: 12,000,000 rows need 864\.0 MB",
    }
    for name, pattern in expected.items():
        cls, message, is_memory, is_imukit = out[name]
        assert cls == "ResourceError", (name, cls, message)
        assert is_memory and is_imukit
        assert re.fullmatch(pattern, message), (name, message)
    assert out["after"] == pytest.approx(20.0)
