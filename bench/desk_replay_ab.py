"""The desk's GUI thread on a recorded patrol: two versions side by side.

A tape of a real patrol (``bench/desk_soak.py --record TAPE``) is played into the
full window (offscreen, built as ``station-patrol --connect`` builds it, with its
archive) by a stand-in link (bench/link_tape.py), so two versions of the desk get
the same messages at the same pace. Each run measures, after a warm-up, with the
stall profiler's ledger (bench/stall_profile.py):

- the GUI thread's own CPU per second of wall time and its run-queue wait;
- the longest GUI-thread CPU between two beats of a 20 ms timer (the longest step),
  and how many gaps between two beats held over 10 and over 15 ms of it, per minute;
- late beats (over 50 ms past their period) split into the GUI thread's own work
  (its CPU inside the gap was over 50 ms: code can fix it), not scheduled (machine
  load) and asleep (the GIL or a blocking call), per minute;
- where the GUI thread's CPU went, by innermost own-code line.

Versions are source trees (``LABEL=DIR``); each run is a process of its own with
``PYTHONPATH=DIR``, and the runs alternate (old, new, old, new, ...) so both see
the same machine load:

    QT_QPA_PLATFORM=offscreen .venv/bin/python bench/desk_replay_ab.py \\
        --tape /tmp/patrol.tape --trees old=/tmp/desk-base,new=. --rounds 2 --seconds 150

One run by itself (what the above starts): ``--play TAPE --seconds S``.
"""

from __future__ import annotations

import argparse
import json
import os
import shlex
import statistics
import subprocess
import sys
import time
from pathlib import Path

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

FIGURES = (("cpu_ms_per_s", "GUI CPU ms/s"), ("wait_ms_per_s", "run-queue wait ms/s"),
           ("longest_cpu_ms", "longest CPU step ms"),
           ("steps10_per_min", "steps over 10 ms /min"),
           ("steps15_per_min", "steps over 15 ms /min"),
           ("own_per_min", "own-work stalls/min"),
           ("load_per_min", "load stalls/min"), ("blocked_per_min", "asleep stalls/min"),
           ("own_max_ms", "own-work stall: most CPU ms"),
           ("own_gc_per_min", "own stalls in a GC /min"), ("gc2_per_min", "full GCs/min"),
           ("gc2_max_ms", "full GC: longest ms"), ("gc_max_ms", "any GC: longest ms"),
           ("objs_gen2", "objects in gen2 at end"), ("full_gc_ms", "a full GC at end, ms"),
           # with --events only: each event the loop delivered, its CPU (a slice)
           ("event_max_ms", "longest event ms"), ("event_p999_ms", "event p99.9 ms"),
           ("events5_per_min", "events over 5 ms /min"),
           ("events10_per_min", "events over 10 ms /min"))


def _event_profiler_app():
    """A QApplication that puts the GUI thread's CPU time (``time.thread_time``) on
    each event it delivers, by event type and receiver (its class, and its object
    name when it has one; a QTimer by its parent's class and its interval), exclusive
    of the events delivered inside it (a window's paint sends its children's). It
    costs a few microseconds an event: for finding where the time goes, not for the
    figures."""
    import collections

    from PySide6.QtCore import QTimer
    from PySide6.QtWidgets import QApplication

    class ProfilingApp(QApplication):
        def __init__(self, argv) -> None:
            super().__init__(argv)
            self.spent: collections.Counter[str] = collections.Counter()
            self.count: collections.Counter[str] = collections.Counter()
            self.longest: collections.Counter[str] = collections.Counter()  # inclusive
            self._child = [0]
            self.on = False
            self.top_ns: list[int] = []  # each event the event loop delivered (not
            # one sent inside another's handling): its CPU, inclusive - a slice

        def notify(self, receiver, event):  # noqa: D401 - Qt's name
            if not self.on:
                return super().notify(receiver, event)
            t0 = time.thread_time_ns()
            self._child.append(0)
            try:
                return super().notify(receiver, event)
            finally:
                dt = time.thread_time_ns() - t0
                inner = self._child.pop()
                if len(self._child) == 1:
                    self.top_ns.append(dt)
                self._child[-1] += dt
                try:
                    name = receiver.objectName()
                    key = f"{event.type().name} -> {type(receiver).__name__}" + (
                        f" '{name}'" if name else "")
                    if isinstance(receiver, QTimer):  # whose timer: its parent, interval
                        parent = receiver.parent()
                        key += (f" of {type(parent).__name__ if parent else '-'}"
                                f" {receiver.interval()} ms")
                except RuntimeError:  # deleted meanwhile
                    key = "(deleted receiver)"
                self.spent[key] += dt - inner
                self.count[key] += 1
                self.longest[key] = max(self.longest[key], dt)

        def report(self, wall_s: float, top: int = 30) -> str:
            lines = [f"GUI thread CPU by event delivered (exclusive, over {wall_s:.0f} s; "
                     "the longest one inclusive of the events delivered inside it):"]
            for key, ns in self.spent.most_common(top):
                lines.append(f"  {ns / 1e6 / wall_s:7.2f} ms/s  {self.count[key] / wall_s:7.1f}/s"
                             f"  longest {self.longest[key] / 1e6:6.1f} ms  {key}")
            return "\n".join(lines)

    return ProfilingApp


