"""Shared fixtures and comparison helpers for the pytest suite."""

from __future__ import annotations

import re
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from numpy.typing import ArrayLike
from scipy.spatial.transform import Rotation

import imukit as ik

N_RANDOM = 10_000


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(20261122)


@pytest.fixture
def rotvecs(rng: np.random.Generator) -> np.ndarray:
    """10,000 rotation vectors with uniformly random rotations (angles in [0, π])."""
    return Rotation.random(N_RANDOM, rng=rng).as_rotvec()


def quat_distance(a: ArrayLike, b: ArrayLike) -> np.ndarray:
    """Largest componentwise gap between quaternions, taking q and -q as equal."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return np.minimum(np.abs(a - b).max(axis=-1), np.abs(a + b).max(axis=-1))


def assert_quat_close(a: ArrayLike, b: ArrayLike, atol: float) -> None:
    """Assert two (batches of) quaternions are the same rotation up to sign, to ``atol``."""
    gap = quat_distance(a, b)
    worst = int(np.argmax(gap)) if np.ndim(gap) else 0
    assert np.all(gap <= atol), f"quaternions differ by {np.max(gap):.3e} (> {atol:.1e}) at {worst}"


def rotation_angle_between(a: ArrayLike, b: ArrayLike) -> np.ndarray:
    """Angle (rad) of aᵀ b for (..., 3, 3) rotation matrices."""
    rel = np.swapaxes(np.asarray(a), -1, -2) @ np.asarray(b)
    return Rotation.from_matrix(rel.reshape(-1, 3, 3)).magnitude().reshape(rel.shape[:-2])


def assert_file_error(path: Path, text: str, read: Callable[[Path], object], message: str) -> None:
    """Write ``text`` to ``path``: ``read(path)`` must raise a FileFormatError (a ValueError) whose
    message is ``path: <path>`` followed by the regex ``message``."""
    path.write_text(text)
    with pytest.raises(ik.io.FileFormatError, match=f"^path: {re.escape(str(path))}{message}") as info:
        read(path)
    assert isinstance(info.value, ValueError) and isinstance(info.value, ik.ImukitError)


def forced_path(results: dict[str, dict[str, np.ndarray]], path: str) -> dict[str, np.ndarray]:
    """The results of a child run with ``IMUKIT_SIMD=path`` (its ``"path"`` entry the path it ran),
    or a skip naming the path when the CPU lacks it: a forced path the CPU lacks runs the best one
    below it, and comparing that again would pass without testing the path named."""
    got = results[path]
    if str(got["path"]) != path:
        pytest.skip(f"this CPU has no {path} path (forcing it ran {got['path']}, tested under its own name)")
    return got


# The corpus's summary lines that pytest-xdist's workers sent back (make test runs on every core).
_WORKER_SUMMARIES: list[str] = []


def _corpus_summary() -> str | None:
    corpus = sys.modules.get("malformed_strategies")
    return corpus.STATS.summary() if corpus is not None and corpus.STATS.cases else None


def pytest_sessionfinish(session: pytest.Session) -> None:
    """On a pytest-xdist worker, hand the corpus's summary to the controller, which prints it."""
    output = getattr(session.config, "workeroutput", None)
    summary = _corpus_summary()
    if output is not None and summary is not None:
        output["malformed_corpus"] = summary


@pytest.hookimpl(optionalhook=True)
def pytest_testnodedown(node: Any, error: object) -> None:
    summary = getattr(node, "workeroutput", {}).get("malformed_corpus")
    if summary is not None:
        _WORKER_SUMMARIES.append(summary)


def pytest_terminal_summary(terminalreporter: pytest.TerminalReporter) -> None:
    """The malformed-input corpus's case count (tests/test_malformed_corpus.py), when it ran here
    or on a worker."""
    own = _corpus_summary()
    for line in ([own] if own is not None else []) + _WORKER_SUMMARIES:
        terminalreporter.write_line(line)
