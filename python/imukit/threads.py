"""Threads of the parallel kernels: ``set_num_threads``, ``get_num_threads``.

The Rust kernels (batched so3 / quat / euler maps, attitude integration, long strapdown
integrations, preintegration windows and long batches, the simulator, the Allan variance) run on a
rayon pool. By default that is rayon's global pool, one
thread per core. ``set_num_threads(n)`` makes every later call use ``n`` threads (e.g.
``set_num_threads(1)`` in a Dask or multiprocessing worker, so that N workers do not each start one
thread per core); a ``threads=`` argument on a call overrides it for that call. Results do not
depend on the count. A child process made by ``fork()`` (``multiprocessing``'s default start
method on Linux) builds its own pools: the parent's threads do not exist there.

Every public function that reaches a parallel kernel takes the keyword-only ``threads``: the number
of threads for that call, an int in [1, MAX_THREADS]; None (the default) uses the setting of
``set_num_threads``. They are the so3 / quat / euler batch functions, ``integrate_attitude``, ``noise.allan_deviation``,
``sim.simulate``, ``integrate``, ``preintegrate``, ``PreintegratedImu.integrate``,
``preintegrate_windows`` and ``preint.reintegrate``.
"""

from __future__ import annotations

import operator
import os

from imukit import _core
from imukit._errors import ParameterError

__all__ = ["MAX_THREADS", "get_num_threads", "set_num_threads", "simd_path"]

MAX_THREADS = 4096  # a thread pool beyond this is a mistake (and past usize for huge ints)

# A child made by fork() (multiprocessing's default start method on Linux) holds copies of the
# Rust thread pools without their threads: the core then builds its pools afresh there.
if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_core.after_fork_in_child)


def _count(n: object, argument: str) -> int:
    """``n`` as an int in [1, MAX_THREADS], else :class:`ParameterError` naming ``argument``."""
    expected = f"expected an int in [1, {MAX_THREADS}], got {n!r}"
    if isinstance(n, bool):
        raise ParameterError(expected, argument=argument)
    try:
        count = operator.index(n)  # type: ignore[arg-type]
    except TypeError:
        raise ParameterError(expected, argument=argument) from None
    if not 1 <= count <= MAX_THREADS:
        raise ParameterError(expected, argument=argument)
    return count


def checked(threads: object) -> int | None:
    """A public function's ``threads=``: None (the process setting) or an int in [1, MAX_THREADS],
    else :class:`ParameterError` with ``argument="threads"``."""
    return None if threads is None else _count(threads, "threads")


def set_num_threads(n: int) -> None:
    """Use ``n`` threads (an int in [1, MAX_THREADS]) in every parallel kernel from now on."""
    _core.set_num_threads(_count(n, "n"))


def get_num_threads() -> int:
    """The number of threads a parallel kernel uses when its call does not say."""
    return _core.get_num_threads()


def simd_path() -> str:
    """The instruction-set path of the hot kernels in this process: ``"avx512"``, ``"avx2"`` or ``"baseline"``.

    Chosen once, at the first kernel call: the best the CPU has, or the one the environment
    variable ``IMUKIT_SIMD`` names (``baseline``, ``avx2``, ``avx512``; ``auto``: the best), falling
    back to the best supported path below a forced one the CPU lacks. The paths give equal results
    (``docs/performance.md``). ``IMUKIT_SIMD`` holding another value is refused when imukit is
    imported (below), so no kernel runs with it.
    """
    return _core.simd_path()


# An unknown ``IMUKIT_SIMD`` (a typo such as ``avx-2``) is a ParameterError naming the variable at
# import, before any kernel could silently run the best path instead; this also fixes the path for
# the process (it is read once).
simd_path()
