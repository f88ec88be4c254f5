"""Malformed-input machinery for tests/test_malformed_corpus.py.

An :class:`Entry` is one public entry point: how to draw a valid call (``make``), how to run it
(``call``), and the role of each argument (:class:`Arg`). A case takes a valid call, replaces one
argument by a :class:`Mutation` of it and checks the outcome against the mutation's
:class:`Expect`:

- ``SAME``: a valid but odd layout of the same numbers (Fortran order, negative strides, a strided
  view, read-only, big-endian, float32 / int values, Python lists). The call must give exactly
  (bit for bit) what it gives for a clean C-contiguous float64 copy of those numbers, or raise
  the same imukit error for both.
- ``RAISE``: invalid input (NaN, ±inf, wrong shape, dtype or timestamps). The call must raise an
  :class:`imukit.ImukitError` whose message starts with the argument's name.
- ``EITHER``: finite but extreme input (subnormals, 1e300, empty, one sample, gaps, stamps near
  2⁶³). The call must return a finite result (no NaN, no ±inf) or raise an ``ImukitError`` naming
  the argument.

Anything else (another exception, a ``PanicException``, NaN or inf from finite input) is a failure.
:data:`STATS` counts the cases for the pytest summary (tests/conftest.py).
"""

from __future__ import annotations

import dataclasses
import enum
import math
import re
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

import imukit as ik


class Expect(enum.Enum):
    SAME = "same result as the clean float64 copy"
    RAISE = "an ImukitError naming the argument"
    EITHER = "a finite result or an ImukitError naming the argument"
    NAN_OK = "a result (NaN documented as missing) or an ImukitError naming the argument"


@dataclass
class Stats:
    cases: int = 0
    entries: set[str] = field(default_factory=set)  # the public names the cases went through
    failures: int = 0

    def summary(self) -> str:
        return (
            f"malformed-input corpus: {self.cases:,} cases through {len(self.entries)} public entry points, "
            f"{self.failures} failures"
        )


STATS = Stats()

INT64_MAX = int(np.iinfo(np.int64).max)
EPOCH_NS = 1_400_000_000_000_000_000  # a EuRoC-like epoch stamp [ns]


@dataclass(frozen=True)
class Arg:
    """One argument of an entry point.

    ``role``: ``"batch"`` (any leading dimensions, trailing shape ``tail``), ``"array"`` (exactly the
    drawn shape), ``"times"`` (strictly increasing float seconds, (N,)), ``"scalar"`` (a float
    option), ``"int"`` (an integer option), ``"rotation"`` (one scipy Rotation), ``"rotations"``
    (a Rotation of the drawn length), ``"object"`` (an imukit object such as ImuData).
    ``names``: accepted first words of an error message about this argument (default: the name).
    """

    role: str
    tail: tuple[int, ...] = ()
    names: tuple[str, ...] = ()
    optional: bool = False  # None is a valid value
    free_length: bool = False  # "array": any length N ≥ 1 is valid (taus, boundaries)
    nan_ok: bool = False  # NaN is documented as a valid value (missing truth rows)
    index: bool = False  # an index: out of range raises IndexError (naming it), as in Python
    # Documented freedoms: mutation label -> the expectation that holds for this argument instead.
    relabel: tuple[tuple[str, Expect], ...] = ()


@dataclass(frozen=True)
class Mutation:
    label: str
    value: Any
    expect: Expect
    reference: Any = None  # for SAME: the clean C-contiguous float64 equivalent


@dataclass
class Entry:
    """One public entry point (or a method) and the names it covers."""

    name: str
    covers: tuple[str, ...]
    make: Callable[[np.random.Generator], dict[str, Any]]
    call: Callable[[dict[str, Any]], Any]
    args: dict[str, Arg]
    clean_is_valid: bool = True  # False where only the mutations make a valid call
    examples: int | None = None  # hypothesis examples, when not the corpus default


# ----------------------------------------------------------------------------- mutations


def _clean(x: Any) -> np.ndarray:
    return np.array(np.asarray(x), dtype=np.float64, order="C")


