"""The station key, command signing and the robot's check of signed commands (no Qt).

One pre-shared 256-bit station key, held by the desk and the robot. Every
COMMAND frame carries an HMAC-SHA256 tag over the frame's header fields
(version, type, length, sequence number, timestamp) and its JSON body, which
names the desk, a random session id and a counter that rises with every
command of that session. The robot refuses a command that is unsigned, whose
tag is wrong, whose counter does not rise (a replay) or whose timestamp is
too far from its own clock or older than its own start (stale). See
docs/security.md.

The key is a file of 64 hex digits, created on first use with owner-only
permissions (file 0600, folder 0700). It is never logged: only its
:func:`fingerprint` is shown.
"""

from __future__ import annotations

import getpass
import hashlib
import hmac
import logging
import os
import secrets
import socket
import stat
from collections import OrderedDict
from pathlib import Path

from app.comm import protocol as P
from app.core import paths

log = logging.getLogger(__name__)

KEY_ENV = "STATION_PATROL_KEY_FILE"
KEY_BYTES = 32
MAC_DOMAIN = b"station-patrol command v1\0"

#: reasons a command is refused, in the order they are checked
REJECT_REASONS = ("unsigned", "malformed", "bad_mac", "stale", "replay")


class KeyFileError(ValueError):
    """The key file is missing, unreadable or not a key (message names the file)."""


def config_dir() -> Path:
    """The platform's per-user configuration folder for Station Patrol."""
    return paths.config_dir()


def default_key_path() -> Path:
    """``$STATION_PATROL_KEY_FILE`` if set, else ``<config dir>/station.key``."""
    env = os.environ.get(KEY_ENV)
    return Path(env).expanduser() if env else config_dir() / "station.key"


def fingerprint(key: bytes) -> str:
    """A short, safe-to-show name of a key: the first 8 bytes of its SHA-256."""
    h = hashlib.sha256(b"station-patrol key fingerprint\0" + key).hexdigest()[:16]
    return "-".join(h[i:i + 4] for i in range(0, 16, 4))


def _parse(text: str, path: Path) -> bytes:
    t = text.strip()
    try:
        key = bytes.fromhex(t)
    except ValueError:
        raise KeyFileError(f"{path}: not a station key (expected {2 * KEY_BYTES} hex digits)") \
            from None
    if len(key) != KEY_BYTES:
        raise KeyFileError(f"{path}: a station key has {2 * KEY_BYTES} hex digits, "
                        f"this file holds {len(t)}")
    return key


def load_key(path: str | os.PathLike | None = None) -> bytes:
    """Read an existing key; :class:`KeyFileError` with a clear message otherwise."""
    p = Path(path).expanduser() if path else default_key_path()
    try:
        text = p.read_text(encoding="ascii")
    except FileNotFoundError:
        raise KeyFileError(f"{p}: no station key here; run `station-patrol pair` "
                        f"on the desk and install the key on the robot") from None
    except (OSError, UnicodeDecodeError) as e:
        raise KeyFileError(f"{p}: cannot read the station key: {e}") from None
    if os.name == "posix":
        mode = stat.S_IMODE(p.stat().st_mode)
        if mode & 0o077:
            log.warning("%s is readable by others (mode %o); chmod 600 it", p, mode)
    return _parse(text, p)


