"""Compiled cell kernels (C via cffi) for DOLFINx's custom-integral hook.

Each kernel is a C file in this package with the ufcx ``tabulate_tensor`` signature
(``A, w, c, coordinate_dofs, entity_local_index, quadrature_permutation, custom_data``),
declared in the ``.h`` file of the same name. :func:`load` compiles a file once per
source text with the system C compiler (``-O2``, no fast-math) into a cache directory
and returns the cffi library; :func:`address` gives a function's address for
``dolfinx.cpp.fem.Form_float64``.

Cache: :func:`cache_root` (``$GEOFRAC_CACHE_DIR`` or ``$XDG_CACHE_HOME/geofrac``, i.e.
``~/.cache/geofrac``), in ``kernels/<name>-<hash of the source>/``; numba's on-disk cache
of the jitted kernels goes to ``numba/`` there (set by :mod:`geofrac` on import unless
``NUMBA_CACHE_DIR`` is set), never into the installed package. Under MPI rank 0
compiles and the other ranks wait for it, so ranks never race on one file.

Kernels:
- ``efmm``: the Enriched Free Mesh Method's node pieces of A_i and C_i per cell
  (:mod:`geofrac.elements.efmm`; numpy reference :mod:`geofrac.elements.efmm_numpy`).
- ``cmulti``: the C-MultiMLSM fit A⁻¹C and stiffness of one node, with the order drop
  (a plain function ``cmulti_node``, not a ufcx kernel; wrapper and numpy reference in
  :mod:`geofrac.mls.cmulti`).
- ``cellstress``: the element cells' midpoint stresses, largest principal stress and
  strain energy of a crack state's solution in one pass (``cell_stresses``; wrapper
  and numpy reference in :mod:`geofrac.fracture.units`).
"""

from __future__ import annotations

import hashlib
import importlib.util
import os
import shutil
import sys
import tempfile
from pathlib import Path
from types import ModuleType
from typing import Any

__all__ = ["address", "cache_dir", "cache_root", "load"]

_HERE = Path(__file__).resolve().parent
_LOADED: dict[str, ModuleType] = {}


def cache_root() -> Path:
    """The per-user cache of geofrac: ``$GEOFRAC_CACHE_DIR``, else ``$XDG_CACHE_HOME/geofrac``."""
    root = os.environ.get("GEOFRAC_CACHE_DIR")
    if root:
        return Path(root)
    xdg = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(xdg) / "geofrac"


def cache_dir() -> Path:
    """Directory of the compiled kernels."""
    return cache_root() / "kernels"


def _build(name: str, source: str, header: str, target: Path) -> None:
    """Compile ``source`` into the extension module ``target/_<name>*.so`` (atomic)."""
    import cffi

    ffi = cffi.FFI()
    ffi.cdef(header)
    ffi.set_source(f"_{name}", source, extra_compile_args=["-O2", "-std=c99"])
    target.parent.mkdir(parents=True, exist_ok=True)
    work = Path(tempfile.mkdtemp(prefix=f".{name}-", dir=target.parent))
    try:
        built = Path(ffi.compile(tmpdir=str(work)))
        staged = work / "staged"
        staged.mkdir()
        shutil.move(str(built), staged / built.name)
        try:
            staged.rename(target)  # atomic: a directory is complete or absent
        except OSError:  # another process finished first
            if not target.exists():
                raise
    finally:
        shutil.rmtree(work, ignore_errors=True)


def load(name: str, comm: Any = None) -> ModuleType:
    """The cffi module of kernel ``name`` (``lib`` and ``ffi``), compiled on first use.

    Args:
        name: kernel file stem in this package, e.g. ``"efmm"``.
        comm: an MPI communicator; when given the call is collective (rank 0 compiles).

    Raises:
        RuntimeError: the C compiler failed (its message is included).
    """
    if name in _LOADED:
        return _LOADED[name]
    source = (_HERE / f"{name}.c").read_text()
    header = (_HERE / f"{name}.h").read_text()
    digest = hashlib.sha256((source + header).encode()).hexdigest()[:16]
    target = cache_dir() / f"{name}-{digest}"
    error = None
    if (comm is None or comm.rank == 0) and not target.exists():
        try:
            _build(name, source, header, target)
        except Exception as exc:  # distutils/cffi raise various types
            error = f"compiling the {name} kernel failed: {exc}"
    if comm is not None:
        error = comm.bcast(error, root=0)
    if error is not None:
        raise RuntimeError(error)
    path = next(target.glob(f"_{name}*.so"))
    spec = importlib.util.spec_from_file_location(f"_{name}", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    sys.modules.setdefault(f"geofrac.kernels._{name}", module)
    _LOADED[name] = module
    return module


def address(module: ModuleType, function: str) -> int:
    """The address of C function ``function`` of a loaded kernel module, as an int."""
    return int(module.ffi.cast("intptr_t", module.ffi.addressof(module.lib, function)))
