"""The MCU's link watchdog at a high time scale: it runs on the link's clock.

The relay keeps the board's link alive every ``keepalive_s`` of wall time and the
board stops the motors after ``mcu_link_timeout_s`` of silence on the same clock, so
a simulation many times faster than real time must not trip it while the link is
healthy, and a cut link must still stop the robot within the limit. Here the
board's thread serves a model whose samples cost more wall time than a period at
x36 (as on a loaded host), so its thread is always catching up.
"""

from __future__ import annotations

import math
import queue
import threading
import time

import pytest

from app.comm.protocol import AlarmFlag, RobotMode
from sim_robot.config import RobotParams, SimConfig
from sim_robot.mcu import McuModel, McuThread
from sim_robot.mcu_link import Keepalive, McuEncoder, MotorCmd
from sim_robot.mcu_port import McuPort
from sim_robot.sim import SimClock
from sim_robot.world import World

from .conftest import wait_until

SAMPLE_COST_S = 0.002  # > one 20 Hz period at x36 (1.4 ms): the thread never catches up
TURN_RPS = 0.5  # turning on the spot: never an obstacle stop


class QueuePort(McuPort):
    """The board's end of a link whose bytes the test's stand-in relay puts in."""

    def __init__(self) -> None:
        self._q: queue.Queue[bytes] = queue.Queue()

    def put(self, data: bytes) -> None:
        self._q.put(data)

    def read(self, timeout_s: float) -> bytes:
        try:
            chunks = [self._q.get(timeout=timeout_s) if timeout_s > 0 else self._q.get_nowait()]
        except queue.Empty:
            return b""
        while True:
            try:
                chunks.append(self._q.get_nowait())
            except queue.Empty:
                return b"".join(chunks)

    def write(self, data: bytes) -> None:
        pass  # the reports are read from the model here


class SlowMcu(McuModel):
    """The patrol robot's board with a costly sample; records each sample as
    (sim time, wall time when it began, flags, mode, commanded turn)."""

    def __init__(self) -> None:
        w = World(seed=2)
        w.set_pose(66.0, 45.0, math.pi)
        super().__init__(w, RobotParams(), seed=2,
                         link_timeout_s=SimConfig().mcu_link_timeout_s)
        self.samples: list[tuple[float, float, int, int, float]] = []

    def step(self, t: float, dt: float):
        wall = time.monotonic()
        time.sleep(SAMPLE_COST_S)
        rep = super().step(t, dt)
        self.samples.append((t, wall, rep.alarm_flags, rep.mode, rep.cmd_angular_rps))
        return rep


class Relay(threading.Thread):
    """Sends what the relay sends the board every ``keepalive_s`` (wall time) until cut."""

    def __init__(self, port: QueuePort, msg) -> None:
        super().__init__(name="test-relay", daemon=True)
        self.port, self.msg = port, msg
        self.enc = McuEncoder()
        self.cut = threading.Event()
        self.sent: list[float] = [time.monotonic()]  # wall time of every frame put
        self.port.put(self.enc.encode(msg))  # the first frame is there at the start

    def run(self) -> None:
        while not self.cut.wait(SimConfig().keepalive_s):
            self.sent.append(time.monotonic())
            self.port.put(self.enc.encode(self.msg))

    def silence_before(self, wall: float) -> float:
        """Wall seconds since the last frame put before ``wall``."""
        return wall - max((t for t in self.sent if t <= wall), default=self.sent[0])


@pytest.fixture
def board():
    started: list[tuple[McuThread, Relay]] = []

    def make(scale: float, msg) -> tuple[SlowMcu, Relay, SimClock]:
        model, port, clock = SlowMcu(), QueuePort(), SimClock(scale)
        relay = Relay(port, msg)
        thread = McuThread(model, port, clock)
        started.append((thread, relay))
        relay.start()
        thread.start()
        return model, relay, clock

    yield make
    for thread, relay in started:
        relay.cut.set()
        thread.stop()
        thread.join(timeout=2)


def test_no_failsafe_at_x36_on_a_healthy_link(board):
    model, relay, clock = board(36.0, Keepalive())
    wait_until(lambda: len(model.samples) >= 1500, 60)
    behind_s = (clock.now() - model.samples[-1][0]) / 36.0
    assert behind_s > SimConfig().mcu_link_timeout_s  # the thread did fall behind
    # a fail-safe sample is right only where the relay really fell silent for the limit
    # (a loaded machine can starve the test's relay thread); anywhere else it is the bug
    limit = SimConfig().mcu_link_timeout_s
    wrong = [s for s in model.samples if s[2] & AlarmFlag.FAILSAFE_STOP
             and relay.silence_before(s[1]) < 0.8 * limit]
    assert wrong == [], f"{len(wrong)} of {len(model.samples)} samples in fail-safe on a live link"


@pytest.mark.parametrize("scale", [1.0, 36.0])
def test_a_cut_link_stops_the_robot_within_the_limit(board, scale):
    model, relay, clock = board(scale, MotorCmd(0.0, TURN_RPS))
    wait_until(lambda: any(s[4] == TURN_RPS for s in model.samples), 20)
    assert not any(s[2] & AlarmFlag.FAILSAFE_STOP for s in model.samples)
    relay.cut.set()
    relay.join(timeout=2)
    wait_until(lambda: any(s[2] & AlarmFlag.FAILSAFE_STOP for s in model.samples), 20)
    limit_s = model.link_timeout_s
    last_rx = model.last_rx  # the last frame's arrival on the link's clock
    n = len(model.samples)
    wait_until(lambda: len(model.samples) >= n + 20, 20)
    heading = model.world.pose.theta
    wait_until(lambda: len(model.samples) >= n + 40, 20)
    samples = list(model.samples)

    # every sample begun more than the limit after the last frame is a fail-safe stop
    late = [s for s in samples if s[1] > last_rx + limit_s]
    assert late and all(s[2] & AlarmFlag.FAILSAFE_STOP and s[3] == RobotMode.FAILSAFE
                        and s[4] == 0.0 for s in late)
    # in sim time: the robot ran on for at most the limit (x the scale) and one period
    sim_of_last_rx = clock.now() - (time.monotonic() - last_rx) * scale
    first_stop = next(s for s in samples if s[2] & AlarmFlag.FAILSAFE_STOP)
    assert first_stop[0] <= sim_of_last_rx + limit_s * scale + 0.05 + 1e-3
    # and it stays stopped
    assert model.world.pose.theta == heading
