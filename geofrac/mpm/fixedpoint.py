"""Exact, order-free sums of floats: fixed-point accumulation in pairs of int64 words.

A floating-point sum depends on the order of its terms; the MPM's nodal sums (mass,
momentum, forces) are taken over a rank's particles in their local order and then over
the ranks, so 1 and 2 ranks would round differently and a long chaotic run would drift
apart. Here every term c of a column is put on a fixed grid of 2^−(HI_BITS + LO_BITS)
times a power of two 2^e above every term of the column (the same on every rank: e comes
from an allreduced bound) and split into two integers,

    x = c · 2^(HI_BITS − e),   hi = trunc x,   lo = trunc((x − hi) · 2^LO_BITS),

so that c ≈ (hi + lo 2^−LO_BITS) 2^(e − HI_BITS) with an error below 2^(e − 102). Integer
sums are associative: the pairs of a node (or of a rank's particles) add up to the same
integers in any order, over any ranks, and one conversion back to float64
(:func:`to_float`) gives every rank and every rank count the same value, to the last bit.

Budget: |x| < 2^HI_BITS = 2^40, so a node can take 2^22 terms before its ``hi`` word
could overflow. The bound need not be tight nor strict: terms 2^k times above it still
add up exactly while 2^k times the terms of a node stays below 2^22 (the step bounds φ
by 1 and |∇φ| by 1/L, which cpGIMP's stretched half-widths beyond L/2 exceed by a small
factor); ``lo`` is kept in [0, 2^LO_BITS) = [0, 2^62) by carrying into ``hi``
(after every addition in the compiled loops, once per sum here). A node far lighter than
the heaviest term (the mass floor of :mod:`~geofrac.mpm.schemes`, 1e-12, or below) keeps
its float64 digits: 2^−102 of the largest term is ~1e-31.

The conversion (:func:`to_float`) is a function of the integers alone, so every rank
gets the same float; a column whose bound is not finite (a blown-up step) becomes NaN,
so the step's checks still see it.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = [
    "HI_BITS",
    "LO_BITS",
    "accumulate",
    "exact_sums",
    "exponents",
    "normalise",
    "scales",
    "split",
    "to_float",
]

#: Bits of a term's integer part: |x| < 2^HI_BITS.
HI_BITS = 40
#: Bits of the fraction word: 0 <= lo < 2^LO_BITS.
LO_BITS = 62
#: The least exponent e (bounds below 2^-900 are taken as 2^-900).
MIN_EXPONENT = -900
_HALF = 31  # lo is summed in two halves of 31 bits here (no carry per addition)


def exponents(bound: np.ndarray) -> np.ndarray:
    """The exponent e per column: every term below 2^e (twice the bound, for margin).

    Args:
        bound: the largest |term| of each column (or an upper bound), shape=(c,).

    Returns:
        shape=(c,) int64; a non-finite bound gives 0 (:func:`to_float` makes its column
        NaN).
    """
    bound = np.asarray(bound, dtype=float)
    finite = np.isfinite(bound)
    e = np.frexp(np.where(finite, bound, 1.0))[1].astype(np.int64) + 1
    return np.where(finite, np.maximum(e, MIN_EXPONENT), 0)


def scales(bound: np.ndarray) -> np.ndarray:
    """2^(HI_BITS − e): a term times it lies in (−2^HI_BITS, 2^HI_BITS), shape=(c,).

    Args:
        bound: the largest |term| of each column (or an upper bound), shape=(c,).
    """
    return np.ldexp(1.0, HI_BITS - exponents(bound))


def split(terms: np.ndarray, scale: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(hi, lo) of every term, both int64 of terms' shape (the last axis is the column).

    hi = trunc x and lo = trunc((x − hi) 2^LO_BITS), x = term · scale: both carry the
    term's sign, and hi + lo 2^−LO_BITS is x to 2^−LO_BITS.

    Args:
        terms: shape=(..., c).
        scale: :func:`scales`, shape=(c,).
    """
    x = terms * scale
    hi = x.astype(np.int64)
    return hi, ((x - hi) * float(2**LO_BITS)).astype(np.int64)