def _same(label: str, value: Any) -> Mutation:
    return Mutation(label, value, Expect.SAME, _clean(value))


def _readonly(a: np.ndarray) -> np.ndarray:
    out = a.copy()
    out.flags.writeable = False
    return out


def _strided(a: np.ndarray) -> np.ndarray:
    """A view with every stride doubled (not contiguous), holding the values of ``a``."""
    big = np.zeros(tuple(2 * max(d, 1) for d in a.shape))
    view = big[tuple(slice(0, 2 * d, 2) for d in a.shape)]
    view[...] = a
    return view


def _negative(a: np.ndarray) -> np.ndarray:
    """A view with negative strides on every axis, holding the values of ``a``."""
    flip = tuple(slice(None, None, -1) for _ in a.shape)
    return np.ascontiguousarray(a[flip])[flip]


def _poke(a: np.ndarray, rng: np.random.Generator, value: float) -> np.ndarray:
    out = np.array(a, dtype=np.float64)
    if out.size:
        out.flat[int(rng.integers(out.size))] = value
    return out


def layout_mutations(a: np.ndarray) -> list[Mutation]:
    """Valid layouts of the same numbers (SAME)."""
    out = [
        _same("fortran order", np.asfortranarray(a)),
        _same("negative strides", _negative(a)),
        _same("strided view", _strided(a)),
        _same("read-only", _readonly(a)),
        _same("big-endian", a.astype(">f8")),
        _same("float32", a.astype(np.float32)),
        _same("int64 values", np.round(a).astype(np.int64)),
        _same("python list", a.tolist()),
    ]
    if a.ndim >= 2:
        out.append(_same("transposed copy viewed back", np.ascontiguousarray(np.swapaxes(a, -1, -2)).swapaxes(-1, -2)))
    return out


def value_mutations(a: np.ndarray, rng: np.random.Generator) -> list[Mutation]:
    """Non-finite (RAISE) and extreme finite (EITHER) values."""
    return [
        Mutation("NaN", _poke(a, rng, math.nan), Expect.RAISE),
        Mutation("+inf", _poke(a, rng, math.inf), Expect.RAISE),
        Mutation("-inf", _poke(a, rng, -math.inf), Expect.RAISE),
        Mutation("subnormal element", _poke(a, rng, 5e-324), Expect.EITHER),
        Mutation("all subnormal", np.full(a.shape, 2.5e-310), Expect.EITHER),
        Mutation("huge element", _poke(a, rng, float(rng.choice([1e300, -1e300]))), Expect.EITHER),
        Mutation("all huge", np.full(a.shape, 1e300), Expect.EITHER),
        Mutation("large element", _poke(a, rng, 1e150), Expect.EITHER),
        Mutation("all zero", np.zeros(a.shape), Expect.EITHER),
    ]


def dtype_mutations(a: np.ndarray) -> list[Mutation]:
    """dtypes that are not real numbers (RAISE)."""
    return [
        Mutation("bool dtype", a != 0, Expect.RAISE),
        Mutation("object dtype", np.array(a, dtype=object), Expect.RAISE),
        Mutation("complex dtype", a.astype(np.complex128), Expect.RAISE),
        Mutation("str dtype", a.astype(str), Expect.RAISE),
        Mutation("None", None, Expect.RAISE),
    ]


def batch_shape_mutations(a: np.ndarray, tail: tuple[int, ...]) -> list[Mutation]:
    rows = a.reshape((-1, *tail))
    wrong_last = np.zeros((*a.shape[:-1], a.shape[-1] + 1))
    return [
        Mutation("wrong last dimension", wrong_last, Expect.RAISE),
        Mutation("short last dimension", a[..., :-1], Expect.RAISE),
        Mutation("extra trailing axis", a[..., None], Expect.RAISE),
        Mutation("0-d", np.float64(1.0), Expect.RAISE),
        Mutation("empty batch", np.zeros((0, *tail)), Expect.EITHER),
        _same("one element", rows[:1]),
        _same("extra leading axes", rows[None, None]),
    ]


