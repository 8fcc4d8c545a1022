"""Run every crack scene of jobs/ and compare the event logs of two runs.

The "behaviour unchanged" check of a refactoring: run all scenes that declare the
``cracking`` effect before and after the change, then compare the two directories::

    python scripts/compare_crack_jobs.py run /tmp/before        # on the old commit
    python scripts/compare_crack_jobs.py run /tmp/after         # on the new commit
    python scripts/compare_crack_jobs.py compare /tmp/before /tmp/after

``run`` writes ``<scene>.events.csv`` per scene and ``runs.json`` (command, cap, seconds,
exit code per scene) into the directory. Long scenes are capped with
``--set cracking.max_events=K`` (:data:`CAPS`, printed as they run) so that each takes
well under a minute on one rank; XDMF output is switched off (``output.xdmf=false``),
which does not touch the event sequence. ``compare`` reports, per scene, whether the two
files are byte-identical and otherwise the first differing row.

The code that runs is the checkout this script lives in (``python -m geofrac`` with the
repository as the working directory and on ``PYTHONPATH``).
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
import tomllib
from pathlib import Path

__all__ = ["CAPS", "compare", "crack_scenes", "main", "run"]

ROOT = Path(__file__).resolve().parents[1]

#: cracking.max_events for the scenes that would take over a minute on one rank
#: (their own max_events is 300-3000). Scenes not listed run to their own end
#: (notched_beam ends `separated` near event 100; crack_patch_test has no events).
CAPS: dict[str, int] = {
    "crack_model1": 40,
    "crack_model2": 40,
    "crack_model3": 40,
    "crack_model4": 40,
    "dcn_plate": 150,
    "grain_dcn_0pct": 100,
    "grain_dcn_4pct_seed1": 100,
    "grain_dcn_4pct_seed2": 100,
    "grain_holes1": 100,
    "grain_holes3": 100,
    "grain_holes5": 100,
    "grain_notched_beam": 100,
    "plate_hole": 150,
}


def crack_scenes(jobs: Path = ROOT / "jobs") -> list[Path]:
    """The scene files whose ``effects`` list names ``cracking``, sorted by name."""
    out = []
    for path in sorted(jobs.glob("*.toml")):
        with path.open("rb") as f:
            if "cracking" in tomllib.load(f).get("effects", []):
                out.append(path)
    return out


def run(directory: Path, only: list[str] | None = None, ranks: int = 1) -> int:
    """Run each crack scene and keep its ``events.csv`` in ``directory``; 0 if all ran."""
    directory.mkdir(parents=True, exist_ok=True)
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    record: dict[str, dict[str, object]] = {}
    failed = 0
    total = time.perf_counter()
    for scene in crack_scenes():
        name = scene.stem
        if only and name not in only:
            continue
        sets = ["output.xdmf=false"]
        if name in CAPS:
            sets.append(f"cracking.max_events={CAPS[name]}")
        with tempfile.TemporaryDirectory(prefix=f"crackjob_{name}_") as out:
            cmd = [sys.executable, "-m", "geofrac", "run", str(scene.relative_to(ROOT))]
            cmd += [a for s in sets for a in ("--set", s)] + ["--out", out, "-q"]
            if ranks > 1:
                mpiexec = Path(sys.executable).with_name("mpiexec")
                cmd = [str(mpiexec), "-n", str(ranks), *cmd[:1], "-m", "mpi4py", *cmd[1:]]
            t0 = time.perf_counter()
            proc = subprocess.run(
                cmd, check=False, cwd=ROOT, env=env, capture_output=True, text=True
            )
            seconds = time.perf_counter() - t0
            events = Path(out) / "events.csv"
            if proc.returncode == 0 and events.is_file():
                shutil.copyfile(events, directory / f"{name}.events.csv")
                rows = sum(1 for _ in events.open()) - 1
            else:
                rows = -1
                failed += 1
                sys.stderr.write(proc.stdout[-2000:] + proc.stderr[-2000:])
        cap = f"cap {CAPS[name]}" if name in CAPS else "no cap"
        print(f"{name:24s} {cap:8s} {rows:5d} events {seconds:7.1f} s  rc {proc.returncode}")
        record[name] = {
            "command": " ".join(cmd[cmd.index("-m") :]).replace(out, "<tmp>"),
            "cap": CAPS.get(name),
            "events": rows,
            "seconds": round(seconds, 1),
            "returncode": proc.returncode,
        }
        sys.stdout.flush()
    print(f"total {time.perf_counter() - total:.1f} s")
    (directory / "runs.json").write_text(json.dumps(record, indent=1) + "\n")
    return 1 if failed else 0


def compare(a: Path, b: Path) -> int:
    """Compare the ``*.events.csv`` of two run directories; 0 if all are byte-identical."""
    names = sorted({p.name for d in (a, b) for p in d.glob("*.events.csv")})
    differ = 0
    for name in names:
        pa, pb = a / name, b / name
        scene = name.removesuffix(".events.csv")
        if not (pa.is_file() and pb.is_file()):
            print(f"{scene:24s} missing in {a if not pa.is_file() else b}")
            differ += 1
            continue
        la, lb = pa.read_bytes().splitlines(), pb.read_bytes().splitlines()
        if la == lb:
            print(f"{scene:24s} identical ({len(la) - 1} events)")
            continue
        differ += 1
        row = next((i for i, (x, y) in enumerate(zip(la, lb, strict=False)) if x != y), None)
        if row is None:
            print(f"{scene:24s} differ: {len(la) - 1} vs {len(lb) - 1} events (common rows equal)")
        else:
            print(f"{scene:24s} differ first at row {row} (header {la[0].decode()}):")
            print(f"  {a}: {la[row].decode()}")
            print(f"  {b}: {lb[row].decode()}")
    return 1 if differ else 0


def main(argv: list[str] | None = None) -> int:
    """Command line: ``run DIR`` or ``compare A B``; the exit code says whether all matched."""
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="command", required=True)
    r = sub.add_parser("run", help="run every crack scene, keep events.csv in DIR")
    r.add_argument("directory", type=Path)
    r.add_argument("--only", nargs="*", help="scene names (default: all crack scenes)")
    r.add_argument("-n", "--ranks", type=int, default=1, help="MPI ranks (default 1)")
    c = sub.add_parser("compare", help="compare the events.csv of two run directories")
    c.add_argument("a", type=Path)
    c.add_argument("b", type=Path)
    args = p.parse_args(argv)
    if args.command == "run":
        return run(args.directory, args.only, args.ranks)
    return compare(args.a, args.b)


if __name__ == "__main__":
    sys.exit(main())
