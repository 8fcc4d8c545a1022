"""Compiled (numba) hot loops of the MPM step: weights, particle ↔ grid transfers, MLS.

The same arithmetic as the numpy reference (:mod:`~geofrac.mpm.shapes`,
:mod:`~geofrac.mpm.schemes`, :mod:`~geofrac.mpm.smoothing`), written as loops over the
particles so that nothing of size (n, k, dim) is built per transfer. The nodal sums run
in particle order, as ``np.bincount`` does, so they agree with the reference to the last
bit; the other results agree to round-off (the reference's ``matmul`` may sum in another
order).

This module imports numba: only a step with ``backend="numba"`` imports it (nothing in
:mod:`geofrac` does at import time). The kernels are compiled on first use and cached
on disk (``cache=True``); ``fastmath`` is off, so no result depends on reassociation.
The MLS fits themselves are in the generated :mod:`~geofrac.mpm.mls_kernels`, whose
neighbour-sum loop alone allows reassociation (see there).
"""

from __future__ import annotations

import numba
import numpy as np

__all__ = [
    "bad_particles",
    "bin_neighbours",
    "elastic_update",
    "forces",
    "forces_bounds",
    "from_grid",
    "from_grid2",
    "kinematics",
    "mass_momentum",
    "mass_momentum_bounds",
    "momentum",
    "neighbour_lists",
    "nodal_acceleration",
    "nodal_velocity",
    "outside",
    "pairs_to_float",
    "scratch",
    "strain_increment",
    "velocity_gradient",
    "weights_bspline2",
    "weights_gimp",
    "weights_hat",
]

_jit = numba.njit(cache=True)

#: Work arrays kept between steps (a fresh large array costs its page faults each step).
_SCRATCH: dict[str, np.ndarray] = {}


