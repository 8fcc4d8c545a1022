"""``geofrac bench stability``: distorted meshes and ν → 0.5 on the Timoshenko cantilever.

For each element the scene ``jobs/cantilever.toml`` is solved on ny × 10 ny meshes built by
:mod:`geofrac.meshing.distorted`: (a) in plane stress at ν = 0.3 on meshes distorted to
minimum angles 45° (undistorted) … 5°; (b) in plane strain for ν = 0.3 … 0.499 on the
undistorted mesh and on the most distorted one. Every case records the relative
displacement and energy errors and their degradation, the ratio to the same element's
error on its baseline: 45° at ν = 0.3 (plane stress) for (a), 45° at the smallest ν
(plane strain) for (b). A solver failure (:class:`~geofrac.errors.RunError`), a mesh that
could not be built or a non-finite error norm is recorded as the case's ``status``,
printed in the table and counted; the study goes on. Writes ``stability.json`` and
``stability.png`` to the output directory, and the meshes to its ``meshes/``.
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path
from typing import TYPE_CHECKING, Any

from geofrac.bench.args import number_list

if TYPE_CHECKING:
    from mpi4py import MPI

__all__ = ["add_arguments", "run"]

_SCENE = Path(__file__).resolve().parents[2] / "jobs" / "cantilever.toml"
#: Beam length and depth of the scene (the exact solution reads them from ``[exact]``).
LENGTH, DEPTH = 10.0, 1.0
#: Minimum angle of the undistorted right-isosceles mesh: the baseline of both sweeps.
UNDISTORTED = 45.0
#: Poisson's ratio of the angle sweep (plane stress).
ANGLE_SWEEP_NU = 0.3

COLUMNS = (
    ("element", "element", "s"),
    ("sweep", "sweep", "s"),
    ("angle_target", "angle", "g"),
    ("min_angle", "min angle", ".2f"),
    ("nu", "nu", "g"),
    ("plane", "plane", "s"),
    ("dofs", "DOFs", "d"),
    ("error_u_relative", "rel ||e||_u", ".3e"),
    ("error_energy_relative", "rel ||e||_energy", ".3e"),
    ("degradation_u", "degr. u", ".3g"),
    ("degradation_energy", "degr. energy", ".3g"),
    ("status", "status", "s"),
)


_float_list = number_list(float, math.isfinite, "finite")


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Options of this bench."""
    from geofrac.elements import available

    p.add_argument(
        "--elements",
        default="cst,p2,rgnt,gnt",
        help=f"comma-separated elements from {', '.join(available())} (default: cst,p2,rgnt,gnt)",
    )
    p.add_argument(
        "--angles",
        type=_float_list,
        default=[45.0, 30.0, 15.0, 10.0, 5.0],
        help="minimum angles [degrees] in (0, 45] of the plane-stress sweep; 45 (undistorted, "
        "the baseline) is always run (default: 45,30,15,10,5)",
    )
    p.add_argument(
        "--nus",
        type=_float_list,
        default=[0.3, 0.45, 0.49, 0.499],
        help="Poisson's ratios of the plane-strain sweep, on the 45° mesh and the smallest "
        "angle's mesh; the smallest is the baseline (default: 0.3,0.45,0.49,0.499)",
    )
    p.add_argument(
        "--ny", type=int, default=8, help="cells across the depth; nx = 10 ny (default: 8)"
    )
    p.add_argument("--seed", type=int, default=0, help="seed of the node distortion (default: 0)")
    p.add_argument(
        "--out", type=Path, default=Path("results/bench-stability"), help="output directory"
    )
    p.add_argument("--json", type=Path, help="also write the JSON report to this file")


def _build_meshes(
    comm: MPI.Comm, targets: list[float], ny: int, seed: int, directory: Path
) -> dict[float, dict[str, Any]]:
    """Build one mesh per target angle on rank 0; every rank gets the same descriptions.

    A mesh that cannot be built is described by ``{"target", "error"}`` (never a hang).
    """
    from geofrac.meshing.distorted import build_distorted_cantilever

    meshes: dict[float, dict[str, Any]] | None = None
    if comm.rank == 0:
        meshes = {}
        for target in targets:
            path = (directory / f"cantilever-ny{ny}-angle{target:g}-seed{seed}.msh").resolve()
            try:
                m = build_distorted_cantilever(
                    path, ny, target, length=LENGTH, depth=DEPTH, seed=seed
                )
            except Exception as exc:  # reported as the status of every case on this mesh
                meshes[target] = {"target": target, "error": f"mesh {target:g}°: {exc}"}
                continue
            meshes[target] = {
                "target": target,
                "path": str(m.path),
                "min_angle": m.min_angle,
                "max_angle": m.max_angle,
                "amplitude": m.amplitude,
                "nodes": m.nodes,
                "cells": m.cells,
            }
    return comm.bcast(meshes, root=0)


