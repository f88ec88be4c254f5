"""Kalibr ``imu.yaml`` noise files: :func:`read_kalibr_imu`, :func:`write_kalibr_imu` (``docs/io.md``).

Kalibr's IMU noise model (github.com/ethz-asl/kalibr/wiki/IMU-Noise-Model) is imukit's: continuous-time
densities, the same numbers as :class:`imukit.ImuNoise` without any conversion. The file is also
how EuRoC's ``imu0/sensor.yaml`` states its noise (with ``rate_hz`` in place of ``update_rate``).
"""

from __future__ import annotations

import codecs
import math
import os
import re
import reprlib
from collections.abc import Hashable, Mapping
from typing import Any, NamedTuple

import yaml

from imukit._errors import FileFormatError, ParameterError
from imukit.imu import ImuNoise, _rate
from imukit.io._lines import regular_file

__all__ = ["KalibrImu", "read_kalibr_imu", "write_kalibr_imu"]

# Kalibr key -> (ImuNoise field, unit, what), in Kalibr's order.
_NOISE_KEYS = {
    "accelerometer_noise_density": ("accel_density", "m/s^2/sqrt(Hz)", "white noise"),
    "accelerometer_random_walk": ("accel_random_walk", "m/s^3/sqrt(Hz)", "bias random walk"),
    "gyroscope_noise_density": ("gyro_density", "rad/s/sqrt(Hz)", "white noise"),
    "gyroscope_random_walk": ("gyro_random_walk", "rad/s^2/sqrt(Hz)", "bias random walk"),
}
# Kalibr names the rate update_rate, EuRoC's sensor.yaml rate_hz.
_RATE_KEYS = ("update_rate", "rate_hz")
# OpenCV's FileStorage writes this first line (EuRoC-derived files carry it); PyYAML refuses it.
_SHOWN = reprlib.Repr()  # bounded: 16 elements a level (T_BS in full), 6 levels, 30 characters a string
_SHOWN.maxlist = _SHOWN.maxtuple = 16
_OPENCV_DIRECTIVE = re.compile(r"\A%YAML:1\.[0-9]+[^\n]*")


class KalibrImu(NamedTuple):
    """What a Kalibr ``imu.yaml`` holds: the noise densities, the rate, and every other key."""

    noise: ImuNoise
    """The four densities (Kalibr units, which are imukit's)."""
    rate_hz: float
    """``update_rate`` (or EuRoC's ``rate_hz``) [Hz]: the rate Kalibr discretises the densities with."""
    extra: dict[str, Any]
    """The other keys as PyYAML parsed them (``rostopic``, ``T_BS``, ``time_offset``, …)."""


