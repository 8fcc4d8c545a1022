"""Command-line argument types shared by the benches (cheap: argparse only)."""

from __future__ import annotations

import argparse
from collections.abc import Callable

__all__ = ["number_list"]


def number_list(
    kind: type[int] | type[float], valid: Callable[[float], bool], requirement: str
) -> Callable[[str], list]:
    """An argparse type for a non-empty comma-separated list of numbers.

    Args:
        kind: ``int`` or ``float``.
        valid: test every value must pass.
        requirement: adjective for the error message, e.g. ``"positive"``.

    Returns:
        ``parse(text) -> list`` raising :class:`argparse.ArgumentTypeError`.
    """
    name = "integers" if kind is int else "numbers"

    def parse(text: str) -> list:
        try:
            values = [kind(v) for v in text.split(",") if v.strip()]
        except ValueError:
            raise argparse.ArgumentTypeError(
                f"expected comma-separated {name}, got {text!r}"
            ) from None
        if not values or not all(valid(v) for v in values):
            raise argparse.ArgumentTypeError(f"expected {requirement} {name}, got {text!r}")
        return values

    return parse
