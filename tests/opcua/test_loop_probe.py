"""The loop probe tells a stall's causes apart: the loop's own CPU, collections, waiting."""

import asyncio
import gc
import time

from app.interop.opcua.loop_probe import CallbackProbe, GcProbe, StallWatch


def _burn(cpu_s: float) -> None:
    """Run on the CPU for ``cpu_s`` of this thread's CPU time."""
    end = time.thread_time() + cpu_s
    while time.thread_time() < end:
        pass


def test_stall_watch_splits_a_stall_into_cpu_gc_and_waiting():
    class FakeGc:
        def paused_between(self, t0, t1):
            return 0.030 if t0 <= 10.05 <= t1 else 0.0

    w = StallWatch(period_s=0.05, over_s=0.05, gc_probe=FakeGc())
    assert w.note(0.0, 0.0, 0.051, 0.001).late_s < 0.05  # first window: the worst so far
    assert w.note(1.0, 0.0, 1.052, 0.001) is not None and w.over == 0
    assert w.note(2.0, 0.0, 2.0505, 0.0) is None  # neither over nor the worst
    # 150 ms late, 60 ms of the loop's CPU, 90 ms of the process's, 30 ms GC
    s = w.note(10.0, 1.0, 10.2, 1.06, 0.09)
    assert abs(s.late_s - 0.15) < 1e-9 and abs(s.cpu_s - 0.06) < 1e-9
    assert abs(s.gc_s - 0.03) < 1e-12 and abs(s.others_s - 0.03) < 1e-9
    assert abs(s.unscheduled_s - 0.11) < 1e-9
    assert w.worst is s and w.over == 1 and list(w.recent) == [s] and w.windows == 4
    w.reset()
    assert w.worst is None and w.over == 0 and w.max_stall_s == 0.0


def test_gc_probe_records_collections_and_their_time_in_a_window():
    with GcProbe() as p:
        junk = [[i] for i in range(50_000)]  # something to walk
        t0 = time.perf_counter()
        gc.collect()
        t1 = time.perf_counter()
        del junk
    assert p.count[2] >= 1 and p.max_s[2] > 0.0
    inside = p.paused_between(t0, t1)
    assert 0.0 < inside <= t1 - t0
    assert p.paused_between(t1 + 10.0, t1 + 20.0) == 0.0
    n = sum(p.count)
    gc.collect()  # the probe is off now
    assert sum(p.count) == n


def test_callback_probe_names_the_callback_that_ran_long_on_the_cpu():
    async def busy_task():
        await asyncio.sleep(0)
        _burn(0.03)

    def light():
        pass

    async def main():
        probe = CallbackProbe(over_s=0.02).install()
        try:
            loop = asyncio.get_running_loop()
            loop.call_soon(light)
            await asyncio.create_task(busy_task())
            loop.call_soon(_burn, 0.025)
            await asyncio.sleep(0.01)
        finally:
            probe.uninstall()
        return probe

    orig = asyncio.Handle._run
    probe = asyncio.run(main())
    assert asyncio.Handle._run is orig and CallbackProbe._orig_run is None  # restored
    assert probe.n >= 3
    assert probe.max_cpu_s >= 0.03 and "busy_task" in probe.max_cpu_name
    assert probe.over_cpu == 2  # the task's step and the plain burn
    assert probe.by_name_cpu["_burn"] >= 0.025
    assert probe.cpu_total_s >= 0.055


def test_a_burst_of_desk_messages_is_served_in_slices():
    """The server's consumer lets the loop run other callbacks while it works through a
    backlog (a flood of alarms): without slices they would wait for the whole burst."""
    from app.config import OpcuaSettings
    from app.interop.opcua.child import ServerConfig
    from app.interop.opcua.core import ServerCore
    from app.interop.opcua.users import UserStore

    async def main(tmp):
        srv = ServerCore(ServerConfig(OpcuaSettings(endpoint="opc.tcp://127.0.0.1:0"),
                                      UserStore(tmp / "users.json"), tmp), lambda msg: None)
        served, others = [], []

        async def apply(kind, args, t, mono):
            _burn(0.002)  # a condition event's worth of work
            served.append(len(others))  # how often the loop ran something else so far

        srv._apply = apply
        srv._q = asyncio.Queue()
        for i in range(50):
            srv._q.put_nowait(("alarm", (i,), 0.0, 0.0))

        async def other():
            while len(served) < 50:
                others.append(1)
                await asyncio.sleep(0)

        consumer = asyncio.create_task(srv._consume(slice_s=0.005))
        await asyncio.wait_for(other(), 30)
        consumer.cancel()
        return served

    import tempfile
    from pathlib import Path
    served = asyncio.run(main(Path(tempfile.mkdtemp())))
    assert len(served) == 50
    # each slice is at most a few messages (2 ms of CPU each, a slice 5 ms of wall)
    assert served[-1] >= 50 // 3 - 1
    assert all(b - a <= 1 for a, b in zip(served, served[1:], strict=False))


def test_start_up_objects_are_frozen_out_of_the_collector():
    """What is alive when the server starts is no longer walked by a full collection;
    garbage made later is still collected."""
    from app.interop.opcua.core import freeze_startup_objects as _freeze_startup_objects

    gc.unfreeze()
    try:
        long_lived = [[i] for i in range(20_000)]
        _freeze_startup_objects()
        frozen = gc.get_freeze_count()
        assert frozen > len(long_lived)
        tracked = len(gc.get_objects())
        assert tracked < frozen  # a full collection walks only what came after
        cycle = []
        cycle.append(cycle)
        del cycle
        assert gc.collect() >= 1  # later garbage: collected as before
    finally:
        gc.unfreeze()
