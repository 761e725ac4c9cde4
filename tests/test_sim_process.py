"""Starting the local simulated robot: a robot that dies before it listens is
reported at once with what it printed; a slow start (a first compile) is waited
for, with a note every so often; the start gives up at its limit."""

from __future__ import annotations

import sys
import time

import pytest

from app.sim_process import SimRobotProcess


def _process(tmp_path, script: str, **kw) -> SimRobotProcess:
    sim = SimRobotProcess(key_file=str(tmp_path / "station.key"), **kw)
    sim.args = [sys.executable, "-c", script]  # a stand-in robot
    return sim


def test_a_robot_that_exits_before_it_listens_is_reported_at_once(tmp_path):
    sim = _process(tmp_path, "import sys; print('no station map here'); sys.exit(3)",
                   start_timeout_s=120.0)
    t0 = time.monotonic()
    with pytest.raises(RuntimeError) as e:
        sim.start()
    assert time.monotonic() - t0 < 60.0  # not the whole start limit
    assert "exited with code 3" in str(e.value)
    assert "no station map here" in str(e.value)


def test_a_slow_start_is_waited_for_with_notes(tmp_path):
    notes: list[float] = []
    sim = _process(tmp_path, "import time; time.sleep(1.5); "
                   "print('listening on 127.0.0.1:4567', flush=True); time.sleep(30)",
                   on_wait=notes.append, wait_note_s=0.2, start_timeout_s=120.0)
    try:
        sim.start()
        assert (sim.host, sim.port) == ("127.0.0.1", 4567)
        assert len(notes) >= 3 and notes == sorted(notes)
    finally:
        sim.stop()


def test_the_start_gives_up_at_its_limit_and_stops_the_robot(tmp_path):
    sim = _process(tmp_path, "import time; print('compiling', flush=True); time.sleep(60)",
                   start_timeout_s=1.0)
    with pytest.raises(RuntimeError) as e:
        sim.start()
    assert "within 1 s" in str(e.value) and "compiling" in str(e.value)
    assert not sim.alive()
