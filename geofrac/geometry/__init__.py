"""Pure geometry shared by the mesh-based layers (numpy only)."""

__all__: list[str] = []