def scratch(name: str, shape: tuple[int, ...], dtype: type = float) -> np.ndarray:
    """A reused, uninitialised C-contiguous work array, valid until the next call by name.

    The buffer grows by a quarter beyond the need, so particle counts that change a
    little (migration between ranks) do not reallocate it.
    """
    need = int(np.prod(shape))
    buf = _SCRATCH.get(name)
    if buf is None or buf.dtype != np.dtype(dtype) or buf.size < need:
        buf = np.empty(need + need // 4, dtype)
        _SCRATCH[name] = buf
    return buf[:need].reshape(shape)


@_jit
def _combos(k1: int, dim: int) -> np.ndarray:
    """The k1**dim combinations of per-direction node indices, C order, shape=(k, dim)."""
    k = k1**dim
    out = np.empty((k, dim), np.int64)
    for c in range(k):
        rem = c
        for a in range(dim - 1, -1, -1):
            out[c, a] = rem % k1
            rem //= k1
    return out


@_jit
def _tensor(
    i: int,
    combos: np.ndarray,
    i1: np.ndarray,
    p1: np.ndarray,
    d1: np.ndarray,
    shape: np.ndarray,
    nodes: np.ndarray,
    phi: np.ndarray,
    grad: np.ndarray,
) -> None:
    """Tensor products (eq. 4.32) of particle i's per-direction weights into row i.

    ``combos`` (shape=(k, dim)) are the k1**dim node combinations in C order (direction 0
    slowest), as :func:`geofrac.mpm.shapes.weights` orders them.
    """
    k, dim = combos.shape
    for c in range(k):
        flat = 0
        ph = p1[0, combos[c, 0]]
        for a in range(dim):
            flat = flat * shape[a] + i1[a, combos[c, a]]
            if a > 0:
                ph *= p1[a, combos[c, a]]
        nodes[i, c] = flat
        phi[i, c] = ph
        for b in range(dim):
            if dim == 1:
                grad[i, c, b] = d1[b, combos[c, b]] * 1.0
                continue
            first = True
            others = 0.0
            for a in range(dim):
                if a == b:
                    continue
                if first:
                    others = p1[a, combos[c, a]]
                    first = False
                else:
                    others *= p1[a, combos[c, a]]
            grad[i, c, b] = d1[b, combos[c, b]] * others


@_jit
def weights_hat(
    x: np.ndarray,
    origin: np.ndarray,
    L: float,
    shape: np.ndarray,
    nodes: np.ndarray,
    phi: np.ndarray,
    grad: np.ndarray,
) -> None:
    """Linear hat weights (eqs. 4.28-4.29) of point particles, written into the outputs.

    Args:
        x: positions inside the grid, shape=(n, dim).
        origin: the grid's lowest corner, shape=(dim,).
        L: cell size.
        shape: nodes per direction, shape=(dim,).
        nodes: out, flat node ids, shape=(n, 2**dim).
        phi: out, φ_ip, shape=(n, 2**dim).
        grad: out, ∇φ_ip, shape=(n, 2**dim, dim).
    """
    n, dim = x.shape
    i1 = np.empty((dim, 2), np.int64)
    p1 = np.empty((dim, 2))
    d1 = np.empty((dim, 2))
    combos = _combos(2, dim)
    for i in range(n):
        for a in range(dim):
            st = np.int64(np.floor((x[i, a] - origin[a]) / L))
            # a particle on the upper boundary belongs to the last cell (numba unifies the
            # np.int64 with the int literal; numpy's stubs give max no common type for them)
            st = min(max(st, 0), shape[a] - 2)  # type: ignore[call-overload]
            s = x[i, a] - (origin[a] + L * st)
            i1[a, 0] = st
            i1[a, 1] = st + 1
            p1[a, 0] = 1.0 - s / L
            p1[a, 1] = s / L
            d1[a, 0] = -1.0 / L
            d1[a, 1] = 1.0 / L
        _tensor(i, combos, i1, p1, d1, shape, nodes, phi, grad)


@_jit
def weights_bspline2(
    x: np.ndarray,
    origin: np.ndarray,
    L: float,
    shape: np.ndarray,
    nodes: np.ndarray,
    phi: np.ndarray,
    grad: np.ndarray,
) -> bool:
    """Quadratic B-spline weights (:func:`geofrac.mpm.shapes.bspline2_1d`) into the outputs.

    Args:
        x: positions, shape=(n, dim).
        origin: the grid's lowest corner, shape=(dim,).
        L: cell size.
        shape: nodes per direction, shape=(dim,).
        nodes: out, flat node ids, shape=(n, 3**dim).
        phi: out, φ_ip, shape=(n, 3**dim).
        grad: out, ∇φ_ip, shape=(n, 3**dim, dim).

    Returns:
        False when a node with weight lies outside the grid.
    """
    n, dim = x.shape
    i1 = np.empty((dim, 3), np.int64)
    p1 = np.empty((dim, 3))
    d1 = np.empty((dim, 3))
    combos = _combos(3, dim)
    ok = True
    for i in range(n):
        for a in range(dim):
            st = np.int64(np.floor((x[i, a] - origin[a]) / L + 0.5)) - 1
            for m in range(3):
                idx = st + m
                r = x[i, a] - (origin[a] + L * idx)
                q = abs(r) / L
                sgn = 1.0 if r > 0 else (-1.0 if r < 0 else 0.0)
                if q < 0.5:
                    ph, dph = 0.75 - q * q, -2.0 * q * sgn / L
                elif q < 1.5:
                    ph, dph = 0.5 * (1.5 - q) ** 2, -(1.5 - q) * sgn / L
                else:
                    ph, dph = 0.0, 0.0
                ok &= _store(a, m, idx, ph, dph, shape[a], i1, p1, d1)
        _tensor(i, combos, i1, p1, d1, shape, nodes, phi, grad)
    return ok


@_jit
def _store(
    a: int,
    m: int,
    idx: int,
    ph: float,
    dph: float,
    n: int,
    i1: np.ndarray,
    p1: np.ndarray,
    d1: np.ndarray,
) -> bool:
    """Store node ``idx`` (of ``n`` along axis a) and its φ, dφ/dx as entry m of the axis.

    A node outside the grid is clipped to it and carries no weight; returns False when
    it had weight (the particle's support reaches beyond the grid).
    """
    inside = 0 <= idx <= n - 1
    if not inside:
        idx = min(max(idx, 0), n - 1)
    i1[a, m] = idx
    p1[a, m] = ph if inside else 0.0
    d1[a, m] = dph if inside else 0.0
    return inside or ph == 0.0


@_jit
def _gimp_1d(r: float, L: float, lp: float) -> tuple[float, float]:
    """Eqs. 4.30-4.31 for one particle–node distance r = x_p − x_i: (φ, dφ/dx)."""
    if r > -L - lp and r <= -L + lp:
        return (L + lp + r) ** 2 / (4 * L * lp), (L + lp + r) / (2 * L * lp)
    if r > -L + lp and r <= -lp:
        return 1 + r / L, 1 / L
    if r > -lp and r <= lp:
        return 1 - (r**2 + lp**2) / (2 * L * lp), -r / (L * lp)
    if r > lp and r <= L - lp:
        return 1 - r / L, -1 / L
    if r > L - lp and r < L + lp:
        return (L + lp - r) ** 2 / (4 * L * lp), -(L + lp - r) / (2 * L * lp)
    return 0.0, 0.0


@_jit
def weights_gimp(
    x: np.ndarray,
    lp: np.ndarray,
    origin: np.ndarray,
    L: float,
    shape: np.ndarray,
    k1: int,
    nodes: np.ndarray,
    phi: np.ndarray,
    grad: np.ndarray,
) -> bool:
    """GIMP weights (eqs. 4.30-4.31, 4.69-4.71), written into the outputs.

    Args:
        x: positions, shape=(n, dim).
        lp: half-widths, shape=(n, dim).
        origin: the grid's lowest corner, shape=(dim,).
        L: cell size.
        shape: nodes per direction, shape=(dim,).
        k1: nodes per direction of every particle (enough for the widest).
        nodes: out, flat node ids, shape=(n, k1**dim); a node out of the grid is clipped
            to it and carries no weight.
        phi: out, φ_ip, shape=(n, k1**dim).
        grad: out, ∇φ_ip, shape=(n, k1**dim, dim).

    Returns:
        False when a node with weight lies outside the grid.
    """
    n, dim = x.shape
    i1 = np.empty((dim, k1), np.int64)
    p1 = np.empty((dim, k1))
    d1 = np.empty((dim, k1))
    combos = _combos(k1, dim)
    ok = True
    for i in range(n):
        for a in range(dim):
            st = np.int64(np.floor((x[i, a] - L - lp[i, a] - origin[a]) / L)) + 1
            for m in range(k1):
                idx = st + m
                r = x[i, a] - (origin[a] + L * idx)
                ph, dph = _gimp_1d(r, L, lp[i, a])
                ok &= _store(a, m, idx, ph, dph, shape[a], i1, p1, d1)
        _tensor(i, combos, i1, p1, d1, shape, nodes, phi, grad)
    return ok


#: Fixed-point words of the nodal sums (:mod:`~geofrac.mpm.fixedpoint`): lo's bits.
_LO_BITS = 62
_LO_MASK = (1 << _LO_BITS) - 1
_LO_ONE = float(2**_LO_BITS)
_LO_UNIT = 1.0 / _LO_ONE


@_jit
def _add(acc: np.ndarray, j: int, col: int, x: float) -> None:
    """Add the scaled term x (|x| < 2^40) to node j's pair (hi, lo) of column ``col``.

    The split of :func:`geofrac.mpm.fixedpoint.split` (hi = trunc x, lo = trunc of the
    rest times 2^62, both signed), then lo's carry into hi, so the pair stays
    normalised (0 <= lo < 2^62) whatever the number of terms.
    """
    h = np.int64(x)
    lo = acc[j, col, 1] + np.int64((x - h) * _LO_ONE)
    acc[j, col, 0] += h + (lo >> _LO_BITS)
    acc[j, col, 1] = lo & _LO_MASK


@_jit
def _bigger(m: float, value: float) -> float:
    """max(m, value), NaN once seen staying NaN (a blown-up step must not hide)."""
    if np.isnan(m):
        return m
    if value > m or np.isnan(value):
        return value
    return m


@_jit
def pairs_to_float(acc: np.ndarray, e: np.ndarray, out: np.ndarray) -> None:
    """:func:`geofrac.mpm.fixedpoint.to_float` of finite columns, the same bits.

    Args:
        acc: normalised pairs, shape=(N, c, 2) int64.
        e: the columns' exponents (:func:`geofrac.mpm.fixedpoint.exponents`),
            shape=(c,).
        out: out, shape=(N, c).
    """
    N, c, _ = acc.shape
    half = np.int64(1) << (_LO_BITS - 1)
    one = np.int64(1) << _LO_BITS
    for a in range(c):
        unit = 2.0 ** (e[a] - 40)  # a power of two: the product is rounded once
        for j in range(N):
            hi = acc[j, a, 0]
            lo = acc[j, a, 1]
            if lo >= half:
                hi += 1
                lo -= one
            out[j, a] = (float(hi) + float(lo) * _LO_UNIT) * unit


@_jit
def mass_momentum_bounds(mass: np.ndarray, v: np.ndarray, pmax: float, out: np.ndarray) -> None:
    """Bounds of the terms φ m_p and φ m_p v_p: out = (pmax max m, pmax max m|v_a|).

    Args:
        mass: m_p, shape=(n,).
        v: v_p, shape=(n, dim).
        pmax: the largest φ_ip (:func:`weight_bounds`).
        out: out, shape=(1 + dim,).
    """
    n, dim = v.shape
    for a in range(1 + dim):
        out[a] = 0.0
    for i in range(n):
        out[0] = _bigger(out[0], mass[i])
        for a in range(dim):
            out[1 + a] = _bigger(out[1 + a], mass[i] * abs(v[i, a]))
    for a in range(1 + dim):
        out[a] *= pmax


@_jit
def forces_bounds(
    volume: np.ndarray,
    stress: np.ndarray,
    mass: np.ndarray,
    gravity: np.ndarray,
    pmax: float,
    gmax: float,
    out: np.ndarray,
) -> None:
    """Bounds of the force terms: out_a = max V_p Σ_b |σ_ab| gmax + m_p pmax |b_a|.

    Args:
        volume: V_p, shape=(n,).
        stress: σ_p, shape=(n, dim, dim).
        mass: m_p, shape=(n,).
        gravity: b, shape=(dim,).
        pmax: the largest φ_ip (:func:`weight_bounds`).
        gmax: the largest |∂φ_ip/∂x_b|.
        out: out, shape=(dim,).
    """
    n, dim, _ = stress.shape
    for a in range(dim):
        out[a] = 0.0
    for i in range(n):
        for a in range(dim):
            row = 0.0
            for b in range(dim):
                row += abs(stress[i, a, b])
            out[a] = _bigger(out[a], volume[i] * row * gmax + mass[i] * pmax * abs(gravity[a]))


@_jit
def mass_momentum(
    nodes: np.ndarray,
    phi: np.ndarray,
    mass: np.ndarray,
    v: np.ndarray,
    scale: np.ndarray,
    acc: np.ndarray,
) -> None:
    """m_i += Σ φ_ip m_p and (m v)_i += Σ φ_ip m_p v_p (eqs. 4.20-4.21, D.1-D.2), exactly.

    Every term is added as a fixed-point pair (:mod:`~geofrac.mpm.fixedpoint`), so the
    sums do not depend on the particles' order.

    Args:
        nodes: the weights' flat node ids, shape=(n, k).
        phi: φ_ip, shape=(n, k).
        mass: m_p, shape=(n,).
        v: v_p, shape=(n, dim).
        scale: the columns' scales (:func:`geofrac.mpm.fixedpoint.scales`; mass, then
            momentum), shape=(>= 1 + dim,).
        acc: the pairs (hi, lo), added to: column 0 the mass, 1 … dim the momentum,
            shape=(N, >= 1 + dim, 2) int64.
    """
    n, k = nodes.shape
    dim = v.shape[1]
    for i in range(n):
        for c in range(k):
            j = nodes[i, c]
            w = phi[i, c]
            _add(acc, j, 0, (w * mass[i]) * scale[0])
            for a in range(dim):
                _add(acc, j, 1 + a, (w * (mass[i] * v[i, a])) * scale[1 + a])


@_jit
def momentum(
    nodes: np.ndarray,
    phi: np.ndarray,
    mass: np.ndarray,
    v: np.ndarray,
    scale: np.ndarray,
    acc: np.ndarray,
    col0: int,
) -> None:
    """(m v)_i += Σ φ_ip m_p v_p (D.6): MUSL's re-mapped momentum, exactly.

    Args:
        nodes: the weights' flat node ids, shape=(n, k).
        phi: φ_ip, shape=(n, k).
        mass: m_p, shape=(n,).
        v: v_p, shape=(n, dim).
        scale: the columns' scales, shape=(>= col0 + dim,).
        acc: pairs, added to in columns col0 …, shape=(N, >= col0 + dim, 2) int64.
        col0: the first column.
    """
    n, k = nodes.shape
    dim = v.shape[1]
    for i in range(n):
        for c in range(k):
            j = nodes[i, c]
            w = phi[i, c]
            for a in range(dim):
                _add(acc, j, col0 + a, (w * (mass[i] * v[i, a])) * scale[col0 + a])


@_jit
def forces(
    nodes: np.ndarray,
    phi: np.ndarray,
    grad: np.ndarray,
    volume: np.ndarray,
    stress: np.ndarray,
    mass: np.ndarray,
    gravity: np.ndarray,
    scale: np.ndarray,
    acc: np.ndarray,
    col0: int,
) -> None:
    """f_i += −Σ V_p σ_p ∇φ_ip + Σ m_p b φ_ip (eqs. 4.22-4.23, D.3), exactly.

    Args:
        nodes: the weights' flat node ids, shape=(n, k).
        phi: φ_ip, shape=(n, k).
        grad: ∇φ_ip, shape=(n, k, dim).
        volume: V_p, shape=(n,).
        stress: σ_p, shape=(n, dim, dim).
        mass: m_p, shape=(n,).
        gravity: b, shape=(dim,).
        scale: the columns' scales, shape=(>= col0 + dim,).
        acc: pairs, added to in columns col0 …, shape=(N, >= col0 + dim, 2) int64.
        col0: the first column.
    """
    n, k = nodes.shape
    dim = stress.shape[1]
    for i in range(n):
        nv = -volume[i]
        for c in range(k):
            j = nodes[i, c]
            mw = mass[i] * phi[i, c]
            for a in range(dim):
                s = 0.0
                for b in range(dim):
                    s += grad[i, c, b] * stress[i, a, b]
                _add(acc, j, col0 + a, (nv * s + mw * gravity[a]) * scale[col0 + a])


@_jit
def from_grid(nodes: np.ndarray, phi: np.ndarray, values: np.ndarray, out: np.ndarray) -> None:
    """out_p = Σ_i φ_ip values_i, values shape=(N, c), out shape=(n, c)."""
    n, k = nodes.shape
    nc = values.shape[1]
    for i in range(n):
        for a in range(nc):
            acc = 0.0
            for c in range(k):
                acc += phi[i, c] * values[nodes[i, c], a]
            out[i, a] = acc


@_jit
def from_grid2(
    nodes: np.ndarray,
    phi: np.ndarray,
    a_grid: np.ndarray,
    v_grid: np.ndarray,
    dt: float,
    v: np.ndarray,
    x: np.ndarray,
) -> None:
    """v_p += Δt Σ φ_ip a_i and x_p += Δt Σ φ_ip v_i (D.4-D.5, D.16-D.17), in place.

    Args:
        nodes: the weights' flat node ids, shape=(n, k).
        phi: φ_ip, shape=(n, k).
        a_grid: nodal accelerations, shape=(N, dim).
        v_grid: nodal velocities after the update, shape=(N, dim).
        dt: time step.
        v: particle velocities, changed, shape=(n, dim).
        x: particle positions, changed, shape=(n, dim).
    """
    n, k = nodes.shape
    dim = v.shape[1]
    for i in range(n):
        for a in range(dim):
            acc_a = 0.0
            acc_v = 0.0
            for c in range(k):
                j = nodes[i, c]
                acc_a += phi[i, c] * a_grid[j, a]
                acc_v += phi[i, c] * v_grid[j, a]
            v[i, a] += dt * acc_a
            x[i, a] += dt * acc_v


@_jit
def velocity_gradient(nodes: np.ndarray, grad: np.ndarray, v: np.ndarray, out: np.ndarray) -> None:
    """∇v_p = Σ_i v_i ⊗ ∇φ_ip (D.7), out shape=(n, dim, dim), v shape=(N, dim)."""
    n, k = nodes.shape
    dim = v.shape[1]
    for i in range(n):
        for a in range(dim):
            for b in range(dim):
                acc = 0.0
                for c in range(k):
                    acc += v[nodes[i, c], a] * grad[i, c, b]
                out[i, a, b] = acc


@_jit
def strain_increment(L: np.ndarray, dt: float, out: np.ndarray) -> None:
    """Δε_p = Δt/2 (∇v + ∇vᵀ) (D.7), both shape=(n, dim, dim)."""
    n, dim, _ = L.shape
    h = 0.5 * dt
    for i in range(n):
        for a in range(dim):
            for b in range(dim):
                out[i, a, b] = h * (L[i, a, b] + L[i, b, a])


@_jit
def elastic_update(
    deps: np.ndarray,
    L: np.ndarray,
    dt: float,
    E: float,
    lam: float,
    mu: float,
    stress: np.ndarray,
    stress_zz: np.ndarray,
) -> None:
    """Elastic stress update (D.8, D.30) of :class:`geofrac.mpm.elastic.Elastic`.

    In 2D and 3D the stress is first turned by the Jaumann rate (D.30-D.31),
    σ ← σ + σ Δω − Δω σ with Δω = −Δt/2 (L − Lᵀ), then Δσ = D : Δε is added (as
    :func:`geofrac.mpm.rotation.rotate_stress` does); plane strain's σ_zz does not turn.

    Args:
        deps: strain increments, shape=(n, dim, dim).
        L: velocity gradients, shape=(n, dim, dim).
        dt: the step of this update.
        E: Young's modulus (used in 1D).
        lam: Lamé's λ (2D, 3D).
        mu: Lamé's μ (2D, 3D).
        stress: σ_p, changed, shape=(n, dim, dim).
        stress_zz: plane strain σ_zz (2D), changed, shape=(n,).
    """
    n, dim, _ = deps.shape
    two_mu = 2 * mu
    spin = np.empty((dim, dim))
    turned = np.empty((dim, dim))
    for i in range(n):
        tr = deps[i, 0, 0]
        for a in range(1, dim):
            tr += deps[i, a, a]
        if dim == 1:
            stress[i, 0, 0] += E * deps[i, 0, 0]
        else:
            for a in range(dim):  # Δω of Edo (2016), eq. D.31
                for b in range(dim):
                    spin[a, b] = -0.5 * dt * (L[i, a, b] - L[i, b, a])
            for a in range(dim):  # σ + σ Δω − Δω σ (D.30)
                for b in range(dim):
                    acc = stress[i, a, b]
                    for c in range(dim):
                        acc += stress[i, a, c] * spin[c, b] - spin[a, c] * stress[i, c, b]
                    turned[a, b] = acc
            for a in range(dim):
                for b in range(dim):
                    stress[i, a, b] = turned[a, b]
            lt = lam * tr
            for a in range(dim):
                for b in range(dim):
                    d = lt if a == b else 0.0
                    stress[i, a, b] += d + two_mu * deps[i, a, b]
            if dim == 2:
                stress_zz[i] += lam * tr


@_jit
def kinematics(
    deps: np.ndarray,
    L: np.ndarray,
    dt: float,
    volume: np.ndarray,
    F: np.ndarray,
    lp0: np.ndarray,
    lp: np.ndarray,
    cpgimp: bool,
) -> None:
    """Volume (D.9), G_p (4.70) and cpGIMP half-widths (4.69) after a stress update.

    Args:
        deps: strain increments, shape=(n, dim, dim).
        L: velocity gradients, shape=(n, dim, dim).
        dt: the step of this update.
        volume: V_p, changed, shape=(n,).
        F: G_p, changed, shape=(n, dim, dim).
        lp0: initial half-widths, shape=(n, dim).
        lp: half-widths, changed when ``cpgimp``, shape=(n, dim).
        cpgimp: whether l_p follows G_p.
    """
    n, dim, _ = deps.shape
    Fn = np.empty((dim, dim))
    for i in range(n):
        tr = deps[i, 0, 0]
        for a in range(1, dim):
            tr += deps[i, a, a]
        volume[i] *= 1.0 + tr
        update_F(i, L, dt, F, Fn)
        if cpgimp:
            for a in range(dim):
                lp[i, a] = lp0[i, a] * abs(F[i, a, a])


@_jit
def update_F(i: int, L: np.ndarray, dt: float, F: np.ndarray, work: np.ndarray) -> None:
    """G_p ← (I + Δt ∇v_p) G_p (eq. 4.70) for particle i; work shape=(dim, dim)."""
    dim = F.shape[1]
    for a in range(dim):
        for b in range(dim):
            acc = 0.0
            for m in range(dim):
                e = (1.0 if a == m else 0.0) + dt * L[i, a, m]
                acc += e * F[i, m, b]
            work[a, b] = acc
    for a in range(dim):
        for b in range(dim):
            F[i, a, b] = work[a, b]


@_jit
def neighbour_lists(
    x: np.ndarray, ids: np.ndarray, radius: float, n_fit: int
) -> tuple[np.ndarray, np.ndarray]:
    """All (p, I) with |x_I − x_p| < radius, p < n_fit, self included, as CSR by p then ids[I].

    Cell binning with bins of size ``radius`` (the 3^dim neighbouring bins are
    searched). Each particle's neighbours are in the order of their global ids, not of
    their rows, so sums over them do not depend on how the particles are stored or
    decomposed.

    Args:
        x: positions, shape=(n, dim).
        ids: global particle ids (unique), shape=(n,).
        radius: the search radius.
        n_fit: the particles whose neighbours are listed (the first rows; the others,
            such as ghosts, are only neighbours).

    Returns:
        starts, shape=(n_fit + 1,), and the neighbours' rows I of p at
        starts[p]:starts[p + 1].
    """
    n, dim = x.shape
    lo = np.empty(dim)
    for a in range(dim):
        lo[a] = x[:, a].min() if n > 0 else 0.0
    key = np.empty((n, dim), np.int64)
    dims = np.ones(dim, np.int64)
    for i in range(n):
        for a in range(dim):
            key[i, a] = np.int64(np.floor((x[i, a] - lo[a]) / radius))
            dims[a] = max(dims[a], key[i, a] + 3)
    flat = np.empty(n, np.int64)
    for i in range(n):
        f = 0
        for a in range(dim):
            f = f * dims[a] + key[i, a] + 1
        flat[i] = f
    order = np.argsort(flat, kind="mergesort")
    sorted_flat = flat[order]
    r2 = radius * radius
    counts = np.zeros(n_fit + 1, np.int64)
    off = np.empty(dim, np.int64)
    # two passes: count, then fill
    for sweep in range(2):
        pos = 0
        buf = np.empty(0, np.int64)
        if sweep == 1:
            buf = np.empty(counts[n_fit], np.int64)
        for i in range(n_fit):
            start = pos
            for o in range(3**dim):
                rem = o
                for a in range(dim - 1, -1, -1):
                    off[a] = rem % 3 - 1
                    rem //= 3
                f = 0
                for a in range(dim):
                    f = f * dims[a] + key[i, a] + 1 + off[a]
                s = np.searchsorted(sorted_flat, f, side="left")
                while s < n and sorted_flat[s] == f:
                    q = order[s]
                    d2 = 0.0
                    for a in range(dim):
                        d2 += (x[q, a] - x[i, a]) ** 2
                    if d2 < r2:
                        if sweep == 1:
                            buf[pos] = q
                        pos += 1
                    s += 1
            if sweep == 0:
                counts[i + 1] = pos
            else:
                mine = buf[start:pos].copy()
                by_id = np.argsort(ids[mine], kind="mergesort")
                for t in range(pos - start):
                    buf[start + t] = mine[by_id[t]]
        if sweep == 1:
            return counts, buf
    return counts, np.empty(0, np.int64)


@_jit
def bin_neighbours(x: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray]:
    """:func:`neighbour_lists` of every row, with the rows as ids.

    The pairs of :func:`geofrac.mpm.smoothing.neighbour_pairs`, in the same order.
    """
    return neighbour_lists(x, np.arange(x.shape[0]), h, x.shape[0])


@_jit
def _spline(s: float) -> float:
    """Eq. 4.51 (standard first branch), the cubic spline W(s)."""
    s = abs(s)
    if s < 0.5:
        return 2 / 3 - 4 * s**2 + 4 * s**3
    if s < 1.0:
        return 4 / 3 - 4 * s + 4 * s**2 - 4 / 3 * s**3
    return 0.0


@_jit
def nodal_velocity(
    mom: np.ndarray, mass: np.ndarray, floor: float, fixed: np.ndarray, v: np.ndarray
) -> None:
    """v_i = (m v)_i / m_i where m_i > floor, else 0; held components 0 (D.6, D.10).

    Args:
        mom: nodal momentum, shape=(N, dim).
        mass: nodal mass, shape=(N,).
        floor: the active nodes' least mass.
        fixed: held components, shape=(N, dim) bool.
        v: out, shape=(N, dim).
    """
    N, dim = mom.shape
    for j in range(N):
        act = mass[j] > floor
        for a in range(dim):
            v[j, a] = mom[j, a] / mass[j] if act and not fixed[j, a] else 0.0


@_jit
def nodal_acceleration(
    f: np.ndarray,
    mass: np.ndarray,
    floor: float,
    fixed: np.ndarray,
    dt: float,
    v: np.ndarray,
    a_out: np.ndarray,
    v_new: np.ndarray,
) -> None:
    """a_i = f_i / m_i (active, not held; else 0) and v*_i = v_i + Δt a_i (D.3-D.4).

    Args:
        f: nodal force, shape=(N, dim).
        mass: nodal mass, shape=(N,).
        floor: the active nodes' least mass.
        fixed: held components, shape=(N, dim) bool.
        dt: time step.
        v: nodal velocity, shape=(N, dim).
        a_out: out, the acceleration, shape=(N, dim).
        v_new: out, the updated velocity, shape=(N, dim).
    """
    N, dim = f.shape
    for j in range(N):
        act = mass[j] > floor
        for a in range(dim):
            acc = f[j, a] / mass[j] if act and not fixed[j, a] else 0.0
            a_out[j, a] = acc
            v_new[j, a] = v[j, a] + dt * acc


@_jit
def outside(
    x: np.ndarray,
    lp: np.ndarray,
    boxes: bool,
    reach: float,
    lo: np.ndarray,
    hi: np.ndarray,
    out: np.ndarray,
) -> int:
    """:meth:`geofrac.mpm.grid.Grid.outside`: which particles reach beyond [lo, hi].

    The margin of :meth:`geofrac.mpm.shapes.Shape.margin`: ``lp`` or ``reach``.

    Args:
        x: positions, shape=(n, dim).
        lp: half-widths, shape=(n, dim), used when ``boxes``.
        boxes: whether the particles have boxes (GIMP).
        reach: the support's half-width beyond a point particle (without ``boxes``).
        lo: the grid's lowest corner, shape=(dim,).
        hi: its highest corner, shape=(dim,).
        out: out, shape=(n,) bool.

    Returns:
        How many are outside.
    """
    n, dim = x.shape
    count = 0
    for i in range(n):
        o = False
        for a in range(dim):
            m = lp[i, a] if boxes else reach
            if x[i, a] - m < lo[a] or x[i, a] + m > hi[a]:
                o = True
        out[i] = o
        count += o
    return count


@_jit
def bad_particles(x: np.ndarray, stress: np.ndarray, volume: np.ndarray, out: np.ndarray) -> int:
    """Particles with a non-finite position or stress or a non-positive volume.

    Args:
        x: positions, shape=(n, dim).
        stress: σ_p, shape=(n, dim, dim).
        volume: V_p, shape=(n,).
        out: out, shape=(n,) bool.

    Returns:
        How many are bad.
    """
    n, dim = x.shape
    count = 0
    for i in range(n):
        ok = volume[i] > 0
        for a in range(dim):
            ok = ok and np.isfinite(x[i, a])
            for b in range(dim):
                ok = ok and np.isfinite(stress[i, a, b])
        out[i] = not ok
        count += not ok
    return count
