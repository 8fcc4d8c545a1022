"""Analytical solutions used as Dirichlet data, tractions and error references.

Pure mathematics: every formula is written once with ``+ - * / **`` only, so the same
method evaluates on numpy arrays (interpolation into finite element spaces, probes) and
on UFL expressions of ``ufl.SpatialCoordinate`` (exact fields inside error integrals).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol, cast

if TYPE_CHECKING:
    import numpy as np
    from numpy.typing import ArrayLike

__all__ = [
    "EXACT_SOLUTIONS",
    "OPTIONAL_PARAMETERS",
    "ExactSolution",
    "Field",
    "LameCylinder",
    "ManufacturedBox",
    "TimoshenkoCantilever",
    "UniformStrain",
    "displacement_gradient",
    "make_exact",
]


class Field(Protocol):
    """What the formulas compute with: a float, a numpy array or a UFL expression.

    Arrays may be complex (:func:`displacement_gradient`) and of any shape; the formulas
    use only ``+ - * / **`` with numbers and each other.
    """

    def __add__(self, other: Any, /) -> Field: ...
    def __radd__(self, other: Any, /) -> Field: ...
    def __sub__(self, other: Any, /) -> Field: ...
    def __rsub__(self, other: Any, /) -> Field: ...
    def __mul__(self, other: Any, /) -> Field: ...
    def __rmul__(self, other: Any, /) -> Field: ...
    def __truediv__(self, other: Any, /) -> Field: ...
    def __rtruediv__(self, other: Any, /) -> Field: ...
    def __pow__(self, other: Any, /) -> Field: ...
    def __neg__(self) -> Field: ...
    def __float__(self) -> float: ...


class ExactSolution:
    """Interface of an analytical elasticity solution in ``dim`` dimensions."""

    dim: int

    def displacement(self, x: Field, y: Field, z: Field | None = None) -> tuple[Field, ...]:
        """Displacement components at (x, y[, z]); arrays of any shape or UFL."""
        raise NotImplementedError

    def stress(self, x: Field, y: Field, z: Field | None = None) -> tuple[tuple[Field, ...], ...]:
        """Cauchy stress tensor rows at (x, y[, z]); shape=(dim, dim) of components."""
        raise NotImplementedError


@dataclass(frozen=True)
class TimoshenkoCantilever(ExactSolution):
    """Cantilever under a parabolic end shear (Timoshenko & Goodier).

    Edo (2016), eqs. 2.24-2.25 and 3.31.

    The beam occupies ``0 <= x <= L``, ``-D/2 <= y <= D/2``; the end ``x = 0`` is held by
    the exact displacement and the end ``x = L`` carries the shear traction
    ``t_y = P/(2I) (D²/4 - y²)`` whose resultant is ``P`` (upward for ``P > 0``).
    ``I = D³/12`` per unit thickness. The formulas are for plane stress; for plane strain
    the constants are replaced by ``E/(1-ν²)`` and ``ν/(1-ν)``.

    Attributes:
        P: end load resultant per unit thickness.
        L: length.
        D: depth.
        E: Young's modulus (effective, see above).
        nu: Poisson's ratio (effective, see above).
    """

    P: float
    L: float
    D: float
    E: float
    nu: float
    dim: int = 2

    @property
    def I(self) -> float:  # noqa: E743 - the symbol of Edo (2016) and of Timoshenko
        """Second moment of area per unit thickness, D³/12."""
        return self.D**3 / 12.0

    def displacement(self, x: Field, y: Field, z: Field | None = None) -> tuple[Field, Field]:
        """Edo (2016), eqs. (2.24)-(2.25): (u, v) at (x, y)."""
        P, L, D, E, nu, I = self.P, self.L, self.D, self.E, self.nu, self.I
        u = -P * y / (6.0 * E * I) * ((6.0 * L - 3.0 * x) * x + (2.0 + nu) * (y * y - D * D / 4.0))
        v = (
            P
            / (6.0 * E * I)
            * (
                3.0 * nu * y * y * (L - x)
                + D * D * x / 4.0 * (4.0 + 5.0 * nu)
                + (3.0 * L - x) * x * x
            )
        )
        return (u, v)

    def stress(
        self, x: Field, y: Field, z: Field | None = None
    ) -> tuple[tuple[Field, Field], tuple[Field, Field]]:
        """Edo (2016), eqs. (3.31c)-(3.31e): ((σx, τxy), (τxy, σy)) at (x, y)."""
        P, L, D, I = self.P, self.L, self.D, self.I
        sxx = -P * (L - x) * y / I
        sxy = P / (2.0 * I) * (D * D / 4.0 - y * y)
        syy = 0.0 * x
        return ((sxx, sxy), (sxy, syy))

    def tip_deflection(self) -> float:
        """v(L, 0) = PL³/(3EI) + (4+5ν) P D² L / (24 E I)."""
        return float(self.displacement(self.L, 0.0)[1])


@dataclass(frozen=True)
class UniformStrain(ExactSolution):
    """Linear displacement with constant strain: the patch test (Edo (2016), eqs. 2.26-2.27).

    u = exx·x + ½gxy·y, v = eyy·y + ½gxy·x; every conforming element must reproduce it
    exactly on any mesh. The patch test of Edo (2016) is exx = 0.002, eyy = -0.0006, gxy = 0.

    Attributes:
        exx, eyy, gxy: strain components (engineering shear gxy).
        lam, mu: Lamé constants of the analysis plane (see :func:`geofrac.materials.lame`).
    """

    exx: float
    eyy: float
    gxy: float
    lam: float
    mu: float
    dim: int = 2

    def displacement(self, x: Field, y: Field, z: Field | None = None) -> tuple[Field, Field]:
        """(u, v) at (x, y)."""
        return (self.exx * x + 0.5 * self.gxy * y, self.eyy * y + 0.5 * self.gxy * x)

    def stress(
        self, x: Field, y: Field, z: Field | None = None
    ) -> tuple[tuple[Field, Field], tuple[Field, Field]]:
        """Constant stress σ = 2μ ε + λ tr(ε) I, broadcast to the shape of x."""
        tr = self.exx + self.eyy
        one = 0.0 * x + 1.0
        sxx = (2.0 * self.mu * self.exx + self.lam * tr) * one
        syy = (2.0 * self.mu * self.eyy + self.lam * tr) * one
        sxy = self.mu * self.gxy * one
        return ((sxx, sxy), (sxy, syy))


@dataclass(frozen=True)
class ManufacturedBox(ExactSolution):
    """A smooth 3D displacement for manufactured-solution convergence studies.

    u = a (x³ + yz(1 + x²), y³z + xz(1 - y²), z⁴ + xy(1 + z²)): quartic, so no element
    studied here reproduces it, with a non-zero rotation field (curl u ≠ 0) that the
    rotational DOFs of RGNQ must follow. The body force is -div σ(u) (a scene's
    ``[[load]] type = "body_force", value = "exact"``) and the boundary values are u.

    Attributes:
        a: amplitude.
        lam, mu: Lamé constants.
    """

    a: float
    lam: float
    mu: float
    dim: int = 3

    def displacement(
        self, x: Field, y: Field, z: Field | None = None
    ) -> tuple[Field, Field, Field]:
        """(u, v, w) at (x, y, z)."""
        assert z is not None  # a 3D solution
        a = self.a
        return (
            a * (x**3 + y * z * (1.0 + x * x)),
            a * (y**3 * z + x * z * (1.0 - y * y)),
            a * (z**4 + x * y * (1.0 + z * z)),
        )

    def gradient(self, x: Field, y: Field, z: Field) -> tuple[tuple[Field, Field, Field], ...]:
        """Rows ∂u_r/∂(x, y, z), written out by hand."""
        a = self.a
        return (
            (a * (3.0 * x * x + 2.0 * x * y * z), a * z * (1.0 + x * x), a * y * (1.0 + x * x)),
            (
                a * z * (1.0 - y * y),
                a * (3.0 * y * y * z - 2.0 * x * y * z),
                a * (y**3 + x * (1.0 - y * y)),
            ),
            (a * y * (1.0 + z * z), a * x * (1.0 + z * z), a * (4.0 * z**3 + 2.0 * x * y * z)),
        )

    def stress(self, x: Field, y: Field, z: Field | None = None) -> tuple[tuple[Field, ...], ...]:
        """σ = λ tr(∇u) I + μ (∇u + ∇uᵀ)."""
        assert z is not None  # a 3D solution
        g = self.gradient(x, y, z)
        tr = g[0][0] + g[1][1] + g[2][2]
        return tuple(
            tuple(
                self.mu * (g[r][s] + g[s][r]) + (self.lam * tr if r == s else 0.0 * x)
                for s in range(3)
            )
            for r in range(3)
        )


@dataclass(frozen=True)
class LameCylinder(ExactSolution):
    """Lamé's thick-walled cylinder under internal and external pressure.

    Timoshenko & Goodier, Theory of Elasticity (3rd ed., 1970), §28: the cylinder
    ``a <= r <= b`` about the z axis with pressure ``p`` on ``r = a`` and ``p_outer`` on
    ``r = b`` (positive pushing into the wall) has

    σ_rr = A - B/r², σ_θθ = A + B/r²,
    A = (p a² - p_outer b²)/(b² - a²), B = (p - p_outer) a² b²/(b² - a²),

    and the radial displacement u_r = (1+ν)/E ((1-2ν) A r + B/r) in plane strain
    (σ_zz = 2ν A, u_z = 0), u_r = ((1-ν) A r + (1+ν) B/r)/E in plane stress (σ_zz = 0).
    In 3D (``dim = 3``) the field is the plane-strain one with u_z = 0: the solution of a
    length of cylinder whose ends are held by rollers. Cartesian components use
    r² = x² + y² only (no square root): u_x = u_r x/r, σ_xx = A + B (y² - x²)/r⁴,
    σ_yy = A + B (x² - y²)/r⁴, σ_xy = -2 B x y/r⁴.

    Attributes:
        a: inner radius.
        b: outer radius, > a.
        p: internal pressure.
        p_outer: external pressure.
        E: Young's modulus.
        nu: Poisson's ratio.
        plane: ``"strain"`` or ``"stress"`` (2D; 3D is plane strain).
        dim: 2 or 3.
    """

    a: float
    b: float
    p: float
    p_outer: float
    E: float
    nu: float
    plane: str = "strain"
    dim: int = 2

    def __post_init__(self) -> None:
        """Refuse radii that are not 0 < a < b (ValueError)."""
        if not 0.0 < self.a < self.b:
            raise ValueError(f"needs 0 < a < b, got a = {self.a!r}, b = {self.b!r}")

    @property
    def A(self) -> float:
        """(p a² - p_outer b²)/(b² - a²)."""
        a2, b2 = self.a * self.a, self.b * self.b
        return (self.p * a2 - self.p_outer * b2) / (b2 - a2)

    @property
    def B(self) -> float:
        """(p - p_outer) a² b²/(b² - a²)."""
        a2, b2 = self.a * self.a, self.b * self.b
        return (self.p - self.p_outer) * a2 * b2 / (b2 - a2)

    def _coefficients(self) -> tuple[float, float]:
        """(c1, c2) with u_r = c1 r + c2 / r."""
        E, nu, A, B = self.E, self.nu, self.A, self.B
        if self.plane == "stress" and self.dim == 2:
            return (1.0 - nu) * A / E, (1.0 + nu) * B / E
        return (1.0 + nu) * (1.0 - 2.0 * nu) * A / E, (1.0 + nu) * B / E

    def radial_displacement(self, r: Field) -> Field:
        """u_r at radius r."""
        c1, c2 = self._coefficients()
        return c1 * r + c2 / r

    def radial_stress(self, r: Field) -> Field:
        """σ_rr at radius r."""
        return self.A - self.B / (r * r)

    def hoop_stress(self, r: Field) -> Field:
        """σ_θθ at radius r."""
        return self.A + self.B / (r * r)

    def displacement(self, x: Field, y: Field, z: Field | None = None) -> tuple[Field, ...]:
        """(u_x, u_y) in 2D, (u_x, u_y, 0) in 3D."""
        c1, c2 = self._coefficients()
        r2 = x * x + y * y
        scale = c1 + c2 / r2  # u_r / r
        out = (scale * x, scale * y)
        return out if self.dim == 2 else (*out, 0.0 * x)

    def stress(self, x: Field, y: Field, z: Field | None = None) -> tuple[tuple[Field, ...], ...]:
        """In-plane stress rows; in 3D with σ_zz = 2ν A (plane strain)."""
        A, B = self.A, self.B
        r2 = x * x + y * y
        r4 = r2 * r2
        sxx = A + B * (y * y - x * x) / r4
        syy = A + B * (x * x - y * y) / r4
        sxy = -2.0 * B * x * y / r4
        if self.dim == 2:
            return ((sxx, sxy), (sxy, syy))
        zero = 0.0 * x
        szz = 2.0 * self.nu * A + zero
        return ((sxx, sxy, zero), (sxy, syy, zero), (zero, zero, szz))


def displacement_gradient(exact: ExactSolution, x: ArrayLike) -> np.ndarray:
    """∂u_r/∂x_s of an exact solution by complex-step differentiation (exact to round-off).

    The formulas use only ``+ - * / **``, so they accept complex arrays; with a step
    h = 1e-30, Im(u(x + i h e_s)) / h is the derivative without cancellation.

    Args:
        exact: the solution.
        x: points, shape=(n, dim) (or more columns; the first ``dim`` are used).

    Returns:
        gradients, shape=(n, dim, dim).
    """
    import numpy as np

    dim = exact.dim
    pts = np.asarray(x, dtype=float)[:, :dim]
    grad = np.empty((len(pts), dim, dim))
    h = 1e-30
    for s in range(dim):
        z = pts.astype(complex)
        z[:, s] += 1j * h
        u = exact.displacement(*z.T)
        for r in range(dim):
            ur = cast("np.ndarray", u[r])  # a complex array, or a number
            grad[:, r, s] = np.imag(np.broadcast_to(ur, (len(pts),))) / h
    return grad


class ExactFactory(Protocol):
    """Builds an exact solution from its parameters and the material."""

    def __call__(
        self, params: dict[str, float], E: float, nu: float, *, plane: str
    ) -> ExactSolution:
        """The solution for ``params`` (names of :data:`EXACT_SOLUTIONS`), E, nu, plane."""
        ...


def _timoshenko(
    params: dict[str, float], E: float, nu: float, *, plane: str
) -> TimoshenkoCantilever:
    if plane == "strain":
        E, nu = E / (1.0 - nu * nu), nu / (1.0 - nu)
    return TimoshenkoCantilever(P=params["P"], L=params["L"], D=params["D"], E=E, nu=nu)


def _uniform_strain(params: dict[str, float], E: float, nu: float, *, plane: str) -> UniformStrain:
    from geofrac.materials import lame

    lam, mu = lame(E, nu, 2, plane=plane)
    return UniformStrain(params["exx"], params["eyy"], params["gxy"], lam, mu)


def _manufactured_box(
    params: dict[str, float], E: float, nu: float, *, plane: str
) -> ManufacturedBox:
    from geofrac.materials import lame

    lam, mu = lame(E, nu, 3)
    return ManufacturedBox(params["a"], lam, mu)


def _lame(dim: int) -> ExactFactory:
    def factory(params: dict[str, float], E: float, nu: float, *, plane: str) -> LameCylinder:
        a, b = params["a"], params["b"]
        p_outer = params.get("p_outer", 0.0)
        return LameCylinder(a, b, params["p"], p_outer, E, nu, plane if dim == 2 else "strain", dim)

    return factory


#: name -> (dimension, required parameter names, factory(params, E, nu, plane=...)).
EXACT_SOLUTIONS: dict[str, tuple[int, tuple[str, ...], ExactFactory]] = {
    "timoshenko_cantilever": (2, ("P", "L", "D"), _timoshenko),
    "uniform_strain": (2, ("exx", "eyy", "gxy"), _uniform_strain),
    "manufactured_box": (3, ("a",), _manufactured_box),
    "lame_cylinder": (2, ("a", "b", "p"), _lame(2)),
    "lame_cylinder_3d": (3, ("a", "b", "p"), _lame(3)),
}
#: name -> parameters that may be left out, with their defaults.
OPTIONAL_PARAMETERS: dict[str, dict[str, float]] = {
    "lame_cylinder": {"p_outer": 0.0},
    "lame_cylinder_3d": {"p_outer": 0.0},
}


def make_exact(
    name: str, params: dict[str, float], *, E: float, nu: float, plane: str
) -> ExactSolution:
    """Build the exact solution ``name`` for a material (E, nu) in plane ``stress``/``strain``."""
    _, _, factory = EXACT_SOLUTIONS[name]
    return factory(params, E, nu, plane=plane)
