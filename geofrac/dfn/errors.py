"""The error type of the DFN package."""

__all__ = ["DfnError"]


class DfnError(ValueError):
    """A DFN request or file is wrong.

    The message says what is wrong and where (the fracture set, the argument, or the file
    with its line number or entry index), so it can be shown to a user as it is.
    """
