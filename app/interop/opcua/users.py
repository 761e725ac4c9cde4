"""OPC UA users of the desk: names, roles and scrypt-hashed passwords in one JSON file.

Roles, from least to most:

- ``viewer``: browse, read and subscribe;
- ``operator``: also start / pause / resume a patrol, return to dock, emergency stop;
- ``supervisor``: everything an operator may, and take an alarm out of service and back
  (OPC UA Disable / Enable; the role a site gives its shift lead).

A password is never stored: the file keeps, per user, a random 16-byte salt and
``hashlib.scrypt(password, salt, n=2**14, r=8, p=1)`` (RFC 7914), compared in
constant time. The file is written atomically and readable by its owner only.

Command line (``station-patrol opcua-user``)::

    station-patrol opcua-user add NAME --role operator --password-stdin
    station-patrol opcua-user remove NAME
    station-patrol opcua-user list
"""

from __future__ import annotations

import argparse
import hashlib
import hmac
import json
import logging
import os
import secrets
import sys
from dataclasses import dataclass
from pathlib import Path

__all__ = ["ROLES", "METHOD_ROLES", "UserStore", "UserStoreError", "default_users_file", "main"]

log = logging.getLogger(__name__)

ROLES = ("viewer", "operator", "supervisor")
# who may call each control-room method (e-stop: every role that may command the robot)
METHOD_ROLES: dict[str, frozenset[str]] = {
    "start_patrol": frozenset({"operator", "supervisor"}),
    "pause_patrol": frozenset({"operator", "supervisor"}),
    "resume_patrol": frozenset({"operator", "supervisor"}),
    "dock": frozenset({"operator", "supervisor"}),
    "estop": frozenset({"operator", "supervisor"}),
    "acknowledge": frozenset({"operator", "supervisor"}),  # an alarm (no lease needed)
    "shelve": frozenset({"operator", "supervisor"}),  # shelve / unshelve an alarm
    # take an alarm out of service / back (OPC UA Disable / Enable): ISA-18.2 wants an
    # authorised person for it
    "disable": frozenset({"supervisor"}),
}
_SCRYPT = {"n": 2 ** 14, "r": 8, "p": 1}


class UserStoreError(ValueError):
    pass


@dataclass(frozen=True)
class _Entry:
    role: str
    salt: bytes
    digest: bytes
    n: int
    r: int
    p: int


def default_users_file(data_dir: str = "") -> Path:
    from app.core.records.paths import default_data_dir

    base = Path(data_dir) if data_dir else default_data_dir()
    return base / "opcua" / "users.json"


def _hash(password: str, salt: bytes, n: int, r: int, p: int) -> bytes:
    return hashlib.scrypt(password.encode("utf-8"), salt=salt, n=n, r=r, p=p,
                          maxmem=64 * 1024 * 1024, dklen=32)


class UserStore:
    """The users file at ``path`` (missing: no users)."""

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self._users: dict[str, _Entry] = {}
        self.load()

    def load(self) -> None:
        if not self.path.exists():
            self._users = {}
            return
        try:
            data = json.loads(self.path.read_text(encoding="utf-8"))
            users = {name: _Entry(u["role"], bytes.fromhex(u["salt"]),
                                  bytes.fromhex(u["scrypt"]), int(u["n"]), int(u["r"]),
                                  int(u["p"]))
                     for name, u in data["users"].items()}
        except (OSError, ValueError, KeyError, TypeError, AttributeError) as e:
            raise UserStoreError(f"{self.path}: not a valid OPC UA users file ({e})") from None
        bad = [n for n, u in users.items() if u.role not in ROLES]
        if bad:
            raise UserStoreError(f"{self.path}: unknown role for {', '.join(bad)}")
        self._users = users

    def _save(self) -> None:
        self.path.parent.mkdir(parents=True, exist_ok=True)
        data = {"users": {name: {"role": u.role, "salt": u.salt.hex(), "scrypt": u.digest.hex(),
                                 "n": u.n, "r": u.r, "p": u.p}
                          for name, u in sorted(self._users.items())}}
        tmp = self.path.with_suffix(".tmp")
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            json.dump(data, f, indent=1)
        os.replace(tmp, self.path)

    def add(self, name: str, role: str, password: str) -> None:
        if not name or not name.isprintable() or name.strip() != name:
            raise UserStoreError(f"user name {name!r} is empty or has blanks at its ends")
        if role not in ROLES:
            raise UserStoreError(f"role must be one of {', '.join(ROLES)}, not {role!r}")
        if len(password) < 8:
            raise UserStoreError("the password must have at least 8 characters")
        salt = secrets.token_bytes(16)
        self._users[name] = _Entry(role, salt, _hash(password, salt, **_SCRYPT), **_SCRYPT)
        self._save()

    def remove(self, name: str) -> None:
        if name not in self._users:
            raise UserStoreError(f"no OPC UA user {name!r}")
        del self._users[name]
        self._save()

    def users(self) -> dict[str, str]:
        """name → role."""
        return {n: u.role for n, u in sorted(self._users.items())}

    def check(self, name: str | None, password: str | None) -> str | None:
        """The user's role when the password is right, else None."""
        u = self._users.get(name or "")
        if u is None or password is None:
            return None
        ok = hmac.compare_digest(_hash(password, u.salt, u.n, u.r, u.p), u.digest)
        return u.role if ok else None


# ---------------------------------------------------------------- command line
def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="station-patrol opcua-user",
                                description="Manage the desk's OPC UA users.")
    p.add_argument("--file", help="users file (default: [opcua] users_file of --config, or "
                   "<data dir>/opcua/users.json)")
    p.add_argument("--config", metavar="FILE.toml", help="desk configuration file")
    sub = p.add_subparsers(dest="what", required=True)
    a = sub.add_parser("add", help="add a user or change its role and password")
    a.add_argument("name")
    a.add_argument("--role", required=True, choices=ROLES)
    a.add_argument("--password-stdin", action="store_true", required=True,
                   help="read the password from the first line of standard input")
    r = sub.add_parser("remove", help="remove a user")
    r.add_argument("name")
    sub.add_parser("list", help="list users and roles")
    args = p.parse_args(argv)
    path = args.file
    if path is None:
        from app.config import ConfigError, load_config

        try:
            cfg = load_config(args.config)
        except ConfigError as e:
            print(f"station-patrol: {e}", file=sys.stderr)
            return 2
        path = cfg.opcua.users_file or default_users_file(cfg.data_dir)
    try:
        store = UserStore(path)
        if args.what == "add":
            password = sys.stdin.readline().rstrip("\r\n")
            store.add(args.name, args.role, password)
            print(f"OPC UA user {args.name} ({args.role}) saved in {store.path}")
        elif args.what == "remove":
            store.remove(args.name)
            print(f"OPC UA user {args.name} removed from {store.path}")
        else:
            for name, role in store.users().items():
                print(f"{name}\t{role}")
    except UserStoreError as e:
        print(f"station-patrol opcua-user: {e}", file=sys.stderr)
        return 1
    return 0
