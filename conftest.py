"""Collection rules above both test roots (the doctests of python/imukit and tests/)."""

import importlib.util

# imukit.torch's modules and the tests' torch case table import torch at the top. Without
# imukit[torch] (the Makefile leaves it out where the disk cannot hold the CUDA libraries) they are
# not collected, and the header says so; the tests under tests/ skip with their own reason.
HAVE_TORCH = importlib.util.find_spec("torch") is not None
collect_ignore = [] if HAVE_TORCH else ["python/imukit/torch", "tests/torch_cases.py"]


def pytest_report_header() -> str | None:
    return None if HAVE_TORCH else "torch not installed: imukit.torch's doctests are not collected"
