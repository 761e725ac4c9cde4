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

pytestmark = pytest.mark.slow(15)

ROOT = Path(__file__).resolve().parents[2]
TIME_SCALE = 8.0  # TEB off the relay's lock: the MCU link keeps up (at 10x, load ~20: not always)


class _Desk:
    """A plain socket desk on a ``sim_robot --robot 4ws`` process: ``pump`` reads
    frames into ``got`` (by type) until a condition holds, with heartbeats."""

    def __init__(self):
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "sim_robot", "--robot", "4ws", "--listen", "127.0.0.1:0",
             "--seed", "1", "--no-video", "--time-scale", str(TIME_SCALE)],
            cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        line = self.proc.stdout.readline()
        assert line.startswith("listening on "), line + self.proc.stderr.read()
        host, port = line.split()[-1].rsplit(":", 1)
        self.sock = socket.create_connection((host, int(port)), timeout=5)
        self.sock.settimeout(0.05)
        signer = auth.CommandSigner(auth.load_or_create_key()[0])
        self.dec, self.enc = P.FrameDecoder(), P.FrameEncoder(signer=signer)
        self.got: dict[P.MsgType, list] = {t: [] for t in P.MsgType}
        self.beat = 0.0

    def pump(self, until, timeout, what):
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            if time.monotonic() - self.beat > 0.25:
                self.beat = time.monotonic()
                self.sock.sendall(self.enc.encode(P.Heartbeat(P.Heartbeat.ROLE_DESK)))
            try:
                data = self.sock.recv(65536)
            except TimeoutError:
                data = b""
            for f in self.dec.feed(data):
                self.got[f.msg_type].append(f.message)
            if until():
                return
        raise AssertionError(f"timed out waiting for {what}; got "
                             + str({k.name: len(v) for k, v in self.got.items() if v}))

    def command(self, name, args):
        seq = self.enc.seq
        self.sock.sendall(self.enc.encode(P.Command(name, args)))
        acks = self.got[P.MsgType.COMMAND_ACK]
        self.pump(lambda: any(a.cmd_seq == seq for a in acks), 10, "ack")
        return next(a for a in acks if a.cmd_seq == seq)

    def close(self):
        self.sock.close()
        self.proc.terminate()
        try:
            self.proc.communicate(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()


@pytest.mark.e2e
@pytest.mark.timeout(600)  # ~35 s on an idle machine, minutes on a loaded one
def test_fws_robot_process_patrols_and_reports_its_wheels():
    desk = _Desk()
    got, pump = desk.got, desk.pump
    try:
        pump(lambda: got[P.MsgType.TELEMETRY] and got[P.MsgType.WHEEL_STATE], 60,
             "telemetry and wheel state")
        w0 = got[P.MsgType.WHEEL_STATE][-1]
        assert isinstance(w0, WheelState) and w0.mode_name == "stopped"
        assert w0.speeds_mps == (0.0, 0.0, 0.0, 0.0)
        ack = desk.command("start_patrol", {})
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
    finally:
        desk.close()


@pytest.mark.e2e
@pytest.mark.timeout(600)
def test_fws_robot_docks_sideways_in_crab_mode():
    """A goal a little to the robot's left, within reach of neither an arc nor a
    pivot-and-drive worth the turn: the navigator closes it in CRAB mode, the
    relay sends the body twist, and the robot's pose moves sideways without
    turning."""
    desk = _Desk()
    got, pump = desk.got, desk.pump
    try:
        pump(lambda: got[P.MsgType.POSE] and got[P.MsgType.WHEEL_STATE], 60, "pose and wheels")
        p0 = got[P.MsgType.POSE][-1]
        c, s = math.cos(p0.theta_rad), math.sin(p0.theta_rad)
        ahead, left = 0.2, 0.25  # the goal in the robot's frame
        gx, gy = p0.x_m + c * ahead - s * left, p0.y_m + s * ahead + c * left
        ack = desk.command("goto", {"x_m": gx, "y_m": gy})
        assert ack.ok, ack.reason

        def crabbed_and_stopped():
            w = got[P.MsgType.WHEEL_STATE]
            return any(x.mode_name == "crab" for x in w) and w[-1].mode_name == "stopped"

        pump(crabbed_and_stopped, 120, "a crab move and a stop")
        wheels = got[P.MsgType.WHEEL_STATE]
        crab = [w for w in wheels if w.mode_name == "crab" and min(w.speeds_mps) > 0.02]
        assert crab, "no wheel state while crabbing"
        # in-phase once the servos have swung over from the last mode: all four
        # wheels at one angle, to the left of ahead, the body sliding left
        settled = [w for w in crab if max(w.angles_rad) - min(w.angles_rad) < 0.02]
        assert settled, [w.angles_rad for w in crab]
        for w in settled:
            tw, _ = body_twist(FwsGeometry(), WheelCommand(w.angles_rad, w.speeds_mps))
            assert tw.vy > 0.02 and abs(tw.omega) < 0.01 and w.angles_rad[0] > 0.1
        # the pose (the relay's estimate: odometry with its sideways term, and
        # the scan matching) moved to the left without turning
        p1 = got[P.MsgType.POSE][-1]
        dx, dy = p1.x_m - p0.x_m, p1.y_m - p0.y_m
        fwd, side = c * dx + s * dy, -s * dx + c * dy
        turn = (p1.theta_rad - p0.theta_rad + math.pi) % (2 * math.pi) - math.pi
        assert side > 0.12, (fwd, side, turn)
        assert abs(turn) < math.radians(8), (fwd, side, turn)
        assert math.hypot(gx - p1.x_m, gy - p1.y_m) < 0.25  # tolerance + the estimate's noise
        modes = [w.mode_name for w in wheels]
        assert "pivot" not in modes[modes.index("crab"):]  # no turning to close it
    finally:
        desk.close()
