"""Child process that runs gmsh on one ``.geo`` file; see :mod:`geofrac.meshing.geo`.

Run as ``python -m geofrac.meshing.geo_worker REQUEST``.
``REQUEST`` is a JSON file: ``mode`` (``"inspect"`` or ``"mesh"``), ``path``,
``parameters``, ``answer`` (where to write the JSON answer), and for ``"mesh"`` also
``mesh_size``, ``algorithm`` (gmsh's ``Mesh.Algorithm`` number, set after the file is
read so it overrides the file's; null keeps it), ``dim``, ``out`` (the ``.msh`` to
write), ``options`` (gmsh options set before writing) and ``verbose``. The answer is
``{"ok": true, ...}`` (``"inspect"``: ``dim``, ``groups`` as [name, dim] pairs,
``overlaps``, ``order``) or ``{"ok": false, "error": ...}``.

Loads gmsh and nothing of MPI, so it is safe to start from an MPI rank.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

from geofrac.meshing.geo import failure_message, gmsh_session, inspect_model

__all__ = ["main", "run"]


def run(request: dict[str, Any]) -> dict[str, Any]:
    """Do what ``request`` asks; the JSON-ready answer."""
    mode = request["mode"]
    verbose = bool(request.get("verbose", False))
    try:
        with gmsh_session(
            Path(request["path"]), request["parameters"], request.get("mesh_size"), verbose=verbose
        ) as gmsh:
            try:
                if mode == "inspect":
                    info = inspect_model(gmsh.model)
                    return {
                        "ok": True,
                        "dim": info.dim,
                        "groups": list(info.groups.items()),
                        "overlaps": [list(o) for o in info.overlaps],
                        "order": info.order,
                    }
                if request.get("algorithm") is not None:
                    gmsh.option.setNumber("Mesh.Algorithm", int(request["algorithm"]))
                gmsh.model.mesh.generate(int(request["dim"]))
                for name, value in request.get("options", {}).items():
                    gmsh.option.setNumber(name, value)
                gmsh.write(request["out"])
                return {"ok": True}
            except Exception as exc:  # gmsh raises bare Exceptions; its log is still open
                return {"ok": False, "error": failure_message(exc, gmsh)}
    except Exception as exc:  # reading failed: gmsh_session has put the message in exc
        return {"ok": False, "error": str(exc)}


def main(argv: list[str] | None = None) -> int:
    """Read the request named on the command line, write the answer; exit status 0."""
    args = sys.argv[1:] if argv is None else argv
    request = json.loads(Path(args[0]).read_text())
    answer = run(request)
    Path(request["answer"]).write_text(json.dumps(answer))
    return 0


if __name__ == "__main__":
    sys.exit(main())
