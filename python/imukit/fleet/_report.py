"""The ``report`` job: what a fleet engineer checks per log (``docs/fleet.md`` lists every column).

======================  ===========================================================================
timing                  ``samples``, ``duration_s``, ``rate_hz`` (median) and ``mean_rate_hz``
                        (:func:`imukit.noise.mean_rate_hz`), ``dt_jitter_s`` (std of the steps that
                        are not gaps), ``gaps`` and ``longest_gap_s`` (:func:`imukit.io.find_gaps`)
reader                  ``skipped_<kind>_lines`` per kind of bad line (:class:`imukit.io.ReadReport`)
saturation              ``gyro_saturated_<axis>_samples`` / ``accel_…``: samples with that axis at
                        ± the full-scale range given as ``gyro_range`` / ``accel_range`` (null when
                        the range is not given)
rest                    ``rest_segments``, ``rest_s`` (:func:`imukit.fleet.rest_segments`)
bias at rest            ``gyro_bias_<axis>_rad_s``: the mean gyro over the rest samples (Earth's
                        rate, 7.3e-5 rad/s, is in it); ``gravity_at_rest_m_s2``: ‖mean accel‖ per
                        segment, weighted by samples, and ``accel_bias_vertical_m_s2`` = it − ‖g‖
                        (``imukit.GRAVITY``): the one accelerometer bias component a static pose
                        observes, to first order
noise density           ``gyro_noise_density_rad_s_sqrt_hz``, ``accel_noise_density_m_s2_sqrt_hz``:
                        σ √Δt of the rest samples about the mean of their window of ``NOISE_WINDOW_S``
                        within a segment, pooled over windows and axes (white noise of density N has
                        σ = N/√Δt); the short windows keep the bias's drift out of it
Allan fit               on the longest rest segment when it lasts ``allan_min_s`` or more
                        (:func:`imukit.noise.fit_allan`, 3 axes jointly): ``<sensor>_allan_N_…``,
                        ``…_B_…``, ``…_K_…``; null otherwise
======================  ===========================================================================
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from typing import Any

import numpy as np

from imukit._errors import ShapeError
from imukit.fleet._load import JobOutput, Scalar, load, per_axis, skipped_counts
from imukit.fleet._rest import RestSegment, rest_segments
from imukit.imu import GRAVITY, ImuData
from imukit.io import find_gaps
from imukit.io._report import OnBadLine
from imukit.noise import allan_deviation, fit_allan, mean_rate_hz

__all__ = ["ALLAN_MIN_S", "report", "report_imu"]

ALLAN_MIN_S = 60.0
"""The shortest rest segment [s] an Allan fit is tried on: τ up to a tenth of it leaves the fit about
ten octaves of τ at 200 Hz, enough to tell white noise from the flat and rising terms."""

NOISE_WINDOW_S = 1.0
"""The window [s] the noise density's σ is taken about the mean of. A bias random walk of density K
adds K²T/6 to the variance about the mean of a T-second window (the variance of a Wiener process
about its own mean): over an hour-long segment with EuRoC's accelerometer K that is 7× the white
noise's σ², over 1 s 0.2 %; the white noise loses one degree of freedom per window."""

# Units of the Allan terms per sensor: N, B, K.
_ALLAN_UNITS = {"gyro": ("rad_s_sqrt_hz", "rad_s", "rad_s2_sqrt_hz"), "accel": ("m_s2_sqrt_hz", "m_s2", "m_s3_sqrt_hz")}


def report(
    path: str | os.PathLike[str],
    *,
    gyro_range: float | None = None,
    accel_range: float | None = None,
    allan_min_s: float = ALLAN_MIN_S,
    on_bad_line: OnBadLine = "skip",
    csv: Mapping[str, Any] | None = None,
) -> JobOutput:
    """The report of the recording at ``path`` (module doc); ``csv`` as in :func:`imukit.io.read_imu`."""
    recording = load(path, on_bad_line=on_bad_line, csv=csv)
    scalars = report_imu(recording.imu, gyro_range=gyro_range, accel_range=accel_range, allan_min_s=allan_min_s)
    return JobOutput({**scalars, **skipped_counts(recording.skipped)})


