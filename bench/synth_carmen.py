"""Synthetic CARMEN logs drawn from other maps, and the laser SLAM measured on
them (issue 13): how the method, developed on two real logs, generalises to
geometries it was never tuned on.

    PYTHONPATH=$PWD python bench/synth_carmen.py                # development logs
    PYTHONPATH=$PWD python bench/synth_carmen.py --held-out     # the held-out logs
    PYTHONPATH=$PWD python bench/synth_carmen.py --logs den-north --draws 0 --write-only

Each log is a tour through a 2-D map (bench/synth_world.py: the map's cells
made into smooth walls, waypoints visited in one order and then back in the
other, so every place is passed at least twice and the tour ends where it
began), sampled as the thinned real logs are (a scan per metre of travel,
±15 %, or per ``turn_max_deg`` of turn), ray-cast with a 180° lidar (the
beam count and no-return value of the log's kind; range noise σ 1 cm, ranges
written to the centimetre, a share of beams dropped to the no-return value),
with raw-like odometry from bench/localisation_bench.py's error model
(app.core.localisation.evaluate.drifting_odometry: scale, turn gain, drift
per metre, noise; × the log's factor), written in a frame of its own (raw
odometry starts anywhere), ODOM lines between the scans, and timestamps
that are regular, all zero, repeated or wrapping. Beam i of n lies at
−90° + i·step, step 180°/(n − 1) for an odd count and 180°/n for an even one,
as app/core/localisation/carmen.py reads them.

The command line (``python -m app.core.localisation carmen LOG --out POSES``)
is run in this process on each log; its poses are scored against the drawn
reference: ATE after rigid alignment, RPE over 1 m and 10 m of path
(evaluate.py), and the CPU it took (time.process_time, the whole command:
reading, every mapping step and the final pass) per scan. A traceback of the
command is a bug and is printed as such. For each log the worst stretches
(RPE 10 m per start scan) are printed with the kind of place they pass:
"open" (over 40 % of the true beams return nothing within 30 m), "corridor"
(the true scan's wall normals hold one direction under a tenth of the
other: the matching is degenerate along the corridor), else "room".

THE SPLIT, fixed before any log was made or run:
- development (the generator was built and checked on these; the mapper's
  figures on them are development figures, no SLAM parameter was changed
  for them): ``den-north`` (den520d's northern half, 0.2 m cells) and
  ``station`` (the simulator's station yard, 0.1 m cells; the method was
  already developed on the simulator).
- held out (run once, reported apart; ``--held-out`` is needed to make
  them): ``den-south`` (den520d's southern half), ``rooms`` (32room_000,
  7 × 7 rooms of 4.8 m, the one-cell doors widened to 0.9 m), ``maze``
  (maze-400-4, 1.2 m corridors) and ``crates`` (random512-20-0 at 0.5 m: a
  hall of crates, 20 % of the floor).
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse  # noqa: E402
import contextlib  # noqa: E402
import io  # noqa: E402
import math  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
import traceback  # noqa: E402
from dataclasses import dataclass, field, replace  # noqa: E402
from pathlib import Path  # noqa: E402
from unittest import mock  # noqa: E402

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from app.core.localisation.__main__ import main as cli_main  # noqa: E402
from app.core.localisation.evaluate import (  # noqa: E402
    OdometryErrors,
    drifting_odometry,
)
from app.core.localisation.mapping import LaserMapper  # noqa: E402
from app.core.localisation.se2 import compose, relative  # noqa: E402
from app.core.planner.grid import load_movingai_map  # noqa: E402
from bench.synth_scoring import diagnose, place_kinds, score, step_errors  # noqa: E402
from bench.synth_world import (  # noqa: E402
    World,
    dense_poses,
    sample_scans,
    tour,
    widen_doors,
    world_from_blocked,
)

MOVINGAI = ROOT.parent / "shared" / "movingai" / "maps"


@dataclass(frozen=True)
class LogSpec:
    name: str
    held_out: bool
    source: str  # a Moving AI map's name, or "station"
    crop: tuple[int, int, int, int] | None  # rows r0:r1, columns c0:c1 of the map
    cell_m: float
    clearance_m: float  # the robot keeps this far from every wall
    beams: int  # 180, 181, 360 or 361 over 180°
    no_return_m: float  # the value a beam without a return reads
    sensor_max_m: float  # beyond this the laser returns nothing
    odo_factor: float = 1.0  # odometry errors × this (localisation_bench's factor)
    timestamps: str = "regular"  # regular | zero | repeat | wrap
    doors_cells: int = 0  # widen one-cell doors to this many cells
    length_m: float = 280.0
    waypoints: int = 10
    turn_max_deg: float = 80.0
    dropout: float = 0.015  # share of beams read as no return (dark or glossy surfaces)
    fov_param: bool = True  # write PARAM laser_front_laser_fov 180
    seed: int = 0


SPECS = [
    # development
    LogSpec("den-north", False, "den520d", (0, 128, 0, 256), 0.2, 0.5, 361, 81.9, 80.0,
            timestamps="regular", seed=11),
    LogSpec("station", False, "station", None, 0.1, 0.8, 180, 32.8, 32.0,
            timestamps="repeat", waypoints=9, fov_param=False, seed=12),
    # held out: made and run once, at the end, reported apart
    LogSpec("den-south", True, "den520d", (128, 257, 0, 256), 0.2, 0.5, 181, 50.0, 49.0,
            odo_factor=1.25, timestamps="wrap", seed=21),
    LogSpec("rooms", True, "32room_000", (0, 225, 0, 225), 0.15, 0.35, 360, 81.9, 80.0,
            timestamps="zero", doors_cells=6, waypoints=12, seed=22),
    LogSpec("maze", True, "maze-400-4", (0, 161, 0, 161), 0.3, 0.45, 180, 32.8, 32.0,
            timestamps="regular", seed=23),
    LogSpec("crates", True, "random512-20-0", (0, 101, 0, 101), 0.5, 0.3, 361, 51.2, 50.0,
            timestamps="repeat", fov_param=False, seed=24),
]


def beam_angles(n: int, fov: float = math.pi, convention: str = "reader") -> np.ndarray:
    """Bearings of n beams from −fov/2: an odd count spans the field ends
    included, an even one steps fov/n ("reader", carmen.py's reading);
    "span": every count ends included (fov/(n − 1))."""
    step = fov / (n - 1) if (n % 2 or convention == "span") else fov / n
    return -fov / 2 + np.arange(n) * step


def make_world(spec: LogSpec) -> World:
    if spec.source == "station":
        from sim_robot.world import World as Station
        occ, res, _ = Station(seed=0).occupancy_grid()  # row 0 at y = 0 already
        return world_from_blocked(occ, res, flip=False)
    blocked = load_movingai_map(MOVINGAI / f"{spec.source}.map").blocked
    if spec.crop is not None:
        r0, r1, c0, c1 = spec.crop
        blocked = blocked[r0:r1, c0:c1]
    if spec.doors_cells:
        blocked = widen_doors(blocked, spec.doors_cells)
    return world_from_blocked(blocked, spec.cell_m)


@dataclass
class Drawn:
    """A drawn log before its odometry: the reference poses and the ranges
    (inf: nothing within the sensor's range; dropouts not yet applied)."""

    ref: np.ndarray
    ranges: np.ndarray
    angles: np.ndarray
    true_ranges: np.ndarray


def draw(spec: LogSpec, world: World | None = None, convention: str = "reader") -> Drawn:
    world = world or make_world(spec)
    path = tour(world, spec.clearance_m, spec.length_m, spec.waypoints, spec.seed)
    ref = sample_scans(dense_poses(path), 1.0, spec.turn_max_deg, spec.seed + 1)
    return draw_at(world, ref, spec.beams, spec.sensor_max_m, spec.seed + 2, convention)


def draw_at(world: World, ref: np.ndarray, beams: int, sensor_max_m: float, seed: int,
            convention: str = "reader") -> Drawn:
    """Ray-cast scans at the reference poses: σ 1 cm range noise."""
    rng = np.random.default_rng(seed)
    angles = beam_angles(beams, convention=convention)
    true = np.array([world.cast(p, angles, sensor_max_m) for p in ref])
    noisy = true + rng.normal(0.0, 0.01, true.shape)
    return Drawn(ref, noisy, angles, true)


def write_log(path: Path, spec: LogSpec, drawn: Drawn, odo: np.ndarray, seed: int,
              decimals: int = 2) -> None:
    """The CARMEN log: PARAM lines, ODOM lines between the scans and one
    FLASER line per scan (its pose fields and odometry fields both the raw
    odometry, as in a raw log)."""
    rng = np.random.default_rng(seed)
    start = np.array([rng.uniform(-500, 500), rng.uniform(-500, 500), rng.uniform(-3, 3)])
    o = np.array([compose(start, relative(odo[0], p)) for p in odo])
    r = drawn.ranges.copy()
    r[~np.isfinite(r)] = spec.no_return_m
    r[rng.random(r.shape) < spec.dropout] = spec.no_return_m
    r = np.clip(r, 0.0, spec.no_return_m)
    ts = timestamps(drawn.ref, spec.timestamps, rng)
    lines = ["# synthetic CARMEN log (bench/synth_carmen.py): drawn, not recorded",
             "# message formats defined: PARAM SYNC ODOM FLASER",
             f"PARAM robot_front_laser_max {spec.no_return_m:g} nohost 0",
             "PARAM robot_frontlaser_offset 0.0 nohost 0"]
    if spec.fov_param:
        lines.append("PARAM laser_front_laser_fov 180 nohost 0")
    fmt = f"{{:.{decimals}f}}"
    for k in range(len(o)):
        if k:
            for f in (1 / 3, 2 / 3):  # odometry between the scans
                p = compose(o[k - 1], relative(o[k - 1], o[k]) * f)
                t = ts[k - 1] + f * (ts[k] - ts[k - 1])
                lines.append(f"ODOM {p[0]:.6f} {p[1]:.6f} {p[2]:.6f} 0.4 0 0 {t:.6f} synth "
                             f"{t:.6f}")
        pose = f"{o[k, 0]:.6f} {o[k, 1]:.6f} {o[k, 2]:.6f}"
        lines.append(f"FLASER {r.shape[1]} " + " ".join(fmt.format(v) for v in r[k])
                     + f" {pose} {pose} {ts[k]:.6f} synth {ts[k]:.6f}")
    path.write_text("\n".join(lines) + "\n", encoding="ascii")


def timestamps(ref: np.ndarray, mode: str, rng: np.random.Generator) -> np.ndarray:
    """Times at 0.4 m/s and 0.35 rad/s: "regular", "zero" (all 0), "repeat"
    (a fifth of the scans repeat the last one's time) or "wrap" (wrapping at
    3600 s, the log starting just before it)."""
    d = np.hypot(*np.diff(ref[:, :2], axis=0).T)
    dth = np.abs(np.diff(np.unwrap(ref[:, 2])))
    t = np.r_[0.0, np.cumsum(d / 0.4 + dth / 0.35)] + 1.6e9
    if mode == "zero":
        return np.zeros_like(t)
    if mode == "repeat":
        rep = np.r_[False, rng.random(len(t) - 1) < 0.2]
        for k in np.where(rep)[0]:
            t[k] = t[k - 1]
        return t
    if mode == "wrap":
        return np.mod(t - 1.6e9 + 3550.0, 3600.0)
    return t


def odometry_errors(factor: float) -> OdometryErrors:
    """localisation_bench's odometry errors, each × ``factor``."""
    e = OdometryErrors()
    return OdometryErrors(e.scale_sigma * factor, e.yaw_gain_sigma * factor,
                          e.yaw_drift_sigma_rad_per_m * factor, e.trans_noise_m * factor,
                          e.yaw_noise_rad * factor)


@dataclass
class Cpu:
    """CPU seconds of one run of the command: all of it, each mapping step,
    and the once-per-log finish (final solve, final pass, ties)."""

    total: float = 0.0
    steps: list[float] = field(default_factory=list)
    finish: float = 0.0
    online: list[np.ndarray] = field(default_factory=list)  # each step's estimate, as made


def run_cli(log_path: Path, out_path: Path) -> tuple[np.ndarray | None, Cpu, str]:
    """The command line in this process: poses (None on a failure), its CPU,
    and what it wrote to standard error (or the traceback). The mapper's
    steps and finish are timed through wrappers round LaserMapper's methods."""
    cpu = Cpu()
    add, fin = LaserMapper.add_scan, LaserMapper.finish

    def timed_add(self, *a, **k):
        t = time.process_time()
        pose = add(self, *a, **k)
        cpu.steps.append(time.process_time() - t)
        cpu.online.append(np.array(pose, float))
        return pose

    def timed_finish(self, *a, **k):
        t = time.process_time()
        try:
            return fin(self, *a, **k)
        finally:
            cpu.finish += time.process_time() - t

    err = io.StringIO()
    t0 = time.process_time()
    try:
        with contextlib.redirect_stderr(err), \
                mock.patch.object(LaserMapper, "add_scan", timed_add), \
                mock.patch.object(LaserMapper, "finish", timed_finish):
            rc = cli_main(["carmen", str(log_path), "--out", str(out_path)])
    except Exception:  # a traceback of the command is a bug: reported, not raised
        cpu.total = time.process_time() - t0
        return None, cpu, "TRACEBACK\n" + traceback.format_exc()
    cpu.total = time.process_time() - t0
    if rc != 0:
        return None, cpu, f"exit {rc}: {err.getvalue().strip()}"
    est = np.loadtxt(out_path, ndmin=2)[:, 1:4]
    return est, cpu, err.getvalue().strip().splitlines()[-1]


def warm_up(out_dir: Path) -> None:
    """Run the command once on a small drawn room, so that loading the
    compiled kernels (once per process) is not timed."""
    b = np.zeros((40, 60), bool)
    b[15:25, 15:45] = True
    b[5:8, 50:53] = True
    world = world_from_blocked(b, 0.2)
    ref = np.array([[2.0 + 0.8 * k, 2.0, 0.0] for k in range(10)])
    drawn = draw_at(world, ref, 180, 30.0, 0)
    spec = LogSpec("warm-up", False, "room", None, 0.2, 0.4, 180, 81.9, 30.0)
    write_log(out_dir / "warm-up.log", spec, drawn, ref, 0)
    run_cli(out_dir / "warm-up.log", out_dir / "warm-up.poses.tsv")


def fmt_row(name: str, s, cpu: Cpu | None = None, scans: int = 1) -> str:
    if cpu is None:
        tail = " |"
    else:
        st = 1000 * np.array(cpu.steps or [0.0])
        tail = (f" | {1000 * cpu.total / scans:6.1f} | {st.mean():5.1f} "
                f"[{np.percentile(st, 95):5.1f}] {st.max():4.0f} | {cpu.finish:5.1f}")
    return (f"  {name:<22} | {s[0]:6.3f} | {s[1]:5.1f} / {s[2]:4.2f} | "
            f"{s[3]:5.1f} / {s[4]:4.2f}" + tail)


def run_spec(spec: LogSpec, draws: list[int], out_dir: Path, write_only: bool,
             convention: str) -> list[tuple]:
    t0 = time.process_time()
    world = make_world(spec)
    drawn = draw(spec, world, convention)
    make_s = time.process_time() - t0
    ref = np.array([relative(drawn.ref[0], p) for p in drawn.ref])
    path_m = float(np.sum(np.hypot(*np.diff(ref[:, :2], axis=0).T)))
    turns = np.degrees(np.abs(np.diff(np.unwrap(ref[:, 2]))))
    steps = np.hypot(*np.diff(ref[:, :2], axis=0).T)
    kinds, ratios = place_kinds(drawn.true_ranges, drawn.angles)
    w, h = world.size_m
    print(f"\n{spec.name} ({'HELD OUT' if spec.held_out else 'development'}; {spec.source}, "
          f"{w:.0f} x {h:.0f} m, {spec.cell_m} m cells): {len(ref)} scans, {path_m:.0f} m, "
          f"steps median {np.median(steps):.2f} m, turns max {turns.max():.0f} deg; "
          f"{spec.beams} beams, no return {spec.no_return_m:g} m, timestamps "
          f"{spec.timestamps}, odometry errors x{spec.odo_factor:g}; places: "
          + ", ".join(f"{k} {kinds.count(k)}" for k in ("corridor", "room", "open"))
          + f"; drawn in {make_s:.1f} s CPU")
    print(f"  {'method (draw)':<22} | {'ATE m':>6} | RPE 1 m cm/deg | RPE 10 m cm/deg | "
          "ms/scan all | step mean [p95] max ms | finish s")
    rows = []
    for d in draws:
        odo = drifting_odometry(ref, 1000 * spec.seed + d, odometry_errors(spec.odo_factor))
        log_path = out_dir / f"{spec.name}-d{d}.log"
        write_log(log_path, spec, drawn, odo, seed=spec.seed * 100 + d)
        np.savetxt(out_dir / f"{spec.name}-d{d}.ref.tsv", ref, fmt="%.5f", delimiter="\t")
        s_odo = score(odo, ref)
        print(fmt_row(f"odometry ({d})", s_odo))
        if write_only:
            continue
        est, cpu, msg = run_cli(log_path, out_dir / f"{spec.name}-d{d}.poses.tsv")
        if est is None:
            print(f"  full method ({d}): FAILED: {msg}")
            rows.append((spec.name, d, s_odo, None, cpu))
            continue
        s = score(est, ref)
        print(fmt_row(f"full method ({d})", s, cpu, len(ref)))
        print(f"      [{msg}]")
        diagnose(est, ref, kinds, ratios)
        if len(cpu.online) == len(ref):
            step_errors(np.array(cpu.online), odo, ref, kinds)
        rows.append((spec.name, d, s_odo, s, cpu))
    return rows


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--logs", default="", help="comma-separated log names (default: the "
                    "development logs, or the held-out ones with --held-out)")
    ap.add_argument("--held-out", action="store_true", help="make and run the held-out logs")
    ap.add_argument("--draws", default="0,1,2", help="odometry draws per log")
    ap.add_argument("--out", default="/tmp/synth_carmen", help="folder for the logs and poses")
    ap.add_argument("--write-only", action="store_true", help="make the logs, run nothing")
    ap.add_argument("--beams", type=int, default=0,
                    help="draw every log with this many beams instead of its own (a "
                    "diagnosis: is a failure the beam count's or the place's?)")
    ap.add_argument("--angles", choices=["reader", "span"], default="reader",
                    help="beam spacing drawn: carmen.py's reading, or ends included for "
                    "every count (a sensitivity check)")
    args = ap.parse_args(argv)
    names = [n for n in args.logs.split(",") if n]
    specs = [s for s in SPECS if (s.name in names if names else s.held_out == args.held_out)]
    if any(s.held_out for s in specs) and not args.held_out:
        print("held-out logs are made only with --held-out", file=sys.stderr)
        return 2
    out_dir = Path(args.out)
    out_dir.mkdir(parents=True, exist_ok=True)
    draws = [int(d) for d in args.draws.split(",")]
    if not args.write_only:
        warm_up(out_dir)
    print("goals: ATE <= 0.25 m; RPE 10 m <= 10 cm / 0.8 deg; RPE 1 m <= 4 cm / 0.45 deg")
    rows = []
    for spec in specs:
        if args.beams:
            spec = replace(spec, beams=args.beams)
        rows += run_spec(spec, draws, out_dir, args.write_only, args.angles)
    done = [r for r in rows if r[3] is not None]
    if done:
        a = np.array([r[3] for r in done])
        print(f"\nfull method over {len(done)} runs: ATE mean {a[:, 0].mean():.3f} m "
              f"[worst {a[:, 0].max():.3f}], RPE 1 m {a[:, 1].mean():.1f} cm / "
              f"{a[:, 2].mean():.2f} deg, RPE 10 m {a[:, 3].mean():.1f} cm / "
              f"{a[:, 4].mean():.2f} deg; {len(rows) - len(done)} failed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