def exact_shape_mutations(a: np.ndarray) -> list[Mutation]:
    out = [
        Mutation("wrong last dimension", np.zeros((*a.shape[:-1], a.shape[-1] + 1)), Expect.RAISE),
        Mutation("extra leading axis", a[None], Expect.RAISE),
        Mutation("flattened", a.reshape(-1) if a.ndim > 1 else a[:, None], Expect.RAISE),
        Mutation("0-d", np.float64(1.0), Expect.RAISE),
        Mutation("empty", np.zeros((0, *a.shape[1:])), Expect.RAISE),
    ]
    if a.ndim >= 1 and len(a) > 1:
        out.append(Mutation("one row short", a[:-1], Expect.RAISE))
    return out


def times_mutations(t: np.ndarray, rng: np.random.Generator) -> list[Mutation]:
    """Timestamp pathologies for strictly increasing float seconds ``t`` (N ≥ 2)."""
    n = len(t)
    k = int(rng.integers(1, n))
    dup, back = t.copy(), t.copy()
    dup[k] = dup[k - 1]
    back[k] = back[k - 1] - 0.25 * (t[1] - t[0])
    gap = t.copy()
    gap[k:] += 1000.0
    ns = EPOCH_NS + np.round((t - t[0]) * 1e9).astype(np.int64)
    near_max = INT64_MAX - (ns[-1] - ns)
    shifted = t - t[0] + 3.0
    mixed: list[float] = [3, *shifted[1:].tolist()]  # a Python int among floats
    return [
        _same("python list", t.tolist()),
        _same("read-only", _readonly(t)),
        _same("negative strides", _negative(t)),
        _same("strided view", _strided(t)),
        _same("big-endian", t.astype(">f8")),
        Mutation("list of an int and floats", mixed, Expect.SAME, shifted),
        Mutation("duplicate stamp", dup, Expect.RAISE),
        Mutation("decreasing stamp", back, Expect.RAISE),
        Mutation("all decreasing", t[::-1].copy(), Expect.RAISE),
        Mutation("NaN stamp", _poke(t, rng, math.nan), Expect.RAISE),
        Mutation("inf stamp", _poke(t, rng, math.inf), Expect.RAISE),
        Mutation("2-d stamps", t[:, None], Expect.RAISE),
        Mutation("bool stamps", np.arange(n) % 2 == 1, Expect.RAISE),
        Mutation("complex stamps", t.astype(np.complex128), Expect.RAISE),
        Mutation("object stamps", np.array(t, dtype=object), Expect.RAISE),
        Mutation("str stamps", t.astype(str), Expect.RAISE),
        Mutation("None", None, Expect.RAISE),
        Mutation("sample indices as ints", np.arange(n), Expect.RAISE),
        Mutation("uint64 past int64 max", np.uint64(INT64_MAX) + np.arange(1, n + 1, dtype=np.uint64), Expect.RAISE),
        Mutation("gap of 1000 s", gap, Expect.EITHER),
        Mutation("int64 ns at an epoch", ns, Expect.EITHER),
        Mutation("uint64 ns", ns.astype(np.uint64), Expect.EITHER),
        Mutation("int64 ns ending at 2^63 - 1", near_max, Expect.EITHER),
        Mutation("int64 ns spanning ±2^62", np.linspace(-(2**62), 2**62, n).astype(np.int64), Expect.EITHER),
        Mutation("float ns (1.4e18 'seconds')", ns.astype(np.float64), Expect.EITHER),
        Mutation("one sample", t[:1].copy(), Expect.EITHER),
        Mutation("empty", np.zeros(0), Expect.EITHER),
        Mutation("huge seconds", t + 1e300, Expect.EITHER),
    ]


