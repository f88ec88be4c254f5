"""Enum names (schemes, representations, conventions) as the core declares them.

The Rust core owns every list of names (``named_enum!``) and parses them (an unknown name is a
``ParameterError`` from Rust naming the argument). Python only checks that a name is a string
and turns a deprecated alias into its canonical name with a ``DeprecationWarning``.
"""

from __future__ import annotations

from collections.abc import Mapping

from imukit._deprecation import deprecated
from imukit._errors import ParameterError

__all__ = ["canonical"]


def canonical(value: object, argument: str, names: tuple[str, ...], aliases: Mapping[str, str] | None = None) -> str:
    """``value`` as a name for the core: a str, with a deprecated alias replaced (and warned about)."""
    if not isinstance(value, str):
        raise ParameterError(f"expected one of {names}, got {value!r}", argument=argument)
    new = (aliases or {}).get(value)
    if new is None:
        return value
    deprecated(f"{argument}={value!r} is deprecated, use {argument}={new!r} (the same update rule)")
    return new
