"""``sim-robot``: the simulated robot (MCU model + relay) serving desks over TCP."""

from __future__ import annotations

import argparse
import logging
import os
import signal
import sys
import threading

from app.comm.protocol import parse_hostport

from .config import SimConfig
from .sim import SimRobot

log = logging.getLogger("sim_robot")


def _listen_address(text: str) -> tuple[str, int]:
    try:
        return parse_hostport(text, allow_port_zero=True)
    except ValueError as e:
        raise argparse.ArgumentTypeError(str(e)) from None


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="sim-robot", description=__doc__)
    ap.add_argument("--listen", type=_listen_address, default=("127.0.0.1", 0),
                    metavar="HOST:PORT", help="TCP address for desks (port 0 = pick one)")
    ap.add_argument("--seed", type=int, default=None, help="random seed (default 0)")
    ap.add_argument("--time-scale", type=float, default=None, metavar="X",
                    help="sim time runs X times faster than wall time")
    ap.add_argument("--serial", metavar="DEVICE", default=None,
                    help="use a real MCU board on this serial device instead of the model "
                         "(a device such as /dev/ttyUSB0 or COM3, or a pyserial URL)")
    ap.add_argument("--mcu-link", choices=("socket", "pty"), default=None,
                    help="the MCU model's end of the serial link: a loopback socket "
                         "(default, every platform) or a pseudo-terminal (Unix)")
    ap.add_argument("--log-truth", metavar="FILE", default=None,
                    help="write ground truth as JSON lines (for evaluation)")
    ap.add_argument("--no-video", action="store_true", help="do not stream camera frames")
    ap.add_argument("--fps", type=float, default=None, help="camera frame rate (wall time)")
    ap.add_argument("--config", metavar="TOML", default=None, help="configuration file")
    ap.add_argument("--station", metavar="JSON", default=None, help="station layout file")
    ap.add_argument("--start-at", metavar="GAUGE", default=None,
                    help="start in front of this gauge (e.g. PG-101) instead of the dock")
    ap.add_argument("--patrol", metavar="ROUTE", nargs="?", const="default", default=None,
                    help="start patrolling at once: the default route, or a route JSON file")
    ap.add_argument("--key-file", metavar="PATH", default=None,
                    help="station key shared with the desks (default: $STATION_PATROL_KEY_FILE "
                         "or ~/.config/station-patrol/station.key; created if missing)")
    ap.add_argument("--exit-with-parent", action="store_true",
                    help="end when standard input closes (the desk that started this robot "
                         "ended, however it ended); on Linux also on the parent's death")
    ap.add_argument("--robot", choices=("patrol", "climber", "4ws"), default="patrol",
                    help="which robot to simulate (climber: the tank-wall inspection crawler; "
                         "4ws: the four-wheel-steer patrol robot)")
    ap.add_argument("--wall", metavar="FILE", default=None,
                    help="climber: wall, corrosion and thickness limit (TOML/JSON; "
                         "default: the 24 m × 9.6 m tank)")
    ap.add_argument("--seam-camera", choices=("sightings", "pixels"), default="sightings",
                    help="climber: the seam camera as sightings drawn from the wall's geometry "
                         "(default) or as grey frames in which the relay finds the seams")
    ap.add_argument("--seam-camera-device", metavar="CAM", default=None,
                    help="climber on a real board (--serial): its downward seam camera, an "
                         "OpenCV capture source (a device index such as 0, /dev/videoN, a "
                         "video file or a stream URL), forward up in the image")
    ap.add_argument("--seam-camera-mm-per-px", metavar="MM", type=float, default=None,
                    help="the seam camera's scale on the wall (needed with its device)")
    ap.add_argument("-v", "--verbose", action="store_true", help="debug logging")
    return ap


def config_from_args(a: argparse.Namespace) -> SimConfig:
    cfg = SimConfig.from_toml(a.config) if a.config else SimConfig()
    cfg.host, cfg.port = a.listen
    if a.seed is not None:
        cfg.seed = a.seed
    if a.time_scale is not None:
        if a.time_scale <= 0:
            raise SystemExit("--time-scale must be positive")
        cfg.time_scale = a.time_scale
    if a.serial:
        cfg.serial_device = a.serial
    if a.mcu_link:
        cfg.mcu_link = a.mcu_link
    if a.log_truth:
        cfg.log_truth = a.log_truth
    if a.no_video:
        cfg.video = False
    if a.fps is not None:
        if a.fps <= 0:
            raise SystemExit("--fps must be positive")
        cfg.fps = a.fps
    if a.station:
        cfg.station_file = a.station
    if a.start_at:
        cfg.start_at = a.start_at
    if a.patrol:
        cfg.patrol = a.patrol
    if a.key_file:
        cfg.key_file = a.key_file
    return cfg


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    logging.basicConfig(level=logging.DEBUG if args.verbose else logging.INFO,
                        format="%(asctime)s %(levelname)s %(name)s: %(message)s",
                        stream=sys.stderr)
    cfg = config_from_args(args)
    done = threading.Event()

    def on_signal(signum, _frame):
        log.info("signal %d: shutting down", signum)
        done.set()

    signal.signal(signal.SIGINT, on_signal)
    signal.signal(signal.SIGTERM, on_signal)
    if args.exit_with_parent:
        from .parent_watch import exit_with_parent

        parent = os.environ.get("SIM_ROBOT_PARENT_PID", "")
        exit_with_parent(done.set, int(parent) if parent.isdigit() else None)
    try:
        if args.robot == "climber":
            from .climber.sim import ClimberSim, load_setup

            mm = args.seam_camera_mm_per_px
            robot = ClimberSim(cfg, load_setup(args.wall), seam_camera=args.seam_camera,
                               camera_device=args.seam_camera_device,
                               camera_m_per_px=None if mm is None else mm / 1000.0)
        elif args.robot == "4ws":
            from .fws_robot import FwsSim

            robot = FwsSim(cfg)
        else:
            robot = SimRobot(cfg)
        robot.start()
    except (OSError, ValueError) as e:
        log.error("cannot start: %s", e)
        return 2
    host, port = robot.address
    log.info("MCU serial on %s%s", robot.device,
             "" if cfg.serial_device else " (built-in model)")
    sys.stdout.write(f"listening on {host}:{port}\n")
    sys.stdout.flush()
    while not done.wait(0.5):
        pass
    robot.close()
    log.info("stopped: %s", robot.relay.stats())
    return 0


if __name__ == "__main__":
    sys.exit(main())
