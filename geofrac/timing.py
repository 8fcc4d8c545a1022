"""Wall-clock time per phase, reduced over ranks (the slowest rank counts)."""

from __future__ import annotations

import resource
import time
from collections.abc import Iterator
from contextlib import contextmanager
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from mpi4py import MPI

__all__ = ["Timings", "peak_rss_mb"]


def peak_rss_mb() -> float:
    """This process's peak resident memory so far, in MiB (``ru_maxrss``)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


class Timings:
    """Accumulates seconds per named phase on this rank."""

    def __init__(self) -> None:
        self.local: dict[str, float] = {}

    @contextmanager
    def phase(self, name: str) -> Iterator[None]:
        """Time the ``with`` block and add it to phase ``name``."""
        start = time.perf_counter()
        try:
            yield
        finally:
            self.local[name] = self.local.get(name, 0.0) + time.perf_counter() - start

    def reduced(self, comm: MPI.Comm) -> dict[str, float]:
        """Per-phase maximum over the ranks of ``comm`` (collective), plus ``total``."""
        names = list(self.local)
        gathered = comm.allgather([self.local[n] for n in names])
        values = [max(column) for column in zip(*gathered, strict=True)]
        out = dict(zip(names, values, strict=True))
        out["total"] = sum(values)
        return out