def normalise(acc: np.ndarray) -> np.ndarray:
    """Carry lo's excess into hi, so 0 <= lo < 2^LO_BITS (in place and returned).

    Args:
        acc: pairs (hi, lo), shape=(..., 2) int64 (lo of any sign: the shift floors).
    """
    acc[..., 0] += acc[..., 1] >> LO_BITS
    acc[..., 1] &= (1 << LO_BITS) - 1
    return acc


def _halves(hi: np.ndarray, lo_upper: np.ndarray, lo_lower: np.ndarray) -> np.ndarray:
    """Normalised pairs from the sums of hi, lo >> 31 and lo & (2^31 − 1), shape=(..., 2)."""
    mask = (1 << _HALF) - 1
    acc = np.empty((*hi.shape, 2), np.int64)
    acc[..., 0] = hi + (lo_upper >> _HALF)
    acc[..., 1] = ((lo_upper & mask) << _HALF) + lo_lower
    return normalise(acc)


def accumulate(nodes: np.ndarray, terms: np.ndarray, scale: np.ndarray, *, num: int) -> np.ndarray:
    """Exact sums of per-(item, node) terms onto ``num`` nodes: the numpy reference.

    lo is summed in two halves of 31 bits (exact for fewer than 2^32 terms a node), so
    no carry is needed per addition.

    Args:
        nodes: node ids, shape=(n, k).
        terms: shape=(n, k, c).
        scale: :func:`scales`, shape=(c,).
        num: number of nodes.

    Returns:
        Normalised pairs, shape=(num, c, 2) int64.
    """
    c = terms.shape[-1]
    hi, lo = split(terms.reshape(-1, c), scale)
    flat = nodes.reshape(-1)
    sums = np.zeros((3, num, c), np.int64)
    np.add.at(sums[0], flat, hi)
    np.add.at(sums[1], flat, lo >> _HALF)
    np.add.at(sums[2], flat, lo & ((1 << _HALF) - 1))
    return _halves(*sums)


def to_float(acc: np.ndarray, bound: np.ndarray) -> np.ndarray:
    """The float64 values of normalised pairs, (hi + lo 2^−62) 2^(e − 40).

    lo is first centred (hi + 1, lo − 2^62 when lo >= 2^61), so a small negative sum is
    not the difference of two nearly equal numbers: the result is within about one
    rounding of the pairs' exact value, and a function of the integers alone.

    Args:
        acc: shape=(..., c, 2) int64, normalised.
        bound: the bound the pairs were split with, shape=(c,); the columns of a
            non-finite bound are NaN.

    Returns:
        shape=(..., c).
    """
    hi, lo = acc[..., 0].copy(), acc[..., 1].copy()
    up = lo >= 1 << (LO_BITS - 1)
    hi[up] += 1
    lo[up] -= 1 << LO_BITS
    out = np.ldexp(
        hi.astype(float) + np.ldexp(lo.astype(float), -LO_BITS), exponents(bound) - HI_BITS
    )
    out[..., ~np.isfinite(np.asarray(bound, dtype=float))] = np.nan
    return out


def exact_sums(values: np.ndarray, comm: Any = None) -> np.ndarray:
    """Column sums over the rows of every rank of ``comm``, the same for any split of rows.

    Two small allreduces (the columns' largest |value|, then the integer sums): neither
    the rows' order nor their distribution over the ranks changes the result.

    Args:
        values: this rank's rows, shape=(n, c).
        comm: an mpi4py communicator, or None for this process alone.

    Returns:
        shape=(c,).
    """
    values = np.asarray(values, dtype=float)
    bound = np.abs(values).max(axis=0, initial=0.0)
    many = comm is not None and comm.size > 1
    if many:
        from mpi4py import MPI

        comm.Allreduce(MPI.IN_PLACE, bound, op=MPI.MAX)
    hi, lo = split(values, scales(bound))
    acc = _halves(hi.sum(axis=0), (lo >> _HALF).sum(axis=0), (lo & ((1 << _HALF) - 1)).sum(axis=0))
    if many:
        comm.Allreduce(MPI.IN_PLACE, acc, op=MPI.SUM)
        normalise(acc)
    return to_float(acc, bound)