def play(tape_path: str, seconds: float, warmup: float, events: bool = False,
         profile: bool = False, threshold_ms: float = 50.0) -> int:
    from PySide6.QtCore import QTimer

    from bench.isolated_desk import open_desk
    from bench.stall_profile import StallSampler

    app, link, win = open_desk(tape_path, "desk-replay-",
                               _event_profiler_app() if events else None)
    link.start()
    # no event filter: less overhead
    sampler = StallSampler(events=False, threshold_ms=threshold_ms).start()
    import cProfile

    prof = cProfile.Profile() if profile else None

    def measure() -> None:
        sampler.reset()
        if prof is not None:
            prof.enable()
        if events:
            app.on = True

    heap: dict[str, float] = {}

    def probe_heap() -> None:
        """What a full collection would walk now, and how long one takes (on the
        GUI thread, as the desk's collector runs it)."""
        import gc

        sampler.stop()  # the figures end here: the collection below is not the desk's
        heap["t_end"] = time.perf_counter()
        heap.update({f"objs_gen{g}": len(gc.get_objects(g)) for g in range(3)})
        heap["frozen"] = gc.get_freeze_count()
        t0, c0 = time.perf_counter(), time.thread_time()
        heap["full_freed"] = gc.collect()
        heap["full_gc_ms"] = 1000 * (time.perf_counter() - t0)
        heap["full_gc_cpu_ms"] = 1000 * (time.thread_time() - c0)
        win.close()

    QTimer.singleShot(int(warmup * 1000), measure)
    QTimer.singleShot(int((warmup + seconds) * 1000), probe_heap)
    app.exec()
    sampler.stop()
    led = sampler.ledger
    wall = max(heap.pop("t_end", time.perf_counter()) - led.t0, 1e-9)
    if prof is not None:
        import pstats

        prof.disable()
        st = pstats.Stats(prof)
        st.sort_stats("tottime").print_stats(25)
        st.sort_stats("cumtime").print_stats(40)
    print(sampler.report())
    if events:
        app.on = False
        print(app.report(wall))
    print(f"tape: {link.emitted} messages played, {link.rounds} rounds of {link.length_s:.0f} s")
    mins = wall / 60
    out = {"wall_s": wall, "cpu_ms_per_s": 1000 * led.cpu_s / wall,
           "wait_ms_per_s": 1000 * led.wait_s / wall,
           "longest_cpu_ms": 1000 * led.longest_cpu_s,
           "steps10_per_min": led.steps_over[10] / mins,
           "steps15_per_min": led.steps_over[15] / mins,
           "own_per_min": led.late["own"] / mins, "load_per_min": led.late["load"] / mins,
           "blocked_per_min": led.late["blocked"] / mins,
           "own_max_ms": 1000 * led.late_cpu_max_s["own"],
           "own_gc_per_min": sampler.own_gc / mins, "gc2_per_min": sampler.gc_count[2] / mins,
           "gc2_max_ms": 1000 * sampler.gc_max_s[2], "gc_max_ms": 1000 * max(sampler.gc_max_s)}
    out.update(heap)
    if events:
        top = sorted(app.top_ns)
        out.update({"event_max_ms": top[-1] / 1e6 if top else 0.0,
                    "event_p999_ms": top[int(0.999 * len(top))] / 1e6 if top else 0.0,
                    "events5_per_min": sum(ns > 5e6 for ns in top) / mins,
                    "events10_per_min": sum(ns > 10e6 for ns in top) / mins})
    print("heap at the end: " + ", ".join(f"{k} {v:.0f}" for k, v in heap.items()))
    print("FIGURES " + json.dumps(out), flush=True)
    win.desk.close()
    return 0


