"""The desk's command-line faces say what happened (issue 12, C)."""

import signal
import socket
import subprocess
import sys

from app.cli import main, probe_robot


def _closed_port() -> int:
    s = socket.create_server(("127.0.0.1", 0))  # a free port ...
    port = s.getsockname()[1]
    s.close()  # ... that nothing listens on any more
    return port


def test_connect_to_a_closed_port_says_connection_refused(capsys, tmp_path):
    port = _closed_port()
    code = main(["--connect", f"127.0.0.1:{port}", "--headless", "--duration", "2",
                 "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code != 0
    assert f"cannot connect to 127.0.0.1:{port}: connection refused" in err
    assert "finished" not in err


def test_probe_says_none_when_something_listens():
    srv = socket.create_server(("127.0.0.1", 0))
    try:
        assert probe_robot("127.0.0.1", srv.getsockname()[1]) is None
    finally:
        srv.close()


def test_connect_to_a_closed_port_exits_non_zero_as_a_process(tmp_path):
    port = _closed_port()
    r = subprocess.run([sys.executable, "-m", "app.cli", "--connect", f"127.0.0.1:{port}",
                        "--headless", "--duration", "2", "--out", str(tmp_path / "o")],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 1
    assert "connection refused" in r.stderr and "finished" not in r.stdout + r.stderr


def test_headless_run_that_never_connected_says_so(qtbot, capsys, tmp_path):
    """Past the probe (a robot that vanished in between): the run does not end
    with "finished" but says it never connected, and why."""
    from app.config import DeskConfig
    from app.headless import run_headless

    cfg = DeskConfig()
    cfg.host, cfg.port = "127.0.0.1", _closed_port()
    cfg.headless_duration_s = 1.5
    cfg.out_dir = str(tmp_path / "out")
    cfg.data_dir = str(tmp_path / "data")
    saved = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        assert run_headless(cfg) == 1
    finally:  # the headless desk installs its own handlers: give pytest its own back
        for s, h in saved.items():
            signal.signal(s, h)
    out = capsys.readouterr()
    assert f"never connected to 127.0.0.1:{cfg.port}" in out.err
    assert "refused" in out.err.lower() and "finished" not in out.out + out.err
