"""The relay's camera stream ("relay-video"): one JPEG frame per ``1 / fps``
seconds of wall time to every desk, none while no desk is connected. Frames go
out as video (a slow desk's frames are dropped, not queued; see
:class:`sim_robot.server.Client`)."""

from __future__ import annotations

import time

from app.comm.protocol import VideoFrame, now_us


class VideoStream:
    """The camera thread (started only when the robot has a camera)."""

    def _video(self) -> None:
        period = 1.0 / self.cfg.fps
        nxt = time.monotonic()
        while not self._stop.wait(max(0.0, nxt - time.monotonic())):
            nxt = max(nxt + period, time.monotonic())
            if not self.server.clients:
                continue
            x, y, th = self.camera_pose()
            ts = now_us()
            fid, jpeg = self.camera.capture_jpeg(x, y, th, self.sim_time())
            self.server.broadcast(VideoFrame(fid, ts, self.camera.w, self.camera.h, 0.0, jpeg),
                                  is_video=True)
            self.counters["video"] += 1

