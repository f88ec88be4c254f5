"""Associative composition along the sequence (dim 0) of tuples of tensors.

``combine(a, b)`` composes element ``a`` (earlier) with ``b`` (later); it must be associative.
``scan`` returns every prefix ``x_0 ∘ … ∘ x_k`` with O(N) work and O(log N) depth: combine
neighbouring pairs, scan the half-length sequence recursively (its element j is the prefix
through 2j + 1), then finish each even prefix with one more combination (Blelloch, "Prefix sums
and their applications", 1990, the recursive formulation). ``reduce`` returns only the total in
log₂ N pairwise levels. ``sequential`` is the left fold, the reference both are tested against.
"""

from __future__ import annotations

from collections.abc import Callable

import torch

Elements = tuple[torch.Tensor, ...]
Combine = Callable[[Elements, Elements], Elements]


def _take(xs: Elements, index: slice) -> Elements:
    return tuple(x[index] for x in xs)


def _pairs(combine: Combine, xs: Elements) -> Elements:
    half = xs[0].shape[0] // 2
    return combine(_take(xs, slice(0, 2 * half, 2)), _take(xs, slice(1, 2 * half, 2)))


def scan(combine: Combine, xs: Elements) -> Elements:
    """Inclusive prefix compositions, the same length as ``xs``."""
    n = xs[0].shape[0]
    if n == 1:
        return xs
    odd = scan(combine, _pairs(combine, xs))
    rest = combine(_take(odd, slice(0, (n - 1) // 2)), _take(xs, slice(2, n, 2)))
    even = tuple(torch.cat((x[:1], r)) for x, r in zip(xs, rest))
    if n % 2:
        odd = tuple(torch.cat((o, e[-1:])) for o, e in zip(odd, even))
    # Interleave: even prefixes at 0, 2, …, odd ones at 1, 3, … (the padding row is cut off).
    return tuple(torch.stack((e, o), dim=1).flatten(0, 1)[:n] for e, o in zip(even, odd))


def reduce(combine: Combine, xs: Elements) -> Elements:
    """The composition of all elements, with a leading dimension of 1."""
    while xs[0].shape[0] > 1:
        n = xs[0].shape[0]
        paired = _pairs(combine, xs)
        xs = tuple(torch.cat((p, x[n - 1 :])) for p, x in zip(paired, xs)) if n % 2 else paired
    return xs


def sequential(combine: Combine, xs: Elements, *, keep: bool) -> Elements:
    """The left fold, one element at a time: every prefix with ``keep``, else the total (length 1)."""
    acc = _take(xs, slice(0, 1))
    out = [acc]
    for k in range(1, xs[0].shape[0]):
        acc = combine(acc, _take(xs, slice(k, k + 1)))
        out.append(acc)
    if not keep:
        return acc
    return tuple(torch.cat(parts) for parts in zip(*out))
