"""The meter reader's warm-up at desk start: it reads a drawn dial with each gauge
type's profile on the reading thread, so the memory a first reading pages in and
grows is taken at start; a real reading afterwards grows the process no more."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from app.core.desk.meters import DeskMeters
from app.core.meter_service import MeterService, read_frame
from app.core.meter_warmup import synthetic_dial_frame, warm_up_reader

ROOT = Path(__file__).resolve().parents[2]


def test_the_drawn_dial_reads_as_drawn():
    """The warm-up frame is a dial the reader reads through its whole path."""
    svc = MeterService()
    gauge = next(g for g, info in svc.gauges.items() if info.type == "pressure_0_1p6mpa")
    prof = svc.profile(gauge)
    for frac in (0.25, 0.6):
        r = read_frame(synthetic_dial_frame(frac), prof)
        span = prof.max_value - prof.min_value
        assert r.value == pytest.approx(prof.min_value + frac * span, abs=0.03 * span), r.error


def test_warm_up_reads_each_gauge_type_once_on_the_reading_thread():
    svc = MeterService()
    types = {info.type for info in svc.gauges.values()}
    assert warm_up_reader(svc) == len(types) >= 1
    jobs = []
    meters = DeskMeters(svc, monitor=None, emit=lambda *a: None, send=lambda *a: None,
                        submit=lambda job, done: jobs.append((job, done)))
    meters.warm_up()
    assert meters.warmed == -1 and len(jobs) == 1  # handed to the reading thread
    job, done = jobs[0]
    done(job())
    assert meters.warmed == len(types)


_GROWTH = textwrap.dedent("""
    import sys
    from concurrent.futures import ThreadPoolExecutor
    import numpy as np
    from app.core.meter_service import MeterService, read_frame
    from app.core.meter_warmup import warm_up_reader
    from sim_robot.gauge_render import render_dial, stock_spec
    def rss_kb():
        for line in open("/proc/self/status"):
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    reading_thread = ThreadPoolExecutor(max_workers=1)  # the desk's one reading thread
    def on_thread(fn):
        reading_thread.submit(fn).result()
    svc = MeterService()
    gauge = next(g for g, i in svc.gauges.items() if i.type == "pressure_0_10bar")
    img = render_dial(stock_spec("pressure_0_10bar"), 4.2, 300)
    frame = np.zeros((480, 640, 3), np.uint8)
    frame[90:390, 170:470] = img[..., :3]
    if sys.argv[1] == "warm":
        on_thread(lambda: warm_up_reader(svc))
    before = rss_kb()
    on_thread(lambda: print(read_frame(frame, svc.profile(gauge)).value))
    print(rss_kb() - before)
""")


def _growth(mode: str) -> tuple[float, int]:
    path = os.pathsep.join(p for p in (str(ROOT), os.environ.get("PYTHONPATH")) if p)
    out = subprocess.run([sys.executable, "-c", _GROWTH, mode], capture_output=True,
                         text=True, timeout=300, check=True,
                         env={**os.environ, "PYTHONPATH": path}).stdout.split()
    return float(out[0]), int(out[1])


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_after_the_warm_up_a_first_real_reading_grows_the_process_little():
    value, cold_kb = _growth("cold")
    assert value == pytest.approx(4.2, abs=0.2)
    value, warm_kb = _growth("warm")
    assert value == pytest.approx(4.2, abs=0.2)
    assert cold_kb > 3000  # the first reading of a cold reader: megabytes
    # What is left after the warm-up is a small part of a cold first reading (the
    # allocator's own bookkeeping varies between C libraries, so no fixed figure).
    assert warm_kb < max(1000, cold_kb // 4), (cold_kb, warm_kb)