def scalar_mutations() -> list[Mutation]:
    return [
        Mutation("NaN", math.nan, Expect.RAISE),
        Mutation("+inf", math.inf, Expect.EITHER),
        Mutation("-inf", -math.inf, Expect.RAISE),
        Mutation("negative", -1.0, Expect.EITHER),
        Mutation("zero", 0.0, Expect.EITHER),
        Mutation("huge", 1e300, Expect.EITHER),
        Mutation("subnormal", 5e-324, Expect.EITHER),
        Mutation("numpy float32", np.float32(0.5), Expect.EITHER),
        Mutation("string", "0.5", Expect.RAISE),
        Mutation("non-numeric string", "fast", Expect.RAISE),
        Mutation("None", None, Expect.EITHER),
        Mutation("array", np.array([1.0, 2.0]), Expect.RAISE),
    ]


def int_mutations() -> list[Mutation]:
    return [
        Mutation("zero", 0, Expect.EITHER),
        Mutation("negative", -1, Expect.EITHER),
        Mutation("float", 1.5, Expect.RAISE),
        Mutation("bool", True, Expect.EITHER),
        Mutation("huge", 2**70, Expect.EITHER),
        Mutation("numpy int", np.int64(2), Expect.EITHER),
        Mutation("string", "2", Expect.RAISE),
    ]


def rotation_mutations(n: int | None) -> list[Mutation]:
    quats = Rotation.identity(max(n or 2, 2)).as_quat()
    out = [
        Mutation("quaternion array", quats[0] if n is None else quats[:n], Expect.RAISE),
        Mutation("string", "identity", Expect.RAISE),
    ]
    if n is None:
        out.append(Mutation("several rotations", Rotation.identity(2), Expect.RAISE))
    else:
        out += [
            Mutation("single rotation", Rotation.identity(), Expect.RAISE),
            Mutation("one rotation too many", Rotation.identity(n + 1), Expect.RAISE),
        ]
    return out


def object_mutations() -> list[Mutation]:
    return [
        Mutation("array", np.zeros((2, 3)), Expect.RAISE),
        Mutation("string", "imu.csv", Expect.RAISE),
        Mutation("dict", {"t": [0.0, 1.0]}, Expect.RAISE),
    ]


def mutations(arg: Arg, value: Any, rng: np.random.Generator) -> list[Mutation]:
    """Every mutation of ``value`` for its role."""
    if arg.role in ("batch", "array"):
        a = np.asarray(value, dtype=np.float64)
        shape = batch_shape_mutations(a, arg.tail) if arg.role == "batch" else exact_shape_mutations(a)
        return layout_mutations(a) + value_mutations(a, rng) + dtype_mutations(a) + shape
    if arg.role == "times":
        return times_mutations(np.asarray(value, dtype=np.float64), rng)
    if arg.role == "scalar":
        return scalar_mutations()
    if arg.role == "int":
        return int_mutations()
    if arg.role == "rotation":
        return rotation_mutations(None)
    if arg.role == "rotations":
        return rotation_mutations(len(value))
    if arg.role == "object":
        return object_mutations()
    raise AssertionError(f"unknown role {arg.role}")


def signal_mutations(a: np.ndarray, rng: np.random.Generator) -> list[Mutation]:
    """For an ``(N,)`` or ``(N, C)`` signal: layouts, values, dtypes and shapes."""
    shapes = [
        Mutation("extra leading axis", a[None], Expect.RAISE),
        Mutation("0-d", np.float64(1.0), Expect.RAISE),
        Mutation("empty", np.zeros((0, *a.shape[1:])), Expect.RAISE),
        Mutation("one sample", a[:1], Expect.RAISE),
        Mutation("no columns", np.zeros((len(a), 0)), Expect.RAISE),
        _same("one column", a.reshape(len(a), -1)[:, :1]),
    ]
    return layout_mutations(a) + value_mutations(a, rng) + dtype_mutations(a) + shapes


