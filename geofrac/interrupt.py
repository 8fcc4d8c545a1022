"""SIGTERM/SIGINT as a request to stop cleanly at the next step or event.

``mpiexec`` (MPICH's hydra) forwards SIGTERM and SIGINT to every rank; SLURM sends
SIGTERM before a time limit (``--signal``). :func:`install` turns both signals into a
flag; the long loops ask :func:`geofrac.io.checkpoint.RunControl.poll` after each
completed step or event, which reduces the flag over all ranks so that every rank stops
at the same step, writes a checkpoint and raises :class:`Interrupted`. A second signal
of the same kind more than :data:`REPEAT_S` seconds after the first takes the default
action, so pressing Ctrl-C again still kills; repeats within that time are the same
request arriving twice (Ctrl-C reaches both ``mpiexec``, which forwards it, and the
ranks of its process group) and are ignored.

No MPI and no DOLFINx here.
"""

from __future__ import annotations

import signal
import threading
import time
from types import FrameType

from geofrac.errors import RunError

__all__ = ["REPEAT_S", "Interrupted", "install", "reassert", "received", "reset", "uninstall"]

_SIGNALS = (signal.SIGTERM, signal.SIGINT)
#: Seconds after a signal during which the same signal again is taken as a duplicate.
REPEAT_S = 5.0
_received: list[int] = []
_first: dict[int, float] = {}
_previous: dict[int, object] = {}


class Interrupted(RunError):
    """The run stopped on a signal after writing a checkpoint (raised on every rank).

    Attributes:
        signum: the signal number (15 SIGTERM, 2 SIGINT).
        where: the last completed step or event, e.g. ``"event 120"``.
    """

    def __init__(self, signum: int, where: str) -> None:
        self.signum, self.where = signum, where
        name = signal.Signals(signum).name if signum else "signal"
        super().__init__(f"interrupted by {name} after {where}")

    def __reduce__(self) -> tuple[type, tuple[int, str]]:
        """Pickle by constructor arguments (the error may be broadcast)."""
        return (Interrupted, (self.signum, self.where))


def _handler(signum: int, frame: FrameType | None) -> None:
    now = time.monotonic()
    if signum in _first:
        if now - _first[signum] > REPEAT_S:  # asked again: fall back to the default action
            signal.signal(signum, signal.SIG_DFL)
            signal.raise_signal(signum)
        return
    _first[signum] = now
    _received.append(signum)


def install() -> None:
    """Turn SIGTERM and SIGINT into the stop flag (main thread only; idempotent)."""
    for s in _SIGNALS:
        if s not in _previous:
            _previous[s] = signal.signal(s, _handler)


def reassert() -> None:
    """Install the handlers again at the OS level, if :func:`install` installed them.

    ``gmsh.initialize`` resets SIGTERM and SIGINT to their default actions in C, while
    Python still reports its own handlers: a signal after meshing would kill the run
    without a checkpoint. Call this after gmsh starts and after it stops (a no-op outside
    the main thread, where Python cannot set handlers).
    """
    if threading.current_thread() is not threading.main_thread():
        return
    for s in _previous:
        signal.signal(s, _handler)


def uninstall() -> None:
    """Restore the handlers :func:`install` replaced and clear the flag."""
    for s, old in list(_previous.items()):
        signal.signal(s, old)  # type: ignore[arg-type]
        del _previous[s]
    reset()


def reset() -> None:
    """Forget signals received so far."""
    _received.clear()
    _first.clear()


def received() -> int:
    """The first signal received on this rank since :func:`reset`, or 0."""
    return _received[0] if _received else 0
