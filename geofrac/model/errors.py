"""The one exception type for bad scenes."""

from __future__ import annotations

import difflib
from collections.abc import Iterable
from pathlib import Path

__all__ = ["SceneError", "did_you_mean"]


class SceneError(ValueError):
    """A scene file (or a ``--set`` override) is wrong.

    The message always names the file and the dotted key, e.g.
    ``jobs/x.toml: material.nu: must lie in (-1, 0.5), got 0.5``.

    Args:
        file: the scene file.
        key: dotted key of the offending entry (``bc[1].group``), or ``""`` for the file.
        message: what is wrong, and where possible what would be right.
    """

    def __init__(self, file: str | Path, key: str, message: str) -> None:
        self.file = str(file)
        self.key = key
        self.message = message
        where = f"{self.file}: {key}" if key else self.file
        super().__init__(f"{where}: {message}")

    def __reduce__(self) -> tuple[type, tuple[str, str, str]]:
        """Pickle by constructor arguments, so the error can be broadcast over MPI."""
        return (SceneError, (self.file, self.key, self.message))


def did_you_mean(word: str, choices: Iterable[str]) -> str:
    """Return `` (did you mean 'x'?)`` for the closest choice, or a list of the valid ones."""
    choices = sorted(choices)
    close = difflib.get_close_matches(word, choices, n=1, cutoff=0.6)
    if close:
        return f" (did you mean '{close[0]}'?)"
    if choices:
        return f" (valid: {', '.join(choices)})"
    return ""