def mask_mutations(mask: np.ndarray) -> list[Mutation]:
    """For a boolean ``(N,)`` selection."""
    n = len(mask)
    return [
        Mutation("python list of bools", mask.tolist(), Expect.SAME, mask.copy()),
        Mutation("read-only", _readonly(mask), Expect.SAME, mask.copy()),
        Mutation("negative strides", _negative(mask), Expect.SAME, mask.copy()),
        Mutation("all False", np.zeros(n, dtype=bool), Expect.EITHER),
        Mutation("float 0/1", mask.astype(np.float64), Expect.RAISE),
        # An integer 0/1 array is a mask (MATLAB logical, uint8 columns); a float one may be weights.
        Mutation("int 0/1", mask.astype(np.int64), Expect.SAME, mask.copy()),
        Mutation("int 0/2", mask.astype(np.int64) * 2, Expect.RAISE),
        Mutation("one too long", np.ones(n + 1, dtype=bool), Expect.RAISE),
        Mutation("2-d", mask[None], Expect.RAISE),
        Mutation("object dtype", np.array(mask, dtype=object), Expect.RAISE),
        Mutation("string", "all", Expect.RAISE),
    ]


def mutations_of(arg: Arg, value: Any, rng: np.random.Generator) -> list[Mutation]:
    """:func:`mutations`, adjusted for the argument's documented freedoms."""
    if arg.role == "signal":
        found = signal_mutations(np.asarray(value, dtype=np.float64), rng)
    elif arg.role == "mask":
        found = mask_mutations(np.asarray(value, dtype=bool))
    else:
        found = mutations(arg, value, rng)
    out = []
    for m in found:
        if arg.optional and m.value is None:
            continue
        if arg.free_length and m.label == "one row short":
            continue
        if arg.nan_ok and m.label == "NaN":
            m = Mutation(m.label, m.value, Expect.NAN_OK)
        for label, expect in arg.relabel:
            if m.label == label:
                m = Mutation(m.label, m.value, expect, m.reference)
        out.append(m)
    return out


# ----------------------------------------------------------------------------- outcomes


def leaves(x: Any, path: str = "") -> Iterator[tuple[str, Any]]:
    """Every number-like leaf of a result, with a path: arrays, floats, Rotations (as quaternions)
    inside tuples, NamedTuples, lists, dicts, dataclasses and imukit's slotted objects."""
    if x is None or isinstance(x, (str, bool, int, np.bool_)):
        yield path, x
    elif isinstance(x, Rotation):
        yield path + ".as_quat()", x.as_quat()
    elif isinstance(x, np.ndarray):
        yield path, x
    elif isinstance(x, (float, np.floating, np.integer)):
        yield path, np.float64(x)
    elif isinstance(x, dict):
        for k, v in x.items():
            yield from leaves(v, f"{path}[{k!r}]")
    elif isinstance(x, (tuple, list)):
        for i, v in enumerate(x):
            yield from leaves(v, f"{path}[{i}]")
    elif dataclasses.is_dataclass(x):
        for f in dataclasses.fields(x):
            yield from leaves(getattr(x, f.name), f"{path}.{f.name}")
    elif isinstance(x, ik.PreintegratedImu):
        yield from leaves(x._state(), path + "._state()")
        yield from leaves(x.covariance_combined, path + ".covariance_combined")
    elif isinstance(x, (ik.filters.Mahony, ik.filters.Madgwick)):
        yield from leaves(x.get_state(), path + ".get_state()")
    elif hasattr(type(x), "__slots__"):
        for name in type(x).__slots__:
            yield from leaves(getattr(x, name, None), f"{path}.{name}")
    else:
        raise AssertionError(f"{path}: no rule to compare a {type(x).__name__}")


def nonfinite_paths(result: Any) -> list[str]:
    """Where a result holds NaN or ±inf (docs/guarantees.md: neither comes from finite input)."""
    bad = []
    for path, leaf in leaves(result):
        if isinstance(leaf, np.ndarray) and leaf.dtype.kind in "fc" and not np.isfinite(leaf).all():
            bad.append(path)
        elif isinstance(leaf, np.floating) and not np.isfinite(leaf):
            bad.append(path)
    return bad


