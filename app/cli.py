"""``station-patrol``: the operator's desk.

    station-patrol --demo                       start a local simulated robot and open the desk
    station-patrol --connect HOST:PORT          connect to a running robot
    station-patrol --demo --headless --duration 30 --out results
                                                no window: record what arrives, write a summary
    station-patrol report --from -8h --out shift.pdf
                                                a patrol report from the archive (see report -h)
    station-patrol export --mcap day.mcap       a session of the archive as MCAP for Foxglove,
                                                Lichtblick, PlotJuggler (see export -h)
    station-patrol pair                         create the station key if missing and print
                                                how to install it on the robot
    station-patrol alarms --check site.toml     check an alarm rule file (see alarms -h)
    station-patrol --demo --opcua opc.tcp://0.0.0.0:4840
                                                also serve the desk over OPC UA (docs/opcua.md)
    station-patrol opcua-user add NAME --role operator --password-stdin
                                                OPC UA users (add / remove / list)

With ``--demo`` and no display available the desk runs headless and says so.
``--connect`` first checks that something answers at HOST:PORT: a refused or
unanswered connection is reported ("connection refused") with exit status 1,
instead of a desk that waits for a robot that is not there. Before a window
opens on X11 the desk checks that Qt's xcb plugin can load, and if not names
every missing system library and the ``apt install`` line (app/platform_check).
"""

from __future__ import annotations

import argparse
import logging
import os
import sys
from pathlib import Path

from app.comm.protocol import parse_hostport
from app.config import ConfigError, DeskConfig, load_config

log = logging.getLogger("station_patrol")


def _hostport(text: str) -> tuple[str, int] | str:
    if text == "":  # `--connect` alone: the last robot address (resolved in main)
        return ""
    try:
        return parse_hostport(text)
    except ValueError as e:
        raise argparse.ArgumentTypeError(str(e)) from None


def probe_robot(host: str, port: int, timeout_s: float = 3.0) -> str | None:
    """None when a TCP connection to ``host:port`` opens (it is closed at once),
    else why not, in plain words ("connection refused", ...)."""
    import socket

    try:
        with socket.create_connection((host, port), timeout=timeout_s):
            return None
    except ConnectionRefusedError:
        return "connection refused (is the robot running and listening there?)"
    except TimeoutError:
        return f"no answer within {timeout_s:g} s"
    except socket.gaierror as e:
        return f"unknown host {host!r} ({e.strerror})"
    except OSError as e:
        return e.strerror or str(e)


