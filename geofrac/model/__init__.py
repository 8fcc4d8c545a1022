"""The validated scene as data: a leaf that every layer reads.

- :mod:`~geofrac.model.scene`: :class:`~geofrac.model.scene.Scene` and the dataclasses of
  its tables (what :func:`geofrac.scene.load_scene` returns);
- :mod:`~geofrac.model.errors`: :class:`~geofrac.model.errors.SceneError`;
- :mod:`~geofrac.model.table`: checks of one TOML table, for the loader and the effects'
  ``configure``;
- :mod:`~geofrac.model.expr`: the safe arithmetic expressions of scene values.

Nothing here imports another geofrac package: the loader (:mod:`geofrac.scene`), the
effects, the meshers and the engines sit above.
"""

__all__: list[str] = []