def _solve_case(
    comm: MPI.Comm, element: str, mesh: dict[str, Any], nu: float, plane: str, overrides: list[str]
) -> dict[str, Any]:
    """Solve one case; failures and non-finite errors become ``status`` = ``"error: ..."``."""
    from geofrac.errors import RunError
    from geofrac.log import echo
    from geofrac.runner import solve_scene
    from geofrac.scene import load_scene_collective
    from geofrac.timing import Timings

    out: dict[str, Any] = {"dofs": None, "solver": None, "warnings": [], "status": "ok"}
    for key in ("u", "energy", "u_relative", "energy_relative"):
        out[f"error_{key}"] = None
    if "error" in mesh:
        out["status"] = f"error: {mesh['error']}"
        return out
    scene_overrides = [
        f"discretization.element={element}",
        f"geometry.file={json.dumps(mesh['path'])}",
        "geometry.parameters={}",
        f"exact.L={LENGTH}",
        f"exact.D={DEPTH}",
        f"material.nu={nu}",
        f"material.plane={plane}",
        "output.probes={}",
        *overrides,
    ]
    scene = load_scene_collective(comm, _SCENE, scene_overrides)
    out["warnings"] = list(scene.warnings)
    for warning in scene.warnings:
        echo(comm, f"warning: {warning}", err=True)
    try:
        solution = solve_scene(scene, comm, Timings(), verbose=False)
    except RunError as exc:  # raised collectively: every rank records the same status
        out["status"] = f"error: {exc}"
        return out
    try:
        errors = solution.results["errors"]
        out["dofs"] = solution.problem.element.num_dofs
        out["solver"] = solution.results["solver"]["preset"]
    finally:
        solution.problem.destroy()
    values = {key: errors[key] for key in ("u", "energy", "u_relative", "energy_relative")}
    if not all(math.isfinite(v) for v in values.values()):
        out["status"] = "error: non-finite error norm " + ", ".join(
            f"{k}={v!r}" for k, v in values.items()
        )
        return out
    for key, value in values.items():
        out[f"error_{key}"] = value
    return out


def _degradation(records: list[dict[str, Any]], baseline_nu: float) -> None:
    """Add ``degradation_u`` and ``degradation_energy``: relative error / baseline's."""
    for r in records:
        if r["sweep"] == "angle":
            base_nu, base_plane = ANGLE_SWEEP_NU, "stress"
        else:
            base_nu, base_plane = baseline_nu, "strain"
        base = next(
            (
                b
                for b in records
                if b["element"] == r["element"]
                and b["sweep"] == r["sweep"]
                and b["angle_target"] == UNDISTORTED
                and b["nu"] == base_nu
                and b["plane"] == base_plane
            ),
            None,
        )
        for key in ("u", "energy"):
            value = r[f"error_{key}_relative"]
            ref = None if base is None else base[f"error_{key}_relative"]
            ok = value is not None and ref is not None and ref > 0
            r[f"degradation_{key}"] = value / ref if ok else None