def display_available() -> bool:
    """True when a window can be shown (or the Qt platform is forced)."""
    if os.environ.get("QT_QPA_PLATFORM"):
        return True
    if sys.platform.startswith("linux"):
        return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))
    return True


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="station-patrol", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    where = p.add_mutually_exclusive_group()
    where.add_argument("--demo", action="store_true",
                       help="start a local sim_robot process and connect to it")
    where.add_argument("--connect", metavar="HOST:PORT", type=_hostport, nargs="?", const="",
                       help="connect to a running robot (alone: the last robot the desk "
                       "connected to)")
    where.add_argument("--replay", action="store_true",
                       help="replay the archive's recording in the window (view only)")
    p.add_argument("--from", dest="replay_from", metavar="TIME",
                   help="with --replay: start (ISO 8601, 'now', -2h; default: the first record)")
    p.add_argument("--to", dest="replay_to", metavar="TIME",
                   help="with --replay: end (default: the last record)")
    p.add_argument("--session", default="latest", metavar="N|latest|all",
                   help="with --replay: which desk session (default: the latest; 'all' "
                   "mixes every session)")
    p.add_argument("--headless", action="store_true",
                   help="no window: record everything received and write a summary")
    p.add_argument("--duration", type=float, metavar="SECONDS",
                   help="headless run length (default 20 s); with a window: quit after it")
    p.add_argument("--out", metavar="DIR", help="folder for recordings and the summary "
                   "(default: results)")
    p.add_argument("--data-dir", metavar="DIR", help="folder of the archive (default: the "
                   "platform's user-data folder, or $STATION_PATROL_DATA_DIR)")
    p.add_argument("--patrol", action="store_true",
                   help="once connected, ask the robot to patrol its default route")
    p.add_argument("--seed", type=int, help="seed of the demo robot's world")
    p.add_argument("--time-scale", type=float, help="demo robot's simulated time speed-up "
                   "(default: 1 with a window, 4 headless)")
    p.add_argument("--config", metavar="FILE.toml", help="desk configuration file")
    p.add_argument("--alarms", metavar="FILE.toml", help="alarm rules overriding the shipped "
                   "app/resources/alarms.toml (a bad entry is reported and its default kept)")
    p.add_argument("--key-file", metavar="PATH", help="station key that signs commands "
                   "(default: $STATION_PATROL_KEY_FILE or ~/.config/station-patrol/station.key)")
    p.add_argument("--foxglove", nargs="?", const=-1, type=int, metavar="PORT",
                   help="serve the live data over the Foxglove WebSocket protocol (default "
                   "port 8765, loopback unless [foxglove] host says otherwise)")
    p.add_argument("--opcua", metavar="opc.tcp://HOST:PORT",
                   help="serve the desk over OPC UA at this endpoint (see docs/opcua.md)")
    p.add_argument("--log-level", default="INFO", choices=["DEBUG", "INFO", "WARNING", "ERROR"])
    p.add_argument("--lang", metavar="zh_CN|en", type=_language,
                   help="the window's language (default: the View menu's choice, else the "
                   "system's)")
    p.add_argument("--log-dir", metavar="DIR", help="folder of the rotating log files (default: "
                   "$STATION_PATROL_LOG_DIR or the platform's log folder; [log] in the TOML)")
    return p


