"""Domain decomposition of the MPM grid over MPI ranks (slabs along axis 0).

The grid's cells along axis 0 are split evenly between the ranks; each rank owns the
particles in its slab and steps them on its own sub-grid, the slab plus ``halo`` ghost
cells each side (clipped at the grid's ends). A step with a :class:`Domain` in its
settings (:class:`geofrac.mpm.schemes.StepSettings`)

- completes the nodal sums of the nodes shared with other ranks: every rank adds the
  partial sums of all ranks whose sub-grids hold the node. The step's sums are exact
  fixed-point integers (:mod:`~geofrac.mpm.fixedpoint`), so a shared node has the same
  value, to the last bit, on every rank that holds it and for any number of ranks;
- sends each rank's MLS ghost particles (positions at the step's start, strain
  increments and global ids of the particles within the smoothing radius of another
  slab; the ids order the MLS sums);
- moves the particles that left a slab to their new rank at the end of the step.

Only this module speaks MPI (mpi4py; the communicator is the caller's), and only
through the small methods of :class:`Domain`.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Any, overload

import numpy as np

from geofrac.mpm.grid import Grid
from geofrac.mpm.particles import Particles, concat, take

__all__ = ["Domain", "decompose"]


@dataclass(frozen=True, eq=False)
class Domain:
    """One rank's part of a decomposed grid.

    Attributes:
        comm: the MPI communicator (mpi4py).
        grid: the whole grid.
        local: this rank's sub-grid: its slab of cells along axis 0 plus ``halo`` ghost
            cells each side, clipped at the grid's ends; node positions are the global
            ones.
        halo: ghost cells each side.
        cuts: the first cell (along axis 0) of each rank's slab, then the number of
            cells, shape=(size + 1,).
        planes: the first and last node plane (along axis 0) of each rank's sub-grid,
            shape=(size, 2).
    """

    comm: Any
    grid: Grid
    local: Grid
    halo: int
    cuts: np.ndarray
    planes: np.ndarray

    @property
    def rank(self) -> int:
        """This rank."""
        return int(self.comm.rank)

    def owner(self, x: np.ndarray) -> np.ndarray:
        """The rank owning each position (its cell's slab along axis 0), shape=(n,).

        Args:
            x: positions, shape=(n, dim).
        """
        g = self.grid
        # a particle on a slab's face goes to either rank with its round-off: no result
        # depends on which (the nodal sums are exact integers, the MLS sums ordered by id)
        cell = np.floor((x[:, 0] - g.origin[0]) / g.spacing).astype(np.int64)
        cell = np.clip(cell, 0, g.cells[0] - 1)
        return np.searchsorted(self.cuts, cell, side="right") - 1

    def distribute(self, p: Particles) -> Particles:
        """This rank's particles of the whole set ``p`` (identical on every rank)."""
        return take(p, self.owner(p.x) == self.rank)

    def gather(self, p: Particles) -> Particles | None:
        """All ranks' particles sorted by id on rank 0; None on the others."""
        parts = self.comm.gather(p, root=0)
        if self.rank != 0:
            return None
        whole = concat(parts, p.dim)
        return take(whole, np.argsort(whole.ids, kind="stable"))

    def allsum(self, value: float | np.ndarray) -> float | np.ndarray:
        """The sum over the ranks (allreduce)."""
        from mpi4py import MPI

        if isinstance(value, np.ndarray):
            out = np.empty_like(value)
            self.comm.Allreduce(np.ascontiguousarray(value), out, op=MPI.SUM)
            return out
        return self.comm.allreduce(value, op=MPI.SUM)

    @overload
    def allmax(self, value: float) -> float: ...
    @overload
    def allmax(self, value: np.ndarray) -> np.ndarray: ...
    def allmax(self, value: float | np.ndarray) -> float | np.ndarray:
        """The largest value over the ranks (per entry of an array)."""
        from mpi4py import MPI

        if isinstance(value, np.ndarray):
            out = np.empty_like(value)
            self.comm.Allreduce(np.ascontiguousarray(value), out, op=MPI.MAX)
            return out
        return float(self.comm.allreduce(float(value), op=MPI.MAX))

    def any(self, *, local: bool) -> bool:
        """Whether ``local`` (this rank's truth value) is true on any rank."""
        from mpi4py import MPI

        return bool(self.comm.allreduce(bool(local), op=MPI.LOR))

    def allgather_rows(self, *arrays: np.ndarray) -> list[np.ndarray]:
        """Each array's rows of all ranks, in rank order (every rank gets them all)."""
        parts = self.comm.allgather(arrays)
        return [np.concatenate([q[i] for q in parts]) for i in range(len(arrays))]

    def _plane_nodes(self) -> int:
        """Nodes per node plane along axis 0."""
        return int(np.prod(self.grid.shape[1:]))

    @property
    def node_offset(self) -> int:
        """The global id of this rank's local node 0 (its sub-grid's first node plane)."""
        return int(self.planes[self.rank][0]) * self._plane_nodes()

    def sum_halo(self, values: np.ndarray) -> np.ndarray:
        """Complete nodal sums of this rank's sub-grid with the other ranks' parts.

        Each node's value becomes the sum, in rank order, of the partial sums of every
        rank whose sub-grid holds it, so all those ranks hold the same value. With
        integer values (the step's fixed-point pairs) the sum is exact and does not depend
        on the order or on the decomposition.

        Args:
            values: this rank's partial sums on ``local``'s nodes, shape=(N, c), float or
                int64.

        Returns:
            The complete sums, shape=(N, c).
        """
        r = self.rank
        a, b = self.planes[r]
        per = self._plane_nodes()
        values = np.ascontiguousarray(values)
        others = [
            q
            for q in range(len(self.planes))
            if q != r and max(a, self.planes[q][0]) <= min(b, self.planes[q][1])
        ]
        if not others:
            return values
        received, requests = {}, []
        for q in others:
            lo, hi = max(a, self.planes[q][0]), min(b, self.planes[q][1])
            part = values[(lo - a) * per : (hi - a + 1) * per]
            received[q] = np.empty_like(part)
            requests.append(self.comm.Irecv(received[q], source=q, tag=71))
            requests.append(self.comm.Isend(np.ascontiguousarray(part), dest=q, tag=71))
        from mpi4py import MPI

        MPI.Request.Waitall(requests)
        out = np.zeros_like(values)
        for q in sorted([*others, r]):
            if q == r:
                out += values
                continue
            lo, hi = max(a, self.planes[q][0]), min(b, self.planes[q][1])
            out[(lo - a) * per : (hi - a + 1) * per] += received[q]
        return out

    def min_halo(self, values: np.ndarray) -> np.ndarray:
        """Complete nodal minima of this rank's sub-grid with the other ranks' parts.

        Like :meth:`sum_halo` with the least value in place of the sum (exact, so the
        same on every rank holding a node and for every decomposition).

        Args:
            values: this rank's partial minima on ``local``'s nodes, shape=(N, c) float.

        Returns:
            The complete minima, shape=(N, c).
        """
        r = self.rank
        a, b = self.planes[r]
        per = self._plane_nodes()
        values = np.ascontiguousarray(values, dtype=float)
        out = values.copy()
        received, requests = {}, []
        for q in range(len(self.planes)):
            lo, hi = max(a, self.planes[q][0]), min(b, self.planes[q][1])
            if q == r or lo > hi:
                continue
            part = values[(lo - a) * per : (hi - a + 1) * per]
            received[q] = (lo, hi, np.empty_like(part))
            requests.append(self.comm.Irecv(received[q][2], source=q, tag=73))
            requests.append(self.comm.Isend(part, dest=q, tag=73))
        if not requests:
            return out
        from mpi4py import MPI

        MPI.Request.Waitall(requests)
        for lo, hi, got in received.values():
            view = out[(lo - a) * per : (hi - a + 1) * per]
            np.minimum(view, got, out=view)
        return out

    def ghost_rows(self, x: np.ndarray, h: float) -> list[np.ndarray]:
        """Per rank, this rank's rows within ``h`` of its slab (along axis 0).

        Args:
            x: this rank's positions (all in its slab), shape=(n, dim).
            h: the radius.

        Returns:
            One index array per rank (empty for this rank), shape=(k_q,) each.
        """
        g = self.grid
        edges = g.origin[0] + g.spacing * self.cuts
        rows = []
        for q in range(len(self.planes)):
            near = (x[:, 0] >= edges[q] - h) & (x[:, 0] <= edges[q + 1] + h)
            rows.append(np.zeros(0, np.int64) if q == self.rank else np.flatnonzero(near))
        return rows

    def send_rows(self, rows: list[np.ndarray], *arrays: np.ndarray) -> list[np.ndarray]:
        """Send each rank its rows of the arrays; return what the others sent (collective).

        Args:
            rows: per rank, the rows to send to it (:meth:`ghost_rows`).
            arrays: this rank's arrays, shape=(n, ...) each.

        Returns:
            Per array, the rows received from the other ranks in rank order,
            shape=(k, ...).
        """
        send = [
            None if len(r) == 0 or q == self.rank else tuple(a[r] for a in arrays)
            for q, r in enumerate(rows)
        ]
        got = [item for item in self.comm.alltoall(send) if item is not None]
        return [
            np.concatenate([item[i] for item in got]) if got else arrays[i][:0]
            for i in range(len(arrays))
        ]

    def ghosts(
        self, x: np.ndarray, values: np.ndarray, h: float, *, ids: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Other ranks' particles within ``h`` of this rank's slab (MLS ghosts).

        Args:
            x: this rank's positions (at the step's start, all in its slab),
                shape=(n, dim).
            values: their values, shape=(n, c).
            h: the radius.
            ids: their global ids, shape=(n,) (the order of the MLS sums).

        Returns:
            The ghosts' positions, shape=(k, dim), values, shape=(k, c), and ids,
            shape=(k,), in rank order.
        """
        gx, gv, gids = self.send_rows(self.ghost_rows(x, h), x, values, ids)
        return gx, gv, gids

    def migrate(self, p: Particles) -> None:
        """Send the particles that left this rank's slab to their owners (p in place)."""
        owner = self.owner(p.x)
        stay = owner == self.rank
        leaving = not stay.all()
        if not self.any(local=leaving):
            return
        send = [
            None if q == self.rank or not np.any(owner == q) else take(p, owner == q)
            for q in range(len(self.planes))
        ]
        arrived = [item for item in self.comm.alltoall(send) if item is not None]
        if not leaving and not arrived:
            return
        new = concat([take(p, stay), *arrived], p.dim)
        for f in fields(Particles):
            setattr(p, f.name, getattr(new, f.name))


def decompose(g: Grid, comm: Any, halo: int = 2) -> Domain:
    """Split ``g`` into slabs of cells along axis 0, evenly by rank.

    Args:
        g: the whole grid.
        comm: the MPI communicator (mpi4py).
        halo: ghost cells each side of a slab (GIMP supports and MLS radii must fit in
            it; a step raises when one does not).

    Raises:
        ValueError: fewer cells along axis 0 than ranks, or a negative halo.
    """
    size, rank = int(comm.size), int(comm.rank)
    cells = g.cells[0]
    if cells < size:
        raise ValueError(f"decompose: {cells} cells along axis 0 cannot feed {size} ranks")
    if halo < 0:
        raise ValueError(f"decompose: halo must be >= 0, got {halo}")
    cuts = np.array([(r * cells) // size for r in range(size + 1)], dtype=np.int64)
    planes = np.stack([np.maximum(cuts[:-1] - halo, 0), np.minimum(cuts[1:] + halo, cells)], 1)
    a, b = planes[rank]
    origin = g.origin.copy()
    origin[0] = g.origin[0] + g.spacing * a
    local = Grid(origin, g.spacing, (int(b - a), *g.cells[1:]))
    return Domain(comm, g, local, int(halo), cuts, planes)