def read_kalibr_imu(path: str | os.PathLike[str], *, section: str | None = None) -> KalibrImu:
    """Read the IMU noise model of a Kalibr ``imu.yaml`` (or an EuRoC ``imu0/sensor.yaml``).

    Parameters
    ----------
    path
        The YAML file. Keys: ``accelerometer_noise_density`` [m/s²/√Hz],
        ``accelerometer_random_walk`` [m/s³/√Hz], ``gyroscope_noise_density`` [rad/s/√Hz],
        ``gyroscope_random_walk`` [rad/s²/√Hz], and the rate ``update_rate`` [Hz] (Kalibr) or
        ``rate_hz`` (EuRoC; if both are present they must agree). A leading OpenCV ``%YAML:1.0``
        line is accepted. Numbers may be written the way YAML 1.1 reads as text (``1e-3``).
    section
        Read the mapping under this top-level key instead, e.g. ``"imu0"`` for the files that
        ``kalibr_calibrate_imu_camera`` writes.

    Returns
    -------
    KalibrImu
        ``(noise, rate_hz, extra)``; ``extra`` holds every other key of the mapping read.

    Raises
    ------
    FileFormatError
        (a ``ValueError``) naming the file and the key: invalid YAML, missing keys, or a value that
        is not a finite number ≥ 0 (a rate must be > 0); naming the line for bytes that are not UTF-8.
    """
    where = os.fspath(path)
    with open(regular_file(path), "rb") as f:
        # Without a byte order mark (Excel, Notepad): it would hide an OpenCV directive from the pattern's \A.
        raw = f.read().removeprefix(codecs.BOM_UTF8)
    try:
        text = _OPENCV_DIRECTIVE.sub("", raw.decode("utf-8"), count=1)  # keeps the newline: line numbers hold
    except UnicodeDecodeError as exc:
        line = raw[: exc.start].count(b"\n") + 1
        raise FileFormatError(
            f"{where}, line {line}: not UTF-8 text (byte {raw[exc.start]:#04x})", argument="path"
        ) from None
    if section is not None and not isinstance(section, str):
        raise ParameterError(f"expected a top-level key (str) or None, got {shown(section)}", argument="section")
    try:
        doc = yaml.load(text, Loader=_KalibrLoader)  # a SafeLoader, stricter still
    except yaml.YAMLError as exc:
        raise FileFormatError(f"{where}{_yaml_problem(exc)}", argument="path") from None
    except RecursionError:
        raise FileFormatError(f"{where}: not valid YAML: nested too deeply", argument="path") from None
    if section is not None:
        if not isinstance(doc, dict) or section not in doc:
            raise FileFormatError(f"{where}: no section {section!r} at the top level", argument="path")
        doc = doc[section]
    within = "" if section is None else f" in section {section!r}"
    if not isinstance(doc, dict):
        raise FileFormatError(
            f"{where}: expected a mapping of Kalibr keys{within}, got {type(doc).__name__}", argument="path"
        )
    missing = [key for key in _NOISE_KEYS if key not in doc]
    rates = [key for key in _RATE_KEYS if key in doc]
    if not rates:
        missing.append("update_rate")
    if missing:
        raise FileFormatError(
            f"{where}: missing key {', '.join(missing)}{within}{_section_hint(doc, section)}", argument="path"
        )
    densities = {field: _number(doc, key, where, positive=False) for key, (field, _, _) in _NOISE_KEYS.items()}
    rate, *others = (_number(doc, key, where, positive=True) for key in rates)
    if others and others[0] != rate:
        raise FileFormatError(
            f"{where}, key 'rate_hz': {others[0]!r} disagrees with update_rate {rate!r}", argument="path"
        )
    extra = {key: value for key, value in doc.items() if key not in _NOISE_KEYS and key not in _RATE_KEYS}
    return KalibrImu(ImuNoise(**densities), rate, extra)


def write_kalibr_imu(
    path: str | os.PathLike[str],
    noise: ImuNoise,
    *,
    rate_hz: float,
    rostopic: str | None = None,
    extra: Mapping[str, Any] | None = None,
    comments: Mapping[str, str] | None = None,
    header: str | None = None,
) -> None:
    """Write ``noise`` as a Kalibr ``imu.yaml``, each value with its unit in a comment.

    Floats are written with ``repr`` (``1.0e-05`` rather than ``1e-05``, which YAML 1.1 would read
    as text), so :func:`read_kalibr_imu` gives back the same floats bit for bit: round estimates
    to the digits they have first (``float(f"{x:.4g}")`` is written ``0.0001697``), and a measured
    rate too (100.00000000000213 is written so). ``rate_hz`` is the ``update_rate`` [Hz] > 0;
    ``rostopic`` (e.g. ``"/imu0"``) and the keys of ``extra`` (plain Python values, written by
    ``yaml.safe_dump``; e.g. ``KalibrImu.extra`` of a file read) follow when given. ``comments``
    maps Kalibr noise keys (``"gyroscope_random_walk"``, …) to text appended to that line's comment;
    ``header`` is added to the file's first comment, one ``#`` line per line of it. Nothing is
    written when an argument is refused (``ParameterError``, ``TypeError``).
    """
    if not isinstance(noise, ImuNoise):
        raise TypeError(f"noise: expected an imukit ImuNoise, got {type(noise).__name__}")
    rate = _rate(rate_hz)
    more = dict(extra or {})
    taken = sorted(set(more) & {*_NOISE_KEYS, *_RATE_KEYS, *([] if rostopic is None else ["rostopic"])})
    if taken:
        raise ParameterError(f"keys {taken} are written from noise, rate_hz and rostopic", argument="extra")
    notes = dict(comments or {})
    unknown = sorted(set(notes) - set(_NOISE_KEYS))
    if unknown:
        raise ParameterError(f"keys {unknown} are not Kalibr noise keys {sorted(_NOISE_KEYS)}", argument="comments")
    if rostopic is not None:
        if not isinstance(rostopic, str):
            raise ParameterError(f"expected a string such as '/imu0', got {rostopic!r}", argument="rostopic")
        more = {"rostopic": rostopic, **more}
    try:
        more_text = [yaml.safe_dump(more, sort_keys=False, allow_unicode=True).rstrip("\n")] if more else []
    except yaml.YAMLError as exc:
        raise ParameterError(f"cannot be written as YAML (plain Python values only): {exc}", argument="extra") from None
    lines = [
        "# Kalibr IMU noise model (continuous-time densities), written by imukit",
        *(f"# {line}".rstrip() for line in (header or "").splitlines()),
        *noise_lines(noise, list(_NOISE_KEYS), notes),
        *more_text,
        f"update_rate: {yaml_float(rate)}  # [Hz]",
    ]
    with open(path, "w", encoding="utf-8", newline="\n") as f:
        f.write("\n".join(lines) + "\n")


