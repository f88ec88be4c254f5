"""Immutable value classes that are data: they pickle and deep-copy exactly.

A :class:`Frozen` subclass lists its ``__slots__`` and, in ``_fields``, the order in which
``_from_validated`` takes them. Its public constructor validates and copies; ``_from_validated``
does neither (the values are already checked: a pickle, a deep copy, fresh output of the core)
and only clears the writeable flag of every array, so a copy is as read-only as the original.
``__reduce__`` is ``(cls._from_validated, fields)``: pickle and ``copy.deepcopy`` round trip
every array bit for bit, dtype and read-only flag included, with no re-validation.
"""

from __future__ import annotations

from typing import Any, ClassVar, TypeVar

import numpy as np

_F = TypeVar("_F", bound="Frozen")


class Frozen:
    """Base of imukit's immutable ``__slots__`` value classes (module docs)."""

    __slots__ = ()
    _fields: ClassVar[tuple[str, ...]]

    def __setattr__(self, name: str, value: object) -> None:
        raise AttributeError(f"{type(self).__name__} is immutable: cannot set {name!r}")

    @classmethod
    def _from_validated(cls: type[_F], *values: Any) -> _F:
        """An instance over ``values`` (in ``_fields`` order), neither checked nor copied; arrays
        are made read-only in place, so they must not be shared with a writer."""
        obj = object.__new__(cls)
        obj._set(*values)
        return obj

    def _set(self, *values: Any) -> None:
        """Set every field, in ``_fields`` order, once (constructors end with it)."""
        if len(values) != len(self._fields):
            raise TypeError(f"{type(self).__name__} has {len(self._fields)} fields, got {len(values)} values")
        for name, value in zip(self._fields, values):
            if isinstance(value, np.ndarray):
                value.setflags(write=False)
            object.__setattr__(self, name, value)

    def __reduce__(self) -> tuple[Any, tuple[Any, ...]]:
        return (type(self)._from_validated, tuple(getattr(self, name) for name in self._fields))
