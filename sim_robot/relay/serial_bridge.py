"""The relay's MCU side: the serial port (pyserial: a board, or the MCU model's socket).

Opens and reopens the port, reads MCU frames (sensor reports feed the robot's
odometry and raise or clear the MCU's alarm flags as events; acks are counted),
writes motor / e-stop / keep-alive / limit frames, and counts every frame the
decoders drop by reason. Uses the state :class:`~.core.Relay` sets up
(``port``, ``mcu_decoder``, ``mcu_encoder``, ``odom``, ``report``, ...).
"""

from __future__ import annotations

import logging
import time

from serial.urlhandler.protocol_socket import Serial as SocketSerial

from app.comm.protocol import AlarmFlag

from ..mcu_link import Ack, ConfigLimits, Estop, Keepalive, McuType, SensorReport

log = logging.getLogger(__name__)

CONFIG_PERIOD_S = 5.0  # the limits are re-sent this often (a rebooted board gets them back)
MCU_SILENT_S = 1.0
DROP_EVENT_MIN_S = 2.0


def read_waiting(port) -> bytes:
    """What the port has: waits up to its timeout for one byte, then takes whatever
    else is waiting without waiting again. Portable (no select on the port, which
    Windows cannot do). pyserial's ``socket://`` port reports ``in_waiting`` as 1 for
    "some", so it is read with a zero timeout instead (cheap there: no line to set
    up); a real port's count is exact."""
    data = port.read(1)
    if not data:
        return data
    if isinstance(port, SocketSerial):
        timeout = port.timeout
        port.timeout = 0
        try:
            return data + port.read(65536)
        finally:
            port.timeout = timeout
    n = port.in_waiting
    return data + port.read(n) if n else data


class SerialBridge:
    """The MCU serial link: port, frames in and out, drop counting."""

    odom_trail = None  # a deque of (t, x, y, θ) odometry samples, where a relay keeps one

    def _open_serial(self) -> bool:
        try:
            self.port = self.open_port()
            if not self.port.timeout:  # a non-blocking port would make the loop spin
                self.port.timeout = 0.1
            return True
        except Exception as e:  # noqa: BLE001 - serial.SerialException, OSError
            self.port = None
            self.serial_errors += 1
            self.event("alarm", "serial_error", f"cannot open the MCU serial port: {e}")
            return False

    def _serial_failed(self, e: Exception) -> None:
        self.serial_errors += 1
        self.event("alarm", "serial_error", f"MCU serial link failed: {e}")
        try:
            self.port.close()
        except Exception:  # noqa: BLE001
            pass
        self.port = None

    def _mcu_send(self, msg) -> None:
        port = self.port
        if port is None:
            return
        with self._tx_lock:
            data = self.mcu_encoder.encode(msg)
            try:
                port.write(data)
            except Exception as e:  # noqa: BLE001
                self._serial_failed(e)

    def _serial_loop(self) -> None:
        while not self._stop.is_set():
            port = self.port
            if port is None:
                if self._stop.wait(1.0):
                    return
                if self._open_serial():
                    self.event("info", "serial_restored", "MCU serial port reopened")
                continue
            try:
                data = read_waiting(port)
            except Exception as e:  # noqa: BLE001
                if not self._stop.is_set():
                    self._serial_failed(e)
                continue
            if not data:
                continue
            for fr in self.mcu_decoder.feed(data):
                if fr.msg_type == McuType.SENSOR_REPORT:
                    self._on_report(fr.message)
                elif fr.msg_type == McuType.ACK:
                    a: Ack = fr.message
                    self.mcu_acks["ok" if a.status == 0 else "rejected"] += 1
                else:
                    self._on_mcu_frame(fr)
            self._check_drops("mcu_serial", self.mcu_decoder.stats.dropped,
                              self.mcu_decoder.last_error)
            self._count_drops("mcu", self.mcu_decoder.stats.as_dict(), self._mcu_drops_seen)

    def _on_mcu_frame(self, fr) -> None:
        """Another robot's own MCU frames (the climber's probe); none here."""

    def _check_drops(self, link: str, dropped: int, why: str) -> None:
        now = time.monotonic()
        before = self._drops_reported.get(link, 0)
        if dropped > before and now - self._last_drop_event.get(link, -1e9) > DROP_EVENT_MIN_S:
            self.event("warning", "decoder_drop", f"{link}: dropped frames ({why})",
                       link=link, dropped=dropped, new=dropped - before)
            self._drops_reported[link] = dropped
            self._last_drop_event[link] = now

    def _count_drops(self, prefix: str, stats: dict[str, int], seen: dict[str, int]) -> None:
        for k, v in stats.items():
            if k in ("frames", "bytes_in", "dropped", "garbage_bytes") or not v:
                continue
            new = v - seen.get(k, 0)
            if new > 0:
                with self._lock:
                    key = f"{prefix}:{k}"
                    self.rejections[key] = self.rejections.get(key, 0) + new
                seen[k] = v


    def _on_report(self, rep: SensorReport) -> None:
        with self._lock:
            self.report = rep
            self.report_mono = time.monotonic()
            # the board's time and the host's as one pair, for readers without the lock
            self.report_stamp = (rep.mcu_time_ms / 1000.0, self.report_mono)
            self.mcu_reports += 1
            self.odom.update(rep.mcu_time_ms, rep.enc_left_ticks, rep.enc_right_ticks,
                             rep.yaw_rate_rps, rep.imu_yaw_rad)
            # every sample, for the navigation to find the pose at a scan's time
            # (several reports may arrive between two navigation steps)
            if self.odom_trail is not None:
                self.odom_trail.append((rep.mcu_time_ms / 1000.0, self.odom.x, self.odom.y,
                                        self.odom.theta))
            changed = rep.alarm_flags ^ self.last_flags
            self.last_flags = rep.alarm_flags
        if self.mcu_silent:
            self.mcu_silent = False
            self.event("info", "mcu_link_up", "MCU sensor reports are arriving")
        for flag in AlarmFlag:
            if changed & flag:
                active = bool(rep.alarm_flags & flag)
                self.event("alarm" if active else "info", "mcu_alarm",
                           f"MCU {flag.name} {'raised' if active else 'cleared'}",
                           flag=flag.name, active=active)
    def _check_mcu_silence(self, now: float) -> None:
        if not self.mcu_silent and now - self.report_mono > MCU_SILENT_S:
            self.mcu_silent = True
            self.event("alarm", "mcu_link_lost", f"no MCU sensor report for {MCU_SILENT_S:g} s")

    def _tick_keepalive(self) -> None:
        with self._lock:
            if self.estop:
                msg = Estop(True)
            elif self._moving():
                msg = self._motor_msg()
            else:
                msg = Keepalive()
        self._mcu_send(msg)

    def _tick_config(self) -> None:
        lim = self.cfg.limits
        self._mcu_send(ConfigLimits(lim.gas_lel_pct, lim.temp_c, lim.humidity_pct,
                                    lim.obstacle_m, lim.battery_low_v))