def load_or_create_key(path: str | os.PathLike | None = None) -> tuple[bytes, bool]:
    """The key at ``path`` (default :func:`default_key_path`), created if missing.
    Returns ``(key, created)``. Creation is atomic (O_EXCL), so two programs
    starting together end up with the same key."""
    p = Path(path).expanduser() if path else default_key_path()
    if not p.exists():
        p.parent.mkdir(mode=0o700, parents=True, exist_ok=True)
        key = secrets.token_bytes(KEY_BYTES)
        try:
            fd = os.open(p, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
        except FileExistsError:
            return load_key(p), False
        with os.fdopen(fd, "w", encoding="ascii") as f:
            f.write(key.hex() + "\n")
        log.info("created a station key at %s (fingerprint %s)", p, fingerprint(key))
        return key, True
    return load_key(p), False


def default_desk_name() -> str:
    try:
        user = getpass.getuser()
    except Exception:  # noqa: BLE001 - no user name in some containers
        user = "desk"
    return f"{user}@{socket.gethostname()}"


class CommandSigner:
    """Signs the commands of one desk session (give it to a FrameEncoder)."""

    def __init__(self, key: bytes, desk: str | None = None,
                 session: str | None = None) -> None:
        self._key = bytes(key)
        self.desk = desk or default_desk_name()
        self.session = session or secrets.token_hex(8)
        self.counter = 0

    @property
    def fingerprint(self) -> str:
        return fingerprint(self._key)

    def seal(self, cmd: P.Command, seq: int, timestamp_us: int) -> bytes:
        """The payload of a signed COMMAND frame with this sequence number and time."""
        self.counter += 1
        auth = {"desk": self.desk, "session": self.session, "ctr": self.counter}
        body = P.Command(cmd.name, cmd.args, auth).json_bytes()
        length = len(body) + 1 + P.MAC_SIZE
        tag = command_tag(self._key, P.MsgType.COMMAND, length, seq, timestamp_us, body)
        return body + b"\0" + tag

    def __repr__(self) -> str:  # never show the key
        return f"CommandSigner(desk={self.desk!r}, key {self.fingerprint})"


def command_tag(key: bytes, msg_type: int, length: int, seq: int, timestamp_us: int,
                body: bytes) -> bytes:
    return hmac.new(key, MAC_DOMAIN + P.mac_header(msg_type, length, seq, timestamp_us)
                    + body, hashlib.sha256).digest()


class CommandGuard:
    """The robot's check of signed commands: tag, freshness and replay.

    ``check(frame)`` returns ``(reason, auth)``: reason ``""`` for a good
    command, else one of :data:`REJECT_REASONS`, each counted in ``counts``.
    Counters are kept per (desk, session) for the last ``max_sessions``
    sessions; a session unknown to this run must also be newer than the
    robot's own start, so a command recorded before a restart is stale.
    """

    def __init__(self, key: bytes, max_skew_s: float = 10.0, started_us: int | None = None,
                 max_sessions: int = 512) -> None:
        self._key = bytes(key)
        self.max_skew_us = int(max_skew_s * 1e6)
        self.started_us = P.now_us() if started_us is None else started_us
        self.max_sessions = max_sessions
        self._last: OrderedDict[tuple[str, str], int] = OrderedDict()
        self.counts = dict.fromkeys(REJECT_REASONS, 0)
        self.accepted = 0

    @property
    def fingerprint(self) -> str:
        return fingerprint(self._key)

    def _reject(self, reason: str) -> tuple[str, dict | None]:
        self.counts[reason] += 1
        return reason, None

    def check(self, fr: P.Frame, now_us: int | None = None) -> tuple[str, dict | None]:
        cmd: P.Command = fr.message
        if not cmd.mac or cmd.auth is None:
            return self._reject("unsigned")
        a = cmd.auth
        desk, session, ctr = a.get("desk"), a.get("session"), a.get("ctr")
        if not (isinstance(desk, str) and isinstance(session, str) and type(ctr) is int
                and len(desk) <= 128 and len(session) <= 64 and ctr > 0):
            return self._reject("malformed")
        length = len(cmd.body) + 1 + P.MAC_SIZE
        want = command_tag(self._key, fr.msg_type, length, fr.seq, fr.timestamp_us, cmd.body)
        if not hmac.compare_digest(want, cmd.mac):
            return self._reject("bad_mac")
        now = P.now_us() if now_us is None else now_us
        if abs(now - fr.timestamp_us) > self.max_skew_us or fr.timestamp_us < self.started_us:
            return self._reject("stale")
        k = (desk, session)
        last = self._last.get(k)
        if last is not None and ctr <= last:
            return self._reject("replay")
        self._last[k] = ctr
        self._last.move_to_end(k)
        while len(self._last) > self.max_sessions:
            self._last.popitem(last=False)
        self.accepted += 1
        return "", {"desk": desk, "session": session, "ctr": ctr}
