"""Typed configuration from TOML, with clear messages for bad files."""

import pytest

from app.config import ConfigError, load_config


def test_defaults_and_overrides(tmp_path):
    assert load_config(None).link.lost_after_s == 3.0
    f = tmp_path / "desk.toml"
    f.write_text('seed = 7\n[link]\nlost_after_s = 2\nreconnect_every_s = 0.25\n')
    cfg = load_config(f)
    assert cfg.seed == 7
    assert cfg.link.lost_after_s == 2.0 and isinstance(cfg.link.lost_after_s, float)
    assert cfg.link.reconnect_every_s == 0.25


@pytest.mark.parametrize("text, message", [
    ("colour = 'grey'\n", "unknown setting 'colour'"),
    ("seed = 'seven'\n", "seed: expected int, got str"),
    ("link = 3\n", "link: expected a table"),
    ("[link]\nlost_after_s = 'soon'\n", "link.lost_after_s: expected float"),
    ("seed = = 1\n", "not valid TOML"),
    ("seed = true\n", "seed: expected int, got bool"),
])
def test_bad_files_say_what_is_wrong(tmp_path, text, message):
    f = tmp_path / "desk.toml"
    f.write_text(text)
    with pytest.raises(ConfigError, match=message):
        load_config(f)


def test_missing_file(tmp_path):
    with pytest.raises(ConfigError, match="not found"):
        load_config(tmp_path / "nope.toml")


def test_loading_the_configuration_does_not_import_qt():
    """The desk's configuration is read by tools without a display: no Qt."""
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    code = ("import sys, app.config; app.config.load_config(None); "
            "print(sorted(m for m in sys.modules if m.split('.')[0] in "
            "('PySide6', 'pyqtgraph', 'shiboken6')))")
    out = subprocess.run([sys.executable, "-c", code], cwd=root, capture_output=True,
                         text=True, timeout=120, env={"PYTHONPATH": str(root)})
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "[]"
