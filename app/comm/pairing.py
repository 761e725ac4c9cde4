"""``station-patrol pair``: make sure the station key exists and say how to give
it to the robot (no Qt). The key itself is never printed, only its fingerprint."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from app.comm import auth

ROBOT_KEY_PATH = "~/.config/station-patrol/station.key"


def pairing_text(key_path: Path, created: bool, fp: str, robot: str) -> str:
    k = str(key_path)
    return f"""Station key: {k} ({'created now' if created else 'already present'})
Fingerprint: {fp}

Install the same key on the robot, readable by its owner only:
  ssh {robot} 'mkdir -p -m 700 ~/.config/station-patrol'
  scp {k} {robot}:{ROBOT_KEY_PATH}
  ssh {robot} 'chmod 600 {ROBOT_KEY_PATH}'
and start the robot with it:
  sim-robot --key-file {ROBOT_KEY_PATH}
(or set STATION_PATROL_KEY_FILE). The robot logs the key's fingerprint when it
starts; it must read {fp}. Every other desk allowed to drive needs the same file
(station-patrol --key-file PATH). A desk started with --demo hands its key to the
simulated robot by itself.
"""


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="station-patrol pair", description=__doc__)
    ap.add_argument("--key-file", metavar="PATH", default=None,
                    help="the station key (default: $STATION_PATROL_KEY_FILE or "
                         "~/.config/station-patrol/station.key)")
    ap.add_argument("--robot", metavar="USER@HOST", default="pi@robot",
                    help="the robot's ssh address, for the printed commands")
    a = ap.parse_args(argv)
    path = Path(a.key_file).expanduser() if a.key_file else auth.default_key_path()
    try:
        key, created = auth.load_or_create_key(path)
    except (auth.KeyFileError, OSError) as e:
        print(f"station-patrol pair: {e}", file=sys.stderr)
        return 2
    sys.stdout.write(pairing_text(path.resolve(), created, auth.fingerprint(key), a.robot))
    return 0
