"""``python -m sim_robot --robot 4ws`` as a process on an ephemeral port, a plain
socket desk: the four wheels' state and the TEB plan arrive over the real link,
and the patrol makes progress along the station's route."""

import math
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from app.comm import auth
from app.comm import protocol as P
from app.comm.fws_protocol import MODES, TebPlan, WheelState
from app.core.kinematics import FwsGeometry, WheelCommand, body_twist

ROOT = Path(__file__).resolve().parents[2]
TIME_SCALE = 8.0  # TEB off the relay's lock: the MCU link keeps up (at 10x, load ~20: not always)


@pytest.mark.e2e
@pytest.mark.timeout(600)  # ~35 s on an idle machine, minutes on a loaded one
def test_fws_robot_process_patrols_and_reports_its_wheels():
    proc = subprocess.Popen(
        [sys.executable, "-m", "sim_robot", "--robot", "4ws", "--listen", "127.0.0.1:0",
         "--seed", "1", "--no-video", "--time-scale", str(TIME_SCALE)],
        cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        line = proc.stdout.readline()
        assert line.startswith("listening on "), line + proc.stderr.read()
        host, port = line.split()[-1].rsplit(":", 1)
        sock = socket.create_connection((host, int(port)), timeout=5)
        sock.settimeout(0.05)
        signer = auth.CommandSigner(auth.load_or_create_key()[0])
        dec, enc = P.FrameDecoder(), P.FrameEncoder(signer=signer)
        got: dict[P.MsgType, list] = {t: [] for t in P.MsgType}
        beat = [0.0]

        def pump(until, timeout, what):
            end = time.monotonic() + timeout
            while time.monotonic() < end:
                if time.monotonic() - beat[0] > 0.25:
                    beat[0] = time.monotonic()
                    sock.sendall(enc.encode(P.Heartbeat(P.Heartbeat.ROLE_DESK)))
                try:
                    data = sock.recv(65536)
                except TimeoutError:
                    data = b""
                for f in dec.feed(data):
                    got[f.msg_type].append(f.message)
                if until():
                    return
            raise AssertionError(f"timed out waiting for {what}; got "
                                 + str({k.name: len(v) for k, v in got.items() if v}))

        pump(lambda: got[P.MsgType.TELEMETRY] and got[P.MsgType.WHEEL_STATE], 60,
             "telemetry and wheel state")
        w0 = got[P.MsgType.WHEEL_STATE][-1]
        assert isinstance(w0, WheelState) and w0.mode_name == "stopped"
        assert w0.speeds_mps == (0.0, 0.0, 0.0, 0.0)
        seq = enc.seq
        sock.sendall(enc.encode(P.Command("start_patrol", {})))
        pump(lambda: any(a.cmd_seq == seq for a in got[P.MsgType.COMMAND_ACK]), 10, "ack")
        ack = next(a for a in got[P.MsgType.COMMAND_ACK] if a.cmd_seq == seq)
        assert ack.ok, ack.reason

        def second_point():
            st = got[P.MsgType.PATROL_STATUS]
            return st and st[-1].index >= 1

        pump(second_point, 150, "the patrol at its second point")
        status = got[P.MsgType.PATROL_STATUS][-1]
        assert status.route == "default" and status.local_planner == "teb"
        events = [(e.code, e.text) for e in got[P.MsgType.EVENT] if e.level != "info"]
        assert status.points[0]["state"] == "done" and status.progress > 0, events
        assert any(e.code == "inspection_done" for e in got[P.MsgType.EVENT])
        # the wheels as the board reports them: driving on front-steer arcs at
        # speed and counter-phase ones otherwise, pivoting to face the gauges,
        # each a rigid-body motion of the chassis
        wheels = got[P.MsgType.WHEEL_STATE]
        modes = {w.mode_name for w in wheels}
        assert {"front", "pivot"} <= modes <= set(MODES)
        geom = FwsGeometry()
        moving = [w for w in wheels if w.mode_name in ("counter", "front")
                  and min(w.speeds_mps) > 0.3]
        assert moving, "no wheel state while driving"
        slips = []
        for w in moving:
            assert all(abs(a) <= geom.servo_range_rad + 1e-3 for a in w.angles_rad)
            tw, slip = body_twist(geom, WheelCommand(w.angles_rad, w.speeds_mps))
            # forward; on a tight counter-phase arc an inner wheel (off the
            # lateral axis through the ICR) may run a little faster than the centre
            assert tw.vx > 0.25
            slips.append(slip)
        # while a servo is still turning the wheels disagree (slip: more of the
        # reports on a loaded machine, where mode changes swing the servos); settled,
        # they agree: a good share of the reports is a rigid-body motion
        assert np.percentile(slips, 25) < 0.01 and max(slips) < 0.3
        pivots = [w for w in wheels if w.mode_name == "pivot" and max(map(abs, w.speeds_mps)) > 0.1]
        assert pivots, "no wheel state while turning in place"
        tw, _ = body_twist(geom, WheelCommand(pivots[-1].angles_rad, pivots[-1].speeds_mps))
        assert abs(tw.vx) < 0.05 and abs(tw.omega) > 0.1
        # the TEB local plan: poses from the robot toward the route, intervals > 0
        plans = [p for p in got[P.MsgType.TEB_PLAN] if not p.turning_in_place]
        assert plans and isinstance(plans[-1], TebPlan)
        for p in plans[-5:]:
            assert len(p.poses) >= 3 and len(p.dts_s) == len(p.poses) - 1
            assert (p.dts_s > 0).all()
            steps = np.linalg.norm(np.diff(p.poses[:, :2], axis=0), axis=1)
            assert steps.max() < 1.0
        poses = got[P.MsgType.POSE]
        first, last = poses[0], poses[-1]
        assert math.hypot(last.x_m - first.x_m, last.y_m - first.y_m) > 3.0
        sock.close()
    finally:
        proc.terminate()
        try:
            proc.communicate(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
