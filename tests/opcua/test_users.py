"""OPC UA users: roles, scrypt-hashed passwords, the opcua-user command line."""

from __future__ import annotations

import io
import json

import pytest

from app.cli import main as cli_main
from app.interop.opcua.users import UserStore, UserStoreError


def test_password_is_stored_hashed_and_checked(tmp_path):
    store = UserStore(tmp_path / "users.json")
    store.add("alice", "operator", "correct horse")
    text = (tmp_path / "users.json").read_text()
    assert "correct horse" not in text
    entry = json.loads(text)["users"]["alice"]
    assert entry["role"] == "operator" and len(bytes.fromhex(entry["salt"])) == 16
    again = UserStore(tmp_path / "users.json")  # read back from the file
    assert again.check("alice", "correct horse") == "operator"
    assert again.check("alice", "wrong horse!") is None
    assert again.check("bob", "correct horse") is None
    assert again.check(None, None) is None


def test_same_password_two_users_two_hashes(tmp_path):
    store = UserStore(tmp_path / "users.json")
    store.add("a", "viewer", "same-password")
    store.add("b", "viewer", "same-password")
    users = json.loads((tmp_path / "users.json").read_text())["users"]
    assert users["a"]["scrypt"] != users["b"]["scrypt"]


@pytest.mark.parametrize("name,role,pw", [("x", "admin", "long-enough"), ("x", "viewer", "short"),
                                          (" x", "viewer", "long-enough")])
def test_bad_user_refused_with_a_message(tmp_path, name, role, pw):
    with pytest.raises(UserStoreError):
        UserStore(tmp_path / "u.json").add(name, role, pw)


def test_broken_file_is_a_clear_error(tmp_path):
    (tmp_path / "u.json").write_text("{not json")
    with pytest.raises(UserStoreError, match="not a valid OPC UA users file"):
        UserStore(tmp_path / "u.json")


def test_command_line_add_list_remove(tmp_path, monkeypatch, capsys):
    f = str(tmp_path / "users.json")
    monkeypatch.setattr("sys.stdin", io.StringIO("s3cret-pass\n"))
    assert cli_main(["opcua-user", "--file", f, "add", "carol", "--role", "supervisor",
                     "--password-stdin"]) == 0
    assert UserStore(f).check("carol", "s3cret-pass") == "supervisor"
    capsys.readouterr()
    assert cli_main(["opcua-user", "--file", f, "list"]) == 0
    assert capsys.readouterr().out.split() == ["carol", "supervisor"]
    assert cli_main(["opcua-user", "--file", f, "remove", "carol"]) == 0
    assert UserStore(f).users() == {}
    assert cli_main(["opcua-user", "--file", f, "remove", "carol"]) == 1
    assert "no OPC UA user" in capsys.readouterr().err
