"""Errors raised while a validated scene runs."""

__all__ = ["RunError"]


class RunError(RuntimeError):
    """A run cannot continue (mesh failed, probe outside the mesh, solver diverged).

    Raised collectively: every rank raises it after the same check, so a run stops
    without a hang and the summary records the message as its ``status``.
    """