def report_imu(
    imu: ImuData, *, gyro_range: float | None = None, accel_range: float | None = None, allan_min_s: float = ALLAN_MIN_S
) -> dict[str, Scalar]:
    """The columns of :func:`report` that come from the samples alone."""
    if len(imu) < 2:
        raise ShapeError(f"{len(imu)} sample, a report needs at least 2", argument="imu")
    gaps = find_gaps(imu)
    steps = np.delete(imu.dt, [gap.sample - 1 for gap in gaps])
    segments = rest_segments(imu)
    scalars: dict[str, Scalar] = {
        "samples": len(imu),
        "duration_s": imu.duration,
        "rate_hz": imu.rate_hz,
        "mean_rate_hz": mean_rate_hz(imu),
        "dt_jitter_s": float(np.std(steps)),
        "gaps": len(gaps),
        "longest_gap_s": max((gap.step for gap in gaps), default=0.0),
        **per_axis("gyro_saturated", "samples", _saturated(imu.gyro, gyro_range)),
        **per_axis("accel_saturated", "samples", _saturated(imu.accel, accel_range)),
        "rest_segments": len(segments),
        "rest_s": sum(s.duration_s for s in segments),
    }
    return {**scalars, **_at_rest(imu, segments), **_allan(imu, segments, allan_min_s)}


def _saturated(samples: np.ndarray, full_scale: float | None) -> np.ndarray | None:
    return None if full_scale is None else (np.abs(samples) >= full_scale).sum(axis=0)


def _at_rest(imu: ImuData, segments: list[RestSegment]) -> dict[str, Scalar]:
    """Bias, gravity and white-noise density from the rest samples (module doc); null without any."""
    if not segments:
        return {
            **per_axis("gyro_bias", "rad_s", None),
            "gravity_at_rest_m_s2": None,
            "accel_bias_vertical_m_s2": None,
            "gyro_noise_density_rad_s_sqrt_hz": None,
            "accel_noise_density_m_s2_sqrt_hz": None,
        }
    gyro = [imu.gyro[s.start : s.stop] for s in segments]
    accel = [imu.accel[s.start : s.stop] for s in segments]
    n = np.array([len(g) for g in gyro], dtype=float)
    gravity = float(np.average([np.linalg.norm(a.mean(axis=0)) for a in accel], weights=n))
    dt = float(np.median(imu.dt))
    return {
        **per_axis("gyro_bias", "rad_s", np.concatenate(gyro).mean(axis=0)),
        "gravity_at_rest_m_s2": gravity,
        "accel_bias_vertical_m_s2": gravity - float(np.linalg.norm(GRAVITY)),
        "gyro_noise_density_rad_s_sqrt_hz": _pooled_sigma(_windows(gyro, dt)) * np.sqrt(dt),
        "accel_noise_density_m_s2_sqrt_hz": _pooled_sigma(_windows(accel, dt)) * np.sqrt(dt),
    }


def _windows(segments: list[np.ndarray], dt: float) -> list[np.ndarray]:
    """Each segment cut into windows of ``NOISE_WINDOW_S`` (at least 2 samples); a shorter tail
    joins the window before it, so every sample counts."""
    width = max(2, round(NOISE_WINDOW_S / dt))
    pieces = []
    for segment in segments:
        cuts = np.arange(width, len(segment) - width + 1, width)
        pieces += np.split(segment, cuts)
    return pieces


def _pooled_sigma(pieces: list[np.ndarray]) -> float:
    """σ of the samples about their own piece's mean, pooled over pieces and the 3 axes
    (Σ squared residuals / Σ (nᵢ − 1) per axis: unbiased for σ²)."""
    squares = sum(float(((p - p.mean(axis=0)) ** 2).sum()) for p in pieces)
    dof = 3 * sum(len(p) - 1 for p in pieces)
    return float(np.sqrt(squares / dof))


def _allan(imu: ImuData, segments: list[RestSegment], allan_min_s: float) -> dict[str, Scalar]:
    longest = max(segments, key=lambda s: s.duration_s, default=None)
    fit = longest is not None and longest.duration_s >= allan_min_s
    columns: dict[str, Scalar] = {}
    for sensor, units in _ALLAN_UNITS.items():
        values: tuple[float | None, ...] = (None, None, None)
        if fit and longest is not None:
            piece = imu[longest.start : longest.stop]
            result = fit_allan(allan_deviation(getattr(piece, sensor), mean_rate_hz(piece)), sensor=sensor)
            values = (result.noise_density, result.bias_instability, result.random_walk)
        for term, unit, value in zip("NBK", units, values):
            columns[f"{sensor}_allan_{term}_{unit}"] = value
    return columns
