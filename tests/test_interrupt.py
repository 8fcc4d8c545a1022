"""Signals become a stop request; a repeat after REPEAT_S seconds kills as usual."""

from __future__ import annotations

import os
import signal
import subprocess
import sys

from geofrac import interrupt
from tests.conftest import subprocess_env


def test_sigterm_and_sigint_set_the_flag_and_duplicates_are_ignored():
    interrupt.install()
    try:
        assert interrupt.received() == 0
        os.kill(os.getpid(), signal.SIGTERM)
        os.kill(os.getpid(), signal.SIGTERM)  # forwarded twice: still alive
        os.kill(os.getpid(), signal.SIGINT)
        assert interrupt.received() == signal.SIGTERM
        assert interrupt._received == [signal.SIGTERM, signal.SIGINT]
    finally:
        interrupt.uninstall()
    assert signal.getsignal(signal.SIGTERM) == signal.SIG_DFL
    assert interrupt.received() == 0


CHILD = """
import os, signal, time
from geofrac import interrupt
interrupt.REPEAT_S = 0.0
interrupt.install()
os.kill(os.getpid(), signal.SIGTERM)
assert interrupt.received() == signal.SIGTERM
time.sleep(0.01)
os.kill(os.getpid(), signal.SIGTERM)  # asked again: the default action, death by SIGTERM
time.sleep(1)
print("survived")
"""


def _child(code: str) -> subprocess.CompletedProcess:
    """Run ``code`` in a fresh Python (its signals do not reach pytest)."""
    return subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        env=subprocess_env(),
        timeout=120,
        check=False,
    )


def test_a_repeated_signal_takes_the_default_action():
    proc = _child(CHILD)
    assert proc.returncode == -signal.SIGTERM, proc.stderr
    assert "survived" not in proc.stdout


GMSH_CHILD = """
import os, signal
from geofrac import interrupt
from geofrac.meshing.geo import gmsh_session
interrupt.install()
with gmsh_session(None, {}) as gmsh:
    os.kill(os.getpid(), signal.SIGTERM)  # while gmsh runs (a DFN scene meshes in-process)
os.kill(os.getpid(), signal.SIGINT)  # after it
assert interrupt._received == [signal.SIGTERM, signal.SIGINT], interrupt._received
print("survived")
"""


def test_signals_still_stop_cleanly_during_and_after_gmsh():
    """gmsh.initialize resets SIGTERM and SIGINT to kill in C: the handlers come back."""
    proc = _child(GMSH_CHILD)
    assert proc.returncode == 0, (proc.returncode, proc.stderr)
    assert "survived" in proc.stdout
