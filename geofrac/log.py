"""Rank-0 messages and progress reporting.

Every message a user sees comes from rank 0 of the communicator the run uses, so an
``mpiexec -n 64`` job prints each line once. Errors that every rank detects (scene
validation) are printed once and every rank exits non-zero.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from typing import Protocol

__all__ = ["Progress", "echo", "format_seconds", "sayer"]


class _Comm(Protocol):
    rank: int


def echo(comm: _Comm | None, message: str, *, err: bool = False) -> None:
    """Print ``message`` on rank 0 only (or always when ``comm`` is ``None``)."""
    if comm is not None and comm.rank != 0:
        return
    stream = sys.stderr if err else sys.stdout
    print(message, file=stream, flush=True)


def sayer(comm: _Comm | None, *, verbose: bool = True) -> Callable[[str], None]:
    """A progress printer: :func:`echo` on ``comm``'s rank 0, or silence when not ``verbose``."""
    if not verbose:
        return lambda message: None
    return lambda message: echo(comm, message)


def format_seconds(seconds: float) -> str:
    """Format a duration as ``1h02m``, ``3m05s``, ``4.2s`` or ``12ms``."""
    if seconds >= 3600:
        return f"{int(seconds // 3600)}h{int(seconds % 3600 // 60):02d}m"
    if seconds >= 60:
        return f"{int(seconds // 60)}m{int(seconds % 60):02d}s"
    if seconds >= 1:
        return f"{seconds:.1f}s"
    return f"{seconds * 1000:.0f}ms"


class Progress:
    """Rank-0 progress lines for a loop of known length: steps done, rate, time left.

    Args:
        comm: communicator whose rank 0 prints (``None`` prints always).
        total: number of steps.
        label: prefix of every line.
        unit: what a step is, for the rate (``cases`` gives "cases/s").
    """

    def __init__(self, comm: _Comm | None, total: int, label: str, *, unit: str = "steps") -> None:
        self.comm = comm
        self.total = total
        self.label = label
        self.unit = unit
        self.done = 0
        self.start = time.perf_counter()

    def step(self, what: str = "") -> None:
        """Mark one step done and print ``[done/total] what  rate  left``."""
        self.done += 1
        elapsed = time.perf_counter() - self.start
        rate = self.done / elapsed if elapsed > 0 else float("inf")
        left = (self.total - self.done) / rate if rate > 0 else 0.0
        echo(
            self.comm,
            f"{self.label} [{self.done}/{self.total}] {what}  "
            f"({rate:.2f} {self.unit}/s, elapsed {format_seconds(elapsed)}, "
            f"left ~{format_seconds(left)})",
        )
