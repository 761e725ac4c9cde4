"""CPU per plan of best_plan, this tree against an older commit, interleaved.

    PYTHONPATH=$PWD python bench/coverage_cpu.py --ref 3193cc0 --family crowded --seeds 0-4
    PYTHONPATH=$PWD python bench/coverage_cpu.py --ref main --family scattered --size 60 --seeds 0-2

The older commit's coverage package is unpacked (``git archive``) into a
temporary directory and imported beside this tree's, so both run in the
same process on the same maps: the order alternates each round, CPU is
time.process_time (the machine is shared; wall time means little), and
each map's plans are compared (turns, U-turns, repetition, coverage, and
whether the cell lists are identical). Use tuning seeds (0–4, 100–109 and
200–209) while choosing; the held-out seeds 300–309 (bench/coverage_maps.py)
only once, at the end of a change. ``--family scattered``: the tests' random
grids (tests/planner/conftest.py ``random_grid``: ``--size`` square, a
``--density`` of the cells blocked at random; seed s draws the grid and then
the start from ``numpy.random.default_rng(s)``), maps cut into thousands of
lanes of one or two cells. "rep" is (visits − distinct) / reachable
(Definition 7). ``--family movingai --map NAME``: a Moving AI map
(/work/shared/movingai, its README), from its first free cell in row-major
order (``--seeds`` ignored).
"""

from __future__ import annotations

import argparse
import importlib
import subprocess
import sys
import tarfile
import tempfile
import time
from io import BytesIO
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from app.core.planner import coverage as new  # noqa: E402
from app.core.planner.coverage import figures  # noqa: E402
from bench.coverage_bench import u_turns  # noqa: E402
from bench.coverage_maps import crowded, full_wall, paper_like, start_cell  # noqa: E402

PKG = "app/core/planner/coverage"
FAMILIES = {
    "paper": paper_like,
    "crowded": crowded,
    "full": lambda _seed: full_wall(),
    "scattered": None,
    "movingai": None,
}
MOVINGAI = Path("/work/shared/movingai/maps")


def scattered(seed: int, size: int, density: float) -> tuple[np.ndarray, tuple[int, int]]:
    """The tests' random grid of ``seed`` and its start (a random free cell)."""
    from tests.planner.conftest import free_cell, random_grid

    rng = np.random.default_rng(seed)
    blocked = random_grid(rng, size, size, density)
    return blocked, free_cell(rng, blocked)


def old_package(ref: str, into: Path):
    """The coverage package as of ``ref``, importable as ``coverage_old``."""
    tar = subprocess.run(
        ["git", "archive", ref, PKG], cwd=ROOT, check=True, capture_output=True
    ).stdout
    with tarfile.open(fileobj=BytesIO(tar)) as t:
        t.extractall(into, filter="data")
    (into / PKG).rename(into / "coverage_old")
    sys.path.insert(0, str(into))
    return importlib.import_module("coverage_old")


def seeds_arg(text: str) -> list[int]:
    lo, _, hi = text.partition("-")
    return list(range(int(lo), int(hi or lo) + 1))


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ref", required=True, help="the older commit (e.g. 3193cc0)")
    ap.add_argument("--family", choices=sorted(FAMILIES), default="crowded")
    ap.add_argument("--seeds", type=seeds_arg, default=seeds_arg("0-4"), help="e.g. 0-4")
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--size", type=int, default=40, help="scattered: rows = columns")
    ap.add_argument("--density", type=float, default=0.2, help="scattered: blocked share")
    ap.add_argument("--map", default="32room_000", help="movingai: the map's name")
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        old = old_package(args.ref, Path(tmp))
        if args.family == "scattered":
            made = [scattered(s, args.size, args.density) for s in args.seeds]
            maps, starts = [m for m, _ in made], [st for _, st in made]
            warm = scattered(10_000, 30, args.density)
        elif args.family == "movingai":
            from app.core.planner.grid import load_movingai_map

            b = np.asarray(load_movingai_map(MOVINGAI / f"{args.map}.map").blocked, dtype=bool)
            r, c = np.argwhere(~b)[0]
            args.seeds, maps, starts = [0], [b], [(int(r), int(c))]
            warm = scattered(10_000, 30, 0.2)
        else:
            maps = [FAMILIES[args.family](s) for s in args.seeds]
            starts = [start_cell(b) for b in maps]
            warm = (maps[0], starts[0])
        for mod in (old, new):  # compile both before timing
            mod.best_plan(*warm)
        cpu = {"old": [], "new": []}
        for rnd in range(args.rounds):
            pair = [("old", old), ("new", new)]
            for seed, b, st in zip(args.seeds, maps, starts, strict=True):
                cells = {}
                for name, mod in pair if rnd % 2 == 0 else pair[::-1]:
                    t0 = time.process_time()
                    cells[name] = mod.best_plan(b, st).cells
                    cpu[name].append(time.process_time() - t0)
                if rnd == 0:
                    row = []
                    for name in ("old", "new"):
                        f = figures(b, st, cells[name])
                        row.append(
                            f"{name} turns {f.turns} U {u_turns(cells[name]):.1f} "
                            f"rep {f.repetition:.2%} cov {f.coverage:.0%} cpu {cpu[name][-1]:.2f}"
                        )
                    same = cells["old"] == cells["new"]
                    print(f"{args.family} {seed}: {' | '.join(row)} identical={same}", flush=True)
        o, n = np.mean(cpu["old"]), np.mean(cpu["new"])
        print(
            f"{args.family}: CPU s/plan old {o:.3f} (max {max(cpu['old']):.3f}) "
            f"new {n:.3f} (max {max(cpu['new']):.3f}), ratio {n / o:.2f}"
        )


if __name__ == "__main__":
    main()
