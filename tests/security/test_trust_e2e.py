"""End-to-end trust tests against a real sim_robot process on an ephemeral port:
signatures, replays, the control lease, the deadman when a desk is killed, and
hostile peers."""

import os
import random
import socket
import subprocess
import sys
import threading
from pathlib import Path

import pytest
from sim.desk import SocketDesk, wait_until

from app.comm import protocol as P
from app.sim_process import SimRobotProcess

pytestmark = [pytest.mark.e2e, pytest.mark.slow(27)]
ROOT = Path(__file__).resolve().parents[2]
DRIVE = P.Command("drive", {"linear_mps": 0.3, "angular_rps": 0.0})


@pytest.fixture
def robot():
    sim = SimRobotProcess(seed=1, extra=["--no-video"]).start()
    yield sim
    sim.stop()


@pytest.fixture
def desks(robot):
    made: list[SocketDesk] = []

    def make(**kw) -> SocketDesk:
        d = SocketDesk(robot.host, robot.port, **kw)
        made.append(d)
        return d

    yield make
    for d in made:
        d.close()


def _tel(desk):
    return desk.of(P.MsgType.TELEMETRY)


def _acks(desk, seq):
    return [a for a in desk.of(P.MsgType.COMMAND_ACK) if a.cmd_seq == seq]


def _send_raw(desk, data: bytes) -> None:
    desk.sock.sendall(data)


def test_unsigned_or_wrongly_signed_drive_is_refused_and_the_robot_stays(desks):
    watcher = desks()
    unsigned = desks(sign=False)
    forged = desks(key=os.urandom(32), desk="intruder")
    wait_until(lambda: _tel(watcher), 10)
    seqs = []
    for _ in range(5):
        for d in (unsigned, forged):
            s = d.send(DRIVE)
            seqs.append((d, s))
            wait_until(lambda d=d, s=s: _acks(d, s), 5)  # answered before the next
    for d, s in seqs:
        wait_until(lambda d=d, s=s: _acks(d, s), 5)
        (a,) = _acks(d, s)
        assert not a.ok and a.reason.startswith("refused")
    # the robot reports the refusals, by reason
    ev = watcher.wait_for(lambda: [e for e in watcher.events("rejections")
                                   if e.data["counts"].get("unsigned") == 5
                                   and e.data["counts"].get("bad_mac") == 5], 5,
                          "rejection counts")
    assert ev[-1].data["counts"]["replay"] == 0
    assert {e.data["reason"] for e in watcher.events("command_rejected")} >= {"unsigned",
                                                                              "bad_mac"}
    # and never moved: every sample since shows no motor command and no wheel speed
    n = len(_tel(watcher))
    wait_until(lambda: len(_tel(watcher)) >= n + 5, 5)
    for t in _tel(watcher):
        assert t.cmd_linear_mps == 0.0 and t.wheel_left_mps == 0.0


def test_a_replayed_valid_command_is_refused(desks):
    desk = desks()
    wait_until(lambda: _tel(desk), 10)
    seq = desk.enc.seq
    drive = desk.enc.encode(P.Command("drive", {"linear_mps": 0.2, "angular_rps": 0.0}))
    _send_raw(desk, drive)
    wait_until(lambda: _acks(desk, seq), 5)
    assert _acks(desk, seq)[0].ok
    stop = desk.send(P.Command("stop", {}))
    wait_until(lambda: _acks(desk, stop), 5)
    _send_raw(desk, drive)  # the captured frame, byte for byte
    wait_until(lambda: len(_acks(desk, seq)) == 2, 5)
    again = _acks(desk, seq)[1]
    assert not again.ok and "replay" in again.reason
    n = len(_tel(desk))
    wait_until(lambda: len(_tel(desk)) >= n + 8, 5)
    assert all(t.cmd_linear_mps == 0.0 for t in _tel(desk)[-4:])