def identical(a: Any, b: Any) -> str | None:
    """None when ``a`` and ``b`` are bit-for-bit the same result, else where they differ."""
    la, lb = list(leaves(a)), list(leaves(b))
    if [p for p, _ in la] != [p for p, _ in lb]:
        return f"structure differs: {[p for p, _ in la]} vs {[p for p, _ in lb]}"
    for (path, x), (_, y) in zip(la, lb):
        if isinstance(x, np.ndarray) or isinstance(y, np.ndarray):
            x, y = np.asarray(x), np.asarray(y)
            if x.shape != y.shape or x.dtype != y.dtype or x.tobytes() != y.tobytes():
                return f"{path} differs"
        elif isinstance(x, np.floating):
            if np.asarray(x).tobytes() != np.asarray(y).tobytes():
                return f"{path} differs: {x!r} vs {y!r}"
        elif x != y:
            return f"{path} differs: {x!r} vs {y!r}"
    return None


def names_argument(message: str, names: tuple[str, ...]) -> bool:
    """Whether the message starts with one of ``names`` (before its first ``:``, where several
    arguments may be named, as in ``q / p: ...``)."""
    head = message.split(":", 1)[0]
    return any(re.search(rf"(^|[\s/(]){re.escape(n)}($|[\s/\[.(])", head) for n in names)


def run_call(entry: Entry, values: dict[str, Any]) -> tuple[str, Any]:
    """("ok", result) or ("error", exception); a non-Exception BaseException (PanicException)
    is returned as ("panic", exc)."""
    try:
        return "ok", entry.call(values)
    except Exception as exc:
        return "error", exc
    except BaseException as exc:  # pyo3's PanicException derives from BaseException
        if isinstance(exc, (KeyboardInterrupt, SystemExit)):
            raise
        return "panic", exc


def check_case(entry: Entry, values: dict[str, Any], arg_name: str, mutation: Mutation) -> str | None:
    """Run one case; None when the outcome meets the expectation, else a description."""
    STATS.cases += 1
    STATS.entries.update(entry.covers)
    mutated = {**values, arg_name: mutation.value}
    kind, out = run_call(entry, mutated)
    where = f"{entry.name}: {arg_name} <- {mutation.label} (expected {mutation.expect.value})"
    names = entry.args[arg_name].names or (arg_name,)
    if kind == "panic":
        return f"{where}: PANIC {type(out).__name__}: {out}"
    if kind == "error":
        if entry.args[arg_name].index and isinstance(out, IndexError) and names_argument(str(out), names):
            return None
        if not isinstance(out, ik.ImukitError):
            return f"{where}: raised {type(out).__name__}: {out}"
        if mutation.expect is Expect.SAME:
            ref_kind, ref = run_call(entry, {**values, arg_name: mutation.reference})
            # The same error about the same argument (a message may quote the dtype, e.g. '>f8').
            if ref_kind == "error" and type(ref) is type(out) and str(ref).split(":")[0] == str(out).split(":")[0]:
                return None
            return f"{where}: raised {type(out).__name__}: {out}; the clean copy gave {ref_kind} {ref!r}"
        if not names_argument(str(out), names):
            return f"{where}: {type(out).__name__} does not start with {names}: {out}"
        return None
    if mutation.expect is Expect.RAISE:
        return f"{where}: returned instead of raising"
    if mutation.expect is Expect.NAN_OK:
        return None
    bad = nonfinite_paths(out)
    if bad:
        return f"{where}: NaN or inf in {bad} from finite input"
    if mutation.expect is Expect.SAME:
        ref_kind, ref = run_call(entry, {**values, arg_name: mutation.reference})
        if ref_kind != "ok":
            return f"{where}: returned, but the clean copy gave {ref_kind} {ref!r}"
        diff = identical(out, ref)
        if diff:
            return f"{where}: {diff} from the clean copy's result"
    return None


def check_clean(entry: Entry, values: dict[str, Any]) -> str | None:
    """The unmutated valid call must succeed with a finite result."""
    STATS.cases += 1
    STATS.entries.update(entry.covers)
    kind, out = run_call(entry, values)
    if kind != "ok":
        return f"{entry.name}: the valid call gave {kind} {type(out).__name__}: {out}"
    bad = nonfinite_paths(out)
    return f"{entry.name}: NaN or inf in {bad} from a valid call" if bad else None
