"""Output: XDMF fields for ParaView, ``summary.json``, benchmark tables and plots."""

__all__: list[str] = []