def noise_lines(noise: ImuNoise, keys: list[str], comments: Mapping[str, str] | None = None) -> list[str]:
    """``key: value  # [unit] what`` lines for the Kalibr ``keys`` of ``noise``, in that order, with
    ``comments[key]`` appended where given."""
    lines = []
    for key in keys:
        field, unit, what = _NOISE_KEYS[key]
        note = (comments or {}).get(key)
        lines.append(f"{key}: {yaml_float(getattr(noise, field))}  # [{unit}] {what}" + (f"; {note}" if note else ""))
    return lines


def yaml_float(x: float) -> str:
    """``repr(x)`` with a ``.0`` in the mantissa where it has none, so YAML 1.1 reads a float."""
    mantissa, e, exponent = repr(float(x)).partition("e")
    if "." not in mantissa:
        mantissa += ".0"
    return mantissa + e + exponent


def _number(doc: dict[Any, Any], key: str, where: str, *, positive: bool) -> float:
    value = doc[key]
    x = math.nan
    if isinstance(value, (int, float, str)) and not isinstance(value, bool):
        try:
            x = float(value)
        except (ValueError, OverflowError):
            pass
    if not (math.isfinite(x) and (x > 0 if positive else x >= 0)):
        what = "a positive, finite number" if positive else "a finite number ≥ 0"
        raise FileFormatError(f"{where}, key {key!r}: expected {what}, got {shown(value)}", argument="path")
    return x


def _section_hint(doc: dict[Any, Any], section: str | None) -> str:
    if section is not None:
        return ""
    nested = [key for key, value in doc.items() if isinstance(value, dict) and "gyroscope_noise_density" in value]
    return f" (found under {nested[0]!r}: pass section={nested[0]!r})" if nested else ""


class _KalibrLoader(yaml.SafeLoader):
    """PyYAML's safe loader without aliases and duplicate keys.

    A Kalibr file is a flat mapping of numbers: an alias (``*a``) there only serves to multiply a
    small file into gigabytes (a "billion laughs" document of 600 bytes took 8 s and 1.6 GB), and a
    repeated key would silently take the last value.
    """

    def compose_node(self, parent: yaml.Node | None, index: int) -> yaml.Node | None:
        if self.check_event(yaml.AliasEvent):
            mark = self.peek_event().start_mark  # type: ignore[no-untyped-call]
            raise yaml.composer.ComposerError(None, None, "aliases (*name) are not accepted in a Kalibr file", mark)
        return super().compose_node(parent, index)

    def construct_mapping(self, node: yaml.MappingNode, deep: bool = False) -> dict[Any, Any]:
        seen: set[object] = set()
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=deep)
            if isinstance(key, Hashable) and key in seen:
                raise yaml.constructor.ConstructorError(None, None, f"duplicate key {shown(key)}", key_node.start_mark)
            seen.add(key)
        return super().construct_mapping(node, deep=deep)


def shown(value: object) -> str:
    """``repr(value)`` cut to a few elements and characters: messages quote values of any size."""
    return _SHOWN.repr(value)


def _yaml_problem(exc: yaml.YAMLError) -> str:
    """``, line N: not valid YAML: problem (context at line M)`` in one line, without PyYAML's excerpt."""
    if not isinstance(exc, yaml.MarkedYAMLError) or exc.problem_mark is None:
        return f": not valid YAML: {exc}"
    context = ""
    if exc.context is not None and exc.context_mark is not None:
        context = f" ({exc.context} at line {exc.context_mark.line + 1})"
    return f", line {exc.problem_mark.line + 1}: not valid YAML: {exc.problem}{context}"
