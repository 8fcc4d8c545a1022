"""Print the interface stresses around a crack tip on EFMM grains (docs/granular.md).

Run from the repository root: ``.venv/bin/python docs/grain_tip_stress.py``. Two cases,
no event loop, one linear solve each, 1 rank:

1. ``tension``: a 100 x 100 plate (E = 30000, nu = 0.25, h = 4) stretched to
   sigma_yy = 30, with one interface cracked at its centre, or a chain of
   ``--chain`` interfaces along y = 50.3. It prints the largest sigma_n of the intact
   interfaces, how far each lies from the crack and which of its two grains use
   C-MultiMLSM, and the strain energy (150 uncracked; Griffith: 150 - pi a^2 sigma^2 / E).
2. ``beam``: jobs/grain_notched_beam.toml with the notch as a line of pre-cracked
   interfaces (``w = 0``) before the first event: sigma_n at the interfaces round the
   notch tip (from the C-MultiMLSM fits), and the EFMM patch stress of the same
   displacement at those interfaces for comparison.

3. ``holes``: jobs/grain_holes3.toml (``--holes 5``: grain_holes5) before the first
   event: the largest interface sigma_n of the EFMM grains beside sigma_n of a P2
   solution on a mesh of size ``--h-ref`` (0.4) at the same points, and the P2 sigma_xx
   above and below each hole.

sigma_n is the criterion's interface stress, the traction n . sigma n normal to the
interface (its chord's normal), docs/granular.md.

``--set KEY=VALUE`` passes scene overrides (``cracking.neighbours=6``, say).
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path
from typing import Any

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import numpy as np
from mpi4py import MPI

from geofrac.effects.cracking import scene_driver
from geofrac.fracture.criterion import normal_stress
from geofrac.fracture.driver import CrackDriver
from geofrac.meshing.distribute import build_mesh
from geofrac.scene import load_scene_collective

REPO = Path(__file__).resolve().parent.parent

SQUARE = """
Point(1) = {0, 0, 0, 4}; Point(2) = {100, 0, 0, 4};
Point(3) = {100, 100, 0, 4}; Point(4) = {0, 100, 0, 4};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};
Physical Surface("domain") = {1};
Physical Curve("bottom") = {1}; Physical Curve("top") = {3}; Physical Curve("left") = {4};
"""

TENSION = """
name = "grain_tip_tension"
effects = ["cracking"]
[geometry]
file = "square.geo"
[material]
E = 30000.0
nu = 0.25
plane = "stress"
tensile_strength = 2.4
[discretization]
element = "efmm"
q_rand = 0.1
domain_seed = 1
[[bc]]
group = "bottom"
value = [0.0]
components = ["y"]
[[bc]]
group = "left"
value = [0.0]
components = ["x"]
[[bc]]
group = "top"
value = [0.1]
components = ["y"]
[cracking]
margin = 1.01
"""


def driver(job: Path, overrides: list[str]) -> CrackDriver:
    """A grain driver for a scene, without output."""
    comm = MPI.COMM_SELF
    return scene_driver(load_scene_collective(comm, job, overrides), comm)


def solve(d: CrackDriver) -> np.ndarray:
    """The unit solution of the current crack state, shape=(num_dofs,)."""
    A, b, _held = d.assemble(np.zeros(d.n_global))
    x = b.duplicate()
    try:
        d.solve(A, b, x)
        return x.getArray().copy()  # one rank: the local array is the whole vector
    finally:
        for obj in (A, b, x):
            obj.destroy()


def report(d: CrackDriver, u: np.ndarray, crack: np.ndarray, near: np.ndarray) -> None:
    """Print the largest sigma_n of intact interfaces and the EFMM readout near ``near``."""
    st, centre = d.state, d.units.faces.centre
    s1, energy, _ = d.measures(u)
    s1[st.cracked] = -np.inf
    mls = st.is_mls()
    print(f"strain energy {energy:.6g}")
    for k in np.argsort(-s1)[:8]:
        dist = np.hypot(*(centre[crack] - centre[k]).T).min()
        grains = "".join("M" if mls[i] else "E" for i in st.mesh.edges[k])
        print(f"  x = ({centre[k, 0]:6.1f}, {centre[k, 1]:6.1f})  sigma_n = {s1[k]:7.2f}  "
              f"{dist:5.1f} from the crack  grains {grains}")  # fmt: skip
    if not len(near):
        return
    print("  at the tip: sigma_n as used | EFMM patch stress of the same u (both grains)")
    for k in near[np.argsort(-s1[near])][:6]:
        efmm = []
        for i in st.mesh.edges[k]:
            op = d.units.operator(int(i))
            stress = op.stress_at(d.units.faces.point[k][None])[0] @ u[d.ctx.mls_dofs(op.patch)]
            efmm.append(float(normal_stress(stress[None], d.units.faces.normal[k][None])[0]))
        print(f"  x = ({centre[k, 0]:6.1f}, {centre[k, 1]:6.1f})  {s1[k]:6.2f} | "
              f"{efmm[0]:6.2f} {efmm[1]:6.2f}")  # fmt: skip


def p2_stress(job: Path, h: float) -> Any:
    """A function (x, y) -> (sigma_xx, sigma_yy, tau_xy) of the P2 solution of a hole plate.

    The plate of ``job`` meshed with size h: bottom u_y = 0, u_x = 0 at the bottom-left
    corner, top u_y = -0.1 (the unit event load), plane stress.
    """
    import ufl
    from dolfinx import fem, geometry
    from dolfinx.fem.petsc import LinearProblem

    comm = MPI.COMM_SELF
    scene = load_scene_collective(comm, job, [f"geometry.parameters.h={h}"])
    msh = build_mesh(scene.geometry, comm).mesh
    mat = scene.material
    mu = mat.E / (2 * (1 + mat.nu))
    lam = mat.E * mat.nu / (1 - mat.nu**2)  # plane stress

    def sigma(w: Any) -> Any:
        eps = ufl.sym(ufl.grad(w))
        return 2 * mu * eps + lam * ufl.tr(eps) * ufl.Identity(2)

    V = fem.functionspace(msh, ("Lagrange", 2, (2,)))
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    L = ufl.inner(fem.Constant(msh, np.zeros(2)), v) * ufl.dx
    bcs = []
    for where, comp, value in [
        (lambda x: np.isclose(x[1], 0.0), 1, 0.0),
        (lambda x: np.isclose(x[1], 200.0), 1, -0.1),
        (lambda x: np.isclose(x[0], 0.0) & np.isclose(x[1], 0.0), 0, 0.0),
    ]:
        dofs = fem.locate_dofs_geometrical((V.sub(comp), V.sub(comp).collapse()[0]), where)
        bcs.append(fem.dirichletbc(np.float64(value), dofs[0], V.sub(comp)))
    problem = LinearProblem(
        ufl.inner(sigma(u), ufl.sym(ufl.grad(v))) * ufl.dx,
        L,
        bcs=bcs,
        petsc_options_prefix="grain_tip_p2_",
        petsc_options={"ksp_type": "preonly", "pc_type": "lu"},
    )
    uh = problem.solve()
    s = sigma(uh[0] if isinstance(uh, tuple) else uh)
    T = fem.functionspace(msh, ("DG", 1, (3,)))
    expr = fem.Expression(
        ufl.as_vector([s[0, 0], s[1, 1], s[0, 1]]), T.element.interpolation_points
    )
    out = fem.Function(T)
    out.interpolate(expr)
    tree = geometry.bb_tree(msh, 2)

    def at(x: float, y: float) -> np.ndarray:
        p = np.array([[x, y, 0.0]])
        cells = geometry.compute_colliding_cells(
            msh, geometry.compute_collisions_points(tree, p), p
        )
        return out.eval(p, cells.links(0)[:1])

    return at


def main() -> None:
    """Parse the command line and print one case."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("case", choices=["tension", "beam", "holes"])
    parser.add_argument("--chain", type=int, default=1, help="interfaces in the crack")
    parser.add_argument("--holes", type=int, default=3, choices=[3, 5])
    parser.add_argument("--h-ref", type=float, default=0.4, help="P2 reference mesh size")
    parser.add_argument("--set", action="append", default=[], dest="overrides")
    args = parser.parse_args()
    if args.case == "tension":
        with tempfile.TemporaryDirectory() as tmp:
            (Path(tmp) / "square.geo").write_text(SQUARE)
            job = Path(tmp) / "tension.toml"
            job.write_text(TENSION)
            d = driver(job, args.overrides)
        m, centre = d.state.mesh, d.units.faces.centre
        a, b = m.coords[m.edges[:, 0]], m.coords[m.edges[:, 1]]
        crosses = np.flatnonzero((a[:, 1] - 50.3) * (b[:, 1] - 50.3) < 0)
        crack = crosses[np.argsort(np.abs(centre[crosses, 0] - 50.0))][: args.chain]
        d.state.start(np.sort(crack))
        x = centre[crack, 0]
        print(f"tension: {len(crack)} cracked interface(s), x from {x.min():.1f} to {x.max():.1f}")
        report(d, solve(d), crack, np.zeros(0, dtype=np.int64))
    elif args.case == "holes":
        job = REPO / "jobs" / f"grain_holes{args.holes}.toml"
        d = driver(job, args.overrides)
        d.state.start(np.zeros(0, dtype=np.int64))
        s1, _, _ = d.measures(solve(d))
        point, normal = d.units.faces.point, d.units.faces.normal
        at = p2_stress(job, args.h_ref)
        print(f"holes: {args.holes} holes, unit load, sigma_n at the interfaces' points")
        print(f"  EFMM grains | P2 (h = {args.h_ref:g}) at the same point")
        for k in np.argsort(-s1)[:8]:
            ref = float(normal_stress(at(*point[k]).reshape(1, 3), normal[k][None])[0])
            print(f"  ({point[k, 0]:6.2f}, {point[k, 1]:6.2f})  {s1[k]:6.2f} | {ref:6.2f}")
        print("  P2 sigma_xx at 0.05, 0.3, 1, 2 mm above and below each hole:")
        holes = [(50, 100, 10), (30, 60, 6), (70, 140, 6), (72, 68, 4), (28, 132, 4)]
        for cx, cy, r in holes[: args.holes]:
            for side, name in ((1, "above"), (-1, "below")):
                sxx = [float(at(cx, cy + side * (r + g))[0]) for g in (0.05, 0.3, 1.0, 2.0)]
                print(f"  hole ({cx}, {cy}) r = {r} {name}: " + " ".join(f"{v:6.2f}" for v in sxx))
    else:
        overrides = ["geometry.parameters.w=0", 'cracking.precracked=["notch"]', *args.overrides]
        d = driver(REPO / "jobs" / "grain_notched_beam.toml", overrides)
        d.state.start(d.precracked)
        centre = d.units.faces.centre
        near = np.flatnonzero(np.hypot(centre[:, 0], centre[:, 1] - 75.0) < 9.0)
        near = near[~d.state.cracked[near]]
        print(f"beam: {len(d.precracked)} interfaces along the notch, before the first event")
        report(d, solve(d), d.precracked, near)
    d.destroy()


if __name__ == "__main__":
    main()
