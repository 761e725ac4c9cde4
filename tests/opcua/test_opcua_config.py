"""[opcua] in the desk's TOML and the --opcua flag."""

from __future__ import annotations

import pytest

from app.cli import apply_flags, build_parser
from app.config import ConfigError, load_config


def test_opcua_section_is_typed(tmp_path):
    f = tmp_path / "desk.toml"
    f.write_text('[opcua]\nendpoint = "opc.tcp://0.0.0.0:4840"\nallow_anonymous = true\n')
    cfg = load_config(f)
    assert cfg.opcua.endpoint == "opc.tcp://0.0.0.0:4840" and cfg.opcua.allow_anonymous
    assert not cfg.opcua.allow_none_security  # off unless the site turns it on
    f.write_text('[opcua]\nallow_anonymous = "yes"\n')
    with pytest.raises(ConfigError, match="opcua.allow_anonymous: expected bool"):
        load_config(f)
    f.write_text('[opcua]\nport = 4840\n')
    with pytest.raises(ConfigError, match="unknown setting 'port'"):
        load_config(f)


def test_opcua_flag_sets_the_endpoint():
    cfg = load_config(None)
    apply_flags(cfg, build_parser().parse_args(["--demo", "--opcua", "opc.tcp://127.0.0.1:4840"]))
    assert cfg.opcua.endpoint == "opc.tcp://127.0.0.1:4840"
    with pytest.raises(SystemExit, match="opc.tcp://HOST:PORT"):
        apply_flags(cfg, build_parser().parse_args(["--demo", "--opcua", "127.0.0.1:4840"]))