def test_a_second_desk_cannot_drive_until_control_is_handed_over(desks):
    a = desks(desk="desk-a")
    b = desks(desk="desk-b")
    wait_until(lambda: _tel(a) and _tel(b), 10)
    s = a.send(P.Command("request_control", {}))
    wait_until(lambda: _acks(a, s), 5)
    assert _acks(a, s)[0].ok
    s = b.send(DRIVE)
    wait_until(lambda: _acks(b, s), 5)
    refused = _acks(b, s)[0]
    assert not refused.ok and "view only" in refused.reason and "desk-a" in refused.reason
    s = b.send(P.Command("request_control", {}))
    wait_until(lambda: _acks(b, s), 5)
    assert not _acks(b, s)[0].ok
    a.wait_for(lambda: a.events("control_requested"), 5, "control request")
    # b may still stop the robot (any signed desk may)
    s = b.send(P.Command("stop", {}))
    wait_until(lambda: _acks(b, s), 5)
    assert _acks(b, s)[0].ok
    s = a.send(P.Command("hand_over", {}))
    wait_until(lambda: _acks(a, s), 5)
    assert _acks(a, s)[0].ok
    lease = b.wait_for(lambda: [e for e in b.events("lease") if e.data["holder"] == "desk-b"],
                       5, "lease to desk-b")
    assert lease[-1].data["holder_session"] == b.signer.session
    s = b.send(DRIVE)
    wait_until(lambda: _acks(b, s), 5)
    assert _acks(b, s)[0].ok
    s = a.send(DRIVE)
    wait_until(lambda: _acks(a, s), 5)
    assert not _acks(a, s)[0].ok
    b.wait_for(lambda: any(t.cmd_linear_mps > 0.1 for t in _tel(b)), 5, "b driving")


def test_the_lease_lapses_when_its_holders_heartbeats_stop(desks):
    a = desks(desk="desk-a")
    b = desks(desk="desk-b")
    wait_until(lambda: _tel(a), 10)
    s = a.send(P.Command("request_control", {}))
    wait_until(lambda: _acks(a, s), 5)
    a.heartbeat = False
    b.wait_for(lambda: b.events("lease_lapsed"), 10, "lease lapse")
    s = b.send(DRIVE)
    wait_until(lambda: _acks(b, s), 5)
    assert _acks(b, s)[0].ok


DRIVER = r"""
import socket, sys, time
from app.comm import auth, protocol as P
s = socket.create_connection((sys.argv[1], int(sys.argv[2])))
enc = P.FrameEncoder(signer=auth.CommandSigner(auth.load_or_create_key()[0], "driver"))
print("driving", flush=True)
while True:
    s.sendall(enc.encode(P.Heartbeat()) + enc.encode(
        P.Command("drive", {"linear_mps": 0.3, "angular_rps": 0.0})))
    time.sleep(0.2)
"""


def test_killing_the_driving_desk_stops_the_robot(robot, desks):
    watcher = desks(desk="watcher")
    wait_until(lambda: _tel(watcher), 10)
    proc = subprocess.Popen([sys.executable, "-c", DRIVER, robot.host, str(robot.port)],
                            cwd=ROOT, stdout=subprocess.PIPE, text=True)
    try:
        assert proc.stdout.readline().strip() == "driving"
        watcher.wait_for(lambda: any(t.cmd_linear_mps > 0.2 for t in _tel(watcher)), 10,
                         "the robot driving")
        proc.kill()  # SIGKILL: no goodbye
        proc.wait(5)
        n = len(_tel(watcher))
        watcher.wait_for(lambda: any(t.cmd_linear_mps == 0.0 and t.wheel_left_mps == 0.0
                                     for t in _tel(watcher)[n:]), 5, "the robot stopped")
        assert watcher.events("failsafe_stop") or watcher.events("lease_released")
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(5)


def test_hostile_peers_do_not_stop_the_robot_serving_a_good_desk(robot, desks):
    good = desks(desk="good")
    wait_until(lambda: _tel(good), 10)
    stop = threading.Event()
    rng = random.Random(5)

    gsock = socket.create_connection((robot.host, robot.port))

    def garbage():
        try:
            while not stop.is_set():
                gsock.sendall(rng.randbytes(4096) + P.MAGIC * 50)
                stop.wait(0.005)
        except OSError:
            pass
        finally:
            gsock.close()

    t = threading.Thread(target=garbage, daemon=True)
    t.start()
    never_reads = socket.create_connection((robot.host, robot.port))  # connects, never reads
    many = []
    for _ in range(20):
        try:
            many.append(socket.create_connection((robot.host, robot.port), timeout=2))
        except OSError:
            pass
    try:
        ev = good.wait_for(lambda: [e for e in good.events("rejections")
                                    if e.data["counts"].get("conn_limit", 0) > 0], 10,
                           "connection refusals")
        assert ev[-1].data["counts"]["conn_limit"] >= 20 - 8
        # the good desk still commands and hears the robot
        s = good.send(DRIVE)
        wait_until(lambda: _acks(good, s), 5)
        assert _acks(good, s)[0].ok
        n = len(_tel(good))
        wait_until(lambda: len(_tel(good)) >= n + 10, 5)
        good.wait_for(lambda: [e for e in good.events("rejections")
                               if any(k.startswith("frame:") for k in e.data["counts"])], 10,
                      "garbage counted")
    finally:
        stop.set()
        t.join(5)
        never_reads.close()
        for s in many:
            s.close()
