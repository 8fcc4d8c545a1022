"""Command-line argument types shared by the benches (cheap: argparse only)."""

from __future__ import annotations

import argparse
from collections.abc import Callable

__all__ = ["name_list", "number_list"]


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


def name_list(allowed: tuple[str, ...], what: str) -> Callable[[str], list[str]]:
    """An argparse type for a non-empty comma-separated list of names from ``allowed``.

    Args:
        allowed: the valid names.
        what: the kind of name for the error message, e.g. ``"model"``.

    Returns:
        ``parse(text) -> list`` raising :class:`argparse.ArgumentTypeError`.
    """

    def parse(text: str) -> list[str]:
        names = [v.strip() for v in text.split(",") if v.strip()]
        if not names:
            raise argparse.ArgumentTypeError(f"expected at least one {what}")
        for name in names:
            if name not in allowed:
                raise argparse.ArgumentTypeError(
                    f"unknown {what} {name!r}; choose from {list(allowed)}"
                )
        return names

    return parse
