"""The station key file and the robot's check of signed commands."""

import os
import stat

import pytest

from app.comm import auth
from app.comm import protocol as P


def _frame(data: bytes) -> P.Frame:
    (fr,) = P.FrameDecoder().feed(data)
    return fr


def test_key_is_created_once_with_owner_only_permissions(tmp_path, monkeypatch):
    monkeypatch.delenv(auth.KEY_ENV)
    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path / "cfg"))
    path = auth.default_key_path()
    assert path == tmp_path / "cfg" / "station-patrol" / "station.key"
    key, created = auth.load_or_create_key()
    assert created and len(key) == auth.KEY_BYTES
    assert stat.S_IMODE(path.stat().st_mode) == 0o600
    assert stat.S_IMODE(path.parent.stat().st_mode) == 0o700
    again, created2 = auth.load_or_create_key()
    assert again == key and not created2


def test_env_variable_names_the_key_file(tmp_path, monkeypatch):
    monkeypatch.setenv(auth.KEY_ENV, str(tmp_path / "k"))
    assert auth.default_key_path() == tmp_path / "k"


def test_a_bad_key_file_gets_a_clear_message(tmp_path):
    p = tmp_path / "station.key"
    with pytest.raises(auth.KeyFileError, match="no station key here"):
        auth.load_key(p)
    p.write_text("not hex at all\n")
    with pytest.raises(auth.KeyFileError, match="hex digits"):
        auth.load_key(p)
    p.write_text("abcd\n")
    with pytest.raises(auth.KeyFileError, match="64 hex digits"):
        auth.load_key(p)


def test_the_key_never_shows_only_its_fingerprint(tmp_path, caplog):
    caplog.set_level("DEBUG")
    key, _ = auth.load_or_create_key(tmp_path / "k")
    signer = auth.CommandSigner(key, "desk-1")
    text = repr(signer) + caplog.text
    assert key.hex() not in text and auth.fingerprint(key) in text
    assert auth.fingerprint(key) != auth.fingerprint(bytes(32))


def test_guard_accepts_good_commands_and_refuses_each_kind_of_bad_one():
    key = bytes(range(32))
    guard = auth.CommandGuard(key, max_skew_s=10.0, started_us=P.now_us() - 1_000_000)
    enc = P.FrameEncoder(signer=auth.CommandSigner(key, "desk-1"))
    good = enc.encode(P.Command("drive", {"linear_mps": 0.2}))
    assert guard.check(_frame(good)) == ("", {"desk": "desk-1", "session": enc.signer.session,
                                              "ctr": 1})
    # the very same bytes again: the counter did not rise
    assert guard.check(_frame(good))[0] == "replay"
    # unsigned
    assert guard.check(_frame(P.FrameEncoder().encode(P.Command("drive", {}))))[0] == "unsigned"
    # signed with another key
    other = P.FrameEncoder(signer=auth.CommandSigner(bytes(32), "desk-1"))
    assert guard.check(_frame(other.encode(P.Command("drive", {}))))[0] == "bad_mac"
    # a changed argument breaks the tag
    tampered = good.replace(b'"linear_mps":0.2', b'"linear_mps":0.9')
    body_fr = _frame(P.FrameEncoder().encode_raw(
        P.MsgType.COMMAND, tampered[P.HEADER_SIZE:-P.TRAILER_SIZE],
        _frame(good).timestamp_us, seq=_frame(good).seq))
    assert guard.check(body_fr)[0] == "bad_mac"
    # a good tag moved to another sequence number
    moved = _frame(P.FrameEncoder().encode_raw(
        P.MsgType.COMMAND, good[P.HEADER_SIZE:-P.TRAILER_SIZE], _frame(good).timestamp_us,
        seq=_frame(good).seq + 1))
    assert guard.check(moved)[0] == "bad_mac"
    # stale: an hour old, or from before the robot started
    old = enc.encode(P.Command("stop", {}), timestamp_us=P.now_us() - 3600_000_000)
    assert guard.check(_frame(old))[0] == "stale"
    before = enc.encode(P.Command("stop", {}), timestamp_us=guard.started_us - 1000)
    assert guard.check(_frame(before))[0] == "stale"
    # a malformed signature block
    bad_auth = P.Command("stop", {}, {"desk": "d", "session": "s", "ctr": "1"}, b"\x01" * 32)
    assert guard.check(_frame(P.FrameEncoder().encode(bad_auth)))[0] == "malformed"
    # the next good command of the session still passes
    assert guard.check(_frame(enc.encode(P.Command("stop", {}))))[0] == ""
    assert guard.counts == {"unsigned": 1, "malformed": 1, "bad_mac": 3, "stale": 2,
                            "replay": 1}
    assert guard.accepted == 2


def test_pair_prints_fingerprint_and_install_commands(tmp_path, capsys):
    from app.comm.pairing import main

    key_path = tmp_path / "sub" / "station.key"
    assert main(["--key-file", str(key_path), "--robot", "ops@robot-7"]) == 0
    out = capsys.readouterr().out
    key = auth.load_key(key_path)
    assert "created now" in out and auth.fingerprint(key) in out
    assert f"scp {key_path}" in out and "ops@robot-7" in out and "chmod 600" in out
    assert "sim-robot --key-file" in out
    assert key.hex() not in out
    assert main(["--key-file", str(key_path)]) == 0
    assert "already present" in capsys.readouterr().out
    assert os.stat(key_path).st_mode & 0o077 == 0


def test_desk_key_file_option_reaches_the_link_and_the_demo_robot(tmp_path, monkeypatch):
    from app.cli import apply_flags, build_parser
    from app.config import DeskConfig
    from app.sim_process import SimRobotProcess

    key_path = tmp_path / "my.key"
    args = build_parser().parse_args(["--demo", "--key-file", str(key_path)])
    apply_flags(DeskConfig(), args)
    assert auth.default_key_path() == key_path
    sim = SimRobotProcess()  # not started: only its command line
    assert sim.args[sim.args.index("--key-file") + 1] == str(key_path)
    assert key_path.exists()  # created for the robot on first use