def _language(text: str) -> str:
    from app.core.i18n import check_language

    try:
        return check_language(text)
    except ValueError as e:
        raise argparse.ArgumentTypeError(str(e)) from None


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    if argv[:1] == ["report"]:
        from app.report.cli import main as report_main

        return report_main(argv[1:])
    if argv[:1] == ["alarms"]:
        from app.core.alarms.cli import main as alarms_main

        return alarms_main(argv[1:])
    if argv[:1] == ["export"]:
        from app.export_cli import main as export_main

        return export_main(argv[1:])
    if argv[:1] == ["opcua-user"]:
        from app.interop.opcua.users import main as users_main

        return users_main(argv[1:])
    if argv[:1] == ["pair"]:
        from app.comm.pairing import main as pair_main

        return pair_main(argv[1:])
    if "--replay" in argv:
        from app.report.cli import join_negative_times

        argv = join_negative_times(argv)
    args = build_parser().parse_args(argv)
    try:
        cfg = load_config(args.config)
    except ConfigError as e:
        print(f"station-patrol: {e}", file=sys.stderr)
        return 2
    apply_flags(cfg, args)
    from app.logs import setup_logging

    setup_logging(args.log_level, cfg.log)  # the console and the rotating log files
    from app.allocator import settle_allocator, start_heap_trimmer

    settle_allocator()  # days of camera frames without the memory creeping (glibc)
    start_heap_trimmer()  # and free holes in the heaps given back once a minute
    if args.connect == "":  # --connect alone: the last robot address
        from app.ui.window_settings import last_address

        last = last_address()
        if last is None:
            print("station-patrol: no robot connected to before: --connect HOST:PORT",
                  file=sys.stderr)
            return 2
        args.connect = parse_hostport(last)
    if cfg.alarms_file:
        from app.core.alarms import use_alarm_file

        # a bad alarm file never stops the desk: it says what is wrong and keeps
        # the defaults for those points
        for problem in use_alarm_file(cfg.alarms_file):
            print(f"station-patrol: alarm rules: {problem}", file=sys.stderr)
    if (args.replay or not args.headless) and display_available():
        # Qt aborts when its xcb plugin misses a system library: say which, first
        from app.platform_check import check_xcb

        problem = check_xcb()
        if problem and (args.replay or args.demo or args.connect):
            print(f"station-patrol: {problem}", file=sys.stderr)
            return 1
    if args.replay:
        from app.ui.app import replay_main

        return replay_main(cfg, args.replay_from, args.replay_to, duration_s=args.duration,
                           session=args.session, lang=args.lang,
                           display=display_available())
    if not args.demo and not args.connect:
        print("station-patrol: say where the robot is: --demo or --connect HOST:PORT",
              file=sys.stderr)
        return 2
    headless = args.headless
    if not headless and not display_available():
        headless = True
        print(f"station-patrol: no display found; running headless for "
              f"{cfg.headless_duration_s:.0f} s, results in {Path(cfg.out_dir).resolve()}",
              flush=True)
    sim = None
    if args.demo:
        from app.sim_process import SimRobotProcess

        scale = cfg.headless_time_scale if headless else cfg.time_scale
        if scale != 1.0:
            print(f"station-patrol: the simulated robot runs at {scale:g}x real time "
                  f"(--time-scale 1 for real time)", flush=True)
        print("station-patrol: starting the simulated robot (a first run compiles its "
              "planner: a minute or more)", flush=True)

        def still_starting(waited: float) -> None:
            print(f"station-patrol: still starting the simulated robot ({waited:.0f} s; a "
                  f"first run compiles its planner)", flush=True)

        sim = SimRobotProcess(seed=cfg.seed, time_scale=scale, on_wait=still_starting)
        try:
            sim.start()
        except (RuntimeError, OSError) as e:
            print(f"station-patrol: could not start the simulated robot: {e}", file=sys.stderr)
            return 1
        cfg.host, cfg.port = sim.host, sim.port
        print(f"station-patrol: simulated robot listening on {sim.host}:{sim.port} "
              f"(pid {sim.pid})", flush=True)
    else:
        cfg.host, cfg.port = args.connect
        why = probe_robot(cfg.host, cfg.port, cfg.link.connect_timeout_s + 1.0)
        if why is not None:
            print(f"station-patrol: cannot connect to {cfg.host}:{cfg.port}: {why}",
                  file=sys.stderr)
            return 1
        from app.ui.window_settings import remember_address

        remember_address(cfg.host, cfg.port)  # `--connect` alone comes back here
    try:
        if headless:
            from app.headless import run_headless

            return run_headless(cfg)
        from app.ui.app import run_window

        return run_window(cfg, duration_s=args.duration, record=args.out is not None,
                          lang=args.lang)
    finally:
        if sim is not None:
            sim.stop()


def apply_flags(cfg: DeskConfig, args: argparse.Namespace) -> None:
    if getattr(args, "key_file", None):
        # the link and a --demo robot both read the key from here
        os.environ["STATION_PATROL_KEY_FILE"] = str(Path(args.key_file).expanduser())
    if args.duration is not None:
        if args.duration <= 0:
            raise SystemExit("station-patrol: --duration must be positive")
        cfg.headless_duration_s = args.duration
    if args.out is not None:
        cfg.out_dir = args.out
    if getattr(args, "data_dir", None) is not None:
        cfg.data_dir = args.data_dir
    if getattr(args, "log_dir", None) is not None:
        cfg.log.dir = args.log_dir
    if getattr(args, "alarms", None) is not None:
        cfg.alarms_file = args.alarms
    if args.seed is not None:
        cfg.seed = args.seed
    if getattr(args, "opcua", None):
        if not args.opcua.startswith("opc.tcp://"):
            raise SystemExit("station-patrol: --opcua wants opc.tcp://HOST:PORT")
        cfg.opcua.endpoint = args.opcua
    if args.patrol:
        cfg.start_patrol = True
    if getattr(args, "foxglove", None) is not None:
        cfg.foxglove.enabled = True
        if args.foxglove >= 0:
            cfg.foxglove.port = args.foxglove
    if args.time_scale is not None:
        if args.time_scale <= 0:
            raise SystemExit("station-patrol: --time-scale must be positive")
        cfg.time_scale = cfg.headless_time_scale = args.time_scale


if __name__ == "__main__":
    sys.exit(main())