def compare(args) -> int:
    trees = dict(t.split("=", 1) for t in args.trees.split(","))
    got: dict[str, list[dict]] = {k: [] for k in trees}
    for r in range(args.rounds):
        for label, tree in trees.items():
            tree = str(Path(tree).resolve())
            cmd = [sys.executable, f"{tree}/bench/desk_replay_ab.py", "--play", args.tape,
                   "--seconds", str(args.seconds), "--warmup", str(args.warmup),
                   *(["--events"] if args.events else [])]
            env = dict(os.environ, PYTHONPATH=tree, QT_QPA_PLATFORM="offscreen")
            load = "/".join(f"{v:.1f}" for v in os.getloadavg())
            print(f"== round {r} {label} (load {load}): PYTHONPATH={tree} "
                  f"{shlex.join(cmd)}", flush=True)
            res = subprocess.run(["nice", "-n", "5", *cmd], env=env, cwd=tree,
                                 capture_output=True, text=True)
            line = next((ln for ln in res.stdout.splitlines() if ln.startswith("FIGURES ")), None)
            if args.verbose or line is None:
                print(res.stdout, res.stderr[-3000:], sep="\n")
            if line is None:
                print(f"round {r} {label}: no figures (exit {res.returncode})")
                continue
            figs = json.loads(line[len("FIGURES "):])
            got[label].append(figs)
            print("   " + ", ".join(f"{name} {figs[key]:.2f}" for key, name in FIGURES
                                    if key in figs),
                  flush=True)
    print(f"\n== medians of {args.rounds} rounds, {args.seconds:g} s measured each ==")
    print(f"{'':24}" + "".join(f"{label:>12}" for label in trees))
    for key, name in FIGURES:
        if not any(key in f for runs in got.values() for f in runs):
            continue
        cells = [f"{statistics.median(f.get(key, float('nan')) for f in got[label]):12.2f}"
                 if got[label]
                 else f"{'n/a':>12}" for label in trees]
        print(f"{name:24}" + "".join(cells))
    return 0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--tape", help="the tape to play (bench/desk_soak.py --record)")
    ap.add_argument("--trees", default="", help="LABEL=DIR,LABEL=DIR: versions compared")
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--seconds", type=float, default=150.0, help="measured, per run")
    ap.add_argument("--warmup", type=float, default=20.0)
    ap.add_argument("--play", metavar="TAPE", help="one run (what --trees starts)")
    ap.add_argument("--events", action="store_true",
                    help="also time each Qt event delivered (slows the desk): CPU by "
                         "event, and the longest events (the GUI thread's slices)")
    ap.add_argument("--cprofile", action="store_true",
                    help="with --play: also profile the Python side (slows the desk)")
    ap.add_argument("--threshold-ms", type=float, default=50.0,
                    help="with --play: a beat this late is late (lower: see the longest "
                         "steps' lines even when none is over 50 ms)")
    ap.add_argument("-v", "--verbose", action="store_true", help="print each run's report")
    args = ap.parse_args(argv)
    if args.play:
        return play(args.play, args.seconds, args.warmup, args.events, args.cprofile,
                    args.threshold_ms)
    if not (args.tape and args.trees):
        ap.error("--tape and --trees, or --play")
    return compare(args)


if __name__ == "__main__":
    sys.exit(main())
