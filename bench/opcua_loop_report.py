"""The OPC UA benches' account of the server loop's stalls (see
app/interop/opcua/loop_probe.py), measured in the server's process and asked for over
its pipe: the longest stall and what filled its window (the loop thread's CPU, the
server process's other threads, garbage collection, the process not running at all),
the longest callbacks, and two bare asyncio loops watched beside the server for the
same time as controls: one in a thread of the bench's (the desk's) process, one in a
process of its own (only the operating system can stall it).
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import subprocess
import sys
import threading
from pathlib import Path
from typing import Any

from app.interop.opcua.loop_probe import CallbackProbe, GcProbe, StallWatch

ROOT = Path(__file__).resolve().parent.parent


def add_arguments(ap: argparse.ArgumentParser) -> None:
    """The options both OPC UA benches have for the server's loop."""
    ap.add_argument("--probe", action="store_true",
                    help="time every callback of the server's loop (wall and CPU)")
    ap.add_argument("--no-gc-freeze", action="store_true",
                    help="the server does not freeze its start-up objects out of the GC")
    ap.add_argument("--no-browse-cache", action="store_true",
                    help="the server browses as asyncua does (no kept reference subtypes)")
    ap.add_argument("--no-fast-path", action="store_true",
                    help="the server writes and sends values as asyncua does "
                         "(app/interop/opcua/fast_path.py not installed)")


def server_options(args: argparse.Namespace) -> dict:
    return {"gc_freeze": not args.no_gc_freeze, "cache_browsing": not args.no_browse_cache,
            "fast_path": not args.no_fast_path}


class LoopWatch:
    """From its making to :meth:`stop`: the server loop's stalls, its process's
    collections, the loop's callbacks (``probe``) and the two control loops."""

    def __init__(self, server: Any, seconds: float, probe: bool) -> None:
        self.server = server
        server.query("watch", probe=probe)
        self.controls = Controls(seconds)

    def stop(self, wall_s: float) -> list[str]:
        """Stop watching (the controls end on their own); the report's lines."""
        seen, gcp, probe, full = self.server.query("watched")
        return loop_report(seen, gcp, probe, wall_s, self.controls.results(), full)


def bare_loop(seconds: float) -> StallWatch:
    """Watch the stalls of an asyncio loop that does nothing else, for ``seconds``."""
    async def run() -> StallWatch:
        w = StallWatch()
        task = asyncio.create_task(w.run())
        await asyncio.sleep(seconds)
        task.cancel()
        return w
    return asyncio.run(run())


class Controls:
    """Two bare asyncio loops watched beside the server for the same time: one in a
    thread of this process (it shares the GIL with the server, the client and the
    desk), one in a process of its own (only the operating system can stall it)."""

    def __init__(self, seconds: float) -> None:
        self.thread_w: StallWatch | None = None
        self.proc = subprocess.Popen(  # this file, as a script: its own loop
            [sys.executable, __file__, str(seconds)],
            stdout=subprocess.PIPE, text=True, env=os.environ | {"PYTHONPATH": str(ROOT)})
        self.th = threading.Thread(target=self._thread, args=(seconds,), daemon=True)
        self.th.start()

    def _thread(self, seconds: float) -> None:
        self.thread_w = bare_loop(seconds)

    def results(self) -> tuple[StallWatch | None, dict]:
        out, _ = self.proc.communicate(timeout=120)
        self.th.join(60)
        return self.thread_w, json.loads(out.strip().splitlines()[-1])



def loop_report(stalls: StallWatch, gcp: GcProbe, probe: CallbackProbe | None,
                wall_s: float, controls: tuple[StallWatch | None, dict], full: str
                ) -> list[str]:
    out = []
    w = stalls.worst
    out.append(f"server loop (process 'opcua'): longest stall {stalls.max_stall_s * 1000:.0f} ms "
               + ("" if w is None else
                  f"[in its {(w.t1 - w.t0) * 1000:.0f} ms window: loop thread CPU "
                  f"{w.cpu_s * 1000:.1f} ms, its process's other threads "
                  f"{w.others_s * 1000:.1f} ms, GC "
                  f"{w.gc_s * 1000:.1f} ms, process not running "
                  f"{w.unscheduled_s * 1000:.0f} ms]")
               + f"; stalls over 50 ms: {stalls.over} of {stalls.windows} windows")
    bare_thread, bare_proc = controls
    if bare_thread is not None:
        out.append(f"  beside it, bare asyncio loops: in a thread of the desk's process longest "
                   f"stall {bare_thread.max_stall_s * 1000:.0f} ms ({bare_thread.over} over "
                   f"50 ms); in a process of its own {bare_proc['max_ms']:.0f} ms "
                   f"({bare_proc['over']} over 50 ms)")
    for st in sorted(stalls.recent, key=lambda x: -x.late_s)[:5]:
        out.append(f"  stall {st.late_s * 1000:4.0f} ms: loop CPU {st.cpu_s * 1000:5.1f} ms, "
                   f"other threads {st.others_s * 1000:5.1f} ms, GC {st.gc_s * 1000:5.1f} ms, "
                   f"process not running {st.unscheduled_s * 1000:4.0f} ms")
    out.append(f"GC (server process): collections gen0/1/2 {gcp.count[0]}/{gcp.count[1]}/"
               f"{gcp.count[2]}, longest pause {max(gcp.max_s) * 1000:.1f} ms (gen2 "
               f"{gcp.max_s[2] * 1000:.1f} ms), total {sum(gcp.total_s) / wall_s * 1000:.1f} "
               f"ms/s")
    out.append(f"server process, {full}")
    if probe is not None:
        out.append(f"server callbacks: {probe.n / wall_s:.0f}/s; longest CPU "
                   f"{probe.max_cpu_s * 1000:.1f} ms ({probe.max_cpu_name}); longest wall "
                   f"{probe.max_wall_s * 1000:.1f} ms with {probe.max_wall_cpu_s * 1000:.1f} "
                   f"ms CPU ({probe.max_wall_name}); over 50 ms: CPU {probe.over_cpu}, "
                   f"wall {probe.over_wall}")
        top = sorted(probe.by_name_cpu.items(), key=lambda kv: -kv[1])[:4]
        for name, c in top:
            out.append(f"  CPU in callbacks over 5 ms: {c / wall_s * 1000:5.1f} ms/s  {name}")
        out.append(f"server callbacks' CPU in all: {probe.cpu_total_s / wall_s * 1000:.1f} ms/s; "
                   f"by callback (count/s, CPU ms/s):")
        every = sorted(probe.all_by_name.items(), key=lambda kv: -kv[1][1])[:10]
        for name, (n, c) in every:
            out.append(f"  {n / wall_s:6.1f}/s {c / wall_s * 1000:5.2f} ms/s  {name}")
    return out


if __name__ == "__main__":  # the control process of Controls: a bare loop for argv[1] s
    w = bare_loop(float(sys.argv[1]))
    print(json.dumps({"max_ms": w.max_stall_s * 1000, "over": w.over, "windows": w.windows}))