def _plot(records: list[dict[str, Any]], path: Path, title: str) -> None:
    """Two panels: relative displacement error vs minimum angle, and vs ν (plane strain)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    from geofrac.bench.report import save_figure

    def forward(nu: np.ndarray) -> np.ndarray:
        return -np.log10(np.clip(0.5 - np.asarray(nu, dtype=float), 1e-9, None))

    def inverse(t: np.ndarray) -> np.ndarray:
        return 0.5 - 10.0 ** (-np.asarray(t, dtype=float))

    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5), constrained_layout=True)
    names = list(dict.fromkeys(r["element"] for r in records))
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    meshes = sorted({r["angle_target"] for r in records if r["sweep"] == "nu"}, reverse=True)
    for color, name in zip(colors, names, strict=False):
        ok = [r for r in records if r["element"] == name and r["error_u_relative"] is not None]
        rows = sorted((r for r in ok if r["sweep"] == "angle"), key=lambda r: r["min_angle"])
        axes[0].semilogy(
            [r["min_angle"] for r in rows],
            [r["error_u_relative"] for r in rows],
            "-o",
            color=color,
            label=name,
        )
        for target, style in zip(meshes, ("-o", "--s"), strict=False):
            rows = sorted(
                (r for r in ok if r["sweep"] == "nu" and r["angle_target"] == target),
                key=lambda r: r["nu"],
            )
            axes[1].semilogy(
                [r["nu"] for r in rows],
                [r["error_u_relative"] for r in rows],
                style,
                color=color,
                label=f"{name}, {target:g}° mesh",
            )
    axes[0].invert_xaxis()
    axes[0].set_xlabel("minimum angle of the mesh [degrees] (plane stress, ν = 0.3)")
    nus = sorted({r["nu"] for r in records if r["sweep"] == "nu"})
    axes[1].set_xscale("function", functions=(forward, inverse))
    axes[1].set_xticks(nus, [f"{nu:g}" for nu in nus])
    axes[1].set_xlabel("Poisson's ratio ν (plane strain; axis: -log10(0.5 - ν))")
    save_figure(fig, axes, path, title=title, ylabel="relative displacement L2 error")


def _summary_lines(records: list[dict[str, Any]], worst_angle: float, nu_max: float) -> list[str]:
    """One line per element: its degradation at the smallest angle and at the largest ν."""

    def find(element: str, sweep: str, angle: float, *, nu: float) -> str:
        r = next(
            (
                r
                for r in records
                if (r["element"], r["sweep"], r["angle_target"], r["nu"])
                == (element, sweep, angle, nu)
            ),
            None,
        )
        if r is None:
            return "-"
        if r["degradation_u"] is None:
            return "failed" if r["status"] != "ok" else "-"
        return f"x{r['degradation_u']:.3g}"

    lines = []
    for element in dict.fromkeys(r["element"] for r in records):
        stress = find(element, "angle", worst_angle, nu=ANGLE_SWEEP_NU)
        parts = [f"{worst_angle:g}° (plane stress): {stress}"]
        for angle in dict.fromkeys((UNDISTORTED, worst_angle)):
            strain = find(element, "nu", angle, nu=nu_max)
            parts.append(f"ν={nu_max:g} plane strain, {angle:g}° mesh: {strain}")
        lines.append(f"degradation of ||e||_u, {element}: " + "; ".join(parts))
    return lines


def run(args: argparse.Namespace, comm: MPI.Comm) -> dict[str, Any]:
    """Run the study; return the JSON report (identical on every rank)."""
    from geofrac.bench.report import format_table, save_report
    from geofrac.bench.study import parse_elements
    from geofrac.io.summary import versions
    from geofrac.log import Progress, echo
    from geofrac.scene import SceneError

    elements = parse_elements(args.elements, 2)
    if not elements:
        raise SceneError("--elements", "", "no element given")
    if args.ny < 1:
        raise SceneError("--ny", "", f"must be >= 1, got {args.ny}")
    for angle in args.angles:
        if not 0.0 < angle <= UNDISTORTED:
            raise SceneError("--angles", "", f"angles must lie in (0, 45], got {angle:g}")
    for nu in args.nus:
        if not -1.0 < nu < 0.5:
            raise SceneError("--nus", "", f"Poisson's ratios must lie in (-1, 0.5), got {nu:g}")
    targets = sorted({UNDISTORTED, *args.angles}, reverse=True)
    worst = targets[-1]
    nus = sorted(set(args.nus))
    nu_meshes = list(dict.fromkeys((UNDISTORTED, worst)))

    meshes = _build_meshes(comm, targets, args.ny, args.seed, args.out / "meshes")
    cases = [(e, "angle", t, ANGLE_SWEEP_NU, "stress") for e in elements for t in targets]
    cases += [(e, "nu", t, nu, "strain") for e in elements for t in nu_meshes for nu in nus]
    cases.sort(key=lambda c: elements.index(c[0]))
    progress = Progress(comm, len(cases), "bench stability", unit="cases")
    records = []
    for element, sweep, target, nu, plane in cases:
        mesh = meshes[target]
        record = {
            "element": element,
            "sweep": sweep,
            "angle_target": target,
            "min_angle": mesh.get("min_angle"),
            "max_angle": mesh.get("max_angle"),
            "nu": nu,
            "plane": plane,
            "mesh": f"{args.ny}x{10 * args.ny}",
        }
        record |= _solve_case(comm, element, mesh, nu, plane, list(args.overrides))
        records.append(record)
        err = record["error_u_relative"]
        progress.step(
            f"{element} {target:g}° ν={nu:g} plane {plane}: "
            + (f"relative ||e||_u = {err:.3e}" if err is not None else record["status"])
        )
    _degradation(records, nus[0])
    failures = [r for r in records if r["status"] != "ok"]

    report = {
        "bench": "stability",
        "scene": str(_SCENE),
        "overrides": list(args.overrides),
        "ranks": comm.size,
        "versions": versions(),
        "mesh": f"{args.ny}x{10 * args.ny}",
        "distortion": (
            "nodes moved by amplitude * h * r, r seeded uniform in [-1, 1]^2 with no component "
            "normal to the boundary; amplitude bisected to the target minimum angle"
        ),
        "seed": args.seed,
        "baseline": (
            f"same element, {UNDISTORTED:g}° mesh: nu = {ANGLE_SWEEP_NU:g} plane stress for the "
            f"angle sweep, nu = {nus[0]:g} plane strain for the nu sweep"
        ),
        "meshes": list(meshes.values()),
        "records": records,
        "failures": len(failures),
        "rates": {},  # one mesh size: no convergence rate
    }
    if comm.rank == 0:
        echo(comm, format_table(records, COLUMNS))
        for line in _summary_lines(records, worst, nus[-1]):
            echo(comm, line)
        echo(comm, f"failures: {len(failures)} of {len(records)} cases")
        for r in failures:
            echo(
                comm,
                f"  {r['element']} {r['angle_target']:g}° ν={r['nu']:g} plane {r['plane']}: "
                f"{r['status']}",
            )
        save_report(report, args.out / "stability.json", args.json)
        _plot(
            records,
            args.out / "stability.png",
            f"Timoshenko cantilever {report['mesh']}: distorted meshes and ν → 0.5",
        )
        echo(comm, f"wrote {args.out / 'stability.json'} and {args.out / 'stability.png'}")
    return report
