"""Threads of the parallel kernels: ``set_num_threads``, ``get_num_threads``.

The Rust kernels (batched so3 / quat / euler maps, attitude integration, preintegration windows,
the simulator) run on a rayon pool. By default that is rayon's global pool, one thread per core.
``set_num_threads(n)`` makes every later call use ``n`` threads (e.g. ``set_num_threads(1)`` in a
Dask or multiprocessing worker, so that N workers do not each start one thread per core); a
``threads=`` argument on a call overrides it for that call. Results do not depend on the count.
"""

from __future__ import annotations

import operator

from imukit import _core
from imukit._errors import ParameterError

__all__ = ["MAX_THREADS", "get_num_threads", "set_num_threads"]

MAX_THREADS = 4096  # a thread pool beyond this is a mistake (and past usize for huge ints)


def set_num_threads(n: int) -> None:
    """Use ``n`` threads (an int in [1, MAX_THREADS]) in every parallel kernel from now on."""
    expected = f"expected an int in [1, {MAX_THREADS}], got {n!r}"
    if isinstance(n, bool):
        raise ParameterError(expected, argument="n")
    try:
        count = operator.index(n)
    except TypeError:
        raise ParameterError(expected, argument="n") from None
    if not 1 <= count <= MAX_THREADS:
        raise ParameterError(expected, argument="n")
    _core.set_num_threads(count)


def get_num_threads() -> int:
    """The number of threads a parallel kernel uses when its call does not say."""
    return _core.get_num_threads()
