"""Start ``python -m sim_robot`` as a process and talk to it over a plain socket."""

import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import cv2
import numpy as np
import pytest

from app.comm import auth
from app.comm import protocol as P

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.e2e
def test_sim_robot_process_end_to_end(tmp_path):
    truth = tmp_path / "truth.jsonl"
    proc = subprocess.Popen(
        [sys.executable, "-m", "sim_robot", "--listen", "127.0.0.1:0", "--seed", "1",
         "--log-truth", str(truth)],
        cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        line = proc.stdout.readline()
        assert line.startswith("listening on "), line + proc.stderr.read()
        host, port = line.split()[-1].rsplit(":", 1)
        sock = socket.create_connection((host, int(port)), timeout=5)
        sock.settimeout(0.05)
        # commands are signed with the station key the robot reads (tests/conftest.py)
        signer = auth.CommandSigner(auth.load_or_create_key()[0])
        dec, enc = P.FrameDecoder(), P.FrameEncoder(signer=signer)
        got: dict[P.MsgType, list] = {t: [] for t in P.MsgType}
        drive_seqs: list[int] = []

        def pump(until, timeout=10.0, drive=False):
            end = time.monotonic() + timeout
            last = 0.0
            while time.monotonic() < end:
                if drive and time.monotonic() - last > 0.2:
                    last = time.monotonic()
                    drive_seqs.append(enc.seq)
                    sock.sendall(enc.encode(P.Command(
                        "drive", {"linear_mps": 0.3, "angular_rps": 0})))
                try:
                    data = sock.recv(65536)
                except TimeoutError:
                    data = b""
                for f in dec.feed(data):
                    got[f.msg_type].append((f, f.message))
                if until():
                    return
            raise AssertionError("timed out; got " + str({k.name: len(v) for k, v in
                                                          got.items()}))

        pump(lambda: all(got[t] for t in (P.MsgType.TELEMETRY, P.MsgType.VIDEO_FRAME,
                                          P.MsgType.LIDAR_SCAN, P.MsgType.POSE,
                                          P.MsgType.HEARTBEAT)))
        tel = got[P.MsgType.TELEMETRY][-1][1]
        assert 18.0 < tel.battery_v < 25.3 and -20 < tel.temp_c < 50
        vf = got[P.MsgType.VIDEO_FRAME][-1][1]
        assert (vf.width, vf.height) == (640, 480)
        img = cv2.imdecode(np.frombuffer(vf.jpeg, np.uint8), cv2.IMREAD_COLOR)
        assert img is not None and img.shape == (480, 640, 3)
        assert abs(P.now_us() - vf.capture_ts_us) < 5_000_000
        scan = got[P.MsgType.LIDAR_SCAN][-1][1]
        assert len(scan.ranges_m) == 360 and scan.range_max_m == pytest.approx(12.0)
        p0 = got[P.MsgType.POSE][-1][1]

        def moved():
            p = got[P.MsgType.POSE][-1][1]
            return math_hypot(p.x_m - p0.x_m, p.y_m - p0.y_m) > 0.3

        pump(moved, timeout=10.0, drive=True)
        acks = {m.cmd_seq: m for _, m in got[P.MsgType.COMMAND_ACK]}
        assert drive_seqs[0] in acks and acks[drive_seqs[0]].ok
        assert dec.stats.dropped == 0
        sock.close()
    finally:
        proc.send_signal(signal.SIGTERM)
        try:
            rc = proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
            raise
    assert rc == 0
    if os.path.exists(truth):
        assert truth.read_text().count("\n") >= 1


def math_hypot(a, b):
    return (a * a + b * b) ** 0.5
